"""Text generators of the rep2 studies (issue 19): hand-made numbers in, verdict and text out."""

import json

import numpy as np
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


def _taper(centre_std, se_std, centre_dbl, se_dbl, partitions=(100, 50)):
    return {
        "rms_log10_change_in_lobe": 0.076,
        "rms_log10_noise_in_lobe": 0.090,
        "lobe_centre_deg_standard": centre_std,
        "lobe_centre_se_deg_standard": se_std,
        "lobe_centre_deg_doubled": centre_dbl,
        "lobe_centre_se_deg_doubled": se_dbl,
        "partitions_standard": partitions[0],
        "partitions_doubled": partitions[1],
    }


def test_fig39_lobe_shift_is_tested_against_its_own_uncertainty():
    mod = _load("fig39")
    ms = {"theta_i_75": {"lobe_centre_deg_pbrdf": 74.5, "lobe_centre_deg_mom": 47.5}}
    # lobe stable, its centre 47.5 -> 54.0 with small standard errors: moved beyond its noise
    text, ok, inside = mod.setup_text({"theta_i_75": _taper(47.5, 1.0, 54.0, 1.2)}, ms)
    assert not ok
    assert "1 of 1 cases beyond" in text and "24% of the 27.0-deg gap" in text
    assert "not the cause" not in text
    # the same standard errors from 6 and 3 partitions: Student t (2 degrees of freedom) widens
    # the interval past the shift
    text, ok, inside = mod.setup_text({"theta_i_75": _taper(47.5, 1.0, 54.0, 1.2, (6, 3))}, ms)
    assert "every case" in text and "cases beyond" not in text
    # the same shift inside broad uncertainties: not distinguishable, set-up cleared
    text, ok, inside = mod.setup_text({"theta_i_75": _taper(47.5, 4.0, 54.0, 4.5)}, ms)
    assert ok and "not the cause" in text
    assert "not significant" not in text and not inside  # the 27-deg gap is beyond 2 x 4 deg
    # a poorly located MoM lobe: the pBRDF's centre inside its 95 % interval, offset not significant
    text, ok, inside = mod.setup_text({"theta_i_75": _taper(47.5, 14.0, 54.0, 15.0)}, ms)
    assert ok and "the offset is not significant" in text
    assert inside == ["theta_i_75"]


@pytest.mark.parametrize(
    ("offset", "se", "partitions", "cls"),
    [
        (10.9, 0.9, 100, "beyond"),  # the lobe-centre offset of the full run
        (-12.0, 1.0, 100, "beyond"),
        (1.0, 1.0, 100, "within"),  # 1 + 1.98 <= 5: agreement shown
        (1.0, 2.0, 6, "straddles"),  # 1 + 2.57 x 2 > 5: a noisy small offset earns no "reproduced"
        (7.6, 2.6, 6, "straddles"),
        (7.6, 2.6, 1, "straddles"),  # no standard error: nothing is shown
    ],
)
def test_fig39_agreement_needs_the_whole_interval_inside_the_tolerance(offset, se, partitions, cls):
    mod = _load("fig39")
    assert mod.offset_class(offset, se, mod.coverage(partitions)) == cls


def test_fig39_lobe_centre_ignores_a_speckle_spike():
    """The defect: the raw argmax of a few-partition average jumps to a one-sample spike."""
    mod = _load("fig39")
    theta_s = mod.THETA_S
    rng = np.random.default_rng(3)
    lobe = np.exp(-0.5 * ((theta_s - np.radians(30)) / np.radians(20)) ** 2)
    coef = lobe * rng.exponential(size=(6, theta_s.size))  # fully developed speckle, 6 partitions
    spiky = coef.copy()
    spike = np.argmin(np.abs(theta_s - np.radians(-25)))
    spiky[0, spike] += 18.0  # three times the lobe in the 6-partition mean
    assert np.argmax(spiky.mean(axis=0)) == spike  # the raw argmax follows it
    truth = mod.lobe_stats(theta_s, lobe)[0]  # the estimator on the noise-free lobe
    k = mod.coverage(6)
    clean, spiked = mod.lobe_jackknife(theta_s, coef), mod.lobe_jackknife(theta_s, spiky)
    for r in (clean, spiked):
        assert 0 < r["se_centre"] < 5
        assert abs(r["centre"] - truth) <= k * r["se_centre"]
    assert abs(spiked["centre"] - clean["centre"]) <= k * clean["se_centre"]


