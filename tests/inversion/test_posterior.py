"""Posterior sampling: agreement with the Laplace approximation where it is Gaussian,
checkpoint/resume,
noise as a parameter, multimodality detection, degenerate data, bad input, and calibrated credible
intervals.
"""

import warnings

import emcee
import h5py
import numpy as np
import pytest

from scatterlab.inversion import (
    ConvergenceWarning,
    model_dolp,
    sample_posterior,
    sample_posteriors,
    split_rhat,
)
from scatterlab.inversion.posterior import _clusters
from scatterlab.runtime import get_executor

TI = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
TR = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])


def quiet_sample(*a, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return sample_posterior(*a, **kw)


def test_gaussian_regime_posterior_matches_laplace_and_contains_truth():
    """Paint (1.39 - 0.34j, sigma 0.3) with noise 3e-4 over 11 geometries: the posterior is nearly
    Gaussian,
    so its standard deviations agree with the Laplace errors (to 5 %) and its median with least
    squares.
    """
    rng = np.random.default_rng(11)
    y = model_dolp(1.39, 0.34, 0.3, TI, TR) + 3e-4 * rng.standard_normal(TI.size)
    post = sample_posterior(y, TI, TR, 3e-4, rng)
    assert post.converged and not post.multimodal
    s = post.summary()
    for name, truth in zip(("n", "kappa", "sigma"), (1.39, 0.34, 0.3)):
        p = s["parameters"][name]
        np.testing.assert_allclose(p["std"], p["laplace_error"], rtol=0.05)  # measured: 0.4-1 %
        assert abs(p["median"] - p["least_squares"]) < 0.2 * p["std"]  # measured: 0.03-0.05 sd
        lo, hi = p["ci95"]
        assert lo < truth < hi
    assert post.chain.shape[-1] == 3 and post.n_steps >= 50 * np.max(post.tau)
    assert 0.15 < post.acceptance < 0.7 and np.all(post.rhat < 1.05)


def test_known_sigma_fills_the_column_and_log_uniform_kappa_prior():
    rng = np.random.default_rng(2)
    y = model_dolp(1.5, 0.02, 0.2, TI[:7], TR[:7]) + 2e-3 * rng.standard_normal(7)
    post = quiet_sample(
        y, TI[:7], TR[:7], 2e-3, rng, sigma=0.2, kappa_prior="log-uniform", n_steps=1500
    )
    assert np.all(post.chain[..., 2] == 0.2)
    assert np.all(post.chain[..., 1] >= 1e-3)  # log-uniform prior's floor
    assert post.summary()["prior"]["kappa"] == "log-uniform"


def test_noise_level_as_a_parameter_is_recovered():
    rng = np.random.default_rng(4)
    ti = np.radians(np.linspace(20, 70, 40))
    y = model_dolp(1.5, 0.1, 0.3, ti, ti) + 0.01 * rng.standard_normal(ti.size)
    post = quiet_sample(y, ti, ti, None, rng, sigma=0.3, n_steps=3000)
    lo, hi = post.summary()["parameters"]["noise"]["ci68"]
    assert post.noise_chain is not None
    assert 0.7 * lo < 0.01 < 1.3 * hi  # the 68 % interval (widened by 30 % for 40 samples' scatter)


def test_checkpoint_and_resume_continue_the_same_chain(tmp_path):
    y = model_dolp(1.39, 0.34, 0.3, TI, TR) + 2e-3 * np.random.default_rng(0).standard_normal(
        TI.size
    )
    path = tmp_path / "chain.h5"
    first = quiet_sample(y, TI, TR, 2e-3, np.random.default_rng(1), n_steps=200, backend=path)
    stored = [
        emcee.backends.HDFBackend(
            str(path), name=f"posterior/ensemble_{k}", read_only=True
        ).get_chain()
        for k in range(first.n_ensembles)
    ]
    resumed = quiet_sample(y, TI, TR, 2e-3, np.random.default_rng(9), n_steps=450, backend=path)
    assert first.n_steps == 200 and resumed.n_steps == 450
    for k, before in enumerate(stored):
        full = emcee.backends.HDFBackend(
            str(path), name=f"posterior/ensemble_{k}", read_only=True
        ).get_chain()
        assert full.shape[0] == 450
        np.testing.assert_array_equal(full[:200], before)  # the interrupted run's steps, untouched
    # the resumed run continues the stored walkers and random state (a different rng is ignored):
    # interrupted and resumed equals one uninterrupted run, step for step
    whole = quiet_sample(
        y, TI, TR, 2e-3, np.random.default_rng(1), n_steps=450, backend=tmp_path / "whole.h5"
    )
    for k in range(first.n_ensembles):
        np.testing.assert_array_equal(
            emcee.backends.HDFBackend(
                str(path), name=f"posterior/ensemble_{k}", read_only=True
            ).get_chain(),
            emcee.backends.HDFBackend(
                str(tmp_path / "whole.h5"), name=f"posterior/ensemble_{k}", read_only=True
            ).get_chain(),
        )
    np.testing.assert_array_equal(resumed.chain, whole.chain)


def test_resuming_with_other_data_or_settings_is_refused(tmp_path):
    """Issue 20: a checkpoint written for other data silently mixed two posteriors; now the digest
    of data,
    geometries, error model, priors and sampler settings stored in the group must match."""
    y = model_dolp(1.39, 0.34, 0.3, TI, TR) + 2e-3 * np.random.default_rng(0).standard_normal(
        TI.size
    )
    path = tmp_path / "chain.h5"
    quiet_sample(y, TI, TR, 2e-3, 1, n_steps=40, n_ensembles=1, backend=path)
    changed = [
        dict(dolp=y + 1e-3),
        dict(noise=3e-3),
        dict(sigma=0.3),
        dict(kappa_prior="log-uniform"),
        dict(systematic=1e-3),
        dict(bounds={"n": (0.5, 4.0)}),
        dict(moves="stretch"),
    ]
    for change in changed:
        kw = dict(dolp=y, noise=2e-3, n_steps=80, n_ensembles=1, backend=path) | change
        with pytest.raises(ValueError, match="other data or settings"):
            quiet_sample(kw.pop("dolp"), TI, TR, kw.pop("noise"), 2, **kw)
    with pytest.raises(ValueError, match="shape"):
        quiet_sample(y, TI, TR, 2e-3, 2, n_steps=80, n_ensembles=1, n_walkers=16, backend=path)
    # the same problem resumes; the group records its digest
    assert quiet_sample(y, TI, TR, 2e-3, 2, n_steps=80, n_ensembles=1, backend=path).n_steps == 80
    with h5py.File(path, "r") as f:
        assert len(f["posterior/ensemble_0"].attrs["scatterlab_digest"]) == 64


def test_many_problems_through_an_executor_are_reproducible(tmp_path):
    y = np.stack([model_dolp(n, k, 0.3, TI, TR) for n, k in ((1.39, 0.34), (1.6, 0.05))])
    y = y + 2e-3 * np.random.default_rng(5).standard_normal(y.shape)
    a = sample_posteriors(y, TI, TR, 2e-3, np.random.default_rng(3), n_steps=300)
    with get_executor("processes", workers=2) as ex:
        b = sample_posteriors(
            y, TI, TR, 2e-3, np.random.default_rng(3), n_steps=300, executor=ex, backend=tmp_path
        )
    assert len(a) == 2 and (tmp_path / "problem_1.h5").exists()
    for pa, pb in zip(a, b):
        np.testing.assert_array_equal(pa.chain, pb.chain)


def test_a_failed_emcee_run_is_rerun_once_with_de_moves(monkeypatch):
    """emcee's KDE move can meet a singular covariance (LinAlgError) and a move can propose NaN
    (ValueError); sample_posteriors reruns that one problem with DE moves instead of failing the batch, says
    so in its messages, and a second failure propagates."""
    from scatterlab.inversion import posterior as post_mod

    real, calls = post_mod.sample_posterior, []

    def flaky(y, *a, **kw):
        calls.append(kw.get("moves"))
        if len(calls) == 1:
            raise np.linalg.LinAlgError("singular matrix")
        return real(y, *a, **kw)

    monkeypatch.setattr(post_mod, "sample_posterior", flaky)
    y = model_dolp(1.39, 0.34, 0.3, TI, TR)[None]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        (p,) = sample_posteriors(y, TI, TR, 2e-3, np.random.default_rng(3), n_steps=200)
    assert calls == [None, "de"]
    assert any("rerun with DE moves" in m for m in p.messages)
    assert np.isfinite(p.chain).all()

    def broken(y, *a, **kw):
        raise ValueError("At least one parameter value was NaN")

    monkeypatch.setattr(post_mod, "sample_posterior", broken)
    from scatterlab.runtime.executors import TaskError

    with pytest.raises(TaskError, match="parameter value was NaN"):
        sample_posteriors(y, TI, TR, 2e-3, np.random.default_rng(3), n_steps=200)


def test_multimodality_detector_separates_two_clusters_and_not_one():
    rng = np.random.default_rng(0)
    one = rng.normal([3.0, 5.0, 0.3], [0.05, 0.05, 0.01], (32, 3))
    sd = np.array([0.2, 0.2, 0.02])
    assert len(_clusters(one, sd, rng)) == 1
    two = one.copy()
    two[:12, :2] += [4.0, -3.0]  # a dielectric-like second mode, 20 within-walker sds away
    modes = _clusters(two, sd, rng)
    assert len(modes) == 2
    np.testing.assert_allclose(sorted(m["weight"] for m in modes), [12 / 32, 20 / 32])


def test_split_rhat_flags_disagreeing_chains():
    rng = np.random.default_rng(0)
    same = rng.standard_normal((1000, 8, 1))
    shifted = same + np.r_[0, 0, 0, 0, 3, 3, 3, 3][None, :, None]
    assert split_rhat(same)[0] < 1.01
    assert split_rhat(shifted)[0] > 1.5


@pytest.mark.parametrize("case", ["zero", "one", "noise", "nan", "kappa0_sigma_small"])
def test_degenerate_data_give_finite_reports(case):
    rng = np.random.default_rng(7)
    y = model_dolp(1.5, 0.0, 1e-3, TI, TR)
    if case == "zero":
        y = np.zeros(TI.size)
    elif case == "one":
        y = np.ones(TI.size)
    elif case == "noise":
        y = rng.uniform(0, 1, TI.size)
    elif case == "nan":
        y[[1, 4, 8]] = np.nan
    post = quiet_sample(y, TI, TR, 0.01, rng, n_steps=300)
    assert np.all(np.isfinite(post.chain)) and np.all(np.isfinite(post.log_prob))
    s = post.summary()
    assert all(np.isfinite(s["parameters"][k]["median"]) for k in ("n", "kappa", "sigma"))


def test_bad_input():
    y = model_dolp(1.5, 0.0, 0.3, TI, TR)
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="noise"):
        sample_posterior(y, TI, TR, -1.0, rng)
    with pytest.raises(ValueError, match="kappa_prior"):
        sample_posterior(y, TI, TR, 0.01, rng, kappa_prior="jeffreys")
    with pytest.raises(ValueError, match="n_walkers"):
        sample_posterior(y, TI, TR, 0.01, rng, n_walkers=4)
    with pytest.raises(ValueError, match="finite values"):
        sample_posterior(np.full(TI.size, np.nan), TI, TR, 0.01, rng)
    with pytest.raises(ValueError, match="bounds"):
        sample_posterior(y, TI, TR, 0.01, rng, bounds={"n": (3.0, 1.0)})
    with pytest.raises(ValueError, match="sample_posteriors"):
        sample_posterior(np.stack([y, y]), TI, TR, 0.01, rng)


