"""Results I/O that never loses or silently overwrites anything.

Every writer writes to a temporary file in the target directory and renames it
into place (``os.replace``, atomic on POSIX), so a crash leaves either the old
file or the new one, never half of one. Writers refuse to overwrite an existing
file unless ``overwrite=True``.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "atomic_write_bytes",
    "write_text",
    "write_json",
    "read_json",
    "write_npz",
    "to_jsonable",
]


def atomic_write_bytes(path, data: bytes, *, overwrite: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically; raise FileExistsError if it exists and not ``overwrite``.

    Parameters
    ----------
    path : str or Path
        Destination file (its directory is created).
    data : bytes
        Contents.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The written path.
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(
            f"{path} exists; pass overwrite=True to replace it (--force on the command line)"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; results are ordinary files
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def write_text(path, text: str, *, overwrite: bool = False) -> Path:
    """Atomically write UTF-8 text.

    Parameters
    ----------
    path : str or Path
        Destination file.
    text : str
        Contents.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The written path.
    """
    return atomic_write_bytes(path, text.encode("utf-8"), overwrite=overwrite)


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays and complex numbers to JSON-friendly Python objects.

    Parameters
    ----------
    obj : object
        Nested dicts, lists, tuples, numpy scalars and arrays, complex numbers.

    Returns
    -------
    object
        The same structure of JSON types (complex as ``{"re": .., "im": ..}``).
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (complex, np.complexfloating)):
        return {"re": float(obj.real), "im": float(obj.imag)}
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None if np.isnan(obj) else (1e308 if obj > 0 else -1e308)
    if isinstance(obj, Path):
        return str(obj)
    return obj


def write_json(path, obj: Any, *, overwrite: bool = False) -> Path:
    """Atomically write ``obj`` as indented JSON (numpy types converted).

    Parameters
    ----------
    path : str or Path
        Destination file.
    obj : object
        Anything :func:`to_jsonable` converts.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path
        The written path.
    """
    return write_text(
        path, json.dumps(to_jsonable(obj), indent=2, sort_keys=False) + "\n", overwrite=overwrite
    )


def read_json(path) -> Any:
    """Read a JSON file.

    Parameters
    ----------
    path : str or Path
        A JSON file.

    Returns
    -------
    object
        The decoded contents.
    """
    return json.loads(Path(path).read_text(encoding="utf-8"))


def write_npz(path, *, overwrite: bool = False, **arrays) -> Path:
    """Atomically write arrays to a compressed ``.npz``.

    Parameters
    ----------
    path : str or Path
        Destination file.
    overwrite : bool
        Replace an existing file.
    **arrays : array_like
        The arrays, by name.

    Returns
    -------
    Path
        The written path.
    """
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)
