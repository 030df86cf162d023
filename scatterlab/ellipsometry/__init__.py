"""Mueller ellipsometry: instrument model (B = A M W), Eigenvalue Calibration Method, pBRDF fits.

``ecm_calibrate(B0, references)`` returns a calibration with ``.W``, ``.A`` and ``.mueller(B)``.
"""

from scatterlab.ellipsometry.ecm import ECMCalibration, ecm_calibrate, reference_mueller, reference_parameters
from scatterlab.ellipsometry.fit import MuellerFit, fit_mueller_elements, normalised_elements
from scatterlab.ellipsometry.instrument import (
    Errors,
    Instrument,
    condition_number,
    rotating_retarder_psa,
    rotating_retarder_psg,
    switched_wave_plate_psa,
    switched_wave_plate_psg,
    tetrahedral_psa,
    tetrahedral_psg,
)

__all__ = [
    "ecm_calibrate", "ECMCalibration", "fit_mueller_elements", "MuellerFit", "normalised_elements", "reference_mueller", "reference_parameters",
    "Instrument", "Errors", "condition_number", "switched_wave_plate_psg", "switched_wave_plate_psa",
    "rotating_retarder_psg", "rotating_retarder_psa", "tetrahedral_psg", "tetrahedral_psa",
]
