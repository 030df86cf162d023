"""Readers and writers of measured data, each validating what it reads.

Bad input raises ValueError naming the file, row and field.

* Mueller-matrix BRDF tables (long CSV, NIST SCATMECH style): :func:`read_mueller_brdf`,
  :func:`write_mueller_brdf` -> :class:`MuellerBRDF` in the project's geometry (``phi = pi``
  specular), the input of :func:`scatterlab.ellipsometry.fit_pbrdf`.
* Measured DOLP against geometry (CSV): :func:`read_dolp_table` -> :class:`DolpData`, the input of
  ``scatterlab fit-dolp`` and :func:`scatterlab.inversion.sample_posterior`.
* In-plane ellipsometer data (CSV): :func:`read_ellipsometry`, :func:`write_ellipsometry` ->
  :class:`EllipsometryData`, the input of :func:`scatterlab.ellipsometry.fit_mueller_elements`.
* Polarimetric image datasets (channel images at several specular geometries):
  :class:`PolarimetricDataset` in HDF5, NPZ, or TIFF with a sidecar TOML (:func:`read_dataset` /
  :func:`write_dataset` and one pair per format); division-of-focal-plane raw frames are demosaiced
  on reading (:func:`demosaic`).
* Example files of every format: ``python -m scatterlab.io.examples OUT`` (simulated, labelled so).
"""

from scatterlab.io.dataset import (
    Optics,
    PolarimetricDataset,
    Truth,
    read_dataset,
    with_pixel_mask,
    write_dataset,
)
from scatterlab.io.dofp import SONY_POLARSENS, demosaic, mosaic
from scatterlab.io.dolp_table import DolpData, read_dolp_table, write_dolp_table
from scatterlab.io.ellipsometry import EllipsometryData, read_ellipsometry, write_ellipsometry
from scatterlab.io.mueller_brdf import MuellerBRDF, read_mueller_brdf, write_mueller_brdf
from scatterlab.io.stacks import *  # noqa: F403  (the per-format readers and writers)
from scatterlab.io.stacks import __all__ as _stacks_all

__all__ = [
    "MuellerBRDF",
    "read_mueller_brdf",
    "write_mueller_brdf",
    "DolpData",
    "read_dolp_table",
    "write_dolp_table",
    "EllipsometryData",
    "read_ellipsometry",
    "write_ellipsometry",
    "PolarimetricDataset",
    "Optics",
    "Truth",
    "read_dataset",
    "write_dataset",
    "with_pixel_mask",
    "demosaic",
    "mosaic",
    "SONY_POLARSENS",
    *_stacks_all,
]
