"""Measured data with several exposures per geometry (``analyze --frames F``): the restoration gives each frame
its own PSF over a common object, the self-calibration re-simulates each frame through its own PSF, and a
frame count that does not fit the channels is a clear error.

Independent truths: duplicated exposures through the same known PSF carry the same object (the maximum
likelihood of the doubled data is that of the single exposure); a noise-free re-simulation of a frame is the
single-frame re-simulation through that frame's PSF.
"""

import json
from dataclasses import replace

import numpy as np
import pytest

from scatterlab.characterization import Plate, SceneConfig, acquire
from scatterlab.characterization.acquisition import Ideal
from scatterlab.characterization.analysis import AnalyzeSettings, analyze
from scatterlab.characterization.restoration import RestoreSettings, restore
from scatterlab.characterization.scene_config import plate_labels
from scatterlab.characterization.self_calibration import (
    _multi_frame_acquisition,
    restoration_bias,
)
from scatterlab.cli import main


def _scene(size=48, seed=3):
    cfg = SceneConfig(image_size=size).validate()
    rng = np.random.default_rng(seed)
    return cfg, plate_labels(cfg, rng), rng


def _two_frame_dataset(size=48, seed=5, d_over_r0=7.9):
    """Two exposures per geometry, each through its own Kolmogorov screen, with the truth."""
    from scatterlab.io import Optics, PolarimetricDataset, Truth

    cfg, labels, rng = _scene(size, seed)
    thetas = np.radians([40.0, 55.0])
    counts, s0, dolp = [], [], []
    for th in thetas:
        frames = [acquire(Plate(), labels, th, "turb", d_over_r0, cfg, rng) for _ in range(2)]
        counts.append(np.concatenate([a.counts for a in frames]))
        s0.append(frames[0].truth_s0)
        dolp.append(frames[0].truth_dolp)
    truth = Truth(
        labels,
        ["paint", "metal", "scratch"],
        np.array([1.39, 1.44, 1.44]),
        np.array([0.34, 16, 16]),
        np.full(3, 0.3),
        s0=np.stack(s0),
        dolp=np.stack(dolp),
    )
    return PolarimetricDataset(
        np.stack(counts),
        np.tile(frames[0].angles, 2),
        thetas,
        1.55e-6,
        Optics(pixels_per_lambda_over_d=2.0),
        read_noise=10.0,
        truth=truth,
        title="two exposures",
        simulated=True,
    )


def test_duplicated_exposures_through_the_known_psf_restore_the_single_exposures_object():
    cfg, labels, rng = _scene()
    acq = acquire(Plate(), labels, np.radians(50.0), "no_turbulence", None, cfg, rng)
    twice = replace(
        acq, counts=np.concatenate([acq.counts, acq.counts]), angles=np.tile(acq.angles, 2)
    )
    one = restore(acq, RestoreSettings(iterations=100), seed=1)
    two = restore(twice, RestoreSettings(iterations=100, frames=2), seed=1)
    np.testing.assert_allclose(two.s0, one.s0, rtol=1e-9)
    np.testing.assert_allclose(two.dolp, one.dolp, rtol=1e-9, atol=1e-12)
    assert one.psf.ndim == 2 and two.psf.shape == (2,) + one.psf.shape


def test_each_blind_frame_gets_its_own_unit_sum_psf():
    ds = _two_frame_dataset(size=32)
    from scatterlab.characterization.analysis import _acquisitions

    acq = _acquisitions(ds, AnalyzeSettings(frames=2))[0]
    rest = restore(acq, RestoreSettings(iterations=5, frames=2), seed=2)
    assert rest.psf.ndim == 3 and rest.psf.shape[0] == 2
    np.testing.assert_allclose(rest.psf.sum(axis=(-2, -1)), 1.0, rtol=1e-9)
    assert np.abs(rest.psf[0] - rest.psf[1]).sum() > 0.1  # two exposures, two random starts
    assert np.all(np.isfinite(rest.s0)) and np.nanmax(rest.dolp) <= 1.0


