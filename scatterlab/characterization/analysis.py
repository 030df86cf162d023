"""Measured data through the main job's stages (``scatterlab analyze``): restore, classify, register, invert.

A :class:`scatterlab.io.PolarimetricDataset` holds channel images of one scene at several specular geometries.
There is no simulation and no no-turbulence reference: each geometry is restored on its own -- blindly
(EM with Schulz pupil PSFs, the default, for images through turbulence) or with the diffraction-limited PSF of
the dataset's optics (``psf="diffraction"``) --, keystone-corrected to object coordinates and aligned with the
geometry nearest 50 deg. The regions (dielectric, metal) come from the mean over the geometries of the
registered maximum-likelihood DOLP, classified by DOLP priors re-centred on its histogram (the adaptive priors
of Sec. 8.1.1; ``classes="priors"`` uses the fixed priors at the geometry nearest 50 deg instead). Each
region's mean DOLP, its error (pixel scatter, edge sensitivity, and the restoration bias measured by
re-simulating the estimated scene through the same PSFs, :mod:`~scatterlab.characterization.self_calibration`)
and the posterior of n and kappa follow as in ``characterize``. When the dataset is a simulation with its
truth, the report shows the truth beside every estimate and whether each interval covers it.

Why these defaults (measured on ``data/examples/painted_plate.*``: 64 px, 40 and 55 deg, D/r0 = 7.9, blind):
``characterize`` scores its regions on the true labels and self-calibrates on the classes of its restored
no-turbulence image; ``analyze`` has neither. The blind restoration leaves the paint's DOLP at about 0.3
(40 deg) and 0.67 (55 deg) against 0.65 and 0.92, so the fixed Ch. VII priors (threshold near 0.4) called
73 % of the field metal (38 % true) and the paint's 95 % interval of n was [1.50, 3.65], missing the truth
1.39. Over the example and three more data realizations (seeds 1-3, one re-simulation each) the paint's
interval covered the truth 1 time in 4 with the fixed priors and 4 in 4 with the adaptive classes. On the
example itself the adaptive classes alone gave [1.49, 3.78]: one re-simulation is one draw of the blind EM's
random start, and the paint's 40 deg bias moved between +0.05 and +0.18 from draw to draw, with two
geometries leaving no inferred noise term to absorb it; with ``bias_samples = 3`` (mean subtracted, spread
added to the error) the interval is [1.04, 4.86] (analysis seeds 1 and 2: [1.33, 4.83], [1.11, 3.28]).
``characterize`` on the same scene (its corrected image) gives [0.94, 4.73] (seed 20101210) and [0.99, 4.21]
(seed 1). Both cover by width, not by accuracy: the medians are 2.1-3.2 against 1.39, the restoration at
this size and turbulence being the limit (the example is small so that the tests run in seconds).
"""

from __future__ import annotations

import contextlib
import json
import time
import warnings
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from scatterlab.characterization.acquisition import Acquisition, Ideal
from scatterlab.characterization.estimation import (
    default_margin,
    pixel_maps,
    region_data,
    region_posteriors,
)
from scatterlab.characterization.pipeline import interior, log_stage, restore_task
from scatterlab.characterization.registration import register_restoration
from scatterlab.characterization.restoration import RestoreSettings

__all__ = ["AnalyzeSettings", "analyze", "DEFAULT_SIGMA"]

# the roughness (rms facet slope) assumed when none is given: the bundled examples' (measured data need
# their own, which the DOLP at specular geometries does not determine)
DEFAULT_SIGMA = 0.3


