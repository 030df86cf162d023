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
Initial guesses: the text (Sec. 5.3.2) starts from S0 = 1, P = 1/2, alpha = 0 and the PSF of a random
Kolmogorov screen (:func:`scatterlab.deconvolution.psf_update.initial_psf`); here S0 and P start by default from
the least-squares Stokes images of the data (``s0_start=1.0, dolp_start=0.5`` gives the text's start), the PSF
from ``psf0``, else the diffraction-limited PSF of ``pupil``. The Poisson log-likelihood
:math:`\sum_n\sum_y[d_n\ln i_n - i_n]` is recorded every iteration; without priors it never decreases.
Speed: with one PSF and a known AOP the channel objects are linear in 2-3 Stokes images, and the convolutions
act on those (:class:`_StokesBasis`); otherwise channel by channel.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.fft as sfft

from scatterlab.deconvolution.priors import dolp_update, map_objective
from scatterlab.deconvolution.psf_update import gerchberg_saxton, resample_psf

__all__ = ["blind_deconvolve", "DeconvolutionResult", "evenly_spaced", "object_grid"]


def evenly_spaced(angles) -> bool:
    """True when the polarizer angles are evenly spaced over 180 deg (mod 180), K >= 3."""
    a = np.sort(np.mod(np.asarray(angles, float), np.pi))
    K = a.size
    if K < 3:
        return False
    d = np.diff(np.r_[a, a[0] + np.pi])
    return bool(np.allclose(d, np.pi / K, atol=1e-9))


@dataclass
class DeconvolutionResult:
    """Estimates on the data grid: s0, dolp, aop (H, W); psfs (K or 1, Hp, Wp) on the object grid (centred);
    classes (H, W) int index into ``priors`` (or None); loglik (iterations + 1,) Poisson log-likelihood;
    objective (with the log priors); iterations; notes; seconds."""

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


def blind_deconvolve(
    data,
    angles,
    *,
    psf0=None,
    pupil=None,
    psf_mode: str = "em",
    shared_psf: bool = True,
    priors: tuple | None = None,
    prior_weight: float = 1.0,
    aop=0.0,
    estimate_aop: bool = False,
    iterations: int = 50,
    tol: float | None = None,
    psf_radius: float | None = None,
    boundary: str = "reeves",
    pad: int | None = None,
    gs_steps: int = 5,
    update_object: bool = True,
    s0_start=None,
    dolp_start=None,
    mask=None,
    saturation: float | None = None,
) -> DeconvolutionResult:
    """Blind deconvolution of polarimetric channel images.

    Parameters
    ----------
    data : array (K, H, W) [photo-electrons] -- negative values (read noise after dark subtraction) are
        clipped at 0 for the Poisson model; NaN is not allowed (use 0 and it contributes nothing).
    angles : array (K,) [rad] -- polarizer angles.
    psf0 : array (Hp, Wp) or (K, Hp, Wp) on the object grid, optional -- initial or known PSF (centred).
    pupil : array (n, n), optional -- aperture for ``psf_mode="pupil"`` and the diffraction-limited start.
    psf_mode : "em", "pupil" or "fixed"
    shared_psf : one PSF for all channels (division of amplitude) or one per channel.
    priors : tuple of SuperGaussianPrior, optional -- one: MAP DOLP; several: per-pixel classification.
    aop : float or array (H, W) [rad] -- fixed AOP (0 for specular observation); start when ``estimate_aop``.
    iterations, tol : stop after ``iterations`` or when the relative change of the log-likelihood < ``tol``.
    psf_radius : PSF support radius [pixels] (default: a quarter of the smaller object side).
    boundary : "reeves" or "periodic"; pad : Reeves padding (default psf_radius).
    s0_start, dolp_start : float or (H, W), optional -- initial S0 [counts] and DOLP instead of the Stokes
        estimates of the data (a DOLP of 0 stays 0: the unpolarized EM is Richardson-Lucy).
    mask : bool array (H, W), optional -- pixels to use (False: saturated, dead, ...); they leave the
        likelihood as the Reeves border does, and the object there is estimated from its neighbours' light.
    saturation : float, optional [photo-electrons] -- pixels where any channel reaches it are masked too.

    Returns
    -------
    DeconvolutionResult
    """
    t0 = time.perf_counter()
    d = np.asarray(data, float)
    if d.ndim != 3:
        raise ValueError(f"data must have shape (K, H, W), got {d.shape}")
    if not np.all(np.isfinite(d)):
        raise ValueError("data must be finite (mark missing pixels with 0 photons)")
    th = np.asarray(angles, float).ravel()
    K = d.shape[0]
    if th.size != K:
        raise ValueError(f"angles has {th.size} entries for {K} channels")
    if psf_mode not in ("em", "pupil", "fixed"):
        raise ValueError(f"psf_mode must be 'em', 'pupil' or 'fixed', got {psf_mode!r}")
    if boundary not in ("reeves", "periodic"):
        raise ValueError(f"boundary must be 'reeves' or 'periodic', got {boundary!r}")
    if np.any(np.abs(th) > 2 * np.pi):
        raise ValueError(
            f"angles must be polarizer angles in radians, got values up to {np.abs(th).max():g} "
            "(degrees? use numpy.radians)"
        )
    if not (np.isfinite(prior_weight) and prior_weight >= 0):
        raise ValueError(f"prior_weight must be finite and >= 0, got {prior_weight!r}")
    if psf_radius is not None and not (np.isfinite(psf_radius) and psf_radius >= 1):
        raise ValueError(f"psf_radius must be >= 1 pixel, got {psf_radius!r}")
    if psf0 is not None:
        p0 = np.asarray(psf0, float)
        if not np.all(np.isfinite(p0)) or np.any(p0 < 0) or not np.all(p0.sum(axis=(-2, -1)) > 0):
            raise ValueError("psf0 must be finite and non-negative with a positive sum (a PSF)")
    if psf_mode == "fixed" and psf0 is None:
        raise ValueError("psf_mode='fixed' needs psf0")
    if psf_mode == "pupil" and pupil is None:
        raise ValueError("psf_mode='pupil' needs the pupil (aperture) array")
    notes = []
    if not evenly_spaced(th):
        notes.append(
            "polarizer angles are not evenly spaced: the S0/DOLP updates are generalised-EM steps "
            "(coupled updates of Sec. 3.3.2)"
        )
    d = np.clip(d, 0.0, None)
    if not d.sum() > 0:
        raise ValueError("data holds no photons (every count is <= 0): nothing to deconvolve")
    valid = np.ones(d.shape[1:], bool)
    if mask is not None:
        m = np.asarray(mask)
        if m.shape != d.shape[1:] or m.dtype != bool:
            raise ValueError(
                f"mask must be a boolean array of shape {d.shape[1:]}, got {m.dtype} {m.shape}"
            )
        valid &= m
    if saturation is not None:
        if not saturation > 0:
            raise ValueError(f"saturation must be > 0 photo-electrons, got {saturation}")
        valid &= np.all(d < saturation, axis=0)
    if not valid.any():
        raise ValueError("mask and saturation leave no pixel to use")
    if not valid.all():
        notes.append(
            f"{int((~valid).sum())} masked pixels (saturated or excluded) left out of the likelihood"
        )
        d = d * valid
    H, W = d.shape[1:]
    if psf_radius is None:
        psf_radius = min(H, W) / 4
    if pad is None:
        pad = int(np.ceil(psf_radius)) if boundary == "reeves" else 0
    ops = _Ops((H, W), pad, boundary, valid)
    Hp, Wp = ops.shape
    yy, xx = np.mgrid[0:Hp, 0:Wp]
    support = np.hypot(yy - Hp // 2, xx - Wp // 2) <= psf_radius

    # PSFs
    nps = 1 if shared_psf else K
    if psf0 is not None:
        h = np.asarray(psf0, float)
        h = (
            np.broadcast_to(h if h.ndim == 3 else h[None], (nps, Hp, Wp)).copy()
            if h.shape[-2:] == (Hp, Wp)
            else None
        )
        if h is None:
            raise ValueError(f"psf0 must be given on the object grid {(Hp, Wp)} (data + 2 pad)")
    elif pupil is not None:
        from scatterlab.imaging import psf as make_psf

        h = np.broadcast_to(resample_psf(make_psf(pupil, pad=2), (Hp, Wp)), (nps, Hp, Wp)).copy()
    else:
        g = np.exp(-((yy - Hp // 2) ** 2 + (xx - Wp // 2) ** 2) / (2 * (psf_radius / 4) ** 2))
        h = np.broadcast_to(g, (nps, Hp, Wp)).copy()
    h = np.where(support, np.clip(h, 0, None), 0.0)
    h /= h.sum(axis=(-2, -1), keepdims=True)
    pupil_phase = np.zeros((nps,) + np.shape(pupil)) if psf_mode == "pupil" else None

    # initial object: least-squares Stokes images of the data (the text's start, S0 = 1 and P = 1/2, via
    # s0_start / dolp_start)
    from scatterlab.imaging import stokes_from_channels

    S = stokes_from_channels(d, th)
    s0 = np.clip(S[0], 1e-3 * max(S[0][valid].mean(), 1e-12), None)
    # EM barely moves a DOLP near 0 (the mixture weight's update is slow at the boundary), so the start must
    # be unbiased there: with the AOP known, the signed projection (S1 cos 2a + S2 sin 2a)/S0, which has no
    # Rician bias (a 0.02 floor left a metal of DOLP 0.005 at 0.012 after 100 iterations); floored at 1e-6
    # (P = 0 would stay 0)
    if estimate_aop:
        P_ls = np.hypot(S[1], S[2]) / np.maximum(S[0], 1e-12)
    else:
        a2 = 2 * np.broadcast_to(np.asarray(aop, float), S[0].shape)
        P_ls = (S[1] * np.cos(a2) + S[2] * np.sin(a2)) / np.maximum(S[0], 1e-12)
    P0 = np.clip(P_ls, 1e-6, 0.98)
    s0 = np.where(valid, s0, S[0][valid].mean())  # masked pixels start from the mean level
    P0 = np.where(valid, P0, 0.5)
    if s0_start is not None:
        s0 = np.broadcast_to(np.asarray(s0_start, float), (H, W)).copy()
    if dolp_start is not None:
        P0 = np.broadcast_to(np.clip(np.asarray(dolp_start, float), 0, 1), (H, W)).copy()
    s0 = _pad_edge(s0, ops.pad)
    P = _pad_edge(P0, ops.pad)
    alpha = np.broadcast_to(np.asarray(aop, float), (H, W)).copy()
    if estimate_aop:
        alpha = 0.5 * np.arctan2(S[2], S[1])
    alpha = _pad_edge(alpha, ops.pad)

    D = d.sum(axis=(-2, -1))
    classes = None
    priors = tuple(priors) if priors else ()
    loglik, objective = [], []
    # one PSF and a known AOP (Ch. VII's specular case): the channel objects are linear in the Stokes images,
    # o_n = (S0 + S1 cos 2theta_n + S2 sin 2theta_n) / 2, so 2 (3 if sin 2alpha != 0) transforms replace K
    # in every convolution, and the PSF update reuses their spectra
    model = (_StokesBasis if shared_psf and not estimate_aop else _PerChannel)(ops, th, alpha)

    def likelihood(i):
        # d ln i - i; where d = 0 the clipped log is finite, so the product is exactly 0
        predicted = float(np.sum(i * valid)) if ops.masked else float(i.sum())
        return float(np.vdot(d, np.log(np.maximum(i, 1e-300)))) - predicted

    state = model.forward(h, s0, P)
    loglik.append(likelihood(state.i))
    objective.append(loglik[-1])
    w = ops.window_share(state.Hf)
    it = 0
    for it in range(1, iterations + 1):
        r = np.divide(d, state.i, out=np.zeros_like(d), where=(state.i > 0) & valid)
        T, Qp, Pp, R = model.estep(state, r, s0, P)
        if update_object:
            # S0 = T / sum_n w_n [(1 - P)/2 + P cos^2(alpha - theta_n)], w_n = h_n^T * 1_window the share of an
            # object pixel's light that reaches the measured window (Reeves; 1 for periodic boundaries)
            s0_new = T / model.s0_denominator(w, P)
            P_new = dolp_update(T, Qp)
            if priors:
                # the priors classify the measured pixels; the Reeves border (never observed) keeps the ML update
                Tw, Qw = ops.crop(T), ops.crop(Qp)
                cands = np.stack([dolp_update(Tw, Qw, pr, prior_weight) for pr in priors])
                objs = np.stack(
                    [
                        map_objective(cands[k], Tw, Qw, pr, prior_weight)
                        for k, pr in enumerate(priors)
                    ]
                )
                classes = np.argmax(objs, axis=0)
                P_new[ops.win] = np.take_along_axis(cands, classes[None], 0)[0]
            if estimate_aop:
                model.set_aop(_aop_mstep(Pp, th))  # weights of ln cos^2(alpha - theta_n)
        else:
            s0_new, P_new = s0, P
        # PSF update (Eq. 194): h <- h (r * o) / D, per channel or summed for a shared PSF
        if psf_mode != "fixed":
            num = sfft.fftshift(model.psf_correlation(state, R), axes=(-2, -1))
            if shared_psf:
                h_em = (h[0] * num.sum(0) / D.sum())[None]
            else:
                h_em = h * num / D[:, None, None]
            h_em = np.where(support, np.clip(h_em, 0, None), 0.0)
            h_em /= np.maximum(h_em.sum(axis=(-2, -1), keepdims=True), 1e-300)
            if psf_mode == "pupil":
                h_new, pupil_phase_new = gerchberg_saxton(
                    h_em, pupil, pupil_phase, (Hp, Wp), gs_steps
                )
                h_new = np.where(support, h_new, 0.0)
                h_new /= h_new.sum(axis=(-2, -1), keepdims=True)
            else:
                h_new = h_em
        else:
            h_new = h
        new_state = model.forward(h_new, s0_new, P_new, Hf=state.Hf if h_new is h else None)
        L_new = likelihood(new_state.i)
        if psf_mode == "pupil" and L_new < loglik[-1]:
            # Schulz: the pupil-projected PSF step is kept only if the objective increased
            h_new = h
            new_state = model.forward(h, s0_new, P_new, Hf=state.Hf)
            L_new = likelihood(new_state.i)
        elif psf_mode == "pupil":
            pupil_phase = pupil_phase_new
        if h_new is not h:
            w = ops.window_share(new_state.Hf)
        h, s0, P, state = h_new, s0_new, P_new, new_state
        loglik.append(L_new)
        obj = L_new
        if priors:
            obj += float(
                np.sum(
                    [
                        np.sum(np.where(classes == k, prior_weight * pr.log_pdf(ops.crop(P)), 0.0))
                        for k, pr in enumerate(priors)
                    ]
                )
            )
        objective.append(obj)
        if tol is not None and abs(loglik[-1] - loglik[-2]) <= tol * abs(loglik[-2]):
            break
    alpha = model.alpha
    aop_out = ops.crop(alpha) if np.ndim(alpha) else np.full((H, W), float(alpha))
    return DeconvolutionResult(
        s0=ops.crop(s0),
        dolp=np.clip(ops.crop(P), 0, 1),
        aop=aop_out,
        psfs=h,
        classes=classes,
        priors=priors,
        loglik=np.array(loglik),
        objective=np.array(objective),
        iterations=it,
        notes=notes,
        seconds=time.perf_counter() - t0,
    )


@dataclass
class _State:
    """Predicted channel images i (K, H, W), the OTF(s) and the spectra the PSF update reuses."""

    i: np.ndarray
    Hf: np.ndarray
    spectra: np.ndarray


class _StokesBasis:
    """Shared PSF, known AOP: o_n = sum_j A_nj B_j with B = (S0, P S0 cos 2alpha, P S0 sin 2alpha) and
    A_n = (1, cos 2theta_n, sin 2theta_n) / 2 (the third term dropped when sin 2alpha = 0 everywhere)."""

    def __init__(self, ops, th, alpha):
        self.ops, self.alpha = ops, alpha
        c2a, s2a = np.cos(2 * alpha), np.sin(2 * alpha)
        self.J = 3 if np.any(np.abs(s2a) > 1e-12) else 2
        self.trig = np.stack([c2a, s2a])[: self.J - 1]  # (J - 1, Hp, Wp)
        self.A = (
            0.5 * np.stack([np.ones_like(th), np.cos(2 * th), np.sin(2 * th)], axis=1)[:, : self.J]
        )  # (K, J)
        self.sum_trig = (2 * self.A[:, 1:]).sum(0)  # sum_n (cos 2theta_n, sin 2theta_n)

    def forward(self, h, s0, P, Hf=None):
        Hf = self.ops.otf(h[0]) if Hf is None else Hf
        B = np.concatenate([s0[None], (P * s0)[None] * self.trig])  # (J, Hp, Wp)
        Bf = self.ops.rfft(B)
        blurred = self.ops.crop(self.ops.irfft(Bf * Hf))
        return _State(np.tensordot(self.A, blurred, axes=1), Hf, Bf)

    def estep(self, state, r, s0, P):
        R = self.ops.rfft(
            self.ops.extend(np.tensordot(2 * self.A.T, r, axes=1))
        )  # spectra of combined ratios
        C = self.ops.irfft(R * np.conj(state.Hf))  # their back-projections (J, Hp, Wp)
        pol = C[0] + np.sum(self.trig * C[1:], axis=0)  # sum_n 2 cos^2(alpha - theta_n) c_n
        T = 0.5 * s0 * ((1 - P) * C[0] + P * pol)
        Qp = 0.5 * P * s0 * pol
        return T, Qp, None, R

    def s0_denominator(self, w, P):
        K = self.A.shape[0]
        return w * (0.5 * K + 0.5 * P * np.tensordot(self.sum_trig, self.trig, axes=1))

    def psf_correlation(self, state, R):
        return self.ops.irfft(0.5 * np.sum(R * np.conj(state.spectra), axis=0))[None]


class _PerChannel:
    """One PSF per channel, or an AOP to estimate: the K channel objects are convolved one by one."""

    def __init__(self, ops, th, alpha):
        self.ops, self.th = ops, th
        self.set_aop(alpha)

    def set_aop(self, alpha):
        self.alpha = alpha
        self.cos2 = np.cos(alpha[None] - self.th[:, None, None]) ** 2  # (K, Hp, Wp)

    def forward(self, h, s0, P, Hf=None):
        Hf = self.ops.otf(h) if Hf is None else Hf
        o = 0.5 * (1 - P) * s0 + P * s0 * self.cos2  # (K, Hp, Wp)
        Of = self.ops.rfft(o)
        return _State(self.ops.crop(self.ops.irfft(Of * Hf)), Hf, Of)

    def estep(self, state, r, s0, P):
        R = self.ops.rfft(self.ops.extend(r))
        c = self.ops.irfft(R * np.conj(state.Hf))  # back-projection (K, Hp, Wp)
        Pp = P * s0 * self.cos2 * c  # sum_y psi_pn
        T = (0.5 * (1 - P) * s0 * c + Pp).sum(0)
        return T, Pp.sum(0), Pp, R

    def s0_denominator(self, w, P):
        return np.sum(w * (0.5 * (1 - P) + P * self.cos2), axis=0)

    def psf_correlation(self, state, R):
        return self.ops.irfft(R * np.conj(state.spectra))  # r_n correlated with o_n


def _aop_mstep(B, th):
    """alpha maximizing sum_n B_n ln cos^2(alpha - theta_n) per pixel: 1-deg grid, parabolic refinement."""
    grid = np.radians(np.arange(-90, 90, 1.0))
    vals = []
    for g in grid:
        vals.append(np.sum(B * np.log(np.maximum(np.cos(g - th[:, None, None]) ** 2, 1e-300)), 0))
    vals = np.stack(vals)
    k = np.argmax(vals, 0)
    km, kp = (k - 1) % grid.size, (k + 1) % grid.size
    f0 = np.take_along_axis(vals, k[None], 0)[0]
    fm = np.take_along_axis(vals, km[None], 0)[0]
    fp = np.take_along_axis(vals, kp[None], 0)[0]
    den = fm - 2 * f0 + fp
    shift = np.where(den < 0, 0.5 * (fm - fp) / np.where(den < 0, den, -1.0), 0.0)
    return grid[k] + np.clip(shift, -0.5, 0.5) * np.radians(1.0)


def object_grid(data_shape, psf_radius=None, boundary: str = "reeves", pad=None) -> tuple:
    """Shape (Hp, Wp) of the object grid :func:`blind_deconvolve` uses for ``data_shape`` (H, W)."""
    H, W = data_shape
    if psf_radius is None:
        psf_radius = min(H, W) / 4
    if pad is None:
        pad = int(np.ceil(psf_radius)) if boundary == "reeves" else 0
    return (H + 2 * pad, W + 2 * pad) if boundary == "reeves" else (H, W)
