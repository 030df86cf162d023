"""scatterlab: polarimetric light scattering from rough surfaces.

Subpackages and modules (one per domain / physical concept):

* :mod:`scatterlab.fresnel` -- complex index helpers, Fresnel coefficients, reflectances, Brewster angles;
* :mod:`scatterlab.polarization` -- Jones, Stokes and Mueller algebra, realizability;
* :mod:`scatterlab.materials` -- named materials eta(wavelength) with their sources;
* :mod:`scatterlab.runtime` -- executors, progress, atomic results, timing (the study runner is
  :mod:`scatterlab.study_runner`).

Conventions: eta = n - 1j*kappa (kappa >= 0, time dependence exp(+j w t)); angles in
radians; lengths in metres; Stokes (..., 4) with S1 = I_s - I_p; Mueller (..., 4, 4).
Equations are cited as "Eq. N" of the reference text (AFIT/DEE/ENG/10-12).
"""

__version__ = "0.1.0"

from scatterlab import fresnel, materials, polarization, runtime  # noqa: E402  (light imports only)

__all__ = ["fresnel", "polarization", "materials", "runtime", "__version__"]
