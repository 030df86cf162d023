"""End-to-end characterization (Ch. VII): acquire -> restore -> register -> invert -> report.

Each stage is a module with a small typed result:

* :mod:`~scatterlab.characterization.acquisition` -- the plate rendered by the pBRDF and recorded by a
  4-channel polarimeter without turbulence and through one Kolmogorov screen per D/r0 (:class:`Acquisition`);
* :mod:`~scatterlab.characterization.restoration` -- Stokes images; the no-turbulence image deconvolved with
  its known PSF, the turbulent ones blindly; ML DOLP for the inversion, DOLP priors for the classes
  (:class:`Restoration`);
* :mod:`~scatterlab.characterization.registration` -- keystone stretch to object coordinates and
  alignment with the no-turbulence image (:class:`Registered`);
* :mod:`~scatterlab.characterization.estimation` -- n and kappa per pixel and, per region, posteriors of
  the region-mean DOLP with an error estimate from the data (:class:`RegionEstimate`);
* :mod:`~scatterlab.characterization.report` -- errors against the truth, HDF5, JSON, figures and Markdown.

:class:`~scatterlab.characterization.acquisition.Ideal` replaces stages by their ideal versions (the error
budget). Only what ``cfg.estimate`` asks for is computed. A run interrupted at any point resumes on a plain
rerun: deconvolutions are checkpointed, and the report (written last) marks a finished run.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scatterlab.characterization.acquisition import Ideal, acquire
from scatterlab.characterization.registration import register_restoration
from scatterlab.characterization.restoration import RestoreSettings, degraded, restore
from scatterlab.characterization.scene_config import SceneConfig

__all__ = [
    "characterize",
    "observe",
    "Observation",
    "PlateResult",
    "run_plate",
    "interior",
    "log_stage",
    "restore_task",
]


@dataclass
class Observation:
    """Everything seen at one geometry: the truth, the acquisitions per case, and the registered images.

    Attributes
    ----------
    theta : float
        Specular angle [rad].
    truth_s0, truth_dolp : ndarray, shape (H, W)
        The object in object coordinates.
    acquisitions : dict
        Case name -> :class:`Acquisition`.
    restorations : dict
        (case, kind) -> :class:`Restoration` (camera coordinates).
    images : dict
        (case, kind) -> :class:`Registered` (object coordinates).
    """

    theta: float
    truth_s0: np.ndarray
    truth_dolp: np.ndarray
    acquisitions: dict = field(default_factory=dict)
    restorations: dict = field(default_factory=dict)
    images: dict = field(default_factory=dict)


@dataclass
class PlateResult:
    """One plate through the pipeline: labels, observations, and per image key (``"no_turbulence"``,
    ``"D_r0_7.9_degraded"``, ...) the registered stacks' estimates and metrics."""

    plate: object
    labels: np.ndarray
    observations: list
    estimates: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)


def log_stage(message: str) -> None:
    """One plain log line on standard error when it is not a terminal (terminals get progress bars).

    Parameters
    ----------
    message : str

    Returns
    -------
    None
    """
    if not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty()):
        print(f"[scatterlab] {message}", file=sys.stderr, flush=True)


def interior(shape, margin):
    """Boolean mask of the pixels at least ``margin`` from the image edges (registration repeats edges).

    Parameters
    ----------
    shape : tuple of int
        (H, W).
    margin : int
        Border [pixels].

    Returns
    -------
    ndarray of bool, shape (H, W)
    """
    m = np.zeros(shape, bool)
    m[margin : shape[0] - margin, margin : shape[1] - margin] = True
    return m


def cases_of(cfg: SceneConfig) -> list:
    """[(case name, D/r0 or None)]: the no-turbulence case first, then one per ``cfg.d_over_r0``.

    Parameters
    ----------
    cfg : SceneConfig

    Returns
    -------
    list of (str, float or None)
    """
    return [("no_turbulence", None)] + [(f"D_r0_{x:g}", float(x)) for x in cfg.d_over_r0]


def restore_task(task):
    """One restoration, as a module-level function of one argument (process executors pickle it).

    Parameters
    ----------
    task : tuple
        ``(acquisition, RestoreSettings, seed, Ideal)``, the arguments of :func:`restore`.

    Returns
    -------
    Restoration
    """
    acq, settings, seed, ideal = task
    return restore(acq, settings, seed, ideal)


_restore_task = restore_task  # the former private name


def observe(
    plate,
    labels,
    thetas,
    cfg: SceneConfig,
    rng,
    *,
    priors=None,
    executor=None,
    ideal: Ideal = Ideal(),
    checkpoint=None,
) -> list:
    """Acquire, restore and register one plate at each specular geometry (all cases of the scene).

    Parameters
    ----------
    plate : Plate
    labels : ndarray of int, shape (H, W)
        Object-coordinate label map (0 paint, 1 metal, 2 scratch).
    thetas : array_like, shape (M,)
        Specular angles [rad].
    cfg : SceneConfig
    rng : numpy.random.Generator
    priors : tuple of SuperGaussianPrior, optional
        DOLP priors for the classification (None: no classes).
    executor : optional
        Runs the deconvolutions (the expensive part) in parallel.
    ideal : Ideal
    checkpoint : path, optional
        Folder for the deconvolution checkpoints.

    Returns
    -------
    list of Observation
    """
    from scatterlab.runtime import get_executor

    settings = RestoreSettings(
        cfg.iterations,
        cfg.psf_model,
        priors,
        True,
        None if checkpoint is None else str(checkpoint),
        psf_refine=cfg.psf_refine,
        starts=cfg.blind_starts,
    )
    obs, tasks = [], []
    for th in np.asarray(thetas, float):
        o = None
        for case, dr0 in cases_of(cfg):
            acq = acquire(plate, labels, th, case, dr0, cfg, rng, ideal)
            if o is None:
                o = Observation(float(th), acq.truth_s0, acq.truth_dolp)
            o.acquisitions[case] = acq
            o.restorations[(case, "degraded")] = degraded(acq, priors)
            tasks.append(((len(obs), case), (acq, settings, int(rng.integers(2**63)), ideal)))
        obs.append(o)
    ex = executor if executor is not None else get_executor("serial")
    results = ex.map(_restore_task, [t for _, t in tasks], desc=f"{plate.metal}: deconvolution")
    for ((k, case), _), rest in zip(tasks, results):
        obs[k].restorations[(case, rest.kind)] = rest
    for o in obs:
        _register(o, ideal)
    return obs


