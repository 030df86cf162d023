r"""Restoration stage: Stokes images, deconvolution and classification of one acquisition (Ch. V, VII).

Three kinds of image come out of an acquisition:

``degraded``
    the least-squares Stokes images of the data (Eq. 197) with no deconvolution;
``restored``
    the no-turbulence image deconvolved with its *known* diffraction-limited PSF (Richardson-Lucy-type EM,
    Reeves boundaries): the metal's diffraction halo, 20-30 times brighter than the paint, otherwise lowers
    the paint's DOLP by 0.1-0.2 (0.66 instead of 0.88 at 50 deg; ``studies/characterization_error_budget.py``);
``corrected``
    a turbulent image deconvolved blindly (EM started from a random Kolmogorov PSF as in Sec. 5.3.2, Schulz
    pupil PSFs by default); or, when the acquisition has defocused cameras, deconvolved with the PSF that
    phase diversity finds from them (:func:`scatterlab.deconvolution.phase_diversity`).

The DOLP passed to the inversion is always the maximum-likelihood one (no priors): the DOLP priors of
Eq. 195 pull each pixel toward its class centre, which is right for classifying and wrong for measuring.
Classes come from a short continuation with the priors (PSF fixed at the ML estimate), or, for images that
are not deconvolved, from the priors' equal-density thresholds (the DOLP thresholding of Ch. V); either is
then refined by linear unmixing of the Stokes images
(:func:`~scatterlab.deconvolution.classify_unmixing`), which puts a blurred edge where the image has it
rather than where the DOLP ratio crosses its threshold (under a metal 12 times brighter, 14 % of its light
makes a paint pixel "metal").

The AOP is not estimated: observation is specular, where symmetry fixes it at 0, so the DOLP of the data is
the signed :math:`S_1/S_0` (no Rician bias from :math:`|S_2|`). DOLP of zero light is NaN.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scatterlab.characterization.acquisition import Acquisition, Ideal

__all__ = [
    "Restoration",
    "RestoreSettings",
    "restore",
    "degraded",
    "signed_dolp",
    "KNOWN_PSF_ITERATIONS",
    "phase_diversity_psf",
    "average_starts",
]

KNOWN_PSF_ITERATIONS = 100
# psf_refine="layout": rounds of layout_psf (the PSF error stops falling by 20 on the default scene: 0.88 at
# 20 and 40 rounds) and the known-PSF iterations that follow (Richardson-Lucy needs about 600 to pull the
# metal's halo out of the paint: 0.071 -> 0.042 classification error from 150 to 600 with the true PSF)
LAYOUT_ROUNDS = 20
LAYOUT_FINAL_ITERATIONS = 600
# psf_refine="layout" with several exposures (frames > 1): they share one two-material soft layout with the
# whole field as PSF support. Four exposures of the default scene (aluminium, D/r0 7.9, 30 rounds): PSF L1
# 1.10-1.17 -> 0.78-0.87, classification after 600 known-PSF iterations 0.054 -> 0.030 (true PSF 0.033);
# pure interiors (edge band 2) identify the paint's DOLP but brought the PSFs only to 1.00-1.02 (0.033)
# (docs/characterization_accuracy.md)
LAYOUT_FRAMES_ROUNDS = 30
# acquisitions with defocused cameras (scene key phase_diversity_waves): the phase-diversity fit's stages
# (Gaussian widths [pupil pixels]) and L-BFGS iterations per stage, then known-PSF iterations with its PSF
PHASE_DIVERSITY_SMOOTHING = (8.0, 6.0, 4.0, 3.0, 2.0, 1.0, 0.5)
PHASE_DIVERSITY_ITERATIONS = 300
PHASE_DIVERSITY_FINAL_ITERATIONS = 2000
# the highest DOLP a restoration hands on as the start of its classification pass (the EM refuses 1)
DOLP_START_MAX = 1.0 - 1e-9


@dataclass
class Restoration:
    """Estimates of one acquisition, in camera coordinates.

    Attributes
    ----------
    kind : str
        ``"degraded"``, ``"restored"`` (known PSF) or ``"corrected"`` (blind).
    s0 : ndarray, shape (H, W)
        Irradiance [photo-electrons per pixel, both polarizations].
    dolp : ndarray, shape (H, W)
        Maximum-likelihood DOLP (NaN where there is no light).
    classes : ndarray of int, shape (H, W), or None
        Index into the priors (None when no classification was asked for).
    psf : ndarray, shape (Hp, Wp) or (F, Hp, Wp), or None
        The PSF used or estimated (object grid of the EM); one per frame for multi-frame data
        (``RestoreSettings.frames`` = F > 1).
    loglik : ndarray or None
        Poisson log-likelihood per EM iteration of the maximum-likelihood phase (never decreasing).
    loglik_classes : ndarray or None
        Log-likelihood during the continuation with the priors (the classification).
    valid : ndarray of bool, shape (H, W), or None
        The measured pixels (the acquisition's ``valid``): elsewhere ``dolp`` is NaN and ``classes`` -1,
        since the estimate there is the restoration's guess from the pixels around; None: all.
    """

    kind: str
    s0: np.ndarray
    dolp: np.ndarray
    classes: np.ndarray | None = None
    psf: np.ndarray | None = None
    loglik: np.ndarray | None = None
    loglik_classes: np.ndarray | None = None
    valid: np.ndarray | None = None


@dataclass(frozen=True)
class RestoreSettings:
    """Options of the restoration (from the scene).

    Attributes
    ----------
    iterations : int
        EM iterations of the maximum-likelihood phase.
    psf_model : str
        ``"pupil"`` (Schulz) or ``"em"`` (non-parametric) for blind deconvolution.
    priors : tuple or None
        DOLP priors for the classification.
    restore_reference : bool
        Deconvolve the no-turbulence image with its known PSF (default) or use its Stokes images as they are.
    checkpoint : str or None
        Folder where each deconvolution is saved, keyed by a digest of its inputs.
    frames : int
        Exposures in the channel stack (Schulz's multi-frame data): the K channels are ``frames``
        consecutive groups of K / frames polarizer channels, each through its own turbulence; the object is
        common and each frame gets its own PSF (:func:`scatterlab.deconvolution.blind_deconvolve`).
    psf_refine : str
        ``"layout"``: the blind PSF is refined with a few-material object
        (:func:`scatterlab.deconvolution.layout_psf`) and the image then restored with it held fixed for
        :data:`LAYOUT_FINAL_ITERATIONS` iterations. One frame: a soft three-material layout,
        :data:`LAYOUT_ROUNDS` rounds, the blind support (radius H/4). Several frames: one two-material soft
        layout shared by the frames, :data:`LAYOUT_FRAMES_ROUNDS` rounds, and the whole field as PSF support
        for the refinement and the final restoration.
        ``"none"``: the blind EM's own estimate.
    starts : int
        Random start PSFs of a blind restoration. With more than one, the blind EM restorations from each
        are aligned with the first and their Stokes images averaged (:func:`average_starts`): the ghosts a
        wrong PSF leaves change place with the start and average down. The PSF, log-likelihood and
        classification continuation are the first start's; the layout refinement, when asked for, runs once,
        from that average and the first start's PSF. Ignored when the PSF is known.
    """

    iterations: int = 150
    psf_model: str = "pupil"
    priors: tuple | None = None
    restore_reference: bool = True
    checkpoint: str | None = None
    frames: int = 1
    psf_refine: str = "none"
    starts: int = 1

    def __post_init__(self):
        if isinstance(self.starts, bool) or not isinstance(self.starts, (int, np.integer)):
            raise ValueError(f"starts must be an integer in [1, 64], got {self.starts!r}")
        if not 1 <= self.starts <= 64:
            raise ValueError(f"starts must be an integer in [1, 64], got {self.starts!r}")


def signed_dolp(S) -> np.ndarray:
    """DOLP ``S1/S0`` of linear Stokes images ``(H, W, 3)`` with the AOP fixed at 0; NaN where ``S0 <= 0``
    (:func:`scatterlab.polarization.signed_dolp`).

    Parameters
    ----------
    S : ndarray, shape (H, W, 3)
        Linear Stokes images.

    Returns
    -------
    ndarray, shape (H, W)
    """
    from scatterlab import polarization

    return polarization.signed_dolp(S)


def degraded(acq: Acquisition, priors=None) -> Restoration:
    """The least-squares Stokes estimate of the data (no deconvolution), classified by DOLP thresholds.

    Parameters
    ----------
    acq : Acquisition
    priors : tuple of SuperGaussianPrior, optional
        Thresholds for the classes (None: no classes).

    Returns
    -------
    Restoration
        ``kind="degraded"``.
    """
    from scatterlab.imaging import stokes_from_channels

    S = stokes_from_channels(acq.counts, acq.angles)
    dolp = signed_dolp(S)
    classes = None
    if priors:
        classes = _unmixed(S[..., 0], dolp, _dolp_classes(dolp, priors), acq)
    return _unmeasured(Restoration("degraded", S[..., 0], dolp, classes), acq)


def _dolp_classes(dolp, priors) -> np.ndarray:
    """The priors' DOLP thresholds (Ch. V), a pixel without light at DOLP 0."""
    from scatterlab.deconvolution import classify_dolp

    return classify_dolp(np.nan_to_num(dolp, nan=0.0), priors)


def _unmixed(s0, dolp, classes, acq: Acquisition) -> np.ndarray:
    """``classes`` refined by linear unmixing of the Stokes images
    (:func:`~scatterlab.deconvolution.classify_unmixing`): the edges where the image has them, not where
    the DOLP ratio crosses its threshold. Pixels without light, or unmeasured (:func:`_measured_pixels`),
    keep the class the DOLP gave them and take no part in the materials' Stokes vectors."""
    from scatterlab.deconvolution import classify_unmixing

    lit = np.isfinite(dolp) & (np.asarray(s0) > 0)
    measured = _measured_pixels(acq)
    if measured is not None:
        lit &= measured
    out = classify_unmixing(s0, np.where(lit, dolp, np.nan), classes)
    return np.where(lit, out, classes)


def _measured_pixels(acq: Acquisition) -> np.ndarray | None:
    """The pixels whose DOLP the acquisition measures (H, W): not bad (``acq.valid``) and with no
    channel at the full well; None when that is all of them.

    Parameters
    ----------
    acq : Acquisition

    Returns
    -------
    ndarray of bool, shape (H, W), or None
    """
    valid = None if acq.valid is None else np.asarray(acq.valid, bool)
    if acq.full_well is not None:
        unsaturated = ~np.any(np.asarray(acq.counts) >= acq.full_well, axis=0)
        valid = unsaturated if valid is None else valid & unsaturated
    return None if valid is None or valid.all() else valid


def _unmeasured(rest: Restoration, acq: Acquisition) -> Restoration:
    """``rest`` with its DOLP NaN and its classes -1 where the acquisition measured no DOLP."""
    valid = _measured_pixels(acq)
    if valid is None:
        return rest
    rest.valid = valid
    rest.dolp = np.where(valid, rest.dolp, np.nan)
    if rest.classes is not None:
        rest.classes = np.where(valid, rest.classes, -1)
    return rest


def _digest(acq: Acquisition, settings: RestoreSettings, ideal: Ideal, seed: int) -> str:
    h = hashlib.sha256(np.ascontiguousarray(acq.counts).tobytes())
    h.update(np.ascontiguousarray(acq.angles).tobytes())
    if acq.valid is not None:
        h.update(np.packbits(np.asarray(acq.valid, bool)).tobytes())
    if acq.full_well is not None:
        h.update(repr(("full_well", float(acq.full_well))).encode())
    if ideal.psf or acq.d_over_r0 is None:
        h.update(np.ascontiguousarray(acq.psf_true).tobytes())
    if acq.diversity_counts is not None:  # the cameras' frames and the fit's constants
        h.update(np.ascontiguousarray(acq.diversity_counts).tobytes())
        h.update(np.ascontiguousarray(acq.diversity_phases).tobytes())
        h.update(
            repr(
                (
                    acq.diversity_share,
                    acq.read_noise,
                    PHASE_DIVERSITY_SMOOTHING,
                    PHASE_DIVERSITY_ITERATIONS,
                    PHASE_DIVERSITY_FINAL_ITERATIONS,
                )
            ).encode()
        )
    pri = tuple((p.c2, p.c3, p.m, p.name) for p in settings.priors or ())
    # the classifier too: checkpoints holding an older one's classes are stale
    h.update(b"classes: DOLP priors, then linear unmixing")
    h.update(
        repr(
            (
                settings.iterations,
                settings.psf_model,
                pri,
                settings.restore_reference,
                settings.frames,
                settings.starts,
                # the refinement's constants too: changing them must not serve stale checkpoints
                (
                    settings.psf_refine,
                    LAYOUT_ROUNDS,
                    LAYOUT_FINAL_ITERATIONS,
                    LAYOUT_FRAMES_ROUNDS,
                    "once, from the averaged starts",
                )
                if settings.psf_refine == "layout"
                else settings.psf_refine,
                ideal.psf,
                seed,
                acq.d_over_r0,
            )
        ).encode()
    )
    return h.hexdigest()[:24]


def phase_diversity_psf(acq: Acquisition) -> np.ndarray:
    """The PSF of a turbulent acquisition found by phase diversity from its defocused cameras.

    The frames are the polarimeter's channel sum (in focus) and the two defocused cameras, with gains in the
    proportion of the light each gets and the read noise of their dark-subtracted pixels
    (:func:`scatterlab.deconvolution.phase_diversity`, stages :data:`PHASE_DIVERSITY_SMOOTHING`,
    :data:`PHASE_DIVERSITY_ITERATIONS` iterations each).

    Parameters
    ----------
    acq : Acquisition
        With ``diversity_counts``.

    Returns
    -------
    ndarray, shape (H, H)
        The in-focus PSF (centred, unit sum, 2 pixels per lambda/D).
    """
    from scatterlab.deconvolution import phase_diversity

    if acq.diversity_counts is None:
        raise ValueError("acq has no defocused cameras (diversity_counts is None)")
    K = acq.counts.shape[0]
    share = acq.diversity_share
    frames = np.concatenate([acq.counts.sum(axis=0)[None], acq.diversity_counts])
    offsets = np.concatenate([np.zeros((1,) + acq.pupil.shape), acq.diversity_phases])
    cams = len(acq.diversity_counts)
    gains = np.array([1.0 - share] + [share / cams] * cams)
    # a dark-subtracted pixel is read twice; the focused frame sums K channels
    read_noise = acq.read_noise * np.sqrt(2.0 * np.array([K] + [1] * cams))
    fit = phase_diversity(
        frames,
        offsets,
        acq.pupil,
        gains=gains,
        read_noise=read_noise,
        smoothing=PHASE_DIVERSITY_SMOOTHING,
        iterations=PHASE_DIVERSITY_ITERATIONS,
    )
    return fit.psfs[0]


def _start_seed(seed: int, k: int) -> int:
    """Seed of the ``k``-th random start of a blind restoration (the first is ``seed`` itself)."""
    if k == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), k]).generate_state(1, np.uint64)[0] >> 1)