def test_fig39_grazing_offset_and_verdict_agree_across_seeds():
    """The user trial: quick runs with seeds 20101210 and 1 put the MoM's raw peak on opposite
    sides of the pBRDF's. The lobe-centre offset at theta_i >= 45 deg must agree between the two
    within its combined 95 % interval, and give the same verdict class."""
    mod = _load("fig39")
    length, partitions = mod.sizes(quick=True)
    k = mod.coverage(partitions)
    found = []
    for seed in (20101210, 1):
        x, y = mod.surface(length, np.random.default_rng(seed))
        coef = mod.incoherent_scattering(
            x, y, 1.0, mod.THETA_I, mod.THETA_S, partitions=partitions
        ).per_partition
        lobe = mod.lobe_analysis(mod.THETA_S, coef)
        off = mod.offset_summary(lobe["pbrdf"], lobe, mod.GRAZING)
        d, u = off["offset_deg"], off["se_deg"]
        found.append((d, u, mod.offset_class(d, u, k)))
    (d1, u1, c1), (d2, u2, c2) = found
    assert 0 < u1 < 10 and 0 < u2 < 10
    assert abs(d1 - d2) <= k * np.hypot(u1, u2)
    assert c1 == c2


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


# --- fig55: single-class maps, the S0 change against its own noise, the class legend ---


def _fig55_maps(steel_classes, steel_correct=0.727, al_correct=0.652):
    def frac(correct, classes):
        return {"correct": correct, "classes_present": list(classes)}

    two = ("dielectric", "iron group")
    return {
        "aluminium": {
            "all_paint_correct": 0.729,
            "no turbulence": frac(0.887, ("dielectric", "aluminium group", "iron group")),
            "degraded": frac(0.467, two),
            "corrected": frac(al_correct, two),
        },
        "steel": {
            "all_paint_correct": 0.727,
            "no turbulence": frac(0.939, two),
            "degraded": frac(steel_correct, steel_classes),
            "corrected": frac(steel_correct, steel_classes),
        },
    }


def test_fig55_single_class_map_is_not_a_classification_result():
    mod = _load("fig55")
    m = _fig55_maps(("dielectric",))
    text = mod.baseline_text(m, ("aluminium", "steel"))
    assert "steel plate's degraded and corrected maps have a single class" in text
    assert "share of the plate that truly is paint, not a classification result" in text
    assert mod._score(m["steel"]["corrected"]) == "one class only"
    assert mod._score(m["aluminium"]["corrected"]) == "0.652"
    # a map scoring below the all-paint map is said to do no better than no classification
    assert "aluminium corrected (0.652)" in text
    # two classes on the steel plate and a score above the all-paint map: nothing to flag
    m = _fig55_maps(("dielectric", "iron group"), steel_correct=0.9, al_correct=0.8)
    text = mod.baseline_text(m, ("aluminium", "steel"))
    assert "single class" not in text and "No better" not in text.split("degraded (0.467)")[-1]


