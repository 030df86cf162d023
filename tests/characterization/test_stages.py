"""The characterization stages against the scene's known truth: with ideal optics, noise and geometry the
pipeline returns the materials it rendered; the known-PSF restoration removes the halo bias of the paint;
an interrupted run resumes to the same results; scene files are validated before anything runs."""

import json

import numpy as np
import pytest

from scatterlab.characterization import Ideal, SceneConfig, characterize, load_scene, run_plate
from scatterlab.characterization.estimation import default_margin, region_data
from scatterlab.characterization.pipeline import interior
from scatterlab.characterization.scene_config import Plate
from scatterlab.inversion import fit_dolp


def small(**kw):
    base = dict(
        image_size=64,
        geometry_deg=[30, 45, 60],
        d_over_r0=[7.9],
        iterations=10,
        posterior_steps=300,
        plates=[Plate()],
        estimate=["n_kappa"],
    )
    base.update(kw)
    return SceneConfig(**base).validate()


def region_fit(res, case, kind, region):
    obs = res.observations
    th = np.array([o.theta for o in obs])
    stack = np.stack([o.images[(case, kind)].dolp for o in obs])
    sel = interior(res.labels.shape, 4)
    truth = (
        (res.plate.paint_n, res.plate.paint_kappa)
        if region == "paint"
        else (res.plate.metal_n, res.plate.metal_kappa)
    )
    d = region_data(region, stack, res.labels, sel, default_margin(th.max()), th, truth)
    f = fit_dolp(d.mean, th, th, sigma=0.3)
    return float(f.n), float(f.kappa), d


def test_ideal_chain_returns_the_rendered_materials():
    """No noise, no blur, no foreshortening: the region-mean DOLP is the pBRDF's (Eq. 203) and the inversion
    recovers the paint's and the steel's indices (independent truth: the scene's own n - j kappa)."""
    cfg = small(plates=[Plate("steel", 3.60, 5.88)], d_over_r0=[])
    res = run_plate(
        cfg.plates[0],
        cfg,
        np.random.default_rng(0),
        ideal=Ideal(noise=True, optics=True, foreshortening=True),
    )
    from scatterlab.pbrdf import Model

    theta = np.array([o.theta for o in res.observations])
    for region, eta in (("paint", 1.39 - 0.34j), ("metal", 3.60 - 5.88j)):
        n, k, d = region_fit(res, "no_turbulence", "restored", region)
        # measured: the DOLP within 1.2e-14 of the pBRDF's, n and kappa within 7e-9 of the truth
        np.testing.assert_allclose(d.mean, Model(0.3).dolp(eta, theta, theta, np.pi), atol=1e-12)
        assert abs(n - eta.real) < 1e-6 and abs(k + eta.imag) < 1e-6


def test_known_psf_restoration_removes_the_halo_bias_of_the_paint():
    """The aluminium's diffraction halo (20-30x brighter than the paint, DOLP ~0.01) lowers the paint's DOLP;
    deconvolving the no-turbulence image with its known PSF brings the region mean back toward the truth."""
    cfg = small(d_over_r0=[])
    res = run_plate(cfg.plates[0], cfg, np.random.default_rng(1), ideal=Ideal(noise=True))
    truth = np.array([np.nanmean(o.truth_dolp[res.labels == 0]) for o in res.observations])
    _, _, raw = region_fit(res, "no_turbulence", "degraded", "paint")
    _, _, restored = region_fit(res, "no_turbulence", "restored", "paint")
    err_raw, err_restored = np.abs(raw.mean - truth), np.abs(restored.mean - truth)
    assert np.all(err_restored < 0.5 * err_raw), (err_raw, err_restored)


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    cfg = small(
        image_size=32,
        iterations=3,
        plates=[Plate(), Plate("steel", 3.60, 5.88)],
        estimate=["classes"],
    )
    out = tmp_path_factory.mktemp("whole")
    characterize(cfg, out)
    return cfg, json.loads((out / "summary.json").read_text())["plates"]


# (module, function, which call dies): killed inside a deconvolution, while scoring the second plate, between
# the two plates' figures, and after results.h5 is in place but before summary.json is written
BOUNDARIES = [
    ("restoration", "_em", 3),
    ("metrics", "score_plate", 2),
    ("report", "plate_figure", 2),
    ("runtime_results", "write_json", 1),
]


@pytest.mark.parametrize("module, name, call", BOUNDARIES)
def test_a_run_killed_at_any_stage_finishes_on_a_plain_rerun(
    tmp_path, monkeypatch, uninterrupted, module, name, call
):
    """A run killed at a stage boundary finishes on a plain rerun (no --force), with the numbers of an
    uninterrupted run; a finished run is not overwritten silently."""
    import importlib

    cfg, whole = uninterrupted
    mod = importlib.import_module(
        {"runtime_results": "scatterlab.runtime.results"}.get(
            module, f"scatterlab.characterization.{module}"
        )
    )
    original = getattr(mod, name)
    calls = {"n": 0}

    def dies(*a, **k):
        calls["n"] += 1
        if calls["n"] == call:
            raise KeyboardInterrupt("killed")
        return original(*a, **k)

    monkeypatch.setattr(mod, name, dies)
    with pytest.raises(KeyboardInterrupt):
        characterize(cfg, tmp_path / "killed")
    monkeypatch.setattr(mod, name, original)
    assert not (tmp_path / "killed" / "report.md").exists()
    rerun = characterize(cfg, tmp_path / "killed")  # no overwrite needed: the run was not finished
    assert json.loads((rerun.parent / "summary.json").read_text())["plates"] == whole
    assert not (tmp_path / "killed" / "checkpoints").exists()
    with pytest.raises(FileExistsError):
        characterize(cfg, tmp_path / "killed")


