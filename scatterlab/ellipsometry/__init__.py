"""Mueller ellipsometry: instrument model (B = A M W), Eigenvalue Calibration Method, pBRDF fits.

``ecm_calibrate(B0, references)`` returns a calibration with ``.W``, ``.A`` and ``.mueller(B)``;
``fit_mueller_elements`` fits in-plane normalised elements, ``fit_pbrdf`` all 16 elements of a
measured Mueller BRDF (:func:`scatterlab.io.read_mueller_brdf`) in and out of the plane.
"""

from scatterlab.ellipsometry.ecm import (
    ECMCalibration,
    ecm_calibrate,
    reference_mueller,
    reference_parameters,
)
from scatterlab.ellipsometry.fit import (
    MuellerFit,
    fit_mueller_elements,
    model_elements,
    normalised_elements,
)
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
from scatterlab.ellipsometry.pbrdf_fit import PBRDFFit, depolarization_index, fit_pbrdf

__all__ = [
    "ecm_calibrate",
    "ECMCalibration",
    "reference_mueller",
    "reference_parameters",
    "fit_mueller_elements",
    "MuellerFit",
    "normalised_elements",
    "model_elements",
    "fit_pbrdf",
    "PBRDFFit",
    "depolarization_index",
    "Instrument",
    "Errors",
    "condition_number",
    "switched_wave_plate_psg",
    "switched_wave_plate_psa",
    "rotating_retarder_psg",
    "rotating_retarder_psa",
    "tetrahedral_psg",
    "tetrahedral_psa",
]
