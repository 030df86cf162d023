"""Turbulence-degraded polarimetric imaging (in progress: turbulence and phase screens so far).

``phase_screen(n, dx, r0, rng, L0=inf, subharmonics=True)`` returns an (n, n) phase in radians.
"""

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
    "phase_screen", "SlidingScreen", "remove_piston_tilt", "kolmogorov_psd", "von_karman_psd", "phase_psd",
    "fried_parameter", "rytov_variance", "rytov_variance_from_r0", "structure_function",
    "structure_function_theory", "phase_variance_theory",
]
