"""The reference text's published numbers, read from the CSV files shipped with the package.

Tables 1-5, the DOLP priors of Fig. 45 and Chs. V-VII, the classification thresholds and the
complex indices the text uses, transcribed from the text (each file's comment lines say from where,
and what the columns mean). Studies and reports compare with these instead of numbers typed into
code.

Files
-----
The repository's ``data/reference/`` folder is the source of truth (edit there). The package ships
the same files in ``scatterlab/data/reference/`` so that the library finds them after a normal
install; a test checks that the two folders are identical (copy the files over after an edit).

Format: ``#`` comment lines (provenance), then one header line of ``name [unit]`` columns (``[1]``
dimensionless, ``[-]`` text), then the rows. Numeric columns become float arrays, with NaN where a
cell is empty (a value the text does not give); text columns become arrays of str.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from importlib import resources

import numpy as np

__all__ = ["ReferenceTable", "names", "table", "read_reference_csv"]

_HEADER = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*\[([^\]]*)\]\s*$")


@dataclass(frozen=True)
class ReferenceTable:
    """One published table.

    Attributes
    ----------
    name : str
        File stem, e.g. ``"table4_classification"``.
    columns : dict of str -> ndarray, shape ``(rows,)``
        float (NaN for an empty cell) or str, by column name (without unit).
    units : dict of str -> str
        Unit of each column as in the header (``"deg"``, ``"um"``, ``"1"``; ``"-"`` for text).
    notes : str
        The file's comment lines: where the numbers come from and what they mean.
    """

    name: str
    columns: dict
    units: dict
    notes: str

    def __getitem__(self, column: str) -> np.ndarray:
        if column not in self.columns:
            raise KeyError(f"{self.name} has no column {column!r}; columns: {list(self.columns)}")
        return self.columns[column]

    def __len__(self) -> int:
        return len(next(iter(self.columns.values())))

    def rows(self) -> list[dict]:
        """The rows as dicts ``{column: value}`` (floats and str)."""
        return [
            {
                k: v[i].item() if isinstance(v[i], np.generic) else v[i]
                for k, v in self.columns.items()
            }
            for i in range(len(self))
        ]

    def where(self, **match) -> list[dict]:
        """Rows whose columns equal the given values, e.g. ``where(sample="steel")``."""
        return [r for r in self.rows() if all(r[k] == v for k, v in match.items())]


def _files():
    return resources.files("scatterlab").joinpath("data", "reference")


def names() -> list[str]:
    """Names of the shipped tables (file stems), sorted.

    Returns
    -------
    list of str
        The table names, usable with :func:`table`.
    """
    return sorted(p.name[:-4] for p in _files().iterdir() if p.name.endswith(".csv"))


def _column(values: list[str], name: str, source: str) -> np.ndarray:
    try:
        return np.array([float(v) if v.strip() else np.nan for v in values])
    except ValueError:
        if any(not v.strip() for v in values):
            raise ValueError(f"{source}: text column {name!r} has an empty cell") from None
        return np.array(values, dtype=str)


def read_reference_csv(text: str, name: str = "table") -> ReferenceTable:
    """Parse the text of a reference CSV (module docstring); ``name`` labels errors and the result.

    Parameters
    ----------
    text : str
        File contents.
    name : str

    Returns
    -------
    ReferenceTable

    Raises
    ------
    ValueError
        A header cell without ``[unit]``, a duplicate column, a row of the wrong length, or no rows;
        the message names the file and the row.
    """
    lines = text.splitlines()
    notes = "\n".join(x[1:].strip() for x in lines if x.startswith("#"))
    rows = list(
        csv.reader(io.StringIO("\n".join(x for x in lines if x.strip() and not x.startswith("#"))))
    )
    if len(rows) < 2:
        raise ValueError(f"{name}: needs a header line and at least one row")
    cols, units = [], {}
    for cell in rows[0]:
        m = _HEADER.match(cell)
        if not m:
            raise ValueError(f"{name}: header cell {cell!r} must read 'name [unit]'")
        if m[1] in units:
            raise ValueError(f"{name}: duplicate column {m[1]!r}")
        cols.append(m[1])
        units[m[1]] = m[2].strip()
    for i, row in enumerate(rows[1:], start=1):
        if len(row) != len(cols):
            raise ValueError(f"{name}: row {i} has {len(row)} cells, the header {len(cols)}")
    columns = {c: _column([r[j] for r in rows[1:]], c, name) for j, c in enumerate(cols)}
    return ReferenceTable(name, columns, units, notes)


def table(name: str) -> ReferenceTable:
    """The shipped table ``name`` (see :func:`names`), e.g. ``table("table4_classification")``.

    Unknown names raise ValueError listing the allowed ones.

    Parameters
    ----------
    name : str
        Table name (file stem), one of :func:`names`.

    Returns
    -------
    ReferenceTable
        The columns (with units) and their provenance.
    """
    if name not in names():
        raise ValueError(f"unknown reference table {name!r}; name must be one of {names()}")
    return read_reference_csv(_files().joinpath(f"{name}.csv").read_text(encoding="utf-8"), name)
