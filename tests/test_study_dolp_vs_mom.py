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
