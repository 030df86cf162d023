"""Method of moments, input checks found by a fuzz review: each bad input raises a ValueError naming
the argument and its range (no NaN, overflow, warning or silently wrong number)."""

import warnings

import numpy as np
import pytest

from scatterlab.mom import (
    PlaneWave,
    TaperedWave,
    contour,
    cylinder_coefficients,
    cylinder_echo_width,
    cylinder_surface_field,
    impedance_matrix,
    incoherent_scattering,
    rough_surface,
    solve,
    solve_tm,
)
from scatterlab.mom.asymptotics import spm1_coefficient
from scatterlab.mom.exact import KA_MAX, KA_MIN
from scatterlab.mom.surfaces import LENGTH_PER_CORRELATION


def flat(n=200, dx=0.1):
    return (np.arange(n) - n / 2) * dx, np.zeros(n)


# 1. SPM1: the user's spectrum is a power spectrum (finite, >= 0), the tuple a pair


@pytest.mark.parametrize(
    "values, match",
    [(-1.0, ">= 0"), (np.nan, "finite"), (np.inf, "finite"), (1j, "real"), ("a", "real")],
)
def test_spm1_refuses_spectrum_values_that_are_not_a_power_spectrum(values, match):
    with pytest.raises(ValueError, match=rf"spectrum.*{match}"):
        spm1_coefficient(
            0.1, [0.2, 0.3], 2 * np.pi, lambda K: values if values == "a" else values + 0 * K
        )


def test_spm1_refuses_a_spectrum_of_the_wrong_shape_or_kind():
    with pytest.raises(ValueError, match="spectrum.*shape"):
        spm1_coefficient(0.1, [0.2, 0.3], 2 * np.pi, lambda K: np.ones(7))
    for bad in ((0.01, 1.0, 5.0), (0.01,), ()):
        with pytest.raises(ValueError, match="spectrum.*two entries"):
            spm1_coefficient(0.1, 0.3, 2 * np.pi, bad)
    with pytest.raises(ValueError, match="spectrum.*callable"):
        spm1_coefficient(0.1, 0.3, 2 * np.pi, 3.0)


def test_spm1_with_a_valid_callable_equals_the_gaussian_pair():
    from scatterlab.mom.surfaces import gaussian_spectrum

    th = np.radians([-60.0, 0.0, 30.0, 75.0])
    ref = spm1_coefficient(0.3, th, 2 * np.pi, (0.01, 1.0), "p", 1.5 - 0.1j)
    got = spm1_coefficient(
        0.3, th, 2 * np.pi, lambda K: gaussian_spectrum(K, 0.01, 1.0), "p", 1.5 - 0.1j
    )
    np.testing.assert_array_equal(got, ref)
    assert np.all(ref > 0)
    const = spm1_coefficient(0.3, th, 2 * np.pi, lambda K: 1e-4)  # a scalar broadcasts to K
    assert const.shape == th.shape and np.all(const > 0)


# 2. rough_surface: a periodic profile needs length >= 5 corr_length; sigma_h within double range


def expected_rms_ratio(r):
    """sqrt(E[var about the mean]) / sigma_h of the periodic profile, r = corr_length / length."""
    n = np.arange(1, 60)
    return np.sqrt(1 + 2 * np.sum(np.exp(-(n**2) / r**2)) - np.sqrt(np.pi) * r)


@pytest.mark.parametrize("corr_length", [1e9, 12.8, 12.8 / 4, 12.8 / 5 * 1.001])
def test_rough_surface_refuses_correlation_lengths_beyond_a_fifth_of_the_length(corr_length):
    with pytest.raises(ValueError, match=r"corr_length .* at most length / 5"):
        rough_surface(12.8, min(0.1, corr_length / 4), 0.1, corr_length, 0)


def test_rough_surface_rms_at_the_limit_is_within_20_percent_of_sigma_h():
    """At corr_length = length / 5 the rms height (about each realization's mean) over 400
    realizations is 0.80 sigma_h, as the Poisson sum says; at length / 20, 0.95."""
    rng = np.random.default_rng(5)
    for per in (LENGTH_PER_CORRELATION, 20.0):
        length, sh = 12.8, 0.1
        var = [np.var(rough_surface(length, 0.05, sh, length / per, rng)[1]) for _ in range(400)]
        ratio = np.sqrt(np.mean(var)) / sh
        assert abs(ratio - expected_rms_ratio(1 / per)) < 0.03
        assert ratio > 0.77
    assert expected_rms_ratio(1 / LENGTH_PER_CORRELATION) >= 0.80
    assert expected_rms_ratio(1.0) < 0.02  # what corr_length = length used to give silently


@pytest.mark.parametrize("sigma_h", [1e300, 1e141, 1e-200, -1.0, np.nan, np.inf])
def test_rough_surface_bounds_sigma_h(sigma_h):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="sigma_h"):
            rough_surface(12.8, 0.1, sigma_h, 1.0, 0)


def test_rough_surface_extreme_but_allowed_heights_are_finite_and_scaled():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, y1 = rough_surface(12.8, 0.1, 1.0, 1.0, 3)
        for sh in (1e-140, 1e140, 0.0):
            _, y = rough_surface(12.8, 0.1, sh, 1.0, 3)
            assert np.all(np.isfinite(y))
            np.testing.assert_allclose(y, sh * y1, rtol=1e-12, atol=0)


