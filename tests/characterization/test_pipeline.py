"""The characterization pipeline runs end to end on a tiny scene, writes atomic HDF5 results and a report,
computes only what the scene asks for, and rejects bad scene files with clear messages."""

import json

import numpy as np
import pytest

from scatterlab.characterization import SceneConfig, characterize, load_scene
from scatterlab.characterization.scene_config import Plate


def tiny(**kw):
    cfg = SceneConfig(
        image_size=32,
        geometry_deg=[35, 55],
        d_over_r0=[7.9],
        iterations=5,
        posterior_steps=300,
        plates=[Plate()],
        **kw,
    )
    return cfg.validate()


def test_pipeline_writes_results_and_report(tmp_path):
    import h5py

    report = characterize(tiny(), tmp_path)
    text = report.read_text()
    assert "aluminium plate" in text and "DOLP RMSE" in text and "Table 5" in text
    with h5py.File(tmp_path / "results.h5") as f:
        g = f["aluminium/theta_35/D_r0_7.9"]
        assert (
            g["dolp_corrected"].shape == (32, 32)
            and "classes_corrected" in g
            and "psf_corrected" in g
        )
        assert (
            "dolp_corrected" not in f["aluminium/theta_35/no_turbulence"]
        )  # the reference is not deconvolved
        assert f["aluminium/D_r0_7.9_corrected/n"].shape == (32, 32)
        assert f["aluminium/D_r0_7.9_corrected/posterior_paint/chain"].shape[-1] == 3
        L = g["loglik_corrected"][()]
        assert np.all(np.diff(L) >= -1e-9 * np.abs(L[1:]))
    s = json.loads((tmp_path / "summary.json").read_text())
    assert set(s["plates"]["aluminium"]) == {
        "no_turbulence",
        "no_turbulence_unrestored",
        "D_r0_7.9_degraded",
        "D_r0_7.9_corrected",
    }
    d = s["plates"]["aluminium"]["D_r0_7.9_corrected"]["psf_l1_error_per_geometry"]
    assert len(d) == 2 and all(0 < x <= 2 for x in d)  # a blind estimate: never the truth exactly
    # at D/r0 7.9 the Strehl ratio is a few per cent: the diffraction-limited PSF shares little of the
    # turbulent one's light (L1 = 2 - 2 x the shared light)
    base = s["plates"]["aluminium"]["D_r0_7.9_corrected"]["psf_l1_diffraction_limited"]
    assert 1.0 < base <= 2.0
    assert "PSF L1" in text
    assert "*Figure: the aluminium plate at theta" in text and "Blank pixels" in text
    post = s["plates"]["aluminium"]["no_turbulence"]["posterior_paint"]
    for q in ("n", "kappa"):  # the truth beside every estimate, and whether each interval covers it
        e = post[q]
        assert e["ci68"][0] <= e["median"] <= e["ci68"][1] and e["ci95"][0] <= e["ci68"][0]
        assert e["covers68"] == (e["ci68"][0] <= e["truth"] <= e["ci68"][1])
    assert s["seed"] == 20101210 and "numpy" in s["versions"] and s["scene"]["image_size"] == 32
    assert "Checks against the truth" in text and "covered 68 / 95 %" in text
    assert not (tmp_path / "results.h5.part").exists()
    with pytest.raises(FileExistsError):
        characterize(tiny(), tmp_path)


def test_only_requested_estimates_are_computed(tmp_path):
    import h5py

    characterize(tiny(estimate=["classes"]), tmp_path)
    with h5py.File(tmp_path / "results.h5") as f:
        assert "no_turbulence" not in f["aluminium"]  # no n, kappa maps and no posteriors
        assert "classes_corrected" in f["aluminium/theta_35/D_r0_7.9"]


