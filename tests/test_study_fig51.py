"""fig51_fig52: the near-normal limitation and the adaptive priors are judged over independent realizations
(95 % Student t interval of the mean, paired draw by draw), never on one draw of the bistable EM."""

import json
import re

import numpy as np
import pytest
from scipy import stats

from scatterlab import study_runner

F51 = study_runner.discover()["fig51_fig52"].module


def _interval(values):
    """Mean and 95 % Student t half-width, computed here independently of the study."""
    v = np.asarray(values, float)
    return v.mean(), stats.t.ppf(0.975, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size)


def _plate(fixed_called, fixed_total, adaptive_total, all_paint, n=None):
    """A plate's error table; lists are realizations, scalars exact values."""
    return {
        F51.FIXED: {"total": fixed_total, "paint_called_metal": fixed_called},
        F51.ADAPTIVE: {"total": adaptive_total, "paint_called_metal": 0.7},
        "no turbulence, P < 0.08": {"total": 0.1, "paint_called_metal": 0.1},
        "all_paint_error": all_paint,
    }


# a bistable EM: the fixed priors keep the paint dielectric in some draws (seed 1's layout: 5 of 12)
ESCAPES_5 = [0.39, 0.14, 1, 1, 1, 1, 0.15, 0.04, 0.16, 1, 1, 1]
ESCAPES_1 = [1] * 11 + [0.07]


def test_versus_is_the_paired_student_t_interval():
    fixed = [
        0.73,
        0.30,
        0.72,
        0.74,
        0.10,
        0.71,
    ]  # large draw-to-draw scatter shared with the adaptive map
    adaptive = [0.70, 0.26, 0.69, 0.70, 0.07, 0.67]
    diff, half, word = F51.versus(adaptive, fixed)
    mean, h = _interval(np.subtract(adaptive, fixed))
    assert diff == pytest.approx(mean) and half == pytest.approx(h)
    assert word == "lower"
    # unpaired, the two means' intervals overlap: only the pairing resolves the 0.035 gain
    assert _interval(fixed)[1] > 0.035 and _interval(adaptive)[1] > 0.035
    # against an exact threshold
    diff, half, word = F51.versus(ESCAPES_5, 0.5)
    mean, h = _interval(ESCAPES_5)
    assert diff == pytest.approx(mean - 0.5) and half == pytest.approx(h)
    assert word == "no change resolved"  # 0.65 +/- 0.27 contains one half
    assert F51.versus(ESCAPES_1, 0.5)[2] == "higher"  # 0.92 +/- 0.17
    # exact values are compared as they are; one draw resolves nothing
    assert F51.versus(0.2, 0.5) == (pytest.approx(-0.3), 0.0, "lower")
    assert F51.versus([0.2], 0.5)[1:] == (np.inf, "no change resolved")


def test_limitation_not_determined_when_the_em_escapes_often():
    m = {
        "aluminium": _plate(ESCAPES_5, [0.3] * 12, [0.5] * 12, [0.27] * 12),
        "steel": _plate([1.0] * 12, [0.72] * 12, [0.5] * 12, [0.27] * 12),
        "realizations": 12,
    }
    verdict, headline, text = F51.adaptive_verdict(m)
    assert "limitation not determined" in headline
    assert "(limitation not determined)" in text and "(limitation shown)" in text
    assert "shown on 1 of 2 plates" in text
    assert verdict == "not reproduced"  # no claim holds on every plate


def test_one_escape_in_twelve_still_shows_the_limitation():
    # typical draws: fixed 0.73, adaptive 0.52 +- 0.04, all-paint 0.27 (the quick run's numbers)
    rng = np.random.default_rng(3)
    adaptive = list(0.52 + 0.04 * rng.standard_normal(12))
    fixed_total = [0.73] * 11 + [0.08]
    m = {
        "aluminium": _plate(ESCAPES_1, fixed_total, adaptive, [0.27] * 12),
        "steel": _plate([1.0] * 12, [0.73] * 12, adaptive, [0.27] * 12),
        "realizations": 12,
    }
    verdict, headline, text = F51.adaptive_verdict(m)
    assert "limitation shown" in headline
    assert "all-paint map on 0/2" in headline
    assert "worse than no classification" in text
    assert verdict == "partly"
    # the paired difference adaptive - fixed: one escape (+0.44) in 12 leaves -0.17 +/- 0.08
    mean, h = _interval(np.subtract(adaptive, fixed_total))
    assert mean + h < 0
    assert "beat the fixed priors on 2 of 2" in text


