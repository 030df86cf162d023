r"""Polarimetric blind deconvolution by expectation-maximization (LeMaster and Cain; Schulz; Eqs. 143-160, 185-194).

Data: K channel images :math:`d_n` (photo-electrons, Poisson) behind linear polarizers at :math:`\theta_n`,
blurred by PSFs :math:`h_n` (one shared, division of amplitude, or one per channel):

.. math:: E[d_n] = h_n \ast \tfrac12 S_0\,[1 + \mathcal P\cos 2(\alpha - \theta_n)]
          = h_n \ast [\tfrac12(1 - \mathcal P)S_0 + \mathcal P S_0\cos^2(\alpha - \theta_n)]

E-step (Eq. 193): with :math:`r_n = d_n / i_n` and the back-projection :math:`c_n = h_n^T \ast r_n`,
:math:`\sum_y\psi_{un} = \tfrac12(1 - \mathcal P)S_0 c_n` and
:math:`\sum_y\psi_{pn} = \mathcal P S_0\cos^2(\alpha - \theta_n)c_n`.
M-step (Eq. 194), for polarizer angles evenly spaced over 180 deg (Eqs. 159-160 decouple the updates):

* :math:`S_0 \leftarrow \sum_n(\psi_{un} + \psi_{pn}) / \sum_n w_n[\tfrac12(1 - \mathcal P)
  + \mathcal P\cos^2(\alpha - \theta_n)]`
  (:math:`\frac2K\sum_n(\psi_{un} + \psi_{pn})` for evenly spaced angles and no boundary loss), w_n the share
  of the object pixel's light that falls in the measured window (1 with periodic boundaries);
* :math:`\mathcal P \leftarrow Q/T` (ML) or the root of Eq. 196 with a super-Gaussian prior
  (:mod:`scatterlab.deconvolution.priors`); with several priors each pixel takes the one whose update
  maximizes the complete-data objective -- the classification (Ch. V, VI);
* :math:`\alpha`: kept fixed when the geometry fixes it (specular observation: 0, Ch. VII); otherwise the
  root of :math:`\sum_n B_n\tan(\alpha - \theta_n) = 0` by a 1-deg grid search refined parabolically;
* PSF: ``"em"`` -- Eq. 194, :math:`h_n \leftarrow h_n\,(r_n \star o_n) / D_n` (Schulz's multiframe update,
  summed over channels for a shared PSF); ``"pupil"`` -- Schulz's parameterised PSF
  :math:`|\mathcal F\{A e^{j\phi}\}|^2`, the EM update projected onto it by Gerchberg-Saxton steps
  (Eqs. 146-150), accepted only when the log-likelihood increases; ``"fixed"`` -- known PSF (the object update
  is then Richardson-Lucy).

For other polarizer angles (e.g. 0/60/120 is evenly spaced; 0/45/90 is not) the updates couple
(Sec. 3.3.2); this implementation then updates S0 and P by the same EM formulas, whose fixed point is still
the ML estimate (each step is a generalised EM step), and says so in the result.

Trivial solution: the PSF is kept at unit sum and confined to a support (a disc of radius ``psf_radius``) --
otherwise "object = point, PSF = image" maximizes the likelihood; the pupil model limits it further to the
optical band. Boundaries: Reeves's approach (Ref. 106) -- the object is estimated on a grid larger than the
data by ``pad`` pixels on each side and only measured pixels enter the likelihood, so no wrap-around; or
``boundary="periodic"``. Masked pixels (``mask``, ``saturation``) leave the likelihood the same way.
Censored values (``censor``, a full well): a channel value at or above it says only "at least this many";
it enters the likelihood as :math:`\ln P(d \ge c)` and the E-step as :math:`E[d \mid d \ge c]` under the
current prediction (both with the normal approximation of the Poisson law, good at full-well counts), so a
saturated area keeps constraining its light -- which masking it would leave to guesswork, with its halo
left on the pixels around.
Initial guesses: the text (Sec. 5.3.2) starts from S0 = 1, P = 1/2, alpha = 0 and the PSF of a random
Kolmogorov screen (:func:`scatterlab.deconvolution.psf_update.initial_psf`); here S0 and P start by default from
the least-squares Stokes images of the data (``s0_start=1.0, dolp_start=0.5`` gives the text's start), the PSF
from ``psf0``, else the diffraction-limited PSF of ``pupil``. The Poisson log-likelihood
:math:`\sum_n\sum_y[d_n\ln i_n - i_n]` is recorded every iteration; without priors it never decreases.
Speed: with one PSF and a known AOP the channel objects are linear in 2-3 Stokes images, and the convolutions
act on those (:class:`_StokesBasis`); otherwise channel by channel.

Structure: :func:`blind_deconvolve` validates and sets up a fixed problem and an :class:`EMState`, then
iterates :func:`e_step`, :func:`m_step` and :func:`psf_step`; its options are grouped in small dataclasses
(:class:`EMOptions` of :class:`PSFOptions`, :class:`PolarizationOptions`, :class:`WindowOptions`,
:class:`StartOptions`, :class:`StopOptions`), and the flat keywords of earlier versions still work.

AOP: the geometry fixes it (``aop``, default 0) for unpolarized light observed in the specular plane; where it
does not (off the specular plane, polarized sources such as LeMaster and Cain's bars, Figs. 31-33),
``estimate_aop=True`` estimates it per pixel by the M-step above, starting from ``aop`` if given, else from the
AOP of the data's least-squares Stokes images. Its resolution is about 0.1 deg (1-deg grid, parabola). With
three channels and one PSF per channel the blind problem is nearly degenerate (per pixel, S0, P and alpha
already fit three channel values) and the AOP can drift with the iterations (studies/fig31_fig33).
"""

from __future__ import annotations

import numbers
import time
from dataclasses import dataclass, field, fields, replace

import numpy as np
import scipy.fft as sfft

from scatterlab._checks import as_count, as_image_shape, as_positive, as_turn
from scatterlab.deconvolution.priors import _dolp_update, _prior_set, map_objective
from scatterlab.deconvolution.psf_update import PupilPhasePSF, gerchberg_saxton, resample_psf
from scatterlab.polarization import dolp as stokes_dolp
from scatterlab.polarization import signed_dolp

__all__ = [
    "blind_deconvolve",
    "DeconvolutionResult",
    "EMOptions",
    "EMState",
    "PSFOptions",
    "PolarizationOptions",
    "StartOptions",
    "StopOptions",
    "WindowOptions",
    "e_step",
    "m_step",
    "psf_step",
    "evenly_spaced",
    "object_grid",
    "censored_mean",
    "censored_log_survival",
]


def evenly_spaced(angles) -> bool:
    """True when the polarizer angles are evenly spaced over 180 deg (mod 180), K >= 3.

    Parameters
    ----------
    angles : array_like ``(K,)`` [rad]

    Returns
    -------
    bool
    """
    a = np.sort(np.mod(np.asarray(angles, float), np.pi))
    K = a.size
    if K < 3:
        return False
    d = np.diff(np.r_[a, a[0] + np.pi])
    return bool(np.allclose(d, np.pi / K, atol=1e-9))


# ---------------------------------------------------------------------------------------------------------
# options: small groups of the keyword arguments of blind_deconvolve


