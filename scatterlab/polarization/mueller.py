r"""Mueller matrices: the Jones-to-Mueller conversion, ideal and non-ideal elements, realizability.

Mueller matrices have shape ``(..., 4, 4)`` and act on Stokes vectors ``(..., 4)``
by ``M @ S[..., None]`` (or :func:`apply`). The Stokes convention is that of
:mod:`scatterlab.polarization.stokes`; every element here equals
:func:`jones_to_mueller` of the corresponding Jones matrix in
:mod:`scatterlab.polarization.jones` (tested).

Physical realizability uses Cloude's coherency matrix
:math:`H = \tfrac14\sum_{ij} M_{ij}\,\sigma_i\otimes\sigma_j^*` (Pauli matrices
:math:`\sigma_0 = I, \sigma_1 = \mathrm{diag}(1,-1), \sigma_2, \sigma_3` in the
order of the Stokes parameters): ``M`` is an ensemble of deterministic
(Jones) systems if and only if ``H`` is positive semi-definite. For a pure
Jones matrix ``H`` has rank one.

References
----------
Reference text Eqs. 33-39 and 133; S. R. Cloude, Optik 75, 26 (1986).
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_finite, as_positive, as_turn, broadcast

__all__ = [
    "jones_to_mueller",
    "mueller_from_jones_elements",
    "apply",
    "rotate_mueller",
    "linear_polarizer",
    "diattenuator",
    "linear_retarder",
    "rotator",
    "depolarizer",
    "coherency_matrix",
    "mueller_from_coherency",
    "is_physical_mueller",
    "nearest_physical_mueller",
]

_PAULI = np.array(
    [
        [[1, 0], [0, 1]],
        [[1, 0], [0, -1]],
        [[0, 1], [1, 0]],
        [[0, -1j], [1j, 0]],
    ],
    dtype=complex,
)
# Basis B_ij = sigma_i (x) conj(sigma_j), shape (4, 4, 4, 4): [i, j, row, col].
_BASIS = np.einsum("iab,jcd->ijacbd", _PAULI, _PAULI.conj()).reshape(4, 4, 4, 4)


def jones_to_mueller(J) -> np.ndarray:
    r"""Mueller matrix of a deterministic system with Jones matrix ``J`` (Eq. 133, all 16 elements).

    With ``J = [[T_ss, T_ps], [T_sp, T_pp]]`` as placed in Eq. 132, e.g.
    :math:`m_{00} = \tfrac12(|T_{ss}|^2+|T_{sp}|^2+|T_{ps}|^2+|T_{pp}|^2)`,
    :math:`m_{23} = \tfrac12[j(T_{ps}T_{sp}^*-T_{ps}^*T_{sp}) - j(T_{ss}T_{pp}^*-T_{ss}^*T_{pp})]`;
    equivalently :math:`m_{ij} = \tfrac12\mathrm{tr}(\sigma_i J\sigma_j J^\dagger)`.

    Parameters
    ----------
    J : array_like, shape ``(..., 2, 2)``, complex.

    Returns
    -------
    M : ndarray, shape ``(..., 4, 4)``, real.
    """
    J = np.asarray(J)
    if J.shape[-2:] != (2, 2):
        raise ValueError(f"J must have shape (..., 2, 2), got {J.shape}")
    J = J.astype(complex, copy=False)
    return mueller_from_jones_elements(J[..., 0, 0], J[..., 0, 1], J[..., 1, 0], J[..., 1, 1])


# Eq. 133, element by element: M[i][j] from |J_k|^2 (sq) and J_k J_l^* (pr) of a = T_ss, b = T_ps,
# c = T_sp, d = T_pp.
_ELEMENTS = (
    (
        lambda q, p: 0.5 * (q("a") + q("b") + q("c") + q("d")),
        lambda q, p: 0.5 * (q("a") - q("b") + q("c") - q("d")),
        lambda q, p: p("ab").real + p("cd").real,
        lambda q, p: p("ab").imag + p("cd").imag,
    ),
    (
        lambda q, p: 0.5 * (q("a") + q("b") - q("c") - q("d")),
        lambda q, p: 0.5 * (q("a") - q("b") - q("c") + q("d")),
        lambda q, p: p("ab").real - p("cd").real,
        lambda q, p: p("ab").imag - p("cd").imag,
    ),
    (
        lambda q, p: p("ac").real + p("bd").real,
        lambda q, p: p("ac").real - p("bd").real,
        lambda q, p: p("ad").real + p("bc").real,
        lambda q, p: p("ad").imag - p("bc").imag,
    ),
    (
        lambda q, p: -p("ac").imag - p("bd").imag,
        lambda q, p: p("bd").imag - p("ac").imag,
        lambda q, p: -p("ad").imag - p("bc").imag,
        lambda q, p: p("ad").real - p("bc").real,
    ),
)


def mueller_from_jones_elements(a, b, c, d, *, shape: tuple[int, int] = (4, 4)) -> np.ndarray:
    """Eq. 133 from the Jones elements ``a = T_ss, b = T_ps, c = T_sp, d = T_pp`` given as arrays.

    The one Jones-to-Mueller kernel: :func:`jones_to_mueller`, the smooth-surface matrix
    (:func:`scatterlab.fresnel.mueller_matrix`) and every pBRDF path use it.

    Parameters
    ----------
    a, b, c, d : array_like of complex, broadcasting
        Jones elements; ``b`` and ``c`` may be None for a diagonal Jones matrix (a reflection in
        the plane of incidence), which skips their products.
    shape : (int, int)
        The leading block of rows and columns to compute, e.g. ``(3, 3)`` for linear polarimetry
        or ``(3, 1)`` for the first column (unpolarized illumination). Default the full matrix.

    Returns
    -------
    M : ndarray, shape ``(..., rows, cols)``, real.
    """
    J = {"a": a, "b": b, "c": c, "d": d}
    cache = {}

    def q(k):
        if J[k] is None:
            return 0.0
        if k not in cache:
            x = J[k]
            cache[k] = x.real * x.real + x.imag * x.imag
        return cache[k]

    def p(kl):
        x, y = J[kl[0]], J[kl[1]]
        if x is None or y is None:
            return 0j
        if kl not in cache:
            cache[kl] = x * np.conj(y)
        return cache[kl]

    rows, cols = shape
    out_shape = np.broadcast_shapes(*(np.shape(x) for x in J.values() if x is not None))
    diagonal = b is None or c is None
    M = (np.zeros if diagonal else np.empty)(out_shape + (rows * cols,))
    for i in range(rows):
        for j in range(cols):
            value = _ELEMENTS[i][j](q, p)
            if not diagonal or np.ndim(value) or value != 0:  # diagonal J: 8 elements stay 0
                M[..., i * cols + j] = value
    return M.reshape(out_shape + (rows, cols))


def apply(M, S) -> np.ndarray:
    """Stokes vector(s) after Mueller matrix ``M``: ``(..., 4, 4) x (..., 4) -> (..., 4)``.

    Parameters
    ----------
    M : array_like, shape (..., 4, 4)
        Mueller matrix or matrices.
    S : array_like, shape (..., 4)
        Stokes vector(s); broadcast against ``M``.

    Returns
    -------
    ndarray, shape (..., 4)
        ``M @ S``.
    """
    M, S = np.asarray(M), np.asarray(S)
    if M.shape[-2:] != (4, 4) or S.shape[-1:] != (4,):
        raise ValueError(
            f"M must have shape (..., 4, 4) and S (..., 4) (Stokes axis last), got {M.shape} and "
            f"{S.shape}"
        )
    return np.einsum("...ij,...j->...i", M, S)


def _frame_rotation(angle, name: str = "angle") -> np.ndarray:
    a = as_turn(angle, name, "rotation angles")
    c, s = np.cos(2 * a), np.sin(2 * a)
    R = np.zeros(a.shape + (4, 4))
    R[..., 0, 0] = R[..., 3, 3] = 1
    R[..., 1, 1] = R[..., 2, 2] = c
    R[..., 1, 2] = s
    R[..., 2, 1] = -s
    return R


def rotate_mueller(M, angle) -> np.ndarray:
    """Mueller matrix of element ``M`` rotated by ``angle`` [rad]: ``R(-a) M R(a)``.

    The linear block ``(..., 3, 3)`` of a Mueller matrix (all that unpolarized light and linear
    analyzers see) rotates with the linear block of the rotation: a rotation about the V axis never
    mixes the circular row and column into it.

    Parameters
    ----------
    M : array_like, shape ``(..., 4, 4)`` or ``(..., 3, 3)``
        Mueller matrices, or their linear blocks.
    angle : array_like [rad], from the s axis towards p, in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    ndarray, shape of ``M`` broadcast against ``angle``
        The rotated Mueller matrix (or linear block).
    """
    M = np.asarray(M)
    if M.ndim < 2 or M.shape[-2:] not in ((4, 4), (3, 3)):
        raise ValueError(
            f"M must have shape (..., 4, 4) or, for the linear block, (..., 3, 3); got {M.shape}"
        )
    k = M.shape[-1]
    R = _frame_rotation(angle)[..., :k, :k]
    return np.swapaxes(R, -1, -2) @ M @ R


def diattenuator(t_max=1.0, t_min=0.0, angle=0.0) -> np.ndarray:
    r"""Linear diattenuator with intensity transmittances ``t_max`` (along ``angle``) and ``t_min``.

    :math:`\tfrac12[[q+r, q-r, 0, 0], [q-r, q+r, 0, 0], [0, 0, 2\sqrt{qr}, 0], [0, 0, 0, 2\sqrt{qr}]]`
    rotated to ``angle`` [rad].

    Parameters
    ----------
    t_max, t_min : array_like
        Intensity transmittances along and across ``angle``, ``0 <= t_min <= t_max <= 1``.
    angle : array_like
        Axis of maximum transmittance, from s towards p [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    M : ndarray, shape ``(..., 4, 4)``.
    """
    q = as_positive(t_max, "t_max", allow_zero=True)
    r = as_positive(t_min, "t_min", allow_zero=True)
    if np.any(q > 1) or np.any(r > q):
        raise ValueError("transmittances must satisfy 0 <= t_min <= t_max <= 1")
    q, r, angle = broadcast(t_max=q, t_min=r, angle=as_turn(angle, "angle", "axis angles"))
    M = np.zeros(q.shape + (4, 4))
    M[..., 0, 0] = M[..., 1, 1] = (q + r) / 2
    M[..., 0, 1] = M[..., 1, 0] = (q - r) / 2
    M[..., 2, 2] = M[..., 3, 3] = np.sqrt(q * r)
    return rotate_mueller(M, angle)


def linear_polarizer(angle=0.0, extinction_ratio=0.0) -> np.ndarray:
    """Linear polarizer at ``angle`` [rad]; ``extinction_ratio`` = t_min/t_max in [0, 1] (0: ideal).

    The ideal polarizer is ``0.5 [[1, c, s, 0], [c, c^2, cs, 0], [s, cs, s^2, 0], [0, 0, 0, 0]]``
    with ``c = cos 2a``, ``s = sin 2a``.

    Parameters
    ----------
    angle : array_like
        Transmission axis, from s towards p [rad], in [-2 pi, 2 pi] (degrees are refused).
    extinction_ratio : array_like
        ``t_min / t_max``, in [0, 1] (0: ideal polarizer).

    Returns
    -------
    M : ndarray, shape ``(..., 4, 4)``.
    """
    eps = as_positive(extinction_ratio, "extinction_ratio", allow_zero=True)
    if np.any(eps > 1):
        raise ValueError("extinction_ratio must be in [0, 1]")
    return diattenuator(1.0, eps, angle)


def linear_retarder(retardance, fast_axis=0.0) -> np.ndarray:
    r"""Linear retarder of retardance :math:`\delta` [rad] with fast axis at ``fast_axis`` [rad].

    With :math:`c = \cos 2\theta, s = \sin 2\theta`:
    ``[[1,0,0,0], [0, c^2+s^2 cos d, cs(1-cos d), -s sin d], [0, cs(1-cos d), s^2+c^2 cos d, c sin d],
    [0, s sin d, -c sin d, cos d]]`` -- for a quarter-wave plate with vertical (p) fast axis
    this is the matrix of Eq. 39.

    Parameters
    ----------
    retardance : array_like
        Retardance :math:`\delta` [rad].
    fast_axis : array_like
        Fast-axis angle :math:`\theta`, from s towards p [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    M : ndarray, shape ``(..., 4, 4)``.
    """
    d, t = broadcast(
        retardance=as_finite(retardance, "retardance"),
        fast_axis=as_turn(fast_axis, "fast_axis", "fast-axis angles"),
    )
    M = np.zeros(d.shape + (4, 4))
    M[..., 0, 0] = M[..., 1, 1] = 1
    M[..., 2, 2] = M[..., 3, 3] = np.cos(d)
    M[..., 2, 3] = np.sin(d)
    M[..., 3, 2] = -np.sin(d)
    return rotate_mueller(M, t)


def rotator(rotation_angle) -> np.ndarray:
    """Optical rotator turning linear polarization by ``rotation_angle`` [rad] (towards p).

    Parameters
    ----------
    rotation_angle : array_like
        Rotation angle, towards p [rad], in [-2 pi, 2 pi] (degrees are refused).

    Returns
    -------
    ndarray, shape (..., 4, 4)
        Mueller matrix of the rotator.
    """
    return _frame_rotation(-as_turn(rotation_angle, "rotation_angle", "rotation angles"))


def depolarizer(a=0.0) -> np.ndarray:
    """Diagonal depolarizer ``diag(1, a1, a2, a3)``; ``a`` scalar or ``(..., 3)`` with ``|a_k| <= 1``.

    ``a = 0`` is the ideal depolarizer. Realizability additionally requires
    ``1 +- a1 +- a2 +- a3 >= 0`` with an even number of minus signs among a's,
    which :func:`is_physical_mueller` checks.

    Parameters
    ----------
    a : array_like, scalar or shape (..., 3)
        Diagonal coefficients ``(a1, a2, a3)`` (a scalar is used for all three), ``|a_k| <= 1``.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``diag(1, a1, a2, a3)``.
    """
    a = as_finite(a, "a")
    if a.ndim == 0 or a.shape[-1] != 3:
        a = np.stack([a, a, a], -1)
    if np.any(np.abs(a) > 1):
        raise ValueError("depolarizer coefficients a must satisfy |a| <= 1")
    M = np.zeros(a.shape[:-1] + (4, 4))
    M[..., 0, 0] = 1
    M[..., 1, 1], M[..., 2, 2], M[..., 3, 3] = a[..., 0], a[..., 1], a[..., 2]
    return M


def coherency_matrix(M) -> np.ndarray:
    r"""Cloude coherency matrix :math:`H = \tfrac14\sum M_{ij}\sigma_i\otimes\sigma_j^*`, shape
    ``(..., 4, 4)``, Hermitian.

    ``trace(H) = M00``; ``H`` is positive semi-definite iff ``M`` is physically realizable.

    Parameters
    ----------
    M : array_like, shape (..., 4, 4)
        Mueller matrix or matrices.

    Returns
    -------
    ndarray, shape (..., 4, 4), complex
        Hermitian coherency matrix ``H``.
    """
    M = as_finite(M, "M")
    if M.shape[-2:] != (4, 4):
        raise ValueError(f"M must have shape (..., 4, 4), got {M.shape}")
    return 0.25 * np.einsum("...ij,ijab->...ab", M, _BASIS)


def mueller_from_coherency(H) -> np.ndarray:
    """Inverse of :func:`coherency_matrix`: ``M_ij = Re tr(B_ij^H H)``, shape ``(..., 4, 4)``.

    Parameters
    ----------
    H : array_like, shape (..., 4, 4)
        Coherency matrix or matrices.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        Real Mueller matrix.
    """
    H = np.asarray(H, complex)
    if H.ndim < 2 or H.shape[-2:] != (4, 4):
        raise ValueError(f"H must have shape (..., 4, 4) (a 4x4 coherency matrix), got {H.shape}")
    return np.einsum("ijab,...ab->...ij", _BASIS.conj(), H).real


def is_physical_mueller(M, atol: float = 1e-10) -> np.ndarray:
    """True where the coherency eigenvalues are >= ``-atol * M00`` (Cloude's criterion).

    Parameters
    ----------
    M : array_like, shape ``(..., 4, 4)``
    atol : float, relative tolerance for rounding.

    Returns
    -------
    ndarray of bool, shape ``(...)``.
    """
    H = coherency_matrix(M)
    lam = np.linalg.eigvalsh(H)
    scale = np.maximum(np.abs(np.asarray(M)[..., 0, 0]), np.finfo(float).tiny)
    return lam[..., 0] >= -atol * scale


def nearest_physical_mueller(M) -> np.ndarray:
    """Nearest physically realizable Mueller matrix (Cloude filtering).

    Negative eigenvalues of the coherency matrix are set to zero and the matrix
    is rebuilt. Because ``M -> H`` is an isometry up to a constant factor
    (Frobenius norms), this is the Frobenius-nearest realizable Mueller matrix.

    Parameters
    ----------
    M : array_like, shape ``(..., 4, 4)``

    Returns
    -------
    ndarray, shape ``(..., 4, 4)``; unchanged (to rounding) where ``M`` is already physical.
    """
    H = coherency_matrix(M)
    lam, V = np.linalg.eigh(H)
    lam = np.clip(lam, 0.0, None)
    Hf = (V * lam[..., None, :]) @ np.conj(np.swapaxes(V, -1, -2))
    return mueller_from_coherency(Hf)
