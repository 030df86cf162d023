r"""Fits of the pBRDF to measured, normalised Mueller elements in the specular geometry (Sec. 4.4).

The measured elements are :math:`M_{01}/M_{00}, M_{11}/M_{00}, M_{22}/M_{00}, M_{23}/M_{00}` against the
angle :math:`\theta = \theta_i = \theta_r` (observation in the specular plane, :math:`\phi = \pi`),
as in Figs. 41-42. The model is :class:`scatterlab.pbrdf.Model` (Eq. 177): in the specular plane its
normalised elements are :math:`\Gamma M_{jk}/[(\Gamma + D) M_{00}]`, so the roughness enters through
the diffuse fraction. Bounded nonlinear least squares (``scipy.optimize.least_squares``, trust-region
reflective) from several starting points; the covariance of the parameters is
:math:`s^2 (J^T J)^{-1}` with :math:`s^2` the residual variance (or the given standard errors as weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from scatterlab._checks import as_angle, as_finite
from scatterlab.pbrdf import Model

__all__ = ["ELEMENTS", "normalised_elements", "fit_mueller_elements", "MuellerFit"]

ELEMENTS = ((0, 1), (1, 1), (2, 2), (2, 3))


def normalised_elements(M) -> np.ndarray:
    """``(M01, M11, M22, M23) / M00`` of Mueller matrices ``(..., 4, 4)`` -> ``(..., 4)``."""
    M = np.asarray(M, float)
    return np.stack([M[..., j, k] / M[..., 0, 0] for j, k in ELEMENTS], -1)


def model_elements(theta, n, kappa, sigma, *, shadowing="torrance-sparrow", diffuse="hyde") -> np.ndarray:
    """pBRDF normalised elements at ``theta_i = theta_r = theta`` [rad], shape ``(len(theta), 4)``."""
    F = Model(sigma, shadowing=shadowing, diffuse=diffuse).mueller(n - 1j * kappa, theta, theta, np.pi)
    return normalised_elements(F)


@dataclass
class MuellerFit:
    """Result of :func:`fit_mueller_elements`: best-fit index and roughness with 1-sigma errors."""

    n: float
    kappa: float
    sigma: float
    covariance: np.ndarray
    residuals: np.ndarray
    cost: float
    success: bool
    starts: int

    @property
    def eta(self) -> complex:
        return complex(self.n, -self.kappa)

    @property
    def errors(self) -> np.ndarray:
        """1-sigma standard errors of the fitted parameters (sqrt of the covariance diagonal)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0, None))


def fit_mueller_elements(theta, measured, *, std=None, sigma=None, fit_sigma: bool = True,
                         starts=((0.5, 5.0), (1.5, 10.0), (3.0, 3.0), (1.5, 0.1)), sigma0: float = 0.3,
                         bounds=((0.01, 10.0), (0.0, 30.0), (0.01, 1.5)), shadowing="torrance-sparrow",
                         diffuse="hyde") -> MuellerFit:
    """Fit (n, kappa[, sigma]) of the pBRDF to normalised Mueller elements at specular angles.

    Parameters
    ----------
    theta : array_like (N,) [rad]
        theta_i = theta_r of each measurement.
    measured : array_like (N, 4)
        ``(M01, M11, M22, M23) / M00`` (see :func:`normalised_elements`).
    std : array_like (N, 4), optional
        Standard errors used as weights.
    sigma : float, optional
        Known roughness (required when ``fit_sigma`` is False; the starting value otherwise).
    starts : sequence of (n, kappa)
        Starting points; the best final cost wins (metal/dielectric ambiguity).
    bounds : ((n_lo, n_hi), (k_lo, k_hi), (s_lo, s_hi))

    Returns
    -------
    MuellerFit
    """
    theta = as_angle(theta, "theta")
    y = as_finite(measured, "measured")
    if y.shape != (theta.size, 4):
        raise ValueError(f"measured must have shape ({theta.size}, 4), got {y.shape}")
    w = np.ones_like(y) if std is None else 1.0 / np.maximum(as_finite(std, "std"), 1e-12)
    if not fit_sigma and sigma is None:
        raise ValueError("sigma must be given when fit_sigma is False")
    s0 = sigma0 if sigma is None else float(sigma)

    def residual(p):
        n, k = p[0], p[1]
        s = p[2] if fit_sigma else s0
        return ((model_elements(theta, n, k, s, shadowing=shadowing, diffuse=diffuse) - y) * w).ravel()

    lo = [bounds[0][0], bounds[1][0]] + ([bounds[2][0]] if fit_sigma else [])
    hi = [bounds[0][1], bounds[1][1]] + ([bounds[2][1]] if fit_sigma else [])
    best = None
    for n0, k0 in starts:
        x0 = np.clip([n0, k0] + ([s0] if fit_sigma else []), np.array(lo) + 1e-9, np.array(hi) - 1e-9)
        res = optimize.least_squares(residual, x0, bounds=(lo, hi), method="trf", x_scale="jac",
                                     xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
        if best is None or res.cost < best.cost:
            best = res
    J = best.jac
    dof = max(1, best.fun.size - J.shape[1])
    s2 = 1.0 if std is not None else 2 * best.cost / dof
    try:
        cov = np.linalg.inv(J.T @ J) * s2
    except np.linalg.LinAlgError:
        cov = np.full((J.shape[1], J.shape[1]), np.inf)
    x = best.x
    sig = x[2] if fit_sigma else s0
    if not fit_sigma:
        cov = np.pad(cov, ((0, 1), (0, 1)))
    return MuellerFit(n=float(x[0]), kappa=float(x[1]), sigma=float(sig), covariance=cov,
                      residuals=best.fun.reshape(-1, 4), cost=float(best.cost), success=bool(best.success),
                      starts=len(starts))
