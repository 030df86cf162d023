"""The study ``dolp_vs_mom`` resumes its saved MoM coefficients only when they come from a run with
the same settings (mode, seed, incidences, surfaces), so a long full run can be re-analysed without
re-solving and a changed run never reuses stale coefficients."""

import numpy as np

from scatterlab import study_runner
from scatterlab.study_runner import StudyContext

MOM = study_runner.discover()["dolp_vs_mom"].module


def _runs(rng):
    return {
        (0.3, 0.5): {
            "glass": {"coef": rng.random((2, 2, 3, 5)), "energy": rng.random((2, 2, 3))},
            "pec": {"coef": rng.random((1, 2, 3, 5)), "energy": rng.random((1, 2, 3))},
        }
    }


def test_saved_coefficients_resume_only_under_the_same_settings(tmp_path):
    runs = _runs(np.random.default_rng(1))
    settings = MOM.run_settings(StudyContext(tmp_path, quick=True, seed=3))
    path = tmp_path / "mom_runs.npz"
    MOM.save_runs(path, runs, settings)

    back = MOM.resume_runs(path, settings)
    assert back is not None
    for name, d in runs[0.3, 0.5].items():
        for q, v in d.items():
            np.testing.assert_array_equal(back[0.3, 0.5][name][q], v)

    for other in (
        StudyContext(tmp_path, quick=True, seed=4),  # another seed
        StudyContext(tmp_path, quick=False, seed=3),  # full mode: other surfaces and angles
    ):
        assert MOM.resume_runs(path, MOM.run_settings(other)) is None
    assert MOM.resume_runs(tmp_path / "absent.npz", settings) is None
    # a file saved without settings (an older run) is never resumed, but still loads by hand
    MOM.save_runs(tmp_path / "old.npz", runs)
    assert MOM.resume_runs(tmp_path / "old.npz", settings) is None
    assert set(MOM.load_runs(tmp_path / "old.npz")[0.3, 0.5]) == {"glass", "pec"}


def test_coverage_verdict_calls_over_and_under_coverage_beyond_two_binomial_errors():
    # 24 units at 68 %: two standard errors are 2 sqrt(0.68 * 0.32 / 24) = 0.19
    assert MOM.coverage_verdict(0.92, 0.68, 24) == "over-covers"
    assert MOM.coverage_verdict(0.50, 0.68, 24) == "nominal"
    assert MOM.coverage_verdict(0.45, 0.68, 24) == "under-covers"
    # 32 units at 95 %: 2 sqrt(0.95 * 0.05 / 32) = 0.077
    assert MOM.coverage_verdict(0.88, 0.95, 32) == "nominal"
    assert MOM.coverage_verdict(0.85, 0.95, 32) == "under-covers"
    assert MOM.coverage_verdict(1.0, 0.95, 32) == "nominal"


def _speckle_coef(dolp, realizations, looks, rng):
    """s and p coefficients (R, 2, ...) whose means give ``dolp`` exactly: each the mean of
    ``looks`` exponential speckles (gamma), s = (1 + d) / 2 and p = (1 - d) / 2 on average."""
    d = np.asarray(dolp, float)
    shape = (realizations,) + d.shape
    s = (1 + d) / 2 * rng.gamma(looks, 1 / looks, shape)
    p = (1 - d) / 2 * rng.gamma(looks, 1 / looks, shape)
    return np.stack([s, p], 1)


def test_leave_one_out_dolp_and_its_jackknife_error_match_a_direct_computation():
    rng = np.random.default_rng(5)
    coef = _speckle_coef(np.full(4, 0.3), 6, 30, rng)
    d, loo = MOM.dolp_loo(coef)
    for r in range(6):
        kept = np.delete(coef, r, 0).mean(0)
        np.testing.assert_allclose(loo[r], (kept[0] - kept[1]) / (kept[0] + kept[1]), rtol=1e-12)
    # jackknife: sqrt((R - 1) / R sum (loo - mean loo)^2), written out
    se = np.sqrt(5 / 6 * np.sum((loo - loo.mean(0)) ** 2, 0))
    np.testing.assert_allclose(MOM.exact_dolp(coef)[1], se, rtol=1e-12)
    assert MOM.dolp_loo(coef[:1])[1].shape == (0, 4)