@pytest.mark.parametrize(
    "text, key",
    [
        ("[[plates]]\nmetal_nn = 1.4\n", "metal_nn"),
        ('image_size = "big"\n', "image_size"),
        ("image_size = 64.0\n", "image_size"),
        ("image_size = 100000\n", "image_size"),
        ("geometry_deg = 45\n", "geometry_deg"),
        ("plates = []\n", "plates"),
        ("photons = nan\n", "photons"),
        ("photons = inf\n", "photons"),
        ("d_over_r0 = [nan]\n", "d_over_r0"),
        ("polarizer_deg = [0, 0, 0, 0]\n", "polarizer_deg"),
        ("sigma_known = 0\n", "sigma_known"),
        ("posterior_steps = -5\n", "posterior_steps"),
        ("[[plates]]\nmetal_n = -1.0\n", "metal_n"),
        ("[[plates]]\nmetal_roughness = 0.0\n", "metal_roughness"),
        ('[[plates]]\nmetal_kappa = "x"\n', "metal_kappa"),
        ('psf_refine = "kmeans"\n', "psf_refine"),
        ("blind_starts = 0\n", "blind_starts"),
        ("blind_starts = 2.5\n", "blind_starts"),
    ],
)
def test_scene_errors_name_the_key_before_anything_runs(tmp_path, text, key):
    p = tmp_path / "scene.toml"
    p.write_text(text)
    with pytest.raises(ValueError, match=key):
        load_scene(p)


def test_a_file_that_is_not_toml_is_named_as_such(tmp_path):
    p = tmp_path / "data.npy"
    np.save(p, np.zeros(3))
    with pytest.raises(ValueError, match="expected a TOML scene"):
        load_scene(p)
    q = tmp_path / "data.csv"
    q.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="expected a TOML scene"):
        load_scene(q)