@dataclass(frozen=True)
class AnalyzeSettings:
    """Options of :func:`analyze`.

    Attributes
    ----------
    psf : str
        ``"blind"`` (images through turbulence) or ``"diffraction"`` (the optics' own PSF is known).
    iterations : int
        EM iterations.
    psf_model : str
        ``"pupil"`` or ``"em"`` for blind restoration.
    priors : str
        DOLP prior set (``ch5``, ``ch6``, ``ch7``): the classification with ``classes="priors"``, the
        class names with ``classes="adaptive"``.
    classes : str
        How the regions are found. ``"adaptive"`` (default): the mean over the geometries of the
        registered maximum-likelihood DOLP, classified by priors re-centred on its histogram
        (two-means, Sec. 8.1.1 of the reference text,
        :func:`scatterlab.deconvolution.adaptive_priors`). ``"priors"``: the fixed priors'
        classification at the geometry nearest 50 deg (the EM's continuation with the priors refined
        by linear unmixing, :func:`scatterlab.deconvolution.classify_unmixing`, as ``characterize``
        classifies). Unmixing puts the paint beside the metal into the paint's region, whose DOLP the
        halo dilutes more than a self-calibration from the same data corrects (on the bundled
        example: paint n 2.23 [68 %: 1.54, 2.73] with unmixed adaptive classes, 1.64 [1.37, 1.95]
        without), so the adaptive classes are not unmixed. A restoration that leaves the
        dielectric's DOLP well below its true value (a blind one through strong turbulence) puts
        much of the paint beyond the fixed priors' threshold; the adaptive classes follow the data.
    sigma : float or None
        Known roughness (per-axis rms facet slope) used by the inversion; None (default): the
        default :data:`DEFAULT_SIGMA` is assumed, and the report says so (the data do not measure
        it). :attr:`roughness` is the value used.
    bias_samples : int
        Re-simulations of the blind restoration for the self-calibration
        (:mod:`~scatterlab.characterization.self_calibration`): their mean bias is subtracted, their
        spread added to the region error. One re-simulation is one draw of the blind EM's random
        start: on the example dataset the paint's bias at 40 deg ranged from +0.05 to +0.18 between
        draws, as much as the rest of its error, and with two geometries no noise term is inferred to
        absorb it. Ignored with the known diffraction PSF, whose self-calibration makes its own noisy
        re-simulations and measures its noise and edge terms from them.
    posterior_steps : int
        Chain length of the region posteriors.
    model_error : bool
        Add the pBRDF's DOLP model error, measured against exact (MoM) solutions for the region's
        class, to each geometry's error (:func:`~scatterlab.inversion.dolp_model_error`). Use it for
        real measurements: the facet model's DOLP is off by up to 0.1-0.7 on rough surfaces, far
        more than the noise. Off by default because the bundled examples are rendered with the
        pBRDF itself.
    seed : int
        Seeds the blind start PSFs, the re-simulation and the chains.
    frames : int
        Exposures per geometry (Schulz's multi-frame data): the dataset's K channels are ``frames``
        consecutive groups of K / frames polarizer channels (e.g. 0/45/90/135 deg, then the same again),
        each exposure through its own turbulence. The object is common; each frame gets its own blind PSF,
        and the self-calibration re-simulates each frame through its own estimated PSF. With the known
        diffraction PSF every frame has that PSF.
    psf_refine : str
        ``"none"`` (default) or ``"layout"``: each blind PSF refined with a few-material object
        (:func:`~scatterlab.deconvolution.layout_psf`) before a restoration with it held fixed; with
        ``frames`` > 1 the frames of a geometry share one layout and their PSFs span the whole field
        (:class:`~scatterlab.characterization.restoration.RestoreSettings`; four exposures of the default
        scene: PSF L1 from the truth 1.10-1.17 -> 0.78-0.87, classification error 0.054 -> 0.030). The
        self-calibration's re-simulations are restored the same way. Tens of times the cost of a blind
        restoration (``studies/performance/perf_layout_frames.py``).
    blind_starts : int
        Random start PSFs per blind restoration, aligned and averaged
        (:func:`~scatterlab.characterization.restoration.average_starts`); the self-calibration's
        re-simulations are restored the same way. The time of the blind restorations grows with it.
    """

    psf: str = "blind"
    iterations: int = 150
    psf_model: str = "pupil"
    priors: str = "ch7"
    classes: str = "adaptive"
    sigma: float | None = None
    bias_samples: int = 3
    posterior_steps: int = 1500
    model_error: bool = False
    seed: int = 20101210
    frames: int = 1
    psf_refine: str = "none"
    blind_starts: int = 3

    @property
    def roughness(self) -> float:
        """The rms facet slope the inversion uses: ``sigma``, or :data:`DEFAULT_SIGMA` when it is None."""
        return DEFAULT_SIGMA if self.sigma is None else float(self.sigma)

    def validate(self) -> "AnalyzeSettings":
        """Check every option.

        Returns
        -------
        AnalyzeSettings
            ``self``.

        Raises
        ------
        ValueError
            Naming the option and its allowed values or range.
        """
        if self.psf not in ("blind", "diffraction"):
            raise ValueError(f"psf must be 'blind' or 'diffraction', got {self.psf!r}")
        if self.psf_model not in ("pupil", "em"):
            raise ValueError(f"psf_model must be 'pupil' or 'em', got {self.psf_model!r}")
        if self.psf_refine not in ("none", "layout"):
            raise ValueError(f"psf_refine must be 'none' or 'layout', got {self.psf_refine!r}")
        if self.classes not in ("adaptive", "priors"):
            raise ValueError(f"classes must be 'adaptive' or 'priors', got {self.classes!r}")
        if self.priors not in ("ch5", "ch6", "ch7"):
            raise ValueError(f"priors must be one of ch5, ch6, ch7, got {self.priors!r}")
        if not 1 <= self.iterations <= 100000:
            raise ValueError(f"iterations must be in [1, 100000], got {self.iterations}")
        if not 1 <= self.blind_starts <= 64:
            raise ValueError(f"blind_starts must be in [1, 64], got {self.blind_starts}")
        if not 1 <= self.bias_samples <= 20:
            raise ValueError(f"bias_samples must be in [1, 20], got {self.bias_samples}")
        if self.sigma is not None and not 1e-3 <= self.sigma <= 1.5:
            raise ValueError(f"sigma must be in [0.001, 1.5], got {self.sigma}")
        if not isinstance(self.model_error, bool):
            raise ValueError(f"model_error must be True or False, got {self.model_error!r}")
        whole = isinstance(self.frames, (int, np.integer)) and not isinstance(self.frames, bool)
        if not (whole and 1 <= self.frames <= 1000):
            raise ValueError(f"frames must be an integer in [1, 1000], got {self.frames!r}")
        if not 100 <= self.posterior_steps <= 10**6:
            raise ValueError(
                f"posterior_steps must be in [100, 1000000], got {self.posterior_steps}"
            )
        return self


