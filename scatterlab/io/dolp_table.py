r"""Measured DOLP against geometry (CSV): the input of ``scatterlab fit-dolp`` and
:func:`scatterlab.inversion.sample_posterior`.

One row per geometry, the DOLP of unpolarized light reflected by the sample and, optionally, its standard
deviation::

    # DOLP of a painted panel, 1550 nm
    theta_i,theta_r,dolp,std_dolp
    30,30,0.412,0.01
    40,40,0.601,0.01

A single angle column (``theta``) means specular geometry, ``theta_i = theta_r``. An optional azimuth
column (``phi``, the relative azimuth ``phi_r - phi_i``; default 180 deg, observation in the plane of
incidence) gives out-of-plane geometries. Angles in degrees unless ``angle_unit="rad"`` (or a unit in the
header: ``theta_i [rad]``, ``theta_i_deg``); polar angles that are all below pi/2 "degrees" are radians
read as degrees and refused. Column names follow :mod:`scatterlab.io.table`: case, spaces and underscores
do not matter. A column the reader does not use is named in the notes (and warned about when its name
looks like an error column, ``uncertainty``, ``sd``, ``error``, while the table has no ``std_dolp``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from scatterlab.io.table import (
    angle_factor,
    check_column_keys,
    format_table,
    mapped_columns_note,
    read_table,
    signed_polar,
    warn_if_header_disagrees,
)

__all__ = ["DolpData", "read_dolp_table", "write_dolp_table"]

ALIASES = {
    "theta": {"theta", "aoi", "angle", "theta0", "incidence", "thetaspec", "thetaspecular"},
    "theta_i": {"thetai", "ti", "thetainc", "thetain"},
    "theta_r": {"thetar", "thetas", "tr", "ts", "thetao", "thetav", "thetaout", "thetascat"},
    "phi": {"phi", "phir", "phis", "dphi", "azimuth"},
    "dolp": {"dolp", "dop", "p", "dolpmeasured"},
    "std": {
        "stddolp",
        "dolpstd",
        "sddolp",
        "dolpsd",
        "errdolp",
        "dolperr",
        "udolp",
        "sigmadolp",
        "std",
    },
}


# normalised names of columns that look like a DOLP error but are not read as one (the std column's names
# are ALIASES["std"]): said so, with the name the reader expects
ERROR_LIKE = {
    "uncertainty",
    "uncertaintydolp",
    "dolpuncertainty",
    "unc",
    "u",
    "sd",
    "sigma",
    "sigmadolp",
    "err",
    "error",
    "errordolp",
    "dolperror",
    "stderr",
    "stdev",
    "stddev",
    "stdevdolp",
    "stddevdolp",
    "dolpstdev",
    "dolpstddev",
    "ddolp",
    "deltadolp",
    "noise",
}
UNUSED_NOTE = "not used by the reader"


@dataclass
class DolpData:
    """Measured DOLP at M geometries.

    Attributes
    ----------
    theta_i, theta_r : ndarray, shape (M,)
        Incidence and observation polar angles [rad], in [0, pi/2].
    phi : ndarray, shape (M,)
        Relative azimuth ``phi_r - phi_i`` [rad] (pi: observation in the plane of incidence).
    dolp : ndarray, shape (M,)
        Degree of linear polarization (dimensionless, in [0, 1] up to noise).
    std : ndarray, shape (M,), or None
        Its standard deviation, when the file gives one.
    source : str
    notes : list of str
        How the file was read: the geometry assumed or read (the azimuths), signed angles, columns
        mapped by the user or not used.
    unused : list of str
        The file's columns the reader did not use, as named in its header.
    """

    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    dolp: np.ndarray
    std: np.ndarray | None = None
    source: str = ""
    notes: list = field(default_factory=list)
    unused: list = field(default_factory=list)

    @property
    def specular(self) -> bool:
        """Every row is a specular geometry (theta_i = theta_r, phi = pi)."""
        return bool(
            np.allclose(self.theta_i, self.theta_r, atol=1e-12)
            and np.allclose(np.mod(self.phi, 2 * np.pi), np.pi, atol=1e-12)
        )


def read_dolp_table(path, columns=None, *, angle_unit: str = "deg") -> DolpData:
    """Read measured DOLP against geometry (module docstring).

    Parameters
    ----------
    path : str or Path
        CSV (or whitespace-delimited) table.
    columns : dict, optional
        ``{"theta_i": NAME, "theta_r": NAME, "theta": NAME, "phi": NAME, "dolp": NAME, "std": NAME}``
        for column names the reader does not recognise.
    angle_unit : {"deg", "rad"}
        Unit of the angle columns.

    Returns
    -------
    DolpData

    Raises
    ------
    ValueError
        Naming the file, line and column: missing DOLP or angle columns, non-numeric or non-finite cells,
        polar angles beyond 90 deg (a negative one is read as the other side of the normal: |theta|,
        the azimuth + 180 deg), polar angles read in degrees that are all below pi/2 (radians read as
        degrees: at such angles the DOLP is near 0 and determines nothing), a DOLP outside [-0.05, 1.05]
        (noise aside, a DOLP is in [0, 1]), a standard deviation <= 0, fewer than two rows; keys of
        ``columns`` other than those above (naming them and the valid ones).

    Warns
    -----
    UserWarning
        A header comment stating another angle unit; a column the reader does not use whose name looks
        like the DOLP's error (``uncertainty``, ``sd``, ``error``) when there is no std column: the
        error would otherwise be inferred from the scatter without a word (every unused column is named
        in ``notes`` and ``unused``).
    """
    f = angle_factor(angle_unit)
    unit = "deg" if f != 1.0 else "rad"
    check_column_keys(columns, ALIASES, path)
    table = read_table(path)
    warn_if_header_disagrees(table, angle_unit)
    notes = []

    def col(what, required=True):
        i = table.find(ALIASES[what], what, required=required, columns=columns)
        return i

    def angles(i):
        table.check_unit(i, unit, table.names[i], "angle_unit")
        return table.values[:, i] * f

    ti, tr = col("theta_i", False), col("theta_r", False)
    if ti is None and tr is None:
        spec = col("theta")
        theta_i = theta_r = angles(spec)
        notes.append(f"column {table.names[spec]!r}: specular geometry, theta_i = theta_r")
        polar = [(spec, theta_i)]
    elif ti is None or tr is None:
        raise ValueError(
            f"{table.path}: give both theta_i and theta_r (or one 'theta' column for specular "
            f"geometry); columns: {', '.join(table.names)}"
        )
    else:
        theta_i, theta_r = angles(ti), angles(tr)
        polar = [(ti, theta_i), (tr, theta_r)]
    # signed in-plane angles: |theta| with the azimuth turned by pi (the DOLP does not change under the
    # mirror that folds the relative azimuth back)
    turn = np.zeros(theta_i.shape, bool)
    folded = []
    for i, v in polar:
        theta, turned = signed_polar(table, i, v, f)
        folded.append(theta)
        if len(polar) == 2:
            turn ^= turned
        if turned.any():
            how = (
                "the azimuth + 180 deg"
                if len(polar) == 2
                else "both directions on the other side of the normal: phi unchanged"
            )
            notes.append(
                f"column {table.names[i]!r}: {int(turned.sum())} signed angle(s) < 0 read as "
                f"|theta| ({how})"
            )
    theta_i, theta_r = (folded[0], folded[0]) if len(polar) == 1 else folded
    _refuse_radians(table, polar, f)
    pi = col("phi", False)
    phi = np.full(theta_i.shape, np.pi) if pi is None else angles(pi)
    if pi is not None:
        bad = np.abs(phi) > 2 * np.pi + 1e-12
        if bad.any():
            row = int(np.argmax(bad))
            raise ValueError(
                f"{table.where(row)}, column {table.names[pi]!r}: azimuth {table.values[row, pi]} "
                f"{angle_unit} is outside [-360, 360] deg (an azimuth in degrees in a file read "
                "with angle_unit='rad'? every angle column takes the same unit)"
            )
    if pi is None:
        notes.append("no azimuth column: phi = 180 deg (observation in the plane of incidence)")
    else:
        notes.append(_azimuth_note(table, pi, f))
    phi = np.where(turn, np.mod(phi + np.pi, 2 * np.pi), phi)
    di = col("dolp")
    dolp = table.values[:, di]
    bad = (dolp < -0.05) | (dolp > 1.05)
    if bad.any():
        row = int(np.argmax(bad))
        percent = np.all((dolp >= -5) & (dolp <= 105)) and dolp.max() > 1.05
        raise ValueError(
            f"{table.where(row)}, column {table.names[di]!r}: DOLP {dolp[row]} is outside [0, 1] "
            "(by more than a noise margin of 0.05)"
            + ("; the column looks like percent: divide it (and its std) by 100" if percent else "")
        )
    si = col("std", False)
    std = None if si is None else table.values[:, si]
    if std is not None and np.any(std <= 0):
        row = int(np.argmax(std <= 0))
        raise ValueError(
            f"{table.where(row)}, column {table.names[si]!r}: standard deviation must be > 0"
        )
    if dolp.size < 2:
        raise ValueError(f"{table.path}: {dolp.size} row; n and kappa need at least two geometries")
    notes += mapped_columns_note(columns)
    used = {i for i, _ in polar} | {di} | {i for i in (pi, si) if i is not None}
    unused = [name for i, name in enumerate(table.names) if i not in used]
    if unused:
        note = _unused_note(table, used, si is None)
        if si is None and any(table.keys[table.names.index(name)] in ERROR_LIKE for name in unused):
            import warnings

            warnings.warn(f"{table.path}: {note}", UserWarning, stacklevel=2)
        else:
            notes.append(note)
    return DolpData(theta_i, theta_r, phi, dolp, std, str(path), notes, unused)


def _refuse_radians(table, polar, factor: float) -> None:
    """ValueError when every polar angle of a table read in degrees is below pi/2 degrees.

    Radians read as degrees look like that (60 deg written 1.047 is read as 1.047 deg); there the DOLP is
    below 1e-3 and determines nothing, so the fit would report nonsense (``scatterlab.io.dataset`` and the
    scene loader refuse the same).
    """
    if factor == 1.0:
        return
    values = np.abs(np.concatenate([table.values[:, i] for i, _ in polar]))
    if values.max() < np.pi / 2 + 1e-9:
        names = " and ".join(repr(table.names[i]) for i, _ in polar)
        raise ValueError(
            f"{table.path}, column {names}: the polar angles are read in degrees and are all below "
            f"{np.pi / 2:.4f} deg (largest {values.max():g}), where the DOLP is near 0 and determines "
            "nothing: radians read as degrees? Write the angles in degrees, or read the file with "
            "angle_unit='rad' (--angle-unit rad on the command line)"
        )


def _azimuth_note(table, i: int, factor: float) -> str:
    """The azimuths of column ``i`` in degrees, as the file gives them, so that a wrong one shows."""
    deg = table.values[:, i] * factor * 180 / np.pi
    values, counts = np.unique(np.round(deg, 9), return_counts=True)
    if values.size <= 12:
        listed = ", ".join(f"{v:g} ({c} row{'s' if c > 1 else ''})" for v, c in zip(values, counts))
    else:
        listed = f"{values.size} values from {values.min():g} to {values.max():g}"
    note = (
        f"column {table.names[i]!r}: relative azimuths phi = phi_r - phi_i used [deg]: {listed}; 180 is "
        "observation in the plane of incidence, 0 back towards the source"
    )
    if factor != 1.0 and np.any(np.isclose(np.abs(deg), np.pi, atol=2e-3)):
        note += "; 3.14 deg is pi radians read as degrees? (every angle column takes the same unit)"
    return note


def _unused_note(table, used, no_std: bool) -> str:
    """The columns the reader does not use, and the name it expects for one that looks like an error."""
    unused = [i for i in range(len(table.names)) if i not in used]
    names = ", ".join(repr(table.names[i]) for i in unused)
    note = f"column{'s' if len(unused) > 1 else ''} {names} {UNUSED_NOTE}"
    errors = [table.names[i] for i in unused if table.keys[i] in ERROR_LIKE]
    if errors:
        name = errors[0]
        note += (
            f"; if {name!r} is the DOLP's standard deviation, name it std_dolp (or std), or map it with "
            f"columns={{'std': {name!r}}} (--column std={name} on the command line)"
        )
        if no_std:
            note += ": the table has no std column, so no DOLP error is read from it"
    return note


def write_dolp_table(
    path, data: DolpData, *, angle_unit: str = "deg", description: str = "", overwrite: bool = False
):
    """Write DOLP against geometry as CSV that :func:`read_dolp_table` reads back exactly.

    Parameters
    ----------
    path : str or Path
    data : DolpData
    angle_unit : {"deg", "rad"}
        Unit of the file's angle columns, stated in its header comment.
    description : str
        A comment line (where the data came from; "simulated ..." for simulations).
    overwrite : bool

    Returns
    -------
    Path
    """
    from scatterlab.runtime.results import write_text

    fa = angle_factor(angle_unit)
    names = ["theta_i", "theta_r", "phi", "dolp"]
    cols = [data.theta_i / fa, data.theta_r / fa, data.phi / fa, data.dolp]
    if data.std is not None:
        names.append("std_dolp")
        cols.append(data.std)
    comments = ([description] if description else []) + [
        f"DOLP of unpolarized light against geometry; angles in {angle_unit} (phi = phi_r - phi_i, "
        "180: observation in the plane of incidence)"
    ]
    return write_text(
        path, format_table(names, np.column_stack(cols), comments), overwrite=overwrite
    )
