"""Convergence diagnostics valid for an ensemble sampler (issue 14, item 4): R-hat between
independent
ensembles, tau-based effective sample sizes, the convergence flag with its reason, and the ArviZ
export.
"""

import warnings

import numpy as np
import pytest

from scatterlab.inversion import (
    ConvergenceWarning,
    effective_sample_size,
    ensemble_rhat,
    model_dolp,
    sample_posterior,
    split_rhat,
)

TI = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
TR = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])


def ar1(rng, steps, walkers, rho, shift=0.0):
    """Stationary AR(1) chains with unit variance: integrated autocorrelation time (1 + rho) / (1 -
    rho)."""
    x = np.empty((steps, walkers))
    x[0] = rng.standard_normal(walkers)
    e = np.sqrt(1 - rho**2) * rng.standard_normal((steps, walkers))
    for t in range(1, steps):
        x[t] = rho * x[t - 1] + e[t]
    return x[..., None] + shift


def test_effective_sample_size_of_ar1_chains_matches_the_analytic_tau():
    """AR(1) with rho = 0.8 has tau = 9 exactly; 32 walkers x 4000 steps estimate it to a few per
    cent
    (emcee's windowed estimator; tolerance 10 %)."""
    rng = np.random.default_rng(0)
    x = ar1(rng, 4000, 32, 0.8)
    np.testing.assert_allclose(effective_sample_size(x), 4000 * 32 / 9.0, rtol=0.1)
    iid = rng.standard_normal((2000, 16, 2))
    np.testing.assert_allclose(effective_sample_size(iid), 2000 * 16, rtol=0.1)
    assert np.isnan(effective_sample_size(np.ones((100, 4, 1)))[0])  # a fixed parameter has no ESS


def test_ensemble_rhat_flags_ensembles_in_different_places_and_not_agreeing_ones():
    """Two ensembles of correlated chains: R-hat - 1 ~ 1 / (2 ESS per half-ensemble) when they
    sample the same
    distribution (here ~1e-3 < 0.01), and ~ shift^2 / 8 when one is displaced by 0.5 sd (0.03 >
    0.01).
    """
    rng = np.random.default_rng(1)
    same = np.concatenate([ar1(rng, 2000, 16, 0.8), ar1(rng, 2000, 16, 0.8)], axis=1)
    assert ensemble_rhat(same, 2)[0] < 1.01
    apart = np.concatenate([ar1(rng, 2000, 16, 0.8), ar1(rng, 2000, 16, 0.8, shift=0.5)], axis=1)
    assert ensemble_rhat(apart, 2)[0] > 1.02
    # the walkers of one ensemble share its position: a walker-wise split R-hat cannot see a second
    # ensemble
    # stuck elsewhere once each ensemble's walkers agree among themselves, the ensemble R-hat can
    common = rng.standard_normal((2000, 1, 1))
    stuck = np.concatenate(
        [
            common + 0.01 * rng.standard_normal((2000, 16, 1)),
            common + 3 + 0.01 * rng.standard_normal((2000, 16, 1)),
        ],
        axis=1,
    )
    assert ensemble_rhat(stuck, 2)[0] > 1.5 and split_rhat(stuck[:, :16])[0] < 1.01
    assert np.isnan(ensemble_rhat(same[:3], 2)[0])


def test_posterior_reports_ess_rhat_and_why_it_is_not_converged():
    rng = np.random.default_rng(3)
    y = model_dolp(1.39, 0.34, 0.3, TI, TR) + 2e-3 * rng.standard_normal(TI.size)
    with pytest.warns(ConvergenceWarning, match="autocorrelation times"):
        short = sample_posterior(y, TI, TR, 2e-3, rng, n_steps=60)
    assert not short.converged and "autocorrelation times" in short.convergence_reason
    s = short.summary()
    d = s["diagnostics"]
    assert d["n_ensembles"] == 2 and d["walkers"] == 64 and not d["converged"]
    assert set(d["ess"]) == {"n", "kappa", "sigma"} and d["convergence_reason"]
    for p in ("n", "kappa", "sigma"):
        assert {"median", "ci68", "ci95", "ess", "rhat"} <= set(s["parameters"][p])
    # the ESS of 60 steps of 64 walkers is at most 64 * 60 / tau
    assert all(0 < d["ess"][p] <= 64 * 60 for p in d["ess"])