def test_fig55_s0_change_claims_only_beyond_its_standard_error():
    mod = _load("fig55")
    assert mod.s0_change_label(-0.125, 0.016) == "lower"
    assert mod.s0_change_label(-0.004, 0.003) == "within noise"  # the trial's steel plate
    assert mod.s0_change_label(0.05, 0.01) == "higher"
    assert mod.s0_change_label(-0.5, float("nan")) == "within noise"

    def m(al, st):
        return {
            p: {
                "s0_rel_rmse_degraded": 0.6,
                "s0_rel_rmse_corrected": 0.6 + d,
                "s0_rel_rmse_change_mean": d,
                "s0_rel_rmse_change_se": se,
            }
            for p, (d, se) in (("aluminium", al), ("steel", st))
        }

    plates = ("aluminium", "steel")
    text, labels = mod.s0_change_text(m((-0.125, 0.016), (-0.004, 0.003)), plates, 4)
    assert labels == {"aluminium": "lower", "steel": "within noise"}
    assert "restores detail the turbulence removed" not in text
    assert "steel plate the change is within noise" in text and "+/- 0.003" in text
    assert "over 4 independent" in text and "3.18 standard errors" in text  # t(3 dof), 95 %
    text, _ = mod.s0_change_text(m((-0.125, 0.016), (-0.06, 0.01)), plates, 4)
    assert "restores detail the turbulence removed" in text
    text, _ = mod.s0_change_text(m((-0.125, 0.016), (0.06, 0.01)), plates, 4)
    assert "contrary to the text" in text
    # 2.5 standard errors: a gain at k = 2, not at the t factor of 4 realizations
    _, labels = mod.s0_change_text(m((-0.05, 0.02), (-0.05, 0.02)), plates, 4)
    assert labels == {"aluminium": "within noise", "steel": "within noise"}


def test_fig55_boundary_claim_rests_on_the_realizations():
    """The boundary claim is made only when the realizations' 95 % interval of the mean enrichment
    clears 1.5x (or lies below it); t factors are Student's."""
    mod = _load("fig55")
    assert mod.t_factor(4) == pytest.approx(3.182, abs=1e-3)
    assert mod.t_factor(1) == float("inf")
    assert mod.boundary_over_realizations([1.9, 2.0, 2.1, 2.0])[0] == "concentrated"
    assert mod.boundary_over_realizations([1.1, 1.2, 1.0, 1.1])[0] == "not concentrated"
    label, mean, half = mod.boundary_over_realizations([1.33, 1.74, 1.6, 1.5])  # the seed survey's
    assert label == "not determined" and mean - half < 1.5 < mean + half
    assert mod.boundary_over_realizations([2.0])[0] == "not determined"  # one draw shows nothing
    se = mod._mean_se([1.0, 2.0, 3.0, 4.0])
    assert se == pytest.approx(np.std([1, 2, 3, 4], ddof=1) / 2)


def test_fig55_report_and_figure_follow_the_run(tmp_path, monkeypatch):
    legends = []
    save = study_runner.StudyContext.save_figure

    def keep(self, fig, name, **kw):
        legends.extend(t.get_text() for leg in fig.legends for t in leg.get_texts())
        titles = [ax.get_title() for ax in fig.axes]
        legends.append(titles)
        save(self, fig, name, **kw)

    monkeypatch.setattr(study_runner.StudyContext, "save_figure", keep)
    report = study_runner.run_study("fig55", tmp_path, quick=True, seed=7).read_text()
    m = json.loads((tmp_path / "metrics.json").read_text())["metrics"]
    *names, titles = legends
    assert names == ["dielectric", "aluminium group", "iron group"]  # the class legend
    mod = _load("fig55")
    for p in ("aluminium", "steel"):
        for k, image in enumerate(mod.IMAGES):
            frac = m[p][image]
            # the classes present are those the fraction table gives pixels to
            shares = np.add(frac["paint"], frac["bare metal"])
            assert frac["classes_present"] == [n for n, v in zip(mod.NAMES, shares) if v > 0]
            title = next(t for t in titles if t.startswith(f"{p}: {image}\n"))
            one = len(frac["classes_present"]) == 1
            score = title.split("\n", 1)[1]  # the first line names the image ("corrected")
            assert ("no classification" in score) == one and ("correct" in score) != one
            if one:
                assert f"{p} plate's" in report and "not a classification result" in report
        label = m[p]["s0_change"]
        reps = m[p]["s0_rel_rmse_change_reps"]
        assert len(reps) == m["realizations"] >= 2
        assert m[p]["s0_rel_rmse_change_mean"] == pytest.approx(np.mean(reps))
        k = mod.t_factor(len(reps))
        assert label == mod.s0_change_label(np.mean(reps), m[p]["s0_rel_rmse_change_se"], k)
    lowered = all(m[p]["s0_change"] == "lower" for p in ("aluminium", "steel"))
    assert ("restores detail the turbulence removed" in report) == lowered
