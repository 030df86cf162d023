r"""Iterative solver for the rough-surface EFIE: block forward-backward (Holliday, DeRaad and St-Cyr, 1998).

Forward-backward computes the current in a forward sweep along the surface (each unknown from the already
updated ones before it and the previous iterate after it) followed by a backward sweep: symmetric
Gauss-Seidel. Here the sweeps go over blocks of ``block`` unknowns, each block solved with its own LU
(block size 1 is Holliday's original). For rough surfaces at moderate grazing the coupling is dominated by the
forward and backward propagating parts, and a few iterations reach 1e-6. Stopping: the relative change of
the current over one iteration below ``tol`` (no extra matrix product; the final residual is reported);
divergence: the change grows for two iterations in a row or exceeds
1e3 -- the caller falls back to LU.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg

from scatterlab._checks import as_count

__all__ = ["forward_backward"]


def forward_backward(A, V, *, tol: float = 1e-6, max_iter: int = 50, block: int = 256):
    """Solve ``A U = V`` by block forward-backward iteration.

    Parameters
    ----------
    A : ndarray, shape (N, N)
        System matrix.
    V : ndarray, shape (N,) or (N, K)
        Right-hand side(s).
    tol : float
        Stop when the relative change of U per iteration is below this.
    max_iter : int
        Maximum number of forward-backward sweep pairs.
    block : int
        Size of the diagonal blocks solved directly.

    Returns
    -------
    U : ndarray, shape of ``V``, complex
        The solution.
    info : dict
        ``converged`` (bool), ``iterations`` (int), ``updates`` (relative change of U per
        iteration), ``residual`` (final ``||A U - V|| / ||V||``), ``reason`` (str).

    Raises
    ------
    ValueError
        ``block`` not an integer >= 1, ``max_iter`` not an integer >= 1, ``tol`` not finite and > 0.
    """
    as_count(block, "block", 1, " (rows per diagonal block)")
    as_count(max_iter, "max_iter", 1)
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be finite and > 0 (relative change of U), got {tol!r}")
    N = A.shape[0]
    V2 = V if V.ndim == 2 else V[:, None]
    starts = list(range(0, N, block))
    blocks = [slice(s, min(N, s + block)) for s in starts]
    lus = [linalg.lu_factor(A[b, b], check_finite=False) for b in blocks]
    U = np.zeros_like(V2, dtype=complex)
    norm_v = np.linalg.norm(V2, axis=0)
    U_old = np.zeros_like(U)
    updates = []
    info = {"converged": False, "iterations": 0, "updates": updates, "reason": "max_iter reached"}
    for it in range(max_iter):
        for bi, b in enumerate(blocks):  # forward sweep
            rhs = V2[b] - A[b, : b.start] @ U[: b.start] - A[b, b.stop :] @ U[b.stop :]
            U[b] = linalg.lu_solve(lus[bi], rhs, check_finite=False)
        for bi in range(len(blocks) - 1, -1, -1):  # backward sweep
            b = blocks[bi]
            rhs = V2[b] - A[b, : b.start] @ U[: b.start] - A[b, b.stop :] @ U[b.stop :]
            U[b] = linalg.lu_solve(lus[bi], rhs, check_finite=False)
        # the relative change of U needs no extra product with A (one sweep pair already costs two)
        r = float(
            np.max(
                np.linalg.norm(U - U_old, axis=0) / np.maximum(np.linalg.norm(U, axis=0), 1e-300)
            )
        )
        U_old[...] = U
        updates.append(r)
        info["iterations"] = it + 1
        if not np.isfinite(r) or r > 1e3:
            info["reason"] = f"diverged (update {r:.3g})"
            break
        if r < tol:
            info["converged"] = True
            info["reason"] = "converged"
            break
        if len(updates) >= 3 and updates[-1] > updates[-2] > updates[-3]:
            info["reason"] = f"diverging (update grew twice, now {r:.3g})"
            break
    with np.errstate(all="ignore"):
        info["residual"] = float(np.max(np.linalg.norm(A @ U - V2, axis=0) / norm_v))
    return (U if V.ndim == 2 else U[:, 0]), info
