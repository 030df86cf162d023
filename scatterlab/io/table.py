"""Delimited text tables (CSV) shared by the readers: parsing, columns, units, element names.

A table is a header line of column names followed by one row of numbers per line. Lines starting
with ``#`` are comments (writers put the units and conventions there); blank lines, and rows of empty
cells that spreadsheets leave below the data, are skipped. The delimiter is a comma, a tab, a
semicolon or white space, whichever the header uses; beside any but a comma a number may have a
decimal comma (``0,25``, the European spreadsheet export). Every error names the file, and the row
(line number in the file) and column where there is one.

Column names are matched case-insensitively, ignoring spaces and underscores (``theta_i`` = ``Theta
I`` = ``thetai``). A unit in brackets or after the last underscore (``lambda [nm]``,
``wavelength_nm``, ``theta_deg``) is read and must agree with the unit the caller asked for.

Mueller element names: ``m11`` ... ``m44`` or ``f_r11`` ... ``f_r44`` (1-based, the Mueller-matrix
literature and NIST SCATMECH), or 0-based ``m00`` ... ``m33`` (told apart by the digits used: a 0
means 0-based, a 4 1-based); an element divided by the first one (``f_r12/f_r11``, ``m12/m11``) is
normalised. A standard deviation is the element name with a prefix ``std``, ``sd``, ``err``, ``u``
or a suffix ``std``, ``sd``, ``err`` (``std_m12``, ``m12_err``; normalised: ``std_m12/m11``).
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "Table",
    "read_table",
    "format_table",
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "angle_factor",
    "length_factor",
    "parse_element",
    "element_name",
    "element_columns",
    "TIME_CONVENTIONS",
    "time_convention_flip",
    "ReaderOptions",
    "wavelength_column",
    "WAVELENGTH_RANGE_UM",
    "wavelength_range_problem",
    "likely_wavelength_unit",
    "check_column_keys",
]

ANGLE_UNITS = {"deg": np.pi / 180, "rad": 1.0}
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}
_UNIT_ALIASES = {
    "degree": "deg",
    "degrees": "deg",
    "radian": "rad",
    "radians": "rad",
    "micron": "um",
    "microns": "um",
    "µm": "um",
    "μm": "um",
    "micrometre": "um",
    "micrometer": "um",
    "nanometre": "nm",
    "nanometer": "nm",
}
# time dependence of the file's Jones calculus -> whether its circular elements need a sign flip
# (the letter, i or j, is only notation: exp(+iwt) is exp(+jwt))
TIME_CONVENTIONS = {"exp(+jwt)": False, "exp(-jwt)": True, "exp(-iwt)": True, "exp(+iwt)": False}


def _unit(name: str, allowed: dict, what: str) -> str:
    u = _UNIT_ALIASES.get(str(name).strip().lower(), str(name).strip().lower())
    if u not in allowed:
        raise ValueError(f"{what} must be one of {sorted(allowed)}, got {name!r}")
    return u


def angle_factor(unit: str, what: str = "angle_unit") -> float:
    """Radians per ``unit`` (``"deg"`` or ``"rad"``).

    Parameters
    ----------
    unit : str
        ``"deg"`` or ``"rad"`` (or an accepted alias).
    what : str
        Name of the setting, for the error message.

    Returns
    -------
    float
        Radians per ``unit`` [rad].
    """
    return ANGLE_UNITS[_unit(unit, ANGLE_UNITS, what)]


def refuse_radians_as_degrees(path, polar, factor: float) -> None:
    """Refuse a file read in degrees whose every polar angle is below pi/2 degrees.

    Radians read as degrees look like that: a 90 deg incidence, written 1.5708, would be read as
    1.57 deg, and every fit of such a file is wrong. No goniometric or ellipsometric measurement lies
    wholly within 1.57 deg of the normal, so the reader stops (as the dataset and DOLP-table readers
    do) and names the option.

    Parameters
    ----------
    path : str or Path
        The file, for the message.
    polar : sequence of ndarray
        Polar angles as read [rad].
    factor : float
        The file's angle unit in rad (1.0 for radians: nothing to check).

    Returns
    -------
    None

    Raises
    ------
    ValueError
        Every polar angle below pi/2 degrees in a file read in degrees.
    """
    if factor == 1.0:
        return
    largest = max(float(np.max(np.abs(v))) for v in polar)
    if largest < np.radians(np.pi / 2 + 1e-9):
        raise ValueError(
            f"{path}: every polar angle is below {np.pi / 2:.4f} deg, read in degrees: radians read as "
            "degrees? Give the angles in degrees, or read the file with angle_unit='rad' (--angle-unit "
            "rad on the command line)"
        )


def signed_polar(table, i: int, theta, factor: float, what: str = "polar angle"):
    """In-plane polar angles that may be signed -> ``(|theta|, turned)``.

    A goniometer's negative polar angle is the direction on the other side of the normal: ``|theta|``
    with its azimuth turned by pi (``docs/conventions.md``). The caller turns the azimuth where
    ``turned``.

    Parameters
    ----------
    table : Table
        The file as read (for the message's line and column).
    i : int
        The column.
    theta : ndarray, shape (N,)
        Its angles [rad].
    factor : float
        The file's angle unit in rad (1.0: radians), for the message.
    what : str
        What the angle is, for the message.

    Returns
    -------
    theta : ndarray, shape (N,)
        ``|theta|`` [rad], in [0, pi/2].
    turned : ndarray of bool, shape (N,)
        Rows given with a negative angle.

    Raises
    ------
    ValueError
        Naming the file, line and column, for ``|theta|`` beyond 90 deg; in a file read in radians,
        a value that would be a polar angle in degrees is said to look like one.
    """
    theta = np.asarray(theta, float)
    bad = np.abs(theta) > np.pi / 2 + 1e-12
    if bad.any():
        row = int(np.argmax(bad))
        value = table.values[row, i]
        if factor == 1.0:
            limits = "[-pi/2, pi/2] rad, i.e. -90 to 90 deg"
            hint = (
                "; it looks like degrees: read the file with angle_unit='deg' (--angle-unit deg), "
                "every angle column takes the same unit"
                if abs(value) <= 90
                else ""
            )
        else:
            limits, hint = "[-90, 90] deg", ""
        unit = "rad" if factor == 1.0 else "deg"
        raise ValueError(
            f"{table.where(row)}, column {table.names[i]!r}: {what} {value} {unit} is outside "
            f"{limits} (a negative angle is the other side of the normal){hint}"
        )
    turned = theta < 0
    return np.abs(theta), turned


def warn_if_header_disagrees(
    table, angle_unit: str | None = None, time_convention: str | None = None, stacklevel: int = 2
) -> None:
    """Warn when a file's header comment states an angle unit or time convention other than the one
    it is read with.

    The writers of :mod:`scatterlab.io` state both (``# angles in deg, ...; time convention
    exp(-iwt)``); a reader does not switch on its own (an argument means what it says), it says so.

    Parameters
    ----------
    table : Table
        The file as read (its ``comments``).
    angle_unit, time_convention : str, optional
        What the reader was told (None: not checked).
    stacklevel : int
        ``warnings.warn``'s, counted from the reader that calls this.

    Returns
    -------
    None
        Warns (``UserWarning``) or does nothing.
    """
    import warnings

    text = " ".join(table.comments)
    problems = []
    stated = re.search(r"angles in (deg|rad)\b", text)
    if angle_unit is not None and stated and angle_factor(stated[1]) != angle_factor(angle_unit):
        problems.append(
            f"angles in {stated[1]} but they are read as {angle_unit} (angle_unit={stated[1]!r}, "
            f"--angle-unit {stated[1]} on the command line)"
        )
    stated = re.search(r"time convention (exp\([+-][ij]wt\))", text)
    if (
        time_convention is not None
        and stated
        and time_convention_flip(stated[1]) != time_convention_flip(time_convention)
    ):
        problems.append(
            f"time convention {stated[1]} but it is read as {time_convention} "
            f"(time_convention={stated[1]!r}, --time-convention {stated[1]!r} on the command line)"
        )
    for problem in problems:
        warnings.warn(
            f"{table.path}: its header states {problem}", UserWarning, stacklevel=stacklevel + 1
        )


def length_factor(unit: str, what: str = "wavelength_unit") -> float:
    """Metres per ``unit`` (``"m"``, ``"mm"``, ``"um"``, ``"nm"``).

    Parameters
    ----------
    unit : str
        ``"m"``, ``"mm"``, ``"um"`` or ``"nm"`` (or an accepted alias).
    what : str
        Name of the setting, for the error message.

    Returns
    -------
    float
        Metres per ``unit`` [m].
    """
    return LENGTH_UNITS[_unit(unit, LENGTH_UNITS, what)]


def time_convention_flip(convention: str) -> bool:
    """True when a file in ``convention`` has the circular elements (4th row and column except m33 =
    M_33) of the opposite sign to the project's ``exp(+jwt)`` convention.

    ``"exp(+jwt)"`` (= ``"exp(+iwt)"``, engineering and ellipsometry, the reference text) needs no
    change; ``"exp(-iwt)"`` (= ``"exp(-jwt)"``, physics, NIST SCATMECH) conjugates every Jones
    matrix, which flips the sign of S3 and so of the circular elements.

    Parameters
    ----------
    convention : str
        Time convention of the file, e.g. ``"exp(+jwt)"`` or ``"exp(-iwt)"``.

    Returns
    -------
    bool
        True when the circular elements must change sign.
    """
    key = str(convention).replace(" ", "").replace("omega", "w").replace("ω", "w").lower()
    if key not in TIME_CONVENTIONS:
        raise ValueError(
            f"time_convention must be one of {sorted(TIME_CONVENTIONS)}, got {convention!r}"
        )
    return TIME_CONVENTIONS[key]


def circular_sign() -> np.ndarray:
    """``(4, 4)`` signs that flip the circular elements: ``C M C``, ``C = diag(1, 1, 1, -1)``.

    Returns
    -------
    ndarray, shape (4, 4)
        ``outer(c, c)`` with ``c = (1, 1, 1, -1)``.
    """
    c = np.array([1.0, 1, 1, -1])
    return np.outer(c, c)


def normalise_name(name: str) -> tuple[str, str | None]:
    """``(key, unit)``: lower case without spaces and underscores, and a unit given in brackets or
    as the last underscore-separated word (``"lambda [nm]"`` -> ``("lambda", "nm")``,
    ``"theta_i_deg"`` -> ``("thetai", "deg")``).

    Parameters
    ----------
    name : str
        Column name as written in the header.

    Returns
    -------
    key : str
        Normalised name.
    unit : str or None
        Unit, or None when the name gives none.
    """
    s = name.strip().lower()
    unit = None
    m = re.match(r"^(.*?)\s*[\[(]\s*([^\])]+?)\s*[\])]\s*$", s)
    if m:
        s, unit = m.group(1), m.group(2)
    else:
        parts = s.rsplit("_", 1)
        if len(parts) == 2 and _UNIT_ALIASES.get(parts[1], parts[1]) in {
            **ANGLE_UNITS,
            **LENGTH_UNITS,
        }:
            s, unit = parts
    if unit is not None:
        unit = _UNIT_ALIASES.get(unit, unit)
    return re.sub(r"[\s_]+", "", s), unit


_ELEMENT = r"(?:fr|m|mm|f)(\d)(\d)"
_STD_PREFIX = ("std", "sd", "err", "u", "sigma")
_STD_SUFFIX = ("std", "sd", "err")


def parse_element(key: str):
    """Parse a normalised column key as a Mueller element.

    Parameters
    ----------
    key : str
        Normalised column key (from :func:`normalise_name`).

    Returns
    -------
    tuple or None
        None when ``key`` is not a Mueller element, else ``(digits, normalised, is_std)``:
        ``digits`` ``(j, k, d)`` the index digits as written (base not yet known; ``d`` the digit of
        the normalising element or None), ``normalised`` True for ``mjk/m11``, ``is_std`` True for a
        standard-deviation column.
    """
    is_std = False
    for p in _STD_PREFIX:
        if key.startswith(p) and re.fullmatch(_ELEMENT + r"(?:/" + _ELEMENT + r")?", key[len(p) :]):
            key, is_std = key[len(p) :], True
            break
    else:
        for sfx in _STD_SUFFIX:
            if key.endswith(sfx) and re.fullmatch(
                _ELEMENT + r"(?:/" + _ELEMENT + r")?", key[: -len(sfx)]
            ):
                key, is_std = key[: -len(sfx)], True
                break
    m = re.fullmatch(_ELEMENT + r"(?:/" + _ELEMENT + r")?", key)
    if not m:
        return None
    j, k, dj, dk = m.groups()
    if dj is not None and dj != dk:
        raise ValueError(
            f"column {key!r}: only normalisation by the first element (m11 or m00) is supported"
        )
    return (int(j), int(k), None if dj is None else int(dj)), dj is not None, is_std


def element_name(
    j: int, k: int, *, prefix: str = "m", normalised: bool = False, std: bool = False
) -> str:
    """1-based column name of element ``(j, k)`` (0-based indices): ``m12``, ``f_r12/f_r11``,
    ``std_m12``.

    Parameters
    ----------
    j, k : int
        0-based row and column of the element.
    prefix : str
        Name prefix, e.g. ``"m"`` or ``"f_r"``.
    normalised : bool
        Append ``/<prefix>11``.
    std : bool
        Prepend ``std_`` (standard-deviation column).

    Returns
    -------
    str
        The column name.
    """
    name = f"{prefix}{j + 1}{k + 1}" + (f"/{prefix}11" if normalised else "")
    return f"std_{name}" if std else name


def element_columns(table, default_base: int | None = None, columns: dict | None = None):
    """Mueller element columns of ``table`` (names: module docstring).

    Parameters
    ----------
    table : Table
        A table from :func:`read_table`.
    default_base : {0, 1, None}
        Index base used when the digits do not tell (no 0 and no 4 index); None refuses.
    columns : dict, optional
        The readers' ``columns``: its keys that are element names (``"m12"``, ``"std_m12"``,
        ``"m12/m11"``, in the file's index base) map an element to a column of any name; that column
        then stands for the element, in place of one the file names so.

    Returns
    -------
    values, stds : dict
        Map 0-based ``(j, k)`` to ``(column index, normalised)``, for the values and for their
        standard deviations.
    """
    prefix_err = table.path
    named = {}  # column index -> the element a ``columns`` entry says it holds
    for key, name in (columns or {}).items():
        p = parse_element(normalise_name(str(key))[0])
        if p is None:
            continue
        hits = [i for i, k in enumerate(table.keys) if k == normalise_name(str(name))[0]]
        if not hits:
            raise ValueError(
                f"{prefix_err}: columns[{key!r}] = {name!r} is not a column "
                f"(columns: {', '.join(table.names)})"
            )
        named[hits[0]] = p
    parsed = dict(named)
    for i, key in enumerate(table.keys):
        p = parse_element(key)
        if p is not None and i not in named and p not in named.values():
            parsed[i] = p
    if not parsed:
        raise ValueError(
            f"{prefix_err}: no Mueller element columns (f_r11 ... f_r44, m11 ... m44 or "
            f"m12/m11 ...; columns: {', '.join(table.names)}; {column_hint('m12')})"
        )
    digits = {
        d
        for (j, k, dn), _, _ in parsed.values()
        for d in (j, k) + ((dn,) if dn is not None else ())
    }
    if 0 in digits and 4 in digits:
        raise ValueError(f"{prefix_err}: element names mix 0-based (m00) and 1-based (m44) indices")
    if 0 not in digits and 4 not in digits and default_base is None:
        raise ValueError(
            f"{prefix_err}: cannot tell 0-based from 1-based element names (no 0 and no 4 index)"
        )
    base = 0 if 0 in digits else 1 if 4 in digits else default_base
    values, stds = {}, {}
    for i, ((j, k, dn), normalised, is_std) in parsed.items():
        jk = (j - base, k - base)
        if not (0 <= jk[0] < 4 and 0 <= jk[1] < 4) or (dn is not None and dn != base):
            raise ValueError(
                f"{prefix_err}: column {table.names[i]!r} is not a Mueller element "
                f"({'0-based' if base == 0 else '1-based'} names, normalised by the first)"
            )
        target = stds if is_std else values
        if jk in target:
            raise ValueError(
                f"{prefix_err}: two columns for element {element_name(*jk)}"
                f"{' (std)' if is_std else ''}: {table.names[target[jk][0]]!r}, "
                f"{table.names[i]!r}"
            )
        target[jk] = (i, normalised)
    return values, stds


@dataclass
class Table:
    """A parsed table: ``names`` as written, ``keys``/``units`` normalised, ``values`` ``(rows,
    columns)``, ``lines`` the file line number of each row, ``comments`` the comment lines (without
    ``#``)."""

    path: str
    names: list
    keys: list
    units: list
    values: np.ndarray
    lines: np.ndarray
    comments: list = field(default_factory=list)

    def where(self, row: int) -> str:
        """``"FILE, line L"`` of table row ``row``."""
        return f"{self.path}, line {int(self.lines[row])}"

    def find(self, aliases, what: str, *, required: bool = True, columns: dict | None = None):
        """Index of the column for quantity ``what`` (one of ``aliases``, or ``columns[what]``), or
        None.
        """
        if columns and what in columns:
            target = normalise_name(str(columns[what]))[0]
            hits = [i for i, k in enumerate(self.keys) if k == target]
            if not hits:
                raise ValueError(
                    f"{self.path}: columns[{what!r}] = {columns[what]!r} is not a column "
                    f"(columns: {', '.join(self.names)})"
                )
            return hits[0]
        hits = [i for i, k in enumerate(self.keys) if k in aliases]
        if len(hits) > 1:
            raise ValueError(
                f"{self.path}: columns {[self.names[i] for i in hits]} all name {what}; "
                f"choose one with columns={{{what!r}: NAME}} (--column {what}=NAME on the command "
                "line)"
            )
        if not hits:
            if required:
                raise ValueError(
                    f"{self.path}: missing column for {what} (looked for "
                    f"{', '.join(sorted(aliases))};"
                    f" columns: {', '.join(self.names)}; {column_hint(what)})"
                )
            return None
        return hits[0]

    def check_unit(self, i: int, expected: str, what: str, argument: str) -> None:
        """Raise if column ``i`` states a unit other than ``expected``."""
        unit = self.units[i]
        if unit is not None and unit != expected:
            raise ValueError(
                f"{self.path}: column {self.names[i]!r} is in {unit} but {argument}={expected!r}; "
                f"pass {argument}={unit!r} (--{argument.replace('_', '-')} {unit} on the command "
                "line)"
            )


@dataclass(frozen=True)
class ReaderOptions:
    """The options every table reader takes, validated (``ValueError`` naming the argument).

    Attributes
    ----------
    angle : float
        Radians per unit of the angle columns (``angle_unit``: ``"deg"`` or ``"rad"``).
    length : float
        Metres per unit of the wavelength column (``wavelength_unit``: m, mm, um, nm).
    flip : bool
        The file's time convention is ``exp(-iwt)``: circular elements change sign.
    tolerance : float
        How far (a fraction, in [0, 10)) elements may exceed their bound before a file is refused.
    angle_unit : str
        The angle unit as given (for messages).
    """

    angle: float
    length: float
    flip: bool
    tolerance: float
    angle_unit: str

    @classmethod
    def of(cls, angle_unit, wavelength_unit, time_convention, tolerance) -> "ReaderOptions":
        """Validate the reader arguments of the same names.

        Parameters
        ----------
        angle_unit, wavelength_unit, time_convention : str
        tolerance : float

        Returns
        -------
        ReaderOptions
        """
        if not 0 <= float(tolerance) < 10:
            raise ValueError(f"tolerance must be in [0, 10), got {tolerance}")
        return cls(
            angle_factor(angle_unit),
            length_factor(wavelength_unit),
            time_convention_flip(time_convention),
            float(tolerance),
            str(angle_unit),
        )


# the wavelengths every reader accepts [um]: far ultraviolet to far infrared. A value outside is a
# unit mistake far more often than a measurement (633 nm written where micrometres are expected)
WAVELENGTH_RANGE_UM = (0.01, 100.0)


def wavelength_range_problem(value, unit: str = "um") -> str | None:
    """Why a wavelength is refused, or None when it lies in :data:`WAVELENGTH_RANGE_UM`.

    The one range check of every reader that takes a wavelength (Mueller BRDF tables, ellipsometry,
    datasets): it names the allowed range and, when the number written would lie in it in another
    unit, that unit (``633`` read as um is 633 nm).

    Parameters
    ----------
    value : float
        The wavelength as written in the file, in ``unit``.
    unit : str
        The unit it is read in (``"m"``, ``"mm"``, ``"um"``, ``"nm"``).

    Returns
    -------
    str or None
        ``"wavelength 633 um is outside [0.01, 100] um: ..."``, or None.
    """
    value, unit = float(value), _unit(unit, LENGTH_UNITS, "wavelength unit")
    lo, hi = WAVELENGTH_RANGE_UM
    if lo <= value * LENGTH_UNITS[unit] / 1e-6 <= hi:
        return None
    message = f"wavelength {value:g} {unit} is outside [{lo:g}, {hi:g}] um"
    u = likely_wavelength_unit(value, unit)
    if u is not None:
        message += (
            f": a wavelength in {u} read as {unit}? ({value:g} {u} = "
            f"{value * LENGTH_UNITS[u] / 1e-6:g} um)"
        )
    return message


def likely_wavelength_unit(value, unit: str = "um") -> str | None:
    """The unit in which a wavelength written as ``value`` lies in :data:`WAVELENGTH_RANGE_UM` (the
    one nearest 1 um when several do), or None (also when it does in ``unit`` itself).

    Parameters
    ----------
    value : float
        The wavelength as written.
    unit : str
        The unit it is read in.

    Returns
    -------
    str or None
        ``"m"``, ``"mm"``, ``"um"`` or ``"nm"``.
    """
    lo, hi = WAVELENGTH_RANGE_UM
    value, unit = float(value), _unit(unit, LENGTH_UNITS, "wavelength unit")
    if not value > 0 or lo <= value * LENGTH_UNITS[unit] / 1e-6 <= hi:
        return None
    fits = [u for u in LENGTH_UNITS if lo <= value * LENGTH_UNITS[u] / 1e-6 <= hi]
    return min(fits, key=lambda u: abs(np.log10(value * LENGTH_UNITS[u] / 1e-6)), default=None)


def check_column_keys(columns, valid, path, *, elements: bool = False) -> None:
    """Refuse keys of a reader's ``columns`` mapping that name no quantity the reader reads (a
    misspelt ``"std_dop"`` would otherwise be ignored without a word).

    Parameters
    ----------
    columns : dict or None
        The reader's ``columns``.
    valid : iterable of str
        The quantities the reader takes.
    path : str or Path
        The file, for the message.
    elements : bool
        Mueller element names (``"m12"``, ``"std_m12"``, ``"f_r12/f_r11"``) are keys too.

    Returns
    -------
    None

    Raises
    ------
    ValueError
        Naming the unknown keys and listing the valid ones.
    """
    if not columns:
        return
    if not isinstance(columns, dict):
        raise ValueError(
            f"{path}: columns must be a dict {{quantity: column name}}, got {type(columns).__name__}"
        )
    valid = list(valid)

    def known(key) -> bool:
        if str(key) in valid:
            return True
        if not elements:
            return False
        try:
            return parse_element(normalise_name(str(key))[0]) is not None
        except ValueError:
            return False

    unknown = [k for k in columns if not known(k)]
    if unknown:
        import difflib

        hints = [
            f"{k!r} (did you mean {close[0]!r}?)" if close else repr(k)
            for k in unknown
            for close in [difflib.get_close_matches(str(k), valid, n=1, cutoff=0.6)]
        ]
        raise ValueError(
            f"{path}: unknown key{'s' if len(unknown) > 1 else ''} in columns: {', '.join(hints)}; "
            f"the valid keys are {', '.join(repr(v) for v in valid)}"
            + (" and Mueller element names ('m12', 'std_m12', 'f_r12/f_r11')" if elements else "")
        )


def wavelength_column(table: "Table", i: int, factor: float) -> np.ndarray:
    """Column ``i`` of ``table`` as wavelengths [m], checked against a unit in its header, > 0 and
    within :data:`WAVELENGTH_RANGE_UM` (:func:`wavelength_range_problem`).

    Parameters
    ----------
    table : Table
    i : int
        Column index.
    factor : float
        Metres per unit of the column (:func:`length_factor`).

    Returns
    -------
    ndarray, shape (rows,)
        Wavelengths [m].
    """
    unit = {v: k for k, v in LENGTH_UNITS.items()}[factor]
    table.check_unit(i, unit, table.names[i], "wavelength_unit")
    w = table.values[:, i] * factor
    if np.any(w <= 0):
        row = int(np.argmax(w <= 0))
        raise ValueError(f"{table.where(row)}, column {table.names[i]!r}: wavelength must be > 0")
    for row, value in enumerate(table.values[:, i]):
        problem = wavelength_range_problem(value, unit)
        if problem:
            likely = likely_wavelength_unit(value, unit)
            raise ValueError(
                f"{table.where(row)}, column {table.names[i]!r}: {problem}"
                + (
                    f"; read the file with wavelength_unit={likely!r} (--wavelength-unit {likely} on "
                    "the command line)"
                    if likely
                    else ""
                )
            )
    return w


def column_hint(key: str) -> str:
    """How to name the column of quantity ``key`` (``"theta"``, ``"m12"``, ``"std_m12"``) when the
    reader does not recognise it, in the Python and the command-line spelling.

    Parameters
    ----------
    key : str
        A key of the readers' ``columns``.

    Returns
    -------
    str
        ``"map yours with columns={'key': NAME}, --column key=NAME on the command line"``.
    """
    return f"map yours with columns={{{key!r}: NAME}}, --column {key}=NAME on the command line"


# a number written with a decimal comma (0,25 or -1,5e-3), which float() refuses
_DECIMAL_COMMA = re.compile(r"^[+-]?\d*,\d+([eE][+-]?\d+)?$")


def mapped_columns_note(columns) -> list[str]:
    """The readers' note of a ``columns`` mapping (empty without one), so that a report records
    which of the file's columns stood for which quantity.

    Parameters
    ----------
    columns : dict or None
        Quantity (or element name) -> the file's column name.

    Returns
    -------
    list of str
        One note, or none.
    """
    if not columns:
        return []
    pairs = ", ".join(f"{name!r} as {key}" for key, name in columns.items())
    return [f"columns named by the user (columns= / --column): {pairs}"]


def _split(line: str, delimiter):
    if delimiter is None:
        return line.split()
    return next(csv.reader(io.StringIO(line), delimiter=delimiter, skipinitialspace=True))


def read_table(path) -> Table:
    """Read a delimited table (module docstring); every cell must be a finite number.

    Parameters
    ----------
    path : str or os.PathLike
        The table file.

    Returns
    -------
    Table
        Header names, normalised keys, units, values ``(rows, columns)`` and comments.

    Raises
    ------
    ValueError
        Empty file, duplicate or missing header names, a row with the wrong number of cells, or a
        cell that is not a finite number (NaN, inf, text), naming the file, line and column.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a text table (not UTF-8 text: {exc.reason})") from None
    header, delimiter, rows, lines, comments = None, None, [], [], []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            comments.append(line[1:].strip())
            continue
        if header is None:
            delimiter = next((d for d in (",", "\t", ";") if d in line), None)
            header = [h.strip() for h in _split(line, delimiter)]
            continue
        cells = _split(line, delimiter)
        if delimiter is not None and not any(c.strip() for c in cells):
            continue  # a row of empty cells (",,,," that spreadsheets leave below the data)
        if len(cells) != len(header):
            raise ValueError(
                f"{path}, line {lineno}: {len(cells)} values for {len(header)} columns"
                + (
                    " (decimal commas? in a comma-separated table they split the numbers: write "
                    "decimal points, e.g. 0.25, or separate the columns with ';')"
                    if delimiter == "," and len(cells) > len(header)
                    else ""
                )
            )
        row = []
        for name, cell in zip(header, cells):
            if delimiter != "," and _DECIMAL_COMMA.match(cell.strip()):
                cell = cell.strip().replace(",", ".")  # 0,25 beside ';' or tabs: a decimal comma
            try:
                v = float(cell)
            except ValueError:
                hint = " (an empty cell: fill it or delete the row)" if not cell.strip() else ""
                raise ValueError(
                    f"{path}, line {lineno}, column {name!r}: {cell!r} is not a number{hint}"
                ) from None
            if not np.isfinite(v):
                raise ValueError(
                    f"{path}, line {lineno}, column {name!r}: {cell!r} is not a finite number"
                )
            row.append(v)
        rows.append(row)
        lines.append(lineno)
    if header is None or not rows:
        raise ValueError(f"{path}: no header line and data rows found")
    if any(not h for h in header):
        raise ValueError(f"{path}: empty column name in the header")
    keys, units = zip(*(normalise_name(h) for h in header))
    dup = sorted({k for k in keys if keys.count(k) > 1})
    if dup:
        raise ValueError(f"{path}: duplicate columns {dup}")
    return Table(
        str(path),
        list(header),
        list(keys),
        list(units),
        np.array(rows, float),
        np.array(lines),
        comments,
    )


def format_table(names, values, comments=()) -> str:
    """CSV text: ``# comment`` lines, a header of ``names`` and one row per line of ``values``
    ``(rows, columns)``, 15 significant digits (unit conversions then read back as written: 30, not
    29.999999999999996; the values to ~1e-15 relative).

    Parameters
    ----------
    names : sequence of str
        Column names.
    values : array_like, shape (rows, columns)
        The numbers.
    comments : sequence of str
        Comment lines written first.

    Returns
    -------
    str
        The CSV text, ending with a newline.
    """
    out = [f"# {c}" for c in comments]
    out.append(",".join(names))
    out.extend(",".join(f"{float(v):.15g}" for v in row) for row in np.asarray(values, float))
    return "\n".join(out) + "\n"