@dataclass(frozen=True)
class PSFOptions:
    """How the PSFs are modelled and updated.

    Parameters
    ----------
    mode : "em" (Eq. 194, non-parametric), "pupil" (Schulz's pupil-phase model, Gerchberg-Saxton projection,
        Eqs. 146-150), "phase" (the same model, its phases maximizing the log-likelihood itself by
        L-BFGS with the analytic gradient, Schulz's multi-frame method; one PSF per frame, known AOP) or
        "fixed" (known PSF ``psf0``: the object update is Richardson-Lucy).
    shared : one PSF for all channels of a frame (division of amplitude) or one per channel (sequential
        capture).
    frames : number of frames (Schulz's multi-frame data): the K channels are ``frames`` consecutive groups
        of K / frames channels, each group one exposure of the same object through its own turbulence.
        With ``shared`` each frame has one PSF; the object is common to all frames. Without ``shared``
        every channel has its own PSF anyway and ``frames`` only has to divide K. A frame without photons
        (a lost exposure) keeps its start PSF: it carries no information on it.
    radius : PSF support radius [pixels]; None: a quarter of the smaller data side.
    gs_steps : Gerchberg-Saxton steps (``mode="pupil"``) or L-BFGS iterations (``mode="phase"``) per
        iteration, an integer >= 0.
    """

    mode: str = "em"
    shared: bool = True
    frames: int = 1
    radius: float | None = None
    gs_steps: int = 5


@dataclass(frozen=True)
class PolarizationOptions:
    """The polarization model of the object.

    Parameters
    ----------
    aop : float or array ``(H, W)`` [rad], optional -- the AOP when the geometry fixes it (None means 0:
        unpolarized light observed in the specular plane, Ch. VII); the start when ``estimate_aop`` (None:
        the AOP of the least-squares Stokes images of the data). Finite, in [-2 pi, 2 pi] (a value beyond
        a full turn is degrees: use numpy.radians), broadcasting to the data's image shape ``(H, W)``.
    estimate_aop : estimate a per-pixel AOP (LeMaster and Cain's M-step, Sec. 3.3.2) instead of keeping
        ``aop`` -- for geometries that do not fix it (off the specular plane, polarized sources).
    priors : tuple of SuperGaussianPrior, optional -- one: MAP DOLP; several: per-pixel classification. A key
        of ``PRIOR_SETS`` (``"ch5"``, ``"ch6"``, ``"ch7"``, as scene files and the command line name them) or a
        single prior is taken for its tuple; anything else raises ValueError.
    prior_weight : weight of the log prior (>= 0).
    """

    aop: object = None
    estimate_aop: bool = False
    priors: tuple | str | None = None
    prior_weight: float = 1.0

    def __post_init__(self):
        if self.priors is not None:
            object.__setattr__(self, "priors", _prior_set(self.priors, "priors"))


@dataclass(frozen=True)
class WindowOptions:
    """Which pixels enter the likelihood.

    Parameters
    ----------
    boundary : "reeves" (object on a grid ``pad`` pixels larger on each side, no wrap-around) or "periodic".
    pad : Reeves padding [pixels]; None: the PSF radius.
    mask : bool array ``(H, W)``, optional -- pixels to use (False: saturated, dead, ...).
    saturation : float, optional [photo-electrons] -- pixels where any channel reaches it are masked too.
    censor : float, optional [photo-electrons] -- full well: channel values at or above it are censored
        (module docstring) instead of masked. Not with ``psf_mode="phase"``.
    """

    boundary: str = "reeves"
    pad: int | None = None
    mask: object = None
    saturation: float | None = None
    censor: float | None = None


@dataclass(frozen=True)
class StartOptions:
    """Initial object; None: the least-squares Stokes estimate of the data.

    Parameters
    ----------
    s0 : float or array ``(H, W)`` [counts], optional -- the text's start is 1. Finite, >= 0, some light,
        broadcasting to the data's image shape ``(H, W)``.
    dolp : float or array ``(H, W)``, optional -- the text's start is 0.5. An unsigned DOLP in [0, 1)
        (the orientation is the AOP, ``aop``), broadcasting to ``(H, W)``. The updates are multiplicative:
        without priors a DOLP of 0 stays 0 (``dolp=0`` everywhere runs the unpolarized EM, which is
        Richardson-Lucy) and one of 1 would stay 1 whatever the data say, so 1 is refused, and so is a
        negative (signed) DOLP, which the model cannot represent (it was read as 0).
    """

    s0: object = None
    dolp: object = None


@dataclass(frozen=True)
class StopOptions:
    """When to stop: after ``iterations`` or when the relative change of the log-likelihood is <= ``tol``.

    Parameters
    ----------
    iterations : int >= 0
    tol : float, optional
    callback : callable, optional -- called after every iteration with a :class:`DeconvolutionResult`
        snapshot (data grid), e.g. to record the convergence; it cannot change the run.
    """

    iterations: int = 50
    tol: float | None = None
    callback: object = None


@dataclass(frozen=True)
class EMOptions:
    """All options of :func:`blind_deconvolve`, grouped.

    Parameters
    ----------
    psf, polarization, window, start, stop : the option groups (defaults: the text's settings).
    update_object : False keeps S0 and the DOLP at their start (PSF-only updates).
    """

    psf: PSFOptions = field(default_factory=PSFOptions)
    polarization: PolarizationOptions = field(default_factory=PolarizationOptions)
    window: WindowOptions = field(default_factory=WindowOptions)
    start: StartOptions = field(default_factory=StartOptions)
    stop: StopOptions = field(default_factory=StopOptions)
    update_object: bool = True


# the flat keyword arguments of earlier versions -> (group, field)
_KEYWORDS = {
    "psf_mode": ("psf", "mode"),
    "shared_psf": ("psf", "shared"),
    "frames": ("psf", "frames"),
    "psf_radius": ("psf", "radius"),
    "gs_steps": ("psf", "gs_steps"),
    "aop": ("polarization", "aop"),
    "estimate_aop": ("polarization", "estimate_aop"),
    "priors": ("polarization", "priors"),
    "prior_weight": ("polarization", "prior_weight"),
    "boundary": ("window", "boundary"),
    "pad": ("window", "pad"),
    "mask": ("window", "mask"),
    "saturation": ("window", "saturation"),
    "censor": ("window", "censor"),
    "s0_start": ("start", "s0"),
    "dolp_start": ("start", "dolp"),
    "iterations": ("stop", "iterations"),
    "tol": ("stop", "tol"),
    "callback": ("stop", "callback"),
}


def _resolve_options(options, keywords) -> EMOptions:
    """``options`` (or the defaults) with the flat keywords applied on top."""
    opts = EMOptions() if options is None else options
    if not isinstance(opts, EMOptions):
        raise TypeError(f"options must be an EMOptions, got {type(opts).__name__}")
    groups = {f.name: getattr(opts, f.name) for f in fields(opts)}
    for key, value in keywords.items():
        if key == "update_object":
            groups["update_object"] = value
            continue
        if key not in _KEYWORDS:
            raise TypeError(f"blind_deconvolve() got an unexpected keyword argument {key!r}")
        group, name = _KEYWORDS[key]
        groups[group] = replace(groups[group], **{name: value})
    return EMOptions(**groups)


