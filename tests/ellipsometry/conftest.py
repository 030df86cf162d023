import numpy as np
import pytest

from scatterlab.ellipsometry import (
    Errors,
    Instrument,
    switched_wave_plate_psa,
    switched_wave_plate_psg,
)
from scatterlab.polarization import linear_polarizer, linear_retarder

TRUE_AZ = np.radians([0.0, 61.5, 118.2, 46.3])  # reference orientations, a few degrees off nominal
NOMINAL = np.radians([0.0, 60.0, 120.0, 45.0])


@pytest.fixture
def instrument():
    """An imperfect switched wave-plate instrument (retardance and azimuth errors, finite
    extinction).
    """
    psg = switched_wave_plate_psg(
        Errors(
            retardance=(0.05, -0.03, 0.04, 0.06),
            azimuth=(0.02, -0.01, 0.03, 0.0),
            extinction_ratio=1e-3,
        )
    )
    psa = switched_wave_plate_psa(
        Errors(
            retardance=(0.03, 0.02, -0.04, 0.01),
            azimuth=(-0.02, 0.01, 0.0, 0.02),
            extinction_ratio=2e-3,
        )
    )
    return Instrument(psg, psa)


def reference_samples():
    return [linear_polarizer(a, 1e-4) * 0.9 for a in TRUE_AZ[:3]] + [
        linear_retarder(np.radians(88), TRUE_AZ[3]) * 0.95
    ]


def measure_references(instrument, rng=None, noise=0.0, repeats=1):
    B0 = instrument.measure(np.eye(4), rng, noise=noise, repeats=repeats)[0]
    Bs = [instrument.measure(M, rng, noise=noise, repeats=repeats)[0] for M in reference_samples()]
    kinds = ["polarizer"] * 3 + ["retarder"]
    return B0, [(k, B, a) for k, B, a in zip(kinds, Bs, NOMINAL)]
