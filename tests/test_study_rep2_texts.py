"""Text generators of the rep2 studies (issue 19): hand-made numbers in, verdict and text out."""

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