def test_output_folder_that_is_a_file_is_a_clear_error(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(ValueError, match="not a folder"):
        characterize(small(image_size=32, estimate=["classes"]), f)


def test_a_scene_that_is_not_the_default_gets_intervals_covering_its_truth():
    """Another metal (titanium 3.69 - j4.59), another paint (1.60 - j0.10), other geometries and sampling:
    without turbulence both regions' 95 % intervals cover the truth (issue: any painted-plate scene a user
    writes). The calibration over many seeds is studies/characterization_coverage.py."""
    cfg = small(
        image_size=96,
        geometry_deg=[35, 45, 55, 65],
        d_over_r0=[],
        iterations=10,
        posterior_steps=800,
        plates=[Plate("titanium", 3.69, 4.59, 1.60, 0.10)],
        estimate=["posterior"],
        seed=11,
    )
    res = run_plate(cfg.plates[0], cfg, np.random.default_rng(cfg.seed))
    for region in ("paint", "titanium"):
        p = res.metrics["no_turbulence"][f"posterior_{region}"]
        assert p["n"]["covers95"] and p["kappa"]["covers95"], (region, p["n"], p["kappa"])


def test_bias_correction_keeps_a_dolp_in_its_range():
    """Subtracting a re-simulated bias never takes a region mean outside [0, 1] (it happened with a corrected
    paint at 0.95 and a bias of -0.12), and the bias stays in the error."""
    from scatterlab.characterization.estimation import RegionData
    from scatterlab.characterization.self_calibration import bias_corrected

    r = RegionData(
        "paint", np.array([0.95, 0.02]), np.array([0.01, 0.01]), np.zeros(2), np.zeros(2), 100
    )
    c = bias_corrected(r, np.array([-0.12, 0.05]))
    np.testing.assert_allclose(c.mean, [1.0, 0.0])
    np.testing.assert_allclose(c.error, np.hypot(0.01, [0.06, 0.025]))


def test_bootstrap_bias_error_carries_the_data_draw():
    """A bootstrap bias over R replicates leaves the data's own draw: its error is the replicate spread times
    sqrt(1 + 1/R), in quadrature with half the bias (scene mismatch); a deterministic bias keeps half of it."""
    from scatterlab.characterization.estimation import RegionData
    from scatterlab.characterization.self_calibration import BiasEstimate, bias_corrected

    r = RegionData(
        "paint", np.array([0.5, 0.6]), np.array([0.01, 0.02]), np.zeros(2), np.zeros(2), 50
    )
    b = BiasEstimate(np.array([-0.2, -0.1]), np.array([0.04, 0.04]), 2)
    c = bias_corrected(r, b)
    np.testing.assert_allclose(c.mean, [0.7, 0.7])
    expect = np.sqrt(r.error**2 + (0.5 * np.abs(b.mean)) ** 2 + 0.04**2 * 1.5)
    np.testing.assert_allclose(c.error, expect)
    np.testing.assert_allclose(c.bias_spread, 0.04)


def test_bootstrap_needs_a_positive_turbulence_strength():
    from scatterlab.characterization.self_calibration import restoration_bias

    with pytest.raises(ValueError, match="d_over_r0"):
        restoration_bias(
            [],
            np.zeros((8, 8)),
            np.radians([30.0]),
            [None],
            None,
            None,
            None,
            1,
            blind=True,
            d_over_r0=-1.0,
        )


def test_model_error_widens_the_region_posterior():
    """The MoM-measured model error (issue 17) enters each geometry's error: with it, the posterior of a
    region whose DOLP is known to 0.002 is wider, and a wrong type for the scene key is refused."""
    from scatterlab.characterization.estimation import RegionData, region_posteriors
    from scatterlab.inversion import model_dolp

    th = np.radians([30.0, 40.0, 50.0, 60.0])
    y = np.asarray(model_dolp(1.5, 0.1, 0.3, th, th), float)
    r = RegionData("paint", y, np.full(4, 0.002), np.full(4, 0.002), np.zeros(4), 100, (1.5, 0.1))
    widths = []
    for me in (False, True):
        est = region_posteriors([r], th, 0.3, np.random.default_rng(3), n_steps=400, model_error=me)
        lo, hi = est[0].parameters["n"]["ci68"]
        widths.append(hi - lo)
    assert widths[1] > 2 * widths[0], widths
    from scatterlab.characterization import SceneConfig

    with pytest.raises(ValueError, match="model_error"):
        SceneConfig(model_error="yes").validate()


def test_ratio_correction_scales_the_data_error_with_the_mean():
    """A paint corrected by a ratio (restored = ratio x true) has its mean divided by the ratio, so its
    statistical and edge errors are divided by it too; the equivalent difference keeps half as systematic."""
    from scatterlab.characterization.estimation import RegionData
    from scatterlab.characterization.self_calibration import (
        BLIND_RATIO_CORRELATED_FRACTION,
        BiasEstimate,
        bias_corrected,
    )

    stat, edge = np.array([0.01, 0.02]), np.array([0.0, 0.01])
    r = RegionData("paint", np.array([0.4, 0.3]), np.hypot(stat, edge), stat, edge, 80)
    ratio = np.array([0.5, 0.6])
    c = bias_corrected(r, BiasEstimate(np.zeros(2), np.zeros(2), 1, ratio))
    np.testing.assert_allclose(c.mean, [0.8, 0.5])
    np.testing.assert_allclose(c.statistical, stat / ratio)
    shift = r.mean - r.mean / ratio  # the equivalent bias: half of it kept per geometry, and
    # BLIND_RATIO_CORRELATED_FRACTION of it as one error of the whole series
    f = BLIND_RATIO_CORRELATED_FRACTION
    np.testing.assert_allclose(c.correlated, f * shift)
    np.testing.assert_allclose(
        c.error, np.sqrt((r.error / ratio) ** 2 + (0.5 * shift) ** 2 + (f * shift) ** 2)
    )


def test_model_error_is_chosen_by_the_regions_class(monkeypatch):
    """With ``model_error=True`` each region's error gains the model error of its class from the
    classification (the region named "metal": metal; any other: dielectric), added in quadrature;
    the class-aware form is the one whose coverage the study dolp_vs_mom measured."""
    import scatterlab.inversion as inv
    from scatterlab.characterization.estimation import RegionData, region_posteriors
    from scatterlab.inversion import dolp_model_error

    seen = {}

    class Stop(Exception):
        pass

    def fake(dolp, theta_i, theta_r, noise=None, rng=None, *, systematic=None, **kw):
        seen["systematic"] = np.asarray(systematic)
        raise Stop

    monkeypatch.setattr(inv, "sample_posteriors", fake)
    th = np.radians([30.0, 40.0, 50.0, 60.0])
    err = np.full(4, 0.01)
    regions = [
        RegionData(name, np.full(4, 0.3), err, err, 0 * err, 100) for name in ("paint", "metal")
    ]
    with pytest.raises(Stop):
        region_posteriors(regions, th, 0.3, np.random.default_rng(0), model_error=True)
    for row, cls in zip(seen["systematic"], ("dielectric", "metal")):
        want = np.hypot(err, dolp_model_error(th, th, 0.3, material_class=cls))
        np.testing.assert_allclose(row, want, rtol=1e-12)
    assert not np.allclose(seen["systematic"][0], seen["systematic"][1])


def test_known_psf_bias_error_is_the_replicates_noise_and_the_unexplained_edge_shift():
    """After noisy known-PSF re-simulations the region's error is their measured noise (spread x
    sqrt(1 + 1/R)), the data's edge shift minus theirs (the edge mixing their layout explains is no error; its
    rms over the geometries, so that no geometry's single draw near 0 leaves it without edge error) and the
    calibrated fraction of the bias, in quadrature; the pixel-scatter estimate is replaced."""
    from scatterlab.characterization.estimation import RegionData
    from scatterlab.characterization.self_calibration import (
        KNOWN_PSF_SYSTEMATIC_FRACTION,
        BiasEstimate,
        bias_corrected,
    )

    stat, shift = np.array([0.003, 0.004]), np.array([-0.010, 0.002])
    r = RegionData(
        "paint",
        np.array([0.40, 0.30]),
        np.hypot(stat, shift),
        stat,
        np.abs(shift),
        80,
        edge_shift=shift,
    )
    b = BiasEstimate(
        np.array([-0.02, -0.01]),
        np.full(2, 0.001),
        4,
        None,
        np.array([-0.008, 0.003]),
        KNOWN_PSF_SYSTEMATIC_FRACTION,
    )
    c = bias_corrected(r, b)
    np.testing.assert_allclose(c.mean, [0.42, 0.31])
    np.testing.assert_allclose(c.statistical, 0.001 * np.sqrt(1.25))
    edge = np.sqrt((0.002**2 + 0.001**2) / 2)  # unexplained shifts -0.002 and -0.001
    np.testing.assert_allclose(c.edge, [edge, edge])
    f = KNOWN_PSF_SYSTEMATIC_FRACTION
    expect = np.sqrt(0.001**2 * 1.25 + edge**2 + (f * np.abs(b.mean)) ** 2)
    np.testing.assert_allclose(c.error, expect)
    # a geometry whose shift the re-simulations happen to match keeps the series' edge error
    c0 = bias_corrected(r, BiasEstimate(b.mean, b.spread, 4, None, np.array([-0.010, 0.0]), f))
    np.testing.assert_allclose(c0.edge, [np.sqrt(0.002**2 / 2)] * 2)


def test_known_psf_replicates_measure_the_noise_of_a_region_mean():
    """Independent truth: the scatter of the data's own paint region mean over independent noise draws (same
    plate, layout and PSF). The known-PSF re-simulations' spread, pooled over geometries (R = 4 replicates x
    2 geometries: 6 degrees of freedom), estimates it; against the truth's 9, the ratio lies in [0.3, 2.8]
    with probability above 0.99."""
    from scatterlab.characterization.pipeline import observe
    from scatterlab.characterization.scene_config import plate_labels
    from scatterlab.characterization.self_calibration import KNOWN_PSF_REPLICATES, restoration_bias

    cfg = small(image_size=48, geometry_deg=[40, 55], d_over_r0=[], iterations=10)
    plate = cfg.plates[0]
    labels = plate_labels(cfg, np.random.default_rng(5))
    th = np.radians(cfg.geometry_deg)
    sel = interior(labels.shape, 3)
    margin = default_margin(th.max())
    means = []
    for k in range(10):
        obs = observe(plate, labels, th, cfg, np.random.default_rng(100 + k))
        stack = np.stack([o.images[("no_turbulence", "restored")].dolp for o in obs])
        means.append(region_data("paint", stack, labels, sel, margin, th).mean)
    truth = np.sqrt(np.mean(np.var(np.array(means), axis=0, ddof=1)))
    regions = [region_data(r, stack, labels, sel, margin, th) for r in ("paint", "metal")]
    bias = restoration_bias(
        regions, labels, th, [None, None], cfg, np.random.default_rng(7), sel, margin
    )["paint"]
    assert bias.replicates == KNOWN_PSF_REPLICATES and bias.edge_shift is not None
    assert 0.3 < bias.spread[0] / truth < 2.8, (bias.spread[0], truth)


def test_a_calibrated_region_gets_its_measured_covariance_and_no_inferred_noise(monkeypatch):
    """A region whose error the known-PSF re-simulations measured is sampled with a fixed covariance: its
    correlated part c c^T (the kept fraction of the bias, one error of the whole series), the rest of its
    error on the diagonal, and the noise floor; no noise level is inferred. An uncalibrated region in the
    same call keeps the inferred noise."""
    import scatterlab.inversion as inv
    from scatterlab.characterization.estimation import NOISE_FLOOR, RegionData, region_posteriors

    calls = []

    def fake(
        dolp, theta_i, theta_r, noise=None, rng=None, *, covariance=None, systematic=None, **kw
    ):
        calls.append(dict(noise=noise, covariance=covariance, systematic=systematic, **kw))
        return [None] * len(dolp)

    monkeypatch.setattr(inv, "sample_posteriors", fake)
    monkeypatch.setattr(
        "scatterlab.characterization.estimation._summarise", lambda name, post, data: name
    )
    th = np.radians([30.0, 40.0, 50.0, 60.0])
    err, c = np.array([0.003, 0.002, 0.002, 0.004]), np.array([-0.001, -0.001, 0.0005, -0.002])
    calibrated = RegionData(
        "paint", np.full(4, 0.5), err, err, 0 * err, 100, calibrated=True, correlated=c
    )
    # a blind region whose correction shares one error c2 over the series: c2 goes to the sampler as the
    # correlated error, the rest of its error per geometry as the systematic beside the inferred noise
    c2 = np.array([0.001, -0.001, 0.0015, 0.002])
    free = RegionData("metal", np.full(4, 0.05), err, err, 0 * err, 100, correlated=c2)
    out = region_posteriors([calibrated, free], th, 0.3, np.random.default_rng(0))
    assert out == ["paint", "metal"]
    inferred, fixed = calls
    assert inferred["noise"] is None and inferred["noise_bounds"] is not None
    np.testing.assert_allclose(inferred["correlated"][0], np.abs(c2))
    np.testing.assert_allclose(inferred["systematic"][0], np.sqrt(err**2 - c2**2))
    assert fixed["noise"] is None
    want = np.diag(err**2 - c**2 + NOISE_FLOOR**2) + np.outer(c, c)
    np.testing.assert_allclose(fixed["covariance"][0], want, rtol=1e-12)
    # a trend over the series is its own rank-one part, taken out of the diagonal like c
    calls.clear()
    t = np.array([-0.0015, -0.0005, 0.0005, 0.0015])
    trended = RegionData(
        "paint", np.full(4, 0.5), err, err, 0 * err, 100, calibrated=True, correlated=c, trend=t
    )
    region_posteriors([trended], th, 0.3, np.random.default_rng(0))
    want = np.diag(err**2 - c**2 - t**2 + NOISE_FLOOR**2) + np.outer(c, c) + np.outer(t, t)
    np.testing.assert_allclose(calls[0]["covariance"][0], want, rtol=1e-12)
    np.testing.assert_allclose(np.sqrt(np.diag(fixed["covariance"][0])), np.hypot(err, NOISE_FLOOR))


def copper_and_paint():
    """Noise-free region means at 30-60 deg of copper-like 0.61 - j10.4 (a ridge of equal DOLP) and a
    paint 1.5 - j0.1, with errors 3e-3 and 2e-3: (theta (4,) [rad], [metal, paint] RegionData)."""
    from scatterlab.characterization.estimation import RegionData
    from scatterlab.inversion import model_dolp

    th = np.radians([30.0, 40.0, 50.0, 60.0])
    return th, [
        RegionData(
            name, np.asarray(model_dolp(n, k, 0.3, th, th), float), e, e, np.zeros(4), 100, (n, k)
        )
        for name, n, k, e in (
            ("metal", 0.61, 10.4, np.full(4, 3e-3)),
            ("paint", 1.5, 0.1, np.full(4, 2e-3)),
        )
    ]


def test_a_metal_the_data_do_not_separate_is_flagged_and_its_truth_is_in_the_joint_region():
    """Copper at 30-60 deg: its DOLP fixes about Re(1/eta), so the posterior runs along a ridge and the
    region's note says that the marginal intervals follow the prior; the exact data put the truth at the
    best fit, inside the joint likelihood-ratio region (Delta chi^2 ~ 0). A paint in the same call is
    determined and gets no such note."""
    from scatterlab.characterization.estimation import region_posteriors

    th, regions = copper_and_paint()
    metal, paint = region_posteriors(regions, th, 0.3, np.random.default_rng(3), n_steps=400)
    assert min(metal.parameters[q]["contraction"] for q in ("n", "kappa")) < 0.9
    assert any("only partly" in w for w in metal.warnings), metal.warnings
    assert metal.joint["covers68"] and metal.joint["delta_chi2"] < 0.5, metal.joint
    assert paint.parameters["kappa"]["contraction"] > 0.99
    assert not any("only partly" in w for w in paint.warnings)


def test_layout_refinement_restores_with_the_psf_it_found(monkeypatch):
    """psf_refine="layout": the blind estimate goes to layout_psf, and the image is then restored with the PSF
    it returns held fixed (the library function itself is tested against simulated truth in
    tests/deconvolution/test_layout_psf.py)."""
    import scatterlab.deconvolution as deconvolution
    from scatterlab.characterization import acquire
    from scatterlab.characterization.restoration import (
        LAYOUT_FINAL_ITERATIONS,
        RestoreSettings,
        restore,
    )
    from scatterlab.deconvolution import LayoutResult, resample_psf

    cfg = small(image_size=32)
    rng = np.random.default_rng(2)
    from scatterlab.characterization.scene_config import plate_labels

    acq = acquire(Plate(), plate_labels(cfg, rng), np.radians(50.0), "D_r0_7.9", 7.9, cfg, rng)
    seen = {}

    def fake_layout_psf(data, angles, start, **kw):
        seen["start"] = start
        truth = resample_psf(acq.psf_true, start.psfs.shape[1:])
        return LayoutResult(truth, None, None, None, None, None)

    monkeypatch.setattr(deconvolution, "layout_psf", fake_layout_psf)
    rest = restore(acq, RestoreSettings(iterations=5, psf_refine="layout"), seed=1)
    assert seen["start"].iterations == 5  # the blind EM's estimate started it
    # the blind support: a disc of a quarter of the field about the grid's centre
    Hp, Wp = rest.psf.shape
    yy, xx = np.mgrid[0:Hp, 0:Wp]
    support = np.hypot(yy - Hp // 2, xx - Wp // 2) <= cfg.image_size / 4
    truth = resample_psf(acq.psf_true, rest.psf.shape) * support
    np.testing.assert_allclose(rest.psf, truth / truth.sum(), rtol=1e-9, atol=1e-15)
    assert rest.loglik.size == LAYOUT_FINAL_ITERATIONS + 1
    assert np.all(np.diff(rest.loglik) >= -1e-10 * abs(rest.loglik[-1]))  # Richardson-Lucy

    # two exposures: one shared layout, the whole field as support, a PSF per frame held fixed
    from dataclasses import replace

    other = acquire(Plate(), plate_labels(cfg, rng), np.radians(50.0), "D_r0_7.9", 7.9, cfg, rng)
    two = replace(
        acq,
        counts=np.concatenate([acq.counts, other.counts]),
        angles=np.tile(acq.angles, 2),
    )
    truths = np.stack([acq.psf_true, other.psf_true])

    def fake_layout_frames(data, angles, start, **kw):
        seen.update(kw)
        shape = (32 + 2 * kw["pad"],) * 2
        return LayoutResult(np.stack([resample_psf(h, shape) for h in truths]), *[None] * 5)

    monkeypatch.setattr(deconvolution, "layout_psf", fake_layout_frames)
    rest = restore(two, RestoreSettings(iterations=5, psf_refine="layout", frames=2), seed=1)
    assert seen["frames"] == 2 and seen["materials"] == 2
    assert seen["pad"] == 16 and seen["psf_radius"] == pytest.approx(np.sqrt(2) * 16)
    assert rest.psf.shape == (2, 64, 64)
    for h, true in zip(rest.psf, truths):  # whole field: nothing cut
        np.testing.assert_allclose(h, resample_psf(true, (64, 64)), rtol=1e-9, atol=1e-15)
    assert rest.loglik.size == LAYOUT_FINAL_ITERATIONS + 1


def test_a_region_whose_truth_is_outside_the_joint_95_region_is_told_not_to_be_trusted():
    """A paint whose DOLP is diluted to 0.6 of its value at every geometry (a restoration bias no error term
    carries, as the metal's halo leaves it): the
    truth (the material the exact DOLP came from) falls outside the joint 95 % region, and the region's
    note says so; the same paint with its exact DOLP gets no such note."""
    from scatterlab.characterization.estimation import RegionData, region_posteriors
    from scatterlab.inversion import model_dolp

    th = np.radians([30.0, 40.0, 50.0, 60.0])
    exact = np.asarray(model_dolp(1.5, 0.1, 0.3, th, th), float)
    e = np.full(4, 2e-3)
    regions = [
        RegionData("paint", mean, e, e, np.zeros(4), 100, (1.5, 0.1))
        for mean in (0.6 * exact, exact)
    ]
    biased, right = region_posteriors(regions, th, 0.3, np.random.default_rng(3), n_steps=400)
    assert not biased.joint["covers95"], biased.joint
    assert any("outside even the joint 95 % region" in w for w in biased.warnings)
    assert right.joint["covers95"]
    assert not any("outside even the joint" in w for w in right.warnings)


def test_blind_bootstrap_on_the_reference_plate_undoes_the_paints_dilution():
    """Independent truth: the object's paint region-mean DOLP. Through D/r0 = 12.9 the blind restoration
    leaves the paint's DOLP diluted by the metal's unpolarized halo (about 0.6 of the truth). The bootstrap
    re-simulates the plate the no-turbulence image shows (its paint's brightness sets the dilution, which
    the turbulent DOLP alone cannot tell): over three scenes the corrected means are the truth within 0.12
    (relative, mean over scenes and geometries), and their residuals are within their stated errors."""
    from scatterlab.characterization.estimation import region_masks

    rel, raw, z = [], [], []
    for seed, plate in (
        (21, Plate("titanium", 3.69, 4.59, 1.55, 0.30)),
        (22, Plate("iron", 3.60, 5.88, 1.40, 0.45)),
        (23, Plate("copper", 0.61, 10.4, 1.45, 0.20)),
    ):
        cfg = small(
            geometry_deg=[30, 45, 60],
            d_over_r0=[12.9],
            iterations=40,
            posterior_steps=200,
            plates=[plate],
            estimate=["posterior"],
            seed=seed,
        )
        res = run_plate(plate, cfg, np.random.default_rng(seed))
        th = np.array([o.theta for o in res.observations])
        sel = interior(res.labels.shape, max(2, res.labels.shape[0] // 16))
        paint = region_masks(res.labels, sel, default_margin(th.max()))["paint"]
        truth = np.array([np.nanmean(o.truth_dolp[paint]) for o in res.observations])
        post = res.metrics["D_r0_12.9_corrected"]["posterior_paint"]
        mean, err = np.array(post["dolp_mean"]), np.array(post["dolp_error"])
        rel.append(mean / truth - 1)
        raw.append((mean + np.array(post["dolp_bias_corrected"])) / truth)  # before correction
        z.append((mean - truth) / err)
    assert np.mean(raw) < 0.8, raw  # the dilution the correction has to undo
    assert abs(np.mean(rel)) < 0.12, rel
    assert np.sqrt(np.mean(np.square(z))) < 2.0, z


def test_a_bootstrap_on_a_reference_plate_re_simulates_that_plate_once():
    """With ``plate=`` the bootstrap re-simulates the given plate in one pass of R x M restorations (no
    re-estimation from the diluted data), and a paint's ratio correction carries the replicates' spread as
    its measured noise and REFERENCE_RATIO_COMMON_FRACTION of the correction as one series-wide error."""
    from scatterlab.characterization.estimation import RegionData
    from scatterlab.characterization.self_calibration import (
        REFERENCE_RATIO_COMMON_FRACTION,
        REFERENCE_RATIO_TREND_CORRELATION,
        REFERENCE_RATIO_TREND_FRACTION,
        bias_corrected,
        restoration_bias,
    )

    shape, th = (16, 16), np.radians([30.0, 50.0])
    labels = np.zeros(shape, int)
    labels[:, 10:] = 1
    reference = Plate("titanium", 3.69, 4.59, 1.5, 0.3)
    seen = []

    class Recorder:
        def map(self, fn, tasks, desc=None):
            seen.extend(tasks)
            out = []
            for t in tasks:
                truth = np.where(labels == 0, 0.8, 0.1)
                k = len(out) // len(th)  # replicate-major: replicate k, then the geometries
                # restored: the paint diluted to 0.6 of its truth (+-0.02 between replicates), the metal
                # shifted by +0.01
                restored = np.where(labels == 0, 0.8 * (0.6 + 0.02 * (-1) ** k), 0.11)
                out.append((restored, truth))
            return out

    sel = np.ones(shape, bool)
    regions = [
        RegionData(r, np.array([0.5, 0.45]), np.full(2, 0.01), np.full(2, 0.01), np.zeros(2), 50)
        for r in ("paint", "metal")
    ]
    cfg = SceneConfig(calibration_replicates=4).validate()

    def bias_of(replicates):
        return restoration_bias(
            regions,
            labels,
            th,
            [None, None],
            cfg,
            np.random.default_rng(0),
            sel,
            1,
            blind=True,
            d_over_r0=12.9,
            replicates=replicates,
            plate=reference,
            executor=Recorder(),
        )

    bias = bias_of(4)
    assert len(seen) == 4 * 2 and all(t[0] is reference for t in seen)
    paint = bias["paint"]
    assert paint.measured and paint.common == REFERENCE_RATIO_COMMON_FRACTION
    np.testing.assert_allclose(paint.ratio, 0.6, atol=1e-12)
    c = bias_corrected(regions[0], paint)
    shift = regions[0].mean - regions[0].mean / 0.6
    draw = paint.spread / 0.6 * np.sqrt(1 + 1 / 4)
    np.testing.assert_allclose(c.mean, regions[0].mean / 0.6)
    # and REFERENCE_RATIO_TREND_FRACTION of it as a series-wide error that changes sign across the angles
    # (30 deg at x = -1, 50 deg at +1), correlated with the level at rho: two independent modes
    x, rho = np.array([-1.0, 1.0]), REFERENCE_RATIO_TREND_CORRELATION
    level = REFERENCE_RATIO_COMMON_FRACTION * shift
    trend = REFERENCE_RATIO_TREND_FRACTION * shift * x
    np.testing.assert_allclose(c.correlated, level + rho * trend)
    np.testing.assert_allclose(c.trend, np.sqrt(1 - rho**2) * trend)
    # their covariance is that of a level and a trend correlated at rho
    C = np.outer(c.correlated, c.correlated) + np.outer(c.trend, c.trend)
    want = (
        np.outer(level, level)
        + np.outer(trend, trend)
        + rho * (np.outer(level, trend) + np.outer(trend, level))
    )
    np.testing.assert_allclose(C, want, atol=1e-15)
    np.testing.assert_allclose(c.error, np.sqrt(draw**2 + np.diag(want)))
    assert c.calibrated and np.all(c.edge == 0)
    # the metal's difference keeps the data's own error terms and the inferred noise
    m = bias_corrected(regions[1], bias["metal"])
    assert not bias["metal"].measured and not m.calibrated
    # one replicate has no spread: it measures no noise, so the paint keeps its own error terms
    seen.clear()
    one = bias_of(1)["paint"]
    assert len(seen) == 2  # one pass of one replicate per geometry
    c1 = bias_corrected(regions[0], one)
    assert not one.measured and not c1.calibrated and np.all(c1.error > regions[0].error / 0.6)
    assert one.trend == 0 and c1.trend is None


def test_report_prints_enough_decimals_to_show_a_miss():
    # a 68 % interval [1.3904, 1.3915] misses a truth of 1.3900 by 4e-4: three decimals would print
    # "[1.390, 1.392], truth 1.390" beside a FAIL
    from scatterlab.characterization.report import _interval_and_truth
    from scatterlab.characterization.report_text import decimals_for

    assert decimals_for(1.39, 1.3904, 1.3915) == 4
    assert decimals_for(1.39, 1.2, 1.5) == 3
    text = _interval_and_truth({"median": 1.391, "ci68": [1.3904, 1.3915], "truth": 1.39})
    assert text == "1.3910 [1.3904, 1.3915], truth 1.3900"


def test_share_of_pixels_on_a_bound_of_the_fit():
    from scatterlab.characterization.metrics import _at_bound

    n = np.array([5.0, 1.44, 2.0, np.nan])
    k = np.array([10.0, 25.0, 12.0, 3.0])
    assert _at_bound(n, k) == 2 / 3  # n = 5 and kappa = 25 are the fit's bounds; NaN not fitted
    assert _at_bound(np.array([np.nan]), np.array([np.nan])) == 0.0


def test_a_contraction_at_or_below_zero_is_printed_as_none():
    """Sampling noise puts the contraction of a prior-wide chain slightly below 0; the report says none."""
    from scatterlab.characterization.estimation import contraction_text

    assert [contraction_text(c) for c in (-0.02, 0.0, 0.004, 0.05, 0.71)] == [
        "none",
        "none",
        "none",
        "0.05",
        "0.71",
    ]


def test_s0_error_is_blind_to_each_geometrys_exposure():
    """Each geometry is exposed for its own brightest pixel while the truth's radiance changes with the
    geometry: an image equal to the truth up to one exposure per geometry has no S0 error. A real error
    (a blurred edge) is still seen, and only on the edges."""
    from types import SimpleNamespace

    from scipy import ndimage

    from scatterlab.characterization.metrics import _image_errors

    labels = np.zeros((32, 32), int)
    labels[:, 16:] = 1
    truth = np.where(labels == 1, 1.0, 0.07)
    sel = interior(labels.shape, 2)
    away = ndimage.binary_erosion(labels == 1, iterations=3) | ndimage.binary_erosion(
        labels == 0, iterations=3
    )

    def obs(exposure, scale, blur):
        t = truth * scale
        img = ndimage.uniform_filter(t, blur) if blur else t
        im = SimpleNamespace(s0=exposure * img, dolp=np.full_like(t, 0.5))
        return SimpleNamespace(
            truth_s0=t,
            truth_dolp=np.full_like(t, 0.5),
            images={("no_turbulence", "restored"): im, ("case", "kind"): im},
        )

    # the truth three times brighter at the second geometry, the exposures 2e5 and 7e4
    exact = [obs(2e5, 1.0, 0), obs(7e4, 3.0, 0)]
    e = _image_errors(exact, "case", "kind", sel, away=away)
    assert e["s0_relative_rmse_truth"] == pytest.approx(0.0, abs=1e-12)
    assert e["s0_relative_rmse_truth_away_from_edges"] == pytest.approx(0.0, abs=1e-12)
    blurred = [obs(2e5, 1.0, 3), obs(7e4, 3.0, 3)]
    e = _image_errors(blurred, "case", "kind", sel, away=away)
    assert e["s0_relative_rmse_truth"] > 0.05
    assert e["s0_relative_rmse_truth_away_from_edges"] < 1e-3 * e["s0_relative_rmse_truth"]


def test_a_corrected_dolp_held_at_a_bound_is_named_in_the_regions_notes():
    """The self-calibration clips a corrected region mean to [0, 1] (a metal's DOLP of 0.005 corrected by
    more than itself): the posterior's notes say at how many geometries; uncorrected data get no note."""
    from dataclasses import replace

    from scatterlab.characterization.estimation import RegionData, region_posteriors
    from scatterlab.inversion import model_dolp

    th = np.radians([30.0, 40.0, 50.0, 60.0])
    e = np.full(4, 3e-3)
    mean = np.asarray(model_dolp(3.6, 5.88, 0.3, th, th), float)
    plain = RegionData("metal", mean, e, e, np.zeros(4), 100, (3.6, 5.88))
    held = replace(plain, mean=np.r_[0.0, mean[1:]], bias=np.full(4, 0.01))
    rng = np.random.default_rng(4)
    (a,) = region_posteriors([plain], th, 0.3, rng, n_steps=300)
    (b,) = region_posteriors([held], th, 0.3, rng, n_steps=300)
    assert not any("held at the bound" in w for w in a.warnings)
    assert any("left [0, 1] at 1 of 4 geometries" in w for w in b.warnings), b.warnings


def test_a_region_whose_fixed_chain_did_not_converge_is_run_until_it_does():
    """400 steps are too few for these two posteriors (the sampler alone flags both); the region
    posteriors run them again, up to EXTEND x as long, and return converged chains without the
    "did not converge" note."""
    from scatterlab.characterization.estimation import region_posteriors
    from scatterlab.inversion import sample_posteriors

    th, regions = copper_and_paint()
    with pytest.warns(Warning):
        short = sample_posteriors(
            np.stack([r.mean for r in regions]),
            th,
            th,
            None,
            np.random.default_rng(3),
            sigma=0.3,
            n_steps=400,
            systematic=np.stack([r.error for r in regions]),
            noise_bounds=(1e-3, 0.5),
        )
    assert not any(p.converged for p in short)
    out = region_posteriors(regions, th, 0.3, np.random.default_rng(3), n_steps=400)
    assert all(e.converged for e in out)
    assert not any("did not converge" in w for e in out for w in e.warnings)
