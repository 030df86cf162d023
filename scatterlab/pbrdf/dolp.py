r"""Closed-form DOLP expressions for comparison with the pBRDF.

* :func:`dolp_smooth_facet` -- :math:`(R_s - R_p)/(R_s + R_p)` at the facet angle
  :math:`\beta` (Eq. 114): the DOLP of light scattered by optically smooth facets,
  Thilak et al.'s forward model (Eq. 115 with the errata's A, B and facet angle);
* :func:`dolp_thilak` -- the same in the specular plane as a function of
  (theta_i, theta_r), :math:`\beta = (\theta_i + \theta_r)/2` (Eq. 112).

The full pBRDF DOLP (Eq. 203 and out of plane) is :meth:`scatterlab.pbrdf.Model.dolp`.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_angle, as_index, broadcast
from scatterlab.pbrdf.model import _reduced_fresnel

__all__ = ["dolp_smooth_facet", "dolp_thilak"]


def dolp_smooth_facet(eta, beta) -> np.ndarray:
    """DOLP ``(Rs - Rp)/(Rs + Rp)`` of unpolarized light reflected at facet angle ``beta`` [rad] (Eqs. 57, 114).

    Continuous at ``eta -> 1`` (computed from reduced coefficients). Returns values in ``[0, 1]``.
    """
    eta = as_index(eta)
    beta = as_angle(beta, "beta")
    eta, beta = broadcast(eta=eta, beta=beta)
    rs, rp, _ = _reduced_fresnel(eta, np.cos(beta))
    Rs, Rp = np.abs(rs) ** 2, np.abs(rp) ** 2
    return np.clip((Rs - Rp) / (Rs + Rp), 0.0, 1.0)


def dolp_thilak(eta, theta_i, theta_r) -> np.ndarray:
    """Thilak et al.'s DOLP (Eq. 115) in the specular plane: the smooth-facet DOLP at ``beta = (theta_i + theta_r)/2``."""
    ti = as_angle(theta_i, "theta_i")
    tr = as_angle(theta_r, "theta_r")
    return dolp_smooth_facet(eta, (ti + tr) / 2)
