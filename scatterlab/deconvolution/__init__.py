"""Polarimetric blind deconvolution, DOLP priors and material classification (Ch. V-VII, Eqs. 185-198).

* :func:`blind_deconvolve` -- EM (LeMaster-Cain / Schulz) for S0, DOLP, AOP and the PSFs;
* :mod:`psf_update` -- the Sec. 5.3.2 start PSF, the Gerchberg-Saxton pupil projection (Eqs. 146-150), and
  :func:`psf_distance`, an estimate's L1 distance from the true PSF;
* :mod:`priors` -- super-Gaussian DOLP priors (Eq. 195), the MAP DOLP update (Eq. 196), adaptive priors;
* classification: several priors given to :func:`blind_deconvolve` label each pixel by the prior whose
  update maximizes the objective; :func:`classify_unmixing` refines a classification by linear unmixing
  of the Stokes images (edges where a blurred image has them); :func:`classification_errors` scores a
  label map like Table 4;
* :func:`layout_psf` -- the PSF of one frame, or of each of several exposures, found with a few-material
  object (each material uniform; a soft layout, or pure interiors with mixing only along the edges): the
  prior a single frame's likelihood needs to tell the PSF;
* :func:`phase_diversity` -- the PSF of one exposure from frames with known pupil-phase offsets (defocused
  cameras beside the polarimeter): an instrument that identifies the PSF where one frame cannot.
"""

from scatterlab.deconvolution.classify import (
    classification_errors,
    classify_dolp,
    classify_unmixing,
)
from scatterlab.deconvolution.em import (
    DeconvolutionResult,
    EMOptions,
    EMState,
    PolarizationOptions,
    PSFOptions,
    StartOptions,
    StopOptions,
    WindowOptions,
    blind_deconvolve,
    e_step,
    evenly_spaced,
    m_step,
    object_grid,
    psf_step,
)
from scatterlab.deconvolution.layout import LayoutResult, layout_psf
from scatterlab.deconvolution.phase_diversity import (
    PhaseDiversityResult,
    defocus_phase,
    phase_diversity,
)
from scatterlab.deconvolution.priors import (
    PRIOR_SETS,
    SuperGaussianPrior,
    adaptive_priors,
    dolp_update,
    dolp_update_companion,
    map_objective,
)
from scatterlab.deconvolution.psf_update import (
    gerchberg_saxton,
    initial_psf,
    psf_distance,
    resample_psf,
)

__all__ = [
    "blind_deconvolve",
    "DeconvolutionResult",
    "EMOptions",
    "EMState",
    "PSFOptions",
    "PolarizationOptions",
    "WindowOptions",
    "StartOptions",
    "StopOptions",
    "e_step",
    "m_step",
    "psf_step",
    "evenly_spaced",
    "SuperGaussianPrior",
    "PRIOR_SETS",
    "dolp_update",
    "dolp_update_companion",
    "adaptive_priors",
    "map_objective",
    "classification_errors",
    "classify_dolp",
    "classify_unmixing",
    "initial_psf",
    "layout_psf",
    "LayoutResult",
    "object_grid",
    "gerchberg_saxton",
    "resample_psf",
    "psf_distance",
    "phase_diversity",
    "PhaseDiversityResult",
    "defocus_phase",
]
