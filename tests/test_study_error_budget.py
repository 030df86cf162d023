"""The error budget's attribution: which stage, made ideal, lowers each error most, and the headline over the
corrected images (hand-made variant tables with a known answer)."""

from scatterlab import study_runner

BUDGET = study_runner.discover()["characterization_error_budget"].module


def _row(dolp, cls, paint, metal):
    return {
        "dolp_rmse_truth": dolp,
        "classification_vs_labels": cls,
        "paint_index_error": paint,
        "metal_index_error": metal,
    }


def test_attribution_names_the_stage_with_the_largest_relative_fall_of_a_corrected_image():
    keys = ["no_turbulence", "D_r0_7.9_corrected"]
    rows = {
        "realistic": {
            "no_turbulence": _row(0.1, 0.01, 0.01, 9.0),
            keys[1]: _row(0.3, 0.2, 0.5, 4.0),
        },
        # lowers the corrected paint index error by half: the headline
        "true PSF": {
            "no_turbulence": _row(0.1, 0.01, 0.01, 9.0),
            keys[1]: _row(0.25, 0.15, 0.25, 4.0),
        },
        # a huge fall of the ill-conditioned metal index and of the no-turbulence image: not the headline
        "no noise": {"no_turbulence": _row(0.0, 0.0, 0.0, 0.1), keys[1]: _row(0.29, 0.2, 0.5, 0.1)},
        # class error zero by construction: never attributed
        "true classes": {
            "no_turbulence": _row(0.1, 0.0, 0.01, 9.0),
            keys[1]: _row(0.3, 0.0, 0.5, 4.0),
        },
        "all ideal (model only)": {k: _row(0.0, 0.0, 0.0, 0.0) for k in keys},
    }
    summary, head = BUDGET.attribution(rows, keys)
    assert head["largest_source"] == "true PSF"
    assert head["quantity"] == "paint_index_error" and head["image"] == keys[1]
    assert abs(head["relative_fall"] - 0.5) < 1e-12
    cls = [s for s in summary if s["quantity"] == "classification_vs_labels"]
    assert all(s["largest_source"] != "true classes" for s in cls)
    metal = next(
        s for s in summary if s["quantity"] == "metal_index_error" and s["image"] == keys[1]
    )
    assert metal["largest_source"] == "no noise"  # listed, but not the headline


def test_attribution_names_no_source_when_no_stage_lowers_the_error():
    # the review's case: every ideal stage leaves the metal index error as is or makes it worse
    keys = ["D_r0_7.9_corrected"]
    rows = {
        "realistic": {keys[0]: _row(0.3, 0.2, 0.5, 3.59)},
        "true PSF": {keys[0]: _row(0.2, 0.1, 0.4, 3.59)},
        "no noise": {keys[0]: _row(0.29, 0.2, 0.5, 4.2)},
        "all ideal (model only)": {keys[0]: _row(0.0, 0.0, 0.0, 0.0)},
    }
    summary, head = BUDGET.attribution(rows, keys)
    metal = next(s for s in summary if s["quantity"] == "metal_index_error")
    assert metal["largest_source"] == "none"
    dolp = next(s for s in summary if s["quantity"] == "dolp_rmse_truth")
    assert dolp["largest_source"] == "true PSF"
    assert head["largest_source"] == "true PSF"
