r"""Mueller-matrix BRDF tables: long CSV, one row per geometry (the NIST SCATMECH-style format).

A row holds the wavelength, the incidence and observation directions (polar angle from the surface
normal and azimuth of the direction towards the source, ``thetai, phii``, and towards the observer,
``thetar, phir``) and the 16 Mueller elements, absolute [1/sr] or normalised by the first one::

    # simulated: ...
    lambda,thetai,phii,thetar,phir,f_r11,f_r12/f_r11,f_r13/f_r11,...,f_r44/f_r11
    0.6328,30,180,-60,0,0.00123,-0.0211,...

Geometry in memory (the project's convention, :mod:`scatterlab.pbrdf.geometry`): ``theta_i,
theta_r`` in ``[0, pi/2]`` and ``phi = |phi_r - phi_i|`` folded into ``[0, pi]``, with ``phi = pi``
the forward specular plane (the specular direction is ``theta_r = theta_i``, ``phi_r = phi_i + pi``:
in SCATMECH's files ``phii = 180`` and ``phir = 0``). The reader:

* makes signed polar angles positive: a goniometer's ``theta < 0`` is the direction at ``|theta|``
  on the other side of the normal, i.e. with the azimuth turned by 180 deg;
* folds ``phi_r - phi_i`` (mod 360 deg) from ``(pi, 2 pi)`` into ``(0, pi)`` by the mirror ``y ->
  -y`` through the plane of incidence, which maps the Mueller matrix of an isotropic surface to ``R
  M R`` with ``R = diag(1, 1, -1, -1)`` (the mirror reverses the s axis and the helicity: S2 and S3
  change sign);
* converts the time convention: the project's Jones calculus is ``exp(+j w t)``. A file written in
  the ``exp(-i w t)`` convention (NIST SCATMECH, most electromagnetics codes) has every Jones matrix
  conjugated, so the sign of S3 and of the circular elements (4th row and column, except M33 itself)
  flipped. The default is ``time_convention="exp(+jwt)"`` (files written by scatterlab read back
  unchanged); pass ``"exp(-iwt)"`` for SCATMECH output;
* reads angles in degrees and wavelengths in micrometres unless told otherwise (``angle_unit``,
  ``wavelength_unit``), and refuses a column whose name states another unit (``lambda_nm``).

Polarization bases (both the project's and SCATMECH's): for each direction ``(s, p, k)`` is
right-handed with ``s`` perpendicular to the plane holding the direction and the surface normal, and
``S1 = I_s - I_p``.

Header names recognised (case, spaces and underscores ignored; ``columns`` maps any other):
wavelength ``lambda``, ``wavelength``, ``wl``; incidence ``thetai``, ``theta_i``, ``aoi``; ``phii``,
``phi_i``; observation ``thetar``, ``thetas``, ``theta_r``, ``theta_s``; ``phir``, ``phis``,
``phi_r``, ``phi_s``. A lone ``phi`` is the incident azimuth when ``phir`` is present, otherwise the
relative azimuth ``phi_r - phi_i``. Without an incident azimuth, ``phii = 180 deg`` (SCATMECH's
incidence). Elements: see :mod:`scatterlab.io.table`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from scatterlab.io.table import (
    ReaderOptions,
    angle_factor,
    check_column_keys,
    circular_sign,
    column_hint,
    element_columns,
    element_name,
    format_table,
    length_factor,
    mapped_columns_note,
    read_table,
    refuse_radians_as_degrees,
    time_convention_flip,
    warn_if_header_disagrees,
    wavelength_column,
)

__all__ = ["MuellerBRDF", "read_mueller_brdf", "write_mueller_brdf", "MIRROR"]

# R M R elementwise signs, R = diag(1, 1, -1, -1)
MIRROR = np.outer([1.0, 1, -1, -1], [1.0, 1, -1, -1])

ALIASES = {
    "wavelength": {"lambda", "wavelength", "wl", "lam", "lambda0"},
    "theta_i": {"thetai", "ti", "aoi", "thetainc", "incidence", "thetain"},
    "phi_i": {"phii", "phiinc", "phiin"},
    "theta_r": {"thetar", "thetas", "tr", "ts", "thetao", "thetav", "thetaout", "thetascat"},
    "phi_r": {"phir", "phis", "phio", "phiv", "phiout", "phiscat"},
    "phi": {"phi"},
}


@dataclass
class MuellerBRDF:
    """Measured (or simulated) Mueller-matrix BRDF at N geometries, in the project's conventions.

    Attributes
    ----------
    wavelength : ndarray (N,) [m]
    theta_i, theta_r : ndarray (N,) [rad] in ``[0, pi/2]``
    phi : ndarray (N,) [rad] in ``[0, pi]``; ``pi`` is the forward specular plane.
    mueller : ndarray (N, 4, 4) [1/sr]
        Mueller BRDF ``F_jk`` (0-based ``j, k``); when ``normalised`` only ``F_jk / F_00`` is known
        and ``mueller[:, 0, 0] == 1``.
    std : ndarray (N, 4, 4) or None
        Standard deviation of each element of ``mueller`` (zero where the element is exact, e.g. a
        normalised ``F_00``).
    normalised : bool
        The file held normalised elements only (no absolute scale).
    source : str
        The file read, or a description.
    notes : list of str
        What the reader assumed or converted (signed angles, folded azimuths, time convention).
    """

    wavelength: np.ndarray
    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    mueller: np.ndarray
    std: np.ndarray | None = None
    normalised: bool = False
    source: str = ""
    notes: list = field(default_factory=list)

    def __post_init__(self):
        self.mueller = np.asarray(self.mueller, float)
        if self.mueller.ndim != 3 or self.mueller.shape[1:] != (4, 4):
            raise ValueError(f"mueller must have shape (N, 4, 4), got {self.mueller.shape}")
        n = self.mueller.shape[0]
        for name in ("wavelength", "theta_i", "theta_r", "phi"):
            v = np.broadcast_to(np.asarray(getattr(self, name), float), (n,)).copy()
            if not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be finite")
            setattr(self, name, v)
        if not np.all(np.isfinite(self.mueller)):
            raise ValueError("mueller must be finite")
        if np.any(self.wavelength <= 0):
            raise ValueError("wavelength must be > 0 [m]")
        for name, hi in (("theta_i", np.pi / 2), ("theta_r", np.pi / 2), ("phi", np.pi)):
            v = getattr(self, name)
            if np.any(v < 0) or np.any(v > hi + 1e-12):
                raise ValueError(f"{name} must be in [0, {hi:.6g}] rad")
        if self.std is not None:
            self.std = np.asarray(self.std, float)
            if self.std.shape != self.mueller.shape:
                raise ValueError(
                    f"std must have the shape of mueller {self.mueller.shape}, got {self.std.shape}"
                )
            if not np.all(np.isfinite(self.std)) or np.any(self.std < 0):
                raise ValueError("std must be finite and >= 0")

    def __len__(self) -> int:
        return self.mueller.shape[0]

    @property
    def wavelengths(self) -> np.ndarray:
        """The distinct wavelengths [m], ascending."""
        return np.unique(self.wavelength)

    def select(self, wavelength, rtol: float = 1e-6) -> "MuellerBRDF":
        """The rows at one wavelength.

        Parameters
        ----------
        wavelength : float [m]
        rtol : float
            Relative tolerance of the match.

        Returns
        -------
        MuellerBRDF

        Raises
        ------
        ValueError
            No row at ``wavelength`` (the message lists the data's wavelengths).
        """
        w = float(wavelength)
        sel = np.abs(self.wavelength - w) <= rtol * w
        if not sel.any():
            have = ", ".join(f"{x:.6g}" for x in self.wavelengths)
            raise ValueError(f"wavelength {w:.6g} m is not in the data (wavelengths [m]: {have})")
        return self.subset(sel)

    def subset(self, sel) -> "MuellerBRDF":
        """The rows selected by a boolean mask or index array."""
        return replace(
            self,
            wavelength=self.wavelength[sel],
            theta_i=self.theta_i[sel],
            theta_r=self.theta_r[sel],
            phi=self.phi[sel],
            mueller=self.mueller[sel],
            std=None if self.std is None else self.std[sel],
            notes=list(self.notes),
        )

    def normalised_mueller(self) -> np.ndarray:
        """``mueller / mueller[:, 0, 0]``, shape (N, 4, 4) (NaN where ``F_00 = 0``)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.mueller / self.mueller[:, :1, :1]


# -----------------------------------------------------------------------------------------------
# reading
def _mueller(table, values, stds, where):
    """Assemble (N, 4, 4) mueller and std from the element columns; returns (M, std, normalised)."""
    n = table.values.shape[0]
    M00_abs = (0, 0) in values and not values[(0, 0)][1]
    missing = [
        element_name(j, k)
        for j in range(4)
        for k in range(4)
        if (j, k) not in values and not ((j, k) == (0, 0) and not M00_abs)
    ]
    if missing:
        raise ValueError(
            f"{where}: missing Mueller element columns {missing} ({column_hint(missing[0])})"
        )
    M, S = np.zeros((n, 4, 4)), np.zeros((n, 4, 4))
    scale = table.values[:, values[(0, 0)][0]] if M00_abs else np.ones(n)
    for (j, k), (i, normalised) in values.items():
        if (j, k) == (0, 0) and normalised:
            if not np.allclose(table.values[:, i], 1.0):
                raise ValueError(f"{where}: column {table.names[i]!r} (m11/m11) must be 1")
            continue
        M[:, j, k] = table.values[:, i] * (scale if normalised else 1.0)
    M[:, 0, 0] = scale
    if stds:
        need = [(j, k) for j in range(4) for k in range(4) if (j, k) != (0, 0) or M00_abs]
        lacking = [element_name(*jk) for jk in need if jk not in stds]
        if lacking:
            raise ValueError(
                f"{where}: standard deviations given for some elements but not for {lacking}"
                f" (under another name: {column_hint('std_' + lacking[0])})"
            )
        for (j, k), (i, normalised) in stds.items():
            s = table.values[:, i]
            # the normalised first element (m11/m11 = 1) is exact: its std may be 0
            exact = (j, k) == (0, 0) and not M00_abs
            bad = s < 0 if exact else s <= 0
            if np.any(bad):
                row = int(np.argmax(bad))
                raise ValueError(
                    f"{table.where(row)}, column {table.names[i]!r}: standard deviation must be > 0, "
                    f"got {s[row]:g} (a measured element is never exact: give its error, or leave "
                    "the std columns out)"
                )
            S[:, j, k] = s * (scale if normalised and (j, k) != (0, 0) else 1.0)
    return M, (S if stds else None), not M00_abs


def _check_elements(table, M, tolerance, where):
    m00 = M[:, 0, 0]
    if np.any(m00 < 0):
        row = int(np.argmax(m00 < 0))
        raise ValueError(
            f"{table.where(row)}: F_00 (m11) = {m00[row]:.6g} < 0 (a BRDF is non-negative)"
        )
    bound = (1 + tolerance) * m00[:, None, None]
    bad = np.abs(M) > bound
    if np.any(bad):
        row, j, k = np.argwhere(bad)[0]
        raise ValueError(
            f"{table.where(row)}: |{element_name(j, k)}| = {abs(M[row, j, k]):.6g} exceeds "
            f"(1 + tolerance) * m11 = {bound[row, 0, 0]:.6g} (a Mueller element is bounded by the "
            f"first; tolerance={tolerance} allows for noise)"
        )


def _angles(table, columns, opt):
    """Polar angles and azimuths [rad] from the table; returns theta_i, phi_i, theta_r, phi_r,
    notes.
    """
    f, angle_unit = opt.angle, opt.angle_unit
    notes = []

    def col(what, required=True):
        i = table.find(ALIASES[what], what, required=required, columns=columns)
        if i is None:
            return None
        table.check_unit(i, "deg" if f != 1.0 else "rad", table.names[i], "angle_unit")
        return i

    ti, tr = col("theta_i"), col("theta_r")
    pi_, pr, ph = col("phi_i", False), col("phi_r", False), col("phi", False)
    if pr is None and ph is None:
        raise ValueError(
            f"{table.path}: missing column for the observation azimuth (phir, phis or a relative "
            f"phi; {column_hint('phi_r')})"
        )
    if pr is not None and pi_ is None and ph is not None:
        pi_, ph = ph, None  # the "phii or phi": phi beside phir is the incident azimuth
    theta_i, theta_r = table.values[:, ti] * f, table.values[:, tr] * f
    if ph is not None:  # relative azimuth phi_r - phi_i
        phi_i = np.zeros_like(theta_i)
        phi_r = table.values[:, ph] * f
        notes.append(f"column {table.names[ph]!r} read as the relative azimuth phi_r - phi_i")
    else:
        phi_r = table.values[:, pr] * f
        if pi_ is None:
            phi_i = np.full_like(theta_i, np.pi)
            notes.append(
                "no incident azimuth column: phii = 180 deg (SCATMECH's incidence, specular at "
                "phir = 0)"
            )
        else:
            phi_i = table.values[:, pi_] * f
    refuse_radians_as_degrees(table.path, (theta_i, theta_r), f)
    for name, idx, v in (("theta_i", ti, theta_i), ("theta_r", tr, theta_r)):
        bad = np.abs(v) > np.pi / 2 + 1e-12
        if np.any(bad):
            row = int(np.argmax(bad))
            raise ValueError(
                f"{table.where(row)}, column {table.names[idx]!r}: polar angle "
                f"{table.values[row, idx]}"
                f" {angle_unit} is outside [-90, 90] deg (angle_unit={angle_unit!r})"
            )
    return theta_i, phi_i, theta_r, phi_r, notes


def read_mueller_brdf(
    path,
    columns=None,
    *,
    angle_unit: str = "deg",
    wavelength_unit: str = "um",
    time_convention: str = "exp(+jwt)",
    tolerance: float = 0.1,
) -> MuellerBRDF:
    """Read a long-format Mueller BRDF table (module docstring) into the project's conventions.

    Parameters
    ----------
    path : str or Path
        CSV (or tab-, semicolon- or space-delimited) file; ``#`` lines are comments.
    columns : dict, optional
        Maps quantities to the file's column names where they are not recognised: keys
        ``"wavelength"``, ``"theta_i"``, ``"phi_i"``, ``"theta_r"``, ``"phi_r"``, ``"phi"``
        (relative azimuth), and element names (``"f_r12"``, ``"m12"``, ``"std_m12"``,
        ``"m12/m11"``, in the file's index base).
    angle_unit : {"deg", "rad"}
        Unit of the angle columns (default degrees).
    wavelength_unit : {"um", "nm", "mm", "m"}
        Unit of the wavelength column (default micrometres, SCATMECH's unit). A file without a
        wavelength column is refused.
    time_convention : {"exp(+jwt)", "exp(-iwt)"}
        Time dependence of the file's polarization calculus. Default ``"exp(+jwt)"``, the project's
        (and the reference text's); ``"exp(-iwt)"`` (NIST SCATMECH) flips the sign of the circular
        elements (4th row and column except M33).
    tolerance : float
        Elements may exceed the first one in magnitude by this fraction (noise) before the file is
        refused.

    Returns
    -------
    MuellerBRDF
        ``wavelength`` [m], ``theta_i``, ``theta_r``, ``phi`` [rad], ``mueller`` (N, 4, 4) [1/sr],
        ``std`` when the file has standard deviations, ``notes`` on what was converted.

    Raises
    ------
    ValueError
        Naming the file, line and column: a missing or duplicated column, a cell that is not a
        finite number, polar angles outside [-90, 90] deg, a wavelength outside [0.01, 100] um (the
        message names the likely unit: 633 read as um is 633 nm), a negative F_00, a standard
        deviation <= 0, an element larger than F_00 beyond ``tolerance``, a unit in a header
        contradicting the arguments, unknown keys in ``columns``.
    """
    opt = ReaderOptions.of(angle_unit, wavelength_unit, time_convention, tolerance)
    check_column_keys(columns, ALIASES, path, elements=True)
    table = read_table(path)
    warn_if_header_disagrees(table, angle_unit, time_convention)
    wi = table.find(ALIASES["wavelength"], "wavelength", columns=columns)
    wavelength = wavelength_column(table, wi, opt.length)
    theta_i, phi_i, theta_r, phi_r, notes = _angles(table, columns, opt)
    notes += mapped_columns_note(columns)
    values, stds = element_columns(table, columns=columns)
    M, S, normalised = _mueller(table, values, stds, str(path))
    _check_elements(table, M, opt.tolerance, str(path))
    theta_i, theta_r, phi, M = _project_geometry(theta_i, phi_i, theta_r, phi_r, M, notes)
    if opt.flip:
        M *= circular_sign()
        notes.append(
            f"time convention {time_convention}: circular elements sign-flipped to exp(+jwt)"
        )
    return MuellerBRDF(wavelength, theta_i, theta_r, phi, M, S, normalised, str(path), notes)


def _project_geometry(theta_i, phi_i, theta_r, phi_r, M, notes):
    """Signed polar angles and azimuths [rad] -> the project's ``theta >= 0`` and
    ``phi = |phi_r - phi_i|`` folded to [0, pi] (``M`` mirrored where the fold reflects the
    geometry); appends to ``notes`` what was converted. Returns theta_i, theta_r, phi, M."""
    for theta, az, what in ((theta_i, phi_i, "incidence"), (theta_r, phi_r, "observation")):
        neg = theta < 0
        if neg.any():
            theta[neg], az[neg] = -theta[neg], az[neg] + np.pi
            notes.append(
                f"{int(neg.sum())} signed {what} angles < 0 read as |theta| with the azimuth + 180 "
                "deg"
            )
    d = np.mod(phi_r - phi_i, 2 * np.pi)
    mirrored = d > np.pi
    phi = np.where(mirrored, 2 * np.pi - d, d)
    if mirrored.any():
        M[mirrored] *= MIRROR
        notes.append(
            f"{int(mirrored.sum())} rows with phi_r - phi_i in (180, 360) deg mirrored into "
            "[0, 180] (M -> R M R, R = diag(1, 1, -1, -1))"
        )
    return theta_i, theta_r, np.clip(phi, 0.0, np.pi), M


# -----------------------------------------------------------------------------------------------
# writing
def _element_columns(data, ratio, flip):
    """Column names, value columns and standard-deviation columns of the 16 (or 15) elements."""
    sign = circular_sign() if flip else 1.0
    M, Mn, S = data.mueller * sign, data.normalised_mueller() * sign, data.std
    prefix, absolute_first = ("m", False) if data.normalised else ("f_r", True)
    names, cols, std_cols = [], [], []
    for j in range(4):
        for k in range(4):
            first = (j, k) == (0, 0)
            if first and not absolute_first:
                continue
            names.append(element_name(j, k, prefix=prefix, normalised=ratio and not first))
            cols.append(M[:, j, k] if (first or not ratio) else Mn[:, j, k])
            if S is not None:
                std_cols.append(
                    S[:, j, k] if (first or not ratio) else S[:, j, k] / data.mueller[:, 0, 0]
                )
    if S is not None:
        names += ["std_" + n for n in names]
    return names, cols, std_cols


def write_mueller_brdf(
    path,
    data: MuellerBRDF,
    *,
    normalised: bool = False,
    signed: bool = False,
    angle_unit: str = "deg",
    wavelength_unit: str = "um",
    time_convention: str = "exp(+jwt)",
    description: str = "",
    overwrite: bool = False,
) -> Path:
    """Write ``data`` as a SCATMECH-style long CSV that :func:`read_mueller_brdf` reads back
    exactly.

    Parameters
    ----------
    path : str or Path
    data : MuellerBRDF
    normalised : bool
        Write ``f_r11`` and the other elements divided by it (``f_r12/f_r11`` ...), as SCATMECH
        tables do; otherwise all 16 absolute. Data without an absolute scale is always written
        normalised (``m12/m11``).
    signed : bool
        Write in-plane geometries with signed polar angles: ``phir = 0`` and ``thetar < 0`` for
        backward scattering (``phi = 0``), as goniometers record them.
    angle_unit, wavelength_unit : str
        Units of the file (stated in its header comments); degrees and micrometres by default.
    time_convention : {"exp(+jwt)", "exp(-iwt)"}
        Convention of the file (the circular elements are flipped for ``"exp(-iwt)"``).
    description : str
        A comment line (e.g. where the data came from; "simulated ..." for simulations).
    overwrite : bool
        Replace an existing file (otherwise FileExistsError).

    Returns
    -------
    Path
        The file written (atomically).

    Notes ----- The incident azimuth is written as ``phii = 180`` deg (SCATMECH's incidence) and
    ``phir = phi - 180`` deg, so that ``phir = 0`` is the specular plane.
    """
    from scatterlab.runtime.results import write_text

    fa, fw = angle_factor(angle_unit), length_factor(wavelength_unit)
    phi_r = data.phi - np.pi
    theta_r = data.theta_r.copy()
    if signed:
        back = np.isclose(phi_r, -np.pi, atol=1e-12)
        theta_r[back], phi_r[back] = -theta_r[back], 0.0
    geo = np.stack(
        [
            data.wavelength / fw,
            data.theta_i / fa,
            np.full(len(data), np.pi / fa),
            theta_r / fa,
            phi_r / fa,
        ],
        1,
    )
    flip = time_convention_flip(time_convention)
    ratio = normalised or data.normalised
    elem_names, cols, std_cols = _element_columns(data, ratio, flip)
    names = ["lambda", "thetai", "phii", "thetar", "phir"] + elem_names
    values = np.column_stack([geo] + cols + std_cols)
    convention = "exp(-iwt)" if flip else "exp(+jwt) (the project's)"
    comments = ([description] if description else []) + [
        "Mueller-matrix BRDF, long format: one row per geometry; F in 1/sr"
        + ("; elements after f_r11 divided by it" if ratio and not data.normalised else "")
        + ("; normalised elements only (no absolute scale)" if data.normalised else ""),
        f"angles in {angle_unit}, wavelength (lambda) in {wavelength_unit}; time convention "
        f"{convention}",
        "theta from the surface normal; phii, phir: azimuths of the directions towards the source "
        "and the observer; specular: thetar = thetai, phir = phii - 180",
    ]
    return write_text(path, format_table(names, values, comments), overwrite=overwrite)
