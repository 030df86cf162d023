r"""Thilak et al.'s two-step estimate of (n, kappa) and theta_r from DOP (Eqs. 115-117), the comparison baseline.

Forward model (Eq. 115, with the errata's A and B): the DOP of unpolarized light reflected by smooth facets
at the facet angle :math:`\beta = (\theta_i + \theta_r)/2`,

.. math:: P(n, \kappa, \beta) = \frac{2A\sin^2\beta\cos\beta}{A^2\cos^2\beta + \sin^4\beta + B^2\cos^2\beta},
   \quad A = \sqrt{(\sqrt C + D)/2},\ B = \sqrt{(\sqrt C - D)/2},\ C = 4n^2\kappa^2 + D^2,\
   D = n^2 - \kappa^2 - \sin^2\beta.

Step 1 (Eq. 116): unconstrained nonlinear least squares (Levenberg-Marquardt) of (n, kappa) with
:math:`\beta_j` from the nominal theta_r. Step 2 (Eq. 117): with (n, kappa) fixed, least squares of theta_r.
As the authors did, a solution outside the physical range (n or kappa < 0, theta_r outside (0, 90) deg) is
discarded and the fit restarted (from a random start drawn with ``rng``); after ``max_restarts`` the trial is
reported as failed (NaN).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from scatterlab._checks import ETA_MIN, as_angle
from scatterlab.fresnel import smooth_dolp

__all__ = ["thilak_dop", "thilak_two_step", "ThilakFit"]


def thilak_dop(n, kappa, beta) -> np.ndarray:
    """Eq. 115 for any real (n, kappa) (the unconstrained fit may visit negative values); broadcasts.

    Eq. 115 depends on ``n`` and ``kappa`` through ``n^2``, ``kappa^2`` and ``(n kappa)^2`` only, and
    for ``n, kappa >= 0`` it is the smooth-facet DOLP ``(Rs - Rp)/(Rs + Rp)``: this evaluates the
    package's kernel :func:`scatterlab.fresnel.smooth_dolp` at ``|n| - j|kappa|`` (tested equal to
    the printed formula with the errata's A and B), continued as an odd function of ``cos(beta)``
    like the printed formula.

    Parameters
    ----------
    n, kappa : array_like
        Real and imaginary parts of the index (any sign).
    beta : array_like [rad]
        Facet angle.

    Returns
    -------
    ndarray, broadcast shape.
    """
    n, kappa, beta = np.broadcast_arrays(
        np.abs(np.asarray(n, float)), np.abs(np.asarray(kappa, float)), np.asarray(beta, float)
    )
    eta = n - 1j * kappa
    eta = np.where(np.abs(eta) < ETA_MIN, ETA_MIN, eta)  # n = kappa = 0: the limit |eta| -> 0
    c = np.cos(beta)  # the fit may visit beta > 90 deg, where Eq. 115 is odd in cos(beta)
    return np.sign(c) * smooth_dolp(eta, np.abs(c), np.sin(beta) ** 2, checked=True)[0]


@dataclass
class ThilakFit:
    """Estimates per trial (K,): ``n``, ``kappa``, ``theta_r`` [rad]; ``restarts`` used; ``ok`` physical."""

    n: np.ndarray
    kappa: np.ndarray
    theta_r: np.ndarray
    restarts: np.ndarray
    ok: np.ndarray


def thilak_two_step(
    dop, theta_i, theta_r_nominal, rng, *, start=(1.0, 1.0), max_restarts: int = 50
) -> ThilakFit:
    """Thilak et al.'s two-step method for each row of ``dop`` (K, M) measured at ``theta_i`` (M,).

    Parameters
    ----------
    dop : array (K, M) or (M,)
    theta_i : array (M,) [rad]
    theta_r_nominal : float [rad] -- the known reflection angle of step 1 and the start of step 2.
    rng : numpy.random.Generator -- restarts.
    start : (n, kappa) of the first attempt.

    Returns
    -------
    ThilakFit
    """
    y = np.atleast_2d(np.asarray(dop, float))
    ti = as_angle(theta_i, "theta_i").ravel()
    tr0 = float(as_angle(theta_r_nominal, "theta_r_nominal"))
    if y.shape[-1] != ti.size:
        raise ValueError(
            f"dop must have {ti.size} values per trial (one per theta_i), got shape {y.shape}"
        )
    if ti.size < 3:
        raise ValueError(
            "theta_i must hold at least 3 measurements (Eq. 116 has two unknowns plus theta_r)"
        )
    beta = (ti + tr0) / 2
    K = y.shape[0]
    out = np.full((K, 3), np.nan)
    restarts = np.zeros(K, int)
    for k, row in enumerate(y):
        x0 = np.array(start, float)
        for attempt in range(max_restarts + 1):
            r1 = optimize.least_squares(
                lambda p, row=row: thilak_dop(p[0], p[1], beta) - row, x0, method="lm"
            )
            n, kap = r1.x
            ok = n >= 0 and kap >= 0
            if ok:
                r2 = optimize.least_squares(
                    lambda t, row=row, n=n, kap=kap: thilak_dop(n, kap, (ti + t[0]) / 2) - row,
                    [tr0],
                    method="lm",
                )
                t_r = float(r2.x[0])
                ok = 0 < t_r < np.pi / 2
            if ok:
                out[k] = n, kap, t_r
                break
            restarts[k] += 1
            x0 = np.array([rng.uniform(0, 5), rng.uniform(0, 10)])
    ok = np.isfinite(out[:, 0])
    return ThilakFit(n=out[:, 0], kappa=out[:, 1], theta_r=out[:, 2], restarts=restarts, ok=ok)
