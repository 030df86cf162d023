r"""Experiment design: Fisher information and Cramer-Rao bounds of (n, kappa, sigma) for a set of
geometries.

For M DOLP measurements with independent Gaussian noise of standard deviation :math:`s`,

.. math:: \mathcal I = J^T J / s^2, \qquad \mathrm{Cov}(\hat p) \succeq \mathcal I^{-1},

with :math:`J_{jk} = \partial\mathcal P_j/\partial p_k` the Jacobian of the pBRDF DOLP
(:class:`~scatterlab.inversion.forward.DolpForward`). The square roots of the diagonal of
:math:`\mathcal I^{-1}` are the smallest standard deviations any unbiased estimator can reach
(bounds on the
parameters ignored).

Identifiability
    A singular :math:`\mathcal I` leaves directions of parameter space that the data do not
    determine: sigma
    from specular-only data, whose DOLP depends on sigma only through the small diffuse share (Fig.
    58); kappa
    at kappa = 0, where the DOLP is stationary; or any design with fewer distinct geometries than
    unknowns
    (seven copies of one geometry determine one combination of the three parameters).
    :func:`inverse_information` finds the null space of the equilibrated information (eigenvalues
    below
    ``rcond`` times the largest) and calls a parameter *identifiable* when it has no weight on it.
    An
    identifiable parameter keeps its finite bound (a linear functional in the row space of
    :math:`\mathcal I` is estimable, with variance :math:`e^T\mathcal I^+e`); an unidentifiable one
    gets an
    infinite variance and NaN covariances: the undetermined directions are never dropped silently.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_angle, as_square_matrix
from scatterlab.inversion.forward import DolpForward

__all__ = ["fisher_information", "crlb", "inverse_information"]

RCOND = 1e-12  # equilibrated eigenvalue ratio below which a direction counts as undetermined
LOADING = 1e-6  # squared weight of a parameter on the null space above which it is unidentifiable


def inverse_information(info, rcond: float = RCOND):
    """Generalised inverse of Fisher information matrices, with the identifiable parameters.

    Parameters
    ----------
    info : array (..., P, P)
        Symmetric positive semi-definite information matrices (e.g. :math:`J^TJ/s^2`): square,
        at least 2-D, and symmetric within rounding (``|I - I^T| <= 1e-8 max|I|`` per matrix),
        else a ValueError naming ``info``. Non-finite entries give NaN covariances (below).
    rcond : float
        Eigenvalues of the equilibrated matrix :math:`D^{-1}\\mathcal I D^{-1}` (:math:`D` the
        square roots
        of its diagonal) below ``rcond`` times the largest span the undetermined directions.

    Returns
    -------
    covariance : ndarray (..., P, P)
        :math:`\\mathcal I^+` on the identifiable parameters; ``inf`` on the diagonal and NaN off it
        in the
        rows and columns of unidentifiable ones; all NaN where ``info`` is not finite.
    identifiable : ndarray of bool (..., P)
    """
    info = as_square_matrix(info, "info", symmetric=True)
    P = info.shape[-1]
    finite = np.all(np.isfinite(info), axis=(-2, -1))
    A = np.where(finite[..., None, None], info, 0.0)
    d = np.diagonal(A, axis1=-2, axis2=-1)
    dmax = np.max(d, axis=-1, keepdims=True)
    touched = (
        d > 1e-300 + 1e-30 * dmax
    )  # a parameter the data do not touch at all stays in, as a null row
    scale = np.where(touched, np.sqrt(np.where(touched, d, 1.0)), 1.0)
    corr = A / (scale[..., :, None] * scale[..., None, :])
    corr = np.where(touched[..., :, None] & touched[..., None, :], corr, 0.0)
    w, V = np.linalg.eigh(corr)
    null = w <= rcond * np.maximum(w[..., -1:], 1e-300)
    loading = np.sum(V * V * null[..., None, :], axis=-1)  # (..., P)
    identifiable = (loading < LOADING) & touched & finite[..., None]
    inv_w = np.where(null, 0.0, 1.0 / np.where(null, 1.0, w))
    cov = np.einsum("...ik,...k,...jk->...ij", V, inv_w, V) / (
        scale[..., :, None] * scale[..., None, :]
    )
    both = identifiable[..., :, None] & identifiable[..., None, :]
    cov = np.where(both, cov, np.nan)
    eye = np.eye(P, dtype=bool)
    cov = np.where(eye & ~identifiable[..., None, :], np.inf, cov)
    cov = np.where(finite[..., None, None], cov, np.nan)
    return cov, identifiable


def _check_truth(n, kappa, sigma):
    n, kappa, sigma = np.broadcast_arrays(*(np.asarray(a, float) for a in (n, kappa, sigma)))
    if not np.all(np.isfinite(n) & (n > 0)):
        raise ValueError("n must be finite and positive (eta = n - 1j*kappa)")
    if not np.all(np.isfinite(kappa) & (kappa >= 0)):
        raise ValueError("kappa must be finite and >= 0 (eta = n - 1j*kappa)")
    if not np.all((sigma >= 1e-3) & (sigma <= 2.5)):
        raise ValueError("sigma must be an rms facet slope in [1e-3, 2.5]")
    return n, kappa, sigma


def fisher_information(
    n, kappa, sigma, theta_i, theta_r, noise, phi=np.pi, *, sigma_known: bool = False, **model_kw
) -> np.ndarray:
    """Fisher information of (n, kappa, sigma) -> (..., P, P), P = 3 (2 with ``sigma_known``).

    Parameters
    ----------
    n, kappa, sigma : array_like (...)
        The true parameters (broadcast); n > 0, kappa >= 0, sigma in [1e-3, 2.5].
    theta_i, theta_r : array (M,) [rad]
        The geometries; M must be at least P (fewer measurements than unknowns is a ValueError).
    noise : float or array (...)
        DOLP noise standard deviation (> 0).
    phi : float or array (M,) [rad], default pi (specular plane)
    sigma_known : bool
        Information of (n, kappa) only, sigma fixed.

    Returns
    -------
    ndarray (..., P, P)
    """
    from scatterlab.inversion.least_squares import check_noise

    noise = check_noise(noise)  # in [1e-12, 1]
    if noise is None:
        raise ValueError("noise must be a DOLP standard deviation in [1e-12, 1], got None")
    n, kappa, sigma = _check_truth(n, kappa, sigma)
    P = 2 if sigma_known else 3
    ti = as_angle(theta_i, "theta_i").ravel()
    if ti.size < P:
        raise ValueError(
            f"theta_i must hold at least {P} geometries to determine {P} parameters; got {ti.size}"
        )
    shape = n.shape
    if sigma_known:
        fwd = DolpForward(theta_i, theta_r, phi, sigma=sigma.ravel(), **model_kw)
        p = np.stack([n.ravel(), kappa.ravel()], -1)
    else:
        fwd = DolpForward(theta_i, theta_r, phi, **model_kw)
        p = np.stack([n.ravel(), kappa.ravel(), sigma.ravel()], -1)
    _, J = fwd.value_and_jacobian(p)
    info = (
        np.einsum("kmi,kmj->kij", J, J)
        / (np.broadcast_to(noise, shape).ravel() ** 2)[:, None, None]
    )
    return info.reshape(shape + info.shape[-2:])


def crlb(
    n, kappa, sigma, theta_i, theta_r, noise, phi=np.pi, *, sigma_known: bool = False, **model_kw
) -> np.ndarray:
    """Cramer-Rao lower bounds (standard deviations) of (n, kappa[, sigma]) -> (..., P).

    Parameters as for :func:`fisher_information`. A parameter the design cannot determine (see the
    module
    docstring) has an infinite bound; the others keep their finite bounds.

    Parameters
    ----------
    n, kappa, sigma : array_like (...)
        The true parameters (broadcast); n > 0, kappa >= 0, sigma (rms slope) in [1e-3, 2.5].
    theta_i, theta_r : array (M,) [rad]
        The geometries, M >= P.
    noise : float or array (...)
        DOLP noise standard deviation (> 0).
    phi : float or array (M,) [rad], default pi (specular plane)
    sigma_known : bool
        Bounds of (n, kappa) only, sigma fixed.
    **model_kw
        ``shadowing``, ``diffuse``, ``distribution`` of :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    ndarray (..., P)
        Standard deviations of (n, kappa[, sigma]) (units of each parameter; inf where undetermined).
    """
    info = fisher_information(
        n, kappa, sigma, theta_i, theta_r, noise, phi, sigma_known=sigma_known, **model_kw
    )
    cov, _ = inverse_information(info)
    return np.sqrt(np.clip(np.diagonal(cov, axis1=-2, axis2=-1), 0, None))
