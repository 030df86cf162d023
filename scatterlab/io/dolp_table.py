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
header: ``theta_i [rad]``, ``theta_i_deg``). Column names follow :mod:`scatterlab.io.table`: case, spaces
and underscores do not matter.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from scatterlab.io.table import (
    angle_factor,
    format_table,
    mapped_columns_note,
    read_table,
    signed_polar,
    warn_if_header_disagrees,
    warn_if_radians,
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
    """

    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    dolp: np.ndarray
    std: np.ndarray | None = None
    source: str = ""
    notes: list = field(default_factory=list)

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
        the azimuth + 180 deg), a DOLP outside [-0.05, 1.05] (noise aside, a DOLP is in
        [0, 1]), a standard deviation <= 0, fewer than two rows.
    """
    f = angle_factor(angle_unit)
    unit = "deg" if f != 1.0 else "rad"
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
    warn_if_radians(table.path, (theta_i, theta_r), f, stacklevel=2)
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
    return DolpData(theta_i, theta_r, phi, dolp, std, str(path), notes)


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
