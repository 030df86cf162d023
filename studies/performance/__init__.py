"""Error-versus-run-time studies of every numerical method with an accuracy knob.

Installed as ``scatterlab.studies.performance``; run with ``scatterlab study run ID``.
"""

__all__: list[str] = []
