"""The joint likelihood-ratio confidence region of (n, kappa) and the posterior contraction.

Independent truths: a fixed truth lies in the 68 % region in about 68 % of noisy data sets (Wilks' theorem),
also for copper at 30-60 deg, whose DOLP fixes about Re(1/eta) only and whose marginal credible intervals
(placed along that ridge by the prior) miss it; the noise profile has the closed form s^2 = mean(r^2).
"""

import warnings

import numpy as np
import pytest

from scatterlab.characterization.estimation import DETERMINED_CONTRACTION
from scatterlab.inversion import ConvergenceWarning, model_dolp, sample_posterior, sample_posteriors
from scatterlab.runtime import get_executor

THETA = np.radians([30.0, 40.0, 50.0, 60.0])
SIGMA = 0.3
COPPER = np.array([0.61, 10.4])  # 1550 nm


def _data(truth, noise, trials, rng):
    return model_dolp(*truth, SIGMA, THETA, THETA) + noise * rng.standard_normal(
        (trials, THETA.size)
    )


def test_the_joint_region_covers_a_fixed_copper_truth_where_the_marginal_intervals_do_not():
    rng = np.random.default_rng(11)
    y = _data(COPPER, 5e-3, 40, rng)
    with warnings.catch_warnings(), get_executor("processes", workers=2) as ex:
        warnings.simplefilter("ignore", ConvergenceWarning)
        posts = sample_posteriors(y, THETA, THETA, 5e-3, rng, sigma=SIGMA, n_steps=400, executor=ex)
    joint = np.array([[p.confidence_region(COPPER, lv) for lv in (0.68, 0.95)] for p in posts])
    se = np.sqrt(np.array([0.68 * 0.32, 0.95 * 0.05]) / len(posts))
    assert np.all(np.abs(joint.mean(0) - [0.68, 0.95]) < 3 * se), joint.mean(0)
    kappa68 = np.mean(
        [p.interval(0.68)[0, 1] <= COPPER[1] <= p.interval(0.68)[1, 1] for p in posts]
    )
    assert kappa68 < 0.3  # the prior puts the marginal interval at higher kappa along the ridge
    contraction = np.array([p.contraction() for p in posts])
    assert np.all(
        contraction[:, :2].max(1) < DETERMINED_CONTRACTION
    )  # reported as weakly determined
    assert np.all(contraction[:, 2] == 1.0)  # sigma known


def test_a_paint_is_determined_and_its_region_is_small():
    rng = np.random.default_rng(4)
    truth = np.array([1.39, 0.34])
    y = _data(truth, 1e-3, 1, rng)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        post = sample_posterior(y, THETA, THETA, 1e-3, rng, sigma=SIGMA, n_steps=400)
    assert np.all(post.contraction()[:2] > 0.999)
    # a point ten marginal standard deviations away in kappa is far outside the 95 % region
    sd = post.samples[:, 1].std()
    assert not post.confidence_region(post.samples.mean(0)[:2] + [0, 10 * sd], 0.95)
    assert post.likelihood_ratio([9.0, 0.3]) == np.inf  # outside the prior box (n <= 5)


def test_an_inferred_noise_is_profiled_to_its_closed_form():
    """With no systematic term the profile over the noise s of -0.5 sum(r^2/s^2 + log s^2) is at
    s^2 = mean(r^2): its value -0.5 M (1 + log mean(r^2))."""
    rng = np.random.default_rng(5)
    y = _data([1.5, 0.2], 4e-3, 1, rng)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        post = sample_posterior(y, THETA, THETA, None, rng, sigma=SIGMA, n_steps=200)
    pts = np.array([[1.5, 0.2], [1.45, 0.25], [1.6, 0.1]])
    r2 = np.mean((model_dolp(pts[:, 0], pts[:, 1], SIGMA, THETA, THETA) - y) ** 2, 1)
    expected = 0.5 * THETA.size * (1 + np.log(r2))
    np.testing.assert_allclose(post._profile_nll(2)(pts), expected, atol=2e-3)


