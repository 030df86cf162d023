r"""Jones vectors and Jones matrices, matrix axes last.

Conventions:

* Basis ``(E_s, E_p)``: the first component is perpendicular (s) to the plane of
  incidence, the second parallel (p), as in Eqs. 54 and 132 of the reference text.
  Jones vectors have shape ``(..., 2)``, Jones matrices ``(..., 2, 2)``.
* Time dependence :math:`e^{+j\omega t}`: a component that *leads* in phase by
  :math:`\delta` is multiplied by :math:`e^{+j\delta}`. A quarter-wave plate with
  its fast axis along p is therefore ``diag(1, j)`` (up to a common phase). The
  reference text's Eq. 33 prints ``diag(1, -j)`` for that plate, which is the
  :math:`e^{-j\omega t}` (Hecht) convention; with :math:`e^{+j\omega t}`,
  ``diag(1, j)`` is what reproduces the Mueller matrix and the worked example of
  Eq. 39 through the Jones-to-Mueller conversion of Eq. 133.
* Element orientation angles are measured from the s axis towards the p axis;
  an element at angle :math:`\alpha` is :math:`R(-\alpha) J R(\alpha)` with
  :math:`R` the coordinate rotation of Eq. 33.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_finite, as_positive, as_turn, broadcast

__all__ = [
    "rotation",
    "rotate_jones",
    "linear_polarizer_jones",
    "linear_retarder_jones",
    "rotator_jones",
    "linear_jones_vector",
    "circular_jones_vector",
]


def rotation(angle) -> np.ndarray:
    r"""Coordinate rotation :math:`R(\alpha) = [[\cos\alpha, \sin\alpha], [-\sin\alpha, \cos\alpha]]` (Eq. 33).

    Parameters
    ----------
    angle : array_like
        Rotation angle [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    R : ndarray, shape ``(..., 2, 2)``.
    """
    a = as_turn(angle, "angle", "rotation angles")
    c, s = np.cos(a), np.sin(a)
    return np.stack([np.stack([c, s], -1), np.stack([-s, c], -1)], -2)


def rotate_jones(J, angle) -> np.ndarray:
    """Jones matrix of element ``J`` rotated by ``angle`` [rad]: ``R(-a) J R(a)`` (Eq. 34).

    Parameters
    ----------
    J : array_like, shape ``(..., 2, 2)``
    angle : array_like [rad], in [-2 pi, 2 pi] (degrees are refused); broadcast against ``J.shape[:-2]``.

    Returns
    -------
    ndarray, shape ``(..., 2, 2)``.
    """
    J = np.asarray(J)
    R = rotation(angle)
    return np.swapaxes(R, -1, -2) @ J @ R


def linear_polarizer_jones(angle=0.0, extinction_ratio=0.0) -> np.ndarray:
    """Jones matrix of a linear polarizer (Eq. 34), optionally non-ideal.

    Parameters
    ----------
    angle : array_like
        Transmission axis from the s axis [rad], in [-2 pi, 2 pi] (degrees are refused).
    extinction_ratio : array_like
        Intensity transmittance of the blocked axis relative to the pass axis,
        in ``[0, 1]`` (0 = ideal polarizer).

    Returns
    -------
    J : ndarray, shape ``(..., 2, 2)``, complex.
    """
    eps = as_positive(extinction_ratio, "extinction_ratio", allow_zero=True)
    if np.any(eps > 1):
        raise ValueError("extinction_ratio must be in [0, 1]")
    angle, eps = broadcast(
        angle=as_turn(angle, "angle", "transmission-axis angles"), extinction_ratio=eps
    )
    J = np.zeros(angle.shape + (2, 2), complex)
    J[..., 0, 0] = 1.0
    J[..., 1, 1] = np.sqrt(eps)
    return rotate_jones(J, angle)


def linear_retarder_jones(retardance, fast_axis=0.0) -> np.ndarray:
    r"""Jones matrix of a linear retarder.

    ``R(-theta) diag(exp(+j delta/2), exp(-j delta/2)) R(theta)``: the fast axis
    leads by the retardance :math:`\delta` (time dependence :math:`e^{+j\omega t}`).

    Parameters
    ----------
    retardance : array_like
        Retardance :math:`\delta` [rad] (``pi/2`` for a quarter-wave plate).
    fast_axis : array_like
        Fast-axis angle from the s axis [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    J : ndarray, shape ``(..., 2, 2)``, complex, unitary.
    """
    d, t = broadcast(
        retardance=as_finite(retardance, "retardance"),
        fast_axis=as_turn(fast_axis, "fast_axis", "fast-axis angles"),
    )
    J = np.zeros(d.shape + (2, 2), complex)
    J[..., 0, 0] = np.exp(0.5j * d)
    J[..., 1, 1] = np.exp(-0.5j * d)
    return rotate_jones(J, t)


def rotator_jones(rotation_angle) -> np.ndarray:
    """Jones matrix of a circular retarder (optical rotator) turning the field by ``rotation_angle`` [rad].

    Parameters
    ----------
    rotation_angle : array_like
        Rotation angle [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    J : ndarray, shape ``(..., 2, 2)``; equals ``rotation(-rotation_angle)``.
    """
    return rotation(-as_turn(rotation_angle, "rotation_angle", "rotation angles")).astype(complex)


def linear_jones_vector(angle) -> np.ndarray:
    """Jones vector ``(cos a, sin a)`` of unit-intensity linear polarization at ``angle`` [rad] from s (Eq. 32).

    Parameters
    ----------
    angle : array_like
        Polarization angle from s towards p [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    E : ndarray, shape ``(..., 2)``, complex.
    """
    a = as_turn(angle, "angle", "polarization angles")
    return np.stack([np.cos(a), np.sin(a)], -1).astype(complex)


def circular_jones_vector(handedness: str = "right") -> np.ndarray:
    """Unit-intensity circular polarization, ``(1, +j)/sqrt(2)`` for right, ``(1, -j)/sqrt(2)`` for left.

    "Right" is the state with Stokes ``S3 = +1`` in this package's convention
    (clockwise rotation seen by an observer facing the source, e^{+jwt}).

    Parameters
    ----------
    handedness : {"right", "left"}
        Handedness of the circular state.

    Returns
    -------
    ndarray, shape (2,), complex
        The unit-intensity Jones vector.
    """
    if handedness not in ("right", "left"):
        raise ValueError("handedness must be 'right' or 'left'")
    sign = 1 if handedness == "right" else -1
    return np.array([1, sign * 1j]) / np.sqrt(2)
