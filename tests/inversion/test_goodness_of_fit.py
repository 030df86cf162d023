"""The posterior's goodness-of-fit check: data that do not fit the model within their stated errors
(understated noise, a wrong geometry) are flagged, with the chi-square checked against an independent
least-squares fit and the explicit covariance; consistent data are not."""

import warnings

import numpy as np
import pytest
from scipy import optimize, stats

from scatterlab.inversion import (
    ConvergenceWarning,
    MisfitWarning,
    model_dolp,
    sample_posterior,
    sample_posteriors,
)
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.posterior import FIT_P_MIN, DolpLogPosterior

TH = np.radians(np.arange(20, 75, 5.0))  # 11 specular geometries
PAINT = (1.39, 0.34, 0.3)


def _sample(y, noise, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return sample_posterior(y, TH, TH, noise, rng=1, sigma=0.3, n_steps=600, **kw)


def _independent_chi2(y, noise):
    """Least-squares chi-square of (n, kappa) at sigma 0.3 by scipy, from several starts, in the box."""
    best = np.inf
    for start in ((1.5, 0.1), (1.4, 0.3), (3.0, 3.0), (1.0, 8.0)):
        fit = optimize.least_squares(
            lambda p: (model_dolp(p[0], p[1], 0.3, TH, TH) - y) / noise,
            start,
            bounds=([0.0, 0.0], [5.0, 25.0]),
            xtol=1e-14,
            ftol=1e-14,
        )
        best = min(best, float(np.sum(fit.fun**2)))
    return best


def test_understated_noise_is_flagged_with_the_independent_chi_square():
    """Noise 0.05 stated as 0.005 (the new user's case): chi-square ~ 100 x its degrees of freedom,
    a MisfitWarning and a message; the chi-square equals scipy's least-squares minimum."""
    y = model_dolp(*PAINT, TH, TH) + 0.05 * np.random.default_rng(0).standard_normal(TH.size)
    with pytest.warns(MisfitWarning, match="do not fit the model"):
        post = _sample(y, 0.005)
    g = post.fit_check
    assert g["dof"] == TH.size - 2
    np.testing.assert_allclose(g["chi2"], _independent_chi2(y, 0.005), rtol=1e-6)
    assert g["p_value"] < FIT_P_MIN
    assert any("do not fit the model" in m for m in post.messages)
    assert post.summary()["goodness_of_fit"] == g


def test_stated_noise_that_is_right_passes_and_never_exceeds_the_truth_chi_square():
    """With the true noise the best fit's chi-square lies below the one at the truth (an independent
    chi-square with 11 degrees of freedom), the p-value is unremarkable and nothing is flagged."""
    rng = np.random.default_rng(3)
    y = model_dolp(*PAINT, TH, TH) + 0.01 * rng.standard_normal(TH.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        post = _sample(y, 0.01)
    g = post.fit_check
    at_truth = float(np.sum(((model_dolp(*PAINT, TH, TH) - y) / 0.01) ** 2))
    assert 0 <= g["chi2"] <= at_truth + 1e-9
    np.testing.assert_allclose(g["chi2"], _independent_chi2(y, 0.01), rtol=1e-6)
    assert g["p_value"] == pytest.approx(stats.chi2.sf(g["chi2"], TH.size - 2))
    assert g["p_value"] > FIT_P_MIN and not any("do not fit" in m for m in post.messages)


def test_p_values_of_consistent_data_are_uniform_enough_to_flag_about_one_in_a_thousand():
    """Over 40 noise draws at the true noise, the chi-square p-values are spread over (0, 1) (a
    Kolmogorov-Smirnov test against the uniform does not reject at 1 %) and none is below FIT_P_MIN
    (expected 0.04 of them)."""
    rng = np.random.default_rng(5)
    truth = model_dolp(*PAINT, TH, TH)
    p = []
    for _ in range(40):
        y = truth + 0.01 * rng.standard_normal(TH.size)
        p.append(stats.chi2.sf(_independent_chi2(y, 0.01), TH.size - 2))
    assert stats.kstest(p, "uniform").pvalue > 0.01
    assert min(p) > FIT_P_MIN


def test_a_wrong_azimuth_is_flagged():
    """Data measured out of the specular plane (phi = 2 rad) fitted as specular (phi = pi)."""
    y = model_dolp(*PAINT, TH, TH, phi=2.0) + 0.005 * np.random.default_rng(1).standard_normal(
        TH.size
    )
    with pytest.warns(MisfitWarning):
        post = _sample(y, 0.005)
    assert post.fit_check["p_value"] < FIT_P_MIN


def test_inferred_noise_has_nothing_to_test():
    y = model_dolp(*PAINT, TH, TH) + 0.05 * np.random.default_rng(0).standard_normal(TH.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        post = _sample(y, None)
    assert post.fit_check is None and post.summary()["goodness_of_fit"] is None


def test_chi_square_of_the_correlated_error_model_equals_the_explicit_covariance():
    """The Sherman-Morrison form (noise, systematic, a shared error c) and a full covariance give the
    Mahalanobis norm r^T V^-1 r of numpy's dense solve."""
    rng = np.random.default_rng(2)
    forward = DolpForward(TH, TH, sigma=0.3)
    y = model_dolp(*PAINT, TH, TH)
    syst = rng.uniform(0.001, 0.01, TH.size)
    c = rng.uniform(0.002, 0.02, TH.size)
    V = np.diag(0.004**2 + syst**2) + np.outer(c, c)
    f = y[None] + rng.normal(0, 0.01, (5, TH.size))
    r = f - y
    expected = np.einsum("wi,wi->w", r, np.linalg.solve(V, r.T).T)
    lo, hi = np.zeros(2), np.array([5.0, 25.0])
    sm = DolpLogPosterior(
        forward,
        y,
        lo,
        hi,
        fit_sigma=False,
        log_kappa=False,
        noise=0.004,
        systematic=syst,
        correlated=c,
    )
    full = DolpLogPosterior(
        forward,
        y,
        lo,
        hi,
        fit_sigma=False,
        log_kappa=False,
        noise=None,
        covariance=V - np.diag(syst**2),
        systematic=syst,
    )
    np.testing.assert_allclose(sm.chi2(f), expected, rtol=1e-10)
    np.testing.assert_allclose(full.chi2(f), expected, rtol=1e-10)
    with pytest.raises(ValueError, match="known error model"):
        DolpLogPosterior(forward, y, lo, hi, fit_sigma=False, log_kappa=False, noise=None).chi2(f)


def test_many_posteriors_say_how_many_misfit_in_one_warning():
    rng = np.random.default_rng(4)
    truth = model_dolp(*PAINT, TH, TH)
    y = np.stack(
        [truth + 0.001 * rng.standard_normal(TH.size), truth + 0.05 * rng.standard_normal(TH.size)]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        with pytest.warns(MisfitWarning, match="1 of 2 posteriors"):
            posts = sample_posteriors(y, TH, TH, 0.001, rng, sigma=0.3, n_steps=400)
    assert posts[0].fit_check["p_value"] > FIT_P_MIN > posts[1].fit_check["p_value"]


def test_the_posterior_report_gives_the_goodness_of_fit_and_the_warning():
    from scatterlab.inversion.report import _markdown

    y = model_dolp(*PAINT, TH, TH) + 0.05 * np.random.default_rng(0).standard_normal(TH.size)
    with pytest.warns(MisfitWarning):
        post = _sample(y, 0.005)
    text = _markdown(post, "paint", PAINT)
    assert f"chi-square {post.fit_check['chi2']:.2f} for 9 degrees of freedom" in text
    assert "**the data do not fit the model within these errors**" in text
    assert "**Warnings:**" in text and "do not fit the model within their stated errors" in text


def test_a_problem_without_light_is_refused_before_the_batch_runs():
    y = np.stack([model_dolp(*PAINT, TH, TH), np.full(TH.size, np.nan)])
    with pytest.raises(ValueError, match=r"1 problem\(s\) without a finite value \(rows \[1\]\)"):
        sample_posteriors(y, TH, TH, 0.01, 1, sigma=0.3)
