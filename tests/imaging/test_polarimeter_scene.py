"""Polarimeter channels, noise and Stokes estimation; pBRDF scenes."""

import numpy as np
import pytest

from scatterlab.imaging import (
    ANGLES_0_45_90_135,
    ANGLES_0_60_120,
    channel_images,
    circular_pupil,
    convolve,
    detect,
    dolp_aop_from_stokes,
    painted_plate,
    psf,
    render_stokes,
    stokes_from_channels,
)
from scatterlab.pbrdf import Model


def random_stokes(rng, shape=(16, 16)):
    s0 = rng.uniform(0.5, 2.0, shape)
    p = rng.uniform(0, 1, shape)
    a = rng.uniform(-np.pi / 2, np.pi / 2, shape)
    return np.stack([s0, s0 * p * np.cos(2 * a), s0 * p * np.sin(2 * a)], axis=-1)  # (H, W, 3)


@pytest.mark.parametrize("angles", [ANGLES_0_45_90_135, ANGLES_0_60_120])
def test_stokes_estimation_exact_without_noise(angles, rng):
    S = random_stokes(rng)
    np.testing.assert_allclose(
        stokes_from_channels(channel_images(S, angles), angles), S, atol=1e-13
    )
    # Malus: a 0-deg polarizer sees (S0 + S1)/2
    np.testing.assert_allclose(channel_images(S, angles)[0], (S[..., 0] + S[..., 1]) / 2)


def test_poisson_statistics_and_unbiased_stokes(rng):
    I = np.full((4, 64, 64), 0.5)
    counts = detect(I, rng, photons=400.0)
    assert counts.mean() == pytest.approx(400.0, rel=0.01)  # 16384 pixels: 0.1 % standard error
    assert counts.var() == pytest.approx(400.0, rel=0.05)  # Poisson: variance = mean
    S = random_stokes(rng, (8, 8))
    chans = channel_images(S, ANGLES_0_45_90_135)
    est = np.mean(
        [
            stokes_from_channels(
                detect(chans, rng, photons=1e3, scale=chans.max(), read_noise=3, dark_current=5),
                ANGLES_0_45_90_135,
            )
            for _ in range(400)
        ],
        axis=0,
    )
    scale = 1e3 / chans.max()
    np.testing.assert_allclose(est / scale, S, atol=0.02)  # unbiased within ~4 standard errors


def test_zero_photon_pixels_and_dark_subtraction(rng):
    zero = np.zeros((4, 32, 32))
    counts = detect(zero, rng, photons=100.0, scale=1.0, read_noise=2.0, dark_current=3.0)
    assert np.all(np.isfinite(counts)) and abs(counts.mean()) < 0.2
    dolp, aop = dolp_aop_from_stokes(stokes_from_channels(np.abs(counts) * 0, ANGLES_0_45_90_135))
    assert dolp.mask.all()  # no light: masked, never NaN leaking out


def test_division_of_amplitude_keeps_uniform_polarization_sequential_misregisters(rng):
    S = np.zeros((64, 64, 3))
    S[16:48, 16:48, 0] = 1.0
    S[16:48, 16:48, 1] = 0.5
    h = psf(circular_pupil(32, 8), pad=2)
    doa = stokes_from_channels(channel_images(S, ANGLES_0_45_90_135, h), ANGLES_0_45_90_135)
    d, _ = dolp_aop_from_stokes(doa, min_intensity=1e-6)
    lit = S[..., 0] > 0
    assert np.allclose(d[lit][np.abs(doa[..., 0][lit] - 1) < 1e-3], 0.5, atol=1e-9)  # interior
    shifted = np.stack([np.roll(h, k, axis=1) for k in range(4)])  # tilt differs per channel
    seq = stokes_from_channels(channel_images(S, ANGLES_0_45_90_135, shifted), ANGLES_0_45_90_135)
    ds, _ = dolp_aop_from_stokes(seq, min_intensity=1e-3)
    assert np.max(np.abs(ds - 0.5)[16:48, 16:48]) > 0.1  # edges misregistered


def test_scene_rendering_matches_the_pbrdf_and_leaves_out_aop():
    scene = painted_plate(64, rng=1)
    S = render_stokes(scene)
    assert S.shape == scene.labels.shape + (3,)
    assert np.all(S[..., 2] == 0)  # specular plane: S2 = 0, AOP fixed
    dolp, _ = dolp_aop_from_stokes(S)
    for k, (eta, sigma) in enumerate(zip(scene.materials, scene.roughness)):
        expected = Model(sigma).dolp(eta, scene.theta_i, scene.theta_r)
        np.testing.assert_allclose(dolp[scene.labels == k], expected, rtol=1e-12)
    assert dolp[scene.labels == 0].mean() > 0.3 > dolp[scene.labels == 1].mean()  # paint vs metal


def test_bad_input(rng):
    with pytest.raises(ValueError, match="angles"):
        stokes_from_channels(np.ones((2, 4, 4)), np.radians([0, 90]))
    with pytest.raises(ValueError, match="stokes"):
        channel_images(np.full((4, 4, 3), np.nan), ANGLES_0_45_90_135)
    with pytest.raises(ValueError, match="psf"):
        convolve(np.ones((8, 8)), np.ones((4, 4)))
    with pytest.raises(ValueError, match="non-negative"):
        detect(-np.ones((1, 4, 4)), rng, photons=10)
    with pytest.raises(ValueError, match="labels"):
        from scatterlab.imaging import Scene

        Scene(np.full((4, 4), 3), [1.5], [0.3], 0.5, 0.5)
    for bad in (-1, 2.5, True):  # -1 drew no scratch, silently
        with pytest.raises(ValueError, match="scratches must be an integer >= 0"):
            painted_plate(32, scratches=bad)
    assert painted_plate(32, scratches=0).labels.max() <= 1


def test_axis_first_stokes_images_are_refused_with_the_expected_shape(rng):
    """The old (3, H, W) layout raises a ValueError naming the argument and the (H, W, 3) layout."""
    S = random_stokes(rng, (8, 10))
    with pytest.raises(ValueError, match=r"stokes must be a Stokes image of shape \(H, W, 3\)"):
        channel_images(np.moveaxis(S, -1, 0), ANGLES_0_45_90_135)
    with pytest.raises(ValueError, match=r"S must .*\(H, W, 3\).*moveaxis"):
        dolp_aop_from_stokes(np.moveaxis(S, -1, 0))
    # (H, W, 4) is read as its linear block: S3 is invisible to linear polarizers
    S4 = np.concatenate([S, 0.1 * S[..., :1]], axis=-1)
    np.testing.assert_array_equal(
        channel_images(S4, ANGLES_0_45_90_135), channel_images(S, ANGLES_0_45_90_135)
    )


def test_dolp_images_follow_the_package_rule(rng):
    """dolp_aop_from_stokes is scatterlab.polarization.dolp / aop with NaN pixels masked."""
    from scatterlab.polarization import aop, dolp

    S = random_stokes(rng, (6, 6))
    S[0, 0] = 0.0
    d, a = dolp_aop_from_stokes(S, min_intensity=0.6)
    np.testing.assert_array_equal(d.filled(np.nan), dolp(S, min_intensity=0.6))
    np.testing.assert_array_equal(a.filled(np.nan), aop(S, min_intensity=0.6))
    assert d.mask[0, 0] and np.array_equal(d.mask, ~(S[..., 0] > 0.6))
