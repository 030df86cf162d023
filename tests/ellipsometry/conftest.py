"""Fixtures of the ellipsometry tests; shared helpers (no fixtures) are in _ecm_helpers.py."""

import pytest

from scatterlab.ellipsometry import (
    Errors,
    Instrument,
    switched_wave_plate_psa,
    switched_wave_plate_psg,
)


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