def _register(o: Observation, ideal: Ideal) -> None:
    """Register every restoration of one geometry onto the reference (the restored no-turbulence S0, or the
    true object with ideal registration)."""
    ref_key = next(k for k in o.restorations if k[0] == "no_turbulence" and k[1] != "degraded")
    fs = o.acquisitions["no_turbulence"].foreshortened
    ref = register_restoration(o.restorations[ref_key], o.theta, None, foreshortened=fs)
    reference = o.truth_s0 if ideal.registration else ref.s0
    for key, rest in o.restorations.items():
        o.images[key] = register_restoration(rest, o.theta, reference, foreshortened=fs)


def image_kinds(cfg: SceneConfig) -> list:
    """[(image key, case, kind)] in report order: the restored no-turbulence image (the reference), the
    unrestored one, then degraded and corrected per D/r0.

    Parameters
    ----------
    cfg : SceneConfig

    Returns
    -------
    list of (str, str, str)
        (image key, case, restoration kind).
    """
    kinds = [
        ("no_turbulence", "no_turbulence", "restored"),
        ("no_turbulence_unrestored", "no_turbulence", "degraded"),
    ]
    for case, _ in cases_of(cfg)[1:]:
        kinds += [(f"{case}_degraded", case, "degraded"), (f"{case}_corrected", case, "corrected")]
    return kinds


def run_plate(
    plate, cfg: SceneConfig, rng, *, executor=None, ideal: Ideal = Ideal(), checkpoint=None
) -> PlateResult:
    """The pipeline for one plate: acquire, restore, register, invert, and score against the truth.

    Parameters
    ----------
    plate : Plate
    cfg : SceneConfig
    rng : numpy.random.Generator
        Draws the scratches, screens, noise, start PSFs and posterior seeds.
    executor : optional
        Parallel deconvolutions and posteriors.
    ideal : Ideal
        Stages replaced by their ideal versions.
    checkpoint : path, optional
        Folder of the deconvolution checkpoints.

    Returns
    -------
    PlateResult
    """
    from scatterlab.characterization import metrics
    from scatterlab.characterization.scene_config import plate_labels
    from scatterlab.deconvolution import PRIOR_SETS

    thetas = np.radians(cfg.geometry_deg)
    priors = (
        None if cfg.priors == "none" or "classes" not in cfg.estimate else PRIOR_SETS[cfg.priors]
    )
    labels = plate_labels(cfg, rng)
    log_stage(
        f"{plate.metal}: acquire and restore {len(thetas)} geometries x {len(cases_of(cfg))} cases"
    )
    obs = observe(
        plate,
        labels,
        thetas,
        cfg,
        rng,
        priors=priors,
        executor=executor,
        ideal=ideal,
        checkpoint=checkpoint,
    )
    if ideal.classes and priors:
        for o in obs:
            for img in o.images.values():
                img.classes = (labels > 0).astype(int)
    result = PlateResult(plate, labels, obs)
    log_stage(f"{plate.metal}: invert and score")
    metrics.score_plate(result, cfg, rng, executor=executor, priors=priors)
    return result


def characterize(
    cfg: SceneConfig, out, *, overwrite: bool = False, executor=None, ideal: Ideal = Ideal()
) -> Path:
    """Run the pipeline for ``cfg`` into the folder ``out``; returns the report path.

    Parameters
    ----------
    cfg : SceneConfig
    out : path
        Output folder: ``results.h5``, ``summary.json``, ``report.md`` and one PNG per plate.
    overwrite : bool
        Replace a finished run (one whose ``report.md`` exists). An unfinished run is resumed either way.
    executor : optional
        Parallel deconvolutions and posteriors.
    ideal : Ideal
        Stages replaced by their ideal versions (error budget).

    Returns
    -------
    Path of ``report.md``.
    """
    from scatterlab.characterization import report

    cfg.validate()
    folder = report.RunFolder(out, overwrite)
    t0 = time.perf_counter()
    rng = np.random.default_rng(cfg.seed)
    results = []
    for plate in cfg.plates:
        results.append(
            run_plate(
                plate, cfg, rng, executor=executor, ideal=ideal, checkpoint=folder.checkpoints
            )
        )
        log_stage(f"{plate.metal}: figure")
        report.plate_figure(folder.path, results[-1], cfg)
    log_stage("report")
    return report.write_all(folder, cfg, results, seconds=time.perf_counter() - t0, ideal=ideal)
