"""table5: the shrink of the paint's scatter is judged on several draws of the scene, not on one.

A seed survey (29 Nov 2026) found one draw's degraded/corrected sd(n) ratio anywhere in 0.2-2.8x, and the
verdict "partly" on 1 of 8 seeds because one case of one draw crossed 2x.
"""

import numpy as np
import pytest
from scipy import stats

from scatterlab import study_runner

T5 = study_runner.discover()["table5"].module


def test_shrink_interval_is_the_geometric_mean_with_a_t_interval_on_the_log():
    # ratios 1, 2, 4, 2: log2 = 0, 1, 2, 1 -> mean 1 (ratio 2), sd 0.8165 log2 units
    c = T5.shrink_interval([1.0, 2.0, 4.0, 2.0], [1.0, 1.0, 1.0, 1.0])
    assert c["ratio"] == pytest.approx(2.0)
    half = stats.t.ppf(0.975, 3) * np.std(np.log([1, 2, 4, 2]), ddof=1) / 2
    assert c["low"] == pytest.approx(2 * np.exp(-half))
    assert c["high"] == pytest.approx(2 * np.exp(half))
    assert c["status"] == "not determined" and c["draws"] == 4


def test_shrink_interval_decides_only_when_the_interval_excludes_the_threshold():
    assert T5.shrink_interval([3.0, 3.1, 2.9, 3.0], [1, 1, 1, 1])["status"] == "reaches"
    assert T5.shrink_interval([1.0, 1.1, 0.9, 1.0], [1, 1, 1, 1])["status"] == "below"
    # one draw at 2.8x among draws near 1: the one-draw rule would have called it reached
    assert T5.shrink_interval([2.84, 1.0, 0.9, 1.2], [1, 1, 1, 1])["status"] == "not determined"


def test_shrink_interval_leaves_out_unmeasured_draws_and_one_draw_decides_nothing():
    c = T5.shrink_interval([1.0, np.nan, 1.0, 1.0], [1.0, 1.0, 0.0, 1.0])
    assert c["draws"] == 2 and np.isnan(c["per_draw"][1]) and np.isnan(c["per_draw"][2])
    one = T5.shrink_interval([5.0], [1.0])
    assert one["ratio"] == pytest.approx(5.0) and one["status"] == "not determined"
    assert "no interval" in T5._fmt_shrink(one)
    none = T5.shrink_interval([np.nan], [1.0])
    assert none["status"] == "not determined" and T5._fmt_shrink(none) == "no draw measured"


def test_shrink_verdict_follows_the_intervals():
    reach, below, nd = ({"status": s} for s in ("reaches", "below", "not determined"))
    pooled_below = {"status": "below", "draws": 4}
    pooled_nd = {"status": "not determined", "draws": 4}
    assert T5.shrink_verdict([reach] * 4, pooled_nd)[0] == "reproduced"
    assert T5.shrink_verdict([reach, nd, below, below], pooled_below) == (
        "partly",
        "above 2x in 1 of 4 cases",
    )
    assert T5.shrink_verdict([below, nd, below, below], pooled_below) == (
        "not reproduced",
        "below 2x",
    )
    # nothing shown either way: not reproduced, and the headline says it is not determined
    verdict, word = T5.shrink_verdict([nd] * 4, pooled_nd)
    assert verdict == "not reproduced" and "not determined at this run size (4 draws)" in word


def test_kappa_interval_pools_every_measured_value():
    # seed 6 of the survey, aluminium: -0.23, -0.84, -0.76, 0.34 (D/r0 7.9), -0.67, -0.30, 0.06, -0.85
    v = [-0.23, -0.84, -0.76, 0.34, -0.67, -0.30, 0.06, -0.85]
    k = T5.kappa_interval(v + [np.nan], 9)
    assert k["mean"] == pytest.approx(np.mean(v))
    assert k["half_width"] == pytest.approx(stats.t.ppf(0.975, 7) * np.std(v, ddof=1) / np.sqrt(8))
    assert k["values"] == 8 and k["of"] == 9
    assert np.isinf(T5.kappa_interval([0.1], 8)["half_width"])


def test_kappa_text_says_missing_means_in_words():
    k = {"mean": -0.39, "half_width": 0.05, "values": 7, "of": 8}
    assert T5._kappa_text("steel", k) == "steel -39% (95 % -44%..-34%), 1 of 8 without a mean"
    assert "not measured" in T5._kappa_text("steel", {**k, "values": 0})
    assert "no interval" in T5._kappa_text("steel", {**k, "half_width": float("inf"), "values": 1})