def average_starts(s0s, dolps, mask=None):
    """One restoration from several blind ones: each aligned with the first and their Stokes images averaged.

    A blind PSF estimate is found up to a translation, and its errors leave ghost copies of the object's
    edges whose places change with the random start (Sec. 5.3.2 starts the EM from a random Kolmogorov PSF).
    Averaging the linear Stokes images ``S0`` and ``S1 = S0 DOLP`` of restorations from independent starts
    (each translated onto the first by :func:`~scatterlab.characterization.registration.estimate_shift`)
    keeps what they agree on and averages their ghosts down: a Monte-Carlo average over the blind estimate's
    random start. Where a translated start does not cover the field, the others' mean is used.

    Parameters
    ----------
    s0s : sequence of ndarray, shape (H, W)
        Irradiance of each restoration [photo-electrons].
    dolps : sequence of ndarray, shape (H, W)
        Their signed DOLP (NaN where undefined, taken as 0).
    mask : ndarray of bool, shape (H, W), optional
        Measured pixels (the translations are estimated from these alone).

    Returns
    -------
    s0 : ndarray, shape (H, W)
        Mean irradiance [photo-electrons].
    dolp : ndarray, shape (H, W)
        Mean ``S1`` over mean ``S0`` (NaN where the mean ``S0 <= 0``).
    shifts : ndarray, shape (K, 2)
        The translation applied to each restoration [pixels]; the first is (0, 0).
    """
    from scipy import ndimage

    from scatterlab.characterization.registration import estimate_shift

    if len(s0s) != len(dolps) or not len(s0s):
        raise ValueError(
            f"s0s and dolps must be non-empty and of equal length, got {len(s0s)} and {len(dolps)}"
        )
    ref = np.asarray(s0s[0], float)
    shape = ref.shape
    shifts = np.zeros((len(s0s), 2))
    weight, s0_sum, s1_sum = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    for k, (s0, dolp) in enumerate(zip(s0s, dolps)):
        s0 = np.asarray(s0, float)
        s1 = s0 * np.nan_to_num(np.asarray(dolp, float), nan=0.0)
        if k:
            shifts[k] = estimate_shift(ref, s0, reference_mask=mask, image_mask=mask)
        # linear interpolation; what is shifted in from beyond the field carries no weight
        moved = [
            ndimage.shift(x, shifts[k], order=1, mode="constant", cval=0.0)
            for x in (np.ones(shape), s0, s1)
        ]
        weight += moved[0]
        s0_sum += moved[1]
        s1_sum += moved[2]
    s0_mean = s0_sum / weight  # the first start covers every pixel: weight >= 1
    s1_mean = s1_sum / weight
    dolp = np.where(s0_mean > 0, s1_mean / np.where(s0_mean > 0, s0_mean, 1.0), np.nan)
    return s0_mean, dolp, shifts