def test_a_re_simulated_frame_is_the_single_frame_re_simulation_through_its_psf():
    """Each frame with its own polarizer angles (0/45/90/135, then 22.5/67.5/112.5/157.5) and its own
    PSF (a delta, a Gaussian): the noise-free image of the plate through each, with equal light."""
    cfg, labels, rng = _scene(32)
    first, second = [0, 45, 90, 135], [22.5, 67.5, 112.5, 157.5]
    cfg = replace(cfg, polarizer_deg=first + second)
    H = cfg.image_size
    delta = np.zeros((H, H))
    delta[H // 2, H // 2] = 1.0
    yy, xx = np.mgrid[0:H, 0:H]
    wide = np.exp(-((yy - H // 2) ** 2 + (xx - H // 2) ** 2) / (2 * 3.0**2))
    args = (Plate(), labels, np.radians(50.0), "resimulation", float("nan"))
    acq = _multi_frame_acquisition(args, cfg, np.stack([delta, wide / wide.sum()]))
    assert acq.counts.shape == (8, H, H)
    np.testing.assert_allclose(np.degrees(acq.angles), cfg.polarizer_deg)
    # equal exposures: the same light from the object in each frame
    assert acq.counts[:4].sum() == pytest.approx(acq.counts[4:].sum(), rel=1e-12)
    for f, (h, angles) in enumerate(((delta, first), (wide / wide.sum(), second))):
        single = acquire(
            *args, replace(cfg, polarizer_deg=angles), None, Ideal(noise=True), psf=h
        ).counts
        got = acq.counts[4 * f : 4 * f + 4]
        np.testing.assert_allclose(got / got.sum(), single / single.sum(), rtol=1e-10, atol=1e-15)


def test_analyze_two_exposures_per_geometry(tmp_path):
    ds = _two_frame_dataset(size=32)
    report = analyze(
        ds, tmp_path, settings=AnalyzeSettings(iterations=8, posterior_steps=200, frames=2)
    )
    assert "2 frames per geometry (one PSF each)" in report.read_text()
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["settings"]["frames"] == 2
    assert s["posteriors"], s["regions_left_out"]
    for p in s["posteriors"].values():
        assert 0 < p["n"]["median"] < 5 and 0 <= p["kappa"]["median"] < 25  # inside the prior


@pytest.mark.parametrize("frames", [0, True, 2.0, -1])
def test_frames_must_be_a_positive_integer(frames):
    with pytest.raises(ValueError, match="frames must be an integer in"):
        AnalyzeSettings(frames=frames).validate()


@pytest.mark.parametrize("frames", [3, 2])
def test_frames_must_split_the_channels_into_polarimetric_frames(tmp_path, frames):
    ds = _two_frame_dataset(size=32)
    ds4 = replace(ds, counts=ds.counts[:, :4], polarizer_angles=ds.polarizer_angles[:4])
    with pytest.raises(ValueError, match=f"frames = {frames} must divide the dataset's 4 channels"):
        analyze(ds4, tmp_path / "x", settings=AnalyzeSettings(frames=frames))


def test_cli_frames_flag(tmp_path, capsys):
    from scatterlab.io import write_dataset

    path = tmp_path / "two.h5"
    write_dataset(path, _two_frame_dataset(size=32))
    args = ["--iterations", "3", "--posterior-steps", "200"]
    out = str(tmp_path / "a")
    assert main(["analyze", str(path), "--out", out, "--frames", "2", *args]) == 0
    assert json.loads((tmp_path / "a" / "summary.json").read_text())["settings"]["frames"] == 2
    assert main(["analyze", str(path), "--out", str(tmp_path / "b"), "--frames", "3"]) == 2
    assert "frames = 3 must divide" in capsys.readouterr().err


@pytest.mark.parametrize("blind, d_over_r0", [(True, 7.9), (False, None)])
def test_multi_frame_psfs_are_re_simulated_only_through_their_blind_estimates(blind, d_over_r0):
    cfg, labels, rng = _scene(32)
    with pytest.raises(ValueError, match="psfs: multi-frame data"):
        restoration_bias(
            [],
            labels,
            np.radians([40.0, 55.0]),
            [np.ones((2, 32, 32)), np.ones((2, 32, 32))],
            cfg,
            rng,
            np.ones((32, 32), bool),
            2,
            blind=blind,
            d_over_r0=d_over_r0,
        )


def test_psf_refine_must_be_none_or_layout():
    with pytest.raises(ValueError, match="psf_refine must be 'none' or 'layout'"):
        AnalyzeSettings(psf_refine="joint").validate()


def test_cli_psf_refine_reaches_the_data_and_the_self_calibration(tmp_path, monkeypatch):
    """--psf-refine layout: every blind restoration, the data's and the self-calibration's re-simulations
    alike (their bias must be the data's), goes through layout_psf with all its frames (the function
    itself is tested against simulated truth in tests/deconvolution/test_layout_psf.py)."""
    import scatterlab.deconvolution as deconvolution
    from scatterlab.deconvolution import LayoutResult, resample_psf
    from scatterlab.io import write_dataset

    calls = []

    def fake_layout_psf(data, angles, start, **kw):
        calls.append(kw["frames"])
        shape = (data.shape[-1] + 2 * kw["pad"],) * 2
        return LayoutResult(np.stack([resample_psf(h, shape) for h in start.psfs]), *[None] * 5)

    monkeypatch.setattr(deconvolution, "layout_psf", fake_layout_psf)
    path = tmp_path / "two.h5"
    write_dataset(path, _two_frame_dataset(size=32))
    out = tmp_path / "a"
    argv = ["analyze", str(path), "--out", str(out), "--frames", "2", "--psf-refine", "layout"]
    argv += ["--iterations", "3", "--posterior-steps", "200", "--bias-samples", "1"]
    assert main(argv) == 0
    assert json.loads((out / "summary.json").read_text())["settings"]["psf_refine"] == "layout"
    assert "PSFs refined with a few-material layout" in (out / "report.md").read_text()
    # 2 geometries: the data and one re-simulation each, refined once from the average of the 3 random
    # starts of --blind-starts
    assert calls == [2] * 4, calls
