"""Method of moments for TM scattering by perfectly conducting rough surfaces and bodies (Sec. 4.3, Eqs. 178-183).

* :func:`rough_surface` -- Gaussian heights, Gaussian correlation, FFT synthesis;
* :class:`PlaneWave`, :class:`TaperedWave` -- incidence (Thorsos's taper with its correction and checks);
* :func:`solve_tm` -- EFIE, pulse basis and point matching, one LU for all incidences or forward-backward;
  the solution gives ``current``, ``far_field``, ``echo_width`` and ``scattering_coefficient``;
* :func:`incoherent_scattering` -- Monte-Carlo average over partitions with standard errors;
* :mod:`scatterlab.mom.exact` -- the exact series for a PEC circular cylinder.
"""

from scatterlab.mom.efie import Solution, contour, impedance_matrix, physical_optics_current, solve_tm
from scatterlab.mom.exact import cylinder_echo_width, cylinder_surface_field
from scatterlab.mom.incidence import PlaneWave, TaperedWave
from scatterlab.mom.montecarlo import IncoherentResult, incoherent_scattering
from scatterlab.mom.solvers import forward_backward
from scatterlab.mom.surfaces import correlation_length_for_slope, rms_slope, rough_surface

__all__ = ["rough_surface", "rms_slope", "correlation_length_for_slope", "PlaneWave", "TaperedWave", "solve_tm",
           "Solution", "contour", "impedance_matrix", "physical_optics_current", "forward_backward",
           "incoherent_scattering", "IncoherentResult", "cylinder_echo_width", "cylinder_surface_field"]
