r"""A few-material object estimated jointly with the pupil phase: the prior that lets the likelihood find the PSF.

A free object (S0 and DOLP at every pixel) lets the Poisson likelihood of one blurred frame prefer a wrong PSF
(``docs/characterization_accuracy.md``: even converged, the exact-likelihood PSF beats the true one). A
painted plate, though, is made of a few materials, each uniform at one geometry. With the object written as

.. math:: S_0(x) = \sum_m a_m\,\chi_m(x), \qquad \mathcal P S_0(x) = \sum_m a_m p_m\,\chi_m(x),
          \qquad \chi_m = e^{z_m} / \textstyle\sum_k e^{z_k}

(M materials of irradiance :math:`a_m` [counts] and signed DOLP :math:`p_m`, a soft layout :math:`\chi_m`
that sums to 1 at every pixel and can place an edge between pixels), the object varies only by mixing the
M materials, never in S0 and DOLP independently (two materials: one degree of freedom per pixel instead of
two), so it cannot fit the noise within a material, and the data pin the PSF: the layout and the
materials are fitted by L-BFGS on the exact Poisson log-likelihood (Eq. 188 with the object above;
analytic gradient through the softmax), the pupil phase by L-BFGS with the object held
(:class:`~scatterlab.deconvolution.psf_update.PupilPhasePSF`, Schulz's parameterisation, Eq. 186), in
alternation. Each step is a descent step on the same objective, so the log-likelihood never decreases.

Start: a blind EM result (:func:`~scatterlab.deconvolution.blind_deconvolve`): its PSF, and a layout from
k-means on its (log S0, DOLP) (:func:`scipy.cluster.vq.kmeans2`). The PSF found is then given to a known-PSF
restoration (``psf_mode="fixed"``) for the final, free object.

Measured on the default scene at 50 deg (seed 1; three materials, 20 rounds, then 600 known-PSF iterations
and the priors' classification), against the shipped Gerchberg-Saxton estimate, aluminium D/r0 7.9 / 12.9,
steel 7.9 / 12.9: PSF distance from the truth (L1 after the best integer shift, 2 = disjoint) 0.90 / 1.04 /
0.69 / 1.04 instead of 1.16 / 1.16 / 1.13 / 1.20; DOLP RMSE 0.235 / 0.313 / 0.156 / 0.253 instead of 0.236 /
0.330 / 0.179 / 0.269; classification error against the no-turbulence classification 0.091 / 0.131 / 0.028
/ 0.082 instead of 0.083 / 0.149 / 0.043 / 0.102 (``docs/characterization_accuracy.md``).

Scope: one frame, one PSF shared by the channels, the AOP fixed by the geometry (``aop``, default 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LayoutResult", "layout_psf"]


@dataclass
class LayoutResult:
    """The PSF found with a few-material object, and that object.

    Attributes
    ----------
    psf : ndarray, shape (Hp, Wp)
        Centred, unit-sum PSF on the object grid of the start (for ``blind_deconvolve(psf0=...)``).
    pupil_phase : ndarray, shape (n, n)
        Its pupil phase [rad].
    layout : ndarray, shape (M, H, W)
        Share of each material at each data pixel (sums to 1).
    s0 : ndarray, shape (M,)
        Each material's S0 [counts per pixel, both polarizations].
    dolp : ndarray, shape (M,)
        Each material's signed DOLP (S1/S0 in the frame of the AOP).

        A dim material's values are not estimates of that material: the soft layout can mix a little of
        a bright material into every pixel of a dim one and raise the dim one's DOLP to make up for it,
        at no cost in likelihood (with the true PSF of the default scene: paint DOLP 1.00 and S0
        12 190 counts for 0.876 and 13 820). Use the PSF, and restore the object with it held fixed.
    loglik : ndarray, shape (rounds + 1,)
        Poisson log-likelihood after each round (the first: the start PSF with the fitted layout's start).
    """

    psf: np.ndarray
    pupil_phase: np.ndarray
    layout: np.ndarray
    s0: np.ndarray
    dolp: np.ndarray
    loglik: np.ndarray


class _Objective:
    """Negative Poisson log-likelihood (scaled by the counts) of the few-material object through one OTF, and
    its gradient, for the packed parameters ``x = (z (M, Hp, Wp), ln a (M,), p (M,))`` (p bounded to [-1, 1]
    by the optimizer: a tanh map would freeze a material that reaches |p| = 1, its gradient vanishing)."""

    def __init__(self, problem, M):
        self.model, self.ops = problem.model, problem.ops
        self.d, self.valid = problem.d, problem.valid
        self.M = M
        self.shape = self.ops.shape
        self.n = M * self.shape[0] * self.shape[1]
        self.scale = float(self.d.sum())

    def unpack(self, x):
        z = x[: self.n].reshape((self.M,) + self.shape)
        e = np.exp(z - z.max(axis=0))
        chi = e / e.sum(axis=0)
        return chi, np.exp(x[self.n : self.n + self.M]), x[self.n + self.M :]

    def stokes(self, x):
        """(S0, P S0) images ``(Hp, Wp)`` of the packed parameters."""
        chi, a, p = self.unpack(x)
        return np.tensordot(a, chi, axes=1), np.tensordot(a * p, chi, axes=1)

    def __call__(self, x, Hf):
        model = self.model
        chi, a, p = self.unpack(x)
        Bf = model.stokes_spectra(np.tensordot(a, chi, axes=1), np.tensordot(a * p, chi, axes=1))
        L, R = model.frame_residual(0, Hf, Bf, self.d, self.valid)
        gB = self.ops.irfft(R * np.conj(Hf))  # dL / d(Stokes images) (J, Hp, Wp)
        g_s0, g_ps0 = gB[0], np.sum(model.trig * gB[1:], axis=0)
        g_chi = a[:, None, None] * (g_s0 + p[:, None, None] * g_ps0)
        g_z = chi * (g_chi - np.sum(chi * g_chi, axis=0))
        G_s0 = np.tensordot(chi, g_s0, axes=((1, 2), (0, 1)))
        G_ps0 = np.tensordot(chi, g_ps0, axes=((1, 2), (0, 1)))
        g_lna = a * (G_s0 + p * G_ps0)
        g = np.concatenate([g_z.ravel(), g_lna, a * G_ps0])
        return -L / self.scale, -g / self.scale


def _start_layout(s0, dolp, pad, M, rng):
    """Logits ``(M, Hp, Wp)`` and material values from k-means on (log S0, 3 DOLP) of the start object."""
    from scipy.cluster.vq import kmeans2

    s0e = np.pad(np.asarray(s0, float), pad, mode="edge")
    Pe = np.pad(np.nan_to_num(np.asarray(dolp, float)), pad, mode="edge")
    floor = 1e-3 * max(float(s0e.mean()), 1e-300)
    feat = np.stack([np.log(np.maximum(s0e, floor)).ravel(), 3 * Pe.ravel()], axis=1)
    _, lab = kmeans2(feat, M, minit="++", seed=rng)
    lab = lab.reshape(s0e.shape)
    z = np.stack([np.where(lab == m, 2.0, -2.0) for m in range(M)])
    a = np.array(
        [max(float(s0e[lab == m].mean()) if np.any(lab == m) else floor, floor) for m in range(M)]
    )
    p = np.array([float(Pe[lab == m].mean()) if np.any(lab == m) else 0.0 for m in range(M)])
    return z, a, np.clip(p, -0.99, 0.99)


def layout_psf(
    data,
    angles,
    start,
    *,
    pupil,
    psf_radius,
    pad,
    materials: int = 3,
    rounds: int = 20,
    object_steps: int = 100,
    phase_steps: int = 30,
    aop: float = 0.0,
    phase0=None,
    rng=None,
) -> LayoutResult:
    """The PSF of one frame, found with a few-material object (module docstring).

    Parameters
    ----------
    data : array (K, H, W) [photo-electrons]
        Channel images of one frame.
    angles : array (K,) [rad]
        Polarizer angles.
    start : DeconvolutionResult
        A blind EM result on the same data with the same ``psf_radius`` and ``pad`` (its PSF and object
        start the search).
    pupil : array (n, n)
        Aperture amplitude.
    psf_radius : float [pixels]; pad : int [pixels]
        The object grid and PSF support of ``start``.
    materials : int
        M >= 2: the number of uniform materials (a painted plate: paint, metal, and one for what neither
        explains, e.g. a brighter scratch).
    rounds : int
        Alternations of the object fit and the phase fit (>= 1): the accuracy knob
        (``studies/performance/perf_layout_psf.py``).
    object_steps, phase_steps : int
        L-BFGS iterations per round for the object and for the pupil phase (>= 1).
    aop : float [rad]
        The AOP the geometry fixes (0 for specular observation of unpolarized light).
    phase0 : array (n, n) [rad], optional
        Start pupil phase; None: the Gerchberg-Saxton fit of the start's PSF.
    rng : None, int or numpy.random.Generator
        Seeds the k-means start of the layout.

    Returns
    -------
    LayoutResult
    """
    from scipy.optimize import minimize

    from scatterlab.deconvolution.em import _resolve_options, _setup

    for name, value, lo in (
        ("materials", materials, 2),
        ("rounds", rounds, 1),
        ("object_steps", object_steps, 1),
        ("phase_steps", phase_steps, 1),
    ):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise ValueError(f"{name} must be an integer >= {lo}, got {value!r}")
    psfs = np.asarray(start.psfs)
    if psfs.ndim != 3 or psfs.shape[0] != 1:
        raise ValueError(
            f"start must be a single-frame blind EM result with one shared PSF, got PSFs {psfs.shape}"
        )
    opts = _resolve_options(
        None, dict(psf_mode="phase", psf_radius=psf_radius, pad=pad, aop=float(aop))
    )
    problem, state = _setup(data, angles, psfs[0], pupil, opts)
    if problem.ops.shape != psfs.shape[1:]:
        raise ValueError(
            f"start's PSFs {psfs.shape[1:]} are not on the object grid {problem.ops.shape} of "
            "psf_radius and pad: use the start's settings"
        )
    f = _Objective(problem, materials)
    pp, inside = problem.phase_psf, problem.phase_psf.inside
    z, a, p = _start_layout(
        start.s0, start.dolp, problem.ops.pad, materials, np.random.default_rng(rng)
    )
    x = np.concatenate([z.ravel(), np.log(a), p])
    bounds = [(None, None)] * (f.n + materials) + [(-1.0, 1.0)] * materials
    phase = state.pupil_phase[0].copy() if phase0 is None else np.array(phase0, float)
    if phase.shape != inside.shape:
        raise ValueError(f"phase0 must have the pupil's shape {inside.shape}, got {phase.shape}")
    h = pp.psf(phase)
    loglik = [-f(x, problem.ops.otf(h))[0] * f.scale]
    for _ in range(rounds):
        x = minimize(
            f,
            x,
            args=(problem.ops.otf(h),),
            jac=True,
            method="L-BFGS-B",
            bounds=bounds,
            options={"maxiter": object_steps, "gtol": 0.0, "ftol": 0.0},
        ).x
        Bf = problem.model.stokes_spectra(*f.stokes(x))

        def phase_objective(y, Bf=Bf):
            ph = np.zeros(inside.shape)
            ph[inside] = y
            L, G = problem.model.frame_loglik(
                0, problem.ops.otf(pp.psf(ph)), Bf, problem.d, problem.valid
            )
            return -L / f.scale, -pp.gradient(ph, G)[inside] / f.scale

        res = minimize(
            phase_objective,
            phase[inside],
            jac=True,
            method="L-BFGS-B",
            options={"maxiter": phase_steps, "gtol": 0.0, "ftol": 0.0},
        )
        phase = np.zeros(inside.shape)
        phase[inside] = res.x
        h = pp.psf(phase)
        loglik.append(-float(res.fun) * f.scale)
    chi, a, p = f.unpack(x)
    return LayoutResult(h, phase, problem.ops.crop(chi), a, p, np.array(loglik))
