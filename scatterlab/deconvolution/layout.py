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
alternation. Each step is a descent step on the same objective, so without ``edge_band`` the log-likelihood
never decreases.

Start: a blind EM result (:func:`~scatterlab.deconvolution.blind_deconvolve`): its PSF, and a layout from
k-means on its (log S0, DOLP) (:func:`scipy.cluster.vq.kmeans2`). The PSF found is then given to a known-PSF
restoration (``psf_mode="fixed"``) for the final, free object.

Measured on the default scene at 50 deg (seed 1; three materials, 20 rounds, then 600 known-PSF iterations
and the priors' classification), against the shipped Gerchberg-Saxton estimate, aluminium D/r0 7.9 / 12.9,
steel 7.9 / 12.9: PSF distance from the truth (L1 after the best integer shift, 2 = disjoint) 0.90 / 1.04 /
0.69 / 1.04 instead of 1.16 / 1.16 / 1.13 / 1.20; DOLP RMSE 0.235 / 0.313 / 0.156 / 0.253 instead of 0.236 /
0.330 / 0.179 / 0.269; classification error against the no-turbulence classification 0.091 / 0.131 / 0.028
/ 0.082 instead of 0.083 / 0.149 / 0.043 / 0.102 (``docs/characterization_accuracy.md``).

**Several exposures** (``frames`` = F > 1, Schulz's multi-frame data: one object through F independent
screens) share the layout and the materials; each gets its own pupil phase. **Pure interiors**
(``edge_band`` = b): the soft layout cannot tell a dim material's own DOLP from a little of a bright one
mixed into every pixel (:class:`LayoutResult`), so every pixel farther than b pixels from an edge of the
current hard layout (the argmax of the shares) is held pure, and only the band along the edges mixes. The
band follows the edges: it is redrawn after each round's object fit.

Measured on four exposures of the default scene's aluminium plate at 50 deg, D/r0 7.9 (each through its own
screen with the full photon budget; two materials, the whole field as PSF support, 30 rounds from the
multi-frame blind EM, whose PSFs are 1.10-1.17 from the truth in L1 after the best shift; classification of
the first exposure restored with its PSF for 600 known-PSF iterations, against the no-turbulence
classification; with the true PSF 0.033, with the blind EM's 0.054):

* soft layout: PSFs 0.78-0.87, classification 0.030; the paint's fitted DOLP 1.00 (truth 0.876);
* pure interiors, ``edge_band`` 2: PSFs 1.00-1.02, classification 0.033; the paint 13 550 counts and DOLP
  0.891 (truth 13 820 and 0.876); ``edge_band`` 1 (40 rounds): 0.92-0.98, 0.036, DOLP 0.913.

So the soft layout finds the better PSFs and pure interiors the material values
(``studies/performance/perf_layout_frames.py`` measures both against the rounds and the time).

Scope: one PSF per frame shared by its channels, the AOP fixed by the geometry (``aop``, default 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterlab._checks import as_count, as_rng

__all__ = ["LayoutResult", "edge_band_mask", "layout_psf"]


@dataclass
class LayoutResult:
    """The PSF(s) found with a few-material object, and that object.

    Attributes
    ----------
    psf : ndarray, shape (Hp, Wp), or (F, Hp, Wp) for F > 1 frames
        Centred, unit-sum PSF(s) on the object grid of ``psf_radius`` and ``pad`` (for
        ``blind_deconvolve(psf0=..., psf_mode="fixed")``).
    pupil_phase : ndarray, shape (n, n), or (F, n, n)
        Their pupil phases [rad].
    layout : ndarray, shape (M, H, W)
        Share of each material at each data pixel (sums to 1).
    s0 : ndarray, shape (M,)
        Each material's S0 [counts per pixel and frame, both polarizations].
    dolp : ndarray, shape (M,)
        Each material's signed DOLP (S1/S0 in the frame of the AOP).

        Without ``edge_band``, a dim material's values are not estimates of that material: the soft layout
        can mix a little of a bright material into every pixel of a dim one and raise the dim one's DOLP to
        make up for it, at no cost in likelihood (with the true PSF of the default scene: paint DOLP 1.00
        and S0 12 190 counts for 0.876 and 13 820). Pure interiors (``edge_band``) remove that freedom.
    loglik : ndarray, shape (rounds + 1,)
        Poisson log-likelihood (all frames) after each round (the first: the start PSFs with the start
        layout's fitted object). With ``edge_band`` the redrawing of the band between rounds can lower it.
    """

    psf: np.ndarray
    pupil_phase: np.ndarray
    layout: np.ndarray
    s0: np.ndarray
    dolp: np.ndarray
    loglik: np.ndarray


# logit held by a pure pixel: the other materials' shares are exp(-2 PIN) ~ 4e-18 each
_PIN = 20.0


class _Objective:
    """Negative Poisson log-likelihood (scaled by the counts) of the few-material object seen by every frame
    through its own OTF, and its gradient, for the packed parameters ``x = (z (M, Hp, Wp), ln a (M,), p (M,))``
    (p bounded to [-1, 1] by the optimizer: a tanh map would freeze a material that reaches |p| = 1, its
    gradient vanishing)."""

    def __init__(self, problem, M):
        self.model, self.ops = problem.model, problem.ops
        self.valid = problem.valid
        F = int(problem.group.max()) + 1
        self.d = [problem.d[problem.group == f] for f in range(F)]
        self.M = M
        self.shape = self.ops.shape
        self.n = M * self.shape[0] * self.shape[1]
        self.scale = float(problem.d.sum())

    def unpack(self, x):
        z = x[: self.n].reshape((self.M,) + self.shape)
        e = np.exp(z - z.max(axis=0))
        chi = e / e.sum(axis=0)
        return chi, np.exp(x[self.n : self.n + self.M]), x[self.n + self.M :]

    def stokes(self, x):
        """(S0, P S0) images ``(Hp, Wp)`` of the packed parameters."""
        chi, a, p = self.unpack(x)
        return np.tensordot(a, chi, axes=1), np.tensordot(a * p, chi, axes=1)

    def __call__(self, x, Hfs):
        model = self.model
        chi, a, p = self.unpack(x)
        Bf = model.stokes_spectra(np.tensordot(a, chi, axes=1), np.tensordot(a * p, chi, axes=1))
        L, RH = 0.0, 0.0
        for f, Hf in enumerate(Hfs):
            L_f, R = model.frame_residual(f, Hf, Bf, self.d[f], self.valid)
            L, RH = L + L_f, RH + R * np.conj(Hf)
        gB = self.ops.irfft(RH)  # dL / d(Stokes images) (J, Hp, Wp), summed over the frames
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


def edge_band_mask(labels, band: int) -> np.ndarray:
    """Pixels within ``band`` pixels (4-connected steps) of a pixel of another label.

    Parameters
    ----------
    labels : ndarray of int, shape (H, W)
        Hard layout.
    band : int
        Half-width of the band [pixels] (0: no pixel is in the band).

    Returns
    -------
    ndarray of bool, shape (H, W)
    """
    from scipy.ndimage import binary_dilation

    labels = np.asarray(labels)
    if band <= 0:
        return np.zeros(labels.shape, bool)
    covered = sum(
        binary_dilation(labels == m, iterations=band).astype(int) for m in np.unique(labels)
    )
    return covered >= 2


def _pin(z, band):
    """Logits with every pixel outside the edge band of their argmax held pure, and the L-BFGS-B bounds
    (lower, upper arrays) that hold them (lower = upper); band pixels keep their logits and are free."""
    M = z.shape[0]
    lab = np.argmax(z, axis=0)
    free = edge_band_mask(lab, band)
    pure = np.where(np.arange(M)[:, None, None] == lab, _PIN, -_PIN)
    z = np.where(free, z, pure)
    return z, (np.where(free, -np.inf, z).ravel(), np.where(free, np.inf, z).ravel())


def _check_count(name, value, lo):
    as_count(value, name, lo)


def layout_psf(
    data,
    angles,
    start,
    *,
    pupil,
    psf_radius,
    pad,
    frames: int = 1,
    materials: int = 3,
    edge_band: int | None = None,
    rounds: int = 20,
    object_steps: int = 100,
    phase_steps: int = 30,
    aop: float = 0.0,
    phase0=None,
    rng=None,
) -> LayoutResult:
    """The PSF of each frame, found with a few-material object (module docstring).

    Parameters
    ----------
    data : array (K, H, W) [photo-electrons]
        Channel images: ``frames`` consecutive groups of K / frames polarizer channels (as
        :func:`~scatterlab.deconvolution.blind_deconvolve` takes them).
    angles : array (K,) [rad]
        Polarizer angles.
    start : DeconvolutionResult
        A blind EM result on the same data with the same ``frames`` and one PSF per frame (its PSFs and
        object start the search). Its PSFs may be on another object grid (e.g. a support of radius H/4
        when the search is to use the whole field): they are centre-cropped or zero-padded onto the grid
        of ``psf_radius`` and ``pad``.
    pupil : array (n, n)
        Aperture amplitude.
    psf_radius : float [pixels]; pad : int [pixels]
        PSF support and the object grid's margin (Reeves boundaries). The whole field (radius
        sqrt(2) H / 2, pad H / 2) lets the PSF carry the turbulent halo, which a support of H / 4 cuts.
    frames : int
        F >= 1 exposures of one object, each through its own PSF (module docstring).
    materials : int
        M >= 2: the number of uniform materials (a painted plate: paint, metal, and for a soft layout one
        for what neither explains, e.g. a brighter scratch).
    edge_band : int or None
        None: a soft layout at every pixel. b >= 0: pure interiors, only pixels within b pixels of an edge
        mix (1 for a plate whose edges fall between pixels).
    rounds : int
        Alternations of the object fit and the phase fits (>= 1): the accuracy knob
        (``studies/performance/perf_layout_psf.py``).
    object_steps, phase_steps : int
        L-BFGS iterations per round for the object and for each frame's pupil phase (>= 1).
    aop : float [rad]
        The AOP the geometry fixes (0 for specular observation of unpolarized light).
    phase0 : array (n, n) or (F, n, n) [rad], optional
        Start pupil phase(s); None: the Gerchberg-Saxton fit of the start's PSFs.
    rng : None, int or numpy.random.Generator
        Seeds the k-means start of the layout.

    Returns
    -------
    LayoutResult

    Raises
    ------
    ValueError
        For counts out of range, a start without one PSF per frame, or a ``phase0`` of the wrong shape.
    """
    from scipy.optimize import Bounds, minimize

    from scatterlab.deconvolution.em import _resolve_options, _setup
    from scatterlab.deconvolution.psf_update import resample_psf

    for name, value, lo in (
        ("frames", frames, 1),
        ("materials", materials, 2),
        ("rounds", rounds, 1),
        ("object_steps", object_steps, 1),
        ("phase_steps", phase_steps, 1),
    ):
        _check_count(name, value, lo)
    if edge_band is not None:
        _check_count("edge_band", edge_band, 0)
    psfs = np.asarray(start.psfs)
    if psfs.ndim != 3 or psfs.shape[0] != frames:
        raise ValueError(
            f"start must be a blind EM result with one PSF per frame (frames={frames}), got PSFs "
            f"{psfs.shape}"
        )
    opts = _resolve_options(
        None,
        dict(psf_mode="phase", psf_radius=psf_radius, pad=pad, aop=float(aop), frames=frames),
    )
    shape = (np.shape(data)[-2] + 2 * int(pad), np.shape(data)[-1] + 2 * int(pad))
    psfs = np.stack([resample_psf(np.clip(h, 0.0, None), shape) for h in psfs])
    problem, state = _setup(data, angles, psfs, pupil, opts)
    f = _Objective(problem, materials)
    pp, inside = problem.phase_psf, problem.phase_psf.inside
    z, a, p = _start_layout(start.s0, start.dolp, problem.ops.pad, materials, as_rng(rng))
    # bounds as arrays (scipy.optimize.Bounds): a list of 10^5 (lo, hi) pairs cost scipy a tenth of the
    # refinement's time to convert at every call
    free_bounds = (np.full(f.n, -np.inf), np.full(f.n, np.inf))
    if edge_band is not None:
        z, free_bounds = _pin(z, edge_band)
    x = np.concatenate([z.ravel(), np.log(a), p])
    # ln a held within 1e-9 .. 1e3 of the brightest pixel's S0 scale: an L-BFGS line search may otherwise
    # try a step whose exp overflows (seen on a re-simulated scene)
    top = max(float(problem.d.max()), 1.0) * 2.0
    ln_a = (np.log(1e-9 * top), np.log(1e3 * top))
    value_lo = np.r_[np.full(materials, ln_a[0]), np.full(materials, -1.0)]
    value_hi = np.r_[np.full(materials, ln_a[1]), np.full(materials, 1.0)]
    x[f.n : f.n + materials] = np.clip(x[f.n : f.n + materials], *ln_a)
    if phase0 is None:
        phases = state.pupil_phase.copy()
    else:
        phases = np.array(phase0, float)
        if phases.shape not in (inside.shape, (frames,) + inside.shape):
            raise ValueError(
                f"phase0 must have the pupil's shape {inside.shape} or {(frames,) + inside.shape}, "
                f"got {phases.shape}"
            )
        phases = np.broadcast_to(phases, (frames,) + inside.shape).copy()
    hs = [pp.psf(ph) for ph in phases]
    loglik = [-f(x, [problem.ops.otf(h) for h in hs])[0] * f.scale]
    for _ in range(rounds):
        x = minimize(
            f,
            x,
            args=([problem.ops.otf(h) for h in hs],),
            jac=True,
            method="L-BFGS-B",
            bounds=Bounds(np.r_[free_bounds[0], value_lo], np.r_[free_bounds[1], value_hi]),
            options={"maxiter": object_steps, "gtol": 0.0, "ftol": 0.0},
        ).x
        if edge_band is not None:  # the band follows the edges the fit moved
            z, free_bounds = _pin(x[: f.n].reshape((materials,) + f.shape), edge_band)
            x[: f.n] = z.ravel()
        Bf = problem.model.stokes_spectra(*f.stokes(x))
        for k in range(frames):
            d_k, scale = f.d[k], float(f.d[k].sum())
            if scale <= 0:  # a lost exposure: nothing to fit its phase to
                continue

            def phase_objective(y, k=k, d_k=d_k, scale=scale):
                ph = np.zeros(inside.shape)
                ph[inside] = y
                L_k, G = problem.model.frame_loglik(
                    k, problem.ops.otf(pp.psf(ph)), Bf, d_k, problem.valid
                )
                return -L_k / scale, -pp.gradient(ph, G)[inside] / scale

            res = minimize(
                phase_objective,
                phases[k][inside],
                jac=True,
                method="L-BFGS-B",
                options={"maxiter": phase_steps, "gtol": 0.0, "ftol": 0.0},
            )
            phases[k] = 0.0
            phases[k][inside] = res.x
            hs[k] = pp.psf(phases[k])
        loglik.append(-f(x, [problem.ops.otf(h) for h in hs])[0] * f.scale)
    chi, a, p = f.unpack(x)
    psf, phase = (hs[0], phases[0]) if frames == 1 else (np.stack(hs), phases)
    return LayoutResult(psf, phase, problem.ops.crop(chi), a, p, np.array(loglik))
