"""Tables 1-2 study: the verdict follows the Monte-Carlo uncertainty, not the draw.

A seed survey found the verdict 'partly' on 6 of 13 quick seeds and 'not reproduced' on 7: it
rested on the closest of 11 candidate procedures, picked after the fact from 6 trials per row, and
on point estimates of its typical factor and bias signs. These tests check the rule on constructed
inputs whose answer is known by construction, and that two quick seeds give the same verdict.
"""

import json

import numpy as np
import pytest

from scatterlab import study_runner

TT = study_runner.discover()["thilak_tables"].module


def _interval(low, high):
    return {"factor": np.sqrt(low * high), "low": low, "high": high, "se_log": 0.1, "groups": 10}


def _signs(value=0, opposite=None):
    signs = {
        (lv, k): {"n": value, "kappa": value} for lv, rows in TT.PUBLISHED.items() for k in rows
    }
    if opposite:
        signs[opposite]["kappa"] = -1
    return signs


def test_in_kind_needs_the_whole_interval_on_one_side_of_the_threshold():
    assert TT.KIND_FACTOR == 1.5
    many = TT.MIN_SIGN_TRIALS
    assert TT.judge_in_kind(_interval(1.1, 1.5), _signs(1), many) == "yes"
    assert TT.judge_in_kind(_interval(1.2, 1.8), _signs(1), many) == "not determined"
    assert TT.judge_in_kind(_interval(1.6, 2.4), _signs(1), many) == "no"
    # one row biased opposite to the published direction rules a candidate out whatever its factor
    assert TT.judge_in_kind(_interval(1.1, 1.4), _signs(1, opposite=("high", "3")), many) == "no"


def test_in_kind_needs_the_direction_shown_not_just_not_contradicted():
    # review: "yes" with every row's direction undetermined called the bias's direction reproduced
    assert TT.judge_in_kind(_interval(1.1, 1.4), _signs(0), TT.MIN_SIGN_TRIALS) == "not determined"


def test_a_small_sample_cannot_rule_a_procedure_out_on_its_factor():
    # with 6 trials per row the factor reads 1.16-1.34x high (the runaway trials that carry the means
    # are missed) and its interval is centred there: the box n <= 20 read 2.25 (1.69-3.00) in quick
    # mode against 1.35 from 150 trials, and was called "no"
    assert TT.judge_in_kind(_interval(1.69, 3.0), _signs(0), 6) == "not determined"
    assert TT.judge_in_kind(_interval(1.69, 3.0), _signs(0), TT.MIN_SIGN_TRIALS) == "no"


def test_a_claim_needs_the_fresh_trials_and_a_rejection_every_candidate():
    nd, no, yes = "not determined", "no", "yes"
    assert TT.study_verdict(yes, [yes, no, nd], all_inside=False) == ("partly", "shown")
    assert TT.study_verdict(yes, [nd] * 11, all_inside=True) == ("reproduced", "shown")
    assert TT.study_verdict(no, [no] * 11, all_inside=False) == ("not reproduced", "ruled out")
    # a "yes" on the trials the closest was picked on is not a claim (post-hoc selection) ...
    assert TT.study_verdict(nd, [yes] + [no] * 10, all_inside=False) == (
        "not reproduced",
        "not determined",
    )
    # ... and one candidate ruled out on fresh trials does not rule out the others
    assert TT.study_verdict(no, [no] * 10 + [nd], all_inside=False) == (
        "not reproduced",
        "not determined",
    )


def _row(values):
    est = np.zeros((len(values), 3))
    est[:, 0] = values
    est[:, 1] = TT.COPPER[1] + 1.0
    est[:, 2] = 60.0
    return TT.row_stats(est)


def test_bias_signs_from_the_t_interval_and_not_from_a_few_trials():
    n0 = TT.COPPER[0]
    above = n0 + 0.5 + 0.1 * np.tile([1, -1], 10)  # mean n0 + 0.5, standard error 0.023
    below = n0 - 0.2 + 0.1 * np.tile([1, -1], 10)
    spread = n0 + 0.05 + 1.0 * np.tile([1, -1], 10)  # standard error 0.23: the interval holds n0
    signs = TT.bias_signs(
        {("low", "3"): _row(above), ("low", "5"): _row(below), ("low", "10"): _row(spread)}
    )
    assert [signs[("low", k)]["n"] for k in ("3", "5", "10")] == [1, -1, 0]
    assert signs[("low", "3")]["kappa"] == 1
    # below MIN_SIGN_TRIALS the direction is not judged, however tight the sample
    assert TT.MIN_SIGN_TRIALS > 6
    few = TT.bias_signs({("low", "3"): _row(below[:6])})
    assert few[("low", "3")] == {"n": 0, "kappa": 0}


