"""Progress bars that degrade gracefully.

:func:`progress` wraps an iterable in a tqdm bar when standard error is a
terminal, and in a silent no-op bar otherwise (CI logs, pipes, tests) or when
tqdm is missing. ``SCATTERLAB_PROGRESS=1`` forces bars on, ``=0`` off.
"""

from __future__ import annotations

import os
import sys

__all__ = ["progress", "progress_enabled"]


class _NullBar:
    def __init__(self, iterable=None, **_):
        self.iterable = iterable

    def __iter__(self):
        return iter(self.iterable if self.iterable is not None else ())

    def update(self, n=1):
        pass

    def close(self):
        pass

    def set_postfix(self, *a, **k):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def progress_enabled() -> bool:
    """Whether bars are shown: ``SCATTERLAB_PROGRESS`` if set, else whether stderr is a terminal.

    Returns
    -------
    bool
        True when progress bars are shown.
    """
    env = os.environ.get("SCATTERLAB_PROGRESS")
    if env is not None:
        return env not in ("0", "", "false", "no")
    return hasattr(sys.stderr, "isatty") and sys.stderr.isatty()


def progress(iterable=None, *, desc: str | None = None, total: int | None = None):
    """A tqdm progress bar over ``iterable`` (or a manual bar with ``update``), or a silent stand-in.

    Parameters
    ----------
    iterable : iterable, optional
        What to iterate over (None: a manual bar advanced with ``update``).
    desc : str, optional
        Label of the bar.
    total : int, optional
        Number of items (when ``iterable`` has no length).

    Returns
    -------
    tqdm or stand-in
        Iterable (and ``update``/``close``-able) bar; a silent object of the same interface when bars
        are off or tqdm is missing.
    """
    if not progress_enabled():
        return _NullBar(iterable)
    try:
        from tqdm.auto import tqdm
    except ImportError:  # pragma: no cover
        return _NullBar(iterable)
    return tqdm(iterable, desc=desc, total=total, leave=False)
