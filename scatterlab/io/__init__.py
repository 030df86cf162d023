"""Readers and writers of measured data, each validating what it reads.

* Mueller-matrix BRDF tables (long CSV, NIST SCATMECH style): :func:`read_mueller_brdf`,
  :func:`write_mueller_brdf` -> :class:`MuellerBRDF` in the project's geometry (``phi = pi`` specular).
* In-plane ellipsometer data (CSV): :func:`read_ellipsometry`, :func:`write_ellipsometry` ->
  :class:`EllipsometryData`, the input of :func:`scatterlab.ellipsometry.fit_mueller_elements`.
"""

from scatterlab.io.ellipsometry import EllipsometryData, read_ellipsometry, write_ellipsometry
from scatterlab.io.mueller_brdf import MuellerBRDF, read_mueller_brdf, write_mueller_brdf

__all__ = [
    "MuellerBRDF", "read_mueller_brdf", "write_mueller_brdf",
    "EllipsometryData", "read_ellipsometry", "write_ellipsometry",
]
