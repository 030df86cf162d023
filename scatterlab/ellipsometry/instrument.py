r"""Mueller-matrix ellipsometer: polarization state generator (PSG), analyzer (PSA) and measurement.

A measurement with 4 generated and 4 analysed states is the 4x4 intensity matrix

.. math::  \mathbf B = \mathbf A\,\mathbf M\,\mathbf W ,

where the columns of ``W`` are the Stokes vectors leaving the PSG and the rows of ``A`` are the
analysis vectors of the PSA (the first row of the PSA's Mueller chain, the detector measuring
:math:`S_0`). The sample Mueller matrix is then :math:`\mathbf M = \mathbf A^{-1}\mathbf B\mathbf
W^{-1}` (Eq. 184). Designs:

* :func:`switched_wave_plate_psg` -- the reference's 1064 nm instrument (Sec. 4.4): a polarizing
  beam splitter (horizontal polarizer) followed by two half-wave plates and a quarter-wave plate
  moved in and out of the beam; the four configurations used here are nothing, HWP at 45 deg (V),
  HWP at 22.5 deg (+45) and QWP at 45 deg (circular). The PSA is its mirror image.
* :func:`rotating_retarder_psg` -- a polarizer followed by a retarder at four azimuths.
* :func:`tetrahedral_psg` -- the optimal design: states at the vertices of a regular tetrahedron on
  the Poincare sphere (condition number sqrt(3), the minimum for 4 states).

Every element may be imperfect: retardance and azimuth errors, polarizer extinction ratio. Angles in
radians; matrices ``(4, 4)``; intensities in arbitrary units.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from scatterlab._checks import as_count, as_finite, as_positive, as_rng
from scatterlab.polarization import linear_polarizer, linear_retarder

__all__ = [
    "Errors",
    "switched_wave_plate_psg",
    "switched_wave_plate_psa",
    "rotating_retarder_psg",
    "rotating_retarder_psa",
    "tetrahedral_psg",
    "tetrahedral_psa",
    "Instrument",
    "condition_number",
    "NOISE_MAX",
]


@dataclass(frozen=True)
class Errors:
    """Imperfections of one arm (all angles in radians).

    Attributes
    ----------
    retardance : float or sequence
        Retardance error added to every wave plate (or one per configuration).
    azimuth : float or sequence
        Azimuth error of every wave plate (or one per configuration).
    polarizer_azimuth : float
        Azimuth error of the arm's polarizer.
    extinction_ratio : float
        Extinction ratio of the arm's polarizer (0 = ideal).
    """

    retardance: float | tuple = 0.0
    azimuth: float | tuple = 0.0
    polarizer_azimuth: float = 0.0
    extinction_ratio: float = 0.0

    def per_state(self, value, k):
        return value[k] if np.ndim(value) else value


_SWITCHED_PLATES = (
    None,
    (np.pi, np.pi / 4),
    (np.pi, np.pi / 8),
    (np.pi / 2, np.pi / 4),
)  # none, V, +45, circular


def _switched_arm(errors: Errors):
    """The arm's polarizer and, per configuration, the inserted wave plate (identity when none)."""
    P = linear_polarizer(errors.polarizer_azimuth, errors.extinction_ratio)
    plates = []
    for k, plate in enumerate(_SWITCHED_PLATES):
        if plate is None:
            plates.append(np.eye(4))
        else:
            plates.append(
                linear_retarder(
                    plate[0] + errors.per_state(errors.retardance, k),
                    plate[1] + errors.per_state(errors.azimuth, k),
                )
            )
    return P, plates


def switched_wave_plate_psg(errors: Errors = Errors()) -> np.ndarray:
    """W of the reference's switched wave-plate PSG (columns: H, V, +45, circular).

    Parameters
    ----------
    errors : Errors
        Imperfections of the arm (retardance and azimuth errors per configuration, polarizer
        extinction).

    Returns
    -------
    ndarray (4, 4)
        Generated Stokes vectors as columns; unit-intensity unpolarized source before the polarizer,
        scaled so an ideal state has S0 = 1.
    """
    P, plates = _switched_arm(errors)
    return np.stack([2 * (R @ P)[:, 0] for R in plates], axis=1)


def switched_wave_plate_psa(errors: Errors = Errors()) -> np.ndarray:
    """A of the mirror-image PSA (wave plates, then a horizontal polarizer, then the detector).

    Parameters
    ----------
    errors : Errors
        Imperfections of the arm.

    Returns
    -------
    ndarray (4, 4)
        Analysis vectors as rows.
    """
    P, plates = _switched_arm(errors)
    return np.stack([2 * (P @ R)[0] for R in plates], axis=0)


_RR_ANGLES = np.radians([-51.7, -15.1, 15.1, 51.7])  # a common near-optimal rotating-retarder set


