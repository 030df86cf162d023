r"""Eigenvalue Calibration Method (Compain, Poirier, Drevillon, Appl. Opt. 38, 3490, 1999; Ref. 25).

From the intensity matrix without a sample, :math:`\mathbf B_0 = \mathbf A\mathbf W`, and those of
reference samples, :math:`\mathbf B_i = \mathbf A\mathbf M_i\mathbf W`:

1. :math:`\mathbf C_i = \mathbf B_0^{-1}\mathbf B_i = \mathbf W^{-1}\mathbf M_i\mathbf W` has the
   eigenvalues of :math:`\mathbf M_i`. A linear diattenuating retarder of transmission :math:`\tau`,
   diattenuation angle :math:`\Psi` and retardance :math:`\Delta` has eigenvalues
   :math:`2\tau\cos^2\Psi`, :math:`2\tau\sin^2\Psi` and :math:`\tau\sin2\Psi\,e^{\pm j\Delta}`; they
   give :math:`(\tau,\Psi,\Delta)` without knowing W or A.
2. With the references' azimuths :math:`\theta_i`, :math:`\mathbf M_i` is known and W solves the
   linear system :math:`\mathbf M_i\mathbf X - \mathbf X\mathbf C_i = 0` for all i: W spans the null
   space of :math:`\mathbf K = \sum_i \mathbf H_i^T\mathbf H_i` (16x16), taken as the eigenvector of
   its smallest eigenvalue :math:`\lambda_{16}`. The azimuths are fitted by minimising
   :math:`\lambda_{16}` (one azimuth is fixed: a common rotation of every reference is a gauge
   freedom that rotates W and A with it).
3. :math:`\mathbf A = \mathbf B_0\mathbf W^{-1}`, and a sample is :math:`\mathbf M = \mathbf
   A^{-1}\mathbf B\mathbf W^{-1}` (Eq. 184).

The quality diagnostic :math:`\lambda_{16}/\lambda_{15}` vanishes without noise and grows as the
square of the noise (tested). W and A are determined up to one overall scale, fixed here by
``mean(W[0]) = 1``; the sample Mueller matrix does not depend on it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from scatterlab._checks import as_finite, as_positive
from scatterlab.polarization.mueller import nearest_physical_mueller, rotate_mueller

__all__ = ["ecm_calibrate", "ECMCalibration", "reference_parameters", "reference_mueller"]

KINDS = ("polarizer", "retarder")
_EPS = float(np.finfo(float).eps)  # the least tolerance scipy's Levenberg-Marquardt accepts


def _check_matrix(B, name) -> np.ndarray:
    B = np.asarray(B, dtype=float)
    if B.shape != (4, 4):
        raise ValueError(f"{name} must be a 4x4 intensity matrix, got shape {B.shape}")
    if not np.all(np.isfinite(B)):
        raise ValueError(f"{name} contains NaN or inf intensities")
    return B


def reference_parameters(C: np.ndarray, kind: str) -> tuple[float, float, float]:
    """(tau, Psi, Delta) of a reference from the eigenvalues of ``C = B0^-1 B`` (step 1).

    Parameters
    ----------
    C : ndarray (4, 4)
        ``B0^-1 B`` of the reference (similar to its Mueller matrix), finite.
    kind : {"polarizer", "retarder"}

    Returns
    -------
    tau : float
        Transmission.
    psi : float [rad]
        Diattenuation angle.
    delta : float [rad]
        Retardance in [0, pi].

    Notes ----- The eigenvalues are ``2 tau cos^2 Psi``, ``2 tau sin^2 Psi`` and the pair ``tau sin
    2Psi exp(+-j Delta)``. ``2 Psi = atan2(sin 2Psi, cos 2Psi)`` with ``sin 2Psi`` from the pair
    (their product is ``tau^2 sin^2 2Psi``) and ``cos 2Psi`` from the real pair: both linear in the
    noise, unlike ``atan(sqrt(l2/l1))`` or ``arcsin``, which amplify noise to its square root near
    Psi = 0 (polarizers) or 45 deg (retarders). For a retarder the pair is the one with the largest
    imaginary parts; for a polarizer it is the two eigenvalues between the largest and the smallest
    in magnitude.

    Raises
    ------
    ValueError
        ``C`` not a finite 4x4 matrix, ``kind`` not one of ``"polarizer"``, ``"retarder"``, or no
        transmitted intensity (``tau <= 0``).
    """
    C = _check_matrix(C, "C")
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    lam = np.linalg.eigvals(C)
    if kind == "retarder":
        order = np.argsort(-np.abs(lam.imag))
        pair, real = lam[order[:2]], np.sort(lam[order[2:]].real)[::-1]
    else:
        order = np.argsort(-np.abs(lam))
        real = np.array([lam[order[0]].real, lam[order[3]].real])
        pair = lam[order[1:3]]
    tau = (
        0.5 * real[0] + 0.5 * real[1]
    )  # halves first: no overflow for matrices near the float limit
    if tau <= 0:
        raise ValueError(
            f"a {kind} reference has no transmitted intensity (check its intensity matrix)"
        )
    # both estimates are linear in the noise: sin 2Psi from the pair (accurate near Psi = 0,
    # polarizers), cos 2Psi = (l1 - l2)/(l1 + l2) from the real ones (accurate near 45 deg,
    # retarders); atan2 uses each where it is well conditioned
    sin2psi = float(np.sqrt(np.abs(pair[0])) * np.sqrt(np.abs(pair[1]))) / tau
    cos2psi = (0.5 * real[0] - 0.5 * real[1]) / tau
    psi = 0.5 * float(np.arctan2(sin2psi, cos2psi))
    top = pair[np.argmax(pair.imag)]
    delta = float(np.abs(np.angle(top))) if np.abs(top) > 0 else 0.0
    return float(tau), psi, delta


def reference_mueller(tau, psi, delta, azimuth) -> np.ndarray:
    """Mueller matrix of a linear diattenuating retarder.

    Parameters
    ----------
    tau : float
        Transmission, finite and ``>= 0``.
    psi, delta : float [rad]
        Diattenuation angle and retardance (finite).
    azimuth : float [rad]
        Orientation of the element (finite).

    Returns
    -------
    ndarray (4, 4)

    Raises
    ------
    ValueError
        A negative or non-finite ``tau``, or a non-finite angle.
    """
    tau = float(as_positive(tau, "tau (transmission)", allow_zero=True))
    psi, delta, azimuth = (
        float(as_finite(v, nm)) for v, nm in ((psi, "psi"), (delta, "delta"), (azimuth, "azimuth"))
    )
    return _reference_mueller(tau, psi, delta, azimuth)


def _reference_mueller(tau, psi, delta, azimuth) -> np.ndarray:
    """:func:`reference_mueller` unchecked (the refinements' residuals: a trial tau may be < 0)."""
    c2, s2 = np.cos(2 * psi), np.sin(2 * psi)
    M0 = tau * np.array(
        [
            [1, c2, 0, 0],
            [c2, 1, 0, 0],
            [0, 0, s2 * np.cos(delta), s2 * np.sin(delta)],
            [0, 0, -s2 * np.sin(delta), s2 * np.cos(delta)],
        ]
    )
    return rotate_mueller(M0, azimuth)


def _K(Ms, Cs) -> np.ndarray:
    eye = np.eye(4)
    K = np.zeros((16, 16))
    for M, C in zip(Ms, Cs):
        H = np.kron(M, eye) - np.kron(eye, C.T)  # row-major vec: vec(MX - XC)
        K += H.T @ H
    return K


@dataclass
class ECMCalibration:
    """Result of :func:`ecm_calibrate`.

    Attributes
    ----------
    W, A : ndarray (4, 4)
        PSG and PSA matrices (overall scale fixed by ``mean(W[0]) = 1``).
    quality : float
        lambda_16 / lambda_15 of K (0 without noise, ~noise^2).
    references : list of dict
        Per reference: kind, tau, psi, delta [rad], azimuth [rad] (fitted, except the first).
    eigenvalues : ndarray (16,)
        Eigenvalues of K, descending.
    cond_W, cond_A : float
    """

    W: np.ndarray
    A: np.ndarray
    quality: float
    references: list
    eigenvalues: np.ndarray
    cond_W: float
    cond_A: float
    _Ainv: np.ndarray = field(repr=False, default=None)
    _Winv: np.ndarray = field(repr=False, default=None)

    def __post_init__(self):
        self._Ainv = np.linalg.inv(self.A)
        self._Winv = np.linalg.inv(self.W)

    def mueller(self, B, *, physical: bool = False) -> np.ndarray:
        """Sample Mueller matrices ``A^-1 B W^-1`` (Eq. 184) from measured intensities.

        Parameters
        ----------
        B : array_like (..., 4, 4)
            Intensity matrices, finite (vectorised over leading axes: Mueller-matrix images).
        physical : bool
            Project each result onto the nearest physically realizable Mueller matrix (Cloude
            filtering).

        Returns
        -------
        ndarray (..., 4, 4)
            Mueller matrices (dimensionless; the overall scale of W and A cancels).

        Raises
        ------
        ValueError
            ``B`` not of shape (..., 4, 4), or NaN/inf intensities.
        """
        B = np.asarray(B, float)
        if B.ndim < 2 or B.shape[-2:] != (4, 4):
            raise ValueError(f"B must have shape (..., 4, 4), got {B.shape}")
        if not np.all(np.isfinite(B)):
            raise ValueError("B (sample intensities) must be finite: NaN or inf found")
        M = self._Ainv @ B @ self._Winv
        return nearest_physical_mueller(M) if physical else M


def _refine(B0, Bs, W, A, params, azimuths, fixed_index=0):
    """Least-squares refinement of W, A and every reference's (tau, Psi, Delta, azimuth) against all
    the measured intensities (B0 = A W, B_i = A M_i W): the maximum-likelihood estimate for Gaussian
    detector noise, started from the ECM solution. Gauges fixed: mean(W[0]) = 1 and the first
    azimuth."""
    n_ref = len(Bs)

    def unpack(x):
        w = x[:15]
        W_ = np.concatenate([[4.0 - w[:3].sum()], w]).reshape(4, 4)  # mean(W[0]) = 1
        A_ = x[15:31].reshape(4, 4)
        rest = x[31:].reshape(n_ref, 4)
        return W_, A_, rest

    def residual(x):
        W_, A_, rest = unpack(x)
        out = [(A_ @ W_ - B0).ravel()]
        for i, B in enumerate(Bs):
            tau, psi, delta, az = rest[i]
            if i == fixed_index:
                az = azimuths[fixed_index]
            out.append((A_ @ _reference_mueller(tau, psi, delta, az) @ W_ - B).ravel())
        return np.concatenate(out)

    x0 = np.concatenate(
        [W.ravel()[1:], A.ravel(), np.array([[*p, a] for p, a in zip(params, azimuths)]).ravel()]
    )
    res = optimize.least_squares(
        residual, x0, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=50 * x0.size
    )
    W_, A_, rest = unpack(res.x)
    rest[fixed_index, 3] = azimuths[fixed_index]
    return W_, A_, [tuple(r[:3]) for r in rest], list(rest[:, 3])


def _parse_references(B0, references):
    """Validate ``B0`` and the references; returns ``(B0, Bs, kinds, Cs, guesses)`` with ``C_i =
    B0^-1 B_i``.
    """
    B0 = _check_matrix(B0, "B0")
    if np.linalg.cond(B0) > 1e12:
        raise ValueError(
            "B0 is singular (cond > 1e12): the PSG and PSA must each produce four independent "
            "states"
        )
    refs = list(references)
    if len(refs) < 2:
        raise ValueError(
            "references must hold at least two samples (e.g. polarizers at 0, 60, 120 deg and a "
            "retarder)"
        )
    kinds, Bs, Cs, guesses = [], [], [], []
    for k, ref in enumerate(refs):
        if len(ref) not in (2, 3):
            raise ValueError("each reference must be (kind, B) or (kind, B, azimuth)")
        kind = ref[0]
        if kind not in KINDS:
            raise ValueError(f"reference kind must be one of {KINDS}, got {kind!r}")
        B = _check_matrix(ref[1], f"references[{k}] intensities")
        kinds.append(kind)
        Bs.append(B)
        Cs.append(np.linalg.solve(B0, B))
        guesses.append(float(ref[2]) if len(ref) == 3 else None)
    if "retarder" not in kinds:
        raise ValueError(
            "degenerate reference set: at least one retarder is needed (polarizers alone leave the "
            "circular part of W undetermined)"
        )
    return B0, Bs, kinds, Cs, guesses


class _AzimuthProblem:
    """Step 2 of ECM for fixed reference parameters: K(azimuths), its null vector and the residuals
    ``H_i w``. The first azimuth is held at ``fixed`` (gauge); ``free`` are the others."""

    def __init__(self, params, Cs, fixed):
        self.params, self.Cs, self.fixed = params, Cs, fixed

    def muellers(self, free):
        az = [self.fixed] + list(free)
        return [_reference_mueller(*p, a) for p, a in zip(self.params, az)]

    def eig(self, free):
        """Eigenvalues (ascending) and eigenvectors of K."""
        return np.linalg.eigh(_K(self.muellers(free), self.Cs))

    def objective(self, free):
        lam, _ = self.eig(free)
        return lam[0] / lam[-1]

    def residual(self, free, w_ref):
        # r = [H_i w] with w the null vector of K: |r|^2 = lambda_16, but r is linear in the azimuth
        # errors, so least squares converges to rounding where minimising lambda_16 stalls at
        # sqrt(eps)
        Ms = self.muellers(free)
        lam, vec = np.linalg.eigh(_K(Ms, self.Cs))
        w = vec[:, 0] * (1.0 if vec[:, 0] @ w_ref >= 0 else -1.0)
        eye = np.eye(4)
        r = [(np.kron(M, eye) - np.kron(eye, C.T)) @ w for M, C in zip(Ms, self.Cs)]
        return np.concatenate(r) / np.sqrt(lam[-1])


def _start_azimuths(problem, kinds, guesses, grid):
    """Nominal azimuths where given; a coarse grid search over [0, pi) for the others.

    A retarder's fast axis is searched in [0, pi/2): ECM cannot tell (Delta, theta) from (-Delta,
    theta + pi/2) -- the handedness of S3 -- without a nominal azimuth; and the first free azimuth
    in [0, pi/2): the mirror theta -> -theta (S2 -> -S2) is the other ambiguity a nominal azimuth
    would resolve.
    """
    if all(g is not None for g in guesses[1:]):
        return np.array(guesses[1:], float)
    x0 = np.array([g if g is not None else 0.0 for g in guesses[1:]])
    free_idx = [i for i, g in enumerate(guesses[1:]) if g is None]
    axes = [
        np.linspace(
            0,
            np.pi / (2 if (kinds[i + 1] == "retarder" or i == free_idx[0]) else 1),
            grid,
            endpoint=False,
        )
        for i in free_idx
    ]
    best = (np.inf, x0)
    for combo in np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(free_idx), -1).T:
        x = x0.copy()
        x[free_idx] = combo
        val = problem.objective(x)
        if val < best[0]:
            best = (val, x)
    return best[1]


