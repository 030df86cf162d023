"""Deprecated: the study runner moved to :mod:`scatterlab.study_runner` (beside the command line).

``runtime`` is the bottom layer (executors, progress, results I/O, timing) and no longer holds the
runner. ``from scatterlab.runtime.studies import NAME`` keeps working through this module, with a
DeprecationWarning; nothing here imports the runner until such a name is asked for.
"""

from __future__ import annotations

import warnings

__all__: list[str] = []  # a deprecated alias: it defines no names of its own


def __getattr__(name: str):
    if name.startswith("__"):  # module protocol probes do not load the runner
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from scatterlab import study_runner

    if name not in study_runner.__all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(
        "scatterlab.runtime.studies is deprecated; import from scatterlab.study_runner",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(study_runner, name)
