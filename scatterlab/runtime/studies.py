"""Deprecated: the study runner moved to :mod:`scatterlab.study_runner` (beside the command line).

``runtime`` is the bottom layer (executors, progress, results I/O, timing) and no longer holds the
runner. ``from scatterlab.runtime.studies import NAME`` keeps working through this module, with a
DeprecationWarning; nothing here imports the runner until such a name is asked for.
"""

from __future__ import annotations

import warnings

__all__ = ["Study", "StudyContext", "studies_dir", "discover", "run_study", "run_all",
           "package_versions"]


def __getattr__(name: str):
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn("scatterlab.runtime.studies is deprecated; import from scatterlab.study_runner",
                  DeprecationWarning, stacklevel=2)
    from scatterlab import study_runner

    return getattr(study_runner, name)
