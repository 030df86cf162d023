r"""Experiment design: Fisher information and Cramer-Rao bounds of (n, kappa, sigma) for a set of geometries.

For M DOLP measurements with independent Gaussian noise of standard deviation :math:`s`,

.. math:: \mathcal I = J^T J / s^2, \qquad \mathrm{Cov}(\hat p) \succeq \mathcal I^{-1},

with :math:`J_{jk} = \partial\mathcal P_j/\partial p_k` the Jacobian of the pBRDF DOLP
(:class:`~scatterlab.inversion.forward.DolpForward`). The square roots of the diagonal of
:math:`\mathcal I^{-1}` are the smallest standard deviations any unbiased estimator can reach (bounds on the
parameters ignored). A singular :math:`\mathcal I` -- sigma from specular-only data, whose DOLP depends on
sigma only through the small diffuse share (Fig. 58) -- gives an infinite bound.
"""

from __future__ import annotations

import numpy as np

from scatterlab.inversion.forward import DolpForward

__all__ = ["fisher_information", "crlb"]


def fisher_information(n, kappa, sigma, theta_i, theta_r, noise, phi=np.pi, *, sigma_known: bool = False,
                       **model_kw) -> np.ndarray:
    """Fisher information of (n, kappa, sigma) -> (..., P, P), P = 3 (2 with ``sigma_known``).

    Parameters
    ----------
    n, kappa, sigma : array_like (...) -- the true parameters (broadcast).
    theta_i, theta_r : array (M,) [rad]; phi : float or (M,) [rad]
    noise : float or array (...) -- DOLP noise standard deviation.
    """
    if np.any(np.asarray(noise) <= 0):
        raise ValueError("noise must be a positive DOLP standard deviation")
    n, kappa, sigma = np.broadcast_arrays(*(np.asarray(a, float) for a in (n, kappa, sigma)))
    shape = n.shape
    if sigma_known:
        fwd = DolpForward(theta_i, theta_r, phi, sigma=sigma.ravel(), **model_kw)
        p = np.stack([n.ravel(), kappa.ravel()], -1)
    else:
        fwd = DolpForward(theta_i, theta_r, phi, **model_kw)
        p = np.stack([n.ravel(), kappa.ravel(), sigma.ravel()], -1)
    _, J = fwd.value_and_jacobian(p)
    info = np.einsum("kmi,kmj->kij", J, J) / (np.broadcast_to(noise, shape).ravel() ** 2)[:, None, None]
    return info.reshape(shape + info.shape[-2:])


def crlb(n, kappa, sigma, theta_i, theta_r, noise, phi=np.pi, *, sigma_known: bool = False,
         **model_kw) -> np.ndarray:
    """Cramer-Rao lower bounds (standard deviations) of (n, kappa[, sigma]) -> (..., P); inf where unidentifiable."""
    info = fisher_information(n, kappa, sigma, theta_i, theta_r, noise, phi, sigma_known=sigma_known, **model_kw)
    P = info.shape[-1]
    scale = np.sqrt(np.clip(np.diagonal(info, axis1=-2, axis2=-1), 1e-300, None))
    corr = info / (scale[..., :, None] * scale[..., None, :])  # equilibrated: condition number of the shape
    out = np.full(info.shape[:-1], np.inf)
    cond = np.linalg.cond(corr)
    ok = np.isfinite(cond) & (cond < 1e12)
    if np.any(ok):
        inv = np.linalg.inv(corr[ok]) / (scale[ok][:, :, None] * scale[ok][:, None, :])
        out[ok] = np.sqrt(np.clip(np.diagonal(inv, axis1=-2, axis2=-1), 0, None))
    return out.reshape(info.shape[:-2] + (P,))