# 3. the exact cylinder series: ka one number in [KA_MIN, KA_MAX], finite phi and wavelength


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"wavelength": 0.0}, "wavelength"),
        ({"wavelength": np.nan}, "wavelength"),
        ({"wavelength": -1.0}, "wavelength"),
        ({"phi": np.nan}, "phi"),
        ({"phi": [0.0, np.inf]}, "phi"),
        ({"ka": KA_MIN / 10}, "ka"),
        ({"ka": np.nan}, "ka"),
        ({"ka": [1.0, 2.0]}, "ka"),
        ({"ka": 10 * KA_MAX}, "ka"),
    ],
)
@pytest.mark.parametrize("function", [cylinder_surface_field, cylinder_echo_width])
def test_cylinder_functions_share_their_checks(function, kwargs, match):
    args = {"ka": 2.0, "phi": 0.5, "wavelength": 1.0} | kwargs
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=match):
            function(args["ka"], args["phi"], args["wavelength"])


def test_cylinder_coefficients_bound_ka_above_and_stay_fast_at_the_bound():
    import time

    with pytest.raises(ValueError, match=r"ka must be <= 20000"):
        cylinder_coefficients(1e7)
    t0 = time.perf_counter()
    n, a, _ = cylinder_coefficients(KA_MAX)
    assert time.perf_counter() - t0 < 10  # measured 0.25 s (PEC)
    assert np.all(np.isfinite(a)) and n.size > 2 * KA_MAX
    # the valid range is unchanged: the smallest radius and an ordinary one
    assert np.all(np.isfinite(cylinder_surface_field(KA_MIN, [0.0, np.pi])))
    assert np.isfinite(cylinder_echo_width(np.float64(2.0), np.pi))


# 4. an empty incidence list


def test_solvers_refuse_an_empty_incidence_list():
    x, y = flat(400, 0.05)
    for kw in ({}, {"polarization": "p"}, {"eta": 1.5}):
        with pytest.raises(ValueError, match="incidence.*non-empty"):
            solve(x, y, 1.0, [], **kw)
    with pytest.raises(ValueError, match="incidence.*non-empty"):
        solve_tm(x, y, 1.0, ())
    sol = solve_tm(x, y, 1.0, [PlaneWave(0.3)])  # one is enough
    assert sol.current.shape == (x.size, 1)


def test_incoherent_scattering_refuses_no_incidence_angle_before_dispatching():
    x = (np.arange(640) - 320) * 0.1
    with pytest.raises(ValueError, match="theta_i.*at least one"):
        incoherent_scattering(x, 0 * x, 1.0, [], [0.1], partitions=2)


# 5. impedance_matrix checks k and the sampling as solve_tm does


@pytest.mark.parametrize("k", [1e10, 2 * np.pi * 3])
def test_impedance_matrix_refuses_undersampling(k):
    c = contour(*flat(40))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"points per wavelength \(k = "):
            impedance_matrix(c, k)


@pytest.mark.parametrize("k", [0.0, -1.0, np.nan, np.inf, [1.0, 2.0]])
def test_impedance_matrix_refuses_bad_wavenumbers(k):
    with pytest.raises(ValueError, match="k must be"):
        impedance_matrix(contour(*flat(40)), k)


def test_impedance_matrix_warns_as_solve_tm_and_keeps_its_values():
    c = contour(*flat(40))
    with pytest.warns(UserWarning, match="points per wavelength"):
        impedance_matrix(c, 2 * np.pi / 0.7)  # 7 points per wavelength
    from scatterlab.mom.efie import _impedance_matrix

    np.testing.assert_array_equal(impedance_matrix(c, 2 * np.pi), _impedance_matrix(c, 2 * np.pi))


# 6. the taper width g


@pytest.mark.parametrize("g", [1e300, 1e200, 1e151])
def test_tapered_wave_refuses_a_taper_too_wide_for_its_correction(g):
    w = TaperedWave(0.3, g)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for f in (w.check, w.incident_power):
            with pytest.raises(ValueError, match=r"g \(taper width\).*<= 1e\+150"):
                f(1.0)


@pytest.mark.parametrize("g", [1e301, np.inf, 0.0, -2.0])
def test_tapered_wave_bounds_g_at_construction(g):
    with pytest.raises(ValueError, match=r"g \(taper width\)"):
        TaperedWave(0.3, g)


def test_tapered_wave_too_narrow_for_its_power_raises_not_divides():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for g in (1e-300, np.float64(1e-300)):
            with pytest.raises(ValueError, match="taper too narrow"):
                TaperedWave(0.3, g).incident_power(2 * np.pi)
    p = TaperedWave(0.3, 15.0).incident_power(2 * np.pi)
    c = np.cos(0.3)
    corr = (1 + 2 * np.tan(0.3) ** 2) / (2 * (2 * np.pi * 15.0 * c) ** 2)
    assert p == pytest.approx(15.0 * np.sqrt(np.pi / 2) * c * (1 - corr), rel=1e-15)


def test_gaussian_spectrum_of_a_very_long_correlation_is_a_delta_without_warnings():
    """l -> inf: W(K) = sigma_h^2 l / (2 sqrt(pi)) exp(-(K l)^2 / 4) vanishes at every K != 0 (its
    integral sigma_h^2 concentrated at K = 0), also where (K l)^2 overflows."""
    import warnings

    from scatterlab.mom import spm1_coefficient
    from scatterlab.mom.surfaces import gaussian_spectrum

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.all(gaussian_spectrum(np.array([0.5, 3.0]), 1e-3, 1e300) == 0.0)
        assert gaussian_spectrum(0.0, 1e-3, 1e300) == pytest.approx(
            1e-6 * 1e300 / (2 * np.sqrt(np.pi))
        )
        assert spm1_coefficient(0.0, 0.3, 2 * np.pi, (1e-3, 1e300)) == 0.0
