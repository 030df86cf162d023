"""Material catalogue: provenance, ranges, presets, and an independent published formula."""

import numpy as np
import pytest

from scatterlab import materials

REQUIRED = ["Au", "Al", "Fe", "Cu", "Ag", "Ti", "Ni", "Cr", "SiO2", "Al2O3", "PTFE", "green_paint"]


@pytest.mark.parametrize("name", REQUIRED)
def test_required_materials_have_source_and_valid_index(name):
    eta = materials.index(name, 1.55e-6)
    assert isinstance(eta, complex)
    assert eta.source and isinstance(eta.source, str)
    assert eta.real > 0 and eta.imag <= 0  # eta = n - j kappa, kappa >= 0


def test_fused_silica_against_malitson_sellmeier():
    """Malitson (1965) Sellmeier coefficients, typed in from the paper, as an independent formula."""
    wl = np.array([0.5, 1.0, 1.064, 1.55])
    B = [0.6961663, 0.4079426, 0.8974794]
    C = [0.0684043, 0.1162414, 9.896161]
    n = np.sqrt(1 + sum(b * wl**2 / (wl**2 - c**2) for b, c in zip(B, C)))
    got = materials.index("SiO2", wl * 1e-6)
    np.testing.assert_allclose(got.real, n, rtol=1e-6)
    assert np.all(got.imag == 0)
    assert got.source.startswith("I. H. Malitson")
    # the reference text's glass at 1 um (Fig. 4) agrees with Malitson to 1e-3
    assert abs(materials.index("ref:glass_1um", 1e-6).real - n[1]) < 1e-3


def test_metals_are_metals_in_the_near_infrared():
    for name in ["Au", "Ag", "Cu", "Al"]:
        eta = materials.index(name, 1.064e-6)
        assert -eta.imag > 5 * eta.real  # kappa >> n: free-electron metals


def test_presets_are_the_reference_values_exactly():
    assert materials.index("ref:copper_thilak", 0.5e-6) == 0.314 - 3.544j
    assert materials.index("ref:al_1550", 1.55e-6) == 1.44 - 16j
    assert materials.index("ref:fe_1550", 1.55e-6) == 3.60 - 5.88j
    assert materials.index("ref:gold_1064", 1.064e-6) == 0.285 - 7.3523j
    assert materials.index("green_paint", 1.55e-6) == 1.39 - 0.34j
    assert "Fig. 44" in materials.index("ref:teflon_1550", 1.55e-6).source


def test_array_wavelengths_carry_source():
    eta = materials.index("Fe", np.array([1.0e-6, 1.55e-6]))
    assert eta.shape == (2,)
    assert "Johnson" in eta.source


@pytest.mark.parametrize("name, wl", [("Au", 3e-6), ("Fe", 0.1e-6), ("PTFE", 0.5e-6)])
def test_outside_range_is_an_error_not_nan(name, wl):
    with pytest.raises(ValueError, match="wavelength"):
        materials.index(name, wl)


def test_unknown_material_and_bad_wavelength():
    with pytest.raises(ValueError, match="unknown material"):
        materials.index("unobtainium", 1e-6)
    with pytest.raises(ValueError, match="wavelength"):
        materials.index("Au", -1e-6)
    with pytest.raises(ValueError, match="wavelength"):
        materials.index("Au", np.nan)