def test_inference_data_export_agrees_with_arviz_own_diagnostics():
    """ArviZ's ESS (walkers as chains, Geyer's initial-monotone estimator) is a peer estimate of the
    same
    quantity as ours (emcee's windowed tau): they agree within a factor of two on a converged run.
    """
    import arviz as az

    rng = np.random.default_rng(4)
    y = model_dolp(1.5, 0.1, 0.3, TI, TR) + 2e-3 * rng.standard_normal(TI.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        post = sample_posterior(y, TI, TR, None, rng, sigma=0.3, n_steps=800)
    idata = post.to_inference_data()
    assert idata.posterior.sizes["chain"] == post.chain.shape[1]
    assert idata.posterior.sizes["draw"] == post.chain.shape[0]
    np.testing.assert_array_equal(idata.posterior["kappa"].values, post.chain[..., 1].T)
    assert "noise" in idata.posterior and idata.posterior.attrs["n_ensembles"] == 2
    ours = post.summary()["parameters"]
    for p in ("n", "kappa", "noise"):
        # thinning by tau / 2 keeps the ESS (tau of the kept draws shrinks by the same factor)
        theirs = float(az.ess(idata, var_names=[p], method="bulk")[p])
        assert 0.5 < theirs / ours[p]["ess"] < 2.0, (p, theirs, ours[p]["ess"])


def test_messages_do_not_repeat_warnings_of_discarded_least_squares_starts():
    # README example: paint at seven specular geometries, sigma known. Some least-squares starts end
    # where kappa is undetermined; the kept minimum determines it, so the posterior's messages must
    # not say "the data do not determine kappa" (four times) beside a finite kappa interval
    th = np.radians([30, 35, 40, 45, 50, 55, 60])
    rng = np.random.default_rng(1)
    y = model_dolp(1.39, 0.34, 0.3, th, th) + 0.005 * rng.standard_normal(7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = sample_posterior(y, th, th, 0.005, 1, sigma=0.3, n_steps=60)
    ls = [m for m in post.messages if m.startswith("least squares")]
    assert ls == []
    lo, hi = post.interval(0.68)[..., 1]  # kappa: finite and about the noise's width
    assert np.isfinite(lo) and np.isfinite(hi) and 0 < hi - lo < 0.2


def test_a_corner_plot_of_a_collapsed_posterior_logs_nothing(caplog):
    """corner logs "Too few points to create valid contours" on the root logger (which prints it on
    the console) when nearly all samples fall in one bin; the report's figure stays quiet."""
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from scatterlab.inversion.report import _corner_figure

    rng = np.random.default_rng(0)
    samples = np.r_[rng.normal(0, 1e-9, (999, 2)), [[1.0, 1.0]]]
    with caplog.at_level("WARNING"):
        fig = _corner_figure(SimpleNamespace(samples=samples), ["n", "kappa"], None)
    plt.close(fig)
    assert not caplog.records
    import logging

    assert logging.root.manager.disable == logging.NOTSET  # logging is on again afterwards


def test_ensemble_rhat_names_a_bad_ensemble_count():
    """An ensemble count below 1 or one that does not divide the walkers is an error, not a silent NaN."""
    chain = np.random.default_rng(0).normal(size=(100, 8, 2))
    for bad in (0, -1, 3, 1.5):
        with pytest.raises(ValueError, match="n_ensembles"):
            ensemble_rhat(chain, bad)
    assert np.all(ensemble_rhat(chain, 4) < 1.1)
