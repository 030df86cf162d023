r"""In-plane Mueller ellipsometer data: normalised elements against the specular angle (CSV).

One row per angle ``theta = theta_i = theta_r`` (observation in the specular plane, ``phi = pi``),
with the four normalised elements that :func:`scatterlab.ellipsometry.fit_mueller_elements` fits,
``(M01, M11, M22, M23) / M00`` (0-based; ``m12, m22, m33, m34`` in the 1-based names of the
literature) and, optionally, their standard deviations::

    # simulated: ...
    theta,m12,m22,m33,m34,std_m12,std_m22,std_m33,std_m34
    10,-0.0021,1.0,0.9989,-0.0463,0.002,0.002,0.002,0.002

Angles in degrees unless ``angle_unit="rad"``; an optional ``lambda`` column (one wavelength per
file, micrometres unless ``wavelength_unit``). The element names follow :mod:`scatterlab.io.table`
(``m12/m11`` and 0-based ``m01`` ... are recognised too); a file that also holds the first element
``m11`` is normalised by it. The time convention is an option as for Mueller BRDF tables:
``"exp(-iwt)"`` files have the sign of ``M23`` flipped on reading (default ``"exp(+jwt)"``, the
project's).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scatterlab.io.table import (
    ReaderOptions,
    angle_factor,
    check_column_keys,
    column_hint,
    element_columns,
    element_name,
    format_table,
    length_factor,
    mapped_columns_note,
    read_table,
    refuse_radians_as_degrees,
    signed_polar,
    time_convention_flip,
    warn_if_header_disagrees,
    wavelength_column,
)

__all__ = ["EllipsometryData", "read_ellipsometry", "write_ellipsometry", "IN_PLANE_ELEMENTS"]

IN_PLANE_ELEMENTS = (
    (0, 1),
    (1, 1),
    (2, 2),
    (2, 3),
)  # the order of scatterlab.ellipsometry.fit.ELEMENTS
_ANGLE = {"theta", "thetai", "aoi", "angle", "theta0", "incidence"}
_WAVELENGTH = {"lambda", "wavelength", "wl", "lam"}


@dataclass
class EllipsometryData:
    """In-plane ellipsometry at N specular angles.

    Attributes
    ----------
    theta : ndarray (N,) [rad] in ``[0, pi/2]``, ``theta_i = theta_r``.
    elements : ndarray (N, 4)
        ``(M01, M11, M22, M23) / M00``, each in [-1, 1] up to noise.
    std : ndarray (N, 4) or None
        Standard deviations of ``elements``.
    wavelength : float or None [m]
    source : str
    notes : list of str
    """

    theta: np.ndarray
    elements: np.ndarray
    std: np.ndarray | None = None
    wavelength: float | None = None
    source: str = ""
    notes: list = field(default_factory=list)

    def __post_init__(self):
        self.theta = np.asarray(self.theta, float).ravel()
        self.elements = np.asarray(self.elements, float)
        if self.elements.shape != (self.theta.size, 4):
            raise ValueError(
                f"elements must have shape ({self.theta.size}, 4), got {self.elements.shape}"
            )
        if not (np.all(np.isfinite(self.theta)) and np.all(np.isfinite(self.elements))):
            raise ValueError("theta and elements must be finite")
        if np.any(self.theta < 0) or np.any(self.theta > np.pi / 2):
            raise ValueError("theta must be in [0, pi/2] rad")
        if self.std is not None:
            self.std = np.asarray(self.std, float)
            if (
                self.std.shape != self.elements.shape
                or not np.all(np.isfinite(self.std))
                or np.any(self.std < 0)
            ):
                raise ValueError(f"std must be finite, >= 0 and of shape {self.elements.shape}")
        if self.wavelength is not None and not float(self.wavelength) > 0:
            raise ValueError(f"wavelength must be > 0 [m], got {self.wavelength}")


def read_ellipsometry(
    path,
    columns=None,
    *,
    angle_unit: str = "deg",
    wavelength_unit: str = "um",
    time_convention: str = "exp(+jwt)",
    tolerance: float = 0.1,
) -> EllipsometryData:
    """Read in-plane ellipsometer data (module docstring).

    Parameters
    ----------
    path : str or Path
    columns : dict, optional
        ``{"theta": NAME, "wavelength": NAME}`` for unrecognised angle or wavelength column names,
        and element names (``"m12"``, ``"std_m12"``, 1-based) for unrecognised element columns.
    angle_unit : {"deg", "rad"}
    wavelength_unit : {"um", "nm", "mm", "m"}
    time_convention : {"exp(+jwt)", "exp(-iwt)"}
        ``"exp(-iwt)"`` flips the sign of M23 (the project's convention is ``exp(+jwt)``).
    tolerance : float
        Normalised elements may exceed 1 in magnitude by this much (noise) before the file is
        refused.

    Returns
    -------
    EllipsometryData
        ``theta`` [rad], ``elements`` (N, 4), ``std`` (N, 4) or None, ``wavelength`` [m] or None.

    Raises
    ------
    ValueError
        Naming the file, line and column: missing angle or element columns, non-numeric or
        non-finite cells, angles beyond 90 deg (a negative one is the mirror geometry: |theta|),
        elements outside [-1 - tolerance, 1 + tolerance], standard deviations <= 0, a wavelength
        outside [0.01, 100] um (the message names the likely unit: 1064 read as um is 1064 nm),
        several wavelengths in one file, unknown keys in ``columns``.
    """
    opt = ReaderOptions.of(angle_unit, wavelength_unit, time_convention, tolerance)
    check_column_keys(columns, ("theta", "wavelength"), path, elements=True)
    table = read_table(path)
    warn_if_header_disagrees(table, angle_unit, time_convention)
    ai = table.find(_ANGLE, "theta", columns=columns)
    table.check_unit(ai, "deg" if opt.angle != 1.0 else "rad", table.names[ai], "angle_unit")
    # a signed angle of incidence is the mirror geometry, whose in-plane block (m12, m22, m33, m34) is
    # the same (R M R with R = diag(1, 1, -1, -1) leaves it): |theta|
    theta, turned = signed_polar(table, ai, table.values[:, ai] * opt.angle, opt.angle, "angle")
    refuse_radians_as_degrees(table.path, (theta,), opt.angle)
    wavelength = _wavelength(table, columns, opt.length)
    E, S = _elements(table, theta.size, opt.tolerance, columns)
    _warn_if_m12_negative(table.path, E[:, 0], None if S is None else S[:, 0])
    notes = []
    if turned.any():
        notes.append(
            f"{int(turned.sum())} signed angle(s) < 0 read as |theta| (the mirror geometry, whose "
            "in-plane elements are the same)"
        )
    if opt.flip:
        E[:, 3] = -E[:, 3]
        notes.append(f"time convention {time_convention}: M23 sign-flipped to exp(+jwt)")
    notes += mapped_columns_note(columns)
    return EllipsometryData(theta, E, S, wavelength, str(path), notes)


def _warn_if_m12_negative(path, m12, std) -> None:
    """Warn when more rows have m12 clearly below 0 than above (at least two): the other sign
    convention of S1.

    Specular reflection from an isotropic passive surface has :math:`|r_p| \\le |r_s|` (Abeles:
    :math:`r_p = r_s (r_s - \\cos 2\\theta) / (1 - r_s \\cos 2\\theta)`, a factor of modulus <= 1), so
    with S1 = I_s - I_p the normalised m12 = (R_s - R_p) / (R_s + R_p), diluted by any unpolarized
    diffuse light, is >= 0 at every angle. "Clearly" is beyond 3 standard deviations and 0.01 (a
    metal's m12 stays near 0 up to 30-40 deg, so a majority of rows need not be clear either way).
    """
    margin = np.maximum(3 * std, 0.01) if std is not None else 0.01
    negative, positive = int(np.sum(m12 < -margin)), int(np.sum(m12 > margin))
    if negative >= 2 and negative > positive:
        warnings.warn(
            f"{path}: m12 < 0 at {negative} of {m12.size} angles, but specular reflection has "
            "R_s >= R_p, so m12 = (R_s - R_p) / (R_s + R_p) >= 0 with S1 = I_s - I_p (this "
            "package's convention): the file probably takes S1 = I_p - I_s; negate its m12 column "
            "(the fit of these data is not meaningful)",
            UserWarning,
            stacklevel=3,
        )


def _elements(table, n, tolerance, columns=None):
    """In-plane elements (n, 4), normalised, and their standard deviations (or None)."""
    values, stds = element_columns(table, default_base=1, columns=columns)
    missing = [element_name(j, k) for j, k in IN_PLANE_ELEMENTS if (j, k) not in values]
    if missing:
        raise ValueError(
            f"{table.path}: missing element columns {missing} (in-plane data: m12, m22, m33, m34; "
            f"{column_hint(missing[0])})"
        )
    first = values.get((0, 0))
    scale = table.values[:, first[0]] if first is not None and not first[1] else np.ones(n)
    if np.any(scale <= 0):
        row = int(np.argmax(scale <= 0))
        raise ValueError(f"{table.where(row)}: m11 = {scale[row]} must be > 0 to normalise by it")

    def stack(cols):
        return np.stack(
            [
                table.values[:, cols[jk][0]] / (1.0 if cols[jk][1] else scale)
                for jk in IN_PLANE_ELEMENTS
            ],
            1,
        )

    E, S = stack(values), None
    if stds:
        lacking = [element_name(*jk) for jk in IN_PLANE_ELEMENTS if jk not in stds]
        if lacking:
            raise ValueError(
                f"{table.path}: standard deviations given for some elements but not for {lacking}"
                f" (under another name: {column_hint('std_' + lacking[0])})"
            )
        S = stack(stds)
        if np.any(S <= 0):
            row, c = np.argwhere(S <= 0)[0]
            raise ValueError(
                f"{table.where(row)}, column {table.names[stds[IN_PLANE_ELEMENTS[c]][0]]!r}: "
                f"standard deviation must be > 0, got {S[row, c]:g} (a measured element is never "
                "exact: give its error, or leave the std columns out and the fit infers one error "
                "from the scatter)"
            )
    out = np.abs(E) > 1 + tolerance
    if out.any():
        row, c = np.argwhere(out)[0]
        raise ValueError(
            f"{table.where(row)}, column {table.names[values[IN_PLANE_ELEMENTS[c]][0]]!r}: "
            f"normalised element {E[row, c]:.6g} is outside [-1, 1] beyond tolerance={tolerance}"
        )
    return E, S


def _wavelength(table, columns, factor):
    wi = table.find(_WAVELENGTH, "wavelength", required=False, columns=columns)
    if wi is None:
        return None
    w = np.unique(wavelength_column(table, wi, factor))
    if w.size != 1:
        raise ValueError(
            f"{table.path}: several wavelengths {(w / factor).tolist()} in one ellipsometry file "
            "(one per file)"
        )
    return float(w[0])


def write_ellipsometry(
    path,
    data: EllipsometryData,
    *,
    angle_unit: str = "deg",
    wavelength_unit: str = "um",
    time_convention: str = "exp(+jwt)",
    description: str = "",
    overwrite: bool = False,
) -> Path:
    """Write in-plane ellipsometer data as CSV that :func:`read_ellipsometry` reads back exactly.

    Parameters
    ----------
    path : str or Path
    data : EllipsometryData
    angle_unit, wavelength_unit : str
        Units of the file (degrees and micrometres by default), stated in its header comments.
    time_convention : {"exp(+jwt)", "exp(-iwt)"}
    description : str
        A comment line (where the data came from; "simulated ..." for simulations).
    overwrite : bool

    Returns
    -------
    Path
    """
    from scatterlab.runtime.results import write_text

    fa = angle_factor(angle_unit)
    E = data.elements.copy()
    if time_convention_flip(time_convention):
        E[:, 3] = -E[:, 3]
    names = ["theta"] + [element_name(j, k) for j, k in IN_PLANE_ELEMENTS]
    cols = [data.theta / fa, E]
    if data.std is not None:
        names += ["std_" + n for n in names[1:5]]
        cols.append(data.std)
    if data.wavelength is not None:
        names.append("lambda")
        cols.append(np.full((len(data.theta), 1), data.wavelength / length_factor(wavelength_unit)))
    comments = ([description] if description else []) + [
        "in-plane Mueller ellipsometry: theta = theta_i = theta_r (specular plane); elements "
        "normalised by m11 "
        "(1-based names: m12 = M01/M00, m22 = M11/M00, m33 = M22/M00, m34 = M23/M00)",
        f"angles in {angle_unit}"
        + (f", wavelength (lambda) in {wavelength_unit}" if data.wavelength else "")
        + f"; time convention {time_convention}",
    ]
    values = np.column_stack([c if np.ndim(c) == 2 else c[:, None] for c in cols])
    return write_text(path, format_table(names, values, comments), overwrite=overwrite)
