"""Polarimetric image stacks on disk: HDF5, NPZ, and TIFF with a sidecar TOML.

The keys are those of :mod:`scatterlab.io.dataset`.

* HDF5: arrays as datasets (gzip-compressed), scalars and strings as attributes of the root group;
* NPZ: every key an array (strings as 0-d unicode arrays; read with ``allow_pickle=False``);
* TIFF: the images as pages (``counts``: G*K pages, geometry-major -- geometry 0's channels first;
  ``raw``: one page per geometry) and a sidecar ``NAME.toml`` holding every other key, ``layout =
  "channels"`` or ``"dofp"``, and optionally ``tiff`` (the stack's file name, or a list of one file
  per geometry), ``truth`` (an NPZ file with the ``truth_*`` arrays) and ``bad_pixels`` (the name of
  a TIFF, one page for the sensor or one per geometry, or of a ``.npy`` file: non-zero = bad).
  A user's own stack needs
  only a sidecar such as::

      wavelength_um = 1.55
      theta_deg = [40, 55]
      polarizer_deg = [0, 45, 90, 135]
      pixels_per_lambda_over_d = 2.0
      layout = "channels"
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from scatterlab.io.dataset import (
    FORMAT_NAME,
    PolarimetricDataset,
    _check_keys,
    check_write_arguments,
    from_flat,
    to_flat,
)

__all__ = [
    "read_dataset_hdf5",
    "write_dataset_hdf5",
    "read_dataset_npz",
    "write_dataset_npz",
    "read_dataset_tiff",
    "write_dataset_tiff",
    "read_pixel_mask",
]

_IMAGES = ("counts", "raw")


def _store(v):
    """float32 for images (counts carry ~1e-7 relative rounding, far below shot noise), as-is
    otherwise.
    """
    a = np.asarray(v)
    return a.astype(np.float32) if a.dtype.kind == "f" and a.ndim >= 2 else a


def _write_hdf5(path, flat: dict, overwrite: bool) -> Path:
    import h5py

    from scatterlab.runtime.results import atomic_write_bytes

    buf = io.BytesIO()
    with h5py.File(buf, "w") as f5:
        for key, value in flat.items():
            a = np.asarray(value)
            if a.ndim == 0:
                f5.attrs[key] = value
            elif a.dtype.kind == "U":
                f5.create_dataset(key, data=a.astype(object), dtype=h5py.string_dtype())
            else:
                f5.create_dataset(key, data=_store(a), compression="gzip", shuffle=True)
    return atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)


def _read_hdf5(path) -> dict:
    import h5py

    try:
        f5 = h5py.File(path, "r")
    except OSError as exc:
        raise ValueError(f"{path}: not an HDF5 file ({exc})") from None
    with f5:
        flat = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f5.attrs.items()}
        for key, item in f5.items():
            if isinstance(item, h5py.Dataset):
                data = item[()]
                flat[key] = (
                    np.array([x.decode() if isinstance(x, bytes) else x for x in data])
                    if item.dtype.kind == "O"
                    else np.asarray(data)
                )
    return flat


def _write_npz(path, flat: dict, overwrite: bool) -> Path:
    from scatterlab.runtime.results import write_npz

    return write_npz(path, overwrite=overwrite, **{k: _store(v) for k, v in flat.items()})


def _read_npz(path) -> dict:
    import zipfile

    # an NPZ is a zip archive: anything else would reach numpy's loader, whose message for arbitrary bytes
    # is about pickles ("allow_pickle"), which says nothing to a user with a damaged file
    if not zipfile.is_zipfile(path):
        raise ValueError(
            f"{path}: not an NPZ dataset (not a zip archive: damaged or another format)"
        )
    try:
        with np.load(path, allow_pickle=False) as z:
            flat = {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise ValueError(f"{path}: not a readable NPZ dataset ({exc})") from None
    return {k: (v.item() if v.ndim == 0 else v) for k, v in flat.items()}


_WRITER_DOC = """Write ``ds`` to {what}.

    Parameters
    ----------
    path : str or Path
    ds : PolarimetricDataset
    dofp_pattern : array_like (2, 2) [deg], optional
        Store DoFP raw frames with this 2x2 layout (four channels needed) instead of channel images.
    overwrite : bool
        Replace existing files (otherwise FileExistsError).

    Returns
    -------
    Path
        The file written (atomically).
    """

_READER_DOC = """Read a dataset from {what}.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    PolarimetricDataset

    Raises
    ------
    ValueError
        Not a readable {kind} file, or a key missing or invalid (named with the file).
    """


def _file_format(name: str, what: str, write_flat, read_flat):
    """The public writer and reader of one file format (``write_dataset_NAME``,
    ``read_dataset_NAME``) from its backends between a file and the flat dict of
    :func:`~scatterlab.io.dataset.to_flat`."""

    def write(path, ds: PolarimetricDataset, *, dofp_pattern=None, overwrite: bool = False) -> Path:
        check_write_arguments(path, ds, f"write_dataset_{name}")
        return write_flat(path, to_flat(ds, dofp_pattern=dofp_pattern), overwrite)

    def read(path) -> PolarimetricDataset:
        return from_flat(read_flat(path), str(path))

    for f, verb, doc in ((write, "write", _WRITER_DOC), (read, "read", _READER_DOC)):
        f.__name__ = f.__qualname__ = f"{verb}_dataset_{name}"
        f.__doc__ = doc.format(what=what, kind=name.upper())
    return write, read


write_dataset_hdf5, read_dataset_hdf5 = _file_format(
    "hdf5", "HDF5 (images gzip-compressed, as float32)", _write_hdf5, _read_hdf5
)
write_dataset_npz, read_dataset_npz = _file_format(
    "npz", "a compressed NPZ (images as float32; no pickles)", _write_npz, _read_npz
)


# ------------------------------------------------------------------------------------------------
# TIFF
def _toml_value(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    a = np.asarray(v)
    if a.ndim:
        return "[" + ", ".join(_toml_value(x) for x in a.tolist()) + "]"
    return repr(float(a)) if a.dtype.kind == "f" else str(a.item())


def write_dataset_tiff(
    path,
    ds: PolarimetricDataset,
    *,
    dofp_pattern=None,
    overwrite: bool = False,
    truth_file: str | None = None,
) -> Path:
    """Write the images as a multi-page float32 TIFF, the rest as its sidecar TOML.

    Parameters
    ----------
    path, ds, dofp_pattern, overwrite
        As :func:`~scatterlab.io.write_dataset`.
    truth_file : str, optional
        Name of the truth NPZ beside the TIFF (default ``NAME-truth.npz``), named in the sidecar.

    Returns
    -------
    Path
        The file written (atomically).
    """
    import tifffile

    from scatterlab.runtime.results import atomic_write_bytes, write_npz, write_text

    check_write_arguments(path, ds, "write_dataset_tiff")
    path = Path(path)
    flat = to_flat(ds, dofp_pattern=dofp_pattern)
    key = "raw" if "raw" in flat else "counts"
    pages = np.asarray(flat.pop(key), np.float32)
    pages = pages.reshape((-1,) + pages.shape[-2:])
    truth = {k: flat.pop(k) for k in list(flat) if k.startswith("truth_")}
    bad = flat.pop("bad_pixels", None)
    lines = [
        f"# {FORMAT_NAME}: sidecar of {path.name} (pages: "
        + (
            "one DoFP raw frame per geometry)"
            if key == "raw"
            else "G*K channel images, geometry-major)"
        ),
        f'tiff = "{path.name}"',
        f'layout = "{"dofp" if key == "raw" else "channels"}"',
    ]
    if truth:
        name = truth_file or f"{path.stem}-truth.npz"
        write_npz(
            path.parent / name, overwrite=overwrite, **{k: _store(v) for k, v in truth.items()}
        )
        lines.append(f'truth = "{name}"')
    if bad is not None:
        name = f"{path.stem}-bad_pixels.tif"
        mask = io.BytesIO()
        tifffile.imwrite(mask, np.asarray(bad, np.uint8), photometric="minisblack")
        atomic_write_bytes(path.parent / name, mask.getvalue(), overwrite=overwrite)
        lines.append(f'bad_pixels = "{name}"')
    lines += [f"{k} = {_toml_value(v)}" for k, v in flat.items()]
    buf = io.BytesIO()
    tifffile.imwrite(buf, pages, photometric="minisblack")
    atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)
    write_text(path.with_suffix(".toml"), "\n".join(lines) + "\n", overwrite=overwrite)
    return path


# the keys a TIFF sidecar holds besides a dataset's own
_SIDECAR_KEYS = ("tiff", "layout", "truth")


def _sidecar(path: Path) -> Path:
    if path.suffix.lower() == ".toml":
        return path
    side = path.with_suffix(".toml")
    if not side.exists():
        raise ValueError(
            f"{path}: a TIFF stack needs its sidecar {side.name} (wavelength_um, theta_deg, "
            f"polarizer_deg, pixels_per_lambda_over_d, layout; see scatterlab.io.stacks)"
        )
    return side


def _load_pages(side: Path, meta: dict, default: Path) -> np.ndarray:
    import tifffile

    names = meta.pop("tiff", None)
    if names is None and not default.exists():
        scene = {"plates", "geometry_deg", "image_size", "d_over_r0"} & set(meta)
        raise ValueError(
            f"{side}: expected a dataset: no TIFF stack {default.name} beside this TOML and no "
            "'tiff' key"
            + (
                " (it looks like a scene description: run it with `scatterlab characterize`)"
                if scene
                else ""
            )
        )
    files = (
        [default]
        if names is None
        else [side.parent / n for n in ([names] if isinstance(names, str) else names)]
    )
    stacks = []
    for f in files:
        if not f.exists():
            raise ValueError(f"{side}: 'tiff' names {f.name}, which does not exist")
        try:
            a = np.asarray(tifffile.imread(f), float)
        except Exception as exc:  # tifffile raises several kinds for a non-TIFF file
            raise ValueError(f"{f}: not a readable TIFF ({exc})") from None
        stacks.append(a.reshape((-1,) + a.shape[-2:]))
    shapes = {s.shape[1:] for s in stacks}
    if len(shapes) != 1:
        raise ValueError(f"{side}: the TIFF files have different image sizes {sorted(shapes)}")
    return np.concatenate(stacks)


def read_pixel_mask(path) -> np.ndarray:
    """A bad-pixel mask file: a TIFF (one page for the sensor, or one per geometry) or a ``.npy``.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    ndarray (H, W) or (G, H, W)
        Non-zero where a pixel is bad (the dataset key ``bad_pixels``).

    Raises
    ------
    ValueError
        A missing or unreadable file, named.
    """
    import tifffile

    f = Path(path)
    if not f.exists():
        raise ValueError(f"bad-pixel mask {f}: no such file")
    try:
        if f.suffix.lower() == ".npy":
            return np.load(f, allow_pickle=False)
        return np.asarray(tifffile.imread(f))
    except Exception as exc:  # tifffile and numpy raise several kinds for a damaged file
        raise ValueError(f"bad-pixel mask {f}: not a readable TIFF or .npy ({exc})") from None


def _load_mask(side: Path, name: str) -> np.ndarray:
    """The ``bad_pixels`` file a sidecar names."""
    try:
        return read_pixel_mask(side.parent / name)
    except ValueError as exc:
        raise ValueError(f"{side}: 'bad_pixels' names {name}: {exc}") from None


def read_dataset_tiff(path) -> PolarimetricDataset:
    """Read a TIFF stack and its sidecar TOML.

    Parameters
    ----------
    path : str or Path
        The TIFF (its sidecar is ``path.with_suffix(".toml")``) or the sidecar itself.

    Returns
    -------
    PolarimetricDataset

    Raises
    ------
    ValueError
        No sidecar, invalid TOML, an unknown layout, missing TIFF files, a page count that does not
        match the geometries and channels, or an invalid key (named with the file).
    """
    import tomllib

    path = Path(path)
    side = _sidecar(path)
    try:
        meta = tomllib.loads(side.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{side}: not a valid TOML sidecar ({exc})") from None
    scene = sorted({"plates", "geometry_deg", "image_size", "d_over_r0"} & set(meta))
    if scene and "theta_deg" not in meta:
        raise ValueError(
            f"{side}: expected a dataset, but its keys {', '.join(scene)} are those of a scene description "
            "(run it with `scatterlab characterize`)"
        )
    # a misspelt key first: without it (theta_degs for theta_deg) the page count below would be wrong
    _check_keys(meta, str(side), extra=_SIDECAR_KEYS)
    layout = meta.pop("layout", "channels")
    if layout not in ("channels", "dofp"):
        raise ValueError(f"{side}: layout must be 'channels' or 'dofp', got {layout!r}")
    default = (
        path
        if path.suffix.lower() != ".toml"
        else next(
            (p for p in (side.with_suffix(".tif"), side.with_suffix(".tiff")) if p.exists()),
            side.with_suffix(".tif"),
        )
    )
    pages = _load_pages(side, meta, default)
    truth = meta.pop("truth", None)
    if truth is not None:
        try:
            with np.load(side.parent / truth, allow_pickle=False) as z:
                meta.update({k: z[k] for k in z.files})
        except (OSError, ValueError) as exc:
            raise ValueError(
                f"{side}: truth file {truth!r} is not a readable NPZ ({exc})"
            ) from None
    if isinstance(meta.get("bad_pixels"), str):
        meta["bad_pixels"] = _load_mask(side, meta["bad_pixels"])
    G = len(np.atleast_1d(meta.get("theta_deg", [])))
    if layout == "dofp":
        if pages.shape[0] != G:
            raise ValueError(f"{side}: {pages.shape[0]} DoFP frames for {G} geometries (theta_deg)")
        meta["raw"] = pages
    else:
        K = len(np.atleast_1d(meta.get("polarizer_deg", [])))
        if G == 0 or K == 0 or pages.shape[0] != G * K:
            raise ValueError(
                f"{side}: {pages.shape[0]} TIFF pages for {G} geometries (theta_deg) x {K} "
                "channels "
                f"(polarizer_deg): need G*K pages, geometry-major"
            )
        meta["counts"] = pages.reshape((G, K) + pages.shape[1:])
    return from_flat(meta, str(side))
