r"""Pupils, point-spread functions and transfer functions (Eqs. 66-67, 82-83).

The PSF of a pupil :math:`A(\mathbf u)` with phase :math:`\varphi(\mathbf u)` is
:math:`h = |\mathcal F\{A e^{j\varphi}\}|^2` (Eq. 83), normalised to unit sum. With the pupil zero-padded by
``pad`` (>= 2), the PSF is sampled at :math:`\lambda/(\mathrm{pad}\,D)` in angle -- Nyquist for the incoherent
PSF, whose OTF cuts off at :math:`D/\lambda`. Frequencies below are normalised to that cut-off,
:math:`\nu = f\lambda/D \in [0, 1]`.

Theory for comparison: the diffraction-limited MTF of a circular pupil,
:math:`\frac{2}{\pi}[\arccos\nu - \nu\sqrt{1-\nu^2}]`; Fried's long-exposure MTF, that times
:math:`\exp[-3.44 (\nu D/r_0)^{5/3}]`; and his short-exposure (tilt-removed) MTF with
:math:`\exp\{-3.44 (\nu D/r_0)^{5/3}[1 - \alpha\nu^{1/3}]\}` (:math:`\alpha = 1` near field, 1/2 far field).
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, special

from scatterlab._checks import as_count, as_finite, as_positive, as_scalar

__all__ = [
    "circular_pupil",
    "psf",
    "otf",
    "mtf",
    "radial_profile",
    "airy_pattern",
    "diffraction_mtf",
    "long_exposure_mtf",
    "short_exposure_mtf",
    "fit_r0",
]


def circular_pupil(n: int, radius: float, obscuration: float = 0.0) -> np.ndarray:
    """Binary circular pupil of ``radius`` pixels centred on an ``(n, n)`` grid, optional central obscuration
    (fraction of the radius in [0, 1)).

    Parameters
    ----------
    n : int
        Grid size [pixels], >= 4.
    radius : float
        Pupil radius [pixels], <= ``n / 2``; with ``obscuration``, it must leave at least one pixel
        centre inside the pupil.
    obscuration : float
        Central obscuration radius as a fraction of ``radius``, in [0, 1).

    Returns
    -------
    ndarray, shape (n, n)
        1 inside the pupil, 0 outside.

    Raises
    ------
    ValueError
        ``n`` not an integer >= 4, ``radius`` not a single number in ``(0, n/2]``, ``obscuration`` not a
        single number in [0, 1), or a pupil with no pixel centre inside.
    """
    n = as_count(n, "n", 4, " [pixels]")
    radius = as_scalar(radius, "radius", 0.0, open_lo=True, unit=" [pixels]")
    if radius > n / 2:
        raise ValueError(f"radius ({radius} px) must fit in the grid (<= n/2 = {n / 2})")
    allowed = (
        "obscuration must be a single finite number in [0, 1) (a fraction of radius), got "
        f"{obscuration!r}"
    )
    try:
        obscuration = as_scalar(obscuration, "obscuration", 0.0, 1.0)
    except ValueError:
        raise ValueError(allowed) from None
    if obscuration == 1:
        raise ValueError(allowed)
    y, x = np.mgrid[0:n, 0:n] - (n - 1) / 2
    r = np.hypot(x, y)
    inside = (r <= radius) & (r >= obscuration * radius)
    if not inside.any():
        nearest = f" (the nearest lies {r.min():.3g} px from it)" if r.min() > radius else ""
        raise ValueError(
            f"radius ({radius:g} px) and obscuration ({obscuration:g}) leave the pupil empty: no pixel "
            f"centre of the {n} x {n} grid lies {obscuration * radius:g} to {radius:g} px from its "
            f"centre{nearest}; increase radius or decrease obscuration"
        )
    return inside.astype(float)


def psf(pupil, phase=None, pad: int = 2) -> np.ndarray:
    """PSF of ``pupil`` with optional ``phase`` [rad] (Eq. 83), zero-padded by ``pad``, centred, unit sum.

    Parameters
    ----------
    pupil : array_like, shape (..., n, n)
        Pupil amplitude [any unit], finite and not zero everywhere (it must transmit light). Only its shape
        matters: it is scaled by a power of two to a largest magnitude in [0.5, 1) first (exact), so any
        magnitude, 1e-300 or 1e300, gives the same finite PSF.
    phase : array_like, optional
        Pupil phase [rad], broadcastable to ``pupil`` (e.g. ``(n, n)``, or ``(F, n, n)`` for ``F``
        screens through one pupil).
    pad : int
        Zero-padding factor, an integer >= 2 (Nyquist sampling of the incoherent PSF).

    Returns
    -------
    ndarray, shape (..., pad n, pad n)
        Centred PSF(s), unit sum each; the leading shape is that of ``pupil`` and ``phase`` broadcast.

    Raises
    ------
    ValueError
        ``pad`` < 2, a dark pupil, or ``phase`` and ``pupil`` shapes that do not broadcast.
    """
    pupil = as_finite(pupil, "pupil")
    pad = as_count(pad, "pad", lo=2, unit=" (Nyquist sampling of the PSF)")
    if pupil.ndim < 2 or pupil.shape[-1] != pupil.shape[-2]:
        raise ValueError(f"pupil must be a square array (..., n, n), got shape {pupil.shape}")
    if not np.all(np.any(pupil != 0, axis=(-2, -1))):
        raise ValueError(
            "pupil must transmit light (it is zero everywhere): the PSF would be undefined"
        )
    # scaled by a power of two to a largest magnitude in [0.5, 1) first (exact): |field| < 1, so the FFT's
    # squares neither overflow (a pupil of 1e200) nor underflow to a 0/0 normalisation (1e-200), and the
    # unit-sum PSF is unchanged by the scale
    pupil = np.ldexp(pupil, -np.frexp(np.max(np.abs(pupil), axis=(-2, -1), keepdims=True))[1])
    if phase is None:
        field = pupil.astype(complex)
    else:
        phase = as_finite(phase, "phase")
        try:
            np.broadcast_shapes(pupil.shape, phase.shape)
        except ValueError:
            raise ValueError(
                f"phase (shape {phase.shape}) must broadcast to pupil (shape {pupil.shape}): one "
                "phase value per pupil pixel"
            ) from None
        field = pupil * np.exp(1j * phase)
    n = pupil.shape[-1]
    m = pad * n
    F = np.fft.fft2(field, s=(m, m))
    h = np.fft.fftshift(F.real**2 + F.imag**2, axes=(-2, -1))
    return h / h.sum(axis=(-2, -1), keepdims=True)


def otf(h) -> np.ndarray:
    """Optical transfer function of a centred PSF, normalised to 1 at zero frequency (centred).

    The PSF is scaled by a power of two to a largest magnitude in [0.5, 1) before its FFT (exact), so a PSF
    of any magnitude (a subnormal 1e-320 peak, or 1e300) gives the same finite OTF.

    Parameters
    ----------
    h : array_like, shape (..., n, n)
        Centred PSF(s) [any intensity unit], finite; each must have a positive sum, larger than the
        rounding error of summing it (``n^2 * 2.2e-16 * sum|h|``: a PSF whose negative values cancel its
        light has no defined normalisation).

    Returns
    -------
    ndarray, shape (..., n, n), complex
        Centred OTF [dimensionless], 1 at zero frequency (pixel ``n // 2``).

    Raises
    ------
    ValueError
        ``h`` not finite or not at least 2-D, or a PSF whose sum is not positive.
    """
    h = as_finite(h, "h")
    if h.ndim < 2 or min(h.shape[-2:]) < 1:
        raise ValueError(f"h must be a PSF (n, n) or a stack (..., n, n), got shape {h.shape}")
    # scaled by a power of two to a largest magnitude in [0.5, 1) (exact; a dark PSF stays 0 and is refused
    # below): the FFT and the normalisation neither overflow nor divide by a subnormal
    h = np.ldexp(h, -np.frexp(np.max(np.abs(h), axis=(-2, -1), keepdims=True, initial=0.0))[1])
    O = np.fft.fftshift(np.fft.fft2(np.fft.ifftshift(h, axes=(-2, -1))), axes=(-2, -1))
    dc = O[..., h.shape[-2] // 2, h.shape[-1] // 2].real  # the sum of h (imaginary part 0)
    rounding = h.shape[-1] * h.shape[-2] * np.finfo(float).eps * np.sum(np.abs(h), axis=(-2, -1))
    if not np.all(dc > rounding):
        raise ValueError(
            "h must have a positive sum (a PSF with light), above its rounding error: its OTF is "
            "normalised by it"
        )
    # |O| <= sum|h| < dc / (n^2 eps): the ratio stays below 1 / (n^2 eps), far from overflow
    return O / dc[..., None, None]


def mtf(h) -> np.ndarray:
    """Modulation transfer function ``|OTF|`` (centred).

    Parameters
    ----------
    h : array_like, shape (..., n, n)
        Centred PSF(s).

    Returns
    -------
    ndarray, shape (..., n, n)
        Centred MTF, 1 at zero frequency.
    """
    return np.abs(otf(h))


def radial_profile(image, nbins=None) -> tuple[np.ndarray, np.ndarray]:
    """Azimuthal mean of a centred image: (radius [px], mean) at integer radii.

    Parameters
    ----------
    image : array_like, shape (n, n)
        Centred, finite image (centre at pixel ``n // 2``).
    nbins : int, optional
        Number of integer radii, >= 1; default ``n // 2`` (at least 1).

    Returns
    -------
    radius : ndarray, shape (nbins,)
        Radii ``0, 1, ..., nbins - 1`` [pixels].
    mean : ndarray, shape (nbins,)
        Mean of the image over the pixels at each rounded radius (0 where there are none).

    Raises
    ------
    ValueError
        ``image`` not a finite square 2-D array, or ``nbins`` not an integer >= 1.
    """
    image = as_finite(image, "image")
    if image.ndim != 2 or image.shape[0] != image.shape[1]:
        raise ValueError(
            f"image must be one square 2-D image (n, n), got shape {image.shape}; for a stack, call "
            "radial_profile on each image"
        )
    n = image.shape[-1]
    nb = max(n // 2, 1) if nbins is None else as_count(nbins, "nbins", lo=1)
    y, x = np.indices(image.shape) - n // 2
    r = np.rint(np.hypot(x, y)).astype(int)
    sums = np.bincount(r.ravel(), weights=image.ravel(), minlength=nb)
    counts = np.bincount(r.ravel(), minlength=nb)
    return np.arange(nb), sums[:nb] / np.maximum(counts[:nb], 1)


def airy_pattern(v) -> np.ndarray:
    """Airy intensity ``[2 J1(v)/v]^2`` at ``v = pi D theta / lambda`` (1 at v = 0; first zero v =
    3.8317).

    Parameters
    ----------
    v : array_like
        Normalised angle ``pi D theta / lambda`` [dimensionless].

    Returns
    -------
    ndarray, shape of ``v``
        Normalised Airy intensity.
    """
    v = np.asarray(v, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(v == 0, 1.0, (2 * special.j1(v) / np.where(v == 0, 1, v)) ** 2)


def diffraction_mtf(nu) -> np.ndarray:
    """Diffraction-limited MTF of a circular pupil at normalised frequency ``nu`` in [0, 1] (0
    beyond).

    Parameters
    ----------
    nu : array_like
        Spatial frequency normalised by the cutoff ``D / lambda`` (clipped to [0, 1]).

    Returns
    -------
    ndarray, shape of ``nu``
        The MTF, 1 at ``nu = 0`` and 0 at ``nu >= 1``.
    """
    nu = np.clip(np.asarray(nu, float), 0, 1)
    return 2 / np.pi * (np.arccos(nu) - nu * np.sqrt(1 - nu * nu))


def long_exposure_mtf(nu, d_over_r0) -> np.ndarray:
    """Fried's long-exposure MTF: diffraction-limited MTF times exp(-3.44 (nu D/r0)^(5/3)).

    Parameters
    ----------
    nu : array_like
        Spatial frequency normalised by the cutoff ``D / lambda`` (clipped to [0, 1]).
    d_over_r0 : float
        Aperture diameter over Fried parameter, ``D / r0`` [dimensionless], a single finite number > 0
        (up to 1.8e308: where the exponent exceeds the double range the MTF is 0, its value to double
        precision).

    Returns
    -------
    ndarray, shape of ``nu``
        The long-exposure MTF [dimensionless], in [0, 1].

    Raises
    ------
    ValueError
        ``d_over_r0`` not a single finite number > 0.
    """
    d_over_r0 = as_scalar(d_over_r0, "d_over_r0", 0.0, open_lo=True)
    nu = np.clip(np.asarray(nu, float), 0, 1)
    # (nu D/r0)^(5/3) overflows to inf for nu D/r0 > 1e185: exp(-inf) = 0 is then the MTF to double
    # precision (it is below exp(-1e308)); a tiny D/r0 underflows to 0, an MTF of diffraction_mtf
    with np.errstate(over="ignore", under="ignore"):
        return diffraction_mtf(nu) * np.exp(-3.44 * (nu * d_over_r0) ** (5 / 3))


def short_exposure_mtf(nu, d_over_r0, alpha: float = 1.0) -> np.ndarray:
    """Fried's short-exposure (tilt-removed) MTF; ``alpha = 1`` near field, 0.5 far field.

    Parameters
    ----------
    nu : array_like
        Spatial frequency normalised by the cutoff ``D / lambda`` (clipped to [0, 1]).
    d_over_r0 : float
        Aperture diameter over Fried parameter, ``D / r0`` [dimensionless], a single finite number > 0
        (up to 1.8e308: where the exponent exceeds the double range the MTF is 0, its value to double
        precision).
    alpha : float
        1 in the near field, 0.5 in the far field (a single number in [0, 1]).

    Returns
    -------
    ndarray, shape of ``nu``
        The short-exposure MTF [dimensionless], in [0, 1].

    Raises
    ------
    ValueError
        ``d_over_r0`` not a single finite number > 0, or ``alpha`` not a single number in [0, 1].
    """
    d_over_r0 = as_scalar(d_over_r0, "d_over_r0", 0.0, open_lo=True)
    alpha = as_scalar(alpha, "alpha", 0.0, 1.0, unit=" (1 near field, 0.5 far)")
    nu = np.clip(np.asarray(nu, float), 0, 1)
    tilt = 1 - alpha * nu ** (1 / 3)  # in [0, 1]; 0 only at nu = 1 with alpha = 1
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        # (nu D/r0)^(5/3) may overflow to inf (nu D/r0 > 1e185): exp(-inf) = 0 is the MTF to double
        # precision; where tilt = 0 the exponent is 0 (inf * 0 would be NaN), and the MTF is
        # diffraction_mtf, 0 at nu = 1
        exponent = np.where(tilt > 0, (nu * d_over_r0) ** (5 / 3) * tilt, 0.0)
        return diffraction_mtf(nu) * np.exp(-3.44 * exponent)


def fit_r0(nu, measured_mtf, diameter, *, floor: float = 0.02) -> float:
    """Fit r0 [m] of the long-exposure MTF to a measured MTF (the reference's calibration of Fig. 48).

    Least squares in ``log MTF`` over the frequencies from 0 up to where the measured MTF first falls
    below ``floor``: a measured long-exposure MTF has a noise floor (finite averaging of speckle, detector
    noise) that would otherwise dominate the logarithmic residuals.

    Parameters
    ----------
    nu : array_like, shape (N,)
        Spatial frequencies normalised by the cutoff ``D / lambda``.
    measured_mtf : array_like, shape (N,)
        Measured MTF at ``nu``.
    diameter : float
        Aperture diameter ``D`` [m].
    floor : float
        Noise floor of the measured MTF: the fit stops where it is first reached.

    Returns
    -------
    float
        Fried parameter r0 [m].

    Raises
    ------
    ValueError
        ``nu`` and ``measured_mtf`` not 1-D of one length, non-finite values, or fewer than three
        frequencies in (0, 1) above ``floor``.
    """
    nu = as_finite(nu, "nu")
    m = as_finite(measured_mtf, "measured_mtf")
    if nu.ndim != 1 or m.shape != nu.shape:
        raise ValueError(
            "nu and measured_mtf must be 1-D arrays of the same length N (one MTF value per "
            f"frequency), got shapes nu {nu.shape} and measured_mtf {m.shape}"
        )
    D = float(as_positive(diameter, "diameter"))
    order = np.argsort(nu)
    nu, m = nu[order], m[order]
    below = np.nonzero((m <= floor) & (nu > 0))[0]
    stop = nu[below[0]] if below.size else 1.0
    sel = (m > floor) & (nu > 0) & (nu < min(stop, 1.0))
    if sel.sum() < 3:
        raise ValueError(
            "measured_mtf must exceed the floor at three or more frequencies in (0, 1)"
        )

    def resid(p):
        return np.log(long_exposure_mtf(nu[sel], np.exp(p[0]))) - np.log(m[sel])

    res = optimize.least_squares(resid, [np.log(5.0)])
    return D / float(np.exp(res.x[0]))