def _fit_azimuths(problem, x0, fit_tolerance):
    """Levenberg-Marquardt on the residuals ``H_i w``; returns the free azimuths and K's
    eigen-decomposition.
    """
    w_ref = problem.eig(x0)[1][:, 0]
    res = optimize.least_squares(
        problem.residual,
        x0,
        args=(w_ref,),
        method="lm",
        xtol=fit_tolerance,
        ftol=1e-15,
        gtol=1e-15,
        max_nfev=200 * (x0.size + 1),
    )
    lam, vec = problem.eig(res.x)
    if lam[1] < 1e-9 * lam[-1]:
        raise ValueError(
            "degenerate reference set: K has more than one null vector, so W is not determined "
            "(use polarizers at two or more azimuths and a retarder)"
        )
    return res.x, lam, vec


def ecm_calibrate(
    B0,
    references,
    *,
    fit_tolerance: float = 1e-12,
    warn_condition: float = 50.0,
    grid: int = 12,
    refine: bool = True,
) -> ECMCalibration:
    """Calibrate W and A of a Mueller ellipsometer by the Eigenvalue Calibration Method.

    Parameters
    ----------
    B0 : array_like (4, 4)
        Intensities with no sample (straight-through), ``A W``.
    references : sequence of (kind, B) or (kind, B, azimuth)
        ``kind`` is ``"polarizer"`` or ``"retarder"``; ``B`` its 4x4 intensities; ``azimuth`` [rad]
        its nominal orientation (start of the fit). The first reference's azimuth (0 when not given)
        is held fixed and defines the frame; without nominal azimuths the others start from a coarse
        grid search (retarders' fast axes and the second reference's azimuth in [0, 90) deg: the
        signs of S3 and S2 are otherwise undetermined, see Notes). The reference text's set:
        polarizer at 0, 60 and 120 deg and a quarter-wave plate at 45 deg.
    fit_tolerance : float
        Relative convergence tolerance of the azimuth fit (Levenberg-Marquardt on the residuals
        ``H_i w``; an accuracy knob, see the performance study); finite, >= machine epsilon.
    warn_condition : float
        Warn when cond(W) or cond(A) exceeds this.
    grid : int
        Grid points per free azimuth for the coarse search.
    refine : bool
        Follow ECM by a least-squares fit of W, A and the references' parameters to all measured
        intensities (maximum likelihood for Gaussian noise; about 3x smaller azimuth errors at 1e-3
        noise). ``refine=False`` returns the algebraic ECM solution.

    Returns
    -------
    ECMCalibration
        ``W``, ``A`` (4, 4), the references' fitted parameters, the quality diagnostic and condition
        numbers; ``.mueller(B)`` turns sample intensities into Mueller matrices.

    Raises
    ------
    ValueError
        Wrong shapes, NaN intensities, a singular ``B0``, an unknown kind, a ``fit_tolerance`` out
        of range, or a degenerate reference set (e.g. no retarder): W is then not determined.

    Notes
    -----
    Steps (module docstring): eigenvalues of ``C_i`` give each reference's (tau, Psi, Delta); the
    azimuths are fitted so that K has a null vector, which is W; ``A = B0 W^-1``; optionally all of
    it is refined. If W solves the ECM equations with a retarder (Delta, theta), then ``diag(1, 1, 1, -1) W``
    solves them with (-Delta, theta), i.e. the fast axis at theta + 90 deg: the handedness of
    circular polarization is fixed only by knowing which axis of the retarder is fast. Likewise the
    mirror image of every azimuth (theta -> -theta) with ``diag(1, 1, -1, -1) W`` is a solution: the
    sense of rotation of the azimuths, i.e. the sign of S2, is fixed by the nominal azimuths.
    """
    fit_tolerance = float(as_finite(fit_tolerance, "fit_tolerance"))
    if not fit_tolerance >= _EPS:
        raise ValueError(
            f"fit_tolerance must be a finite number >= {_EPS:.3g} (machine epsilon), "
            f"got {fit_tolerance!r}"
        )
    B0, Bs, kinds, Cs, guesses = _parse_references(B0, references)
    params = [reference_parameters(C, kind) for C, kind in zip(Cs, kinds)]  # step 1: eigenvalues
    problem = _AzimuthProblem(params, Cs, guesses[0] if guesses[0] is not None else 0.0)
    start = _start_azimuths(problem, kinds, guesses, grid)
    free, lam, vec = _fit_azimuths(problem, start, fit_tolerance)  # step 2: W is K's null vector
    W = vec[:, 0].reshape(4, 4)
    W = W / np.mean(W[0])
    A = np.linalg.solve(W.T, B0.T).T  # step 3: A = B0 W^-1
    azimuths = [problem.fixed] + list(free)
    if refine:
        W, A, params, azimuths = _refine(B0, Bs, W, A, params, azimuths)
    cond_W, cond_A = np.linalg.cond(W), np.linalg.cond(A)
    _warn_conditioning(cond_W, cond_A, warn_condition)
    return ECMCalibration(
        W=W,
        A=A,
        quality=float(lam[0] / lam[1]),
        references=_reference_table(kinds, params, azimuths),
        eigenvalues=lam[::-1].copy(),
        cond_W=float(cond_W),
        cond_A=float(cond_A),
    )


def _warn_conditioning(cond_W: float, cond_A: float, limit: float) -> None:
    """RuntimeWarning when cond(W) or cond(A) exceeds ``limit`` (noise is amplified by it)."""
    if max(cond_W, cond_A) > limit:
        warnings.warn(
            f"ill-conditioned calibration: cond(W) = {cond_W:.1f}, cond(A) = {cond_A:.1f} "
            f"(> {limit}); Mueller errors will be amplified",
            RuntimeWarning,
            stacklevel=3,
        )


def _reference_table(kinds, params, azimuths) -> list[dict]:
    """One dict per reference: kind, tau, psi, delta [rad] and azimuth in [0, pi) [rad]."""
    return [
        {
            "kind": k,
            "tau": float(p[0]),
            "psi": float(p[1]),
            "delta": float(p[2]),
            "azimuth": float(np.mod(a, np.pi)),
        }
        for k, p, a in zip(kinds, params, azimuths)
    ]
