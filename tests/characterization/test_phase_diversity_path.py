"""The main job's phase-diversity path: defocused cameras in the acquisition, their PSF in the restoration."""

import time

import numpy as np
import pytest

from scatterlab.characterization import SceneConfig, acquire, load_scene
from scatterlab.characterization.acquisition import Ideal
from scatterlab.characterization.scene_config import Plate, plate_labels


def scene(**kw):
    base = dict(
        image_size=32,
        geometry_deg=[30, 50],
        d_over_r0=[5.0],
        iterations=5,
        plates=[Plate()],
        estimate=["classes"],
        phase_diversity_waves=1.0,
    )
    base.update(kw)
    return SceneConfig(**base).validate()


def _acq(cfg, seed=3, ideal=Ideal(), d_over_r0=5.0):
    rng = np.random.default_rng(seed)
    labels = plate_labels(cfg, rng)
    case = "no_turbulence" if d_over_r0 is None else f"D_r0_{d_over_r0}"
    return acquire(Plate(), labels, np.radians(50.0), case, d_over_r0, cfg, rng, ideal)


def test_the_defocused_cameras_see_the_same_instant_with_their_share_of_the_light():
    """Independent truths: a vanishing defocus makes each camera an unpolarized copy of the polarimeter's
    channel sum (same screen, same instant), scaled by the beam splitter's shares; no turbulence or no
    waves means no cameras; the polarimeter's brightest pixel keeps (1 - share) of the photons."""
    share = 0.25
    cfg = scene(phase_diversity_waves=1e-9, phase_diversity_share=share)
    acq = _acq(cfg, ideal=Ideal(noise=True))
    assert acq.diversity_counts.shape == (2, 32, 32)
    assert acq.diversity_phases.shape == (2, 16, 16)
    total = acq.counts.sum(axis=0)
    for cam in acq.diversity_counts:
        np.testing.assert_allclose(cam, 0.5 * share / (1 - share) * total, rtol=1e-6, atol=1e-6)
    assert acq.counts.max() == pytest.approx((1 - share) * cfg.photons, rel=1e-9)

    # a real defocus spreads the light: the cameras are not copies, and the two sides of focus differ
    acq = _acq(scene(), ideal=Ideal(noise=True))
    a, b = acq.diversity_counts
    assert np.abs(a - b).sum() > 0.05 * a.sum()
    assert np.max(a) < 0.5 * 0.3333 / (1 - 0.3333) * acq.counts.sum(axis=0).max()

    assert _acq(scene(), d_over_r0=None).diversity_counts is None
    assert _acq(scene(phase_diversity_waves=0.0)).diversity_counts is None
    assert _acq(scene(), ideal=Ideal(optics=True)).diversity_counts is None


def test_the_defocus_can_grow_with_the_turbulence():
    """One defocus per D/r0: +-2 waves at 12.9 spread the cameras' light more than +-1 at 5 (the Zernike
    defocus's peak-to-valley sets the blur), and 0 turns the cameras off for that strength."""
    from scatterlab.characterization.scene_config import diversity_waves

    cfg = scene(d_over_r0=[5.0, 12.9, 3.0], phase_diversity_waves=[1.0, 2.0, 0.0])
    assert diversity_waves(cfg, 12.9) == 2.0 and diversity_waves(cfg, 5.0) == 1.0
    assert diversity_waves(cfg, None) == 0.0
    acq = _acq(cfg, d_over_r0=12.9)
    inside = acq.pupil > 0
    spread = acq.diversity_phases[0][inside]
    assert spread.max() - spread.min() == pytest.approx(2 * 2 * np.pi, rel=0.1)
    assert _acq(cfg, d_over_r0=3.0).diversity_counts is None


def test_noisy_cameras_carry_shot_and_read_noise():
    """The same seed draws the same screen: the noisy cameras scatter about the noise-free ones with the
    variance of Poisson counts plus two reads (image and dark frame)."""
    cfg = scene()
    noisy, clean = _acq(cfg, seed=4), _acq(cfg, seed=4, ideal=Ideal(noise=True))
    z = (noisy.diversity_counts - clean.diversity_counts) / np.sqrt(
        clean.diversity_counts + 2 * 10.0**2
    )
    assert np.all(np.isfinite(noisy.diversity_counts))
    assert abs(z.mean()) < 0.1 and 0.9 < z.std() < 1.1
    assert noisy.read_noise == 10.0