def _matching(trials):
    """Estimates whose means and RMSEs equal the published ones in every row: two points per
    parameter, mean +/- sqrt(RMSE^2 - bias^2), alternating so that every jackknife pair is balanced."""
    out = {}
    for level, rows in TT.PUBLISHED.items():
        for key, p in rows.items():
            sign = np.tile([1.0, -1.0], trials // 2)
            cols = [
                m + sign * np.sqrt(r**2 - (m - truth) ** 2)
                for (_, truth), m, r in zip(TT.PARAMS, (p[0], p[3], p[6]), (p[2], p[5], p[8]))
            ]
            out[(level, key)] = np.column_stack(cols)
    return out


def test_estimates_equal_to_the_tables_have_factor_one_without_uncertainty():
    fi = TT.factor_interval(_matching(20))  # 10 jackknife groups of one +/- pair each
    assert fi["groups"] == 10
    assert fi["factor"] == pytest.approx(1.0)
    assert fi["low"] == pytest.approx(1.0) and fi["high"] == pytest.approx(1.0)


def _synthetic(f, trials, rng):
    """Skewed (gamma) estimates whose population mean and RMSE of n and kappa are f x the published
    ones in every row, so the population's typical factor is f exactly (theta_r as published)."""
    out = {}
    for level, rows in TT.PUBLISHED.items():
        for key, p in rows.items():
            cols = []
            for (par, truth), m, r in zip(TT.PARAMS, (p[0], p[3], p[6]), (p[2], p[5], p[8])):
                scale = 1.0 if par == "theta_r" else f
                mu = scale * m
                var = (scale * r) ** 2 - (mu - truth) ** 2
                cols.append(rng.gamma(mu**2 / var, var / mu, trials))
            out[(level, key)] = np.column_stack(cols)
    return out


def _judge_many(f, trials, reps, seed):
    rng = np.random.default_rng(seed)
    covered, kinds = 0, []
    for _ in range(reps):
        est = _synthetic(f, trials, rng)
        fi = TT.factor_interval(est)
        covered += fi["low"] <= f <= fi["high"]
        kinds.append(
            TT.judge_in_kind(
                fi, TT.bias_signs({k: TT.row_stats(e) for k, e in est.items()}), trials
            )
        )
    return covered / reps, {k: kinds.count(k) / reps for k in ("yes", "no", "not determined")}


def test_factor_interval_covers_a_known_factor_and_decides_only_when_it_can():
    # measured over 200 draws each (29 Nov 2026): coverage of f by the 95 % interval 0.94-1.00
    # (the jackknife of this median overstates its standard error by 1.2-1.4x); f = 1.3 at 6 trials
    # per row "not determined" 0.95; f = 1.7 at 150 "no" 0.94.
    # 100 draws: a binomial standard error of at most 0.05, so the bounds below are 2-3 of them
    # under the measured rates
    cover, kinds = _judge_many(1.3, 24, 100, seed=1)
    assert cover >= 0.88
    cover, kinds = _judge_many(1.3, 6, 100, seed=2)
    assert cover >= 0.85 and kinds["not determined"] >= 0.85
    # "yes" needs every row's direction shown as well: at the fresh rerun's 400 trials per row it is
    # (measured 1.00 at f = 1.2 and 1.3); at the ranking's 150 only 0.70, the rest "not determined"
    _, kinds = _judge_many(1.2, TT.FRESH_TRIALS[False], 100, seed=3)
    assert kinds["yes"] >= 0.9
    _, kinds = _judge_many(1.7, 150, 100, seed=4)
    assert kinds["no"] >= 0.8 and kinds["yes"] == 0


def test_two_quick_seeds_give_the_same_verdict(tmp_path):
    # seeds 20101210 and 2 gave 'partly' and 'not reproduced' under the old rule; quick mode cannot
    # decide (200 of 200 quick-sized draws from 300-trial pools 'not determined'), and says so
    found = []
    for seed in (20101210, 2):
        out = tmp_path / str(seed)
        report = study_runner.run_study("thilak_tables", out, quick=True, seed=seed).read_text()
        m = json.loads((out / "metrics.json").read_text())["metrics"]
        assert "not determined at this run size" in m["headline"]
        assert "not determined at this run size" in report
        found.append((m["verdict"], m["in_kind"]))
    assert found[0] == found[1] == ("not reproduced", "not determined")


def test_a_row_without_runaway_trials_prints_none_not_nan():
    # the median of an empty set of runaway trials is NaN; the report printed it as "nan"
    assert TT._median_or_none(float("nan")) == "none"
    assert TT._median_or_none(0.123) == "0.12"
