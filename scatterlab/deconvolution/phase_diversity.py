r"""Phase diversity: the turbulent PSF of one exposure from frames with known pupil-phase offsets.

A single frame does not identify its PSF: a sharper PSF and a softer object fit it as well as the truth
(measured in ``docs/characterization_accuracy.md``). Phase diversity (Gonsalves 1982; Paxman, Schulz and
Fienup 1992) records the same instant on further detectors whose pupil phase differs from the focused
one's by a known amount, usually a defocus. Frame :math:`f` then records

.. math:: d_f \sim \mathrm{Poisson}\big(g_f\,(o * h_f) + \sigma_f^2\big) - \sigma_f^2, \qquad
          h_f = |\mathcal F\{A\,e^{j(\phi + \theta_f)}\}|^2 / \textstyle\sum |\cdot|^2,

with one unknown phase :math:`\phi` and one object :math:`o`, the known offsets :math:`\theta_f` and gains
:math:`g_f` (the share of light each detector gets), and the read noise as a Poisson offset (Snyder). The
PSF model is that of Schulz's multi-frame blind deconvolution (Eq. 186, Sec. 5.3.2); what the offsets add
is that a wrong :math:`\phi` can no longer be traded for a wrong object in every frame at once.

:func:`phase_diversity` maximizes the joint Poisson likelihood over :math:`\phi` and :math:`o \ge 0`
together, by L-BFGS-B on the analytic gradient (the phase part is
:meth:`~scatterlab.deconvolution.psf_update.PupilPhasePSF.gradient`). The object lives on the field padded
on every side, so light from outside the field enters it and nothing wraps around. The phase is the
Gaussian smoothing of free values, narrowed from coarse to fine over the stages (``smoothing``, in pupil
pixels): a coarse phase first, then its detail, which keeps the search out of the local optima a free
phase runs into.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from scatterlab._checks import as_count

__all__ = ["defocus_phase", "phase_diversity", "PhaseDiversityResult"]

# L-BFGS-B's memory (corrections kept). Its own work per iteration grows with it and, with 10^5 variables,
# exceeded the likelihood's at 20; on the default scene's aluminium at D/r0 7.9 (7 stages of 300
# iterations) 5 and 10 reached PSF L1 0.137, 20 reached 0.18 in about twice the time
LBFGS_MEMORY = 5


def defocus_phase(pupil, waves: float) -> np.ndarray:
    r"""A defocus of ``waves`` waves peak to valley over the aperture: :math:`\pi w (2\rho^2 - 1)`.

    The Zernike defocus shape, :math:`\rho` the distance from the aperture's centre (the grid centre,
    as :func:`scatterlab.imaging.circular_pupil` places it) over its radius (from its area).

    Parameters
    ----------
    pupil : array_like, shape (n, n)
        Aperture amplitude (non-zero inside).
    waves : float
        Peak-to-valley defocus [waves] (finite; the sign chooses the side of focus).

    Returns
    -------
    ndarray, shape (n, n)
        Phase [rad], zero outside the aperture.
    """
    A = np.asarray(pupil, float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not np.any(A > 0):
        raise ValueError(f"pupil must be a square 2-D aperture with light, got shape {A.shape}")
    if not np.isfinite(waves):
        raise ValueError(f"waves must be finite, got {waves!r}")
    n = A.shape[0]
    radius = np.sqrt((A > 0).sum() / np.pi)
    y, x = np.mgrid[0:n, 0:n] - (n - 1) / 2
    rho2 = (x**2 + y**2) / radius**2
    return np.where(A > 0, np.pi * float(waves) * (2 * rho2 - 1), 0.0)


@dataclass
class PhaseDiversityResult:
    """The outcome of :func:`phase_diversity`.

    Attributes
    ----------
    phase : ndarray, shape (n, n)
        The unknown phase common to all frames [rad] (the focused frame's, whose offset is zero); zero
        outside the aperture. Piston and tilt are not determined: the tilt moves the object instead.
    psfs : ndarray, shape (F, 2n, 2n)
        Each frame's PSF (centred, unit sum, 2 pixels per lambda/D as :func:`scatterlab.imaging.psf`).
    object : ndarray, shape (H + 2 pad, W + 2 pad)
        The object [counts of a gain-1 frame per pixel], on the padded field.
    neg_log_likelihood : float
        Poisson negative log-likelihood at the end, as half the deviance (0 for a perfect fit).
    history : list of tuple
        ``(smoothing, neg_log_likelihood, status)`` after each stage (status: scipy's L-BFGS-B code,
        0 converged, 1 iteration limit).
    """

    phase: np.ndarray
    psfs: np.ndarray
    object: np.ndarray
    neg_log_likelihood: float
    history: list = field(default_factory=list)


class _Likelihood:
    """The joint Poisson negative log-likelihood of the frames and its gradient in (phase, object)."""

    def __init__(self, frames, diversity, pupil, gains, offsets, pad):
        from scatterlab.deconvolution.psf_update import PupilPhasePSF

        F, H, W = frames.shape
        self.shape = (H + 2 * pad, W + 2 * pad)
        self.mask = np.zeros(self.shape)
        self.mask[pad : pad + H, pad : pad + W] = 1.0
        self.diversity, self.gains, self.offsets = diversity, gains, offsets
        # the data plus the read-noise offset (Snyder), which a dark-subtracted frame can push below 0
        self.shifted = np.zeros((F,) + self.shape)
        self.shifted[:, pad : pad + H, pad : pad + W] = np.maximum(
            frames + offsets[:, None, None], 0.0
        )
        self.model = PupilPhasePSF(pupil, self.shape, np.ones(self.shape, bool))

    def _otf(self, h):
        return np.fft.rfft2(np.fft.ifftshift(h))

    def __call__(self, phase, obj):
        """(negative log-likelihood, d/d phase (n, n), d/d object (Hp, Wp))."""
        irfft = lambda a: np.fft.irfft2(a, s=self.shape)  # noqa: E731
        O = np.fft.rfft2(obj)
        nll, g_phase, g_obj = 0.0, np.zeros_like(phase), np.zeros(self.shape)
        for y, theta, g, b in zip(self.shifted, self.diversity, self.gains, self.offsets):
            ph = phase + theta
            Hf = self._otf(self.model.psf(ph))
            m = np.maximum(g * irfft(O * Hf) + b, 1e-12)
            # the Poisson deviance / 2: zero for a perfect fit, so tolerances do not scale with brightness
            nll += float(np.sum(self.mask * (m - y + y * np.log(np.where(y > 0, y, 1.0) / m))))
            R = np.fft.rfft2(self.mask * (1.0 - y / m) * g)
            # dL/dh[x] = sum_y R[y] o[y - x] (centred), dL/do = R correlated with h
            g_phase += self.model.gradient(ph, np.fft.fftshift(irfft(R * np.conj(O))))
            g_obj += irfft(R * np.conj(Hf))
        return nll, g_phase, g_obj


def _check(frames, diversity, pupil, gains, read_noise, pad, smoothing, iterations):
    from scatterlab._checks import as_finite

    d = as_finite(frames, "frames")
    if d.ndim != 3 or d.shape[0] < 2:
        raise ValueError(
            f"frames must be (F, H, W) with F >= 2 (the focused frame and at least one with a known "
            f"phase offset), got shape {d.shape}"
        )
    dark = [f for f in range(d.shape[0]) if not np.any(d[f] > 0)]
    if (
        dark
    ):  # a frame without light says nothing of the phase; all dark, nothing of the object either
        raise ValueError(
            f"frames {dark} hold no photons (every count is <= 0): each frame, the focused one and the "
            "diverse ones, needs light to identify the PSF"
        )
    A = as_finite(pupil, "pupil")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not np.any(A > 0) or np.any(A < 0):
        raise ValueError(
            f"pupil must be a square 2-D aperture amplitude (>= 0) with light, got shape {A.shape}"
        )
    th = as_finite(diversity, "diversity")
    if th.shape != (d.shape[0],) + A.shape:
        raise ValueError(
            f"diversity must be one phase offset [rad] per frame, shape {(d.shape[0],) + A.shape}, "
            f"got {th.shape}"
        )
    inside = A > 0
    if all(np.allclose(t[inside], th[0][inside]) for t in th[1:]):
        raise ValueError(
            "diversity: every frame has the same phase offset; without a known difference between the "
            "frames the PSF is not identified (defocus_phase gives one)"
        )
    F = d.shape[0]
    per_frame = []
    for name, value in (("gains", 1.0 if gains is None else gains), ("read_noise", read_noise)):
        v = np.atleast_1d(as_finite(value, name))
        if v.shape not in ((1,), (F,)):
            raise ValueError(
                f"{name} must be one number or one per frame ({F}), got shape {v.shape}"
            )
        per_frame.append(np.broadcast_to(v, (F,)).copy())
    g, s = per_frame
    if np.any(g <= 0):
        raise ValueError(f"gains must be > 0 (each frame's share of the light), got {g}")
    if np.any(s < 0):
        raise ValueError(f"read_noise must be >= 0 [e- rms], got {s}")
    n = A.shape[0]
    if pad is None:
        pad = max(n, max(d.shape[1], d.shape[2]) // 2)
    as_count(pad, "pad", 0, " [pixels]")
    if 2 * n > min(d.shape[1], d.shape[2]) + 2 * pad:
        raise ValueError(
            f"pad = {pad} is too small for the pupil's {2 * n} x {2 * n} PSF: the padded field "
            f"must hold it (pad >= {(2 * n - min(d.shape[1], d.shape[2]) + 1) // 2}; >= {n} for no "
            "wrap-around)"
        )
    sm = [float(v) for v in np.atleast_1d(as_finite(smoothing, "smoothing"))]
    if not sm or any(v < 0 for v in sm):
        raise ValueError(
            f"smoothing must be one or more widths >= 0 [pupil pixels], got {smoothing!r}"
        )
    if (
        isinstance(iterations, bool)
        or not isinstance(iterations, (int, np.integer))
        or iterations < 1
    ):
        raise ValueError(f"iterations must be an integer >= 1, got {iterations!r}")
    return d, th, A, g, s, int(pad), sm


def phase_diversity(
    frames,
    diversity,
    pupil,
    *,
    gains=None,
    read_noise=0.0,
    pad: int | None = None,
    smoothing=(8.0, 6.0, 4.0, 3.0, 2.0, 1.0, 0.5),
    iterations: int = 300,
    phase0=None,
) -> PhaseDiversityResult:
    """The pupil phase, PSFs and object of frames that differ by known pupil-phase offsets.

    Parameters
    ----------
    frames : array_like, shape (F, H, W)
        Dark-subtracted counts [photo-electrons] of the same instant, F >= 2: typically the sum of a
        polarimeter's channels (its focused frame) and one or two defocused unpolarized frames.
    diversity : array_like, shape (F, n, n)
        Each frame's known pupil-phase offset [rad] (zero for the focused frame; :func:`defocus_phase`).
    pupil : array_like, shape (n, n)
        Aperture amplitude, sampled so that its PSF (2n x 2n) has 2 pixels per lambda/D on the frames'
        grid.
    gains : array_like, shape (F,), optional
        Expected counts of each frame per unit object (> 0; default 1 for all).
    read_noise : float or array_like (F,)
        Total read noise of a frame pixel [e- rms] (>= 0; sqrt(2) times the per-read noise when a dark
        frame was subtracted), modelled as a Poisson offset of its variance.
    pad : int, optional
        Pixels of object around the field on every side (default the larger of n and half the field;
        at least n - H/2 so that the 2n x 2n PSF fits the padded grid). With ``pad >= n`` light from
        outside the field enters it and nothing wraps around.
    smoothing : sequence of float
        Gaussian widths [pupil pixels] of the phase parameterisation, one L-BFGS stage each, coarse to
        fine (0: a free phase).
    iterations : int
        L-BFGS iterations per stage (>= 1), the accuracy knob with ``smoothing``.
    phase0 : array_like, shape (n, n), optional
        Start phase [rad] (default zero: the diffraction-limited PSF); the stages add smooth
        corrections to it.

    Returns
    -------
    PhaseDiversityResult
        Phase, PSFs, object and the likelihood after each stage.

    Raises
    ------
    ValueError
        Fewer than two frames, shapes that do not match, non-finite data, the same offset in every
        frame, a negative pupil, gains not > 0, negative read noise, ``gains`` or ``read_noise`` of
        the wrong length, a ``pad`` too small for the PSF, a bad ``smoothing`` or ``iterations``.
    """
    from scipy.ndimage import gaussian_filter
    from scipy.optimize import Bounds, minimize

    from scatterlab.imaging import psf as pupil_psf

    d, theta, A, g, s, pad, stages = _check(
        frames, diversity, pupil, gains, read_noise, pad, smoothing, iterations
    )
    like = _Likelihood(d, theta, A, g, s**2, pad)
    inside = A > 0
    n = A.shape[0]
    phase = np.zeros((n, n)) if phase0 is None else np.where(inside, _as_phase(phase0, (n, n)), 0.0)
    # start object: the gain-normalised mean frame, its edges carried into the padding
    mean = np.clip(np.mean(d / g[:, None, None], axis=0), 0.0, None)
    obj = np.pad(mean, pad, mode="edge")
    c = max(float(obj.mean()), 1e-12)  # object unit for the optimizer
    scale = 1.0 / d[0].size  # per pixel: tolerances that do not depend on the field size
    npx, no = n * n, obj.size
    history = []
    for width in stages:

        def smooth(a, width=width):
            return gaussian_filter(a, width, mode="constant") if width > 0 else a

        # each stage fits a smooth correction to the phase the last one ended at
        def objective(v, smooth=smooth, base=phase):
            ph = base + np.where(inside, smooth(v[:npx].reshape(n, n)), 0.0)
            nll, g_ph, g_o = like(ph, c * v[npx:].reshape(like.shape))
            g_free = smooth(np.where(inside, g_ph, 0.0))
            return nll * scale, np.concatenate([g_free.ravel(), c * g_o.ravel()]) * scale

        x0 = np.concatenate([np.zeros(npx), obj.ravel() / c])
        # arrays, not a list of pairs: scipy converts 10^5 pairs one by one on every stage
        bounds = Bounds(np.r_[np.full(npx, -np.inf), np.zeros(no)], np.inf)
        res = minimize(
            objective,
            x0,
            jac=True,
            method="L-BFGS-B",
            bounds=bounds,
            options={"maxiter": iterations, "maxcor": LBFGS_MEMORY},
        )
        phase = phase + np.where(inside, smooth(res.x[:npx].reshape(n, n)), 0.0)
        obj = c * res.x[npx:].reshape(like.shape)
        history.append((width, float(res.fun / scale), int(res.status)))
    psfs = np.stack([pupil_psf(A, phase + t, pad=2) for t in theta])
    return PhaseDiversityResult(phase, psfs, obj, history[-1][1], history)


def _as_phase(value, shape) -> np.ndarray:
    """A finite phase array [rad] of ``shape``, else a ValueError naming ``phase0``."""
    from scatterlab._checks import as_finite

    p = as_finite(value, "phase0")
    if p.shape != tuple(shape):
        raise ValueError(f"phase0 must have the pupil's shape {tuple(shape)}, got {p.shape}")
    return p
