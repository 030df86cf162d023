"""Tables 4-5 and Figs. 41-42: report sentences generated from the numbers (issue 19).

Hand-made numbers, each chosen so that the old fixed wording would have been wrong.
"""

import importlib
import json

import numpy as np
import pytest

from scatterlab import study_runner

STUDIES = study_runner.discover()  # mounts this checkout's studies/ as scatterlab.studies
_common = importlib.import_module("scatterlab.studies._common")
T4 = STUDIES["table4"].module
T5 = STUDIES["table5"].module
T5S = STUDIES["table5_synthetic"].module


def test_table5_synthetic_quick_mode_does_not_judge():
    # 30 pixels: a band sqrt(2000 / 30) = 8 x the full run's; 1 of 6 inside was called "partly"
    verdict, text = T5S._verdict(1, 6, 30, quick=True)
    assert verdict == "not reproduced"
    assert "cannot judge" in text and "8 x wider" in text
    assert T5S._verdict(1, 6, 2000, quick=False)[0] == "partly"
    assert T5S._verdict(0, 6, 2000, quick=False)[0] == "not reproduced"
    assert T5S._verdict(6, 6, 2000, quick=False)[0] == "reproduced"


def test_table4_metal_share_mismatch_is_stated():
    implied = {"aluminium": 0.40, "steel": 0.49}
    text = T4._share_text({"aluminium": 0.328, "steel": 0.269}, implied)
    assert "not like for like" in text and "aluminium, steel" in text
    text = T4._share_text({"aluminium": 0.38, "steel": 0.269}, implied)
    assert "for steel, so there" in text
    assert "matches" in T4._share_text({"aluminium": 0.41, "steel": 0.47}, implied)


def test_table4_uncertainty_with_one_screen_is_the_binomial_error():
    # p = 0.4 over 1600 pixels: sqrt(0.24 / 1600) = 0.01225
    assert T4._binomial_u(0.4, np.ones(1600, bool)) == pytest.approx(0.012247, rel=1e-4)


def test_fig42_chain_accuracy_is_the_computed_d_eta():
    # flame-sprayed Al: literature 1.226 - j10.413, published fit 0.8886 - j3.4602:
    # shift |(-0.3374) + 6.9528j| = 6.961
    text = _common._chain_accuracy_text(1.5e-2, 1.226 - 10.413j, "0.8886 - j3.4602")
    assert "|d eta| = 1.5e-02" in text and "= 7" in text and "far smaller" in text
    assert "a few 1e-3" not in text
    assert "not smaller" in _common._chain_accuracy_text(8.0, 1.226 - 10.413j, "0.8886 - j3.4602")


# --- table5_synthetic: pixels on a bound, non-converged posteriors (user trial) ---


def test_table5_synthetic_bound_shares_count_pixels_on_either_bound():
    n = np.array([0.5, 5.0, 1.0, 2.0])
    kappa = np.array([25.0, 3.0, 25.0, 4.0])
    at = np.array([[False, True], [True, False], [True, True], [False, False]])
    b = T5S.bound_shares(n, kappa, at)
    assert b["share"] == pytest.approx(0.75) and b["pixels"] == 3
    assert b["n"] == pytest.approx(0.5) and b["kappa"] == pytest.approx(0.5)
    # the mean of the pixels off the bounds is of those pixels only
    assert b["off_bound_mean_n"] == pytest.approx(2.0)
    assert b["off_bound_mean_kappa"] == pytest.approx(4.0)
    assert np.isnan(T5S.bound_shares(n, kappa, np.ones((4, 2), bool))["off_bound_mean_n"])


def test_table5_synthetic_bound_limit_tightens_with_more_pixels():
    # f sd <= sd / sqrt(N): the more precise the mean, the fewer censored pixels it tolerates
    assert T5S.bound_limit(30) == pytest.approx(1 / np.sqrt(30))
    assert T5S.bound_limit(2000) < T5S.bound_limit(30) < 0.5


def test_table5_synthetic_mean_over_bound_pixels_is_not_scored():
    # the trial's aluminium kappa: inside its band, but 47 % of the pixels on a bound
    c = _common.compare("aluminium E[kappa]", 11.18, 12.69, 0.0, 2.09)
    assert c["inside"]
    limit = T5S.bound_limit(30)
    s = T5S.score_on_bounds(c, 0.47, limit)
    assert s["scored"] is False and s["inside"] is None and s["inside_band"] is True
    assert "not scored" in s["text"] and "47 %" in s["text"] and "inside" not in s["text"]
    # few pixels on a bound: the comparison stands as it was
    kept = T5S.score_on_bounds(c, 0.5 * limit, limit)
    assert kept["scored"] is True and kept["inside"] is True and kept["text"] == c["text"]
    outside = _common.compare("steel E[n]", 3.86, 3.2, 0.0, 0.01)
    assert T5S.score_on_bounds(outside, 0.0, limit)["inside"] is False


def test_table5_synthetic_unscored_means_never_make_it_reproduced():
    # 2 scored means inside, 4 not scored: not every mean shown to agree
    verdict, text = T5S._verdict(2, 6, 2000, quick=False, unscored=4)
    assert verdict == "partly" and "4 not scored" in text
    assert T5S._verdict(0, 6, 2000, quick=False, unscored=4)[0] == "not reproduced"
    assert "4 not scored" in T5S._verdict(0, 6, 30, quick=True, unscored=4)[1]


def test_table5_synthetic_non_converged_posteriors_are_flagged():
    m = {
        "paint": {"posterior_converged": True, "posterior_convergence_reason": ""},
        "aluminium": {"posterior_converged": False, "posterior_convergence_reason": "too short"},
    }
    text = T5S.posterior_flags(m, ["paint", "aluminium"])
    assert "**Not converged**" in text and "aluminium" in text and "too short" in text
    assert "paint" not in text
    m["aluminium"]["posterior_converged"] = True
    assert "converged" in T5S.posterior_flags(m, ["paint", "aluminium"])
    assert "Not converged" not in T5S.posterior_flags(m, ["paint", "aluminium"])


@pytest.mark.filterwarnings("ignore:the fit ended on a bound")  # expected: the report states it
def test_table5_synthetic_report_flags_bounds_and_convergence(tmp_path):
    # the quick run: every statement in the report follows the run's own metrics
    report = study_runner.run_study("table5_synthetic", tmp_path, quick=True, seed=7).read_text()
    m = json.loads((tmp_path / "metrics.json").read_text())["metrics"]
    limit = m["bound_share_limit"]
    assert limit == pytest.approx(1 / np.sqrt(m["pixels"]))
    rows = {
        line.split("|")[1].strip(): line for line in report.splitlines() if line.startswith("|")
    }
    for c in m["comparisons"]:
        name = c["name"].split()[0]
        share = m[name]["ls_bound"]["share"]
        assert c["scored"] == (share <= limit)
        assert c["text"] in report
        if not c["scored"]:
            assert c["inside"] is None and "not scored" in c["text"]
    for name in ("paint", "aluminium", "steel"):
        share = m[name]["ls_bound"]["share"]
        assert T5S._pct(share) in rows[name]  # the bound column
        flagged = "**not converged**" in rows[name]
        assert flagged == (not m[name]["posterior_converged"])
    inside = sum(bool(c["inside"]) for c in m["comparisons"])
    assert f"{inside} of {sum(c['scored'] for c in m['comparisons'])} scored inside" in report
    assert "a mean over many such pixels is not a measurement" in report
