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


def test_polarizer_angles_in_degrees_are_refused():
    """0, 45, 90, 135 (degrees) were read as radians: S = (1, .2, .4) came back as (1.03, -.10, .40)."""
    from scatterlab.imaging import analyzer_matrix

    S = np.ones((4, 4, 3)) * [1.0, 0.2, 0.4]
    degrees = [0, 45, 90, 135]
    for call in (
        lambda: channel_images(S, degrees),
        lambda: stokes_from_channels(np.ones((4, 4, 4)), degrees),
        lambda: analyzer_matrix(degrees),
    ):
        with pytest.raises(
            ValueError, match=r"angles must be .* radians in \[-2 pi, 2 pi\].*degrees"
        ):
            call()
    # any angle within a full turn is a polarizer: 0/45/90/135 deg plus a half turn is the same analyzer.
    # Malus (Eq. 197) by hand: 0.5 (1 + 0.2 cos 2a + 0.4 sin 2a) = 0.6, 0.7, 0.4, 0.3
    angles = ANGLES_0_45_90_135 + np.pi
    ch = channel_images(S, angles)
    np.testing.assert_allclose(ch[:, 0, 0], [0.6, 0.7, 0.4, 0.3], rtol=1e-14)
    np.testing.assert_allclose(stokes_from_channels(ch, angles - 2 * np.pi), S, rtol=1e-14)


def test_unphysical_stokes_and_psfs_are_refused(rng):
    """S1 = 2 S0 gave a channel of -0.5, and a negative PSF a silently black image."""
    dark, one = np.zeros((4, 4)), np.ones((4, 4))
    A = ANGLES_0_45_90_135
    with pytest.raises(ValueError, match=r"stokes must be physical, S0 >= sqrt\(S1\^2 \+ S2\^2\)"):
        channel_images(np.dstack([one, 2 * one, dark]), A)
    with pytest.raises(ValueError, match="stokes must be physical"):
        channel_images(np.dstack([-one, dark, dark]), A)
    S = np.dstack([one, dark, dark])
    with pytest.raises(ValueError, match="psfs must be non-negative"):
        channel_images(S, A, psfs=-one / 16)
    with pytest.raises(ValueError, match="psfs must have unit sum"):
        channel_images(S, A, psfs=one)
    with pytest.raises(
        ValueError, match=r"psfs must be one PSF \(H, W\) or one per channel \(4, H, W\)"
    ):
        channel_images(S, A, psfs=np.ones((3, 4, 4)) / 16)
    # fully polarized light (DOLP = 1 up to rounding) is physical: behind a polarizer at its own angle it
    # passes entirely, behind the crossed one not at all (Malus)
    a = rng.uniform(-np.pi / 2, np.pi / 2, (8, 8))
    full = np.stack([np.ones((8, 8)), np.cos(2 * a), np.sin(2 * a)], axis=-1)
    ch = channel_images(full, np.stack([a[0, 0], a[0, 0] + np.pi / 2, 0.3]))
    assert ch[0, 0, 0] == pytest.approx(1.0, abs=1e-15) and ch[1, 0, 0] == pytest.approx(
        0, abs=1e-15
    )
    # a unit-sum, non-negative PSF conserves the light of every channel
    h = rng.uniform(0, 1, (8, 8))
    h /= h.sum()
    np.testing.assert_allclose(
        channel_images(full, A, h).sum(axis=(1, 2)),
        channel_images(full, A).sum(axis=(1, 2)),
        rtol=1e-12,
    )
