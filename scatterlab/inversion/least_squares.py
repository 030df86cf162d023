r"""Least-squares inversion of (n, kappa, sigma) from multi-geometry DOLP (Sec. 7.2.2, Eqs. 199-204).

The forward model is the pBRDF DOLP of :class:`scatterlab.pbrdf.Model` (Eq. 203 in the specular plane).
:func:`fit_dolp` solves, for every pixel of a batch at once,

.. math:: \min_{n,\kappa,\sigma} \sum_j [\mathcal P^{thy}(n - j\kappa, \sigma; \theta_{i,j}, \theta_{r,j}, \phi_j) - \mathcal P_j]^2

with a vectorised Levenberg-Marquardt iteration in numpy (forward-difference Jacobian, per-pixel damping,
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


def fit_dolp(dolp, theta_i, theta_r, phi=np.pi, *, sigma=None, noise=None, bounds=None,
             starts=DEFAULT_STARTS, sigma0: float = 0.3, max_iter: int = 100, tol: float = 1e-14,
             **model_kw) -> DolpFit:
    """Batched bounded least squares of (n, kappa[, sigma]) to DOLP measured at M geometries.

    Parameters
    ----------
    dolp : array (..., M)
        Measured DOLP; NaN entries are masked.
    theta_i, theta_r : array (M,) [rad]
    phi : float or array (M,) [rad], default pi (specular plane)
    sigma : float or array (...), optional
        Known roughness; when given only (n, kappa) are fitted.
    noise : float, optional
        DOLP noise standard deviation for the covariance (default: estimated from the residuals).
    bounds : dict, optional
        ``{"n": (lo, hi), "kappa": (lo, hi), "sigma": (lo, hi)}``; defaults in ``DEFAULT_BOUNDS``.
    starts : sequence of (n, kappa)
    max_iter, tol : Levenberg-Marquardt limits (iterations; relative cost decrease).

    Returns
    -------
    DolpFit
    """
    y, ti, tr, ph = _prepare(dolp, theta_i, theta_r, phi)
    b = dict(DEFAULT_BOUNDS, **(bounds or {}))
    fit_sigma = sigma is None
    P = 3 if fit_sigma else 2
    lo = np.array([b["n"][0], b["kappa"][0], b["sigma"][0]][:P])
    hi = np.array([b["n"][1], b["kappa"][1], b["sigma"][1]][:P])
    batch = y.shape[:-1]
    mask = np.isfinite(y)
    valid = mask.sum(-1) >= P
    y0 = np.where(mask, y, 0.0)
    sig_known = None if fit_sigma else np.broadcast_to(np.asarray(sigma, float), batch)

    def predict(p):
        s = p[..., 2] if fit_sigma else sig_known
        return model_dolp(p[..., 0], p[..., 1], s, ti, tr, ph, **model_kw)

    def residual(p):
        return np.where(mask, predict(p) - y0, 0.0)

    def jacobian(p, r):
        J = np.empty(batch + (y.shape[-1], P))
        for k in range(P):
            h = 1e-7 * np.maximum(1.0, np.abs(p[..., k]))
            q = p.copy()
            up = q[..., k] + h <= hi[k]
            q[..., k] = np.where(up, q[..., k] + h, q[..., k] - h)
            step = np.where(up, h, -h)
            J[..., k] = (residual(q) - r) / step[..., None]
        return J

    best_p = best_cost = None
    total_iter = 0
    for n0, k0 in starts:
        p = np.empty(batch + (P,))
        p[..., 0], p[..., 1] = n0, k0
        if fit_sigma:
            p[..., 2] = sigma0
        p = np.clip(p, lo, hi)
        r = residual(p)
        cost = 0.5 * np.sum(r * r, -1)
        lam = np.full(batch, 1e-3)
        done = ~valid
        for it in range(max_iter):
            J = jacobian(p, r)
            A = np.einsum("...mi,...mj->...ij", J, J)
            g = np.einsum("...mi,...m->...i", J, r)
            diag = np.diagonal(A, axis1=-2, axis2=-1)
            A_damped = A + lam[..., None, None] * (np.eye(P) * (diag[..., None, :] + 1e-12))
            delta = -np.linalg.solve(A_damped, g[..., None])[..., 0]
            p_new = np.clip(p + delta, lo, hi)
            r_new = residual(p_new)
            cost_new = 0.5 * np.sum(r_new * r_new, -1)
            better = (cost_new < cost) & ~done
            rel = np.where(better, (cost - cost_new) / np.maximum(cost, 1e-300), 0.0)
            p = np.where(better[..., None], p_new, p)
            r = np.where(better[..., None], r_new, r)
            converged_now = (better & (rel < tol)) | (~better & (lam > 1e10)) | (cost_new < 1e-30)
            cost = np.where(better, cost_new, cost)
            lam = np.where(better, lam / 3, lam * 4)
            done |= converged_now
            total_iter += 1
            if np.all(done):
                break
        if best_p is None:
            best_p, best_cost, best_done = p, cost, done
        else:
            take = cost < best_cost
            best_p = np.where(take[..., None], p, best_p)
            best_done = np.where(take, done, best_done)
            best_cost = np.where(take, cost, best_cost)
    r = residual(best_p)
    J = jacobian(best_p, r)
    m = mask.sum(-1)
    s2 = (noise**2 if noise is not None
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
    """Baseline: one ``scipy.optimize.least_squares`` (trust-region reflective) per pixel and start."""
    y, ti, tr, ph = _prepare(dolp, theta_i, theta_r, phi)
    b = dict(DEFAULT_BOUNDS, **(bounds or {}))
    fit_sigma = sigma is None
    P = 3 if fit_sigma else 2
    lo = [b["n"][0], b["kappa"][0], b["sigma"][0]][:P]
    hi = [b["n"][1], b["kappa"][1], b["sigma"][1]][:P]
    batch = y.shape[:-1]
    flat = y.reshape(-1, y.shape[-1])
    sig_flat = None if fit_sigma else np.broadcast_to(np.asarray(sigma, float), batch).ravel()
    out = np.full((flat.shape[0], 3), np.nan)
    cost = np.full(flat.shape[0], np.nan)
    for i, row in enumerate(flat):
        ok = np.isfinite(row)
        if ok.sum() < P:
            continue

        def res(p, row=row, ok=ok, i=i):
            s = p[2] if fit_sigma else sig_flat[i]
            return model_dolp(p[0], p[1], s, ti[ok], tr[ok], ph[ok], **model_kw) - row[ok]

        best = None
        for n0, k0 in starts:
            x0 = np.clip([n0, k0] + ([sigma0] if fit_sigma else []), np.array(lo) + 1e-9, np.array(hi) - 1e-9)
            res_ = optimize.least_squares(res, x0, bounds=(lo, hi), xtol=1e-14, ftol=1e-14, gtol=1e-14)
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
