"""Polarization algebra: Jones vectors and matrices, Stokes vectors, Mueller matrices.

Matrix axes last and full broadcasting: Jones ``(..., 2, 2)``, Stokes ``(..., 4)``,
Mueller ``(..., 4, 4)``. Basis (s, p); ``S1 = I_s - I_p``; time dependence
e^{+j w t} (see :mod:`scatterlab.polarization.jones` for the consequences).
"""

from scatterlab.polarization.jones import (
    circular_jones_vector,
    linear_jones_vector,
    linear_polarizer_jones,
    linear_retarder_jones,
    rotate_jones,
    rotation,
    rotator_jones,
)
from scatterlab.polarization.mueller import (
    apply,
    coherency_matrix,
    depolarizer,
    diattenuator,
    is_physical_mueller,
    jones_to_mueller,
    linear_polarizer,
    linear_retarder,
    mueller_from_coherency,
    nearest_physical_mueller,
    rotate_mueller,
    rotator,
)
from scatterlab.polarization.stokes import (
    aop,
    dolp,
    dolp_aop,
    dop,
    is_physical_stokes,
    jones_to_stokes,
    signed_dolp,
    stokes_vector,
)

__all__ = [
    "rotation",
    "rotate_jones",
    "linear_polarizer_jones",
    "linear_retarder_jones",
    "rotator_jones",
    "linear_jones_vector",
    "circular_jones_vector",
    "jones_to_mueller",
    "apply",
    "rotate_mueller",
    "linear_polarizer",
    "diattenuator",
    "linear_retarder",
    "rotator",
    "depolarizer",
    "coherency_matrix",
    "mueller_from_coherency",
    "is_physical_mueller",
    "nearest_physical_mueller",
    "jones_to_stokes",
    "stokes_vector",
    "dop",
    "dolp",
    "aop",
    "dolp_aop",
    "signed_dolp",
    "is_physical_stokes",
]
