"""Turbulence-degraded polarimetric imaging: turbulence, PSFs, pBRDF scenes, polarimeter channels and noise.

``phase_screen(n, dx, r0, rng, L0=inf, subharmonics=True)`` returns an (n, n) phase in radians.
"""

from scatterlab.imaging.polarimeter import (
    ANGLES_0_45_90_135,
    ANGLES_0_60_120,
    analyzer_matrix,
    channel_images,
    convolve,
    detect,
    dolp_aop_from_stokes,
    stokes_from_channels,
)
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
from scatterlab.imaging.scene import Scene, painted_plate, render_stokes
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
    "analyzer_matrix",
    "channel_images",
    "convolve",
    "detect",
    "stokes_from_channels",
    "dolp_aop_from_stokes",
    "ANGLES_0_45_90_135",
    "ANGLES_0_60_120",
    "Scene",
    "painted_plate",
    "render_stokes",
    "circular_pupil",
    "psf",
    "otf",
    "mtf",
    "radial_profile",
    "airy_pattern",
    "diffraction_mtf",
    "long_exposure_mtf",
    "short_exposure_mtf",
    "fit_r0",
    "phase_screen",
    "SlidingScreen",
    "remove_piston_tilt",
    "kolmogorov_psd",
    "von_karman_psd",
    "phase_psd",
    "fried_parameter",
    "rytov_variance",
    "rytov_variance_from_r0",
    "structure_function",
    "structure_function_theory",
    "phase_variance_theory",
]