def test_adaptive_within_noise_of_the_fixed_priors_is_not_claimed():
    # the draws where the EM escapes (fixed total 0.10) outweigh the others (0.73) in the mean difference
    fixed_total = [0.10 if c < 0.5 else 0.73 for c in ESCAPES_5]
    m = {
        "aluminium": _plate(ESCAPES_5, fixed_total, [0.52] * 12, [0.27] * 12),
        "steel": _plate([1.0] * 12, [0.73] * 12, [0.52] * 12, [0.27] * 12),
    }
    _, headline, text = F51.adaptive_verdict(m)
    mean, h = _interval(np.subtract(0.52, fixed_total))
    assert abs(mean) < h  # +0.05 +/- 0.21
    assert f"aluminium {mean:+.3f} +/- {h:.3f}" in headline
    assert "beat fixed on 1/2 plates" in headline
    assert (
        "on the aluminium plate the difference from the fixed priors is within the noise (the EM with the "
        "fixed priors called under half of the paint metal in 5 of 12 draws)" in text
    )


def test_adaptive_within_noise_of_the_all_paint_map_is_not_claimed():
    adaptive = [0.20, 0.35, 0.25, 0.30] * 3  # 0.275 +/- 0.03 against 0.27: neither better nor worse
    m = {p: _plate([1.0] * 12, [0.73] * 12, adaptive, [0.27] * 12) for p in ("aluminium", "steel")}
    verdict, headline, text = F51.adaptive_verdict(m)
    assert "all-paint map on 0/2" in headline
    assert "worse than no classification" not in text
    assert "within the noise" in text
    assert verdict == "partly"


def test_adaptive_working_without_the_limitation_is_partly():
    m = {
        p: _plate([0.1] * 12, [0.73, 0.72, 0.74, 0.73] * 3, [0.1, 0.12, 0.11, 0.1] * 3, [0.27] * 12)
        for p in ("a", "b")
    }
    verdict, headline, _ = F51.adaptive_verdict(m)
    assert "limitation NOT shown" in headline
    assert "beat fixed on 2/2 plates, the all-paint map on 2/2" in headline
    assert verdict == "partly"


def test_one_draw_claims_nothing():
    m = {p: _plate([1.0], [0.73], [0.1], [0.27]) for p in ("aluminium", "steel")}
    verdict, headline, _ = F51.adaptive_verdict(m)
    assert "limitation not determined" in headline
    assert "beat fixed on 0/2 plates, the all-paint map on 0/2" in headline
    assert verdict == "not reproduced"


def _observation(paint_dolp, metal_dolp, labels, classes, rng):
    """An observation whose every image has the given DOLP per label (plus 0.005 noise)."""
    dolp = np.where(labels > 0, metal_dolp, paint_dolp) + 0.005 * rng.standard_normal(labels.shape)
    img = {"dolp": dolp, "classes": classes}
    return {"no_turbulence": {"degraded": img}, "D_r0_7.9": {"degraded": img, "corrected": img}}


