"""Inversion of (n, kappa, sigma) from multi-geometry DOLP (in progress: batched least squares so far).

``fit_dolp(dolp, theta_i, theta_r, ...)`` returns a result with ``.n``, ``.kappa``, ``.sigma`` over the
batch's leading axes.
"""

from scatterlab.inversion.least_squares import (
    DEFAULT_BOUNDS,
    DEFAULT_STARTS,
    DolpFit,
    fit_dolp,
    fit_dolp_per_pixel,
    model_dolp,
)

__all__ = ["fit_dolp", "fit_dolp_per_pixel", "DolpFit", "model_dolp", "DEFAULT_BOUNDS", "DEFAULT_STARTS"]
