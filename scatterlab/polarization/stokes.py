r"""Stokes vectors and the polarization quantities derived from them.

Conventions: Stokes vectors have shape ``(..., 4)``; ``S0`` is the intensity,
``S1 = I_s - I_p`` (s perpendicular to the plane of incidence), ``S2 = I_{+45} -
I_{-45}`` and ``S3 = 2 Im(E_s^* E_p)``, the sign that makes the Jones-to-Mueller
conversion of Eq. 133 and the worked example of Eq. 39 agree (see
:mod:`scatterlab.polarization.jones`); ``(1, 0, 0, 1)`` is right circular as in Eq. 38.

Undefined quantities (the one zero-light rule of the package): the degree of
polarization and the angle of polarization of zero light (``S0 <= min_intensity``,
``min_intensity = 0`` by default) are mathematically undefined and are returned as
NaN (documented, never a crash, never a warning); the angle of polarization of light
with no linear part (``S1 = S2 = 0``) is returned as NaN too. Images that need a mask
take ``numpy.isnan`` of the result, or :func:`dolp_aop` with ``mask=True``.

:func:`dolp` is the one DOLP-from-Stokes computation of the package: imaging,
deconvolution, characterization, pBRDF and plotting call it. :func:`signed_dolp` is
the projection ``(S1 cos 2a + S2 sin 2a) / S0`` onto a known AOP ``a`` (specular
geometry fixes ``a = 0``): unlike :func:`dolp` it has no noise (Rician) bias and can
be negative. Both accept ``(..., 4)`` or the linear block ``(..., 3)``, axis last.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_finite, as_scalar, as_turn

__all__ = [
    "jones_to_stokes",
    "stokes_vector",
    "dop",
    "dolp",
    "aop",
    "dolp_aop",
    "signed_dolp",
    "is_physical_stokes",
]


def _stokes(S) -> np.ndarray:
    S = as_finite(S, "S")
    if S.shape[-1:] != (4,):
        raise ValueError(f"S must have shape (..., 4), got {S.shape}")
    return S


def jones_to_stokes(E) -> np.ndarray:
    """Stokes vector of a fully polarized field with Jones vector ``E`` (Eq. 37, Eq. 133's sign of S3).

    Parameters
    ----------
    E : array_like, shape ``(..., 2)``, complex (E_s, E_p).

    Returns
    -------
    S : ndarray, shape ``(..., 4)``.
    """
    E = np.asarray(E, complex)
    if E.shape[-1:] != (2,):
        raise ValueError(f"E must have shape (..., 2), got {E.shape}")
    es, ep = E[..., 0], E[..., 1]
    x = np.conj(es) * ep
    Is, Ip = np.abs(es) ** 2, np.abs(ep) ** 2
    return np.stack([Is + Ip, Is - Ip, 2 * x.real, 2 * x.imag], -1)


def stokes_vector(intensity=1.0, dop=0.0, aop=0.0, ellipticity=0.0) -> np.ndarray:
    r"""Stokes vector from intensity, degree of polarization, angle of polarization and ellipticity angle.

    :math:`S = I\,(1, p\cos2\chi\cos2\psi, p\cos2\chi\sin2\psi, p\sin2\chi)`.

    Parameters
    ----------
    intensity : array_like, ``>= 0``
    dop : array_like in ``[0, 1]``
    aop : array_like [rad], from the s axis, in [-2 pi, 2 pi] (degrees are refused).
    ellipticity : array_like [rad] in ``[-pi/4, pi/4]`` (positive: right-handed).

    Returns
    -------
    S : ndarray, shape ``(..., 4)``.
    """
    I = as_finite(intensity, "intensity")
    p = as_finite(dop, "dop")
    psi = as_turn(aop, "aop", "angles of polarization")
    chi = as_finite(ellipticity, "ellipticity")
    if np.any(I < 0):
        raise ValueError("intensity must be >= 0")
    if np.any((p < 0) | (p > 1)):
        raise ValueError("dop must be in [0, 1]")
    if np.any(np.abs(chi) > np.pi / 4 + 1e-15):
        raise ValueError("ellipticity must be in [-pi/4, pi/4] rad")
    I, p, psi, chi = np.broadcast_arrays(I, p, psi, chi)
    return np.stack(
        [
            I,
            I * p * np.cos(2 * chi) * np.cos(2 * psi),
            I * p * np.cos(2 * chi) * np.sin(2 * psi),
            I * p * np.sin(2 * chi),
        ],
        -1,
    )


def _ratio(num, den, floor=0.0):
    """``num / den`` where ``den > floor``, NaN elsewhere and where either is not finite (an infinite
    S0 or S1 leaves the ratio undefined: inf / x and x / inf are not DOLPs) -- no warnings."""
    ok = (den > floor) & np.isfinite(den) & np.isfinite(num)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(ok, num / np.where(ok, den, 1.0), np.nan)


def _linear(S, name="S"):
    S = np.asarray(S, float)
    if S.ndim == 0 or S.shape[-1] not in (3, 4):
        raise ValueError(
            f"{name} must be Stokes vectors with the Stokes axis last, shape (..., 4) or (..., 3), "
            f"got {S.shape}"
        )
    return S  # NaN and inf propagate as NaN (undefined), no warnings


def _min_intensity(v):
    return as_scalar(v, "min_intensity", 0.0)


def dop(S) -> np.ndarray:
    """Degree of polarization ``sqrt(S1^2 + S2^2 + S3^2) / S0`` (Eq. 40); NaN where ``S0 == 0``.

    Parameters
    ----------
    S : array_like, shape ``(..., 4)``

    Returns
    -------
    ndarray, shape ``(...)``; in [0, 1] for a physical Stokes vector.
    """
    S = _stokes(S)
    # hypot, not the root of a sum of squares, which overflows from |S| ~ 1e154
    return _ratio(np.hypot(np.hypot(S[..., 1], S[..., 2]), S[..., 3]), S[..., 0])


def dolp(S, *, min_intensity: float = 0.0) -> np.ndarray:
    """Degree of linear polarization ``sqrt(S1^2 + S2^2) / S0``; NaN where ``S0 <= min_intensity``.

    The one DOLP-from-Stokes computation of the package. Not clipped: noisy estimated Stokes
    images can give a DOLP above 1 (an honest estimate, not a bounded one); a NaN (or an
    infinite S0) in ``S`` gives NaN.

    Parameters
    ----------
    S : array_like, shape ``(..., 4)`` (or ``(..., 3)``: the linear block), Stokes axis last.
    min_intensity : float, ``>= 0``
        Light at or below this ``S0`` counts as no light (same units as ``S``).

    Returns
    -------
    ndarray, shape ``(...)``, dimensionless.
    """
    S = _linear(S)
    return _ratio(np.hypot(S[..., 1], S[..., 2]), S[..., 0], _min_intensity(min_intensity))


def signed_dolp(S, aop=0.0, *, min_intensity: float = 0.0) -> np.ndarray:
    """DOLP projected on a known AOP: ``(S1 cos 2a + S2 sin 2a) / S0``; NaN where ``S0 <= min_intensity``.

    Used where the geometry fixes the AOP (unpolarized light observed in the specular plane:
    ``a = 0``, so it is ``S1 / S0``). Equal to :func:`dolp` for noise-free light polarized at
    ``a``; for noisy estimates it is unbiased (no Rician bias) and can be negative.

    Parameters
    ----------
    S : array_like, shape ``(..., 4)`` or ``(..., 3)``, Stokes axis last.
    aop : array_like [rad], finite, in [-2 pi, 2 pi] (degrees are refused); broadcasting with ``S[..., 0]``.
    min_intensity : float, ``>= 0``

    Returns
    -------
    ndarray, shape ``(...)``, dimensionless, in ``[-1, 1]`` for physical Stokes vectors.
    """
    S = _linear(S)
    a2 = 2 * as_turn(aop, "aop", "angles of polarization")
    proj = S[..., 1] * np.cos(a2) + S[..., 2] * np.sin(a2)
    return _ratio(proj, S[..., 0], _min_intensity(min_intensity))


def aop(S, *, min_intensity: float = 0.0) -> np.ndarray:
    """Angle of polarization ``0.5 * arctan2(S2, S1)`` [rad] in ``(-pi/2, pi/2]`` (Eq. 41).

    Measured from the s axis. NaN where there is no linear polarization
    (``S1 = S2 = 0``, e.g. unpolarized or circular light) or no light (``S0 <= min_intensity``).

    Parameters
    ----------
    S : array_like, shape ``(..., 4)`` or ``(..., 3)``, Stokes axis last.
    min_intensity : float, ``>= 0``

    Returns
    -------
    ndarray [rad], shape ``(...)``.
    """
    S = _linear(S)
    s1, s2 = S[..., 1], S[..., 2]
    a = 0.5 * np.arctan2(s2, s1)
    a = np.where(a <= -np.pi / 2, a + np.pi, a)
    dark = ~(S[..., 0] > _min_intensity(min_intensity))
    return np.where(((s1 == 0) & (s2 == 0)) | dark, np.nan, a)


def dolp_aop(S, *, min_intensity: float = 0.0, mask: bool = False):
    """DOLP and AOP together (:func:`dolp`, :func:`aop`), optionally with the mask of defined pixels.

    Parameters
    ----------
    S : array_like, shape ``(..., 4)`` or ``(..., 3)``, Stokes axis last (images: ``(H, W, 3)``).
    min_intensity : float, ``>= 0``
        ``S0`` at or below it is no light: DOLP and AOP NaN there.
    mask : bool
        Also return ``valid``, True where the DOLP is defined (``S0 > min_intensity``).

    Returns
    -------
    dolp : ndarray ``(...)``; aop : ndarray ``(...)`` [rad]; valid : bool ndarray ``(...)`` if ``mask``.
    """
    d = dolp(S, min_intensity=min_intensity)
    a = aop(S, min_intensity=min_intensity)
    return (d, a, ~np.isnan(d)) if mask else (d, a)


def is_physical_stokes(S, atol: float = 1e-12) -> np.ndarray:
    """True where ``S0 >= sqrt(S1^2 + S2^2 + S3^2)`` (within ``atol * S0``) and ``S0 >= 0``.

    The tolerance is relative only, so the test does not depend on the units of ``S``.

    Parameters
    ----------
    S : array_like, shape ``(..., 4)``
    atol : float, relative tolerance for rounding.

    Returns
    -------
    ndarray of bool, shape ``(...)``.
    """
    S = _stokes(S)
    pol = np.hypot(np.hypot(S[..., 1], S[..., 2]), S[..., 3])
    return (S[..., 0] >= 0) & (pol <= S[..., 0] * (1 + atol))
