"""Phase diversity against the true PSF of a simulated exposure (the truth the simulation knows)."""

import numpy as np
import pytest

from scatterlab.deconvolution import psf_distance, resample_psf
from scatterlab.deconvolution.phase_diversity import _Likelihood, defocus_phase, phase_diversity
from scatterlab.imaging import circular_pupil, convolve, phase_screen, psf


def _exposure(N=48, d_over_r0=5.0, seed=2, waves=1.0):
    """A two-material plate (metal 10 times brighter than paint, edges in both directions) seen through one
    Kolmogorov screen by a focused camera (gain 1) and two cameras defocused by +-``waves`` (gain 1/4),
    rendered on a field twice as wide and cropped (light from outside enters, none wraps), 1e5 e- at the
    focused frame's brightest pixel, read noise 10 e-."""
    rng = np.random.default_rng(seed)
    n = N // 2
    A = circular_pupil(n, n / 2)
    W = 2 * N
    obj = np.ones((W, W))
    obj[W // 2 - N // 4 : W // 2 + N // 8, W // 2 - N // 3 : W // 2 + N // 5] = 10.0
    obj[:, W // 2 + N // 3 : W // 2 + N // 3 + 3] = 10.0
    obj[W // 2 + N // 4 :, : W // 2] = 10.0
    screen = phase_screen(n, 1.0, n / d_over_r0, rng)
    div = np.stack([np.zeros((n, n)), defocus_phase(A, waves), defocus_phase(A, -waves)])
    gains = np.array([1.0, 0.25, 0.25])
    hs = [psf(A, screen + t, pad=2) for t in div]
    m = N // 2
    clean = np.stack(
        [
            g * convolve(obj, resample_psf(h, (W, W)))[m : m + N, m : m + N]
            for g, h in zip(gains, hs)
        ]
    )
    clean *= 1e5 / clean[0].max()
    frames = rng.poisson(clean) + 10.0 * rng.standard_normal(clean.shape)
    return A, screen, div, gains, frames, hs


def test_defocus_phase_is_the_zernike_shape():
    A = circular_pupil(32, 16)
    d = defocus_phase(A, 1.0)
    inside = d[A > 0]
    # peak to valley one wave (2 pi) up to the grid's sampling of the rim; zero mean over the disc
    assert 2 * np.pi * 0.9 < inside.max() - inside.min() <= 2 * np.pi
    assert abs(inside.mean()) < 0.05
    assert np.all(d[A == 0] == 0)
    np.testing.assert_allclose(defocus_phase(A, -0.5), -0.5 * d)
    with pytest.raises(ValueError, match="waves must be finite"):
        defocus_phase(A, np.nan)


def test_likelihood_gradient_matches_finite_differences():
    A, screen, div, gains, frames, _ = _exposure(N=32, seed=5)
    like = _Likelihood(frames, div, A, gains, np.full(3, 100.0), 16)
    rng = np.random.default_rng(0)
    phase = np.where(A > 0, 0.5 * rng.standard_normal(A.shape), 0.0)
    obj = np.abs(rng.normal(1e4, 2e3, like.shape))
    _, g_phase, g_obj = like(phase, obj)
    for i, j in [(8, 8), (5, 10), (10, 4)]:
        e = np.zeros_like(phase)
        e[i, j] = 1e-5
        fd = (like(phase + e, obj)[0] - like(phase - e, obj)[0]) / 2e-5
        assert g_phase[i, j] == pytest.approx(fd, rel=1e-4, abs=1e-6 * abs(g_phase).max())
    for i, j in [(32, 32), (20, 40), (5, 5)]:
        e = np.zeros_like(obj)
        e[i, j] = 1.0
        fd = (like(phase, obj + e)[0] - like(phase, obj - e)[0]) / 2.0
        assert g_obj[i, j] == pytest.approx(fd, rel=1e-4, abs=1e-8 * abs(g_obj).max())


def test_phase_diversity_finds_the_turbulent_psf_that_one_frame_cannot():
    """From the diffraction-limited start (L1 about 1.3 from the truth) to within 0.7 of the true PSF, and
    started at the true phase the fit stays there (the likelihood identifies the PSF)."""
    A, screen, div, gains, frames, hs = _exposure()
    start = psf_distance(psf(A, None, pad=2), hs[0])[0]
    res = phase_diversity(
        frames, div, A, gains=gains, read_noise=10.0, smoothing=(6, 3, 1.5, 0), iterations=80
    )
    found = psf_distance(res.psfs[0], hs[0])[0]
    assert start > 1.2
    assert found < 0.7 and found < 0.5 * start, (found, start)
    # the defocused frames' PSFs are found too (the truth's, not only the model's own consistency)
    for h, truth in zip(res.psfs[1:], hs[1:]):
        assert psf_distance(h, truth)[0] < 0.5 * psf_distance(psf(A, div[1], pad=2), truth)[0]
    assert res.object.shape == (96, 96) and np.all(res.object >= 0)
    # each stage starts where the last ended, so the likelihood never gets worse
    nlls = [h[1] for h in res.history]
    assert all(b <= a * (1 + 1e-9) for a, b in zip(nlls, nlls[1:])), nlls
    held = phase_diversity(
        frames,
        div,
        A,
        gains=gains,
        read_noise=10.0,
        smoothing=(0,),
        iterations=80,
        phase0=np.where(A > 0, screen, 0.0),
    )
    kept = psf_distance(held.psfs[0], hs[0])[0]
    assert kept < 0.4 and kept < found, (kept, found)


def test_phase_diversity_stays_finite_on_zero_photon_frames():
    """A few photons on a dark field, with read noise or dark-subtracted: no NaN or negative object.
    (Frames without any photon carry nothing of the phase and are refused: test below.)"""
    A = circular_pupil(16, 8)
    div = np.stack([np.zeros((16, 16)), defocus_phase(A, 1.0)])
    sparse = np.zeros((2, 32, 32))
    sparse[:, 10:20, 10:20] = np.random.default_rng(0).poisson(3, (2, 10, 10))
    negative = sparse + np.random.default_rng(1).normal(0.0, 5.0, sparse.shape)  # dark-subtracted
    for frames, noise in ((sparse, 5.0), (negative, 0.0)):
        res = phase_diversity(frames, div, A, read_noise=noise, smoothing=(2, 0), iterations=5)
        for a in (res.phase, res.psfs, res.object):
            assert np.all(np.isfinite(a))
        assert np.all(res.object >= 0) and np.isfinite(res.neg_log_likelihood)
        np.testing.assert_allclose(res.psfs.sum(axis=(1, 2)), 1.0)


def test_phase_diversity_refuses_bad_input():
    A = circular_pupil(16, 8)
    frames = np.ones((2, 32, 32))
    div = np.zeros((2, 16, 16))
    div[1] = defocus_phase(A, 1.0)
    with pytest.raises(ValueError, match="F >= 2"):
        phase_diversity(frames[:1], div[:1], A)
    with pytest.raises(ValueError, match="diversity must be one phase offset"):
        phase_diversity(frames, div[:, :8], A)
    with pytest.raises(ValueError, match="gains must be > 0"):
        phase_diversity(frames, div, A, gains=[1.0, 0.0])
    with pytest.raises(ValueError, match="read_noise must be >= 0"):
        phase_diversity(frames, div, A, read_noise=-1.0)
    with pytest.raises(ValueError, match="pad must be an integer"):
        phase_diversity(frames, div, A, pad=2.5)
    with pytest.raises(ValueError, match="smoothing must be"):
        phase_diversity(frames, div, A, smoothing=(-1.0,))
    with pytest.raises(ValueError, match="iterations must be"):
        phase_diversity(frames, div, A, iterations=0)
    with pytest.raises(ValueError, match="phase0 must have the pupil's shape"):
        phase_diversity(frames, div, A, phase0=np.zeros((8, 8)))
    with pytest.raises(ValueError, match="frames"):
        phase_diversity(np.full((2, 32, 32), np.nan), div, A)
    defocus = np.stack([np.zeros((16, 16)), defocus_phase(A, 1.0)])
    with pytest.raises(ValueError, match="diversity: every frame has the same phase offset"):
        phase_diversity(frames, np.zeros((2, 16, 16)), A)
    with pytest.raises(ValueError, match=r"gains must be one number or one per frame \(2\)"):
        phase_diversity(frames, defocus, A, gains=[1.0, 0.5, 0.5])
    with pytest.raises(ValueError, match="read_noise must be one number"):
        phase_diversity(frames, defocus, A, read_noise=[1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="pupil must be a square 2-D aperture amplitude"):
        phase_diversity(frames, defocus, -A)
    with pytest.raises(ValueError, match="pad = 0 is too small"):
        phase_diversity(np.ones((2, 16, 16)), defocus, A, pad=0)
    dark = frames.copy()
    dark[1] = (
        0.0  # a diverse frame without light (as blind_deconvolve refuses data without photons)
    )
    with pytest.raises(ValueError, match=r"frames \[1\] hold no photons"):
        phase_diversity(dark, defocus, A)
    with pytest.raises(ValueError, match=r"frames \[0, 1\] hold no photons"):
        phase_diversity(np.zeros_like(frames), defocus, A)
