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
Layouts: images are ``(H, W)``; channel stacks ``(K, H, W)`` (one image per polarizer, as a camera
delivers them); Stokes images ``(H, W, 3)`` -- the Stokes axis last, as everywhere in the package
(:mod:`scatterlab.polarization`), ``(H, W, 4)`` accepted where Stokes images are read (S3 is invisible to
linear polarizers). The axis-first ``(3, H, W)`` layout of earlier versions raises a ValueError naming the
argument (convert with ``numpy.moveaxis(S, 0, -1)``).

DOLP and AOP images: :func:`dolp_aop_from_stokes` wraps :func:`scatterlab.polarization.dolp_aop` (NaN where
there is no light) and masks those pixels.
"""

from __future__ import annotations

import math

import numpy as np

from scatterlab._checks import as_finite, as_rng, as_scalar, as_turn
from scatterlab.polarization import dolp_aop

__all__ = [
    "analyzer_matrix",
    "convolve",
    "channel_images",
    "detect",
    "stokes_from_channels",
    "dolp_aop_from_stokes",
    "stokes_image",
    "ANGLES_0_45_90_135",
    "ANGLES_0_60_120",
]

ANGLES_0_45_90_135 = np.radians([0.0, 45.0, 90.0, 135.0])
ANGLES_0_60_120 = np.radians([0.0, 60.0, 120.0])
# [e-] the largest mean signal and mean dark count of a pixel: numpy's Poisson sampler refuses means
# above 9.2e18 (its int64 range), and the two means add
_MAX_MEAN = 1e18
# relative round-off allowed in the checks of Stokes images and PSFs (S0 >= |(S1, S2)|, h >= 0, sum h = 1)
_ROUNDING = 1e-9


def analyzer_matrix(angles) -> np.ndarray:
    """Rows ``0.5 (1, cos 2a, sin 2a)`` for polarizer angles ``a`` [rad], shape ``(K, 3)``.

    Parameters
    ----------
    angles : array_like, shape (K,)
        Polarizer angles [rad] in ``[-2 pi, 2 pi]`` (flattened; larger values are taken for degrees and
        refused); at least three distinct orientations mod pi.

    Returns
    -------
    ndarray, shape (K, 3)
        Analyzer rows ``0.5 (1, cos 2a, sin 2a)``.

    Raises
    ------
    ValueError
        Angles outside ``[-2 pi, 2 pi]`` (degrees?) or fewer than three distinct orientations.
    """
    a = as_turn(angles, "angles", "polarizer angles").ravel()
    P = 0.5 * np.stack([np.ones_like(a), np.cos(2 * a), np.sin(2 * a)], axis=1)
    if np.linalg.matrix_rank(P) < 3:
        raise ValueError(
            "angles must include at least three distinct polarizer orientations (mod 180 deg)"
        )
    return P


def convolve(images, psfs) -> np.ndarray:
    """Circular convolution of images ``(..., H, W)`` with centred, unit-sum PSFs of the same size
    (FFT).

    Parameters
    ----------
    images : array_like, shape (..., H, W)
        Images.
    psfs : array_like, shape (..., H, W)
        Centred, unit-sum PSFs, broadcast against ``images``.

    Returns
    -------
    ndarray, shape (..., H, W)
        The convolved images.
    """
    images = np.asarray(images, float)
    psfs = np.asarray(psfs, float)
    if psfs.shape[-2:] != images.shape[-2:]:
        raise ValueError(
            f"psf shape {psfs.shape[-2:]} must equal the image shape {images.shape[-2:]}"
        )
    H = np.fft.rfft2(np.fft.ifftshift(psfs, axes=(-2, -1)))
    return np.fft.irfft2(np.fft.rfft2(images) * H, s=images.shape[-2:])


def stokes_image(S, name: str = "stokes") -> np.ndarray:
    """Check and return a linear Stokes image ``(H, W, 3)`` (the S3 plane of ``(H, W, 4)`` is dropped).

    Parameters
    ----------
    S : array_like, shape ``(H, W, 3)`` or ``(H, W, 4)``, Stokes axis last, finite.
    name : str
        Argument name for the error message.

    Returns
    -------
    ndarray ``(H, W, 3)`` float.

    Raises
    ------
    ValueError
        Any other shape, in particular the old axis-first ``(3, H, W)``, or non-finite values.
    """
    S = as_finite(S, name)
    if S.ndim == 3 and S.shape[-1] in (3, 4):
        return S[..., :3]
    hint = ""
    if S.ndim == 3 and S.shape[0] in (3, 4):
        hint = " (the axis-first (3, H, W) layout is gone: use numpy.moveaxis(S, 0, -1))"
    raise ValueError(
        f"{name} must be a Stokes image of shape (H, W, 3) with the Stokes axis last, "
        f"got {S.shape}{hint}"
    )


def channel_images(stokes, angles, psfs=None) -> np.ndarray:
    """Noise-free channel images from linear Stokes images (Eq. 197).

    Parameters
    ----------
    stokes : array_like, shape ``(H, W, 3)`` (or ``(H, W, 4)``)
        Physical linear Stokes images, Stokes axis last [any intensity unit]: ``S0 >= sqrt(S1^2 + S2^2)``
        at every pixel (up to a round-off of 1e-9 of the image's largest ``|S|``).
    angles : array_like, shape ``(K,)``
        Polarizer angles [rad] from the s axis, in ``[-2 pi, 2 pi]`` (degrees are refused).
    psfs : None or array_like, shape ``(H, W)`` or ``(K, H, W)``
        None (no blur), one PSF shared by all channels (division of amplitude), or one per channel
        (sequential capture, one realization per channel). Each PSF is centred, non-negative and has
        unit sum (to 1e-9: the sum scales the channels' light).

    Returns
    -------
    ndarray, shape ``(K, H, W)``
        ``0.5 (S0 + S1 cos 2a_k + S2 sin 2a_k)`` blurred by the PSF(s), same unit as ``stokes``; >= 0.

    Raises
    ------
    ValueError
        Degrees for ``angles``, an unphysical ``stokes`` (``S0 < sqrt(S1^2 + S2^2)`` or ``S0 < 0``), a
        negative PSF or one whose sum is not 1, or shapes that do not match.
    """
    S = stokes_image(stokes, "stokes")
    P = analyzer_matrix(angles)
    tol = _ROUNDING * float(np.abs(S).max(initial=0.0))
    excess = np.hypot(S[..., 1], S[..., 2]) - S[..., 0]
    if np.any(excess > tol):
        h, w = np.unravel_index(int(np.argmax(excess)), excess.shape)
        raise ValueError(
            "stokes must be physical, S0 >= sqrt(S1^2 + S2^2) (degree of polarization <= 1, S0 >= 0), "
            f"at every pixel; got S = {tuple(float(v) for v in S[h, w])} at pixel ({h}, {w})"
        )
    I = np.einsum("ks,hws->khw", P, S)
    if psfs is None:
        return I
    psfs = as_finite(psfs, "psfs")
    K = P.shape[0]
    if psfs.ndim not in (2, 3) or (psfs.ndim == 3 and psfs.shape[0] != K):
        raise ValueError(
            f"psfs must be one PSF (H, W) or one per channel ({K}, H, W), got shape {psfs.shape}"
        )
    peak = psfs.max(axis=(-2, -1), keepdims=True)
    if np.any(psfs < -_ROUNDING * np.abs(peak)):
        raise ValueError(
            f"psfs must be non-negative (a PSF is an intensity), got a minimum of {psfs.min():g}"
        )
    total = psfs.sum(axis=(-2, -1))
    if np.any(np.abs(total - 1) > _ROUNDING):
        raise ValueError(
            "psfs must have unit sum (a PSF spreads the light, it does not add or remove it; divide "
            f"by psfs.sum(axis=(-2, -1))), got sums {np.ravel(total)[:4]}"
        )
    # the FFT's round-off leaves -1e-16 where the image is dark: intensities are >= 0
    return np.maximum(convolve(I, psfs), 0.0)


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

    The mean of pixel ``(k, h, w)`` is ``photons * channels[k, h, w] / scale`` [e-], formed with
    ``channels`` and ``scale`` scaled by powers of two (exactly) so that no intermediate product overflows:
    intensities of any magnitude, 1e-300 or 1e300, give the same counts as intensities near 1.

    Parameters
    ----------
    channels : array_like, shape ``(K, H, W)``
        Non-negative, finite intensities [any unit].
    rng : None, int, SeedSequence, BitGenerator or Generator
        Seeds the noise.
    photons : float
        Expected photo-electrons for intensity ``scale`` (default: the largest channel intensity), in
        ``(0, 1e18]`` [e-]: the Poisson sampler draws means up to 9.2e18 e- only (its int64 range).
    read_noise : float
        Gaussian read noise [e-] per read (the image and its dark frame are each read once), in
        ``[0, 1e18]`` (a few e- in a real camera; the bound keeps the difference of two reads finite).
    dark_current : float
        Mean dark electrons per pixel, in ``[0, 1e18]`` [e-]; a dark frame with the same statistics is
        subtracted.
    scale : float, optional
        The intensity that gives ``photons`` (finite, > 0; same unit as ``channels``); the brightest pixel's
        mean, ``photons * max(channels) / scale``, must not exceed 1e18 e- either.

    Returns
    -------
    ndarray, shape ``(K, H, W)``
        Poisson(signal + dark) + read - (Poisson(dark) + read) [e-]. Zero-photon pixels stay finite (their
        value is pure noise).

    Raises
    ------
    ValueError
        ``channels`` negative or not finite; ``photons``, ``read_noise``, ``dark_current`` or ``scale`` not a
        single finite number in its range (``None`` or a string included); or a brightest pixel's mean
        above 1e18 e- (``scale`` too small for ``photons``).
    """
    I = as_finite(channels, "channels")
    if np.any(I < 0):
        raise ValueError("channels must be non-negative intensities")
    sampler = "the Poisson sampler draws means up to 9.2e18 e- only"
    limit = f" [e-] ({sampler})"
    photons = as_scalar(photons, "photons", 0.0, _MAX_MEAN, open_lo=True, unit=limit)
    read_noise = as_scalar(read_noise, "read_noise", 0.0, _MAX_MEAN, unit=" [e-]")
    dark_current = as_scalar(dark_current, "dark_current", 0.0, _MAX_MEAN, unit=limit)
    if scale is not None:
        scale = as_scalar(scale, "scale (the intensity that gives `photons`)", 0.0, open_lo=True)
    peak = float(I.max(initial=0.0))
    if peak == 0:
        expected = np.zeros_like(I)  # no light: the frame is dark current and read noise only
    else:
        scale = peak if scale is None else scale
        # photons * I / scale with I and scale first scaled by powers of two into [0.5, 1) (exact): the
        # product cannot overflow (photons * I did for I = 1e300), and the result, scaled back exactly, is
        # the plain expression's to the last bit wherever that one did not overflow or underflow
        e_peak, e_scale = math.frexp(peak)[1], math.frexp(scale)[1]
        with np.errstate(over="ignore", under="ignore"):
            ratio = photons * np.ldexp(I, -e_peak) / math.ldexp(scale, -e_scale)  # <= 2 photons
            expected = np.ldexp(ratio, e_peak - e_scale)
        brightest = float(expected.max())
        # rounding may put photons * peak / peak an ulp above photons = 1e18: allowed (the sampler's limit
        # is 9.2e18)
        if not brightest <= _MAX_MEAN * (1 + 1e-12):
            shown = f"{brightest:.3g} e-" if math.isfinite(brightest) else "above 1.8e308 e-"
            raise ValueError(
                f"scale ({scale!r}) is too small for photons ({photons!r}): the brightest pixel's mean, "
                f"photons * max(channels) / scale = {shown}, must be <= {_MAX_MEAN:g} e- ({sampler})"
            )
    rng = as_rng(rng)
    frame = rng.poisson(expected + dark_current).astype(float) + read_noise * rng.standard_normal(
        I.shape
    )
    dark = rng.poisson(np.full(I.shape, dark_current)).astype(
        float
    ) + read_noise * rng.standard_normal(I.shape)
    return frame - dark


def stokes_from_channels(channels, angles) -> np.ndarray:
    """Least-squares linear Stokes images from channel images (Eqs. 99, 197).

    Parameters
    ----------
    channels : array_like ``(K, H, W)`` [counts or intensity], one image per polarizer.
    angles : array_like ``(K,)`` [rad], in ``[-2 pi, 2 pi]`` (degrees are refused).

    Returns
    -------
    ndarray ``(H, W, 3)``: (S0, S1, S2) with the Stokes axis last, same unit as ``channels``.

    Raises
    ------
    ValueError
        Degrees for ``angles``, fewer than three distinct orientations, or ``channels`` not
        ``(K, H, W)``.
    """
    I = as_finite(channels, "channels")
    P = analyzer_matrix(angles)
    if I.ndim != 3 or I.shape[0] != P.shape[0]:
        raise ValueError(
            f"channels must have shape (K, H, W) with K = {P.shape[0]} (one image per angle), "
            f"got {I.shape}"
        )
    return np.einsum("sk,khw->hws", np.linalg.pinv(P), I)


def dolp_aop_from_stokes(S, *, min_intensity: float = 0.0):
    """DOLP and AOP images from Stokes images, masked where there is no light.

    Calls :func:`scatterlab.polarization.dolp_aop` (the package's one DOLP rule: NaN where
    ``S0 <= min_intensity``) and masks the undefined pixels.

    Parameters
    ----------
    S : array_like ``(H, W, 3)`` (or ``(H, W, 4)``), Stokes axis last.
    min_intensity : float, ``>= 0``, same unit as ``S``.

    Returns
    -------
    dolp, aop : masked arrays ``(H, W)`` (AOP in (-pi/2, pi/2] [rad]); DOLP is not clipped, so noise can
    push it above 1 -- an honest estimate, not a bounded one. The AOP is masked also where
    ``S1 = S2 = 0``.
    """
    dolp, aop = dolp_aop(stokes_image(S, "S"), min_intensity=min_intensity)
    return np.ma.masked_invalid(dolp), np.ma.masked_invalid(aop)
