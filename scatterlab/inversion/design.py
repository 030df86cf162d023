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
    flat = info.reshape(-1, P, P)
    out = np.full(flat.shape[:-1], np.inf)
    for i, I in enumerate(flat):
        # a parameter the data do not touch (zero information, e.g. kappa at kappa = 0 where the DOLP is
        # stationary) has an infinite bound and is left out of the inversion for the others
        d = np.diagonal(I)
        keep = d > 1e-300 * max(d.max(), 1e-300)
        if not np.any(keep):
            continue
        sub = I[np.ix_(keep, keep)]
        scale = np.sqrt(np.diagonal(sub))
        corr = sub / np.outer(scale, scale)  # equilibrated: the condition number measures identifiability
        if np.linalg.cond(corr) < 1e12:
            out[i, keep] = np.sqrt(np.clip(np.diagonal(np.linalg.inv(corr)), 0, None)) / scale
    return out.reshape(info.shape[:-2] + (P,))
