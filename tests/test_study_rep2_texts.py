"""Text generators of the rep2 studies (issue 19): hand-made numbers in, verdict and text out."""

import pytest

from scatterlab import study_runner

STUDIES = study_runner.discover()


def _load(study_id):
    return STUDIES[study_id].module


def _plate(fixed, adaptive, all_paint, no_turb=0.1):
    return {
        "corrected, Ch. V priors": {"total": fixed, "paint_called_metal": 1.0},
        "corrected, adaptive priors": {"total": adaptive, "paint_called_metal": 0.7},
        "no turbulence, P < 0.08": {"total": no_turb, "paint_called_metal": 0.1},
        "all_paint_error": all_paint,
    }


def test_fig51_adaptive_worse_than_all_paint_is_partly():
    # the review's numbers: adaptive beats fixed but is worse than calling every pixel paint
    mod = _load("fig51_fig52")
    m = {"aluminium": _plate(0.729, 0.555, 0.271), "steel": _plate(0.722, 0.488, 0.278)}
    verdict, headline, text = mod.adaptive_verdict(m)
    assert verdict == "partly"
    assert "all-paint map on 0/2" in headline
    assert "worse than no classification" in text


def test_fig51_adaptive_better_than_both_is_reproduced():
    mod = _load("fig51_fig52")
    m = {"aluminium": _plate(0.729, 0.15, 0.271), "steel": _plate(0.722, 0.12, 0.278)}
    verdict, headline, _ = mod.adaptive_verdict(m)
    assert verdict == "reproduced"
    assert "all-paint map on 2/2" in headline


@pytest.mark.parametrize(
    ("edge", "band", "label"),
    [
        (0.80, 0.54, "borderline"),  # the review's quick-mode numbers: 1.48x
        (0.80, 0.30, "concentrated"),
        (0.50, 0.50, "not concentrated"),
        (float("nan"), 0.5, "no errors"),
    ],
)
def test_fig55_boundary_label(edge, band, label):
    assert _load("fig55").boundary_concentration(edge, band)[0] == label


def test_fig24_caption_criterion_is_above_40_deg():
    # the review's example: a first peak at 60 deg is "> 40 deg", one at 40 deg is not
    firsts = {"Al_5": 60.0, "Al_10": 40.0, "MgO_10": 40.0, "MgO_20": None, "Al_20": 45.0}
    assert _load("fig24").caption_consistent(firsts) == ["Al_5", "Al_20"]


def _design_bounds(spec01, off01, spec_rough, off_rough):
    rough = {"0.3": {"specular": spec_rough, "off": off_rough}}
    return {"sigma_bound_at_0.1": {"specular": spec01, "off": off01}, "sigma_bound_rough": rough}


def test_design_text_follows_the_bounds():
    mod = _load("design")
    # sweep better at 0.1 for both, but 10x apart at 0.3: not "comparable", remark holds
    m = {"iron": _design_bounds(10.0, 2.0, 10.0, 1.0), "paint": _design_bounds(1.0, 0.3, 1, 0.9)}
    text, holds = mod.design_text(m)
    assert holds
    assert "NOT comparable" in text and "1 of 2" in text
    # specular better at 0.1 for paint: the remark does not hold
    m["paint"] = _design_bounds(0.2, 0.3, 1.0, 0.9)
    text, holds = mod.design_text(m)
    assert not holds
    assert "does NOT hold" in text


def _coverage_case(cover_at_09, converged):
    levels = [0.5, 0.9]
    return {
        "levels": levels,
        "coverage": [[0.5, 0.5, 0.5], [0.9, cover_at_09, 0.9]],
        "max_abs_z": abs(cover_at_09 - 0.9) / (0.09 / 100) ** 0.5,
        "converged_fraction": converged,
    }


@pytest.mark.parametrize(
    ("cover", "converged", "words"),
    [
        (0.5, 1.0, ["UNDER-covers", "kappa at nominal 0.9: 0.50"]),  # the review's 0.9 -> 0.5
        (1.0, 1.0, ["OVER-covers"]),  # 10 s.e. above with 100 trials
        (0.88, 1.0, ["consistent with calibrated"]),
        (0.88, 0.0, ["NOT judged", "only 0% of the runs converged"]),  # the review's iron case
    ],
)
def test_coverage_case_text(cover, converged, words):
    text, short = _load("coverage").case_text("paint", _coverage_case(cover, converged), 100)
    assert all(w in text for w in words)
    assert ("not judged" in short) == (converged < 0.5)


def test_a_quick_coverage_run_is_recorded_not_judged():
    """Six trials of a quick run: even a 0.9 -> 0.5 miss is recorded, not called under-coverage."""
    text, short = _load("coverage").case_text("paint", _coverage_case(0.5, 1.0), 6, judged=False)
    assert "not judged" in text and "UNDER" not in text and short == "not judged (quick)"


def _taper(peak_std, peak_dbl, range_std, range_dbl):
    return {
        "rms_log10_change_in_lobe": 0.076,
        "rms_log10_noise_in_lobe": 0.090,
        "peak_deg_standard": peak_std,
        "peak_deg_doubled": peak_dbl,
        "peak_range_deg_standard": range_std,
        "peak_range_deg_doubled": range_dbl,
    }


def test_fig39_peak_shift_is_tested_against_its_own_uncertainty():
    mod = _load("fig39")
    ms = {"theta_i_75": {"peak_deg_pbrdf": 74.5, "peak_deg_mom": 47.5}}
    # the review's full-mode case: lobe stable, peak 47.5 -> 54.0 with narrow, disjoint peaks
    text, ok, inside = mod.setup_text({"theta_i_75": _taper(47.5, 54.0, [46, 49], [52, 56])}, ms)
    assert not ok
    assert "1 of 1 cases beyond" in text and "24% of the 27.0-deg gap" in text
    assert "not the cause" not in text
    # the same shift inside broad peak ranges: not distinguishable, set-up cleared
    text, ok, inside = mod.setup_text({"theta_i_75": _taper(47.5, 54.0, [44, 56], [45, 58])}, ms)
    assert ok and "not the cause" in text
    assert "not significant" not in text  # the pBRDF peak (74.5) lies outside 44-56
    # the full run's flat lobe: the pBRDF peak inside the MoM peak's range, offset not significant
    text, ok, inside = mod.setup_text(
        {"theta_i_75": _taper(47.5, 54.0, [28.5, 77], [21.5, 80])}, ms
    )
    assert ok and "the peak offset is not significant" in text
    assert inside == ["theta_i_75"]


def test_fig31_verdict_follows_the_errors():
    mod = _load("fig31_fig33")
    # the review's numbers: errors 1.3 and 3.0 deg at s.e. 0.2 and 0.5; raw LS 0.5 and 0.1 deg
    verdict, text = mod.aop_verdict([1.3, 3.0], [0.2, 0.5], [10, 11], [0.5, 0.1])
    assert verdict == "partly"
    assert "does NOT cover the error of 2 of 2" in text
    assert "top and bottom bars WORSE" in text
    verdict, text = mod.aop_verdict([0.3, 0.4], [0.2, 0.5], [10, 11], [0.5, 0.6])
    assert verdict == "reproduced" and "improves on it for every bar" in text
    assert mod.aop_verdict([12.0, 0.4], [0.2, 0.5], [10, 11], [0.5, 0.6])[0] == "not reproduced"
