"""Shared helpers of the ECM tests: the reference samples and their simulated measurements.

A plain module, not ``conftest.py``: ``from conftest import ...`` resolves to whichever test folder's
conftest pytest imported last (tests/ are not packages), e.g. tests/pbrdf's when both folders are
collected. The name is unique under tests/, so ``from _ecm_helpers import ...`` is unambiguous (pytest
puts this folder on ``sys.path`` when it imports a test module from it). Fixtures stay in conftest.py.
"""

import numpy as np

from scatterlab.polarization import linear_polarizer, linear_retarder

TRUE_AZ = np.radians([0.0, 61.5, 118.2, 46.3])  # reference orientations, a few degrees off nominal
NOMINAL = np.radians([0.0, 60.0, 120.0, 45.0])


def reference_samples():
    """Three partial polarizers at ``TRUE_AZ[:3]`` and an 88 deg retarder at ``TRUE_AZ[3]``.

    Returns
    -------
    list of ndarray (4, 4)
        Mueller matrices of the references.
    """
    return [linear_polarizer(a, 1e-4) * 0.9 for a in TRUE_AZ[:3]] + [
        linear_retarder(np.radians(88), TRUE_AZ[3]) * 0.95
    ]


def measure_references(instrument, rng=None, noise=0.0, repeats=1):
    """Simulated ECM input: the empty-beam measurement and the references with nominal azimuths.

    Parameters
    ----------
    instrument : scatterlab.ellipsometry.Instrument
    rng : seed or numpy.random.Generator
    noise : float
        Relative noise of :meth:`~scatterlab.ellipsometry.Instrument.measure`.
    repeats : int
        Measurements averaged.

    Returns
    -------
    B0 : ndarray (4, 4)
        Intensities with no sample.
    references : list of (kind, ndarray (4, 4), float)
        ``("polarizer" | "retarder", intensities, nominal azimuth [rad])``.
    """
    B0 = instrument.measure(np.eye(4), rng, noise=noise, repeats=repeats)[0]
    Bs = [instrument.measure(M, rng, noise=noise, repeats=repeats)[0] for M in reference_samples()]
    kinds = ["polarizer"] * 3 + ["retarder"]
    return B0, [(k, B, a) for k, B, a in zip(kinds, Bs, NOMINAL)]
