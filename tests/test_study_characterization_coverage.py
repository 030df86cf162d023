"""The coverage study's report says which way a family misses its nominal rate, and how wide its intervals
are (hand-made rows with known answers)."""

from studies.characterization_coverage import _label, coverage, direction, median_widths


def _trial(covers68, covers95, lo, hi):
    flags = {"ci68": covers68, "ci95": covers95, "interval68": [lo, hi]}
    return {"metal": "gold", "no_turbulence/paint/n": flags}


def test_a_family_covering_every_truth_over_covers_and_its_width_is_the_median():
    trials = [_trial(True, True, 0.0, 1.0 + k) for k in range(24)]
    cov = coverage(trials)
    row = cov["no_turbulence/paint/n"]
    assert row["ci68"]["rate"] == 1.0 and not row["ci68"]["within_2se"]
    assert direction(row) == "over-covers"
    assert median_widths(trials)["no_turbulence/paint/n"] == 12.5


def test_a_family_missing_most_truths_under_covers():
    trials = [_trial(k < 6, k < 12, 0.0, 0.1) for k in range(24)]
    assert direction(coverage(trials)["no_turbulence/paint/n"]) == "under-covers"


def test_metal_coverage_is_split_by_metal():
    from studies.characterization_coverage import metal_coverage

    def t(metal, covers):
        return {"metal": metal, "no_turbulence/metal/n": {"ci68": covers, "ci95": True}}

    out = metal_coverage([t("gold", False), t("gold", False), t("iron", True), t("iron", False)])
    assert out["families"] == ["no_turbulence/metal/n"]
    assert out["metals"]["gold"] == {"trials": 2, "no_turbulence/metal/n": 0.0}
    assert out["metals"]["iron"]["no_turbulence/metal/n"] == 0.5


def test_weakly_determined_trials_leave_the_marginal_family_and_too_few_are_not_judged():
    """A marginal interval is judged over the trials that determined its parameter: 14 weakly determined
    misses are left out of a family whose 10 determined trials cover at 0.7; a family with 9 judged trials
    is not judged; the joint region (always judged) of the same trials misses its rate."""
    from studies.characterization_coverage import passes

    def t(k):
        weak = k < 14
        return {
            "metal": "copper",
            "no_turbulence/metal/n": {
                "ci68": not weak and k < 21,
                "ci95": not weak,
                "determined": not weak,
                "interval68": [0.0, 1.0],
            },
            "no_turbulence/metal/kappa": {
                "ci68": True,
                "ci95": True,
                "determined": k >= 15,
                "interval68": [0.0, 1.0],
            },
            "no_turbulence/metal/joint": {"ci68": k < 5, "ci95": k < 10, "determined": True},
        }

    cov = coverage([t(k) for k in range(24)])
    n = cov["no_turbulence/metal/n"]
    assert (n["trials"], n["weak"], n["ci68"]["rate"]) == (10, 14, 0.7) and passes(n)
    kappa = cov["no_turbulence/metal/kappa"]
    assert kappa["trials"] == 9 and not kappa["judged"] and passes(kappa)
    joint = cov["no_turbulence/metal/joint"]
    assert joint["trials"] == 24 and not passes(joint) and direction(joint) == "under-covers"


def test_the_figure_names_a_turbulence_case_as_its_title_reads():
    """Tick labels read "D/r0 = 7.9", as the main job's figures do; the D/r0 slash is not a separator."""
    assert _label("D_r0_7.9_corrected/paint/n") == "D/r0 = 7.9 / paint / n"
    assert _label("no_turbulence/metal/joint") == "no turbulence / metal / joint"


def test_joint_regions_of_a_matched_prior_run_are_recorded_not_judged():
    from studies.characterization_coverage import passes

    trials = [
        {
            "metal": "metal",
            "no_turbulence/metal/joint": {"ci68": True, "ci95": True, "recorded_only": True},
        }
        for _ in range(24)
    ]
    row = coverage(trials)["no_turbulence/metal/joint"]
    assert row["recorded_only"] and not row["judged"] and passes(row)
    assert row["ci68"]["rate"] == 1.0  # still recorded


def test_a_matched_prior_plate_is_drawn_from_the_prior_its_posteriors_use():
    import numpy as np

    from studies.characterization_coverage import METAL_PRIOR, METALS, PAINT_PRIOR, draw_plate

    rng = np.random.default_rng(3)
    for _ in range(20):
        p = draw_plate(rng, True)
        for region, box in (("metal", METAL_PRIOR), ("paint", PAINT_PRIOR)):
            b = p.validate().prior_bounds(region)
            assert b == {q: tuple(box[q]) for q in ("n", "kappa")}
            assert all(b[q][0] <= getattr(p, f"{region}_{q}") <= b[q][1] for q in ("n", "kappa"))
    p = draw_plate(rng, False)  # a user's scene: a fixed metal, the default prior
    assert p.metal in METALS and p.metal_n_prior is None and p.paint_kappa_prior is None


def test_the_wide_prior_design_draws_the_plates_it_drew_before():
    """A seed of the held-out study gives the plate its documented runs had: a metal index, then the paint's
    n and kappa."""
    import numpy as np

    from studies.characterization_coverage import METALS, draw_plate

    plate = draw_plate(np.random.default_rng(7), False)
    rng = np.random.default_rng(7)
    name = list(METALS)[rng.integers(len(METALS))]
    assert (plate.metal, plate.paint_n, plate.paint_kappa) == (
        name,
        rng.uniform(1.3, 1.7),
        rng.uniform(0.05, 0.6),
    )
