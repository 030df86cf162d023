import warnings

import numpy as np
import pytest

from scatterlab.ellipsometry import fit_mueller_elements, normalised_elements
from scatterlab.ellipsometry.fit import model_elements
from scatterlab.pbrdf import Model

THETA = np.radians(np.arange(10, 81, 10))


@pytest.mark.parametrize(
    "eta, sigma", [(0.285 - 7.3523j, 0.44), (1.226 - 10.413j, 0.43), (3.6 - 5.88j, 0.2)]
)
def test_noise_free_fit_recovers_eta_and_sigma(eta, sigma):
    y = normalised_elements(Model(sigma).mueller(eta, THETA, THETA, np.pi))
    fit = fit_mueller_elements(THETA, y)
    assert fit.n == pytest.approx(eta.real, abs=1e-6)
    assert fit.kappa == pytest.approx(-eta.imag, abs=1e-6)
    assert fit.sigma == pytest.approx(sigma, abs=1e-6)
    assert fit.eta == pytest.approx(eta, abs=1e-6)


def test_known_sigma_and_covariance_scaling():
    eta, sigma = 0.285 - 7.3523j, 0.44
    y = model_elements(THETA, eta.real, -eta.imag, sigma)
    rng = np.random.default_rng(0)
    std = np.full_like(y, 2e-3)
    fit = fit_mueller_elements(
        THETA, y + std * rng.standard_normal(y.shape), std=std, sigma=sigma, fit_sigma=False
    )
    assert fit.sigma == sigma
    assert (
        abs(fit.n - eta.real) < 5 * fit.errors[0] and abs(fit.kappa + eta.imag) < 5 * fit.errors[1]
    )


def test_bad_input():
    with pytest.raises(ValueError, match="measured"):
        fit_mueller_elements(THETA, np.zeros((3, 4)))
    with pytest.raises(ValueError, match="sigma"):
        fit_mueller_elements(THETA, np.zeros((THETA.size, 4)), fit_sigma=False)
    with pytest.raises(ValueError, match="theta"):
        fit_mueller_elements(THETA + 2, np.zeros((THETA.size, 4)))


def test_rejects_negative_std_and_elements_outside_the_unit_interval():
    y = model_elements(THETA, 1.4, 7.0, 0.3)
    with pytest.raises(ValueError, match="std"):
        fit_mueller_elements(THETA, y, std=np.full_like(y, -1e-3))
    with pytest.raises(ValueError, match="std"):
        fit_mueller_elements(THETA, y, std=np.zeros_like(y))
    bad = y.copy()
    bad[2, 1] = 1.2  # e.g. a percent/fraction mix-up or a wrong normalisation
    with pytest.raises(ValueError, match=r"measured\[2, 1\] = 1.2.*\[-1, 1\]"):
        fit_mueller_elements(THETA, bad)
    bad[2, 1] = 1.03  # within the stated tolerance (noise)
    fit_mueller_elements(THETA, bad, starts=((1.5, 10.0),))
    with pytest.raises(ValueError, match="starts"):
        fit_mueller_elements(THETA, y, starts=())


BAD_BOUNDS = [
    (((np.nan, 10), (0, 30), (0.01, 1.5)), "finite"),
    (((0.01, 10), (0, 30)), r"shape \(3, 2\)"),
    (((0.01, 10), (0, 30), (0.0, 1.5)), r"sigma within \[0.0001, 5\]"),
    (((0.01, 10), (0, 30), (0.01, 100)), r"sigma within \[0.0001, 5\]"),
    (((-5, 10), (0, 30), (0.01, 1.5)), "n_lo >= 0 and kappa_lo >= 0"),
    (((0.01, 10), (-5, 30), (0.01, 1.5)), "n_lo >= 0 and kappa_lo >= 0"),
    (((10, 0.01), (0, 30), (0.01, 1.5)), "lo < hi"),
    ("box", "got .box."),
]


@pytest.mark.parametrize("bounds, match", BAD_BOUNDS)
def test_bounds_are_checked_the_same_way_by_both_fits(bounds, match):
    from scatterlab.ellipsometry import fit_pbrdf
    from scatterlab.io import MuellerBRDF

    y = model_elements(THETA, 1.5, 0.1, 0.2)
    with pytest.raises(ValueError, match=rf"bounds must be .*{match}"):
        fit_mueller_elements(THETA, y, bounds=bounds)
    M = Model(0.2).mueller(1.5 - 0.1j, THETA, THETA, np.pi)
    with pytest.raises(ValueError, match=rf"bounds must be .*{match}"):
        fit_pbrdf(MuellerBRDF(1e-6, THETA, THETA, np.pi, M), bounds=bounds)


