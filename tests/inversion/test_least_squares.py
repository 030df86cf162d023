"""Batched DOLP least squares: exact recovery, agreement with the per-pixel baseline, masking,
Laplace errors."""

import numpy as np
import pytest

from scatterlab.inversion import fit_dolp, fit_dolp_per_pixel, model_dolp
from scatterlab.inversion.forward import DolpForward
from scatterlab.pbrdf import Model, facet_dolp

# specular 30-60 deg (Ch. VII) plus an off-specular sweep at theta_i = 45 deg, which determines
# sigma (Fig. 58)
TI = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
TR = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])
TRUTH = [
    (1.39, 0.34, 0.3),
    (1.44, 16.0, 0.2),
    (3.6, 5.88, 0.3),
    (1.5, 0.0, 0.4),
]  # paint, Al, Fe, glass


def test_noise_free_recovery_to_1e_6_and_batched_equals_per_pixel():
    y = np.stack([model_dolp(n, k, s, TI, TR) for n, k, s in TRUTH])
    fit = fit_dolp(y, TI, TR)
    truth = np.array(TRUTH)
    np.testing.assert_allclose(fit.n, truth[:, 0], atol=1e-6)
    np.testing.assert_allclose(fit.kappa, truth[:, 1], atol=1e-6)
    np.testing.assert_allclose(fit.sigma, truth[:, 2], atol=1e-6)
    assert np.all(fit.converged)
    base = fit_dolp_per_pixel(y, TI, TR)
    np.testing.assert_allclose(base.n, fit.n, atol=1e-5)
    np.testing.assert_allclose(base.kappa, fit.kappa, atol=1e-5)
    np.testing.assert_allclose(base.sigma, fit.sigma, atol=1e-5)


def test_known_sigma_and_batch_shape():
    y = model_dolp(
        np.array([[1.39, 3.6]]), np.array([[0.34, 5.88]]), 0.3, TI[:7], TR[:7]
    )  # specular only
    fit = fit_dolp(y, TI[:7], TR[:7], sigma=0.3)
    assert fit.n.shape == (1, 2)
    np.testing.assert_allclose(fit.n, [[1.39, 3.6]], atol=1e-6)
    np.testing.assert_allclose(fit.kappa, [[0.34, 5.88]], atol=1e-6)
    assert fit.covariance.shape == (1, 2, 2, 2)


def test_nan_measurements_are_masked_and_underdetermined_pixels_reported():
    y = np.stack([model_dolp(1.39, 0.34, 0.3, TI, TR)] * 3)
    y[1, [0, 4]] = np.nan  # two missing angles: still fitted
    y[2, 2:] = np.nan  # two measurements left for three unknowns: not fitted
    fit = fit_dolp(y, TI, TR)
    assert fit.valid.tolist() == [True, True, False]
    np.testing.assert_allclose(fit.n[:2], 1.39, atol=1e-6)
    assert np.isnan(fit.n[2]) and not fit.converged[2]


def test_laplace_errors_match_monte_carlo_scatter_where_the_posterior_is_gaussian():
    """Iron with DOLP noise 1e-4 (a well-identified, Gaussian regime): the Laplace standard errors
    agree with
    the scatter of 150 noisy fits within 20 % (the sample standard deviation of 150 draws is known
    to ~6 %).
    At noise 5e-3 the (n, kappa) valley of metals makes the errors non-Gaussian -- posterior
    sampling's job.
    """
    rng = np.random.default_rng(5)
    clean = model_dolp(3.6, 5.88, 0.3, TI, TR)
    y = clean + 1e-4 * rng.standard_normal((150, TI.size))
    fit = fit_dolp(y, TI, TR, noise=1e-4, starts=((3.0, 4.0),))
    scatter = np.std(np.stack([fit.n, fit.kappa, fit.sigma], -1), axis=0, ddof=1)
    laplace = np.median(fit.errors, axis=0)
    np.testing.assert_allclose(laplace, scatter, rtol=0.2)


