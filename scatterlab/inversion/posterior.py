r"""Posterior sampling of (n, kappa, sigma) from multi-geometry DOLP with emcee.

Model and likelihood
    :math:`\mathcal P_j = \mathcal P^{thy}(n - j\kappa, \sigma; \theta_{i,j}, \theta_{r,j}, \phi_j) + e_j` with
    independent Gaussian errors :math:`e_j \sim N(0, s^2)` (the pBRDF DOLP of Eq. 203). The noise level
    :math:`s` is either known (``noise=0.01``) or a parameter (``noise=None``) with a log-uniform prior on
    ``noise_bounds``. NaN measurements are left out.

Priors
    Uniform on the bounds (defaults of :data:`~scatterlab.inversion.DEFAULT_BOUNDS`: n in [0, 5], kappa in
    [0, 25], sigma in [0.01, 1.5]); with ``kappa_prior="log-uniform"`` the sampler works in
    :math:`\log\kappa`, uniform on ``[log(max(kappa_lo, 1e-3)), log(kappa_hi)]`` -- the choice for a material
    whose absorption is unknown to within orders of magnitude. Chains are always reported in (n, kappa,
    sigma).

Sampling
    The affine-invariant ensemble sampler (``emcee``), vectorised over walkers. Walkers start in a small
    ball (half the Laplace standard errors) around the least-squares solution (:func:`~scatterlab.inversion.fit_dolp`), shared among all local
    minima whose chi-square is within ``mode_delta_chi2`` of the best (so a degenerate metal/dielectric pair
    is explored from both sides). With ``n_steps=None`` the chain is extended in blocks until it is at least
    ``min_tau_multiple`` (50) integrated autocorrelation times long and tau has changed by less than 5 %,
    up to ``max_steps``; otherwise a :class:`ConvergenceWarning` says so. Burn-in is 2 tau, thinning tau/2.

Diagnostics
    tau per parameter, the mean acceptance fraction, the split-chain potential scale reduction R-hat (each
    walker's kept chain cut in halves), the effective sample size, and modes: the walkers' medians are
    clustered (two-means on standardised coordinates); two clusters further apart than ``6`` pooled
    within-walker standard deviations, each holding at least two walkers, make the posterior *multimodal*,
    and both modes are reported with their weights.

Checkpointing
    ``backend="run.h5"`` stores the chain in emcee's HDF5 backend (group ``name``); calling again with the
    same file resumes where the chain stopped (the walkers' state and all samples are in the file).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.least_squares import DEFAULT_BOUNDS, DEFAULT_STARTS, DolpFit, _bounds, _prepare, fit_dolp

__all__ = ["sample_posterior", "sample_posteriors", "Posterior", "ConvergenceWarning", "PARAMETERS",
           "split_rhat", "local_minima"]

PARAMETERS = ("n", "kappa", "sigma")
KAPPA_FLOOR = 1e-3  # lower end of the log-uniform kappa prior


class ConvergenceWarning(UserWarning):
    """The MCMC chain is too short for its autocorrelation time, or the acceptance fraction is off."""


def split_rhat(chain: np.ndarray) -> np.ndarray:
    """Split-chain potential scale reduction (Gelman et al., BDA3 Sec. 11.4).

    Parameters
    ----------
    chain : array (steps, chains, P)

    Returns
    -------
    ndarray (P,); values near 1 (below about 1.01-1.05) mean the chains agree.
    """
    steps = chain.shape[0] // 2
    if steps < 2:
        return np.full(chain.shape[-1], np.nan)
    halves = np.concatenate([chain[:steps], chain[steps:2 * steps]], axis=1)  # (steps, 2C, P)
    means = halves.mean(0)
    W = halves.var(0, ddof=1).mean(0)
    B = steps * means.var(0, ddof=1)
    var = (steps - 1) / steps * W + B / steps
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(np.where(W > 0, var / W, np.nan))


def local_minima(dolp, theta_i, theta_r, phi=np.pi, *, sigma=None, bounds=None, starts=DEFAULT_STARTS,
                 noise=None, delta_chi2: float = 4.0, **model_kw) -> list[DolpFit]:
    """Distinct least-squares minima of one measurement vector whose chi-square is within ``delta_chi2`` of the best.

    One fit per start; minima closer than 1e-4 (relative, in every parameter) are merged. With ``noise``
    unknown, chi-square uses the best fit's residual variance. Best first.
    """
    fits = [fit_dolp(dolp, theta_i, theta_r, phi, sigma=sigma, bounds=bounds, starts=(s,), noise=noise,
                     **model_kw) for s in starts]
    fits = [f for f in fits if np.isfinite(f.cost)]
    if not fits:
        return []
    fits.sort(key=lambda f: float(f.cost))
    best = float(fits[0].cost)
    m = int(np.isfinite(np.asarray(dolp, float)).sum())
    P = 3 if sigma is None else 2
    s2 = noise**2 if noise is not None else max(2 * best / max(m - P, 1), 1e-30)
    out: list[DolpFit] = []
    for f in fits:
        if 2 * (float(f.cost) - best) / s2 > delta_chi2:
            continue
        x = np.array([f.n, f.kappa, f.sigma], float)
        if any(np.all(np.abs(x - np.array([g.n, g.kappa, g.sigma], float)) <= 1e-4 * (1 + np.abs(x)))
               for g in out):
            continue
        out.append(f)
    return out


@dataclass
class Posterior:
    """Posterior samples of (n, kappa, sigma) for one measurement vector, with diagnostics.

    Attributes
    ----------
    chain : ndarray (steps, walkers, 3)
        Kept samples (after burn-in and thinning) of (n, kappa, sigma); sigma is constant when it was known.
    noise_chain : ndarray (steps, walkers) or None
        Samples of the DOLP noise level when it was a parameter.
    log_prob : ndarray (steps, walkers)
    tau : ndarray (P,) -- integrated autocorrelation time [steps] of the sampled parameters.
    n_steps, burn, thin : int
    acceptance : float -- mean acceptance fraction.
    rhat : ndarray (P,)
    converged : bool -- run length >= min_tau_multiple * tau, acceptance in [0.15, 0.7] and R-hat < 1.05.
    modes : list of dict -- ``{"weight", "median": (3,)}`` per cluster of walkers; two or more: multimodal.
    least_squares : list of DolpFit -- the least-squares minima the walkers started from (best first).
    dolp, theta_i, theta_r, phi : the data and geometries.
    noise : float or None; sigma_known : float or None; kappa_prior : str; bounds : dict
    messages : list of str -- warnings raised during sampling, kept for the report.
    seconds : float -- wall time of the sampling.
    """

    chain: np.ndarray
    noise_chain: np.ndarray | None
    log_prob: np.ndarray
    tau: np.ndarray
    n_steps: int
    burn: int
    thin: int
    acceptance: float
    rhat: np.ndarray
    converged: bool
    modes: list
    least_squares: list
    dolp: np.ndarray
    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    noise: float | None
    sigma_known: float | None
    kappa_prior: str
    bounds: dict
    model_kw: dict = field(default_factory=dict)
    messages: list = field(default_factory=list)
    seconds: float = float("nan")

    @property
    def samples(self) -> np.ndarray:
        """All kept samples flattened, (N, 3)."""
        return self.chain.reshape(-1, 3)

    @property
    def multimodal(self) -> bool:
        return len(self.modes) > 1

    @property
    def n_effective(self) -> float:
        """Effective number of independent samples, ``walkers * (steps - burn) / max tau``."""
        return float(self.chain.shape[1] * (self.n_steps - self.burn) / np.max(self.tau))

    def quantiles(self, q) -> np.ndarray:
        """Quantiles ``q`` (K,) of each parameter -> (K, 3)."""
        return np.quantile(self.samples, q, axis=0)

    def interval(self, level: float = 0.68) -> np.ndarray:
        """Equal-tailed credible interval, (2, 3): lower and upper bounds of n, kappa, sigma."""
        a = (1 - level) / 2
        return self.quantiles([a, 1 - a])

    def summary(self) -> dict:
        """Medians, 68 % and 95 % credible intervals, mean and std per parameter, with the least-squares
        value and its Laplace standard error beside them, and the diagnostics (JSON-ready)."""
        q = self.quantiles([0.025, 0.16, 0.5, 0.84, 0.975])
        ls = self.least_squares[0] if self.least_squares else None
        params = {}
        for k, name in enumerate(PARAMETERS):
            entry = {"median": q[2, k], "ci68": [q[1, k], q[3, k]], "ci95": [q[0, k], q[4, k]],
                     "mean": float(self.samples[:, k].mean()), "std": float(self.samples[:, k].std())}
            if ls is not None:
                entry["least_squares"] = float(getattr(ls, name))
                P = ls.covariance.shape[-1]
                entry["laplace_error"] = float(ls.errors[k]) if k < P else 0.0
            params[name] = entry
        if self.noise_chain is not None:
            nq = np.quantile(self.noise_chain, [0.16, 0.5, 0.84])
            params["noise"] = {"median": nq[1], "ci68": [nq[0], nq[2]]}
        return {
            "parameters": params,
            "diagnostics": {
                "n_steps": self.n_steps, "burn": self.burn, "thin": self.thin,
                "walkers": int(self.chain.shape[1]), "tau": self.tau.tolist(),
                "steps_over_tau": float(self.n_steps / np.max(self.tau)),
                "acceptance": self.acceptance, "rhat": self.rhat.tolist(),
                "n_effective": self.n_effective, "converged": self.converged,
                "multimodal": self.multimodal,
                "modes": [{"weight": m["weight"], "median": list(m["median"])} for m in self.modes],
                "seconds": self.seconds,
            },
            "prior": {"kappa": self.kappa_prior, "bounds": self.bounds,
                      "noise": "known" if self.noise is not None else "log-uniform parameter"},
            "messages": list(self.messages),
        }

    def predictive(self, rng, n_draws: int = 200, *, theta_i=None, theta_r=None, phi=None,
                   with_noise: bool = False) -> np.ndarray:
        """Posterior-predictive DOLP (n_draws, M') at the data's geometries or at new ones."""
        ti = self.theta_i if theta_i is None else np.atleast_1d(theta_i)
        tr = self.theta_r if theta_r is None else np.atleast_1d(theta_r)
        ph = self.phi if phi is None else np.broadcast_to(phi, ti.shape)
        idx = rng.integers(0, self.samples.shape[0], n_draws)
        draws = self.samples[idx]
        y = DolpForward(ti, tr, ph, **self.model_kw)(draws)
        if with_noise:
            s = self.noise if self.noise is not None else self.noise_chain.ravel()[idx % self.noise_chain.size]
            y = y + np.asarray(s)[..., None] * rng.standard_normal(y.shape)
        return y


class _LogPosterior:
    """Vectorised log posterior over walkers (picklable)."""

    def __init__(self, forward, y, lo, hi, fit_sigma, log_kappa, noise, noise_bounds):
        self.forward, self.y, self.lo, self.hi = forward, y, lo, hi
        self.fit_sigma, self.log_kappa, self.noise, self.noise_bounds = fit_sigma, log_kappa, noise, noise_bounds
        self.mask = np.isfinite(y)
        self.m = int(self.mask.sum())

    def physical(self, x):
        """Sampler coordinates (W, D) -> (n, kappa, sigma) (W, P) and noise (W,) or None."""
        p = x[:, :3 if self.fit_sigma else 2].copy()
        if self.log_kappa:
            p[:, 1] = np.exp(p[:, 1])
        s = None if self.noise is not None else np.exp(x[:, -1])
        return p, s

    def __call__(self, x):
        x = np.atleast_2d(x)
        out = np.full(x.shape[0], -np.inf)
        inside = np.all((x >= self.lo) & (x <= self.hi), axis=1)
        if not np.any(inside):
            return out
        p, s = self.physical(x[inside])
        f = self.forward(p)
        r = np.where(self.mask, f - np.where(self.mask, self.y, 0.0), 0.0)
        chi2 = np.sum(r * r, -1)
        if self.noise is not None:
            out[inside] = -0.5 * chi2 / self.noise**2
        else:  # log-uniform prior on s is uniform in log s: no Jacobian term
            out[inside] = -0.5 * chi2 / s**2 - self.m * np.log(s)
        return out


def _clusters(walker_medians: np.ndarray, within_sd: np.ndarray, rng) -> list[dict]:
    """One or two clusters of walkers (see the module docstring)."""
    from scipy.cluster.vq import kmeans2

    W = walker_medians.shape[0]
    scale = np.where(within_sd > 0, within_sd, 1.0)
    z = walker_medians / scale
    single = [{"weight": 1.0, "median": np.median(walker_medians, 0)}]
    if W < 4 or np.allclose(z, z[0]):
        return single
    seed = int(rng.integers(2**31))
    centroids, labels = kmeans2(z, 2, seed=seed, minit="++")
    counts = np.bincount(labels, minlength=2)
    if counts.min() < 2 or np.linalg.norm(centroids[0] - centroids[1]) < 6.0:
        return single
    return [{"weight": float(counts[k] / W), "median": np.median(walker_medians[labels == k], 0)}
            for k in np.argsort(-counts)]


def sample_posterior(dolp, theta_i, theta_r, noise=None, rng=None, *, phi=np.pi, sigma=None, bounds=None,
                     kappa_prior: str = "uniform", noise_bounds=(1e-5, 1.0), n_walkers: int = 32,
                     n_steps: int | None = None, max_steps: int = 20000, block: int = 500,
                     min_tau_multiple: float = 50.0, starts=DEFAULT_STARTS, mode_delta_chi2: float = 4.0,
                     backend: str | Path | None = None, name: str = "posterior", progress: bool = False,
                     moves: str = "kde", **model_kw) -> Posterior:
    """Sample the posterior of (n, kappa, sigma) given DOLP at M geometries.

    Parameters
    ----------
    dolp : array (M,)
        Measured DOLP; NaN entries are masked. (For many problems use :func:`sample_posteriors`.)
    theta_i, theta_r : array (M,) [rad]
    noise : float or None
        DOLP noise standard deviation; ``None`` makes it a parameter (log-uniform on ``noise_bounds``).
    rng : numpy.random.Generator
        Seeds the walkers' start and emcee's moves.
    phi : float or array (M,) [rad], default pi
    sigma : float, optional
        Known roughness (then only n and kappa are sampled).
    bounds : dict, optional -- prior ranges, as for :func:`~scatterlab.inversion.fit_dolp`.
    kappa_prior : "uniform" or "log-uniform"
    n_walkers : int (>= 2 * dimensions)
    n_steps : int, optional
        Fixed chain length; ``None`` extends the chain in ``block``-step pieces until it is converged (module
        docstring) or ``max_steps`` long.
    backend : path, optional
        HDF5 file for emcee's backend (checkpoint and resume); ``name`` is the group.
    moves : "kde", "de" or "stretch"
        emcee proposal: "kde" (default) mixes the Gaussian-KDE move (80 %) with differential evolution (20 %);
        on the curved (n, kappa, sigma) posteriors it cuts tau about 10x against the stretch move (measured in
        ``studies/performance/perf_mcmc.py``) for 1.5x the cost per step.
    **model_kw : passed to :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    Posterior
    """
    import time

    import emcee

    if rng is None or not isinstance(rng, np.random.Generator):
        raise ValueError("rng must be a numpy.random.Generator (e.g. numpy.random.default_rng(seed))")
    if kappa_prior not in ("uniform", "log-uniform"):
        raise ValueError(f"kappa_prior must be 'uniform' or 'log-uniform', got {kappa_prior!r}")
    if noise is not None and not (np.isfinite(noise) and noise > 0):
        raise ValueError(f"noise must be a positive DOLP standard deviation or None, got {noise!r}")
    if not (0 < noise_bounds[0] < noise_bounds[1]):
        raise ValueError(f"noise_bounds must satisfy 0 < low < high, got {noise_bounds!r}")
    y, ti, tr, ph = _prepare(dolp, theta_i, theta_r, phi)
    if y.ndim != 1:
        raise ValueError(f"dolp must be one measurement vector (M,); got shape {y.shape}: use sample_posteriors")
    fit_sigma = sigma is None
    P = 3 if fit_sigma else 2
    if np.isfinite(y).sum() < P + (noise is None):
        raise ValueError(f"dolp has {int(np.isfinite(y).sum())} finite values; at least {P + (noise is None)} "
                         "are needed for the unknowns")
    lo, hi = _bounds(bounds, P)
    b = dict(DEFAULT_BOUNDS, **(bounds or {}))
    log_kappa = kappa_prior == "log-uniform"
    s_lo, s_hi = lo.copy(), hi.copy()
    if log_kappa:
        s_lo[1], s_hi[1] = np.log(max(lo[1], KAPPA_FLOOR)), np.log(hi[1])
    if noise is None:
        s_lo, s_hi = np.r_[s_lo, np.log(noise_bounds[0])], np.r_[s_hi, np.log(noise_bounds[1])]
    D = s_lo.size
    if n_walkers < 2 * D:
        raise ValueError(f"n_walkers must be at least {2 * D} (twice the number of sampled parameters)")
    forward = DolpForward(ti, tr, ph, sigma=None if fit_sigma else float(sigma), **model_kw)
    log_post = _LogPosterior(forward, y, s_lo, s_hi, fit_sigma, log_kappa, noise, noise_bounds)

    minima = local_minima(y, ti, tr, ph, sigma=sigma, bounds=bounds, starts=starts, noise=noise,
                          delta_chi2=mode_delta_chi2, **model_kw)
    messages: list[str] = []
    if len(minima) > 1:
        messages.append(f"{len(minima)} least-squares minima within delta chi2 = {mode_delta_chi2}: "
                        + "; ".join(f"n={float(f.n):.4g}, kappa={float(f.kappa):.4g}, sigma={float(f.sigma):.4g}"
                                    for f in minima))

    def start_ball(count):
        x = np.empty((count, D))
        which = np.arange(count) % max(len(minima), 1)
        for w in range(count):
            if minima:
                f = minima[which[w]]
                centre = np.array([float(f.n), float(f.kappa), float(f.sigma)])[:P]
                err = np.nan_to_num(np.asarray(f.errors, float), nan=0.0)
            else:
                centre, err = (lo + hi) / 2, (hi - lo) / 4
            width = np.clip(err, 1e-6 * (hi - lo), 0.05 * (hi - lo))
            x[w, :P] = centre + 0.5 * width * rng.standard_normal(P)
            if noise is None:
                resid = np.sqrt(2 * float(minima[0].cost) / max(np.isfinite(y).sum() - P, 1)) if minima else 0.01
                x[w, -1] = np.log(np.clip(resid, noise_bounds[0] * 1.01, noise_bounds[1] / 1.01)) \
                    + 0.1 * rng.standard_normal()
        if log_kappa:
            x[:, 1] = np.log(np.maximum(x[:, 1], KAPPA_FLOOR * 1.01))
        eps = 1e-9 * (s_hi - s_lo)
        return np.clip(x, s_lo + eps, s_hi - eps)

    be = None
    start = None
    done_steps = 0
    if backend is not None:
        Path(backend).parent.mkdir(parents=True, exist_ok=True)
        be = emcee.backends.HDFBackend(str(backend), name=name)
        try:
            done_steps = be.iteration
        except Exception:  # new file or group
            done_steps = 0
        if done_steps > 0:
            if be.shape != (n_walkers, D):
                raise ValueError(f"backend {backend}:{name} holds a chain of shape {be.shape}, not ({n_walkers}, {D})")
        else:
            be.reset(n_walkers, D)
    move_sets = {"kde": [(emcee.moves.KDEMove(), 0.8), (emcee.moves.DEMove(), 0.2)],
                 "de": [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)],
                 "stretch": [(emcee.moves.StretchMove(), 1.0)]}
    if moves not in move_sets:
        raise ValueError(f"moves must be one of {sorted(move_sets)}, got {moves!r}")
    sampler = emcee.EnsembleSampler(n_walkers, D, log_post, vectorize=True, backend=be, moves=move_sets[moves])
    sampler.random_state = np.random.RandomState(int(rng.integers(2**32))).get_state()
    if done_steps == 0:
        start = start_ball(n_walkers)

    t0 = time.perf_counter()
    tau = np.full(D, np.inf)
    target = n_steps if n_steps is not None else max_steps
    old_tau = np.inf
    while done_steps < target:
        steps = min(block if n_steps is None else target - done_steps, target - done_steps)
        sampler.run_mcmc(start, steps, progress=progress)
        start = None
        done_steps = sampler.iteration
        tau = sampler.get_autocorr_time(tol=0)
        if n_steps is None:
            stable = np.all(np.abs(old_tau - tau) < 0.05 * tau)
            if done_steps >= min_tau_multiple * np.max(tau) and stable:
                break
            old_tau = tau
    seconds = time.perf_counter() - t0

    tau = sampler.get_autocorr_time(tol=0)
    tmax = float(np.max(tau))
    burn = int(min(np.ceil(2 * tmax), done_steps // 2))
    thin = max(1, int(tmax // 2))
    x = sampler.get_chain(discard=burn, thin=thin)  # (S, W, D)
    lp = sampler.get_log_prob(discard=burn, thin=thin)
    S, W = x.shape[:2]
    p, s = log_post.physical(x.reshape(-1, D))
    chain = np.empty((S * W, 3))
    chain[:, :P] = p
    if not fit_sigma:
        chain[:, 2] = float(sigma)
    chain = chain.reshape(S, W, 3)
    noise_chain = None if s is None else s.reshape(S, W)
    acceptance = float(np.mean(sampler.acceptance_fraction))
    sampled = chain[..., :P] if noise_chain is None else np.concatenate([chain[..., :P], noise_chain[..., None]], -1)
    rhat = split_rhat(sampled)
    long_enough = done_steps >= min_tau_multiple * tmax
    if not long_enough:
        messages.append(f"chain of {done_steps} steps is shorter than {min_tau_multiple:g} autocorrelation times "
                        f"(tau = {tmax:.1f}); quantiles may be off: run longer (n_steps or max_steps)")
    if not 0.15 <= acceptance <= 0.7:
        messages.append(f"mean acceptance fraction {acceptance:.2f} is outside [0.15, 0.7]")
    if np.any(rhat > 1.05):
        messages.append(f"split R-hat {np.round(rhat, 3).tolist()} exceeds 1.05: walkers disagree")
    half = chain[S // 2:, :, :P]
    modes = _clusters(np.median(half, 0), np.sqrt(np.mean(np.var(half, 0), 0)), rng)
    for m in modes:
        if not fit_sigma:
            m["median"] = np.r_[m["median"], float(sigma)]
        m["median"] = np.asarray(m["median"], float)
    if len(modes) > 1:
        messages.append("multimodal posterior: " + "; ".join(
            f"{m['weight']:.0%} of walkers near n={m['median'][0]:.4g}, kappa={m['median'][1]:.4g}" for m in modes))
    for msg in messages:
        if "autocorrelation" in msg or "acceptance" in msg or "R-hat" in msg:
            warnings.warn(msg, ConvergenceWarning, stacklevel=2)
    return Posterior(chain=chain, noise_chain=noise_chain, log_prob=lp, tau=tau, n_steps=int(done_steps),
                     burn=burn, thin=thin, acceptance=acceptance, rhat=rhat,
                     converged=bool(long_enough and 0.15 <= acceptance <= 0.7 and np.all(rhat < 1.05)),
                     modes=modes, least_squares=minima, dolp=y, theta_i=ti, theta_r=tr, phi=ph, noise=noise,
                     sigma_known=None if fit_sigma else float(sigma), kappa_prior=kappa_prior,
                     bounds={k: list(v) for k, v in b.items()}, model_kw=dict(model_kw), messages=messages,
                     seconds=seconds)


def _sample_task(task):
    y, seed, args, kw = task
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # kept in Posterior.messages
        return sample_posterior(y, *args, rng=np.random.default_rng(seed), **kw)


def sample_posteriors(dolp, theta_i, theta_r, noise=None, rng=None, *, executor=None, backend=None,
                      **kw) -> list[Posterior]:
    """:func:`sample_posterior` for each row of ``dolp`` (K, M) -- regions or pixels -- through an executor.

    Each problem gets its own seed drawn from ``rng``, so results do not depend on the executor. With
    ``backend`` (a directory) problem k is checkpointed in ``backend/problem_k.h5``. Convergence warnings are
    collected in each posterior's ``messages`` rather than raised.
    """
    from scatterlab.runtime import get_executor

    if rng is None or not isinstance(rng, np.random.Generator):
        raise ValueError("rng must be a numpy.random.Generator")
    y = np.atleast_2d(np.asarray(dolp, float))
    seeds = rng.integers(2**63, size=y.shape[0])
    tasks = []
    for k, row in enumerate(y):
        kk = dict(kw)
        if backend is not None:  # one file per problem: HDF5 files are not safe for concurrent writers
            kk.update(backend=str(Path(backend) / f"problem_{k}.h5"), name="posterior")
        tasks.append((row, int(seeds[k]), (theta_i, theta_r, noise), kk))
    ex = executor if executor is not None else get_executor("serial")
    return ex.map(_sample_task, tasks, desc="posteriors")
