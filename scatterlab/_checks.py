"""Input checks shared by the physics modules.

Every public function validates its arguments with these helpers so that bad
input raises a :class:`ValueError` whose message names the argument and the
allowed range, instead of returning NaN or a silently wrong number.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "ETA_MIN",
    "ETA_MAX",
    "as_index",
    "as_angle",
    "as_positive",
    "as_finite",
    "broadcast",
    "check_starts",
    "as_scalar",
    "as_square_matrix",
    "as_image_shape",
]


def as_finite(value, name: str, *, dtype=float) -> np.ndarray:
    """Return ``value`` as an array of ``dtype``; raise if any element is NaN or inf.

    Parameters
    ----------
    value : array_like
        The input.
    name : str
        Argument name used in the error message.
    dtype : numpy dtype
        Target dtype (default float).

    Returns
    -------
    ndarray
        ``value`` as an array of ``dtype``, same shape.
    """
    try:
        arr = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


ETA_MIN, ETA_MAX = 1e-50, 1e50
"""Allowed range of ``|eta|``: inside it every Fresnel and pBRDF formula is evaluated without
overflow or underflow of its intermediate powers (up to ``|eta|^4``) and is tested (see
:mod:`scatterlab.fresnel`)."""


def as_index(eta, name: str = "eta") -> np.ndarray:
    """Validate a complex index of refraction ``eta = n - 1j*kappa``.

    Allowed: finite, ``n >= 0``, ``kappa >= 0`` (imaginary part <= 0) and
    ``1e-50 <= |eta| <= 1e50`` (:data:`ETA_MIN`, :data:`ETA_MAX`). ``n = 0`` with ``kappa > 0`` is a
    lossless medium below its plasma frequency and is allowed; ``eta = 0`` is not. A positive
    imaginary part is the other sign convention and is rejected rather than conjugated silently.

    Parameters
    ----------
    eta : array_like of complex
        Complex index ``n - 1j*kappa`` (dimensionless), any shape.
    name : str
        Argument name used in the error message.

    Returns
    -------
    ndarray of complex
        ``eta``, same shape.
    """
    arr = as_finite(eta, name, dtype=complex)
    if np.any(arr.imag > 0):
        raise ValueError(
            f"{name} must have a non-positive imaginary part (eta = n - 1j*kappa, "
            f"kappa >= 0); got a positive imaginary part. Conjugate it if your source "
            f"uses the n + i*kappa convention."
        )
    if np.any(arr.real < 0):
        raise ValueError(f"{name} must have a non-negative real part n >= 0")
    mag = np.abs(arr)
    bad = (mag < ETA_MIN) | (mag > ETA_MAX)
    if np.any(bad):
        worst = complex(arr[bad].flat[0])
        raise ValueError(
            f"{name} must satisfy {ETA_MIN:g} <= |{name}| <= {ETA_MAX:g} (got {name} = {worst!r}); "
            f"outside this range the Fresnel formulas overflow double precision"
        )
    return arr


def as_angle(theta, name: str = "theta", lo: float = 0.0, hi: float = np.pi / 2) -> np.ndarray:
    """Validate angles in radians within ``[lo, hi]``.

    Parameters
    ----------
    theta : array_like
        Angles [rad], any shape.
    name : str
        Argument name used in the error message.
    lo, hi : float
        Allowed range [rad] (default ``[0, pi/2]``).

    Returns
    -------
    ndarray of float
        ``theta`` [rad], same shape.
    """
    arr = as_finite(theta, name)
    if np.any(arr < lo) or np.any(arr > hi):
        raise ValueError(f"{name} must be in [{lo:g}, {hi:g}] rad (angles are in radians)")
    return arr


def as_rng(rng, name: str = "rng") -> np.random.Generator:
    """A numpy Generator from what every ``rng`` argument of the package accepts.

    Parameters
    ----------
    rng : None, int >= 0, sequence of int >= 0, numpy.random.SeedSequence, BitGenerator or Generator
        None draws fresh entropy (not reproducible); a Generator is used as it is (shared state).
    name : str
        Argument name used in the error message.

    Returns
    -------
    numpy.random.Generator
    """
    if isinstance(rng, np.random.Generator):
        return rng
    allowed = (
        f"{name} must be None, a non-negative integer (a seed), a sequence of them, a "
        "numpy.random.SeedSequence, BitGenerator or Generator"
    )
    ok = rng is None or isinstance(rng, (np.random.SeedSequence, np.random.BitGenerator))
    if not ok:
        seeds = np.asarray(rng, dtype=object).ravel() if not isinstance(rng, (str, bytes)) else None
        ok = (
            seeds is not None
            and seeds.size > 0
            and all(
                isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_))
                for v in seeds
            )
        )
        if ok and any(int(v) < 0 for v in seeds):
            raise ValueError(f"{allowed}; got a negative seed {rng!r}")
    if not ok:
        raise ValueError(f"{allowed}; got {rng!r}")
    return np.random.default_rng(rng)


def as_turn(values, name: str, what: str = "angles", hint: str = "") -> np.ndarray:
    """Validate angles in radians within a full turn either way, ``[-2 pi, 2 pi]``.

    Azimuths and polarizer angles are periodic, but one beyond a full turn is almost always given in
    degrees (180, or 0, 45, 90, 135), which would otherwise be read silently as radians.

    Parameters
    ----------
    values : array_like
        Angles [rad], any shape.
    name : str
        Argument name used in the error message.
    what : str
        What the angles are, for the message.
    hint : str
        Appended to the message (e.g. the value of a common geometry).

    Returns
    -------
    ndarray of float
        ``values`` [rad], same shape.
    """
    arr = as_finite(values, name)
    if np.any(np.abs(arr) > 2 * np.pi * (1 + 1e-12)):
        worst = float(arr.flat[int(np.argmax(np.abs(arr)))])
        raise ValueError(
            f"{name} must be {what} in radians in [-2 pi, 2 pi], got {worst:g} (degrees? use "
            f"numpy.radians{hint})"
        )
    return arr


def as_azimuth(phi, name: str = "phi") -> np.ndarray:
    """Validate azimuths [rad] within ``[-2 pi, 2 pi]`` (:func:`as_turn`; ``phi = 180`` is degrees).

    Parameters
    ----------
    phi : array_like
        Azimuths [rad], any shape.
    name : str
        Argument name used in the error message.

    Returns
    -------
    ndarray of float
        ``phi`` [rad], same shape.
    """
    return as_turn(phi, name, "azimuths", f"; the specular plane is {name} = pi")


def as_positive(value, name: str, *, allow_zero: bool = False) -> np.ndarray:
    """Validate a strictly positive (or non-negative) finite real array.

    Parameters
    ----------
    value : array_like
        The input (any unit), any shape.
    name : str
        Argument name used in the error message.
    allow_zero : bool
        Accept zero.

    Returns
    -------
    ndarray of float
        ``value``, same shape.
    """
    arr = as_finite(value, name)
    bad = arr < 0 if allow_zero else arr <= 0
    if np.any(bad):
        rng = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be {rng}")
    return arr


def as_count(value, name: str, lo: int = 0, unit: str = "") -> int:
    """``value`` as an int, checked to be an integer (not a bool) >= ``lo``.

    Parameters
    ----------
    value : int
        A count: iterations, grid points, pixels.
    name : str
        The argument's name in the message.
    lo : int
        The smallest allowed value.
    unit : str
        Appended to the range in the message, e.g. ``" [pixels]"``.

    Returns
    -------
    int
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
        raise ValueError(f"{name} must be an integer >= {lo}{unit}, got {value!r}")
    return int(value)