@dataclass
class DeconvolutionResult:
    """Estimates on the data grid.

    Attributes
    ----------
    s0, dolp, aop : arrays ``(H, W)`` [counts, -, rad]
    psfs : array ``(P, Hp, Wp)`` on the object grid (centred, unit sum): one per frame with a shared PSF
        (P = ``frames``), else one per channel (P = K)
    classes : int array ``(H, W)`` (index into ``priors``) or None
    loglik : array ``(iterations + 1,)`` Poisson log-likelihood; objective: with the log priors
    iterations : int; notes : list of str; seconds : float [s]
    """

    s0: np.ndarray
    dolp: np.ndarray
    aop: np.ndarray
    psfs: np.ndarray
    classes: np.ndarray | None
    priors: tuple
    loglik: np.ndarray
    objective: np.ndarray
    iterations: int
    notes: list = field(default_factory=list)
    seconds: float = float("nan")


class _Ops:
    """FFT convolution on the object grid (scipy.fft, real transforms), with the data window (Reeves) or
    periodic. The spectrum of the window indicator is cached: the share of an object pixel's light that reaches
    the window costs one inverse transform per PSF change."""

    def __init__(self, data_shape, pad, boundary, valid=None):
        self.H, self.W = data_shape
        self.pad = pad if boundary == "reeves" else 0
        self.shape = (self.H + 2 * self.pad, self.W + 2 * self.pad)
        self.win = (slice(self.pad, self.pad + self.H), slice(self.pad, self.pad + self.W))
        # measured pixels: the data window (Reeves) less the masked ones (saturated, bad)
        self.masked = valid is not None and not np.all(valid)
        ind = np.ones((self.H, self.W)) if valid is None else np.asarray(valid, float)
        self._win_spec = self.rfft(self.extend(ind)) if (self.pad or self.masked) else None

    def rfft(self, a):
        return sfft.rfft2(a)

    def irfft(self, A):
        return sfft.irfft2(A, s=self.shape)

    def otf(self, h):
        return self.rfft(sfft.ifftshift(h, axes=(-2, -1)))

    def window_share(self, Hf):
        """h^T * 1_window on the object grid (1 for periodic boundaries)."""
        if self._win_spec is None:
            return 1.0
        return np.clip(self.irfft(self._win_spec * np.conj(Hf)), 1e-6, None)

    def crop(self, a):
        return a[(..., *self.win)]

    def extend(self, a):
        out = np.zeros(a.shape[:-2] + self.shape)
        out[(..., *self.win)] = a
        return out


def _pad_edge(a, pad):
    return np.pad(a, [(0, 0)] * (a.ndim - 2) + [(pad, pad), (pad, pad)], mode="edge") if pad else a


# ---------------------------------------------------------------------------------------------------------
# the problem (fixed during the iterations) and the state (updated every iteration)


@dataclass
class _Problem:
    """What the iterations read but never change: data, angles, measured pixels, FFT operators, PSF
    support, forward model, options."""

    d: np.ndarray  # (K, H, W) clipped, masked counts
    th: np.ndarray  # (K,) [rad]
    valid: np.ndarray  # (H, W) bool
    ops: _Ops
    support: np.ndarray  # (Hp, Wp) bool
    D: np.ndarray  # (K,) total counts per channel
    group: np.ndarray  # (K,) index of each channel's PSF
    model: object  # _StokesBasis or _PerChannel
    opts: EMOptions
    pupil: np.ndarray | None
    notes: list
    phase_psf: PupilPhasePSF | None = None
    censored: np.ndarray | None = None  # (K, H, W) bool: values at or above the full well
    ceiling: float = np.inf  # the full well [photo-electrons]

    @property
    def priors(self) -> tuple:
        return tuple(self.opts.polarization.priors) if self.opts.polarization.priors else ()

    def data(self, i) -> np.ndarray:
        """The data the E-step reads: the counts, with each censored value replaced by its expectation
        ``E[d | d >= ceiling]`` under the prediction ``i`` (K, H, W)."""
        if self.censored is None:
            return self.d
        d = self.d.copy()
        d[self.censored] = censored_mean(i[self.censored], self.ceiling)
        return d

    def likelihood(self, i) -> float:
        """Poisson log-likelihood sum(d ln i - i) over the measured pixels; a censored value
        contributes ln P(d >= ceiling) instead."""
        # d ln i - i; where d = 0 the clipped log is finite, so the product is exactly 0
        predicted = float(np.sum(i * self.valid)) if self.ops.masked else float(i.sum())
        L = float(np.vdot(self.d, np.log(np.maximum(i, 1e-300)))) - predicted
        if self.censored is not None:
            ic = i[self.censored]
            L -= float(np.sum(self.d[self.censored] * np.log(np.maximum(ic, 1e-300)) - ic))
            L += float(np.sum(censored_log_survival(ic, self.ceiling)))
        return L


def _standardised(i, c):
    """``(c - i) / sigma`` with the Poisson sigma ``sqrt(i)`` (at least 1 count)."""
    sigma = np.sqrt(np.maximum(i, 1.0))
    return (c - i) / sigma, sigma


def censored_mean(i, c) -> np.ndarray:
    """``E[d | d >= c]`` for counts of mean ``i`` (normal approximation of the Poisson law).

    Parameters
    ----------
    i : array_like [photo-electrons] -- expected counts.
    c : float [photo-electrons] -- the censoring level (full well).

    Returns
    -------
    ndarray
        ``i + sigma phi(a) / Q(a)``, ``a = (c - i) / sigma``, ``sigma = sqrt(i)``: at least ``c``, and
        ``i`` when ``i >> c`` (computed with ``erfcx``, finite for any ``a``).
    """
    from scipy.special import erfcx

    i = np.asarray(i, float)
    a, sigma = _standardised(i, c)
    # phi(a) / Q(a) = sqrt(2 / pi) / erfcx(a / sqrt 2)
    return np.maximum(i + sigma * np.sqrt(2.0 / np.pi) / erfcx(a / np.sqrt(2.0)), c)


def censored_log_survival(i, c) -> np.ndarray:
    """``ln P(d >= c)`` for counts of mean ``i`` (normal approximation, finite for any ``i``).

    Parameters
    ----------
    i : array_like [photo-electrons]; c : float [photo-electrons]

    Returns
    -------
    ndarray
        ``ln Q(a) = ln(erfcx(a / sqrt 2) / 2) - a^2 / 2`` for ``a >= 0``, ``ln(1 - erfc(-a / sqrt 2) / 2)``
        below.
    """
    from scipy.special import erfc, erfcx

    a, _ = _standardised(np.asarray(i, float), c)
    upper = np.log(erfcx(np.maximum(a, 0.0) / np.sqrt(2.0)) / 2.0) - np.maximum(a, 0.0) ** 2 / 2
    lower = np.log1p(-erfc(-np.minimum(a, 0.0) / np.sqrt(2.0)) / 2.0)
    return np.where(a >= 0, upper, lower)


@dataclass
class EMState:
    """The evolving estimate of :func:`blind_deconvolve` on the object grid ``(Hp, Wp)``.

    Attributes
    ----------
    h : array ``(P, Hp, Wp)`` -- PSFs (centred, unit sum): one per frame (``frames``, 1 for a single
        frame) with a shared PSF, else one per channel
    s0, P : arrays ``(Hp, Wp)`` -- S0 [counts] and DOLP
    pred : predicted channel images ``(K, H, W)`` with the OTFs and object spectra (``_State``)
    w : window share ``h^T * 1_window`` (array or 1.0)
    pupil_phase : array ``(P, n, n)`` [rad] or None (``mode="pupil"``)
    classes : int array ``(H, W)`` or None
    loglik, objective : lists of floats, one per iteration (plus the start)
    """

    h: np.ndarray
    s0: np.ndarray
    P: np.ndarray
    pred: object
    w: object
    pupil_phase: np.ndarray | None
    classes: np.ndarray | None = None
    loglik: list = field(default_factory=list)
    objective: list = field(default_factory=list)


