r"""Imaging polarimeter: channel images through linear polarizers, noise, and Stokes estimation (Eqs. 99, 197).

A channel behind an ideal linear polarizer at angle :math:`\theta_k` (from the s axis) records
:math:`I_k = \tfrac12(S_0 + S_1\cos2\theta_k + S_2\sin2\theta_k)` (Eq. 197), blurred by its PSF. The linear
Stokes parameters follow by least squares, :math:`\hat{\mathbf S} = \mathbf P^+\mathbf I` with
:math:`\mathbf P_k = \tfrac12(1, \cos2\theta_k, \sin2\theta_k)` -- exact for noise-free data and unbiased
with noise; 0/45/90/135 deg (Eq. 197) and 0/60/120 deg (LeMaster and Cain, Eq. 99) are both supported.

Capture modes: division of amplitude (one PSF, one turbulence realization, shared by all channels) or
sequential (one PSF per channel; tilt is kept, so the channels are misregistered as in a real sequential
polarimeter). Noise: a photon budget (expected photo-electrons of the brightest pixel of an unpolarized
channel), Poisson shot noise, Gaussian read noise and a dark current subtracted with a dark frame.
Images are ``(H, W)``; channel stacks ``(K, H, W)``; Stokes stacks ``(3, H, W)``.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_finite

__all__ = [
    "analyzer_matrix",
    "convolve",
    "channel_images",
    "detect",
    "stokes_from_channels",
    "dolp_aop_from_stokes",
    "ANGLES_0_45_90_135",
    "ANGLES_0_60_120",
]

ANGLES_0_45_90_135 = np.radians([0.0, 45.0, 90.0, 135.0])
ANGLES_0_60_120 = np.radians([0.0, 60.0, 120.0])


def analyzer_matrix(angles) -> np.ndarray:
    """Rows ``0.5 (1, cos 2a, sin 2a)`` for polarizer angles ``a`` [rad], shape ``(K, 3)``."""
    a = as_finite(angles, "angles").ravel()
    P = 0.5 * np.stack([np.ones_like(a), np.cos(2 * a), np.sin(2 * a)], axis=1)
    if np.linalg.matrix_rank(P) < 3:
        raise ValueError(
            "angles must include at least three distinct polarizer orientations (mod 180 deg)"
        )
    return P


def convolve(images, psfs) -> np.ndarray:
    """Circular convolution of images ``(..., H, W)`` with centred, unit-sum PSFs of the same size (FFT)."""
    images = np.asarray(images, float)
    psfs = np.asarray(psfs, float)
    if psfs.shape[-2:] != images.shape[-2:]:
        raise ValueError(
            f"psf shape {psfs.shape[-2:]} must equal the image shape {images.shape[-2:]}"
        )
    H = np.fft.rfft2(np.fft.ifftshift(psfs, axes=(-2, -1)))
    return np.fft.irfft2(np.fft.rfft2(images) * H, s=images.shape[-2:])


def channel_images(stokes, angles, psfs=None) -> np.ndarray:
    """Noise-free channel images ``(K, H, W)`` from linear Stokes images ``(3, H, W)`` (Eq. 197).

    ``psfs``: None (no blur), one ``(H, W)`` PSF shared by all channels (division of amplitude), or ``(K, H, W)``
    (sequential capture, one realization per channel).
    """
    S = as_finite(stokes, "stokes")
    if S.ndim != 3 or S.shape[0] != 3:
        raise ValueError(f"stokes must have shape (3, H, W), got {S.shape}")
    P = analyzer_matrix(angles)
    I = np.einsum("ks,shw->khw", P, S)
    if psfs is None:
        return I
    psfs = as_finite(psfs, "psfs")
    if psfs.ndim == 3 and psfs.shape[0] != P.shape[0]:
        raise ValueError("psfs must be one PSF (H, W) or one per channel (K, H, W)")
    return convolve(I, psfs)


def detect(
    channels,
    rng=None,
    *,
    photons: float,
    read_noise: float = 0.0,
    dark_current: float = 0.0,
    scale: float | None = None,
) -> np.ndarray:
    """Noisy, dark-subtracted detector images in photo-electrons.

    Parameters
    ----------
    channels : array ``(K, H, W)`` of non-negative intensities.
    photons : float
        Expected photo-electrons for intensity ``scale`` (default: the largest channel intensity).
    read_noise : float
        Gaussian read noise [e-] per read (the image and its dark frame are each read once).
    dark_current : float
        Mean dark electrons per pixel; a dark frame with the same statistics is subtracted.

    Returns
    -------
    array ``(K, H, W)`` [e-]: Poisson(signal + dark) + read - (Poisson(dark) + read). Zero-photon pixels stay
    finite (their value is pure noise).
    """
    I = as_finite(channels, "channels")
    if np.any(I < 0):
        raise ValueError("channels must be non-negative intensities")
    for name, v, lo in (
        ("photons", photons, "> 0"),
        ("read_noise", read_noise, ">= 0"),
        ("dark_current", dark_current, ">= 0"),
    ):
        if not (np.isfinite(v) and (v > 0 if lo == "> 0" else v >= 0)):
            raise ValueError(f"{name} must be finite and {lo} [e-], got {v!r}")
    if scale is not None and not (np.isfinite(scale) and scale > 0):
        raise ValueError(
            f"scale (the intensity that gives `photons`) must be finite and > 0, got {scale!r}"
        )
    rng = np.random.default_rng(rng)
    scale = float(I.max()) if scale is None else float(scale)
    expected = photons * I / scale if scale > 0 else np.zeros_like(I)
    frame = rng.poisson(expected + dark_current).astype(float) + read_noise * rng.standard_normal(
        I.shape
    )
    dark = rng.poisson(np.full(I.shape, dark_current)).astype(
        float
    ) + read_noise * rng.standard_normal(I.shape)
    return frame - dark


def stokes_from_channels(channels, angles) -> np.ndarray:
    """Least-squares linear Stokes images ``(3, H, W)`` from channel images ``(K, H, W)`` (Eqs. 99, 197)."""
    I = as_finite(channels, "channels")
    P = analyzer_matrix(angles)
    if I.shape[0] != P.shape[0]:
        raise ValueError(f"channels has {I.shape[0]} images but angles has {P.shape[0]}")
    return np.einsum("sk,khw->shw", np.linalg.pinv(P), I)


def dolp_aop_from_stokes(S, *, min_intensity: float = 0.0):
    """DOLP and AOP images from Stokes ``(3, H, W)``; pixels with ``S0 <= min_intensity`` are masked.

    Returns
    -------
    dolp, aop : masked arrays ``(H, W)`` (AOP in (-pi/2, pi/2] [rad]); DOLP is not clipped, so noise can
    push it above 1 -- an honest estimate, not a bounded one.
    """
    S = as_finite(S, "S")
    s0, s1, s2 = S
    bad = s0 <= min_intensity
    with np.errstate(divide="ignore", invalid="ignore"):
        dolp = np.hypot(s1, s2) / np.where(bad, 1.0, s0)
    aop = 0.5 * np.arctan2(s2, s1)
    return np.ma.masked_array(dolp, bad), np.ma.masked_array(aop, bad | ((s1 == 0) & (s2 == 0)))