def as_image_shape(value, name: str) -> tuple[int, int]:
    """``value`` as an image shape ``(H, W)``: two integers >= 1 [pixels].

    Parameters
    ----------
    value : sequence of two int
        The shape.
    name : str
        The argument's name in the message.

    Returns
    -------
    (H, W) : tuple of int
    """
    try:
        H, W = value
        return as_count(H, "H", 1), as_count(W, "W", 1)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be (H, W), two integers >= 1 [pixels], got {value!r}"
        ) from exc


def broadcast(**arrays) -> list[np.ndarray]:
    """Broadcast named arrays together; a shape mismatch names the arguments.

    Parameters
    ----------
    **arrays : array_like
        The arrays, named for the error message.

    Returns
    -------
    list of ndarray
        The arrays broadcast to their common shape (read-only views), in the order given.
    """
    try:
        return list(np.broadcast_arrays(*arrays.values()))
    except ValueError as exc:
        shapes = ", ".join(f"{k}{np.shape(v)}" for k, v in arrays.items())
        raise ValueError(f"shapes do not broadcast: {shapes}") from exc


def check_starts(starts, name: str = "starts"):
    """``starts`` as an array (S, 2) of (n, kappa) starting points; empty or malformed is a
    ValueError.

    Parameters
    ----------
    starts : sequence of (n, kappa)
        Starting points: finite, ``n >= 0`` and ``kappa >= 0`` (the domain of ``n - 1j*kappa``).
    name : str
        The argument's name in the messages.

    Returns
    -------
    ndarray (S, 2)
        The starting points as floats.
    """
    try:
        arr = np.asarray(starts, float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a sequence of (n, kappa) pairs, got {starts!r}") from exc
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] != 2 or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"{name} must be a non-empty sequence of finite (n, kappa) pairs, got {starts!r}"
        )
    if np.any(arr < 0):
        raise ValueError(
            f"{name} must have n >= 0 and kappa >= 0 in every (n, kappa) pair, got {starts!r}"
        )
    return arr