def _check_inputs(data, angles, psf0, pupil, opts: EMOptions):
    """Validate the data, angles and options; return the data (K, H, W) and the angles (K,)."""
    d = np.asarray(data, float)
    if d.ndim != 3:
        raise ValueError(f"data must have shape (K, H, W), got {d.shape}")
    if not np.all(np.isfinite(d)):
        bad = int((~np.all(np.isfinite(d), axis=0)).sum())
        raise ValueError(
            f"data must be finite: {bad} pixel(s) hold NaN or inf. Leave missing pixels out with "
            "mask=... (a boolean (H, W) array, False there, e.g. numpy.isfinite(data).all(axis=0)) "
            "and set them to any finite value; 0 photons without the mask would read as a black "
            "spot of DOLP 0, which the classification takes for metal"
        )
    th = as_turn(angles, "angles", "polarizer angles").ravel()
    K = d.shape[0]
    if th.size != K:
        raise ValueError(f"angles has {th.size} entries for {K} channels")
    mode, radius, frames = opts.psf.mode, opts.psf.radius, opts.psf.frames
    whole = isinstance(frames, (int, np.integer)) and not isinstance(frames, bool)
    if not (whole and frames >= 1 and K % frames == 0):
        raise ValueError(
            f"frames must be a positive integer that divides the {K} channels, got {frames!r}"
        )
    if mode not in ("em", "pupil", "phase", "fixed"):
        raise ValueError(f"psf_mode must be 'em', 'pupil', 'phase' or 'fixed', got {mode!r}")
    if opts.window.boundary not in ("reeves", "periodic"):
        raise ValueError(f"boundary must be 'reeves' or 'periodic', got {opts.window.boundary!r}")
    if opts.window.censor is not None and mode == "phase":
        raise ValueError(
            "censor (a full well) works with psf_mode 'em', 'pupil' or 'fixed', not 'phase' (its "
            "likelihood has no censored term)"
        )
    weight = opts.polarization.prior_weight
    if not (np.isfinite(weight) and weight >= 0):
        raise ValueError(f"prior_weight must be finite and >= 0, got {weight!r}")
    H, W = d.shape[1:]
    if radius is not None and not (np.isfinite(radius) and 1 <= radius <= np.hypot(H, W)):
        raise ValueError(
            f"psf_radius must be in [1, {np.hypot(H, W):.4g}] pixels (the image's diagonal), got "
            f"{radius!r}"
        )
    pad = opts.window.pad
    if pad is not None and not (
        isinstance(pad, (int, np.integer))
        and not isinstance(pad, bool)
        and 0 <= pad <= 2 * max(H, W)
    ):
        raise ValueError(f"pad must be an integer in [0, {2 * max(H, W)}] pixels, got {pad!r}")
    as_count(opts.psf.gs_steps, "gs_steps", 0)
    _check_start_and_stop(opts, (H, W))
    if psf0 is not None:
        try:
            p0 = np.asarray(psf0, float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"psf0 must be a numeric array (a PSF), got {psf0!r}") from exc
        if p0.ndim not in (2, 3):
            raise ValueError(
                f"psf0 must have shape (Hp, Wp) or (P, Hp, Wp) on the object grid, got {p0.shape}"
            )
        if not np.all(np.isfinite(p0)) or np.any(p0 < 0) or not np.all(p0.sum(axis=(-2, -1)) > 0):
            raise ValueError("psf0 must be finite and non-negative with a positive sum (a PSF)")
    if mode == "fixed" and psf0 is None:
        raise ValueError("psf_mode='fixed' needs psf0")
    if mode in ("pupil", "phase") and pupil is None:
        raise ValueError(f"psf_mode={mode!r} needs the pupil (aperture) array")
    if mode == "phase" and (not opts.psf.shared or opts.polarization.estimate_aop):
        raise ValueError(
            "psf_mode='phase' needs one PSF per frame (shared_psf=True) and a known AOP "
            "(estimate_aop=False)"
        )
    return d, th