def test_a_turbulent_image_with_cameras_is_restored_with_the_psf_phase_diversity_finds(monkeypatch):
    """The restoration hands the frames to phase_diversity with the light's shares as gains and the read
    noise of dark-subtracted sums, and restores with the PSF it returns held fixed (the fit itself is tested
    against simulated truth in tests/deconvolution/test_phase_diversity.py)."""
    import scatterlab.deconvolution as deconvolution
    from scatterlab.characterization import restoration
    from scatterlab.deconvolution import PhaseDiversityResult, resample_psf

    acq = _acq(scene())
    seen = {}

    def fake(frames, diversity, pupil, **kw):
        seen.update(kw, frames=frames, diversity=diversity)
        psfs = np.stack([acq.psf_true] * len(frames))
        return PhaseDiversityResult(np.zeros_like(pupil), psfs, None, 0.0, [])

    monkeypatch.setattr(deconvolution, "phase_diversity", fake)
    monkeypatch.setattr(restoration, "PHASE_DIVERSITY_FINAL_ITERATIONS", 7)
    rest = restoration.restore(acq, restoration.RestoreSettings(iterations=5), seed=1)
    np.testing.assert_allclose(seen["frames"][0], acq.counts.sum(axis=0))
    np.testing.assert_allclose(seen["frames"][1:], acq.diversity_counts)
    assert np.all(seen["diversity"][0] == 0)
    np.testing.assert_allclose(seen["gains"], [1 - 0.3333, 0.3333 / 2, 0.3333 / 2])
    np.testing.assert_allclose(seen["read_noise"], 10 * np.sqrt([8, 2, 2]))
    assert rest.kind == "corrected"
    np.testing.assert_allclose(rest.psf, resample_psf(acq.psf_true, rest.psf.shape), rtol=1e-9)
    assert rest.loglik.size == 7 + 1
    assert np.all(np.diff(rest.loglik) >= -1e-10 * abs(rest.loglik[-1]))  # Richardson-Lucy


def test_phase_diversity_in_the_restoration_finds_the_turbulent_psf():
    """End to end on a small plate at D/r0 5: the PSF found is much closer to the true one than the
    diffraction-limited start."""
    from scatterlab.characterization.restoration import phase_diversity_psf
    from scatterlab.deconvolution import psf_distance, resample_psf
    from scatterlab.imaging import psf

    acq = _acq(scene(image_size=64), seed=5)
    t0 = time.perf_counter()
    h = phase_diversity_psf(acq)
    print(f"phase diversity at 64 x 64: {time.perf_counter() - t0:.1f} s")
    start = resample_psf(psf(acq.pupil, None, pad=2), acq.psf_true.shape)
    # L1 at the best shift: the fit does not determine the tilt (the object moves instead)
    found, before = psf_distance(h, acq.psf_true)[0], psf_distance(start, acq.psf_true)[0]
    assert found < 0.5 * before, (found, before)


def test_a_clear_image_has_no_phase_diversity_to_use():
    from scatterlab.characterization.restoration import phase_diversity_psf

    with pytest.raises(ValueError, match="diversity_counts"):
        phase_diversity_psf(_acq(scene(), d_over_r0=None))


@pytest.mark.parametrize(
    "text, key",
    [
        ("phase_diversity_waves = -1.0", "phase_diversity_waves"),
        ("phase_diversity_waves = 11.0", "phase_diversity_waves"),
        ('phase_diversity_waves = "1"', "phase_diversity_waves"),
        ("phase_diversity_waves = [1.0]", "one entry per d_over_r0"),
        ("phase_diversity_waves = [1.0, -2.0]", "phase_diversity_waves"),
        ("phase_diversity_share = 0.0", "phase_diversity_share"),
        ("phase_diversity_share = 0.95", "phase_diversity_share"),
    ],
)
def test_scene_keys_of_the_cameras_are_checked(tmp_path, text, key):
    p = tmp_path / "s.toml"
    p.write_text(text + "\n")
    with pytest.raises(ValueError, match=key):
        load_scene(p)


def test_the_report_says_how_the_turbulent_psfs_were_found():
    from scatterlab.characterization.report_text import _header

    text = "\n".join(_header(scene(phase_diversity_share=0.25), 1.0, Ideal()))
    assert "phase diversity" in text and "+-1 waves" in text and "25% of the light" in text
    assert "EM iterations" not in text
    two = scene(d_over_r0=[7.9, 12.9], phase_diversity_waves=[1.0, 2.0])
    assert "+-1 at D/r0 7.9, +-2 at D/r0 12.9 waves" in "\n".join(_header(two, 1.0, Ideal()))
    text = "\n".join(_header(scene(phase_diversity_waves=0.0), 1.0, Ideal()))
    assert "phase diversity" not in text and "5 EM iterations (pupil PSFs)" in text
