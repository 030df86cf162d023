"""Fig. 26 study: the Priest-Germer pBRDF at the specular angle against independent truths."""

import json

import numpy as np
import pytest

from scatterlab import study_runner

FIG26 = study_runner.discover()["fig26"].module


def _fresnel_elements(eta, theta):
    """Normalised (M01, M11, M22, M23)/M00 of smooth reflection, written out here from the
    Fresnel amplitudes (rp in the convention rp = -rs at normal incidence)."""
    c, s2 = np.cos(theta), np.sin(theta) ** 2
    root = np.sqrt(eta**2 - s2 + 0j)
    rs = (c - root) / (c + root)
    rp = (eta**2 * c - root) / (eta**2 * c + root)
    total = abs(rs) ** 2 + abs(rp) ** 2
    cross = 2 * rs * np.conj(rp) / total
    return np.stack(
        [(abs(rs) ** 2 - abs(rp) ** 2) / total, np.ones_like(c), cross.real, cross.imag], -1
    )


@pytest.mark.parametrize("eta", [1.699 + 0j, 1.576 - 24.53j, 1.4 - 0.2j])
@pytest.mark.parametrize("sigma", [0.05, 0.44, 1.0])
def test_specular_elements_are_smooth_fresnel_for_any_roughness(eta, sigma):
    # at theta_i = theta_r, phi = pi the facet is the mean surface: Eq. 134 / m00 is Fresnel's
    theta = np.radians(np.linspace(0.5, 85, 50))
    got = FIG26.normalised(FIG26.priest_germer(eta, theta, sigma))
    np.testing.assert_allclose(got, _fresnel_elements(eta, theta), atol=1e-12)


def test_matrices_are_physical_and_non_depolarizing():
    theta = np.radians(np.linspace(0, 85, 40))
    for eta in (1.699 + 0j, 1.576 - 24.53j, 1.4 - 0.2j):
        r = FIG26.realizability(FIG26.priest_germer(eta, theta, 0.3))
        assert r["min_eig"] > -1e-12  # positive semi-definite coherency matrix
        assert r["second_eig"] < 1e-12  # rank one: a pure (Jones) reflection
        assert r["pure_identity"] < 1e-12
        assert r["depolarization_index"] == pytest.approx(1.0, abs=1e-9)


def test_depolarizing_matrix_is_detected():
    # the check must be able to fail: an ideal depolarizer has index 0 and rank 4
    r = FIG26.realizability(np.diag([1.0, 0.0, 0.0, 0.0])[None])
    assert r["depolarization_index"] == pytest.approx(0.0)
    assert r["second_eig"] == pytest.approx(0.25)


def test_study_quick_run(tmp_path):
    study_runner.run_study("fig26", tmp_path, quick=True, seed=3)
    m = json.loads((tmp_path / "metrics.json").read_text())["metrics"]
    assert m["verdict"] == "partly"
    # Brewster's angle of the dielectric (kappa = 0): M01/M00 = 1 at arctan(n), 0.01-deg grid
    b = m["brewster_deg"]
    assert b["argmax_M01"] == pytest.approx(
        np.degrees(np.arctan(m["materials"]["Enhanced Martin Black"][0])), abs=0.02
    )
    assert b["max_M01"] == pytest.approx(1.0, abs=1e-6)
    # the diffuse term of Eq. 177 depolarizes (index < 1); the Priest-Germer form never does
    lo, hi = m["infragold_eq177_depolarization_index_range"]
    assert lo < 0.95 and hi <= 1.0 + 1e-12
    assert m["realizability"]["LabSphere Infragold"]["depolarization_index"] == pytest.approx(1.0)