def test_bad_input():
    with pytest.raises(ValueError, match="dolp"):
        fit_dolp(np.zeros((3, 4)), TI, TR)
    with pytest.raises(ValueError, match="theta_i"):
        fit_dolp(np.zeros(TI.size), TI + 2, TR)
    with pytest.raises(ValueError, match="geometry"):
        fit_dolp(np.zeros(TI.size), TI, TR[:-1])


def test_several_starting_roughnesses_escape_the_local_minima_of_one():
    """Sigma fitted from five specular geometries: from sigma0 alone a good share of noiseless pixels
    stop in a local minimum (the truth fits exactly, so any residual above rounding is one); the default
    extra roughness starts (0.05, 1.0) remove most of them, and never end worse than sigma0 alone.
    Independent truth: the parameters the noiseless data were made from."""
    from scatterlab.inversion import FitOptions

    th = np.radians([30.0, 40.0, 50.0, 60.0, 70.0])
    rng = np.random.default_rng(0)
    N = 120
    truth = np.c_[
        rng.uniform(1.1, 4.5, N),
        np.exp(rng.uniform(np.log(0.01), np.log(20), N)),
        np.exp(rng.uniform(np.log(0.02), np.log(1.2), N)),
    ]
    y = np.stack([model_dolp(*t, th, th) for t in truth])

    def residual(fit):
        est = np.c_[fit.n, fit.kappa, fit.sigma]
        return np.array([np.max(np.abs(model_dolp(*e, th, th) - yy)) for e, yy in zip(est, y)])

    with pytest.warns(Warning):  # a few metals' kappa is undetermined
        one = residual(fit_dolp(y, th, th, options=FitOptions(sigma_starts=())))
    with pytest.warns(Warning):
        several = residual(fit_dolp(y, th, th))
    assert np.sum(several > 1e-6) < 0.6 * np.sum(one > 1e-6), (
        np.sum(one > 1e-6),
        np.sum(several > 1e-6),
    )
    assert np.all(several <= one + 1e-9)
    # the case that started this: glass-like paint from sigma0 = 1 ends on kappa = 0 alone
    y1 = model_dolp(1.5, 0.1, 0.3, th, th)
    fit = fit_dolp(y1, th, th, options=FitOptions(sigma0=1.0))
    np.testing.assert_allclose([fit.n, fit.kappa, fit.sigma], [1.5, 0.1, 0.3], atol=1e-6)


@pytest.mark.parametrize("bad", [(-0.1,), (np.nan,), "ab", ((0.1, 0.2),)])
def test_sigma_starts_are_checked(bad):
    from scatterlab.inversion import FitOptions

    with pytest.raises(ValueError, match="sigma_starts"):
        FitOptions(sigma_starts=bad).validate()


def test_a_fit_pinned_on_a_bound_says_so():
    """kappa = 1e3 with the default kappa bound 25: the fit returned 25 +- 7.8, 'converged' and
    'identifiable', without a word. The value is the bound; kappa = 0 (a lossless medium) is a physical
    limit, not a bound reached."""
    import warnings

    from scatterlab.inversion import BoundWarning

    th = np.radians([30.0, 40.0, 50.0, 60.0, 70.0])
    with pytest.warns(BoundWarning, match="in kappa"):
        fit = fit_dolp(model_dolp(1.5, 1e3, 0.1, th, th), th, th)
    assert fit.kappa == pytest.approx(25.0) and fit.at_bound.tolist() == [False, True, False]
    with warnings.catch_warnings():
        warnings.simplefilter("error", BoundWarning)
        glass = fit_dolp(model_dolp(1.5, 0.0, 0.3, th, th), th, th, sigma=0.3)
    assert not glass.at_bound.any()


# -- model_dolp is finite where the pBRDF reflects no light or diverges: the limit, or DolpForward's --
HALF_PI = np.pi / 2


