"""Method of moments for rough surfaces and bodies, both polarizations, PEC and real materials (Sec. 4.3).

* :func:`rough_surface` -- Gaussian heights, Gaussian correlation, FFT synthesis;
* :class:`PlaneWave`, :class:`TaperedWave` -- incidence (Thorsos's taper with its correction and checks);
* :func:`solve` -- the one entry: ``polarization`` "s"/"p", ``eta`` (None: PEC), exact two-medium or impedance
  formulation (:mod:`scatterlab.mom.formulations`, kernels in :mod:`scatterlab.mom.kernels`);
* :func:`solve_tm` -- the s-pol PEC case: EFIE, pulse basis and point matching, one LU for all
  incidences or forward-backward;
  the solution gives ``current``, ``far_field``, ``echo_width`` and ``scattering_coefficient``;
* :func:`incoherent_scattering` -- Monte-Carlo average over partitions with standard errors;
* :mod:`scatterlab.mom.exact` -- the exact series for a circular cylinder (PEC or penetrable, s and p);
* :func:`spm1_coefficient`, :func:`physical_optics` -- the small-roughness and Kirchhoff limits
  (:mod:`scatterlab.mom.asymptotics`);
* ``solve_tm(..., solver="fast")`` -- banded matrix + FFT far interactions for long PEC profiles
  (:mod:`scatterlab.mom.fast`, 10^5 unknowns in minutes).
"""

from scatterlab.mom.asymptotics import physical_optics, spm1_coefficient
from scatterlab.mom.efie import (
    Solution,
    contour,
    impedance_matrix,
    physical_optics_current,
    solve_tm,
)
from scatterlab.mom.exact import (
    cylinder_coefficients,
    cylinder_echo_width,
    cylinder_surface_field,
)
from scatterlab.mom.formulations import TruncationWarning, solve
from scatterlab.mom.incidence import PlaneWave, TaperedWave
from scatterlab.mom.montecarlo import IncoherentResult, incoherent_scattering
from scatterlab.mom.solvers import forward_backward
from scatterlab.mom.surfaces import (
    correlation_length_for_slope,
    rms_slope,
    rough_surface,
)

__all__ = [
    "IncoherentResult",
    "PlaneWave",
    "Solution",
    "TaperedWave",
    "TruncationWarning",
    "contour",
    "correlation_length_for_slope",
    "cylinder_coefficients",
    "cylinder_echo_width",
    "cylinder_surface_field",
    "forward_backward",
    "impedance_matrix",
    "incoherent_scattering",
    "physical_optics",
    "physical_optics_current",
    "rms_slope",
    "rough_surface",
    "solve",
    "solve_tm",
    "spm1_coefficient",
]