def as_scalar(
    value,
    name: str,
    lo: float = -np.inf,
    hi: float = np.inf,
    *,
    open_lo: bool = False,
    unit: str = "",
) -> float:
    """``value`` as one finite float in ``[lo, hi]`` (``(lo, hi]`` with ``open_lo``).

    Parameters
    ----------
    value : float
        The input: a real number (not a string, not an array of more than one value).
    name : str
        Argument name used in the error message.
    lo, hi : float
        Allowed range.
    open_lo : bool
        Exclude ``lo`` itself.
    unit : str
        Appended to the range in the message, e.g. ``" [rad]"``.

    Returns
    -------
    float
    """
    if np.isinf(hi):
        rng = "" if np.isinf(lo) else f" {'>' if open_lo else '>='} {lo:g}"
    else:
        rng = f" in {'(' if open_lo else '['}{lo:g}, {hi:g}]"
    allowed = f"{name} must be a single finite number{rng}{unit}"
    if isinstance(value, (str, bytes, bool, np.bool_)) or np.ndim(value) != 0:
        raise ValueError(f"{allowed}, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{allowed}, got {value!r}") from exc
    if not (np.isfinite(v) and (v > lo if open_lo else v >= lo) and v <= hi):
        raise ValueError(f"{allowed}, got {value!r}")
    return v


def as_square_matrix(
    value, name: str, *, symmetric: bool = False, rtol: float = 1e-8
) -> np.ndarray:
    """``value`` as a float array (..., P, P) of square matrices, optionally checked symmetric.

    Parameters
    ----------
    value : array_like (..., P, P)
        The matrices; NaN or inf entries are allowed (the caller decides what they mean).
    name : str
        Argument name used in the error message.
    symmetric : bool
        Require ``|A - A^T| <= rtol * max|A|`` (per matrix, finite entries): symmetric within
        rounding.
    rtol : float
        Relative tolerance of the symmetry check.

    Returns
    -------
    ndarray (..., P, P)
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array (..., P, P), got {value!r}") from exc
    if arr.ndim < 2 or arr.shape[-1] != arr.shape[-2] or arr.shape[-1] == 0:
        raise ValueError(
            f"{name} must be square matrices of shape (..., P, P) with P >= 1, got shape {arr.shape}"
        )
    if symmetric:
        ok = np.isfinite(arr) & np.isfinite(np.swapaxes(arr, -1, -2))
        a = np.where(ok, arr, 0.0)
        diff = np.max(np.abs(a - np.swapaxes(a, -1, -2)), axis=(-2, -1))
        size = np.max(np.abs(a), axis=(-2, -1))
        if np.any(diff > rtol * size):
            raise ValueError(
                f"{name} must be symmetric (within {rtol:g} relative rounding); got a matrix with "
                f"|A - A^T| = {float(np.max(diff)):.3g} against max|A| = "
                f"{float(size.flat[int(np.argmax(diff))]):.3g}"
            )
    return arr
