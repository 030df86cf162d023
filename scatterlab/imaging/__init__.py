"""Turbulence-degraded polarimetric imaging (in progress: turbulence, phase screens, PSFs and MTFs so far).

``phase_screen(n, dx, r0, rng, L0=inf, subharmonics=True)`` returns an (n, n) phase in radians.
"""

from scatterlab.imaging.psf import (
    airy_pattern,
    circular_pupil,
    diffraction_mtf,
    fit_r0,
    long_exposure_mtf,
    mtf,
    otf,
    psf,
    radial_profile,
    short_exposure_mtf,
)
from scatterlab.imaging.turbulence import (
    SlidingScreen,
    fried_parameter,
    kolmogorov_psd,
    phase_psd,
    phase_screen,
    phase_variance_theory,
    remove_piston_tilt,
    rytov_variance,
    rytov_variance_from_r0,
    structure_function,
    structure_function_theory,
    von_karman_psd,
)

__all__ = [
    "circular_pupil", "psf", "otf", "mtf", "radial_profile", "airy_pattern", "diffraction_mtf",
    "long_exposure_mtf", "short_exposure_mtf", "fit_r0",
    "phase_screen", "SlidingScreen", "remove_piston_tilt", "kolmogorov_psd", "von_karman_psd", "phase_psd",
    "fried_parameter", "rytov_variance", "rytov_variance_from_r0", "structure_function",
    "structure_function_theory", "phase_variance_theory",
]
