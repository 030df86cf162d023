"""Polarimetric BRDF of rough surfaces: geometry, facet distributions, shadowing, model, DHR, DOLP.

``Model(sigma, shadowing="torrance-sparrow", diffuse="hyde")`` is the reference text's pBRDF
(Eqs. 173, 177); see :mod:`scatterlab.pbrdf.model` for the conventions and fast paths.
Shadowing functions are :class:`Shadowing` strategy objects (names are shortcuts), and all DHR code
lives in :mod:`scatterlab.pbrdf.dhr`.
"""

from scatterlab.pbrdf.dhr import (
    DHRTable,
    SpecularDHR,
    dhr_beckmann,
    dhr_slope_quadrature,
    dhr_sphere_unshadowed,
    dhr_table,
)
from scatterlab.pbrdf.distributions import Beckmann, FacetDistribution, HyperCauchy
from scatterlab.pbrdf.dolp import (
    dolp_smooth_facet,
    dolp_thilak,
    facet_dolp,
    facet_jones,
    facet_mueller,
)
from scatterlab.pbrdf.geometry import FacetGeometry, facet_geometry, in_plane_geometry
from scatterlab.pbrdf.inplane import dhr_pec_1d, dolp_1d, inplane_coefficients
from scatterlab.pbrdf.model import DIFFUSE, PEC, Model
from scatterlab.pbrdf.shadowing import (
    NO_SHADOWING,
    SHADOWING,
    SMITH,
    TORRANCE_SPARROW,
    Shadowing,
    shadowing_strategy,
)

__all__ = [
    "Model",
    "PEC",
    "DIFFUSE",
    "SHADOWING",
    "Shadowing",
    "shadowing_strategy",
    "TORRANCE_SPARROW",
    "SMITH",
    "NO_SHADOWING",
    "Beckmann",
    "HyperCauchy",
    "FacetDistribution",
    "FacetGeometry",
    "facet_geometry",
    "in_plane_geometry",
    "DHRTable",
    "SpecularDHR",
    "dhr_beckmann",
    "dhr_slope_quadrature",
    "dhr_sphere_unshadowed",
    "dhr_table",
    "dolp_smooth_facet",
    "dolp_thilak",
    "facet_dolp",
    "facet_jones",
    "facet_mueller",
    "dhr_pec_1d",
    "dolp_1d",
    "inplane_coefficients",
]
