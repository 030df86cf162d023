r"""Least-squares inversion of (n, kappa, sigma) from multi-geometry DOLP (Sec. 7.2.2, Eqs. 199-204).

The forward model is the pBRDF DOLP of :class:`scatterlab.pbrdf.Model` (Eq. 203 in the specular plane).
:func:`fit_dolp` solves, for every pixel of a batch at once,

.. math:: \min_{n,\kappa,\sigma} \sum_j [\mathcal P^{thy}(n - j\kappa, \sigma; \theta_{i,j}, \theta_{r,j}, \phi_j) - \mathcal P_j]^2

with a vectorised Levenberg-Marquardt iteration in numpy (analytic Jacobian, per-pixel damping,
bounds by projection), from several starting points so that the metal/dielectric ambiguity does not trap a
pixel in a local minimum; the best start wins per pixel. NaN measurements are masked (left out of the
residuals); a pixel with fewer valid measurements than unknowns is reported, not fitted. The parameter
covariance is the Laplace approximation :math:`s^2 (J^TJ)^{-1}` at the solution (``noise`` given: its
variance instead of the residual variance). :func:`fit_dolp_per_pixel` is the per-pixel
``scipy.optimize.least_squares`` baseline.

Default bounds follow the reference (n in [0, 5], kappa in [0, 25]); sigma in [0.01, 1.5].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from scatterlab._checks import as_angle
from scatterlab.inversion.forward import DolpForward
from scatterlab.pbrdf import Model

__all__ = ["fit_dolp", "fit_dolp_per_pixel", "DolpFit", "model_dolp", "DEFAULT_BOUNDS", "DEFAULT_STARTS"]

DEFAULT_BOUNDS = {"n": (0.0, 5.0), "kappa": (0.0, 25.0), "sigma": (0.01, 1.5)}
DEFAULT_STARTS = ((1.5, 0.05), (1.3, 3.0), (3.0, 4.0), (1.0, 10.0), (1.5, 18.0))


def model_dolp(n, kappa, sigma, theta_i, theta_r, phi=np.pi, **model_kw) -> np.ndarray:
    """pBRDF DOLP for parameters ``(...)`` and geometries ``(M,)`` -> ``(..., M)``."""
    n = np.maximum(np.asarray(n, float), 1e-6)[..., None]
    kappa = np.maximum(np.asarray(kappa, float), 0.0)[..., None]
    sigma = np.asarray(sigma, float)[..., None]
    return Model(sigma, **model_kw).dolp(n - 1j * kappa, theta_i, theta_r, phi)


@dataclass
class DolpFit:
    """Result of :func:`fit_dolp` (arrays over the batch's leading axes).

    Attributes
    ----------
    n, kappa, sigma : ndarray
    covariance : ndarray (..., P, P) -- Laplace approximation; P = 3 (or 2 with sigma known).
    cost : ndarray -- half the sum of squared residuals.
    converged : ndarray of bool
    valid : ndarray of bool -- enough finite measurements to fit.
    iterations : int
    """

    n: np.ndarray
    kappa: np.ndarray
    sigma: np.ndarray
    covariance: np.ndarray
    cost: np.ndarray
    converged: np.ndarray
    valid: np.ndarray
    iterations: int

    @property
    def eta(self) -> np.ndarray:
        return self.n - 1j * self.kappa

    @property
    def errors(self) -> np.ndarray:
        """1-sigma standard errors (..., P) from the covariance diagonal."""
        return np.sqrt(np.clip(np.diagonal(self.covariance, axis1=-2, axis2=-1), 0, None))


def _prepare(dolp, theta_i, theta_r, phi):
    y = np.asarray(dolp, float)
    ti = as_angle(theta_i, "theta_i").ravel()
    tr = as_angle(theta_r, "theta_r").ravel()
    ph = np.broadcast_to(np.asarray(phi, float), ti.shape)
    if ti.shape != tr.shape:
        raise ValueError("theta_i and theta_r must have one entry per measured geometry")
    if y.shape[-1:] != ti.shape:
        raise ValueError(f"dolp must have shape (..., {ti.size}) (one value per geometry), got {y.shape}")
    return y, ti, tr, ph


def _bounds(bounds, P):
    b = dict(DEFAULT_BOUNDS, **(bounds or {}))
    for name, (lo, hi) in b.items():
        if not lo < hi:
            raise ValueError(f"bounds[{name!r}] must be (low, high) with low < high, got {(lo, hi)}")
    if b["n"][0] < 0 or b["kappa"][0] < 0 or b["sigma"][0] < 1e-3 or b["sigma"][1] > 2.5:
        raise ValueError("bounds must keep n >= 0, kappa >= 0 and sigma within [1e-3, 2.5]")
    lo = np.array([b["n"][0], b["kappa"][0], b["sigma"][0]][:P])
    hi = np.array([b["n"][1], b["kappa"][1], b["sigma"][1]][:P])
    return lo, hi


def _levenberg_marquardt(forward, y0, mask, p, lo, hi, active, max_iter, tol):
    """Bounded LM from starts ``p`` (N, P) for N pixels at once; returns (p, cost, converged, iterations).

    Converged pixels leave the working set, so an iteration costs in proportion to the pixels still moving.
    A pixel converges when a successful step changes the cost by less than ``tol`` (relative) or moves every
    parameter by less than ``1e-10`` of its bound range, or when the damping grows past 1e10 without success.
    """
    N, P = p.shape
    p = p.copy()
    cost = np.full(N, np.nan)
    done = ~active
    idx = np.flatnonzero(active)
    f, J = forward.value_and_jacobian(p[idx], rows=idx)
    r = np.where(mask[idx], f - y0[idx], 0.0)
    c = 0.5 * np.sum(r * r, -1)
    lam = np.full(idx.size, 1e-3)
    xtol = 1e-10 * (hi - lo)
    iterations = 0
    for _ in range(max_iter):
        if idx.size == 0:
            break
        m = mask[idx]
        J = np.where(m[..., None], J, 0.0)
        A = np.einsum("nmi,nmj->nij", J, J)
        g = np.einsum("nmi,nm->ni", J, r)
        pi = p[idx]
        # active bounds: a parameter on its bound whose descent direction leaves the box is held there,
        # and the step is solved in the free subspace (projection alone stalls along the bound)
        held = ((pi <= lo) & (g > 0)) | ((pi >= hi) & (g < 0))
        free = ~held
        A = A * (free[:, :, None] & free[:, None, :]) + np.eye(P) * held[:, None, :]
        g = np.where(free, g, 0.0)
        diag = np.diagonal(A, axis1=-2, axis2=-1)
        A_damped = A + lam[:, None, None] * (np.eye(P) * (diag[:, None, :] + 1e-12))
        with np.errstate(all="ignore"):
            delta = -np.linalg.solve(A_damped, g[..., None])[..., 0]
        delta = np.where(np.isfinite(delta), delta, 0.0)
        p_new = np.clip(pi + delta, lo, hi)
        f_new, J_new = forward.value_and_jacobian(p_new, rows=idx)
        r_new = np.where(m, f_new - y0[idx], 0.0)
        c_new = 0.5 * np.sum(r_new * r_new, -1)
        better = c_new < c
        rel = np.where(better, (c - c_new) / np.maximum(c, 1e-300), 0.0)
        small_step = np.all(np.abs(p_new - pi) <= xtol, axis=-1)
        finished = (better & ((rel < tol) | small_step)) | (~better & (lam > 1e10)) | (np.minimum(c, c_new) < 1e-30)
        p[idx] = np.where(better[:, None], p_new, pi)
        r = np.where(better[:, None], r_new, r)
        J = np.where(better[:, None, None], J_new, J)
        c = np.where(better, c_new, c)
        lam = np.where(better, lam / 3, lam * 4)
        iterations += 1
        if np.any(finished):
            cost[idx[finished]] = c[finished]
            done[idx[finished]] = True
            keep = ~finished
            idx, r, J, c, lam = idx[keep], r[keep], J[keep], c[keep], lam[keep]
    cost[idx] = c  # not converged within max_iter: best point so far
    return p, cost, done, iterations


def fit_dolp(dolp, theta_i, theta_r, phi=np.pi, *, sigma=None, noise=None, bounds=None,
             starts=DEFAULT_STARTS, sigma0: float = 0.3, max_iter: int = 200, tol: float = 1e-12,
             **model_kw) -> DolpFit:
    """Batched bounded least squares of (n, kappa[, sigma]) to DOLP measured at M geometries.

    Every pixel runs a Levenberg-Marquardt iteration with its own damping, in one vectorised pass; the
    Jacobian is analytic in (n, kappa) (:class:`~scatterlab.inversion.forward.DolpForward`). Each start of
    ``starts`` is run for every pixel and the lowest cost wins per pixel.

    Parameters
    ----------
    dolp : array (..., M)
        Measured DOLP; NaN entries are masked.
    theta_i, theta_r : array (M,) [rad]
    phi : float or array (M,) [rad], default pi (specular plane)
    sigma : float or array (...), optional
        Known roughness; when given only (n, kappa) are fitted.
    noise : float or array (...), optional
        DOLP noise standard deviation for the covariance (default: estimated from the residuals).
    bounds : dict, optional
        ``{"n": (lo, hi), "kappa": (lo, hi), "sigma": (lo, hi)}``; defaults in ``DEFAULT_BOUNDS``.
    starts : sequence of (n, kappa)
    sigma0 : float -- starting roughness.
    max_iter, tol : Levenberg-Marquardt limits (iterations per start; relative cost decrease).

    Returns
    -------
    DolpFit
    """
    y, ti, tr, ph = _prepare(dolp, theta_i, theta_r, phi)
    fit_sigma = sigma is None
    P = 3 if fit_sigma else 2
    lo, hi = _bounds(bounds, P)
    batch = y.shape[:-1]
    mask = np.isfinite(y)
    valid = mask.sum(-1) >= P
    y0 = np.where(mask, y, 0.0)
    sig_known = None if fit_sigma else np.broadcast_to(np.asarray(sigma, float), batch)
    forward = DolpForward(ti, tr, ph, sigma=None if fit_sigma else sig_known.ravel(), **model_kw)

    y0f, maskf, validf = y0.reshape(-1, y.shape[-1]), mask.reshape(-1, y.shape[-1]), valid.ravel()
    best_p = best_cost = best_done = None
    total_iter = 0
    for n0, k0 in starts:
        p = np.empty((validf.size, P))
        p[:, 0], p[:, 1] = n0, k0
        if fit_sigma:
            p[:, 2] = sigma0
        p = np.clip(p, lo, hi)
        p, cost, done, it = _levenberg_marquardt(forward, y0f, maskf, p, lo, hi, validf, max_iter, tol)
        p, cost, done = p.reshape(batch + (P,)), cost.reshape(batch), done.reshape(batch)
        total_iter += it
        if best_p is None:
            best_p, best_cost, best_done = p, cost, done
        else:
            take = cost < best_cost
            best_p = np.where(take[..., None], p, best_p)
            best_done = np.where(take, done, best_done)
            best_cost = np.where(take, cost, best_cost)
    _, J = forward.value_and_jacobian(best_p.reshape(-1, P))
    J = J.reshape(batch + J.shape[-2:])
    J = np.where(mask[..., None], J, 0.0)
    m = mask.sum(-1)
    s2 = (np.asarray(noise, float) ** 2 if noise is not None
          else np.where(m > P, 2 * best_cost / np.maximum(m - P, 1), np.nan))
    A = np.einsum("...mi,...mj->...ij", J, J)
    with np.errstate(all="ignore"):
        cov = np.linalg.pinv(A) * np.asarray(s2)[..., None, None]
    nan = np.where(valid, 1.0, np.nan)
    sig_out = best_p[..., 2] if fit_sigma else sig_known
    return DolpFit(n=best_p[..., 0] * nan, kappa=best_p[..., 1] * nan, sigma=np.asarray(sig_out) * nan,
                   covariance=cov * nan[..., None, None], cost=best_cost * nan, converged=best_done & valid,
                   valid=valid, iterations=total_iter)


def fit_dolp_per_pixel(dolp, theta_i, theta_r, phi=np.pi, *, sigma=None, bounds=None,
                       starts=DEFAULT_STARTS, sigma0: float = 0.3, **model_kw) -> DolpFit:
    """Baseline: one ``scipy.optimize.least_squares`` (trust-region reflective) per pixel and start.

    Same forward model, analytic Jacobian, starts and bounds as :func:`fit_dolp`, so that comparing the two
    measures batching alone. No covariance (NaN).
    """
    y, ti, tr, ph = _prepare(dolp, theta_i, theta_r, phi)
    fit_sigma = sigma is None
    P = 3 if fit_sigma else 2
    lo, hi = _bounds(bounds, P)
    batch = y.shape[:-1]
    flat = y.reshape(-1, y.shape[-1])
    sig_flat = None if fit_sigma else np.broadcast_to(np.asarray(sigma, float), batch).ravel()
    out = np.full((flat.shape[0], 3), np.nan)
    cost = np.full(flat.shape[0], np.nan)
    for i, row in enumerate(flat):
        ok = np.isfinite(row)
        if ok.sum() < P:
            continue
        fwd = DolpForward(ti[ok], tr[ok], ph[ok], sigma=None if fit_sigma else sig_flat[i], **model_kw)
        target = row[ok]

        def res(p, fwd=fwd, target=target):
            return fwd(p) - target

        def jac(p, fwd=fwd):
            return fwd.value_and_jacobian(p)[1]

        best = None
        for n0, k0 in starts:
            x0 = np.clip([n0, k0] + ([sigma0] if fit_sigma else []), lo + 1e-9, hi - 1e-9)
            res_ = optimize.least_squares(res, x0, jac=jac, bounds=(lo, hi), xtol=1e-14, ftol=1e-14, gtol=1e-14)
            if best is None or res_.cost < best.cost:
                best = res_
        out[i, :P] = best.x
        if not fit_sigma:
            out[i, 2] = sig_flat[i]
        cost[i] = best.cost
    valid = np.isfinite(cost).reshape(batch)
    return DolpFit(n=out[:, 0].reshape(batch), kappa=out[:, 1].reshape(batch), sigma=out[:, 2].reshape(batch),
                   covariance=np.full(batch + (P, P), np.nan), cost=cost.reshape(batch), converged=valid,
                   valid=valid, iterations=0)