def test_bad_points_and_levels_are_refused():
    rng = np.random.default_rng(6)
    y = _data([1.5, 0.2], 2e-3, 1, rng)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        post = sample_posterior(y, THETA, THETA, 2e-3, rng, sigma=SIGMA, n_steps=100)
    with pytest.raises(ValueError, match="points must have 2 columns"):
        post.likelihood_ratio([1.5, 0.2, 0.3])
    with pytest.raises(ValueError, match="level must be in"):
        post.confidence_region([1.5, 0.2], level=1.5)


def test_with_an_inferred_noise_the_region_keeps_its_rate_with_four_geometries():
    """Profiling the noise out of four data leaves two degrees of freedom: Wilks' chi^2_2 threshold
    would cover a paint in about 40 % of trials at 68 %; the F-based threshold holds the nominal rate."""
    rng = np.random.default_rng(12)
    truth = np.array([1.5, 0.3])
    y = _data(truth, 5e-3, 40, rng)
    with warnings.catch_warnings(), get_executor("processes", workers=2) as ex:
        warnings.simplefilter("ignore", ConvergenceWarning)
        posts = sample_posteriors(
            y,
            THETA,
            THETA,
            None,
            rng,
            sigma=SIGMA,
            n_steps=400,
            executor=ex,
            noise_bounds=(1e-4, 0.5),
        )
    joint = np.array([[p.confidence_region(truth, lv) for lv in (0.68, 0.95)] for p in posts])
    se = np.sqrt(np.array([0.68 * 0.32, 0.95 * 0.05]) / len(posts))
    assert np.all(np.abs(joint.mean(0) - [0.68, 0.95]) < 3 * se), joint.mean(0)


@pytest.mark.parametrize("inferred", [True, False])
def test_a_series_wide_error_enters_the_likelihood_as_its_rank_one_covariance(inferred):
    """Sherman-Morrison form of V = diag(s^2 + t^2) + c c^T (inferred noise) and the Cholesky form of
    C + c c^T (fixed covariance) against scipy's dense multivariate normal (which keeps the 2 pi term)."""
    from scipy.stats import multivariate_normal

    from scatterlab.inversion.forward import DolpForward
    from scatterlab.inversion.posterior import DolpLogPosterior

    f = DolpForward(THETA, THETA, sigma=SIGMA)
    rng = np.random.default_rng(8)
    y = f(np.array([[1.5, 0.3]]))[0] + 0.01 * rng.standard_normal(4)
    c, t = np.array([0.02, -0.03, 0.01, 0.04]), np.array([0.003, 0.004, 0.002, 0.001])
    pts, s = np.array([[1.4, 0.2], [1.6, 0.5]]), np.array([0.005, 0.02])
    cov = None if inferred else np.diag([1e-4, 4e-4, 9e-4, 1e-4]) + 5e-5
    lp = DolpLogPosterior(
        f,
        y,
        None,
        None,
        fit_sigma=False,
        log_kappa=False,
        noise=None,
        systematic=t,
        covariance=cov,
        correlated=c,
    )
    got = lp.log_likelihood(f(pts), s if inferred else None)
    dense = [
        (np.diag(s[k] ** 2 + t**2) if inferred else cov + np.diag(t**2)) + np.outer(c, c)
        for k in range(2)
    ]
    want = [multivariate_normal(f(pts)[k], dense[k]).logpdf(y) for k in range(2)]
    if inferred:  # the log determinant varies with s: only the 2 pi term is dropped
        np.testing.assert_allclose(got - want, 0.5 * 4 * np.log(2 * np.pi), rtol=1e-10)
    else:  # a fixed covariance drops its whole normalisation: differences between points agree
        np.testing.assert_allclose(got[0] - got[1], want[0] - want[1], rtol=1e-10)
