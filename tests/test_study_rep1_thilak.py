"""Tables 1-2 study: the report's sentences are generated from its numbers (issue 19).

Hand-made numbers, each chosen so that the old fixed wording would have been wrong.
"""

from scatterlab import study_runner

TT = study_runner.discover()["thilak_tables"].module


def test_over_coverage_is_reported_as_such():
    # 24 trials: 2 SE = 2 sqrt(0.68 * 0.32 / 24) = 0.19, band 0.49-0.87; 0.92 over-covers,
    # 0.40 under-covers (the old text counted only under-coverage: "consistent in 7 of 7")
    text = TT._calibration_text([0.7, 0.6, 0.8], [0.68, 0.92, 0.40], 24)
    assert "HPD region is consistent with 68 % in 3 of 3 cases" in text
    assert "likelihood-ratio region is consistent with 68 % in 1 of 3 cases" in text
    assert "under-covers in 1" in text and "over-covers in 1" in text


def _row(ls_n, med_n, ls_k, med_k):
    return (
        "low",
        "3",
        {
            "least_squares": {"n": {"rmse": ls_n}, "kappa": {"rmse": ls_k}},
            "posterior_median": {"n": {"rmse": med_n}, "kappa": {"rmse": med_k}},
        },
    )


def test_posterior_median_against_least_squares_is_counted():
    rows = [_row(2.0, 1.0, 1.0, 2.0), _row(2.0, 3.0, 1.0, 2.0), _row(5.0, 1.0, 3.0, 1.0)]
    text = TT._median_vs_ls_text(rows)
    assert "for n in 2 of 3 and for kappa in 1 of 3 cases" in text


def _scored(theta_rmses, inside):
    return {
        "results": {("low", str(i)): {"theta_r": {"rmse": r}} for i, r in enumerate(theta_rmses)},
        "inside_theta": inside,
    }


def test_random_step2_is_compared_with_the_fixed_start_not_with_itself():
    random, fixed = _scored([0.5, 1.1], 4), _scored([0.2, 0.3], 9)
    text = TT._step2_text(random, fixed, 14)
    assert "4 of 14 inside, theta_r RMSE up to 1.1 deg, against 9 of 14 and 0.3 deg" in text
    assert "another minimum" in text  # 1.1 > 1.5 x 0.3
    assert "changes little" in TT._step2_text(_scored([0.3], 4), _scored([0.3], 4), 14)


def test_verdict_note_names_the_post_hoc_selection_and_our_estimator():
    # the verdict now rests on the closest procedure's rerun on fresh trials (test_study_thilak_verdict)
    scored = dict.fromkeys(range(11))
    fresh = {"factor": 1.3, "interval": {"low": 1.2, "high": 1.4}, "in_kind": "yes"}
    note = TT._verdict_note(
        "partly", "shown", "box", scored, fresh, True, two_step_reproduces=False
    )
    assert '"partly"' in note and "after the fact" in note and "6 trials per row" in note
    assert "11 candidates" in note and "fresh trials" in note
    assert "Our two-step estimator does not reproduce the tables" in note
    assert "does not reproduce" in TT._two_step_verdict_text(7, 14)
    assert "reproduces the tables: all 14" in TT._two_step_verdict_text(14, 14)
    ruled_out = TT._verdict_note(
        "not reproduced", "ruled out", "b", scored, fresh | {"in_kind": "no"}, True, 0
    )
    assert "not even in kind" in ruled_out
    open_ = TT._verdict_note(
        "not reproduced",
        "not determined",
        "b",
        scored,
        fresh | {"in_kind": "not determined"},
        True,
        0,
    )
    assert "not determined at this run size" in open_ and "nothing is shown" in open_
