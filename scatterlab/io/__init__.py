"""Readers and writers of measured data, each validating what it reads.

* Mueller-matrix BRDF tables (long CSV, NIST SCATMECH style): :func:`read_mueller_brdf`,
  :func:`write_mueller_brdf` -> :class:`MuellerBRDF` in the project's geometry (``phi = pi`` specular).
"""

from scatterlab.io.mueller_brdf import MuellerBRDF, read_mueller_brdf, write_mueller_brdf

__all__ = ["MuellerBRDF", "read_mueller_brdf", "write_mueller_brdf"]