@pytest.mark.slow
def test_credible_intervals_are_calibrated_over_200_trials():
    """Coverage: 200 noisy data sets (paint, noise 2e-3, 11 geometries); the 68 % and 95 % intervals
    of each
    parameter contain the truth at their nominal rates within 3 binomial standard errors (3.3 % and
    1.5 %).
    """
    truth = np.array([1.39, 0.34, 0.3])
    rng = np.random.default_rng(2024)
    y = model_dolp(*truth, TI, TR) + 2e-3 * rng.standard_normal((200, TI.size))
    with get_executor("processes", workers=2) as ex:
        posts = sample_posteriors(y, TI, TR, 2e-3, rng, n_steps=800, executor=ex)
    for level, nominal in ((0.68, 0.68), (0.95, 0.95)):
        inside = np.array(
            [[lo <= t <= hi for lo, hi, t in zip(*p.interval(level), truth)] for p in posts]
        )
        rate = inside.mean(0)
        se = np.sqrt(nominal * (1 - nominal) / len(posts))
        assert np.all(np.abs(rate - nominal) < 3 * se), (level, rate)


def test_the_sampler_runs_with_one_blas_thread():
    """The moves' linear algebra is on (walkers x D) matrices: BLAS threads would only contend with each
    other and with a process pool (on a busy 2-core machine ten times slower)."""
    from threadpoolctl import threadpool_info

    from scatterlab.inversion.posterior import SamplerOptions, run_ensembles

    seen = []

    def log_prob(P):
        seen.extend(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")
        return -0.5 * np.sum(P**2, axis=1)

    opts = SamplerOptions(n_walkers=8, n_steps=3)
    run_ensembles(log_prob, 2, [np.random.default_rng(0).normal(size=(8, 2))], opts, [1])
    assert seen and set(seen) == {1}


def test_a_singular_kde_move_is_rerun_with_de_moves():
    """Eight walkers for three parameters: emcee's KDE move met a singular covariance of one half of the
    walkers (numpy's LinAlgError escaped to the user in 2 of 10 seeds); it is rerun with DE moves, and
    says so."""
    g = np.r_[0.3, 0.6, 1.0, 1.2]
    post = quiet_sample(
        model_dolp(1.5, 0.1, 0.1, g, g), g, g, 0.01, 0, n_walkers=8, n_ensembles=1, n_steps=20
    )
    assert any("rerun with DE moves" in m for m in post.messages)
    assert np.all(np.isfinite(post.chain))


def test_a_known_sigma_is_reported_as_known_not_as_an_interval():
    from scatterlab.inversion.report import summary_table

    th = np.radians([30.0, 40.0, 50.0, 60.0])
    post = quiet_sample(
        model_dolp(1.39, 0.34, 0.3, th, th), th, th, 0.005, 1, sigma=0.3, n_steps=200
    )
    table = summary_table(post, truth=(1.39, 0.34, 0.3))
    assert "| sigma | 0.3 (known, not sampled) |" in table and "[0.3, 0.3]" not in table
