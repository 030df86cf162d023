r"""Shadowing/masking (visibility) functions G(theta_i, theta_r, phi).

* ``"torrance-sparrow"`` -- the V-groove function in Blinn's form (Eq. 172),
  :math:`G = \min(1, 2\cos\alpha\cos\theta_r/\cos\beta, 2\cos\alpha\cos\theta_i/\cos\beta)`;
* ``"none"`` -- :math:`G = 1`, the Priest-Germer pBRDF (Eq. 134);
* ``"smith"`` -- Smith's height-correlated function for the facet distribution,
  :math:`G = 1/(1 + \Lambda(\theta_i) + \Lambda(\theta_r))` (Heitz 2014), available
  where the distribution provides :math:`\Lambda` in closed form.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SHADOWING", "shadowing_factor"]

SHADOWING = ("torrance-sparrow", "none", "smith")


def torrance_sparrow(cos_alpha, cos_beta, cos_theta_i, cos_theta_r) -> np.ndarray:
    """Eq. 172 (Blinn's form of the Torrance-Sparrow V-groove function)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(cos_beta > 0, 2 * cos_alpha / np.where(cos_beta > 0, cos_beta, 1.0), 0.0)
    return np.clip(np.minimum(k * cos_theta_r, k * cos_theta_i), 0.0, 1.0)


def smith(distribution, cos_theta_i, cos_theta_r) -> np.ndarray:
    """Height-correlated Smith function for ``distribution``."""
    def tan_of(c):
        c = np.clip(c, 0.0, 1.0)
        with np.errstate(divide="ignore"):
            return np.where(c > 0, np.sqrt(1 - c * c) / np.where(c > 0, c, 1.0), np.inf)

    lam_i = distribution.smith_lambda(tan_of(cos_theta_i))
    lam_r = distribution.smith_lambda(tan_of(cos_theta_r))
    return 1.0 / (1.0 + lam_i + lam_r)


def shadowing_factor(kind: str, geometry, distribution) -> np.ndarray:
    """G for a :class:`~scatterlab.pbrdf.geometry.FacetGeometry` and shadowing ``kind``."""
    if kind == "torrance-sparrow":
        return torrance_sparrow(geometry.cos_alpha, geometry.cos_beta, geometry.cos_theta_i,
                                geometry.cos_theta_r)
    if kind == "none":
        return np.ones_like(geometry.cos_beta)
    if kind == "smith":
        return smith(distribution, geometry.cos_theta_i, geometry.cos_theta_r)
    raise ValueError(f"shadowing must be one of {SHADOWING}, got {kind!r}")
