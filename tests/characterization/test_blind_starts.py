"""Blind restorations averaged over random starts (``blind_starts``): the translations between the starts are
found, their Stokes images (not their DOLPs) are averaged, ghosts that change place with the start average
down, and a known PSF is not restarted."""

import numpy as np
import pytest
from scipy import ndimage

from scatterlab.characterization import acquire
from scatterlab.characterization.restoration import (
    RestoreSettings,
    _start_seed,
    average_starts,
    restore,
)
from scatterlab.characterization.scene_config import Plate, SceneConfig, plate_labels


def plate_object(n=96):
    """A bright metal bar and a dim, strongly polarized paint (S0 [counts], signed DOLP)."""
    s0 = np.full((n, n), 1.0e3)
    dolp = np.full((n, n), 0.85)
    s0[30:60, 20:70] = 1.2e4
    dolp[30:60, 20:70] = 0.02
    s0[70:74, 10:80] = 1.2e4  # a thin stroke
    dolp[70:74, 10:80] = 0.02
    return ndimage.gaussian_filter(s0, 1.0), ndimage.gaussian_filter(dolp, 1.0)


def test_translated_starts_are_aligned_and_their_ghosts_average_down():
    """Each 'restoration' is the object plus a ghost copy of it at a random place (a wrong PSF's echo; zero
    mean, as a flux-conserving PSF error leaves), translated by a known amount: the translations come back,
    and the average's error is the four ghosts' mean, well below one ghost (1/sqrt(4) if they did not
    overlap)."""
    s0, dolp = plate_object()
    s1 = s0 * dolp
    rng = np.random.default_rng(3)
    moves = [(0.0, 0.0), (3.0, -5.0), (-4.5, 2.0), (6.0, 6.5)]
    s0s, dolps, errors = [], [], []
    for move in moves:
        echo = tuple(rng.integers(-20, 21, 2))
        g0 = s0 + 0.1 * (np.roll(s0, echo, axis=(0, 1)) - s0.mean())
        g1 = s1 + 0.1 * (np.roll(s1, echo, axis=(0, 1)) - s1.mean())
        errors.append(g0 - s0)
        s0s.append(ndimage.shift(g0, move, order=3, mode="nearest"))
        dolps.append(ndimage.shift(g1, move, order=3, mode="nearest") / s0s[-1])
    mean_s0, _, shifts = average_starts(s0s, dolps)
    # each start's own ghost pulls the correlation peak a little: sub-pixel, not exact
    np.testing.assert_allclose(shifts, -np.array(moves), atol=0.5)
    # without ghosts the translations come back to a tenth of a pixel
    clean = [ndimage.shift(s0, move, order=3, mode="nearest") for move in moves]
    _, _, exact = average_starts(clean, [np.full_like(s0, 0.5)] * len(moves))
    np.testing.assert_allclose(exact, -np.array(moves), atol=0.1)
    inner = (slice(12, -12), slice(12, -12))  # away from what the translations bring in
    single = np.sqrt(np.mean(np.square(errors)[(slice(None),) + inner]))
    averaged = np.sqrt(np.mean((mean_s0 - s0)[inner] ** 2))
    expected = np.sqrt(np.mean(np.mean(errors, axis=0)[inner] ** 2))  # the ghosts' own mean
    assert averaged < 0.65 * single
    assert averaged == pytest.approx(expected, rel=0.1)  # the alignment adds little


def test_identical_starts_give_themselves_and_the_dolp_is_a_ratio_of_means():
    s0, dolp = plate_object(48)
    out_s0, out_dolp, shifts = average_starts([s0, s0], [dolp, dolp])
    np.testing.assert_allclose(out_s0, s0, rtol=1e-12)
    np.testing.assert_allclose(out_dolp, dolp, rtol=1e-12)
    np.testing.assert_allclose(shifts, 0.0, atol=1e-9)
    # two starts that differ only in brightness and polarization at one place: S1 averaged, not the DOLP
    s0b, dolpb = s0.copy(), dolp.copy()
    s0b[5, 5], dolpb[5, 5] = 3 * s0[5, 5], 0.1
    out_s0, out_dolp, shifts = average_starts([s0, s0b], [dolp, dolpb])
    assert np.abs(shifts).max() < 0.01  # one brighter pixel barely moves the correlation peak
    want = (s0[5, 5] * dolp[5, 5] + s0b[5, 5] * 0.1) / (s0[5, 5] + s0b[5, 5])  # 0.29
    assert out_dolp[5, 5] == pytest.approx(want, rel=2e-3)  # the mean DOLP would be 0.47
    # no light: DOLP undefined (NaN), never a division by zero
    dark = np.zeros_like(s0)
    _, d, _ = average_starts([dark, dark], [np.full_like(s0, np.nan)] * 2)
    assert np.isnan(d).all()


def test_bad_arguments_name_themselves():
    with pytest.raises(ValueError, match="s0s and dolps"):
        average_starts([np.ones((8, 8))], [])
    for bad in (0, 65, 2.0, True):
        with pytest.raises(ValueError, match="starts"):
            RestoreSettings(starts=bad)
    with pytest.raises(ValueError, match="blind_starts"):
        SceneConfig(blind_starts=0).validate()


def small_acquisition(d_over_r0):
    cfg = SceneConfig(
        image_size=32, geometry_deg=[45, 50], d_over_r0=[7.9], iterations=5, plates=[Plate()]
    ).validate()
    rng = np.random.default_rng(5)
    labels = plate_labels(cfg, rng)
    case = "no_turbulence" if d_over_r0 is None else f"D_r0_{d_over_r0:g}"
    return acquire(Plate(), labels, np.radians(50.0), case, d_over_r0, cfg, rng)


def test_a_blind_restoration_with_starts_averages_its_single_start_restorations():
    acq = small_acquisition(7.9)
    seed = 11
    several = restore(acq, RestoreSettings(iterations=5, starts=3), seed=seed)
    singles = [
        restore(acq, RestoreSettings(iterations=5), seed=_start_seed(seed, k)) for k in range(3)
    ]
    s0, dolp, _ = average_starts([r.s0 for r in singles], [r.dolp for r in singles])
    np.testing.assert_allclose(several.s0, s0, rtol=1e-10)
    np.testing.assert_allclose(several.dolp, dolp, rtol=1e-10, atol=1e-12)
    # the PSF and the likelihood history are the first start's, which is the single-start restoration
    np.testing.assert_allclose(several.psf, singles[0].psf, rtol=1e-12)
    np.testing.assert_allclose(several.loglik, singles[0].loglik, rtol=1e-12)
    assert len({_start_seed(seed, k) for k in range(10)}) == 10


def test_a_known_psf_is_not_restarted():
    acq = small_acquisition(None)
    one = restore(acq, RestoreSettings(iterations=5), seed=1)
    three = restore(acq, RestoreSettings(iterations=5, starts=3), seed=1)
    np.testing.assert_array_equal(one.s0, three.s0)
    np.testing.assert_array_equal(one.dolp, three.dolp)