def test_scene_files_are_validated(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text(
        'image_size = 32\ngeometry_deg = [40, 50]\n[[plates]]\nmetal = "steel"\nmetal_n = 3.6\nmetal_kappa = 5.88\n'
    )
    cfg = load_scene(p)
    assert cfg.plates[0].metal == "steel" and cfg.image_size == 32
    p.write_text("image_sise = 32\n")
    with pytest.raises(ValueError, match="image_sise"):
        load_scene(p)
    p.write_text("geometry_deg = [95]\n")
    with pytest.raises(ValueError, match="geometry_deg"):
        load_scene(p)
    p.write_text("geometry_deg = [0.52, 0.79, 1.05]\n")  # radians typed as degrees
    with pytest.raises(ValueError, match="geometry_deg .* radians given as degrees"):
        load_scene(p)
    p.write_text('priors = "ch9"\n')
    with pytest.raises(ValueError, match="priors"):
        load_scene(p)
    for bad, name in (
        ("wavelength_um = -1.55", "wavelength_um"),
        ('psf_model = "gauss"', "psf_model"),
        ("iterations = 0", "iterations"),
    ):
        p.write_text(bad + "\n")
        with pytest.raises(ValueError, match=name):
            load_scene(p)


def test_keystone_registration_recovers_object_coordinates_and_shifts():
    """Foreshortening by cos(theta) and its inverse stretch bring a label map back (up to the half-pixel
    rounding of nearest-neighbour sampling); the correlation finds a sub-pixel translation."""
    from scatterlab.characterization.registration import (
        apply_shift,
        estimate_shift,
        foreshorten,
        keystone_correct,
        register,
    )
    from scatterlab.imaging import painted_plate

    labels = painted_plate(128, scratches=0).labels
    for deg in (30.0, 60.0):
        th = np.radians(deg)
        cam = foreshorten(labels, th)
        # the letters look narrower by cos(theta) along the plane of incidence
        assert abs((cam > 0).sum() / (labels > 0).sum() - np.cos(th)) < 0.03
        back = np.rint(keystone_correct(cam.astype(float), th, order=0)).astype(int)
        assert np.mean(back != labels) < 0.03
    rng = np.random.default_rng(0)
    img = np.fft.irfft2(
        np.fft.rfft2(rng.random((64, 64)))
        * np.exp(
            -0.02 * np.add.outer(np.fft.fftfreq(64) ** 2 * 4096, np.fft.rfftfreq(64) ** 2 * 4096)
        ),
        s=(64, 64),
    )
    true = np.array([3.3, -5.6])
    moved = np.fft.irfft2(
        np.fft.rfft2(img)
        * np.exp(
            -2j * np.pi * np.add.outer(np.fft.fftfreq(64) * true[0], np.fft.rfftfreq(64) * true[1])
        ),
        s=(64, 64),
    )
    est = estimate_shift(img, moved)
    # the sub-pixel peak of a smooth image's correlation: measured within 0.004 of the Fourier shift
    np.testing.assert_allclose(est, -true, atol=0.02)
    aligned = apply_shift(moved, est)
    assert np.sqrt(np.mean((aligned - img)[10:-10, 10:-10] ** 2)) < 0.08 * img.std()  # 0.039
    s0, others, shift = register(moved, np.stack([moved, moved]), 0.0, reference=img)
    np.testing.assert_allclose(shift, est)
    np.testing.assert_allclose(others[0], s0)
    with pytest.raises(ValueError, match="theta_r"):
        keystone_correct(img, np.radians(89.5))
    with pytest.raises(ValueError, match="same shape"):
        estimate_shift(img, img[:10])


def test_registration_finds_large_shifts_of_a_plate_whose_metal_runs_off_the_field():
    """A blurred view of a plate whose bright metal runs off the field's edges, cut from a larger scene 4
    and -15 pixels away from the sharp reference: the normalised correlation over the fields' overlap
    finds the known offset (the plain circular correlation answered (0, 10) here, pulled toward zero by
    the wrap-around). Dead pixels listed in ``image_mask`` are left out."""
    from scipy import ndimage

    from scatterlab.characterization.registration import estimate_shift

    H = 96
    big = np.full((2 * H, 2 * H), 1.0)
    big[:, : H // 2 + 10] = 12.0  # a metal strip running off the field's left edge
    big[H // 2 - 10 : H // 2 + 20, H + 20 :] = 12.0  # and a block off its right edge
    sharp = big[H // 2 : H // 2 + H, H // 2 : H // 2 + H]
    y0, x0 = H // 2 - 4, H // 2 + 15  # the content sits at +4 rows, -15 columns: align by (-4, +15)
    moved = ndimage.gaussian_filter(big, 6.0)[y0 : y0 + H, x0 : x0 + H]
    np.testing.assert_allclose(estimate_shift(sharp, moved), [-4.0, 15.0], atol=0.5)
    dead = moved.copy()
    dead[30:60, 20:50] = 0.0
    ok = np.ones(dead.shape, bool)
    ok[30:60, 20:50] = False
    np.testing.assert_allclose(estimate_shift(sharp, dead, image_mask=ok), [-4.0, 15.0], atol=0.5)
    with pytest.raises(ValueError, match="image_mask"):
        estimate_shift(sharp, moved, image_mask=ok[:10])
    np.testing.assert_array_equal(estimate_shift(np.ones((8, 8)), np.ones((8, 8))), [0.0, 0.0])


def test_pixels_a_registration_brings_in_from_beyond_the_field_are_not_measurements():
    """A restoration whose content sits 4 rows and -15 columns away from the reference is aligned by
    (-4, +15): the 15 columns on the left and the 4 rows at the bottom come from beyond the camera's field
    (filled by repeating its edge), so they are unmeasured -- ``measured`` False, their values kept for
    the region means, whose re-simulations are registered alike -- and the classification scores leave
    them out; an image needing no shift has every pixel measured."""
    from types import SimpleNamespace

    from scipy import ndimage

    from scatterlab.characterization.metrics import _classification
    from scatterlab.characterization.registration import register_restoration

    H = 96
    big = np.full((2 * H, 2 * H), 1.0)
    big[:, : H // 2 + 10] = 12.0
    big[H // 2 - 10 : H // 2 + 20, H + 20 :] = 12.0
    sharp = big[H // 2 : H // 2 + H, H // 2 : H // 2 + H]
    y0, x0 = H // 2 - 4, H // 2 + 15
    moved = ndimage.gaussian_filter(big, 6.0)[y0 : y0 + H, x0 : x0 + H]
    cls = (moved > 6.0).astype(int)
    rest = SimpleNamespace(kind="degraded", s0=moved, dolp=np.full((H, H), 0.5), classes=cls)
    reg = register_restoration(rest, 0.0, sharp, foreshortened=False)
    np.testing.assert_allclose(reg.shift, [-4.0, 15.0], atol=0.5)
    assert not reg.measured[:, :14].any() and not reg.measured[-3:, :].any()
    assert reg.measured[5:-5, 17:].all()
    assert np.isfinite(reg.dolp).all() and (reg.classes >= 0).all()
    assert register_restoration(rest, 0.0, moved, foreshortened=False).measured is None
    assert register_restoration(rest, 0.0, None, foreshortened=False).measured is None
    # scored against a reference that measured everything, the unmeasured pixels are left out
    ref = SimpleNamespace(classes=(sharp > 6.0).astype(int), measured=None)
    o = SimpleNamespace(images={("no_turbulence", "restored"): ref, ("c", "degraded"): reg})
    result = SimpleNamespace(observations=[o], labels=(sharp > 6.0).astype(int))
    scores = _classification(result, "c", "degraded", 0, np.ones((H, H), bool), (None, None))
    assert scores["classification_vs_no_turbulence"]["pixels"] == int(reg.measured.sum())
    assert scores["classification_vs_labels"]["pixels"] == int(reg.measured.sum())


def test_deconvolutions_are_checkpointed_and_resumed(tmp_path, monkeypatch):
    """A run interrupted after some deconvolutions finished resumes from their checkpoints with identical
    results; the checkpoints go once the results are written."""
    import json

    from scatterlab.characterization import restoration

    cfg = tiny(estimate=["classes"])
    calls = []
    real = restoration._em

    def counting(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt  # the second deconvolution is interrupted
        return real(*a, **k)

    monkeypatch.setattr(restoration, "_em", counting)
    with pytest.raises(KeyboardInterrupt):
        characterize(cfg, tmp_path / "run")
    assert len(list((tmp_path / "run" / "checkpoints").glob("*.npz"))) == 1
    assert not (tmp_path / "run" / "results.h5").exists()
    resumed = []
    monkeypatch.setattr(restoration, "_em", lambda *a, **k: resumed.append(1) or real(*a, **k))
    characterize(cfg, tmp_path / "run")  # a plain rerun finishes an unfinished run
    total = len(cfg.geometry_deg) * (1 + len(cfg.d_over_r0))
    assert len(resumed) == total - 1  # one read back from its checkpoint
    assert not (tmp_path / "run" / "checkpoints").exists()
    characterize(tiny(estimate=["classes"]), tmp_path / "fresh")
    a = json.loads((tmp_path / "run" / "summary.json").read_text())["plates"]
    b = json.loads((tmp_path / "fresh" / "summary.json").read_text())["plates"]
    assert a == b


def test_cli_quick_run_infers_the_noise_the_re_simulations_did_not_measure(tmp_path):
    """`scatterlab characterize --quick` runs the bundled scene end to end (three geometries). After blind
    correction the paint's noise is the bootstrap replicates' spread (re-simulated on the no-turbulence
    image's plate): no DOLP-noise parameter; the metal's difference correction leaves one to infer, bounded
    below by the pixel scatter. A bad scene file exits with 2."""
    from scatterlab.cli import main

    assert main(["characterize", "--quick", "--out", str(tmp_path / "q")]) == 0
    s = json.loads((tmp_path / "q" / "summary.json").read_text())["plates"]
    post = s["aluminium"]["D_r0_7.9_corrected"]["posterior_paint"]
    assert {"n", "kappa", "converged", "dolp_bias_corrected"} <= set(post) and "noise" not in post
    assert len(post["dolp_mean"]) == 3
    metal = s["aluminium"]["D_r0_7.9_corrected"]["posterior_aluminium"]
    assert metal["noise"]["median"] > 0
    assert "covered 68 / 95 %" in (tmp_path / "q" / "report.md").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text("image_size = 7\n")
    assert main(["characterize", str(bad), "--out", str(tmp_path / "b")]) == 2


def test_failure_notes_give_the_cause_of_a_failure_after_deconvolution():
    """A failure after deconvolution names the PSF estimate's distance from the truth, unless the run was
    given the true PSF; a metal's marginal miss is named as the ridge's, and too many missed statements
    get their own note."""
    from types import SimpleNamespace

    from scatterlab.characterization import Ideal
    from scatterlab.characterization.report_text import _failure_notes

    res = SimpleNamespace(
        plate=SimpleNamespace(metal="steel"),
        metrics={"no_turbulence": {}, "D_r0_7.9_corrected": {"psf_l1_error": 1.234}},
    )
    checks = [
        ("steel: paint posterior median of n within 0.05 of the truth (no turbulence)", "", True),
        ("steel, D/r0 = 7.9: corrected vs no-turbulence classification error <= 0.06", "", False),
    ]
    text = "\n".join(_failure_notes([res], checks, Ideal()))
    assert "steel D/r0 = 7.9: 1.23" in text
    assert "1.23" not in "\n".join(_failure_notes([res], checks, Ideal(psf=True)))
    assert _failure_notes([res], [(c, v, True) for c, v, _ in checks], Ideal()) == []
    ridge = (
        "steel: steel posterior 68 % interval of n covers the truth (no turbulence)",
        "",
        False,
    )
    # the ridge's note only where the data determine the parameter partly (contraction < 0.9); a
    # determined parameter's miss is the error model's (or chance), not the ridge's
    for contraction, said, unsaid in (
        (0.3, "only partly (steel's n)", "do determine"),
        (0.98, "do determine the parameter (steel's n", "only partly"),
    ):
        res.metrics["no_turbulence"]["posterior_steel"] = {"n": {"contraction": contraction}}
        text = "\n".join(_failure_notes([res], [ridge], Ideal()))
        assert "1 of the metals' marginal 68 % intervals miss" in text
        assert said in text and unsaid not in text
    # the corrected image's ghosts are this run's counts, not another run's
    res.metrics["D_r0_7.9_corrected"]["classification_vs_no_turbulence"] = {
        "false_metal": 0.01,
        "pixels": 3136,
    }
    res.metrics["D_r0_7.9_degraded"] = {
        "classification_vs_no_turbulence": {"false_metal": 0.0, "pixels": 3000}
    }
    text = "\n".join(_failure_notes([res], checks, Ideal()))
    assert (
        "adds is its ghosts, pixels wrongly metal: steel, D/r0 = 7.9: 31 against 0 in the degraded "
        "image, of 3 136 and 3 000" in text
    )
    assert "12 544 pixels scored" not in text
    many = ("no turbulence: the 68 % statements (...) miss the truth no more often ...", "", False)
    assert "More statements miss" in "\n".join(_failure_notes([res], [many], Ideal()))


def test_interval_statements_are_judged_together_by_their_binomial_chance():
    """A calibrated 68 % statement misses with probability 0.32: 1 miss of 3 happens at least that often
    with probability 1 - 0.68**3 (closed form) and passes; 3 of 3 (0.32**3 = 0.033) fails. At 95 %, one
    miss of 8 has probability 1 - 0.95**8 = 0.34 and passes."""
    from scatterlab.characterization.report import _calibration_checks

    (c68, v68, ok68), (c95, v95, ok95) = _calibration_checks(
        [(True, True), (False, True), (True, True)]
    )
    assert ok68 and ok95 and "1 of 3 miss" in v68 and f"probability {1 - 0.68**3:.2f}" in v68
    assert "0 of 3 miss" in v95 and "probability 1.00" in v95
    (_, v, ok), _ = _calibration_checks([(False, True)] * 3)
    assert not ok and f"probability {0.32**3:.2f}" in v
    _, (_, v, ok) = _calibration_checks([(True, False)] + [(True, True)] * 7)
    assert ok and f"probability {1 - 0.95**8:.2f}" in v
    assert _calibration_checks([]) == []


def test_a_plates_prior_ranges_reach_its_posteriors_and_the_report(tmp_path):
    plate = Plate(metal_n_prior=[1.0, 2.0], metal_kappa_prior=[14.0, 18.0])
    cfg = tiny(estimate=["posterior"])
    cfg.plates = [plate.validate()]
    text = characterize(cfg, tmp_path).read_text()
    assert "aluminium n in [1.0, 2.0], kappa in [14.0, 18.0]" in text
    assert "paint n in [0.0, 5.0], kappa in [0.0, 25.0]" in text  # the default where none is given
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["scene"]["plates"][0]["metal_kappa_prior"] == [14.0, 18.0]
    for case in ("no_turbulence", "D_r0_7.9_corrected"):
        post = s["plates"]["aluminium"][case]["posterior_aluminium"]
        for q, (lo, hi) in (("n", (1.0, 2.0)), ("kappa", (14.0, 18.0))):
            assert lo <= post[q]["ci95"][0] and post[q]["ci95"][1] <= hi, (case, q, post[q])


def test_the_figures_truth_column_shows_the_object():
    """The truth panels are the plate's own materials by label (scratches are bare metal), its S0 at the
    reference image's flux, and the metal in the class the no-turbulence image gives most of it (with the
    Ch. VI priors, its group)."""
    from types import SimpleNamespace

    from scatterlab.characterization.report import _truth_panels
    from scatterlab.characterization.scene_config import Plate

    labels = np.zeros((6, 6), int)
    labels[:, 3:] = 1
    labels[0, :3] = 2
    ref_classes = np.where(labels > 0, 2, 0)
    ref_classes[1, 4] = 1  # one pixel of the other metal group
    truth_s0 = np.where(labels > 0, 4.0, 1.0)
    ref = SimpleNamespace(s0=3.0 * truth_s0)
    o = SimpleNamespace(
        truth_s0=truth_s0, truth_dolp=np.full((6, 6), 0.5), images={("a", "b"): ref}
    )
    plate = Plate(metal="steel", metal_n=3.6, metal_kappa=5.88)
    panels = _truth_panels(plate, labels, o, ("a", "b"), ref_classes)
    np.testing.assert_allclose(panels["S0"], ref.s0)
    np.testing.assert_array_equal(panels["classes"], np.where(labels > 0, 2, 0))
    np.testing.assert_array_equal(panels["n"], np.where(labels > 0, 3.6, plate.paint_n))
    np.testing.assert_array_equal(panels["kappa"], np.where(labels > 0, 5.88, plate.paint_kappa))
    assert "classes" not in _truth_panels(plate, labels, o, ("a", "b"))  # a run without classes


def test_index_maps_are_scaled_to_the_plate_within_the_fit_box():
    """Steel's kappa of 5.88 gets a scale of 11.76 (its bar extends beyond), aluminium's 16 the whole box
    of 25; n is 0-5 for both (the box is below twice steel's 3.6)."""
    from scatterlab.characterization.report import _index_scales
    from scatterlab.characterization.scene_config import Plate

    tops, extend = _index_scales(Plate(metal="steel", metal_n=3.6, metal_kappa=5.88))
    assert tops == {"n": 5.0, "kappa": pytest.approx(11.76)}
    assert extend == {"n": "neither", "kappa": "max"}
    tops, extend = _index_scales(Plate(metal="aluminium", metal_n=1.44, metal_kappa=16.0))
    assert tops["kappa"] == 25.0 and extend["kappa"] == "neither"
    assert tops["n"] == pytest.approx(2.88) and extend["n"] == "max"


def test_classification_comparisons_give_the_pixel_counts():
    from scatterlab.characterization.report import _pixel_counts
    from scatterlab.deconvolution import classification_errors

    truth = np.zeros((10, 10), int)
    truth[:, 5:] = 1
    a, b = truth.copy(), truth.copy()
    a[0, :3] = 1  # 3 pixels wrong
    b[:2, :2] = 1  # 4 pixels wrong
    ca, cb = classification_errors(a, truth), classification_errors(b, truth)
    assert ca["pixels"] == 100
    assert _pixel_counts(ca, cb) == " (3 vs 4 of 100 pixels)"
    # a summary written before the count existed
    assert _pixel_counts({"total_error": 0.1}, cb) == ""
    cc = classification_errors(a, truth, mask=np.arange(100).reshape(10, 10) >= 10)  # 90 scored
    assert _pixel_counts(cc, cb) == " (0 of 90 vs 4 of 100 pixels)"


def test_the_header_says_what_the_inversion_is_given():
    from scatterlab.characterization import default_scene
    from scatterlab.characterization.report_text import _inversion_note

    cfg = default_scene()
    text = _inversion_note(cfg)
    assert "rms facet slope 0.3) is given to the inversion at its true value" in text
    assert "no model error" in text and "3 random start PSFs" in text and "4 times" in text
    cfg.model_error = True
    assert "adds the tabulated pBRDF model error" in _inversion_note(cfg)


def test_the_figure_caption_gives_the_scale_and_the_fit_bound_colour():
    """The caption names the resolution in object pixels at the figure's angle (2 / cos 60 deg = 4.0
    horizontally) and says what the cyan pixels of the n and kappa maps are."""
    import dataclasses

    from scatterlab.characterization import default_scene
    from scatterlab.characterization.report_text import _figure_caption

    cfg = dataclasses.replace(default_scene(), image_size=96)
    text = _figure_caption("steel", 60, cfg)
    assert "96 object pixels across" in text and "(4.0 here)" in text
    assert "cyan where the fit stopped on the box's edge, n 0 or 5, kappa 0 or 25" in text