def test_pooled_error_removes_the_monte_carlo_noise_from_the_rms_and_its_errors_are_calibrated():
    """Two independent cells (6 and 3 points) whose true DOLP is known and a model off by known
    amounts: over 400 repeated runs of 12 realizations the noise-corrected mean square is unbiased
    for the true one (the naive one is not: the noise adds about 0.9e-3 to a true 0.37e-3), and
    the standard errors match the scatter of the estimates."""
    rng = np.random.default_rng(20101210)
    truth = [np.linspace(0.05, 0.6, 6), np.array([0.1, 0.2, 0.3])]
    err = [np.array([0.02, -0.01, 0.03, 0.0, 0.01, 0.02]), np.array([-0.03, 0.01, 0.02])]
    true_ms = np.mean(np.concatenate(err) ** 2)
    true_mean = np.mean(np.concatenate(err))
    est = []
    for _ in range(400):
        cells = []
        for d, e in zip(truth, err):
            exact, loo = MOM.dolp_loo(_speckle_coef(d, 12, 50, rng))
            cells.append((exact, loo, d - e))
        naive = np.mean(np.concatenate([c[0] - c[2] for c in cells]) ** 2)
        r = MOM.pooled_error(cells)
        est.append((r["ms"], r["ms_se"], r["mean"], r["mean_se"], naive, r["rms"], r["rms_se"]))
    ms, ms_se, mean, mean_se, naive, rms, rms_se = np.array(est).T
    n = len(ms)
    # unbiased within 3 standard errors of the 400-run mean
    assert abs(ms.mean() - true_ms) < 3 * ms.std(ddof=1) / np.sqrt(n)
    assert abs(mean.mean() - true_mean) < 3 * mean.std(ddof=1) / np.sqrt(n)
    assert naive.mean() - true_ms > 10 * naive.std(ddof=1) / np.sqrt(
        n
    )  # what the correction removes
    # stated standard error against the scatter of 400 estimates (their sd known to about
    # 1 / sqrt(2 * 400) = 3.5 %): the mean's is calibrated; the mean square's is never smaller
    # than the scatter, and larger by the jackknife's known upward bias (Efron-Stein), which is
    # largest where, as here, the noise exceeds the error: 0.79 measured, 0.86-0.94 with less noise
    assert 0.9 < mean.std(ddof=1) / np.sqrt(np.mean(mean_se**2)) < 1.1
    assert 0.7 < ms.std(ddof=1) / np.sqrt(np.mean(ms_se**2)) < 1.1
    # 95 % intervals (Student t over 12 realizations) hold the truth about 95 % of the time
    # (400 runs: binomial s.e. 1.1 %)
    t = MOM.t_factor(12)
    assert np.mean(np.abs(mean - true_mean) <= t * mean_se) > 0.92
    assert np.mean(np.abs(rms - np.sqrt(true_ms)) <= t * rms_se) > 0.92


def test_specular_summary_tells_a_model_that_is_right_from_one_that_is_off_and_no_more():
    """The exact DOLP built on the model's own specular DOLP (1-D, shadowed, diffuse), off by 0.1
    at 20 and 40 deg and exact elsewhere, with little noise: those two points are off by more than
    0.01, the others within 0.01, and the rms is the truth's sqrt(2 / 6) * 0.1 within its errors."""
    rng = np.random.default_rng(3)
    theta_i = np.radians(np.arange(10, 61, 10))
    offset = np.where(np.isin(np.arange(10, 61, 10), (20, 40)), 0.1, 0.0)
    runs = {(0.3, 0.5): {}}
    for name, eta, _ in MOM.MATERIALS:
        d = np.clip(MOM.model_curves(eta, 0.3, theta_i)["ts_hyde"] + offset[:, None], -0.99, 0.99)
        runs[0.3, 0.5][name] = {"coef": _speckle_coef(d, 12, 20000, rng)}
    res = MOM.compare(runs, theta_i)
    for name, s in MOM.specular_summary(res, [(0.3, 0.5)], theta_i).items():
        np.testing.assert_array_equal(s["off"][0], offset > 0, err_msg=name)
        np.testing.assert_array_equal(s["within"][0], offset == 0, err_msg=name)
        assert abs(s["rms"] - 0.1 * np.sqrt(2 / 6)) < 3 * s["rms_se"], name
        assert abs(s["mean"] - 0.2 / 6) < 3 * s["mean_se"], name


def test_export_from_runs_writes_a_table_the_inversion_loads_and_fresnel_like_dolp(tmp_path):
    """``export_from_runs`` is how the shipped model-error table and the tests' held-out DOLP were made:
    on a quick run's own MoM coefficients it writes a table that ``model_error_table`` loads, and
    held-out specular DOLPs of glass near the smooth-surface Fresnel DOLP (independent truth: the 0.3
    slope and the realizations' standard error of 0.01-0.02 move it by at most 0.047 on this seed)."""
    from scatterlab import fresnel
    from scatterlab.inversion.model_error import model_error_table

    ctx = StudyContext(tmp_path, quick=True, seed=3)
    theta_i, length, reals, metal_reals, _ = MOM._settings(True)
    runs = MOM._run_cells(ctx, MOM.cells(True), theta_i, length, reals, metal_reals)
    MOM.save_runs(tmp_path / "mom_runs.npz", runs, MOM.run_settings(ctx))
    MOM.export_from_runs(
        tmp_path / "mom_runs.npz",
        tmp_path / "table.npz",
        tmp_path / "heldout.npz",
        theta_i_deg=np.degrees(theta_i),
        length=length,
    )
    table = model_error_table(tmp_path / "table.npz")
    assert [str(m) for m in table["materials"]] == [m[0] for m in MOM.MATERIALS]
    np.testing.assert_allclose(table["theta_i"], theta_i)
    assert np.all(np.isfinite(table["error"])) and np.all(table["error"] >= 0)
    with np.load(tmp_path / "heldout.npz") as z:
        dolp, se, deg = z["dolp"], z["se"], z["theta_deg"]
    assert dolp.shape == (len(MOM.MATERIALS), 1, len(MOM.INV_DEG)) and np.all(se >= 0)
    Rs, Rp = fresnel.reflectances(1.5 + 0j, np.radians(deg))
    np.testing.assert_allclose(dolp[0, 0], (Rs - Rp) / (Rs + Rp), atol=0.06)