def _optics_psf(ds):
    """(pupil, diffraction-limited PSF (H, W)) of the dataset's optics (integer pixels per lambda/D >= 2)."""
    from scatterlab.imaging import circular_pupil, psf

    H = ds.counts.shape[-2]
    q = ds.optics.sampling(ds.wavelength)
    if abs(q - round(q)) > 1e-6 or round(q) < 2 or H % round(q):
        raise ValueError(
            f"the dataset's optics sample the PSF at {q:.4g} pixels per lambda/D: analyze needs "
            f"an integer >= 2 that divides the image size {H}"
        )
    n = H // round(q)
    pupil = circular_pupil(n, n / 2)
    return pupil, psf(pupil, pad=round(q))


def _acquisitions(ds, settings):
    pupil, h = _optics_psf(ds)
    H, W = ds.counts.shape[-2:]
    blank = np.full((H, W), np.nan)
    valid = ds.valid_pixels()
    out = []
    for g, th in enumerate(ds.theta):
        t = ds.truth
        ts = t.s0[g] if t is not None and t.s0 is not None else blank
        td = t.dolp[g] if t is not None and t.dolp is not None else blank
        out.append(
            Acquisition(
                float(th),
                "measured",
                None if settings.psf == "diffraction" else float("nan"),
                np.asarray(ds.counts[g], float),
                np.asarray(ds.polarizer_angles, float),
                h,
                pupil,
                ts,
                td,
                valid=None if valid is None else valid[g],
                full_well=ds.full_well,
            )
        )
    return out


def _config(ds, settings):
    """The scene description the re-simulation needs (sizes, polarizers, EM settings)."""
    from scatterlab.characterization.scene_config import SceneConfig

    return SceneConfig(
        image_size=int(ds.counts.shape[-1]),
        geometry_deg=list(np.degrees(ds.theta)),
        d_over_r0=[],
        polarizer_deg=list(np.degrees(ds.polarizer_angles)),
        iterations=settings.iterations,
        psf_model=settings.psf_model,
        psf_refine=settings.psf_refine,
        blind_starts=settings.blind_starts,
        priors=settings.priors,
        sigma_known=settings.roughness,
        posterior_steps=settings.posterior_steps,
        seed=settings.seed,
        wavelength_um=ds.wavelength * 1e6,
    )


def analyze(
    dataset,
    out,
    *,
    settings: AnalyzeSettings = AnalyzeSettings(),
    overwrite: bool = False,
    executor=None,
) -> Path:
    """Restore, classify and invert a measured polarimetric dataset; returns the report path.

    Parameters
    ----------
    dataset : PolarimetricDataset or path
        Channel images (G, K, H, W) at G >= 2 specular geometries (read with
        :func:`scatterlab.io.read_dataset`).
    out : path
        Output folder: ``report.md``, ``summary.json``, ``results.h5``, ``maps.png``.
    settings : AnalyzeSettings
    overwrite : bool
        Replace a finished run.
    executor : optional
        Parallel restorations and posteriors.

    Returns
    -------
    Path
        ``report.md``.
    """
    from scatterlab.characterization.report import RunFolder
    from scatterlab.io import read_dataset

    settings.validate()
    ds = dataset if hasattr(dataset, "counts") else read_dataset(dataset)
    if len(ds.theta) < 2:
        raise ValueError(f"the dataset has {len(ds.theta)} geometry; n and kappa need at least two")
    K, H, W = ds.counts.shape[1:]
    if (
        min(H, W) < 8
    ):  # the pupil grid is half the image, and a PSF needs at least 4 samples across it
        raise ValueError(f"the images are {H} x {W} pixels; deconvolution needs at least 8 x 8")
    if K % settings.frames or K // settings.frames < 3:
        raise ValueError(
            f"frames = {settings.frames} must divide the dataset's {K} channels into frames of at least "
            "3 polarizer channels"
        )
    if _unmeasured_pixels(ds) and settings.psf_refine == "layout" and settings.psf == "blind":
        raise ValueError(
            "psf_refine='layout' (--psf-refine layout) cannot leave out the dataset's bad pixels or "
            "censor its saturated ones yet (bad_pixels, full_well_e, --bad-pixels, --full-well): use "
            "psf_refine='none'"
        )
    folder = RunFolder(out, overwrite)
    t0 = time.perf_counter()
    rng = np.random.default_rng(settings.seed)
    acqs = _acquisitions(ds, settings)
    said = []  # (stage, message) of the warnings the stages gave, each once: in the report
    with _warnings_into(said, "restoration"):
        rests, images = _restore_and_register(acqs, ds.theta, settings, folder, rng, executor)
        layout = _layout(images, ds.theta, settings)
    log_stage("invert: per-pixel maps, self-calibration, region posteriors")
    with _warnings_into(said, "inversion"):
        estimates, maps, missing = _invert(ds, settings, rests, acqs, images, layout, rng, executor)
    seconds = time.perf_counter() - t0
    return _write(folder, ds, settings, images, layout, maps, estimates, seconds, missing, said)


