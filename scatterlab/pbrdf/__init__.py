"""Polarimetric BRDF of rough surfaces: geometry, facet distributions, shadowing, model, DHR, DOLP.

``Model(sigma, shadowing="torrance-sparrow", diffuse="hyde")`` is the reference text's pBRDF
(Eqs. 173, 177); see :mod:`scatterlab.pbrdf.model` for the conventions and fast paths.
"""

from scatterlab.pbrdf.dhr import DHRTable, dhr_beckmann, dhr_sphere_unshadowed, dhr_table
from scatterlab.pbrdf.distributions import Beckmann, FacetDistribution, HyperCauchy
from scatterlab.pbrdf.dolp import dolp_smooth_facet, dolp_thilak
from scatterlab.pbrdf.geometry import FacetGeometry, facet_geometry
from scatterlab.pbrdf.model import DIFFUSE, PEC, Model
from scatterlab.pbrdf.shadowing import SHADOWING

__all__ = [
    "Model", "PEC", "DIFFUSE", "SHADOWING",
    "Beckmann", "HyperCauchy", "FacetDistribution",
    "FacetGeometry", "facet_geometry",
    "DHRTable", "dhr_beckmann", "dhr_sphere_unshadowed", "dhr_table",
    "dolp_smooth_facet", "dolp_thilak",
]