def test_tiny_standard_errors_are_refused_not_overflowed():
    """std = 1e-300 made the weights 1e300 and J^T J overflow; a standard error below the double
    precision of elements in [-1, 1] is refused, naming std and the allowed range."""
    y = model_elements(THETA, 1.5, 0.1, 0.2)
    with pytest.raises(ValueError, match=r"std .* must be >= 1e-15"):
        fit_mueller_elements(THETA, y, std=np.full_like(y, 1e-300))
    fit = fit_mueller_elements(THETA, y, std=np.full_like(y, 1e-15))  # the floor itself: fine
    assert [fit.n, fit.kappa, fit.sigma] == pytest.approx([1.5, 0.1, 0.2], abs=1e-6)


def _in_plane(d, a, b, e, scale=1.0):
    """A Mueller matrix of the specular-plane form with normalised elements (d, a, b, e) exactly."""
    return scale * np.array(
        [[1.0, d, 0.0, 0.0], [d, a, 0.0, 0.0], [0.0, 0.0, b, e], [0.0, 0.0, -e, b]]
    )


def test_normalised_elements_of_a_subnormal_m00_are_the_ratios_or_a_clear_error():
    """M00 = 1e-310 (subnormal) with normal elements: the ratio exceeds the largest double, which
    overflowed with a RuntimeWarning; now a ValueError naming M and the element. Representable ratios
    stay correctly rounded without a warning: a matrix scaled by 1e-310 (44 bits left) or 1e300 has
    the normalised elements it was built with, and M00 = 1e-310 with M01 = 1e-300 gives 1e10."""
    truth = np.array([-0.3, 0.9, 0.7, 0.2])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for scale in (1e-310, 1e-300, 1.0, 1e300):
            np.testing.assert_allclose(
                normalised_elements(_in_plane(*truth, scale)), truth, rtol=1e-12
            )
        M = np.diag([1e-310, 1e-300, 0.0, 0.0])
        M[0, 1] = 5e-301
        np.testing.assert_allclose(normalised_elements(M), [5e9, 1e10, 0.0, 0.0], rtol=1e-12)
        M = np.stack([np.zeros((4, 4)), _in_plane(*truth, 0.5), _in_plane(*truth, 0.5)])
        M[2, 0, 0] = 1e-310  # no longer physical: |M01| = 0.15 > M00
        with pytest.raises(ValueError, match=r"M\[2, 0, 1\] / M\[2, 0, 0\] .* exceeds the largest"):
            normalised_elements(M)
        M[2, 0, 0] = 0.0  # no light: NaN, as documented
        out = normalised_elements(M)
        assert np.all(np.isnan(out[[0, 2]])) and np.allclose(out[1], truth, rtol=1e-15)
        for bad in (np.inf, np.nan):  # inf / inf was NaN with an "invalid value" warning
            M = _in_plane(*truth)
            M[0, 0] = M[1, 1] = bad
            with pytest.raises(ValueError, match="M must be finite"):
                normalised_elements(M)


@pytest.mark.parametrize(
    "options",
    [{}, {"diffuse": "none"}, {"shadowing": "none"}, {"shadowing": "smith"}],
)
def test_model_elements_at_exactly_grazing_are_the_limit_of_the_fresnel_matrix(options):
    """At theta = pi/2 (the float) the specular term diverges and Model.mueller holds it at 0, so the
    ratios were the diffuse term's (0, 0, 0, 0), or NaN without it. The specular term dominates there:
    the ratios' limit is the Fresnel matrix's at grazing incidence, where r_s = r_p = -1 for any
    interface (Eq. 55: (0, 1, 1, 0)), and the values just above the horizon converge to it (linearly
    in cos theta, once it is well below 1 / |eta|: slowest for |eta| = 1e3)."""
    for n, kappa in ((1.5, 0.01), (3.6, 5.88), (0.2, 1e3)):
        at = model_elements(np.array([np.pi / 2]), n, kappa, 0.3, **options)[0]
        np.testing.assert_allclose(at, [0, 1, 1, 0], atol=1e-12)
        near = model_elements(np.pi / 2 - np.array([1e-5, 1e-6, 1e-7]), n, kappa, 0.3, **options)
        gaps = np.abs(near - at).max(axis=1)
        assert np.all(np.diff(gaps) < 0) and gaps[-1] < 1e-3, gaps
    # no interface: no light, NaN as at any angle
    assert np.all(np.isnan(model_elements(np.pi / 2, 1.0, 0.0, 0.3, **options)))