def rotating_retarder_psg(
    angles=_RR_ANGLES, retardance: float = np.radians(132), errors: Errors = Errors()
):
    """W of a polarizer followed by a retarder at four azimuths.

    Parameters
    ----------
    angles : array_like (4,) [rad]
        Retarder azimuths (default +-15.1 and +-51.7 deg, near-optimal with 132 deg).
    retardance : float [rad]
    errors : Errors
        Per-configuration retardance and azimuth errors, polarizer azimuth and extinction.

    Returns
    -------
    ndarray (4, 4)
        Generated Stokes vectors as columns.
    """
    angles = as_finite(angles, "angles")
    P = linear_polarizer(errors.polarizer_azimuth, errors.extinction_ratio)
    cols = [
        2
        * (
            linear_retarder(
                retardance + errors.per_state(errors.retardance, k),
                a + errors.per_state(errors.azimuth, k),
            )
            @ P
        )[:, 0]
        for k, a in enumerate(angles)
    ]
    return np.stack(cols, axis=1)


def rotating_retarder_psa(
    angles=_RR_ANGLES, retardance: float = np.radians(132), errors: Errors = Errors()
):
    """A of a retarder at ``angles`` followed by a polarizer (the mirror of
    :func:`rotating_retarder_psg`).

    Parameters
    ----------
    angles : array_like (4,) [rad]
    retardance : float [rad]
    errors : Errors

    Returns
    -------
    ndarray (4, 4)
        Analysis vectors as rows.
    """
    angles = as_finite(angles, "angles")
    P = linear_polarizer(errors.polarizer_azimuth, errors.extinction_ratio)
    rows = [
        2
        * (
            P
            @ linear_retarder(
                retardance + errors.per_state(errors.retardance, k),
                a + errors.per_state(errors.azimuth, k),
            )
        )[0]
        for k, a in enumerate(angles)
    ]
    return np.stack(rows, axis=0)


def tetrahedral_psg() -> np.ndarray:
    """W with fully polarized unit states at the vertices of a regular tetrahedron on the Poincare
    sphere.

    Returns
    -------
    ndarray (4, 4)
        Generated Stokes vectors as columns (condition number sqrt(3), the optimum).
    """
    v = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)
    return np.vstack([np.ones(4), v.T])


def tetrahedral_psa() -> np.ndarray:
    """A with analysis vectors at the tetrahedron vertices (transpose of :func:`tetrahedral_psg`).

    Returns
    -------
    ndarray (4, 4)
    """
    return tetrahedral_psg().T


def _mueller(M) -> np.ndarray:
    """``M`` as a finite float array of shape (..., 4, 4), else a ValueError naming it."""
    M = as_finite(M, "M (the sample Mueller matrices)")
    if M.ndim < 2 or M.shape[-2:] != (4, 4):
        raise ValueError(
            f"M (the sample Mueller matrices) must have shape (..., 4, 4), got {M.shape}"
        )
    return M


NOISE_MAX = 1.0
"""Largest relative noise of :meth:`Instrument.measure`: a standard deviation equal to the reading."""


def _noise_level(noise) -> float:
    """``noise`` as a float in ``[0, NOISE_MAX]``, else a ValueError naming it and the range."""
    if np.ndim(noise) != 0:
        raise ValueError(f"noise must be a single number in [0, {NOISE_MAX:g}], got {noise!r}")
    value = float(as_positive(noise, "noise", allow_zero=True))
    if value > NOISE_MAX:
        raise ValueError(
            f"noise must be in [0, {NOISE_MAX:g}] (a relative standard deviation: 1 is noise as "
            f"large as the reading itself), got {value:g}"
        )
    return value


def condition_number(X) -> float:
    """2-norm condition number of a PSG or PSA matrix.

    Parameters
    ----------
    X : array_like (4, 4)

    Returns
    -------
    float
        sqrt(3) is optimal for 4 states.
    """
    return float(np.linalg.cond(np.asarray(X, float)))