def _ml_phase(acq: Acquisition, settings: RestoreSettings, kw, grid, mode_of, seed: int):
    """The maximum-likelihood deconvolution from one start: blind EM (or the known PSF held fixed)."""
    from scatterlab.deconvolution import blind_deconvolve, initial_psf

    known_psf, diversity, psf_known = mode_of
    F = settings.frames
    if (
        known_psf
    ):  # the true PSF or the one phase diversity finds, the same for every frame, held fixed
        psf0, mode = psf_known, "fixed"
    elif F == 1:
        psf0, mode = initial_psf(acq.pupil, grid, rng=seed), settings.psf_model
    else:  # each frame starts from its own random screen
        seeds = np.random.SeedSequence(seed).spawn(F)
        psf0 = np.stack([initial_psf(acq.pupil, grid, rng=np.random.default_rng(s)) for s in seeds])
        mode = settings.psf_model
    # with a known PSF the EM is Richardson-Lucy on the Stokes images: cheap per iteration, slow to pull the
    # metal's halo back out of the paint, so it gets at least KNOWN_PSF_ITERATIONS
    its = max(settings.iterations, KNOWN_PSF_ITERATIONS) if known_psf else settings.iterations
    if diversity:
        its = PHASE_DIVERSITY_FINAL_ITERATIONS
    return blind_deconvolve(acq.counts, acq.angles, psf0=psf0, psf_mode=mode, iterations=its, **kw)


