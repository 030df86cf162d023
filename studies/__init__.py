"""The studies: one module per reproduced figure or table of the reference text; ``performance``.

This folder sits at the top of the repository and is installed as the package
``scatterlab.studies`` (``package-dir`` in pyproject.toml), so that the studies run after a
normal install without putting a top-level ``studies`` name on the import path. Each study
``<id>_<slug>.py`` defines ``STUDY`` and ``run(ctx)`` (see :mod:`scatterlab.study_runner`); it is
run with ``scatterlab study run ID``, never imported for its names. Shared helpers live in
``_common`` (skipped by the runner, like every name starting with ``_``).
"""

__all__: list[str] = []