def _in_unit_interval(d):
    return bool(np.all(np.isfinite(d)) and np.all((d >= 0) & (d <= 1)))


@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith", "none"])
@pytest.mark.parametrize("diffuse", ["hyde", "none"])
def test_model_dolp_at_exactly_90_deg_is_the_limit(shadowing, diffuse):
    """Exactly 90 deg (both directions, or one without shadowing): NaN before (e.g. Torrance-Sparrow
    without a diffuse term at theta_i = theta_r = 90 deg, where the lobe diverges and F holds 0). Now
    finite, the values at 89.99 deg and 90 deg - 1e-9 rad continued, and equal to DolpForward."""
    kw = dict(shadowing=shadowing, diffuse=diffuse)
    ti = np.array([HALF_PI, HALF_PI, 1.0, 0.3])
    tr = np.array([HALF_PI, 1.0, HALF_PI, 0.3])
    for n, kappa in [(1.5, 0.0), (3.23, 4.35)]:
        at = model_dolp(n, kappa, 0.3, ti, tr, **kw)
        assert _in_unit_interval(at)
        for near, tol in ((np.radians(89.99), 2e-3), (HALF_PI - 1e-9, 1e-7)):
            ti_n, tr_n = np.where(ti == HALF_PI, near, ti), np.where(tr == HALF_PI, near, tr)
            np.testing.assert_allclose(at, model_dolp(n, kappa, 0.3, ti_n, tr_n, **kw), atol=tol)
        fwd = DolpForward(ti, tr, **kw)([n, kappa, 0.3])
        np.testing.assert_allclose(at, fwd, atol=2e-5)


def test_model_dolp_where_smith_shadowing_underflows_is_the_facet_dolp():
    """Smith shadowing, sigma = 0.01, 0.1 rad to 1.4 rad: Gamma underflows and rho is 1 to rounding
    (D = 0), so F = 0 and model_dolp was NaN. Now the formula of the fits (DolpForward): Gamma/(Gamma +
    0) = 1, the facet's DOLP."""
    ti, tr = np.array([0.1, 0.1]), np.array([1.4, 1.45])
    for diffuse in ("hyde", "none"):
        kw = dict(shadowing="smith", diffuse=diffuse)
        assert np.all(np.isnan(Model(0.01, **kw).dolp(1.5, ti, tr)))  # the measurement: no light
        d = model_dolp(1.5, 0.0, 0.01, ti, tr, **kw)
        assert _in_unit_interval(d)
        np.testing.assert_allclose(d, facet_dolp(1.5, ti, tr), rtol=1e-12)
        np.testing.assert_allclose(d, DolpForward(ti, tr, **kw)([1.5, 0.0, 0.01]), rtol=1e-12)


@pytest.mark.parametrize("phi", [np.pi, 2.0])
def test_model_dolp_at_eta_one_is_the_limit(phi):
    """eta = 1 (index-matched: no interface, nothing reflected, 0/0): NaN before. Now the limit eta -> 1
    (DolpForward's value): the continuous extension of the facet's DOLP times the specular fraction."""
    th = np.radians([10.0, 30.0, 50.0, 70.0, 89.99])
    at = model_dolp(1.0, 0.0, 0.3, th, th, phi)
    assert _in_unit_interval(at) and at.max() > 0.1
    for n, kappa in [(1 + 1e-6, 0.0), (1.0, 1e-6)]:
        np.testing.assert_allclose(at, model_dolp(n, kappa, 0.3, th, th, phi), atol=1e-5)
    np.testing.assert_allclose(at, DolpForward(th, th, phi)([1.0, 0.0, 0.3]), atol=2e-5)
    batch = model_dolp(np.array([1.0, 1.5]), 0.0, 0.3, th, th, phi)  # only the dark row changes
    np.testing.assert_array_equal(batch, np.stack([at, model_dolp(1.5, 0.0, 0.3, th, th, phi)]))