@contextlib.contextmanager
def _warnings_into(said: list, stage: str):
    """Collect the ``UserWarning`` s a stage gives into ``said`` as ``(stage, message)``, each message
    once (a fit repeated per re-simulation gives the same warning each time), and show each once on
    stderr: the report prints them beside its numbers. Other warnings pass through unchanged."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        yield
    known = {m for _, m in said}
    for w in caught:
        message = str(w.message)
        if not issubclass(w.category, UserWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        elif message not in known:
            known.add(message)
            said.append((stage, message))
            warnings.warn_explicit(f"{message} (in report.md)", w.category, w.filename, w.lineno)


def _mid(thetas) -> int:
    """Index of the geometry nearest 50 deg (the reference of the registration)."""
    return int(np.argmin(np.abs(np.degrees(np.asarray(thetas, float)) - 50)))


def _restore_and_register(acqs, thetas, settings, folder, rng, executor):
    """Restore every geometry (:func:`~scatterlab.characterization.pipeline.restore_task`) and register it
    to object coordinates, aligned with the geometry nearest 50 deg: (restorations, registered images)."""
    from scatterlab.deconvolution import PRIOR_SETS
    from scatterlab.runtime import get_executor

    priors = PRIOR_SETS[settings.priors] if settings.classes == "priors" else None
    log_stage(f"restore {len(acqs)} geometries ({settings.psf} PSF)")
    rs = RestoreSettings(
        settings.iterations,
        settings.psf_model,
        priors,
        True,
        str(folder.checkpoints),
        settings.frames,
        settings.psf_refine,
        settings.blind_starts,
    )
    ex = executor if executor is not None else get_executor("serial")
    tasks = [(a, rs, int(rng.integers(2**63)), Ideal()) for a in acqs]
    rests = ex.map(restore_task, tasks, desc="restoration")
    thetas = np.asarray(thetas, float)
    mid = _mid(thetas)
    ref = register_restoration(rests[mid], thetas[mid], None)
    return rests, [register_restoration(r, th, ref.s0) for r, th in zip(rests, thetas)]


def _layout(images, thetas, settings) -> np.ndarray:
    """Metal (1) / dielectric (0) map in object coordinates (:class:`AnalyzeSettings`, ``classes``);
    -1 where no geometry measured the pixel's DOLP (bad or saturated pixels, or no light; with
    ``classes="priors"``, where the geometry nearest 50 deg did not): unclassified."""
    from scatterlab.deconvolution import PRIOR_SETS, adaptive_priors, classify_dolp

    priors = PRIOR_SETS[settings.priors]
    if settings.classes == "priors":
        im = images[_mid(thetas)]
        cls = (
            im.classes if im.classes is not None else classify_dolp(np.nan_to_num(im.dolp), priors)
        )
        return np.where(np.isfinite(im.dolp) & (cls >= 0), np.asarray(cls) > 0, -1).astype(int)
    with warnings.catch_warnings():  # a pixel unmeasured at every geometry: NaN, unclassified
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(np.stack([im.dolp for im in images]), axis=0)
    known = np.isfinite(mean)
    try:
        adapted = adaptive_priors(mean[known], priors)
    except ValueError as exc:  # one material, or too few measured pixels: nothing to re-centre on
        raise ValueError(
            f"classes='adaptive' cannot re-centre the priors on this dataset's restored DOLP ({exc}); "
            "classify with the fixed priors: analyze --classes priors (AnalyzeSettings(classes='priors'))"
        ) from exc
    cls = classify_dolp(np.where(known, mean, 0.0), adapted)
    return np.where(known, np.asarray(cls) > 0, -1).astype(int)


def _filled(layout) -> np.ndarray:
    """``layout`` with each unclassified pixel (-1) given its nearest classified pixel's class: the plate
    the self-calibration re-simulates (the regions themselves leave those pixels out)."""
    from scipy import ndimage

    unknown = np.asarray(layout) < 0
    if not unknown.any():
        return layout
    nearest = ndimage.distance_transform_edt(unknown, return_distances=False, return_indices=True)
    return np.asarray(layout)[tuple(nearest)]


def _invert(ds, settings, rests, acqs, images, layout, rng, executor):
    """Region data from the layout, their self-calibration and posteriors, and the per-pixel maps:
    (estimates, maps, regions left out)."""
    from scatterlab.characterization.self_calibration import bias_corrected, restoration_bias

    thetas = np.asarray(ds.theta, float)
    shape = layout.shape
    sel = interior(shape, max(2, shape[0] // 16))
    margin = default_margin(thetas.max())
    stack = np.stack([im.dolp for im in images])
    truths = _truths(ds)
    regions, missing = [], []
    for r in ("paint", "metal"):
        try:
            regions.append(region_data(r, stack, layout, sel, margin, thetas, truths.get(r)))
        except ValueError as exc:  # the classification found (almost) none of this material
            missing.append(f"{'dielectric' if r == 'paint' else r}: {exc}")
    if not regions:
        raise ValueError(
            "no region of either material is large enough for an estimate: " + "; ".join(missing)
        )
    blind = settings.psf == "blind"
    psfs = [_on_image_grid(r.psf, shape) if blind else a.psf_true for r, a in zip(rests, acqs)]
    cfg = _config(ds, settings)
    # a known-PSF re-simulation measures its own noise and edge terms (one call); a blind one is repeated
    samples = settings.bias_samples if blind else 1
    draws = [
        restoration_bias(
            regions,
            _filled(layout),
            thetas,
            psfs,
            cfg,
            rng,
            sel,
            margin,
            blind=blind,
            executor=executor,
            scored=layout,
        )
        for _ in range(samples)
    ]
    if blind:
        regions = [_bias_corrected(r, np.stack([d[r.name].mean for d in draws])) for r in regions]
    else:
        regions = [bias_corrected(r, draws[0][r.name]) for r in regions]
    estimates = region_posteriors(
        regions,
        thetas,
        settings.roughness,
        rng,
        n_steps=settings.posterior_steps,
        executor=executor,
        model_error=settings.model_error,
    )
    for e in estimates if _unmeasured_pixels(ds) else ():  # only bad or saturated pixels make holes
        warning = _unmeasured_border(e.name, layout, stack, thetas, sel, margin)
        if warning:
            e.warnings.append(warning)
    return estimates, pixel_maps(stack, thetas, settings.roughness), missing


def _unmeasured_pixels(ds) -> bool:
    """Whether the dataset leaves pixels unmeasured: bad pixels listed, or a full well given."""
    return ds.valid_pixels() is not None or ds.full_well is not None


# a region bordered by unmeasured pixels amounting to more than this share of its size gets a warning
UNMEASURED_BORDER_SHARE = 0.1


def _unmeasured_border(name, layout, stack, thetas, sel, margin) -> str | None:
    """A warning when, at some geometry, a region borders or contains many pixels whose DOLP nobody
    measured there (bad or saturated; NaN in ``stack`` (M, H, W)), counted as the unmeasured patches it
    touches against its own size: a saturated metal's brightest, purest part is then missing from its
    mean at that geometry, and what is left lies in halos and thin features mixed with the
    neighbouring material."""
    from scipy import ndimage

    layout = np.asarray(layout)
    lab = {"paint": 0, "metal": 1}[name]
    region = layout == lab
    size = int(np.sum(region & sel))
    if not size:
        return None
    reach = ndimage.binary_dilation(region, iterations=margin)
    worst = (0, 0)
    for g, dolp in enumerate(stack):
        unknown = ~np.isfinite(dolp) | (layout < 0)
        if not unknown.any():
            continue
        patches, _ = ndimage.label(unknown)
        touched = np.unique(patches[reach & unknown])
        worst = max(worst, (int(np.isin(patches, touched[touched > 0]).sum()), g))
    bordering, g = worst
    if bordering <= UNMEASURED_BORDER_SHARE * size:
        return None
    return (
        f"at {np.degrees(thetas[g]):.0f} deg it borders or contains {bordering} unmeasured (bad or "
        f"saturated) pixels, {bordering / size:.0%} of its own {size}: where those are its brightest, "
        "purest part (a saturated metal), its mean rests on what is left -- edges, halos and thin "
        "features mixed with the neighbouring material -- and can be biased beyond its interval. "
        "Expose so that it does not saturate to measure it."
    )


def _on_image_grid(psf, shape):
    """An estimated PSF ``(Hp, Wp)``, or one per frame ``(F, Hp, Wp)``, resampled onto the image grid."""
    from scatterlab.deconvolution import resample_psf

    if np.ndim(psf) == 2:
        return resample_psf(psf, shape)
    return np.stack([resample_psf(h, shape) for h in psf])


def _bias_corrected(region, draws):
    """``region`` corrected by the mean of the re-simulated biases ``draws`` (S, M)
    (:func:`~scatterlab.characterization.self_calibration.bias_corrected`), with their spread added
    to its error in quadrature: the data went through one blind restoration, whose random start
    moves its bias from the mean by about one spread."""
    from scatterlab.characterization.self_calibration import bias_corrected

    out = bias_corrected(region, draws.mean(axis=0))
    if len(draws) < 2:
        return out
    return replace(out, error=np.hypot(out.error, draws.std(axis=0, ddof=1)))


def _classification_vs_labels(ds, layout) -> dict | None:
    """The regions (``layout``, 1 = metal) scored against a simulation's true labels (label 0 the
    dielectric, every other label a metal) over the interior the posteriors use
    (:func:`~scatterlab.deconvolution.classification_errors`), or None without labels on this grid.
    The images are registered to the restored 50-degree image, so a residual shift counts as error."""
    from scatterlab.deconvolution import classification_errors

    t = ds.truth
    if t is None or not ds.simulated or np.shape(t.labels) != np.shape(layout):
        return None
    sel = interior(layout.shape, max(2, layout.shape[0] // 16)) & (layout >= 0)
    metal = tuple(range(1, len(t.names)))
    return classification_errors(layout, t.labels, metal_classes=metal, mask=sel)


def _truths(ds) -> dict:
    """Region -> (n, kappa) of the simulated truth (label 0 the dielectric, label 1 the metal), or {}."""
    t = ds.truth
    if t is None or not ds.simulated or len(t.n) < 2:
        return {}
    return {
        "paint": (float(t.n[0]), float(t.kappa[0])),
        "metal": (float(t.n[1]), float(t.kappa[1])),
    }


def _write(
    folder, ds, settings, images, layout, maps, estimates, seconds, missing, said=()
) -> Path:
    import h5py

    from scatterlab.characterization.metrics import at_fit_bound
    from scatterlab.characterization.report import save_png, versions
    from scatterlab.runtime.results import write_json, write_text

    tmp = folder.path / "results.h5.part"
    with h5py.File(tmp, "w") as f5:
        f5.attrs["settings"] = json.dumps(asdict(settings))
        f5["layout"], f5["n"], f5["kappa"], f5["n_kappa_errors"] = (
            layout,
            maps.n,
            maps.kappa,
            maps.errors,
        )
        for g, im in enumerate(images):
            gg = f5.create_group(f"geometry_{g}")
            gg["s0"], gg["dolp"] = im.s0, im.dolp
            if im.classes is not None:
                gg["classes"] = im.classes
        for e in estimates:
            gr = f5.create_group(f"posterior_{e.name}")
            gr["chain"] = e.chain
            gr.attrs["summary"] = json.dumps(e.parameters)
    tmp.replace(folder.path / "results.h5")
    posts = {
        ("dielectric" if e.name == "paint" else "metal"): dict(
            e.parameters,
            converged=e.converged,
            warnings=e.warnings,
            dolp_mean=e.data.mean.tolist(),
            dolp_error=e.data.error.tolist(),
            pixels=e.data.pixels,
        )
        for e in estimates
    }
    summary = {
        "title": ds.title,
        "source": ds.source,
        "simulated": bool(ds.simulated),
        "settings": asdict(settings),
        "versions": versions(),
        "seconds": seconds,
        "theta_deg": np.degrees(ds.theta).tolist(),
        "posteriors": posts,
        "metal_share": float(np.mean(layout[layout >= 0])),
        "unclassified_pixels": int(np.sum(layout < 0)),
        "data_notes": list(ds.notes),
        "regions_left_out": missing,
        "sigma": {"value": settings.roughness, "assumed": settings.sigma is None},
        "warnings": [{"stage": stage, "message": m} for stage, m in said],
        "pixels_at_fit_bound": int(np.sum(at_fit_bound(maps.n, maps.kappa))),
    }
    scored = _classification_vs_labels(ds, layout)
    if scored is not None:
        summary["classification_vs_labels"] = scored
    write_json(folder.path / "summary.json", summary, overwrite=True)
    _maps_figure(folder.path, images, layout, maps, ds, save_png)
    text = _markdown(
        ds, settings, posts, seconds, missing, scored, int(np.sum(layout < 0)), list(said)
    )
    text = text.replace("![maps](maps.png)", _maps_caption(maps) + "\n\n![maps](maps.png)")
    report = write_text(folder.report, text, overwrite=True)
    import shutil

    shutil.rmtree(folder.checkpoints, ignore_errors=True)
    return report


def _maps_figure(path, images, layout, maps, ds, save_png):
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from scatterlab.characterization.report import AT_BOUND_COLOUR, mark_fit_bound
    from scatterlab.plotting import headless_pyplot

    plt = headless_pyplot()
    mid = _mid(ds.theta)
    t = ds.truth
    # a simulation's true regions beside the estimated ones (label 0 the dielectric, every other a metal)
    true_regions = (
        np.where(np.asarray(t.labels) > 0, 1, 0)
        if t is not None and ds.simulated and np.shape(t.labels) == np.shape(layout)
        else None
    )
    truths = _truths(ds)
    panels = [
        (np.sqrt(np.clip(images[mid].s0, 0, None)), "gray", None, "sqrt(S0)"),
        (images[mid].dolp, "viridis", (0, 1), "DOLP"),
        (layout, None, None, "regions"),
        *([(true_regions, None, None, "true regions")] if true_regions is not None else []),
        (maps.n, "magma", (0, 5), "n"),
        (maps.kappa, "magma", (0, 25), "kappa"),
    ]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.4 * len(panels), 3.6), layout="constrained")
    for ax, (img, cmap, lim, title) in zip(axes, panels):
        if title in ("regions", "true regions"):
            ax.imshow(
                img,
                cmap=ListedColormap(["#d81b60", "#2e7d32", "#9e9e9e"]),
                vmin=-1.5,
                vmax=1.5,
                interpolation="nearest",
            )
            unmeasured = [Patch(color="#d81b60", label="unmeasured")] if np.any(img < 0) else []
            ax.legend(
                handles=[
                    Patch(color="#2e7d32", label="dielectric"),
                    Patch(color="#9e9e9e", label="metal"),
                    *unmeasured,
                ],
                fontsize=7,
                loc="lower right",
            )
        else:
            im = ax.imshow(
                img, cmap=cmap, vmin=lim[0] if lim else None, vmax=lim[1] if lim else None
            )
            if title in ("n", "kappa"):
                on = mark_fit_bound(ax, maps, img)  # as in characterize's figure
                if on.any() and title == "kappa":
                    ax.legend(
                        handles=[Patch(color=AT_BOUND_COLOUR, label="fit on its box's edge")],
                        fontsize=7,
                        loc="lower right",
                    )
            # S0 of the restoration is in photo-electrons per pixel (both polarizations)
            unit = {"sqrt(S0)": "sqrt(S0) [sqrt(e-)]"}.get(title, title)
            fig.colorbar(im, ax=ax, shrink=0.8, label=unit)
        if title in ("n", "kappa") and truths:
            k = 0 if title == "n" else 1
            title += f" (truth: paint {truths['paint'][k]:.2f}, metal {truths['metal'][k]:.2f})"
        elif title not in ("n", "kappa", "true regions"):
            title += f", theta = {np.degrees(ds.theta[mid]):.0f} deg"
        ax.set(title=title, xticks=[], yticks=[])
    fig.suptitle(
        f"{ds.title or 'dataset'}: object coordinates; n, kappa per pixel from all geometries",
        fontsize=9,
    )
    save_png(fig, Path(path) / "maps.png")


def _maps_caption(maps) -> str:
    """The figure's caption: what the per-pixel maps are, and how many pixels' fits stopped on the box's
    edge (cyan in the figure)."""
    from scatterlab.characterization.metrics import at_fit_bound
    from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

    fitted = int(np.sum(np.isfinite(maps.n) & np.isfinite(maps.kappa)))
    on = int(np.sum(at_fit_bound(maps.n, maps.kappa)))
    box = ", ".join(
        f"{p} {DEFAULT_BOUNDS[p][0]:g}-{DEFAULT_BOUNDS[p][1]:g}" for p in ("n", "kappa")
    )
    text = (
        "Per-pixel n and kappa (`maps.png`): a least-squares fit of each pixel's DOLP over the geometries "
        f"within the box {box}"
    )
    if on:
        text += (
            f"; {on} of {fitted} fitted pixels stopped on the box's edge (cyan): the bound, not an "
            "estimate"
        )
    return text + "."


def _sigma_text(settings) -> str:
    """How the report states the roughness: given, or the default assumed (and how to change it)."""
    if settings.sigma is not None:
        return f"sigma {settings.roughness:g} (given)"
    return (
        f"sigma {settings.roughness:g} (assumed: the default, not measured; give the surface's own "
        "with --sigma S, AnalyzeSettings(sigma=S))"
    )


def _markdown(ds, settings, posts, seconds, missing, scored=None, unclassified=0, said=()) -> str:
    lines = [
        f"# Analysis: {ds.title or 'polarimetric dataset'}",
        "",
        f"{ds.counts.shape[0]} specular geometries {np.round(np.degrees(ds.theta), 2).tolist()} deg, "
        f"{ds.counts.shape[1]} channels, {ds.counts.shape[2]} x {ds.counts.shape[3]} pixels, "
        f"{ds.wavelength * 1e6:g} um. Restoration: {settings.psf} PSF, {settings.iterations} EM iterations"
        + (f", {settings.frames} frames per geometry (one PSF each)" if settings.frames > 1 else "")
        + (
            ", PSFs refined with a few-material layout"
            if settings.psf_refine == "layout" and settings.psf == "blind"
            else ""
        )
        + "; "
        f"priors {settings.priors}; {_sigma_text(settings)}. Run time {seconds:.0f} s."
        + (
            (
                " **Simulated data: the truth is shown beside every estimate.**"
                if ds.truth is not None
                else " Simulated data, but the file holds no truth (truth_* keys) to compare with."
            )
            if ds.simulated
            else ""
        ),
        *(["", ds.description] if ds.description.strip() else []),
        "",
        "Posterior of n and kappa from each region's mean DOLP over the geometries (regions from the "
        + (
            "adaptive classification of the DOLP averaged over the geometries"
            if settings.classes == "adaptive"
            else f"{settings.priors} priors' classification at the geometry nearest 50 deg"
        )
        + ", eroded at their edges; error from the pixel "
        "scatter, the edge sensitivity and the re-simulated restoration bias, plus an inferred noise):",
        "",
        "| region | n [68 %] | n 95 % | kappa [68 %] | kappa 95 % |"
        + (" truth | covered 68 / 95 % |" if ds.simulated else ""),
        "|---|---|---|---|---|" + ("---|---|" if ds.simulated else ""),
    ]
    notes = []
    for region, p in posts.items():
        n, k = p["n"], p["kappa"]
        row = (
            f"| {region}{'' if p['converged'] else ' (not converged)'} | {n['median']:.3f} "
            f"[{n['ci68'][0]:.3f}, {n['ci68'][1]:.3f}] | [{n['ci95'][0]:.3f}, {n['ci95'][1]:.3f}] | "
            f"{k['median']:.3f} [{k['ci68'][0]:.3f}, {k['ci68'][1]:.3f}] | "
            f"[{k['ci95'][0]:.3f}, {k['ci95'][1]:.3f}] |"
        )
        if "truth" in n:
            cov = " ".join(
                f"{q}: {'yes' if p[q]['covers68'] else '**no**'}/{'yes' if p[q]['covers95'] else '**no**'}"
                for q in ("n", "kappa")
            )
            row += f" {n['truth']:.2f} - j{k['truth']:.2f} | {cov} |"
        elif ds.simulated:
            row += " - | - |"
        lines.append(row)
        notes += [f"- **{region}:** {w}" for w in p["warnings"]]
    notes += [f"- **Warning ({stage}):** {m}" for stage, m in said]
    notes += [f"- **Region left out**, {m}" for m in missing]
    notes += [f"- **Data:** {n}." for n in ds.notes]
    if unclassified:
        notes.append(
            f"- **{unclassified} pixels are unclassified** (magenta in the regions map): no geometry "
            "measured their DOLP (bad or saturated pixels, or no light), so they are in neither region."
        )
    if not settings.model_error:
        notes.append(
            "- **The pBRDF's own error is not in these intervals** (`--model-error` adds it, "
            "measured against exact solutions): right for data rendered with the pBRDF, as the "
            "bundled examples are; for a measured surface the facet model's DOLP can be off by more "
            "than the noise, and intervals without it are too narrow."
        )
    missed = [
        r
        for r, p in posts.items()
        if "truth" in p["n"] and not all(p[q]["covers95"] for q in ("n", "kappa"))
    ]
    if missed:
        notes.append(
            f"- **The truth lies outside the 95 % interval** for {', '.join(missed)}: the error "
            "model leaves out something these data carry (the warnings above may say what; "
            "restoration bias, registration or the model's own error are the usual causes)."
        )
    if scored is not None:
        notes.append(
            f"- **Regions against the true labels** (interior pixels): total error "
            f"{scored['total_error']:.3f} ({scored['false_metal_rate']:.3f} of the dielectric taken "
            f"for metal, {scored['false_dielectric_rate']:.3f} of the metal for dielectric; metal "
            f"share {scored['metal_share']:.2f}). A residual registration shift counts as error."
        )
    lines += (
        [""]
        + notes
        + [
            "",
            "![maps](maps.png)",
            "",
            "Data: `results.h5` (registered S0, DOLP, classes per geometry; n, kappa maps; chains); "
            "every number: `summary.json`.",
        ]
    )
    return "\n".join(lines) + "\n"
