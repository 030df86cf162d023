"""Inversion of (n, kappa, sigma) from multi-geometry DOLP (Sec. 3.1.2.3, Eqs. 115-117; Sec. 7.2,
Eqs. 199-204).

* :func:`fit_dolp` -- batched bounded least squares over leading axes (whole images at once);
  :func:`fit_dolp_per_pixel` is the per-pixel scipy baseline;
* :func:`thilak_two_step` -- Thilak et al.'s two-step method (Eqs. 116-117), the comparison
  baseline, and :func:`thilak_crlb`, the Cramer-Rao bound of its (n, kappa, theta_r) from Eq. 115;
* :func:`sample_posterior` / :func:`sample_posteriors` -- emcee posterior sampling with diagnostics,
  multimodality detection and HDF5 checkpoints;
* :func:`fisher_information`, :func:`crlb` -- experiment design;
* :func:`scatterlab.inversion.report.posterior_report` -- corner, traces, predictive band, tables.
"""

from scatterlab.inversion.design import crlb, fisher_information, inverse_information
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.least_squares import (
    DEFAULT_BOUNDS,
    DEFAULT_STARTS,
    DOLP_MARGIN,
    BoundWarning,
    DolpFit,
    FitOptions,
    IdentifiabilityWarning,
    fit_dolp,
    fit_dolp_per_pixel,
    model_dolp,
)
from scatterlab.inversion.model_error import dolp_model_error, dolp_model_error_covariance
from scatterlab.inversion.posterior import (
    ConvergenceWarning,
    MisfitWarning,
    Posterior,
    PriorOptions,
    SamplerOptions,
    effective_sample_size,
    ensemble_rhat,
    local_minima,
    sample_posterior,
    sample_posteriors,
    split_rhat,
)
from scatterlab.inversion.thilak import ThilakFit, thilak_crlb, thilak_two_step

__all__ = [
    "fit_dolp",
    "fit_dolp_per_pixel",
    "FitOptions",
    "DolpFit",
    "model_dolp",
    "DEFAULT_BOUNDS",
    "DEFAULT_STARTS",
    "DOLP_MARGIN",
    "BoundWarning",
    "IdentifiabilityWarning",
    "DolpForward",
    "sample_posterior",
    "sample_posteriors",
    "Posterior",
    "PriorOptions",
    "SamplerOptions",
    "ConvergenceWarning",
    "MisfitWarning",
    "local_minima",
    "split_rhat",
    "ensemble_rhat",
    "effective_sample_size",
    "thilak_two_step",
    "thilak_crlb",
    "ThilakFit",
    "fisher_information",
    "crlb",
    "inverse_information",
    "dolp_model_error",
    "dolp_model_error_covariance",
]