def _image_option(value, name: str, shape) -> np.ndarray:
    """``value`` as a float array broadcasting to the image ``shape`` (H, W); ValueError naming ``name``."""
    try:
        a = np.asarray(value, float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a number or an array of numbers, got {value!r}") from exc
    try:
        np.broadcast_to(a, shape)
    except ValueError as exc:
        raise ValueError(
            f"{name} must be a number or an array of the data's image shape {tuple(shape)} (H, W), "
            f"got shape {a.shape}"
        ) from exc
    return a


def _check_start_and_stop(opts: EMOptions, shape) -> None:
    """The start object, the fixed AOP and the stopping rule: each a ValueError naming it; ``shape`` is
    the data's image shape (H, W)."""
    s0, dolp, aop = opts.start.s0, opts.start.dolp, opts.polarization.aop
    if s0 is not None:
        a = _image_option(s0, "s0_start", shape)
        if not (np.all(np.isfinite(a) & (a >= 0)) and np.any(a > 0)):
            raise ValueError(
                "s0_start must be finite and >= 0 counts with some light (the EM's updates are "
                "multiplicative: a pixel that starts at 0 stays 0)"
            )
    if dolp is not None:
        p = _image_option(dolp, "dolp_start", shape)
        if not np.all((p >= 0) & (p < 1)):
            raise ValueError(
                "dolp_start must be finite and in [0, 1) (an unsigned DOLP; the orientation is aop): "
                "the EM's updates are multiplicative, so a DOLP of 1 never moves, and a negative "
                "(signed) DOLP cannot be represented -- for light polarized across aop give |DOLP| "
                "and aop + pi/2. 0 stays 0 without priors (the unpolarized, Richardson-Lucy EM)"
            )
    if aop is not None:
        as_turn(_image_option(aop, "aop", shape), "aop", "AOPs")
    its = opts.stop.iterations
    as_count(its, "iterations", 0)
    tol = opts.stop.tol
    if tol is not None and not (np.ndim(tol) == 0 and np.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be None or a single finite float >= 0, got {tol!r}")


def _valid_pixels(d, window: WindowOptions, notes):
    """Clip the data at 0 and mask it; return (data, valid (H, W) bool, censored (K, H, W) bool or
    None)."""
    d = np.clip(d, 0.0, None)
    if not d.sum() > 0:
        raise ValueError("data holds no photons (every count is <= 0): nothing to deconvolve")
    valid = np.ones(d.shape[1:], bool)
    if window.mask is not None:
        m = np.asarray(window.mask)
        if m.shape != d.shape[1:] or m.dtype != bool:
            raise ValueError(
                f"mask must be a boolean array of shape {d.shape[1:]}, got {m.dtype} {m.shape}"
            )
        valid &= m
    if window.saturation is not None:
        if not window.saturation > 0:
            raise ValueError(f"saturation must be > 0 photo-electrons, got {window.saturation}")
        valid &= np.all(d < window.saturation, axis=0)
    if not valid.any():
        raise ValueError("mask and saturation leave no pixel to use")
    if not valid.all():
        notes.append(
            f"{int((~valid).sum())} masked pixels (saturated or excluded) left out of the likelihood"
        )
        d = d * valid
    censored = None
    if window.censor is not None:
        c = window.censor
        real = isinstance(c, numbers.Real) and not isinstance(c, (bool, np.bool_))
        if not (real and np.isfinite(c) and c > 0):
            raise ValueError(
                f"censor (the full well) must be a number > 0 photo-electrons, got {c!r}"
            )
        censored = (d >= c) & valid
        if censored.any():
            notes.append(
                f"{int(censored.sum())} channel values at or above the full well {c:g} e- censored "
                "(they count as 'at least this many')"
            )
        else:
            censored = None
    return d, valid, censored


def _initial_psfs(psf0, pupil, ops: _Ops, support, radius, nps):
    """Start PSFs (nps, Hp, Wp): ``psf0``, else the diffraction-limited PSF of ``pupil``, else a Gaussian
    of standard deviation radius / 4; confined to the support, unit sum."""
    Hp, Wp = ops.shape
    if psf0 is not None:
        h = np.asarray(psf0, float)
        if h.shape[-2:] != (Hp, Wp):
            raise ValueError(f"psf0 must be given on the object grid {(Hp, Wp)} (data + 2 pad)")
        if h.ndim not in (2, 3):
            raise ValueError(f"psf0 must have shape (Hp, Wp) or (P, Hp, Wp), got {h.shape}")
        if h.ndim == 3 and h.shape[0] not in (1, nps):
            raise ValueError(
                f"psf0 holds {h.shape[0]} PSFs; the data need 1 or {nps} (one per frame with a shared "
                "PSF, one per channel otherwise)"
            )
        h = np.broadcast_to(h if h.ndim == 3 else h[None], (nps, Hp, Wp)).copy()
    elif pupil is not None:
        from scatterlab.imaging import psf as make_psf

        h = np.broadcast_to(resample_psf(make_psf(pupil, pad=2), (Hp, Wp)), (nps, Hp, Wp)).copy()
    else:
        yy, xx = np.mgrid[0:Hp, 0:Wp]
        g = np.exp(-((yy - Hp // 2) ** 2 + (xx - Wp // 2) ** 2) / (2 * (radius / 4) ** 2))
        h = np.broadcast_to(g, (nps, Hp, Wp)).copy()
    h = np.where(support, np.clip(h, 0, None), 0.0)
    h /= h.sum(axis=(-2, -1), keepdims=True)
    return h


def _initial_object(d, th, valid, opts: EMOptions):
    """Start S0, DOLP and AOP (H, W) from the least-squares Stokes images of the data (or the options).

    EM barely moves a DOLP near 0 (the mixture weight's update is slow at the boundary), so the start must be
    unbiased there: with the AOP known, :func:`scatterlab.polarization.signed_dolp`, which has no Rician bias
    (a 0.02 floor left a metal of DOLP 0.005 at 0.012 after 100 iterations); floored at 1e-6 (P = 0 would
    stay 0). Pixels without light (DOLP NaN) start at that floor, masked pixels at 0.5.
    """
    from scatterlab.imaging import stokes_from_channels

    H, W = d.shape[1:]
    pol = opts.polarization
    S = stokes_from_channels(d, th)  # (H, W, 3)
    s00 = S[..., 0]
    s0 = np.clip(s00, 1e-3 * max(s00[valid].mean(), 1e-12), None)
    aop = 0.0 if pol.aop is None else pol.aop
    if pol.estimate_aop:
        P_ls = stokes_dolp(S)
    else:
        P_ls = signed_dolp(S, np.broadcast_to(np.asarray(aop, float), (H, W)))
    P0 = np.clip(np.nan_to_num(P_ls, nan=0.0), 1e-6, 0.98)
    s0 = np.where(valid, s0, s00[valid].mean())  # masked pixels start from the mean level
    P0 = np.where(valid, P0, 0.5)
    if opts.start.s0 is not None:
        s0 = np.broadcast_to(np.asarray(opts.start.s0, float), (H, W)).copy()
    if opts.start.dolp is not None:
        P0 = np.broadcast_to(np.clip(np.asarray(opts.start.dolp, float), 0, 1), (H, W)).copy()
    alpha = np.broadcast_to(np.asarray(aop, float), (H, W)).copy()
    if pol.estimate_aop and pol.aop is None:
        alpha = 0.5 * np.arctan2(S[..., 2], S[..., 1])
    return s0, P0, alpha


def _setup(data, angles, psf0, pupil, opts: EMOptions):
    """Validate, build the fixed problem and the start state."""
    notes = []
    d, th = _check_inputs(data, angles, psf0, pupil, opts)
    # judged per frame: frames of 0/45/90/135 deg tiled together are evenly spaced
    if not all(evenly_spaced(a) for a in th.reshape(opts.psf.frames, -1)):
        notes.append(
            "polarizer angles are not evenly spaced: the S0/DOLP updates are generalised-EM steps "
            "(coupled updates of Sec. 3.3.2)"
        )
    d, valid, censored = _valid_pixels(d, opts.window, notes)
    H, W = d.shape[1:]
    radius = min(H, W) / 4 if opts.psf.radius is None else opts.psf.radius
    pad = opts.window.pad
    if pad is None:
        pad = int(np.ceil(radius)) if opts.window.boundary == "reeves" else 0
    ops = _Ops((H, W), pad, opts.window.boundary, valid)
    Hp, Wp = ops.shape
    yy, xx = np.mgrid[0:Hp, 0:Wp]
    support = np.hypot(yy - Hp // 2, xx - Wp // 2) <= radius
    K, frames = d.shape[0], opts.psf.frames
    nps = frames if opts.psf.shared else K
    group = np.repeat(np.arange(frames), K // frames) if opts.psf.shared else np.arange(K)
    h = _initial_psfs(psf0, pupil, ops, support, radius, nps)
    pupil_phase = (
        np.zeros((nps,) + np.shape(pupil)) if opts.psf.mode in ("pupil", "phase") else None
    )
    phase_psf = None
    if opts.psf.mode == "phase":
        # the start phases reproduce the start PSFs (Gerchberg-Saxton), which are then exactly the model's
        phase_psf = PupilPhasePSF(pupil, ops.shape, support)
        _, pupil_phase = gerchberg_saxton(h, pupil, pupil_phase, ops.shape, 200)
        h = np.stack([phase_psf.psf(ph) for ph in pupil_phase])
    s0, P0, alpha = _initial_object(d, th, valid, opts)
    s0, P, alpha = (_pad_edge(a, ops.pad) for a in (s0, P0, alpha))
    # one PSF per frame and a known AOP (Ch. VII's specular case): the channel objects are linear in the
    # Stokes images, o_n = (S0 + S1 cos 2theta_n + S2 sin 2theta_n) / 2, so 2 (3 if sin 2alpha != 0)
    # transforms per frame replace its channels in every convolution, and the PSF update reuses their spectra
    fast = opts.psf.shared and not opts.polarization.estimate_aop
    model = (_StokesBasis if fast else _PerChannel)(ops, th, alpha, group)
    D = d.sum(axis=(-2, -1))
    empty = np.flatnonzero(np.bincount(group, weights=D, minlength=nps) <= 0)
    if empty.size:
        notes.append(
            f"PSF(s) {empty.tolist()} saw no photons (lost exposures): they keep their start"
        )
    problem = _Problem(d, th, valid, ops, support, D, group, model, opts, pupil, notes, phase_psf)
    if censored is not None:
        problem.censored, problem.ceiling = censored, float(opts.window.censor)
    pred = model.forward(h, s0, P)
    state = EMState(h, s0, P, pred, ops.window_share(pred.Hf), pupil_phase)
    state.loglik.append(problem.likelihood(pred.i))
    state.objective.append(state.loglik[-1])
    return problem, state


def e_step(problem: _Problem, state: EMState):
    """E-step (Eq. 193): back-project the data-to-prediction ratios.

    Parameters
    ----------
    problem : the fixed problem of :func:`blind_deconvolve`
    state : EMState

    Returns
    -------
    T : ``(Hp, Wp)`` expected photons from each object pixel; Qp : ``(Hp, Wp)`` their polarized part;
    Pp : ``(K, Hp, Wp)`` per-channel polarized part (None on the Stokes fast path); R : ratio spectra
    """
    i = state.pred.i
    r = np.divide(problem.data(i), i, out=np.zeros_like(problem.d), where=(i > 0) & problem.valid)
    return problem.model.estep(state.pred, r, state.s0, state.P)


def m_step(problem: _Problem, state: EMState, T, Qp, Pp):
    """M-step (Eq. 194, with the MAP DOLP of Eq. 196): new S0 and DOLP ``(Hp, Wp)``.

    Sets ``state.classes`` when several priors are given, and the AOP of the forward model when it is
    estimated.

    Parameters
    ----------
    problem, state : as for :func:`e_step`; T, Qp, Pp : its outputs

    Returns
    -------
    s0_new, P_new : arrays ``(Hp, Wp)``
    """
    if not problem.opts.update_object:
        return state.s0, state.P
    ops, model, priors = problem.ops, problem.model, problem.priors
    weight = problem.opts.polarization.prior_weight
    # S0 = T / sum_n w_n [(1 - P)/2 + P cos^2(alpha - theta_n)], w_n = h_n^T * 1_window the share of an
    # object pixel's light that reaches the measured window (Reeves; 1 for periodic boundaries)
    s0_new = T / model.s0_denominator(state.w, state.P)
    P_new = _dolp_update(T, Qp)  # unchecked: T >= 0 up to FFT round-off, which it reads as no light
    if priors:
        # the priors classify the measured pixels; the Reeves border (never observed) keeps the ML update
        Tw, Qw = ops.crop(T), ops.crop(Qp)
        cands = np.stack([_dolp_update(Tw, Qw, pr, weight) for pr in priors])
        objs = np.stack(
            [map_objective(cands[k], Tw, Qw, pr, weight) for k, pr in enumerate(priors)]
        )
        state.classes = np.argmax(objs, axis=0)
        P_new[ops.win] = np.take_along_axis(cands, state.classes[None], 0)[0]
    if problem.opts.polarization.estimate_aop:
        model.set_aop(_aop_mstep(Pp, problem.th))  # weights of ln cos^2(alpha - theta_n)
    return s0_new, P_new


def psf_step(problem: _Problem, state: EMState, R, s0_new=None, P_new=None):
    """PSF update (Eq. 194): ``h <- h (r * o) / D``, per channel, or summed over the channels that share a
    PSF (one frame); confined to the support; with ``mode="pupil"`` projected on the pupil model by
    Gerchberg-Saxton steps.

    Parameters
    ----------
    problem, state : as for :func:`e_step`; R : the ratio spectra from :func:`e_step`; s0_new, P_new : the
    object after the M-step (``mode="phase"`` fits the phases to it; None: the state's object)

    Returns
    -------
    h_new : ``(P, Hp, Wp)`` (``state.h`` itself when the PSF is fixed); pupil_phase : new pupil phases
    or None
    """
    popt, h, D, support = problem.opts.psf, state.h, problem.D, problem.support
    if popt.mode == "fixed":
        return h, None
    if popt.mode == "phase":
        s0 = state.s0 if s0_new is None else s0_new
        return _phase_step(problem, state, s0, state.P if P_new is None else P_new)
    num = sfft.fftshift(problem.model.psf_correlation(state.pred, R), axes=(-2, -1))
    group = problem.group
    if num.shape[0] != h.shape[0]:  # per-channel correlations of PSFs shared by several channels
        num = np.stack([num[group == g].sum(0) for g in range(h.shape[0])])
    Dg = np.bincount(group, weights=D, minlength=h.shape[0])[:, None, None]
    # a PSF that no photon reached (a lost exposure) keeps its value
    h_em = np.where(Dg > 0, h * num / np.maximum(Dg, 1e-300), h)
    h_em = np.where(support, np.clip(h_em, 0, None), 0.0)
    h_em /= np.maximum(h_em.sum(axis=(-2, -1), keepdims=True), 1e-300)
    if popt.mode != "pupil":
        return h_em, None
    h_new, phase = gerchberg_saxton(
        h_em, problem.pupil, state.pupil_phase, problem.ops.shape, popt.gs_steps
    )
    h_new = np.where(support, h_new, 0.0)
    h_new /= h_new.sum(axis=(-2, -1), keepdims=True)
    return h_new, phase


def _phase_step(problem: _Problem, state: EMState, s0, P):
    """Each frame's pupil phase maximizing its Poisson log-likelihood with the object held at (s0, P):
    ``gs_steps`` L-BFGS iterations from the current phase (the objective is scaled by the frame's counts)."""
    from scipy.optimize import minimize

    model, ops, pp = problem.model, problem.ops, problem.phase_psf
    Bf = model.object_spectra(s0, P)
    inside = pp.inside
    hs, phases = [], []
    for f in range(state.h.shape[0]):
        chan = problem.group == f
        d_f, scale = problem.d[chan], float(problem.D[chan].sum())
        if scale <= 0:  # a lost exposure: no information on its PSF
            phases.append(state.pupil_phase[f])
            hs.append(state.h[f])
            continue

        def objective(x, f=f, d_f=d_f, scale=scale):
            ph = np.zeros(inside.shape)
            ph[inside] = x
            L, G = model.frame_loglik(f, ops.otf(pp.psf(ph)), Bf, d_f, problem.valid)
            return -L / scale, -pp.gradient(ph, G)[inside] / scale

        x0 = state.pupil_phase[f][inside]
        res = minimize(
            objective,
            x0,
            jac=True,
            method="L-BFGS-B",
            # the scaled objective's gradient is small (1e-6 per phase pixel): stop on the steps only
            options={"maxiter": problem.opts.psf.gs_steps, "gtol": 0.0, "ftol": 0.0},
        )
        ph = np.zeros(inside.shape)
        ph[inside] = res.x
        phases.append(ph)
        hs.append(pp.psf(ph))
    return np.stack(hs), np.stack(phases)


def _accept(problem: _Problem, state: EMState, s0_new, P_new, h_new, phase_new):
    """Move the state to the new estimate; Schulz: a pupil-projected PSF step is kept only if the
    log-likelihood increased. Records the log-likelihood and the objective."""
    model, h = problem.model, state.h
    pred = model.forward(h_new, s0_new, P_new, Hf=state.pred.Hf if h_new is h else None)
    L_new = problem.likelihood(pred.i)
    parametric = problem.opts.psf.mode in ("pupil", "phase")
    if parametric and L_new < state.loglik[-1]:
        h_new = h
        pred = model.forward(h, s0_new, P_new, Hf=state.pred.Hf)
        L_new = problem.likelihood(pred.i)
    elif parametric:
        state.pupil_phase = phase_new
    if h_new is not h:
        state.w = problem.ops.window_share(pred.Hf)
    state.h, state.s0, state.P, state.pred = h_new, s0_new, P_new, pred
    state.loglik.append(L_new)
    state.objective.append(L_new + _log_prior(problem, state))


def _log_prior(problem: _Problem, state: EMState) -> float:
    """Sum over pixels of the weighted log prior of each pixel's class (0 without priors)."""
    if not problem.priors:
        return 0.0
    weight, P = problem.opts.polarization.prior_weight, problem.ops.crop(state.P)
    return float(
        np.sum(
            [
                np.sum(np.where(state.classes == k, weight * pr.log_pdf(P), 0.0))
                for k, pr in enumerate(problem.priors)
            ]
        )
    )


def blind_deconvolve(
    data, angles, *, psf0=None, pupil=None, options: EMOptions | None = None, **keywords
) -> DeconvolutionResult:
    """Blind deconvolution of polarimetric channel images (EM, Eqs. 185-196).

    The options come grouped in ``options`` (:class:`EMOptions`) or as the flat keywords of earlier
    versions, applied on top of ``options``: ``psf_mode``, ``shared_psf``, ``psf_radius``, ``gs_steps``
    (:class:`PSFOptions`); ``aop``, ``estimate_aop``, ``priors``, ``prior_weight``
    (:class:`PolarizationOptions`); ``boundary``, ``pad``, ``mask``, ``saturation``, ``censor``
    (:class:`WindowOptions`); ``s0_start``, ``dolp_start`` (:class:`StartOptions`); ``iterations``, ``tol``,
    ``callback`` (:class:`StopOptions`);
    ``update_object``. Each iteration is :func:`e_step`, :func:`m_step`, :func:`psf_step` on an
    :class:`EMState`.

    Parameters
    ----------
    data : array (K, H, W) [photo-electrons] -- negative values (read noise after dark subtraction) are
        clipped at 0 for the Poisson model; NaN is not allowed: give missing pixels any finite value and
        leave them out with ``mask`` (0 photons alone would read as a black spot of DOLP 0, i.e. metal).
    angles : array (K,) [rad] -- polarizer angles, in [-2 pi, 2 pi] (degrees are refused).
    psf0 : array (Hp, Wp) or (P, Hp, Wp) on the object grid, optional -- initial or known PSF(s) (centred,
        finite, >= 0, positive sum), P = ``frames`` with a shared PSF, K without.
    pupil : array (n, n), optional -- aperture for ``psf_mode="pupil"`` and the diffraction-limited start.
    options : EMOptions, optional
    **keywords : the flat option names above (unknown names raise TypeError).

    Returns
    -------
    DeconvolutionResult
        ``aop`` is the fixed AOP, or the per-pixel estimate with ``estimate_aop=True`` [rad].
    """
    t0 = time.perf_counter()
    opts = _resolve_options(options, keywords)
    problem, state = _setup(data, angles, psf0, pupil, opts)
    it, tol = 0, opts.stop.tol
    for it in range(1, opts.stop.iterations + 1):
        T, Qp, Pp, R = e_step(problem, state)
        s0_new, P_new = m_step(problem, state, T, Qp, Pp)
        h_new, phase_new = psf_step(problem, state, R, s0_new, P_new)
        _accept(problem, state, s0_new, P_new, h_new, phase_new)
        if opts.stop.callback is not None:
            opts.stop.callback(_result(problem, state, it, time.perf_counter() - t0))
        L = state.loglik
        if tol is not None and abs(L[-1] - L[-2]) <= tol * abs(L[-2]):
            break
    return _result(problem, state, it, time.perf_counter() - t0)


def _result(problem: _Problem, state: EMState, iterations, seconds) -> DeconvolutionResult:
    ops, alpha = problem.ops, problem.model.alpha
    aop = ops.crop(alpha) if np.ndim(alpha) else np.full((ops.H, ops.W), float(alpha))
    return DeconvolutionResult(
        # the FFT correlations of the multiplicative update leave round-off (|x| ~ 1e-80) where there is
        # no light; an intensity is >= 0
        s0=np.maximum(ops.crop(state.s0), 0.0),
        dolp=np.clip(ops.crop(state.P), 0, 1),
        aop=aop,
        psfs=state.h,
        classes=state.classes,
        priors=problem.priors,
        loglik=np.array(state.loglik),
        objective=np.array(state.objective),
        iterations=iterations,
        notes=problem.notes,
        seconds=seconds,
    )


@dataclass
class _State:
    """Predicted channel images i (K, H, W), the OTF(s) and the spectra the PSF update reuses."""

    i: np.ndarray
    Hf: np.ndarray
    spectra: np.ndarray


class _StokesBasis:
    """One PSF per frame, known AOP: o_n = sum_j A_nj B_j with B = (S0, P S0 cos 2alpha, P S0 sin 2alpha)
    and A_n = (1, cos 2theta_n, sin 2theta_n) / 2 (the third term dropped when sin 2alpha = 0 everywhere).
    The object's spectra are shared by the frames; the back-projections of all frames are summed in the
    Fourier domain, so a frame costs J transforms forward and J back."""

    def __init__(self, ops, th, alpha, group):
        self.ops, self.alpha = ops, alpha
        self.frames = int(group.max()) + 1
        c2a, s2a = np.cos(2 * alpha), np.sin(2 * alpha)
        self.J = 3 if np.any(np.abs(s2a) > 1e-12) else 2
        self.trig = np.stack([c2a, s2a])[: self.J - 1]  # (J - 1, Hp, Wp)
        A = 0.5 * np.stack([np.ones_like(th), np.cos(2 * th), np.sin(2 * th)], axis=1)[:, : self.J]
        self.A = A.reshape(self.frames, -1, self.J)  # (F, K / F, J)
        # (F, J - 1): sum over each frame's channels of (cos 2theta_n, sin 2theta_n)
        self.sum_trig = (2 * self.A[..., 1:]).sum(1)

    def forward(self, h, s0, P, Hf=None):
        Hf = self.ops.otf(h) if Hf is None else Hf  # (F, Hp, Wr)
        Bf = self.object_spectra(s0, P)
        blurred = self.ops.crop(self.ops.irfft(Bf[None] * Hf[:, None]))  # (F, J, H, W)
        i = np.einsum("fkj,fjyx->fkyx", self.A, blurred)
        return _State(i.reshape((-1,) + i.shape[2:]), Hf, Bf)

    def estep(self, state, r, s0, P):
        rf = r.reshape(self.A.shape[:2] + r.shape[1:])  # (F, K / F, H, W)
        # spectra of each frame's combined ratios (F, J, ...), back-projected and summed over the frames
        R = self.ops.rfft(self.ops.extend(np.einsum("fkj,fkyx->fjyx", 2 * self.A, rf)))
        C = self.ops.irfft(np.sum(R * np.conj(state.Hf)[:, None], axis=0))  # (J, Hp, Wp)
        pol = C[0] + np.sum(self.trig * C[1:], axis=0)  # sum_n 2 cos^2(alpha - theta_n) c_n
        T = 0.5 * s0 * ((1 - P) * C[0] + P * pol)
        Qp = 0.5 * P * s0 * pol
        return T, Qp, None, R

    def object_spectra(self, s0, P):
        """Spectra of the Stokes images B = (S0, P S0 cos 2alpha[, P S0 sin 2alpha]), (J, Hp, Wr)."""
        return self.stokes_spectra(s0, P * s0)

    def stokes_spectra(self, s0, ps0):
        """:meth:`object_spectra` from S0 and the polarized irradiance P S0 ``(Hp, Wp)``."""
        return self.ops.rfft(np.concatenate([s0[None], ps0[None] * self.trig]))

    def frame_residual(self, f, Hf, Bf, d, valid):
        """Poisson log-likelihood of frame ``f`` (its channels ``d``) through the OTF ``Hf`` of one PSF, and
        the spectra ``(J, Hp, Wr)`` of its residuals sum_n A_nj (d_n / i_n - 1), from which the gradients
        follow: with respect to the PSF by correlation with the object, to the Stokes images with the PSF."""
        A = self.A[f]  # (K / F, J)
        i = np.tensordot(A, self.ops.crop(self.ops.irfft(Bf * Hf)), axes=1)
        i = np.maximum(i, 1e-300)
        L = float(np.vdot(d, np.log(i))) - float(np.sum(i * valid))
        r = np.where(valid, d / i - 1.0, 0.0)
        return L, self.ops.rfft(self.ops.extend(np.tensordot(A.T, r, axes=1)))

    def frame_loglik(self, f, Hf, Bf, d, valid):
        """Poisson log-likelihood of frame ``f`` (its channels ``d``) through the OTF ``Hf`` of one PSF, and
        its gradient with respect to that (centred) PSF: sum_n (d_n / i_n - 1) correlated with o_n."""
        L, R = self.frame_residual(f, Hf, Bf, d, valid)
        G = sfft.fftshift(self.ops.irfft(np.sum(R * np.conj(Bf), axis=0)))
        return L, G

    def s0_denominator(self, w, P):
        w = np.broadcast_to(w, (self.frames,) + P.shape)
        K = self.A.shape[1]
        per = 0.5 * K + 0.5 * P * np.einsum("fj,jyx->fyx", self.sum_trig, self.trig)
        return np.sum(w * per, axis=0)

    def psf_correlation(self, state, R):
        return self.ops.irfft(0.5 * np.sum(R * np.conj(state.spectra)[None], axis=1))  # (F, Hp, Wp)


class _PerChannel:
    """One PSF per channel, or an AOP to estimate: the K channel objects are convolved one by one (channel n
    through PSF ``group[n]``)."""

    def __init__(self, ops, th, alpha, group):
        self.ops, self.th, self.group = ops, th, group
        self.set_aop(alpha)

    def _per_channel(self, a):
        """PSF-indexed ``a`` (P, ...) as channel-indexed (K, ...) (as it is when P is 1 or K)."""
        return a if np.ndim(a) == 0 or a.shape[0] in (1, self.th.size) else a[self.group]

    def set_aop(self, alpha):
        self.alpha = alpha
        self.cos2 = np.cos(alpha[None] - self.th[:, None, None]) ** 2  # (K, Hp, Wp)

    def forward(self, h, s0, P, Hf=None):
        Hf = self.ops.otf(h) if Hf is None else Hf
        o = 0.5 * (1 - P) * s0 + P * s0 * self.cos2  # (K, Hp, Wp)
        Of = self.ops.rfft(o)
        return _State(self.ops.crop(self.ops.irfft(Of * self._per_channel(Hf))), Hf, Of)

    def estep(self, state, r, s0, P):
        R = self.ops.rfft(self.ops.extend(r))
        c = self.ops.irfft(R * np.conj(self._per_channel(state.Hf)))  # back-projection (K, Hp, Wp)
        Pp = P * s0 * self.cos2 * c  # sum_y psi_pn
        T = (0.5 * (1 - P) * s0 * c + Pp).sum(0)
        return T, Pp.sum(0), Pp, R

    def s0_denominator(self, w, P):
        return np.sum(self._per_channel(w) * (0.5 * (1 - P) + P * self.cos2), axis=0)

    def psf_correlation(self, state, R):
        return self.ops.irfft(R * np.conj(state.spectra))  # r_n correlated with o_n


def _aop_mstep(B, th):
    """alpha maximizing sum_n B_n ln cos^2(alpha - theta_n) per pixel: 1-deg grid, parabolic refinement.

    ``B`` (K, Hp, Wp) weights, ``th`` (K,) [rad]; returns alpha (Hp, Wp) [rad]. The table
    ln cos^2(g - theta_n) is (grid, K): the objective on the grid is one weighted sum over n per pixel,
    accumulated in the order n = 0, 1, ... (the same sums as a per-grid-point loop).
    """
    grid = np.radians(np.arange(-90, 90, 1.0))
    table = np.log(np.maximum(np.cos(grid[:, None] - th[None, :]) ** 2, 1e-300))  # (G, K)
    vals = table[:, 0, None, None] * B[0]
    for n in range(1, B.shape[0]):
        vals += table[:, n, None, None] * B[n]
    k = np.argmax(vals, 0)
    km, kp = (k - 1) % grid.size, (k + 1) % grid.size
    f0 = np.take_along_axis(vals, k[None], 0)[0]
    fm = np.take_along_axis(vals, km[None], 0)[0]
    fp = np.take_along_axis(vals, kp[None], 0)[0]
    den = fm - 2 * f0 + fp
    shift = np.where(den < 0, 0.5 * (fm - fp) / np.where(den < 0, den, -1.0), 0.0)
    return grid[k] + np.clip(shift, -0.5, 0.5) * np.radians(1.0)


def object_grid(data_shape, psf_radius=None, boundary: str = "reeves", pad=None) -> tuple:
    """Shape (Hp, Wp) of the object grid :func:`blind_deconvolve` uses for ``data_shape`` (H, W).

    Parameters
    ----------
    data_shape : tuple of int
        Shape ``(H, W)`` of the data frames [pixels], integers >= 1.
    psf_radius : float, optional
        PSF support radius [pixels], in ``(0, hypot(H, W)]`` (at most the image's diagonal); default
        ``min(H, W) / 4``.
    boundary : str
        ``"reeves"`` (padded object grid) or any other boundary (object grid = data grid).
    pad : int, optional
        Padding on each side [pixels] for ``"reeves"``, an integer >= 0; default ``ceil(psf_radius)``.

    Returns
    -------
    tuple of int
        ``(Hp, Wp)``: ``(H + 2 pad, W + 2 pad)`` for ``"reeves"``, else ``(H, W)``.
    """
    H, W = as_image_shape(data_shape, "data_shape")
    if pad is not None:
        pad = as_count(pad, "pad", 0, " [pixels]")
    if psf_radius is None:
        psf_radius = min(H, W) / 4
    elif np.ndim(psf_radius) != 0:
        raise ValueError(f"psf_radius must be a single float > 0 [pixels], got {psf_radius!r}")
    else:
        psf_radius = float(as_positive(psf_radius, "psf_radius"))
        if psf_radius > np.hypot(H, W):
            raise ValueError(
                f"psf_radius must be in (0, {np.hypot(H, W):.4g}] pixels (the image's diagonal), got "
                f"{psf_radius!r}"
            )
    if pad is None:
        pad = int(np.ceil(psf_radius)) if boundary == "reeves" else 0
    return (H + 2 * pad, W + 2 * pad) if boundary == "reeves" else (H, W)