@dataclass
class Instrument:
    """A Mueller ellipsometer with PSG matrix ``W`` and PSA matrix ``A`` (4x4 each, finite and
    non-singular, else a ValueError naming it).

    ``measure(M, rng, noise=..., repeats=...)`` returns the mean intensity matrix over ``repeats``
    measurements and its standard deviation; detector noise is Gaussian with standard deviation
    ``noise`` times each noiseless intensity (``relative_to="each"``, the default: relative noise of
    every reading) or times the largest intensity of the 4x4 measurement (``relative_to="max"``: a
    constant noise floor), plus an optional absolute floor ``noise_floor``; ``noise`` is in
    ``[0, 1]`` (:data:`NOISE_MAX`).
    """

    W: np.ndarray
    A: np.ndarray
    name: str = "instrument"
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        for nm in ("W", "A"):
            X = np.asarray(getattr(self, nm), float)
            if X.shape != (4, 4) or not np.all(np.isfinite(X)):
                raise ValueError(f"{nm} must be a finite 4x4 matrix")
            rank = np.linalg.matrix_rank(X)
            if rank < 4:
                raise ValueError(
                    f"{nm} must be a non-singular 4x4 matrix (rank 4, four independent states), "
                    f"got rank {rank}: M = A^-1 B W^-1 is then not determined"
                )
            setattr(self, nm, X)
        # physical states: a PSG column is a Stokes vector, a PSA row an analysis vector, both with
        # |(x1, x2, x3)| <= x0. Otherwise a physical sample can give negative intensities.
        for nm, states in (("W", self.W.T), ("A", self.A)):
            excess = np.linalg.norm(states[:, 1:], axis=1) - states[:, 0]
            worst = int(np.argmax(excess))
            if excess[worst] > 1e-9 * np.max(np.abs(states[:, 0])):
                what = "column" if nm == "W" else "row"
                warnings.warn(
                    f"{nm} {what} {worst} is not a physical polarization state (its polarized part "
                    f"exceeds its intensity by {excess[worst]:.3g}): intensities A M W of a physical "
                    "sample can be negative",
                    UserWarning,
                    stacklevel=3,
                )

    @property
    def condition_numbers(self) -> tuple[float, float]:
        """(cond W, cond A)."""
        return condition_number(self.W), condition_number(self.A)

    def intensities(self, M) -> np.ndarray:
        """Noise-free intensities ``B = A M W``.

        Non-negative for a physical ``M`` (see
        :func:`scatterlab.polarization.is_physical_mueller`) and physical states (the class warns
        otherwise); an unphysical ``M`` can give negative intensities, as it would in no experiment.

        Parameters
        ----------
        M : array_like (..., 4, 4)
            Sample Mueller matrices, finite.

        Returns
        -------
        ndarray (..., 4, 4)

        Raises
        ------
        ValueError
            ``M`` not of shape (..., 4, 4), or NaN/inf in it, or intensities beyond the largest
            double (elements of ``M`` near 1e308).
        """
        M = _mueller(M)
        with np.errstate(over="ignore", invalid="ignore"):
            B = self.A @ M @ self.W
        if not np.all(np.isfinite(B)):
            raise ValueError(
                "M (the sample Mueller matrices) is too large: its intensities A M W exceed the "
                f"largest double (1.8e308); largest |M| = {float(np.max(np.abs(M))):.3g}"
            )
        return B

    def measure(
        self,
        M,
        rng=None,
        *,
        noise: float = 0.0,
        noise_floor: float = 0.0,
        repeats: int = 1,
        relative_to: str = "each",
    ):
        """Mean and standard deviation of ``repeats`` noisy measurements of ``M``.

        Parameters
        ----------
        M : array_like (..., 4, 4)
            Sample Mueller matrices.
        rng : None, int >= 0, SeedSequence, BitGenerator or Generator
        noise : float
            Relative Gaussian noise: the standard deviation as a fraction of each reading or of the
            largest (see ``relative_to``), in ``[0, 1]`` (:data:`NOISE_MAX`). At 1 the noise is
            as large as the reading itself (with ``relative_to="each"`` a reading is then negative
            one time in six); beyond, the readings are noise rather than a measurement, and such
            a level (``noise=1e300`` overflowed) is refused rather than simulated.
        noise_floor : float
            Absolute noise standard deviation added to the relative one (same units as B; finite,
            >= 0).
        repeats : int
            Measurements averaged (an integer >= 1).
        relative_to : {"each", "max"}

        Returns
        -------
        B_mean, B_std : ndarray ``(..., 4, 4)`` (std is zero for one repeat).

        Raises
        ------
        ValueError
            ``M`` not a finite array of shape (..., 4, 4); ``noise`` outside ``[0, 1]`` or not
            finite; ``noise_floor`` negative or not finite; ``repeats`` not an integer >= 1; an
            unknown ``relative_to``; an ``rng`` that is not a seed or generator; noisy readings
            beyond the largest double (intensities or ``noise_floor`` near 1e308).

        Notes
        -----
        The readings are ``B + s z`` with ``s = noise * ref + noise_floor`` and ``z`` standard
        normal draws, so the mean and standard deviation are computed as ``B + s mean(z)`` and
        ``s std(z)``: equal to those of the readings, without squaring them (no overflow for
        readings up to the largest double).
        """
        M = _mueller(M)
        repeats = as_count(repeats, "repeats", 1)
        noise = _noise_level(noise)
        if np.ndim(noise_floor) != 0:  # float() of an array was a TypeError
            raise ValueError(f"noise_floor must be a single number >= 0, got {noise_floor!r}")
        noise_floor = float(as_positive(noise_floor, "noise_floor", allow_zero=True))
        if relative_to not in ("each", "max"):
            raise ValueError("relative_to must be 'each' or 'max'")
        rng = as_rng(rng)
        B = self.intensities(M)
        ref = (
            np.abs(B) if relative_to == "each" else np.max(np.abs(B), axis=(-2, -1), keepdims=True)
        )
        z = rng.standard_normal((repeats,) + B.shape)
        with np.errstate(over="ignore", invalid="ignore"):
            scale = noise * ref + noise_floor
            mean = B + scale * z.mean(axis=0)
            std = scale * z.std(axis=0, ddof=1) if repeats > 1 else np.zeros_like(B)
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(std))):
            raise ValueError(
                "the noisy readings exceed the largest double (1.8e308): intensities up to "
                f"{float(np.max(np.abs(B))):.3g} with noise={noise:g} and "
                f"noise_floor={noise_floor:g}; M or noise_floor must be smaller"
            )
        return mean, std