def _layout_refined(acq: Acquisition, settings: RestoreSettings, kw, start, seed: int):
    """The blind PSF refined with a few-material object (:func:`~scatterlab.deconvolution.layout_psf`) from
    the blind result ``start``, then the image restored with it held fixed."""
    from scatterlab.deconvolution import blind_deconvolve, layout_psf

    H = acq.counts.shape[1]
    F = settings.frames
    kw = dict(kw)
    if F == 1:
        refine = dict(materials=3, rounds=LAYOUT_ROUNDS)
    else:  # one layout shared by the frames, whole field (module constants above)
        kw.update(psf_radius=np.sqrt(2) * H / 2, pad=H // 2)
        refine = dict(materials=2, rounds=LAYOUT_FRAMES_ROUNDS)
    h = layout_psf(
        acq.counts,
        acq.angles,
        start,
        pupil=acq.pupil,
        psf_radius=kw["psf_radius"],
        pad=kw["pad"],
        frames=F,
        rng=seed,
        **refine,
    ).psf
    ml = blind_deconvolve(
        acq.counts,
        acq.angles,
        psf0=h,
        psf_mode="fixed",
        iterations=LAYOUT_FINAL_ITERATIONS,
        **kw,
    )
    return ml, kw


def _em(acq: Acquisition, settings: RestoreSettings, known_psf: bool, seed: int):
    """ML deconvolution (averaged over ``settings.starts`` random starts when blind), then a short
    continuation with the priors for the classes (PSF held fixed)."""
    from scatterlab.deconvolution import blind_deconvolve, object_grid, resample_psf

    H, W = acq.counts.shape[1:]
    diversity = not known_psf and acq.diversity_counts is not None
    known_psf = known_psf or diversity
    # a known PSF is used whole (its Airy tail carries a few per cent of the metal's light onto the paint, as
    # much as the paint's own signal; the whole H x H square: cutting its corners drops ~0.2 % of the light,
    # 2 % of the paint's S0 under a metal 25x brighter); a blind estimate is confined to a disc of a quarter
    # of the field
    radius, pad = (np.sqrt(2) * H / 2, H // 2) if known_psf else (H / 4, int(np.ceil(H / 4)))
    grid = object_grid((H, W), radius, pad=pad)
    F = settings.frames
    kw = dict(
        psf_radius=radius, pad=pad, pupil=acq.pupil, frames=F, mask=acq.valid, censor=acq.full_well
    )
    psf_known = None
    if diversity:
        psf_known = resample_psf(phase_diversity_psf(acq), grid)
    elif known_psf:
        psf_known = resample_psf(acq.psf_true, grid)
    mode_of = (known_psf, diversity, psf_known)
    # a known PSF gives the same restoration from any start; a blind one is averaged over its random starts
    starts = 1 if known_psf else settings.starts
    runs = [
        _ml_phase(acq, settings, kw, grid, mode_of, _start_seed(seed, k)) for k in range(starts)
    ]
    ml = runs[0]
    s0, dolp = ml.s0, np.where(ml.s0 > 0, ml.dolp, np.nan)
    if starts > 1:
        s0, dolp, _ = average_starts(
            [r.s0 for r in runs], [r.dolp for r in runs], mask=_measured_pixels(acq)
        )
    if not known_psf and settings.psf_refine == "layout":
        # refined once, from the starts' average (fewer ghosts for its k-means layout to take for a
        # material) and the first start's PSF, to which the others were aligned: on the default scene's
        # aluminium plate as good as refining every start and averaging (classification 219 and 356 pixels
        # wrong against 228 and 340, degraded 377 and 397) at a third of the time
        start = dataclasses.replace(ml, s0=s0, dolp=np.nan_to_num(dolp, nan=0.0))
        ml, kw = _layout_refined(acq, settings, kw, start, seed)
        s0, dolp, starts = ml.s0, np.where(ml.s0 > 0, ml.dolp, np.nan), 1
    classes, loglik_classes = None, np.zeros(0)
    if settings.priors:
        steps = max(10, settings.iterations // 5)
        cont = blind_deconvolve(
            acq.counts,
            acq.angles,
            psf0=ml.psfs,
            psf_mode="fixed",
            iterations=steps,
            priors=settings.priors,
            s0_start=s0,
            # a restoration can end at DOLP 1 (an overshoot beside the metal), which the EM refuses
            # as a start (a multiplicative update never moves it): just below 1 the priors can
            dolp_start=np.clip(
                ml.dolp if starts == 1 else np.nan_to_num(dolp, nan=0.0), 0.0, DOLP_START_MAX
            ),
            **kw,
        )
        loglik_classes = cont.loglik
        classes = _unmixed(s0, dolp, cont.classes, acq)
    psf = ml.psfs[0] if F == 1 else ml.psfs
    return s0, dolp, classes, psf, ml.loglik, loglik_classes


def restore(
    acq: Acquisition, settings: RestoreSettings, seed: int, ideal: Ideal = Ideal()
) -> Restoration:
    """Deconvolve one acquisition: known PSF for the no-turbulence image (or with ``ideal.psf``), blind EM
    otherwise; checkpointed in ``settings.checkpoint`` (a rerun after an interruption reads it back).

    Parameters
    ----------
    acq : Acquisition
    settings : RestoreSettings
    seed : int
        Seeds the random start PSF of the blind EM.
    ideal : Ideal
        ``psf`` gives the true PSF to the EM.

    Returns
    -------
    Restoration
        ``kind`` is ``"restored"`` for the no-turbulence image (known PSF) and ``"corrected"`` for a
        turbulent one (blind, or with the true PSF under ``Ideal(psf=True)``).
    """
    known = ideal.psf or acq.d_over_r0 is None
    kind = "restored" if acq.d_over_r0 is None else "corrected"
    path = None
    if settings.checkpoint:
        path = Path(settings.checkpoint) / f"{_digest(acq, settings, ideal, seed)}.npz"
        if path.exists():
            with np.load(path, allow_pickle=False) as z:
                cls = z["classes"] if z["classes"].size else None
                rest = Restoration(
                    kind, z["s0"], z["dolp"], cls, z["psf"], z["loglik"], z["loglik_classes"]
                )
                return _unmeasured(rest, acq)
    s0, dolp, classes, psf, loglik, loglik_classes = _em(acq, settings, known, seed)
    if path is not None:
        from scatterlab.runtime.results import write_npz

        write_npz(
            path,
            overwrite=True,
            s0=s0,
            dolp=dolp,
            psf=psf,
            loglik=loglik,
            loglik_classes=loglik_classes,
            classes=np.zeros(0, int) if classes is None else classes,
        )
    return _unmeasured(Restoration(kind, s0, dolp, classes, psf, loglik, loglik_classes), acq)
