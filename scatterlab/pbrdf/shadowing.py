r"""Shadowing/masking (visibility) functions as strategy objects.

* ``"torrance-sparrow"`` -- the V-groove function in Blinn's form (Eq. 172),
  :math:`G = \min(1, 2\cos\alpha\cos\theta_r/\cos\beta, 2\cos\alpha\cos\theta_i/\cos\beta)`;
* ``"none"`` -- :math:`G = 1`, the Priest-Germer pBRDF (Eq. 134), which does not conserve energy;
* ``"smith"`` -- Smith's height-correlated function for the facet distribution,
  :math:`G = 1/(1 + \Lambda(\theta_i) + \Lambda(\theta_r))` (Heitz 2014), available
  where the distribution provides :math:`\Lambda` in closed form.

Each is a :class:`Shadowing`: its name, :math:`G/(\cos\theta_i\cos\theta_r)` for the pBRDF, the
slope-space integrand of the DHR quadrature, and the facts the rest of the package needs about it.
The pBRDF, the DHR tables and the inversion's forward model all take one from
:func:`shadowing_strategy`, the only place a name is turned into a function; a :class:`Shadowing`
object may be passed wherever a name is accepted.

At exactly grazing directions (``cos theta = 0``) ``G/(cos cos)`` is its limit where that is
finite (one direction grazing, Torrance-Sparrow or Smith) and ``inf`` where the model diverges
(both directions grazing; any grazing direction without shadowing); the pBRDF sets its specular
term to 0 there (:class:`scatterlab.pbrdf.Model`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = [
    "SHADOWING",
    "Shadowing",
    "shadowing_strategy",
    "shadowing_factor",
    "TORRANCE_SPARROW",
    "SMITH",
    "NO_SHADOWING",
]


def torrance_sparrow(cos_alpha, cos_beta, cos_theta_i, cos_theta_r) -> np.ndarray:
    """Eq. 172 (Blinn's form of the Torrance-Sparrow V-groove function).

    Parameters
    ----------
    cos_alpha : array_like
        Cosine of the facet tilt from the mean surface normal.
    cos_beta : array_like
        Cosine of the angle between the facet normal and the incident (or reflected) direction.
    cos_theta_i, cos_theta_r : array_like
        Cosines of the incidence and observation angles.

    Returns
    -------
    ndarray
        ``G = min(1, 2 cos(alpha) cos(theta_i) / cos(beta), 2 cos(alpha) cos(theta_r) / cos(beta))``
        in [0, 1], broadcast shape.
    """
    k = _v_groove_slope(cos_alpha, cos_beta)
    return np.clip(np.minimum(k * cos_theta_r, k * cos_theta_i), 0.0, 1.0)


def _v_groove_slope(cos_alpha, cos_beta):
    """``k = 2 cos(alpha)/cos(beta)`` (0 where cos(beta) = 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cos_beta > 0, 2 * cos_alpha / np.where(cos_beta > 0, cos_beta, 1.0), 0.0)


def smith(distribution, cos_theta_i, cos_theta_r) -> np.ndarray:
    """Height-correlated Smith function for ``distribution``.

    Parameters
    ----------
    distribution : FacetDistribution
        Facet slope distribution with a closed-form ``smith_lambda``.
    cos_theta_i, cos_theta_r : array_like
        Cosines of the incidence and observation angles.

    Returns
    -------
    ndarray
        ``G = 1 / (1 + Lambda(theta_i) + Lambda(theta_r))`` in [0, 1], broadcast shape.
    """

    def tan_of(c):
        c = np.clip(c, 0.0, 1.0)
        with np.errstate(divide="ignore"):
            return np.where(c > 0, np.sqrt(1 - c * c) / np.where(c > 0, c, 1.0), np.inf)

    lam_i = distribution.smith_lambda(tan_of(cos_theta_i))
    lam_r = distribution.smith_lambda(tan_of(cos_theta_r))
    return 1.0 / (1.0 + lam_i + lam_r)


def _ts_g_over_cos(geo, slopes):
    # G/(ci cr) = min(1/(ci cr), k/ci, k/cr): no 0 * inf
    k = _v_groove_slope(geo.cos_alpha, geo.cos_beta)
    ci, cr = geo.cos_theta_i, geo.cos_theta_r
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.minimum(np.minimum(1 / (ci * cr), k / ci), k / cr)


def _none_g_over_cos(geo, slopes):
    with np.errstate(divide="ignore"):
        return 1 / (geo.cos_theta_i * geo.cos_theta_r)


def _smith_g_over_cos(geo, slopes):
    # G/(ci cr) = 1/(ci cr + cr (ci Lambda_i) + ci (cr Lambda_r)), cos * Lambda finite at grazing
    ci, cr = geo.cos_theta_i, geo.cos_theta_r
    den = ci * cr + cr * slopes.smith_lambda_cos(ci) + ci * slopes.smith_lambda_cos(cr)
    with np.errstate(divide="ignore"):
        return 1 / den


def _ts_slope(m, rz, c, s, slopes):
    return np.minimum(np.minimum(m / c, 2 * rz / c), 2.0)


def _none_slope(m, rz, c, s, slopes):
    return m / c


def _smith_slope(m, rz, c, s, slopes):
    tan_i = s / np.maximum(c, 1e-300)
    tan_r = np.sqrt(np.maximum(1 - rz * rz, 0)) / np.maximum(rz, 1e-300)
    return m / c / (1 + slopes.smith_lambda(tan_i) + slopes.smith_lambda(tan_r))


@dataclass(frozen=True)
class Shadowing:
    """A shadowing function and what the pBRDF, DHR and inversion code need to know about it.

    Attributes
    ----------
    name : str
    g_over_cos : callable ``(FacetGeometry, slopes) -> ndarray``
        :math:`G/(\\cos\\theta_i\\cos\\theta_r)` [dimensionless], ``slopes`` the facet distribution.
    slope_integrand : callable ``(m, cos_theta_r, c, s, slopes) -> ndarray``
        :math:`G\\,(\\cos\\theta_i - s_x\\sin\\theta_i)/\\cos\\theta_i` of the DHR in slope space,
        ``m = cos(theta_i) - s_x sin(theta_i)``, ``c, s`` the cosine and sine of ``theta_i``.
    conserves_energy : bool
        The specular DHR of a PEC is at most 1 (clipped there at rounding). False for ``"none"``,
        whose DHR diverges like ``tan(theta_i)`` at grazing.
    kinks : bool
        The integrand has kinks the DHR quadrature splits at (Torrance-Sparrow's ``min``).
    sigma_free : bool
        ``G`` does not depend on the roughness.
    quadrature_nodes : int
        Gauss-Legendre nodes per piece that give <= 1e-9 in the DHR quadrature (perf_dhr study).
    """

    name: str
    g_over_cos: Callable
    slope_integrand: Callable
    conserves_energy: bool = True
    kinks: bool = False
    sigma_free: bool = True
    quadrature_nodes: int = 16

    def __str__(self):
        return self.name


TORRANCE_SPARROW = Shadowing(
    "torrance-sparrow", _ts_g_over_cos, _ts_slope, kinks=True, quadrature_nodes=16
)
NO_SHADOWING = Shadowing(
    "none", _none_g_over_cos, _none_slope, conserves_energy=False, quadrature_nodes=24
)
SMITH = Shadowing("smith", _smith_g_over_cos, _smith_slope, sigma_free=False, quadrature_nodes=32)

_BY_NAME = {s.name: s for s in (TORRANCE_SPARROW, NO_SHADOWING, SMITH)}
SHADOWING = tuple(_BY_NAME)


def shadowing_strategy(shadowing) -> Shadowing:
    """The :class:`Shadowing` for a name in :data:`SHADOWING` (or the object itself).

    Parameters
    ----------
    shadowing : str or Shadowing
        ``"torrance-sparrow"``, ``"smith"`` or ``"none"``, or a :class:`Shadowing` object.

    Returns
    -------
    Shadowing
        The strategy object.
    """
    if isinstance(shadowing, Shadowing):
        return shadowing
    try:
        return _BY_NAME[shadowing]
    except (KeyError, TypeError):
        raise ValueError(
            f"shadowing must be one of {SHADOWING} or a Shadowing, got {shadowing!r}"
        ) from None


def shadowing_factor(kind, geometry, distribution) -> np.ndarray:
    """G itself for a :class:`~scatterlab.pbrdf.geometry.FacetGeometry` and shadowing ``kind``.

    Parameters
    ----------
    kind : str or Shadowing
        The shadowing function.
    geometry : FacetGeometry
        Facet angles of the geometries.
    distribution : FacetDistribution
        Facet slopes (used by Smith).

    Returns
    -------
    ndarray
        G in [0, 1], the geometry's shape.
    """
    strategy = shadowing_strategy(kind)
    g = strategy.g_over_cos(geometry, distribution) * geometry.cos_theta_i * geometry.cos_theta_r
    return np.clip(np.where(np.isfinite(g), g, 0.0), 0.0, 1.0)