def test_metal_maps_and_scores_on_a_known_plate():
    rng = np.random.default_rng(0)
    labels = np.zeros((20, 20), int)
    labels[:, :6] = 1  # metal share 0.3
    labels[3, 10:] = 2  # a scratch counts as metal: 10 more pixels
    everything_metal = np.ones_like(labels)
    o = _observation(0.20, 0.02, labels, everything_metal, rng)
    maps = F51.metal_maps(o, "D_r0_7.9", F51.PRIOR_SETS["ch5"])
    truth = (labels > 0).astype(int)
    # paint at 0.20 is above the 0.08 threshold; the re-centred priors separate 0.20 from 0.02 exactly
    for name in (F51.MAPS[0], F51.MAPS[1], F51.ADAPTIVE):
        np.testing.assert_array_equal(maps[name], truth)
    np.testing.assert_array_equal(maps[F51.FIXED], everything_metal)  # the EM's own classes
    sel = np.ones(labels.shape, bool)
    s = F51.draw_scores(o, "D_r0_7.9", maps, labels, sel)
    metal_share = (120 + 10) / 400
    assert s["all_paint_error"] == pytest.approx(metal_share)
    assert s[F51.FIXED] == pytest.approx(
        {"total": 1 - metal_share, "paint_called_metal": 1.0, "metal_called_paint": 0.0}
    )
    assert s[F51.ADAPTIVE] == pytest.approx(
        {"total": 0.0, "paint_called_metal": 0.0, "metal_called_paint": 0.0}
    )
    assert s["paint_dolp_no_turbulence"] == pytest.approx(0.20, abs=0.002)


def test_quick_report_states_its_uncertainty(tmp_path):
    report = study_runner.run_study("fig51_fig52", tmp_path, quick=True, seed=20101210)
    text = report.read_text()
    m = json.loads((tmp_path / "metrics.json").read_text())["metrics"]
    n = F51.REALIZATIONS["quick"]
    assert m["realizations"] == n >= 12
    for p in ("aluminium", "steel"):
        assert len(m[p][F51.ADAPTIVE]["total"]) == len(m[p]["all_paint_error"]) == n
    assert f"Mean over {n} independent realizations" in text and "95 % Student t" in text
    # the headline's interval of adaptive minus all-paint is the paired t interval of the stored draws
    mean, h = _interval(
        np.subtract(m["aluminium"][F51.ADAPTIVE]["total"], m["aluminium"]["all_paint_error"])
    )
    assert f"aluminium {mean:+.3f} +/- {h:.3f}" in m["headline"]
    assert f"95 % intervals over {n} realizations" in m["headline"]
    assert not re.search(r"\bnan\b", m["headline"], re.IGNORECASE)
    # every table row carries its half-width
    rows = [
        r for r in text.splitlines() if r.startswith("| aluminium |") or r.startswith("| steel |")
    ]
    assert rows and all("+/-" in r for r in rows)


def test_most_draws_is_an_exact_binomial_interval_on_the_draws_that_call_the_paint_metal():
    # the bistable share: a t interval of its mean ran past 1 (0.93 +/- 0.10) or shrank to zero width
    above, n, low, high, word = F51.most_draws([1.0] * 22 + [0.1, 0.2])
    ci = stats.binomtest(22, 24).proportion_ci(confidence_level=0.95, method="exact")
    assert (above, n) == (22, 24) and (low, high) == pytest.approx((ci.low, ci.high))
    assert word == "higher" and 0 <= low < high <= 1
    assert F51.most_draws([1.0] * 24)[3] == 1.0  # all draws: the interval reaches 1, not past it
    # 4 of 4 cannot show "most draws": the exact interval's lower end is 0.40
    assert F51.most_draws([1.0] * 4)[4] == "no change resolved"
    assert F51.most_draws([0.1] * 12)[4] == "lower"
    assert F51.most_draws(ESCAPES_5)[4] == "no change resolved"  # 7 of 12


def test_shares_whose_interval_reaches_past_one_are_shown_as_the_range_inside_it():
    """A share of pixels is in [0, 1]: 23 draws at 1 and one at 0 give a mean of 0.958 whose Student t
    half-width (0.086) reaches past 1, so the table shows the range cut at 1, not "+/- 0.086"."""
    values = np.r_[np.ones(23), 0.0]
    half = stats.t.ppf(0.975, 23) * np.std(values, ddof=1) / np.sqrt(24)
    assert F51.pm(values) == f"0.958 (95 % {0.958333 - half:.3f}-1.000)"
    inside = np.array([0.2, 0.3, 0.25, 0.35])
    h = stats.t.ppf(0.975, 3) * np.std(inside, ddof=1) / 2
    assert F51.pm(inside) == f"0.275 +/- {h:.3f}"
