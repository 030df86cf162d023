r"""Posterior sampling of (n, kappa, sigma) from multi-geometry DOLP with emcee.

Model and likelihood
    :math:`\mathcal P_j = \mathcal P^{thy}(n - j\kappa, \sigma; \theta_{i,j}, \theta_{r,j}, \phi_j)
    + e_j` (the
    pBRDF DOLP of Eq. 203) with Gaussian errors :math:`e \sim N(0, V)`:

    * default: independent, :math:`V = s^2 I`; the noise level :math:`s` is known (``noise=0.01``)
    or a
      parameter (``noise=None``) with a log-uniform prior on ``noise_bounds``;
    * ``systematic`` (float or (M,)): a known systematic standard deviation :math:`t_j` per geometry
    (model
      error, a measured deconvolution or registration error) added in quadrature,
      :math:`V = \mathrm{diag}(s^2 + t_j^2)`, whether :math:`s` is known or inferred;
    * ``covariance`` ((M, M)): a full error covariance :math:`C` (errors correlated across
    geometries) used
      instead of ``noise`` (which must then be None and is not inferred), :math:`V = C +
      \mathrm{diag}(t^2)`,
      factorised (Cholesky) once.

    * ``correlated`` ((M,)): one error :math:`c\,z` shared by the whole series (:math:`z \sim N(0, 1)`,
      a scale error of a correction applied to all geometries), added to any of the above:
      :math:`V + c\,c^\mathsf{T}`; with a diagonal :math:`V` the likelihood uses the Sherman-Morrison form,
      so an inferred noise stays cheap.

    NaN measurements are left out (their rows and columns of :math:`V` too).

Priors
    Uniform on the bounds (defaults of :data:`~scatterlab.inversion.DEFAULT_BOUNDS`: n in [0, 5],
    kappa in
    [0, 25], sigma in [0.01, 1.5]); with ``kappa_prior="log-uniform"`` the sampler works in
    :math:`\log\kappa`, uniform on ``[log(max(kappa_lo, 1e-3)), log(kappa_hi)]`` -- the choice for a
    material
    whose absorption is unknown to within orders of magnitude. Chains are always reported in (n,
    kappa,
    sigma). The prior options are grouped in :class:`PriorOptions`.

Sampling (:class:`SamplerOptions`)
    ``n_ensembles`` (default 2) independent runs of the affine-invariant ensemble sampler
    (``emcee``), each
    with ``n_walkers`` walkers, its own seed and its own start, vectorised over walkers. Walkers
    start in a
    small ball (half the Laplace standard errors) around the least-squares solution
    (:func:`~scatterlab.inversion.fit_dolp`), shared among all local minima whose chi-square is
    within
    ``mode_delta_chi2`` of the best (so a degenerate metal/dielectric pair is explored from both
    sides). With
    ``n_steps=None`` the ensembles are extended in blocks until each is at least
    ``min_tau_multiple`` (50)
    integrated autocorrelation times long, tau has changed by less than 5 % and the ensembles agree
    (R-hat
    below 1.01), up to ``max_steps``; otherwise a :class:`ConvergenceWarning` says so. Burn-in is 2
    tau,
    thinning tau/2. ``moves`` takes an emcee move (or a list of ``(move, weight)``) or a shortcut
    string.

Diagnostics
    The walkers of one ensemble are not independent chains (each move uses the others), so a split
    R-hat over
    walkers says little. Here R-hat (:func:`ensemble_rhat`) compares the independent ensembles, each
    pooled
    over its walkers and split in halves; the effective sample size per parameter
    (:func:`effective_sample_size`) is walkers x steps / tau with emcee's integrated autocorrelation
    time
    tau. Also the mean acceptance fraction and modes: the walkers' medians are clustered (two-means
    on
    standardised coordinates); two clusters further apart than ``6`` pooled within-walker standard
    deviations, each holding at least two walkers, make the posterior *multimodal*, and both modes
    are
    reported with their weights. :meth:`Posterior.to_inference_data` exports the chains to ArviZ.

Checkpointing
    ``backend="run.h5"`` stores each ensemble in emcee's HDF5 backend (group
    ``<name>/ensemble_<k>``);
    calling again with the same file resumes where the chains stopped. Each group records a digest
    of the data,
    geometries, error model, priors and sampler settings, and resuming with any of them changed is a
    ValueError (the chains would mix two posteriors). emcee backend objects can be passed instead of
    a path.
"""

from __future__ import annotations

import hashlib
import json
import time
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from scatterlab._checks import as_finite, as_rng, as_scalar
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.least_squares import (
    DEFAULT_BOUNDS,
    DEFAULT_STARTS,
    DOLP_MARGIN,
    NOISE_RANGE,
    DolpFit,
    IdentifiabilityWarning,
    check_covariance,
    check_noise,
    check_starts,
    check_systematic,
    fit_dolp,
    parameter_bounds,
    prepare_data,
)
from scatterlab.inversion.options import MODEL_KEYS, resolve_options

__all__ = [
    "sample_posterior",
    "sample_posteriors",
    "Posterior",
    "ConvergenceWarning",
    "PARAMETERS",
    "PriorOptions",
    "SamplerOptions",
    "PosteriorProblem",
    "posterior_problem",
    "start_walkers",
    "run_ensembles",
    "diagnose",
    "split_rhat",
    "ensemble_rhat",
    "effective_sample_size",
    "local_minima",
    "MOVES",
    "MisfitWarning",
    "FIT_P_MIN",
]

PARAMETERS = ("n", "kappa", "sigma")
KAPPA_FLOOR = 1e-3  # lower end of the log-uniform kappa prior
RHAT_MAX = 1.01  # between-ensemble R-hat above which the ensembles disagree (Vehtari et al. 2021)
ACCEPTANCE = (0.15, 0.7)  # acceptance fractions outside this range mean a poorly tuned proposal


FIT_P_MIN = 1e-3  # chi-square p-value below which the data misfit the model and its stated errors


class MisfitWarning(UserWarning):
    """The best fit's chi-square is improbable under the stated DOLP errors (p < :data:`FIT_P_MIN`):
    the errors are understated, the geometry is wrong (angles in other units, a wrong azimuth), or the
    model lacks an error term, and the intervals, which assume the stated errors, are too narrow."""


class ConvergenceWarning(UserWarning):
    """The MCMC chain is too short for its autocorrelation time, the ensembles disagree, or the
    acceptance
    fraction is off."""


# -- diagnostics
# ---------------------------------------------------------------------------------------------
def _check_chain(chain, name: str = "chain") -> np.ndarray:
    """``chain`` as a finite float array (steps, walkers, P), else a ValueError naming it."""
    arr = as_finite(chain, name)
    if arr.ndim != 3 or 0 in arr.shape:
        raise ValueError(
            f"{name} must be a 3-D array (steps, walkers, P) (one column per parameter), got shape "
            f"{arr.shape}; add an axis for a single walker or parameter"
        )
    return arr


def _standardised(chain: np.ndarray) -> np.ndarray:
    """Each parameter of ``chain`` (..., P) centred and scaled to unit standard deviation (a constant
    one to zeros): the diagnostics are scale-invariant, and 1e160 no longer overflows in squares."""
    P = chain.shape[-1]
    flat = chain.reshape(-1, P)
    big = np.max(np.abs(flat), axis=0)
    x = flat / np.where(big > 0, big, 1.0)  # in [-1, 1] first: the moments cannot overflow
    x = x - x.mean(0)
    sd = x.std(0)
    return (x / np.where(sd > 0, sd, 1.0)).reshape(chain.shape)


def split_rhat(chain: np.ndarray) -> np.ndarray:
    """Split-chain potential scale reduction (Gelman et al., BDA3 Sec. 11.4) over independent
    chains.

    Parameters
    ----------
    chain : array (steps, chains, P)
        The chains must be independent (not the walkers of one emcee ensemble: use
        :func:`ensemble_rhat`).

    Returns
    -------
    ndarray (P,); values near 1 (below about 1.01) mean the chains agree.
    """
    steps = chain.shape[0] // 2
    if steps < 2:
        return np.full(chain.shape[-1], np.nan)
    halves = np.concatenate([chain[:steps], chain[steps : 2 * steps]], axis=1)  # (steps, 2C, P)
    means = halves.mean(0)
    W = halves.var(0, ddof=1).mean(0)
    B = steps * means.var(0, ddof=1)
    var = (steps - 1) / steps * W + B / steps
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(np.where(W > 0, var / W, np.nan))


def ensemble_rhat(chain: np.ndarray, n_ensembles: int) -> np.ndarray:
    """R-hat between independent ensembles, each pooled over its walkers and split in halves.

    Parameters
    ----------
    chain : array (steps, n_ensembles * walkers, P)
        The walkers of ensemble k are the k-th contiguous block of the walker axis; finite and 3-D
        (a ValueError otherwise).
    n_ensembles : int

    Returns
    -------
    ndarray (P,)
        :math:`\\sqrt{((N-1)/N\\,W + B/N)/W}` with the 2E half-ensembles as chains of N pooled
        samples:
        :math:`W` the mean within-chain variance, :math:`B/N` the variance of the chain means. Near
        1 when the
        ensembles sample the same distribution (:math:`B/N \\approx W/\\mathrm{ESS}`); NaN for fewer
        than 4
        steps. With one ensemble only its two halves are compared (stationarity, not agreement).
    """
    if (
        isinstance(n_ensembles, bool)
        or not isinstance(n_ensembles, (int, np.integer))
        or n_ensembles < 1
    ):
        raise ValueError(f"n_ensembles must be an integer >= 1, got {n_ensembles!r}")
    chain = _standardised(_check_chain(chain))
    S, WT, P = chain.shape
    if WT % n_ensembles:
        raise ValueError(
            f"n_ensembles ({n_ensembles}) must divide the chain's {WT} walkers (axis 1): each ensemble has "
            "the same number of walkers"
        )
    half = S // 2
    if half < 2:
        return np.full(P, np.nan)
    x = chain[: 2 * half].reshape(2, half, n_ensembles, WT // n_ensembles, P)
    pieces = np.moveaxis(x, 2, 1).reshape(2 * n_ensembles, -1, P)  # (2E, half * walkers, P)
    N = pieces.shape[1]
    W = pieces.var(1, ddof=1).mean(0)
    b_over_n = pieces.mean(1).var(0, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(np.where(W > 0, ((N - 1) / N * W + b_over_n) / W, np.nan))


def effective_sample_size(chain: np.ndarray) -> np.ndarray:
    """Effective number of independent samples per parameter, walkers x steps / tau.

    Parameters
    ----------
    chain : array (steps, walkers, P)
        Unthinned samples after burn-in, finite and 3-D (a ValueError otherwise; standardised per
        parameter first, so the result does not depend on units); tau is emcee's integrated
        autocorrelation time
        (walker-averaged
        autocorrelation, automatic window; Goodman & Weare 2010, Sokal 1997).

    Returns
    -------
    ndarray (P,); NaN for a parameter that does not move.
    """
    import emcee

    chain = _check_chain(chain)
    S, W, P = chain.shape
    if S < 2:
        return np.full(P, np.nan)
    moving = np.ptp(chain.reshape(-1, P), axis=0) > 0
    chain = _standardised(chain)  # tau is scale-invariant; a chain of 1e160 overflowed to NaN
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore")
        with np.errstate(invalid="ignore", divide="ignore"):  # a constant chain: tau NaN, flagged
            tau = emcee.autocorr.integrated_time(chain, tol=0)
    return np.where(moving & (tau > 0), S * W / np.maximum(tau, 1e-300), np.nan)


# -- options
# -------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PriorOptions:
    """Prior ranges of :func:`sample_posterior`.

    Attributes
    ----------
    bounds : dict or None
        ``{"n": (lo, hi), "kappa": (lo, hi), "sigma": (lo, hi)}`` uniform prior ranges (defaults in
        :data:`~scatterlab.inversion.DEFAULT_BOUNDS`).
    kappa_prior : "uniform" or "log-uniform"
    noise_bounds : (low, high)
        Log-uniform prior range of the DOLP noise when it is a parameter, within the range of
        ``noise`` (``1e-12 <= low < high <= 1``; below, the whitened residuals overflow).
    """

    bounds: dict | None = None
    kappa_prior: str = "uniform"
    noise_bounds: tuple = (1e-5, 1.0)

    def validate(self) -> None:
        if self.kappa_prior not in ("uniform", "log-uniform"):
            raise ValueError(
                f"kappa_prior must be 'uniform' or 'log-uniform', got {self.kappa_prior!r}"
            )
        nb = self.noise_bounds
        lo, hi = NOISE_RANGE
        allowed = (
            f"noise_bounds must be (low, high), two DOLP standard deviations with "
            f"{lo:g} <= low < high <= {hi:g}"
        )
        try:
            ok = not isinstance(nb, (str, bytes)) and np.shape(nb) == (2,)
            pair = np.asarray(nb, float) if ok else None
        except (TypeError, ValueError):
            pair = None
        if pair is None or not (np.all(np.isfinite(pair)) and lo <= pair[0] < pair[1] <= hi):
            raise ValueError(f"{allowed}, got {nb!r}")


MOVES = ("kde", "de", "stretch")


@dataclass(frozen=True)
class SamplerOptions:
    """Sampler settings of :func:`sample_posterior` (see the module docstring).

    Attributes
    ----------
    n_walkers : int -- walkers per ensemble (>= 2 x the sampled dimensions).
    n_ensembles : int -- independent ensembles (>= 1; 2 or more for a between-ensemble R-hat).
    n_steps : int or None -- fixed chain length (>= 20), or None: run until converged.
    max_steps, block : int -- the adaptive run's limit and block length [steps].
    min_tau_multiple : float -- required run length in autocorrelation times.
    moves : str, emcee move or list of (move, weight)
        "kde" (default) mixes the Gaussian-KDE move (80 %) with differential evolution (20 %); on
        the curved
        (n, kappa, sigma) posteriors it cuts tau about 10x against the stretch move (measured in
        ``studies/performance/perf_mcmc.py``) for 1.5x the cost per step; "de" (DE 80 % + snooker 20
        %);
        "stretch".
    starts : sequence of (n, kappa) -- least-squares starts that locate the modes.
    mode_delta_chi2 : float -- minima within this chi-square of the best seed walkers (finite, > 0).
    progress : bool -- emcee's progress bar.
    """

    n_walkers: int = 32
    n_ensembles: int = 2
    n_steps: int | None = None
    max_steps: int = 20000
    block: int = 500
    min_tau_multiple: float = 50.0
    moves: object = "kde"
    starts: tuple = DEFAULT_STARTS
    mode_delta_chi2: float = 4.0
    progress: bool = False

    def validate(self, ndim: int) -> None:
        def integer(v):
            return isinstance(v, (int, np.integer)) and not isinstance(v, bool)

        if not (integer(self.n_walkers) and self.n_walkers >= 2 * ndim):
            raise ValueError(
                f"n_walkers must be an integer of at least {2 * ndim} (twice the number of sampled "
                f"parameters), got {self.n_walkers!r}"
            )
        if not (integer(self.n_ensembles) and self.n_ensembles >= 1):
            raise ValueError(f"n_ensembles must be a positive integer, got {self.n_ensembles!r}")
        if self.n_steps is not None and not (integer(self.n_steps) and self.n_steps >= 20):
            raise ValueError(
                "n_steps must be None (run until converged) or an integer >= 20, got "
                f"{self.n_steps!r}"
            )
        if not (
            integer(self.max_steps)
            and self.max_steps >= 20
            and integer(self.block)
            and self.block >= 1
        ):
            raise ValueError(
                f"max_steps must be an integer >= 20 and block >= 1, got {self.max_steps!r}, "
                f"{self.block!r}"
            )
        if not self.min_tau_multiple > 0:
            raise ValueError(f"min_tau_multiple must be > 0, got {self.min_tau_multiple!r}")
        if isinstance(self.moves, str) and self.moves not in MOVES:
            raise ValueError(
                f"moves must be one of {list(MOVES)} or emcee move objects, got {self.moves!r}"
            )
        as_scalar(self.mode_delta_chi2, "mode_delta_chi2", 0.0, np.inf, open_lo=True)
        check_starts(self.starts)


def _emcee_moves(moves):
    """emcee moves for a shortcut string, or the given move objects unchanged."""
    import emcee

    if not isinstance(moves, str):
        return moves
    return {
        "kde": [(emcee.moves.KDEMove(), 0.8), (emcee.moves.DEMove(), 0.2)],
        "de": [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)],
        "stretch": [(emcee.moves.StretchMove(), 1.0)],
    }[moves]


def _moves_key(moves) -> str:
    """A stable description of the moves for the checkpoint digest."""
    if isinstance(moves, str):
        return moves
    items = moves if isinstance(moves, (list, tuple)) else [moves]
    return repr(
        [
            (type(m[0]).__name__, float(m[1])) if isinstance(m, tuple) else type(m).__name__
            for m in items
        ]
    )


def _resolve_options(prior, sampler, kw):
    """Split legacy keywords into PriorOptions, SamplerOptions and pBRDF model keywords."""
    groups = {"prior": (PriorOptions, prior), "sampler": (SamplerOptions, sampler)}
    return resolve_options(kw, groups, MODEL_KEYS)


# -- the problem: data, error model, prior, log posterior
# ------------------------------------------------------
class DolpLogPosterior:
    """Vectorised log posterior over walkers in sampler coordinates (picklable).

    Sampler coordinates are (n, kappa or log kappa[, sigma][, log noise]); the prior is uniform on
    ``[lo, hi]`` in them. The likelihood is Gaussian with the error model of the module docstring;
    constant
    terms are dropped.
    """

    def __init__(
        self,
        forward,
        y,
        lo,
        hi,
        *,
        fit_sigma,
        log_kappa,
        noise,
        systematic=None,
        covariance=None,
        correlated=None,
    ):
        from scipy.linalg import cholesky

        self.forward, self.lo, self.hi = forward, lo, hi
        self.fit_sigma, self.log_kappa, self.noise = fit_sigma, log_kappa, noise
        mask = np.isfinite(y)
        self.index, self.y, self.m = np.flatnonzero(mask), y[mask], int(mask.sum())
        self.syst2 = np.zeros(self.m) if systematic is None else systematic[mask] ** 2
        self.chol = None
        self.c = None if correlated is None else np.asarray(correlated, float)[mask]
        if covariance is not None:
            full = covariance[np.ix_(mask, mask)] + np.diag(self.syst2)
            if self.c is not None:
                full = full + np.outer(self.c, self.c)
            self.chol = cholesky(full, lower=True)
        self.var = None if noise is None else noise**2 + self.syst2

    def physical(self, x):
        """Sampler coordinates (W, D) -> (n, kappa, sigma) (W, P) and noise (W,) or None."""
        p = x[:, : 3 if self.fit_sigma else 2].copy()
        if self.log_kappa:
            p[:, 1] = np.exp(p[:, 1])
        s = np.exp(x[:, -1]) if self.infers_noise else None
        return p, s

    @property
    def infers_noise(self) -> bool:
        return self.noise is None and self.chol is None

    def _quadratic(self, r, v):
        """``r^T V^-1 r`` and ``log det V`` (W,) of residuals ``r`` (W, M): V from the Cholesky factor of
        a covariance (its log det a constant, returned as 0), else diag(``v``) (W, M) plus the shared
        error's ``c c^T``."""
        from scipy.linalg import solve_triangular

        if self.chol is not None:
            z = solve_triangular(self.chol, r.T, lower=True)
            return np.sum(z * z, 0), 0.0
        quad, logdet = np.sum(r * r / v, -1), np.sum(np.log(v), -1)
        if self.c is not None:
            # V = diag(v) + c c^T (Sherman-Morrison): r^T V^-1 r = r^T D^-1 r - (r^T D^-1 c)^2 / (1 + g),
            # log det V = log det D + log(1 + g), g = c^T D^-1 c
            g = np.sum(self.c**2 / v, -1)
            u = np.sum(r * self.c / v, -1)
            quad, logdet = quad - u**2 / (1 + g), logdet + np.log1p(g)
        return quad, logdet

    def _variance(self, r, s):
        """Diagonal error variance (W, M) for noise ``s`` (W,) or the known one (None); None with a
        covariance."""
        if self.chol is not None:
            return None
        if s is None:
            return np.broadcast_to(self.var, r.shape)
        return (
            s[:, None] ** 2 + self.syst2
        )  # log-uniform prior on s is uniform in log s: no Jacobian

    def log_likelihood(self, f, s):
        """Log likelihood (W,) of model DOLP ``f`` (W, M) and noise ``s`` (W,) or None."""
        r = f[:, self.index] - self.y
        quad, logdet = self._quadratic(r, self._variance(r, s))
        return -0.5 * (quad + logdet)

    def chi2(self, f) -> np.ndarray:
        """Chi-square (W,) of model DOLP ``f`` (W, M) under the known error model (the Mahalanobis
        norm of the residual; no normalisation terms). Only for a known error model.

        Parameters
        ----------
        f : ndarray, shape (W, M)

        Returns
        -------
        ndarray, shape (W,)
        """
        if self.infers_noise:
            raise ValueError(
                "chi2 needs a known error model (noise or covariance), not an inferred noise"
            )
        r = f[:, self.index] - self.y
        return self._quadratic(r, self._variance(r, None))[0]

    def __call__(self, x):
        x = np.atleast_2d(x)
        out = np.full(x.shape[0], -np.inf)
        inside = np.all((x >= self.lo) & (x <= self.hi), axis=1)
        if not np.any(inside):
            return out
        p, s = self.physical(x[inside])
        out[inside] = self.log_likelihood(self.forward(p), s)
        return out


@dataclass
class PosteriorProblem:
    """A validated posterior problem: data, geometries, error model, prior and its log posterior."""

    dolp: np.ndarray
    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    noise: float | None
    sigma: float | None
    systematic: np.ndarray | None
    covariance: np.ndarray | None
    prior: PriorOptions
    model_kw: dict
    log_post: DolpLogPosterior
    lo: np.ndarray  # physical bounds (P,)
    hi: np.ndarray
    correlated: np.ndarray | None = None

    @property
    def P(self) -> int:
        return self.lo.size

    @property
    def ndim(self) -> int:
        return self.log_post.lo.size

    def error_sd(self) -> float | None:
        """A typical known DOLP error standard deviation (None when the noise is inferred)."""
        if self.covariance is not None:
            return float(np.sqrt(np.mean(np.diag(self.covariance)) + np.mean(self.log_post.syst2)))
        if self.noise is None:
            return None
        return float(np.sqrt(self.noise**2 + np.mean(self.log_post.syst2)))

    def digest(self, sampler: SamplerOptions, ensemble: int) -> str:
        """SHA-256 of everything a resumed chain must share with the stored one."""
        h = hashlib.sha256()
        for a in (
            self.dolp,
            self.theta_i,
            self.theta_r,
            self.phi,
            self.systematic,
            self.covariance,
            self.correlated,
        ):
            h.update(b"-" if a is None else np.ascontiguousarray(a, float).tobytes())
        meta = {
            "noise": self.noise,
            "sigma": self.sigma,
            "prior": asdict(self.prior),
            "model": {k: repr(v) for k, v in sorted(self.model_kw.items())},
            "walkers": sampler.n_walkers,
            "ndim": self.ndim,
            "moves": _moves_key(sampler.moves),
            "ensemble": ensemble,
        }
        h.update(json.dumps(meta, sort_keys=True, default=repr).encode())
        return h.hexdigest()


def _check_error_model(noise, systematic, covariance, M):
    """Validated scalar noise (or None), systematic (M,) (or None) and covariance (M, M) (or None)."""
    noise = check_noise(noise)
    if noise is not None and noise.ndim:
        raise ValueError(
            f"noise must be a scalar DOLP standard deviation or None, got shape {noise.shape}"
        )
    noise = None if noise is None else float(noise)
    systematic = check_systematic(systematic, M)
    return noise, systematic, check_covariance(covariance, noise, M)


def posterior_problem(
    dolp,
    theta_i,
    theta_r,
    noise=None,
    *,
    phi=np.pi,
    sigma=None,
    systematic=None,
    covariance=None,
    correlated=None,
    prior: PriorOptions | None = None,
    model_kw=None,
) -> PosteriorProblem:
    r"""Validate the inputs of :func:`sample_posterior` and build its log posterior (the *start*
    piece).

    Parameters
    ----------
    dolp : array (M,)
        Measured DOLP (NaN: missing).
    theta_i, theta_r : array (M,) [rad]
    noise : float or None
        Known DOLP noise standard deviation, or None to infer it.
    phi : float or array (M,) [rad]
    sigma : float, optional
        Known roughness.
    systematic : float or array (M,), optional
        Known systematic DOLP standard deviation per geometry, in ``[0, 1]``.
    covariance : array (M, M), optional
        Full DOLP error covariance (as :func:`~scatterlab.inversion.least_squares.check_covariance`:
        variances <= 1, eigenvalues >= 1e-24).
    correlated : array (M,), optional
        One error shared by the whole series [DOLP], finite with ``|c| <= 1``: adds
        :math:`c\,c^\mathsf{T}` to the covariance.
    prior : PriorOptions, optional
    model_kw : dict, optional
        Keywords of :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    PosteriorProblem
        Validated data and the vectorised log posterior in sampler coordinates.
    """
    prior = prior if prior is not None else PriorOptions()
    prior.validate()
    model_kw = dict(model_kw or {})
    M = np.size(theta_i)
    noise, systematic, covariance = _check_error_model(noise, systematic, covariance, M)
    if correlated is not None:
        try:
            c = None if isinstance(correlated, (str, bytes)) else np.asarray(correlated, float)
        except (TypeError, ValueError):
            c = None
        if (
            c is None
            or c.shape != (M,)
            or not np.all(np.isfinite(c) & (np.abs(c) <= NOISE_RANGE[1]))
        ):
            raise ValueError(
                f"correlated must be an array ({M},) of DOLP errors with |c| <= "
                f"{NOISE_RANGE[1]:g}, got {correlated!r}"
            )
        correlated = c
    known = (
        [noise or 0.0]
        + ([] if systematic is None else [float(systematic.max())])
        + ([] if covariance is None else [float(np.sqrt(np.max(np.diag(covariance))))])
        + ([] if correlated is None else [float(np.abs(correlated).max())])
    )
    margin = max(DOLP_MARGIN, 5 * float(np.sqrt(np.sum(np.square(known)))))
    y, ti, tr, ph = prepare_data(dolp, theta_i, theta_r, phi, margin=margin)
    if y.ndim != 1:
        raise ValueError(
            f"dolp must be one measurement vector (M,); got shape {y.shape}: use sample_posteriors"
        )
    fit_sigma = sigma is None
    if not fit_sigma and not (np.ndim(sigma) == 0 and 1e-3 <= float(sigma) <= 2.5):
        raise ValueError(f"sigma must be a known rms slope in [1e-3, 2.5] or None, got {sigma!r}")
    P = 3 if fit_sigma else 2
    infer = noise is None and covariance is None
    if np.isfinite(y).sum() < P + infer:
        raise ValueError(
            f"dolp has {int(np.isfinite(y).sum())} finite values; at least {P + infer} are needed "
            "for the unknowns"
        )
    lo, hi = parameter_bounds(prior.bounds, P)
    s_lo, s_hi = lo.copy(), hi.copy()
    log_kappa = prior.kappa_prior == "log-uniform"
    if log_kappa:
        s_lo[1], s_hi[1] = np.log(max(lo[1], KAPPA_FLOOR)), np.log(hi[1])
    if infer:
        s_lo, s_hi = (
            np.r_[s_lo, np.log(prior.noise_bounds[0])],
            np.r_[s_hi, np.log(prior.noise_bounds[1])],
        )
    forward = DolpForward(ti, tr, ph, sigma=None if fit_sigma else float(sigma), **model_kw)
    log_post = DolpLogPosterior(
        forward,
        y,
        s_lo,
        s_hi,
        fit_sigma=fit_sigma,
        log_kappa=log_kappa,
        noise=noise,
        systematic=systematic,
        covariance=covariance,
        correlated=correlated,
    )
    return PosteriorProblem(
        y,
        ti,
        tr,
        ph,
        noise,
        None if fit_sigma else float(sigma),
        systematic,
        covariance,
        prior,
        model_kw,
        log_post,
        lo,
        hi,
        correlated,
    )


def local_minima(
    dolp,
    theta_i,
    theta_r,
    phi=np.pi,
    *,
    sigma=None,
    bounds=None,
    starts=DEFAULT_STARTS,
    noise=None,
    delta_chi2: float = 4.0,
    **model_kw,
) -> list[DolpFit]:
    """Distinct least-squares minima of one measurement vector whose chi-square is within
    ``delta_chi2`` of the best.

    One fit per start; minima closer than 1e-4 (relative, in every parameter) are merged. With
    ``noise``
    unknown, chi-square uses the best fit's residual variance. Best first.

    Parameters
    ----------
    dolp : array (M,)
        Measured DOLP.
    theta_i, theta_r : array (M,) [rad]
    phi : float or array (M,) [rad]
    sigma : float, optional
        Known roughness.
    bounds : dict, optional
        Parameter bounds (see :data:`~scatterlab.inversion.DEFAULT_BOUNDS`).
    starts : sequence of (n, kappa)
    noise : float, optional
        Known DOLP noise standard deviation.
    delta_chi2 : float
        Chi-square window above the best minimum: finite and > 0 (a ValueError otherwise).
    **model_kw
        ``shadowing``, ``diffuse``, ``distribution`` of :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    list of DolpFit
        The distinct minima, lowest cost first (empty when no start could be fitted).
    """
    delta_chi2 = as_scalar(delta_chi2, "delta_chi2", 0.0, np.inf, open_lo=True)
    fits = [
        fit_dolp(
            dolp,
            theta_i,
            theta_r,
            phi,
            sigma=sigma,
            bounds=bounds,
            starts=(s,),
            noise=noise,
            **model_kw,
        )
        for s in check_starts(starts)
    ]
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
        if any(
            np.all(np.abs(x - np.array([g.n, g.kappa, g.sigma], float)) <= 1e-4 * (1 + np.abs(x)))
            for g in out
        ):
            continue
        out.append(f)
    return out


def _problem_minima(
    problem: PosteriorProblem, options: SamplerOptions, messages: list
) -> list[DolpFit]:
    """The least-squares minima that seed the walkers, with one message per statement about them.

    The least-squares column of the report is the best minimum; each message names the minimum it is
    about (the fits of the other starts, and their warnings, are not reported).
    """
    with warnings.catch_warnings():
        # every start's fit warns of its own end point; what matters is said below per kept minimum
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        minima = local_minima(
            problem.dolp,
            problem.theta_i,
            problem.theta_r,
            problem.phi,
            sigma=problem.sigma,
            bounds=problem.prior.bounds,
            starts=options.starts,
            # the chi-square scale of the window; a known error above 1 (noise and systematic
            # together) is clipped to the range a DOLP noise may take
            noise=None if problem.error_sd() is None else min(problem.error_sd(), NOISE_RANGE[1]),
            delta_chi2=options.mode_delta_chi2,
            **problem.model_kw,
        )
    messages.extend(_minima_messages(minima, problem, options.mode_delta_chi2))
    return minima


def _describe_minimum(f: DolpFit, k: int, count: int) -> str:
    """``"the least-squares minimum n=..., kappa=..., sigma=... (the best: ...)"``."""
    at = f"n={float(f.n):.4g}, kappa={float(f.kappa):.4g}, sigma={float(f.sigma):.4g}"
    if count == 1:
        return f"the least-squares minimum ({at}; the table's least-squares column)"
    which = "the best, the table's least-squares column" if k == 0 else "not the table's"
    return f"least-squares minimum {k + 1} of {count} ({at}; {which})"


def _minima_messages(minima: list, problem: PosteriorProblem, delta_chi2: float) -> list[str]:
    """What the data say about each least-squares minimum that starts the sampler: an undetermined
    parameter (singular information, infinite Laplace error), a value within one Laplace error of a
    bound of the prior (the Laplace error is then no interval), a value on a bound of the box."""
    out = []
    lo, hi = problem.lo, problem.hi
    if len(minima) > 1:
        out.append(
            f"{len(minima)} least-squares minima within delta chi2 = {delta_chi2:g} start the "
            "sampler's walkers: "
            + "; ".join(
                f"n={float(f.n):.4g}, kappa={float(f.kappa):.4g}, sigma={float(f.sigma):.4g}"
                for f in minima
            )
            + " (best first; whether the posterior has one mode or more is in the diagnostics)"
        )
    for k, f in enumerate(minima):
        x = np.array([float(f.n), float(f.kappa), float(f.sigma)])[: problem.P]
        err = np.asarray(f.errors, float)[: problem.P]
        names = PARAMETERS[: problem.P]
        who = _describe_minimum(f, k, len(minima))
        undetermined = [nm for j, nm in enumerate(names) if not np.isfinite(err[j])]
        if undetermined:
            why = (
                "; kappa is on its bound 0, where the DOLP is stationary in kappa"
                if "kappa" in undetermined and x[1] <= lo[1]
                else ""
            )
            out.append(
                f"at {who} the data do not determine {', '.join(undetermined)} (singular Fisher "
                f"information{why}): its Laplace error is inf; the intervals are the posterior's"
            )
        near = [
            (nm, x[j], err[j], lo[j] if x[j] - err[j] <= lo[j] else hi[j])
            for j, nm in enumerate(names)
            if np.isfinite(err[j]) and (x[j] - err[j] <= lo[j] or x[j] + err[j] >= hi[j])
        ]
        on = [(nm, b) for nm, v, e, b in near if abs(v - b) <= 1e-9 * (hi - lo)[names.index(nm)]]
        close = [(nm, v, e, b) for nm, v, e, b in near if (nm, b) not in on]
        if on:
            out.append(
                f"at {who} {' and '.join(f'{nm} ends on its prior bound {b:g}' for nm, b in on)}: "
                "the value there is the bound, not an estimate, and its Laplace error ignores the bound"
            )
        if close:
            out.append(
                f"at {who} "
                + " and ".join(f"{nm} = {v:.4g} +/- {e:.2g}" for nm, v, e, _ in close)
                + " (Laplace) lie within one error of the prior bound "
                + " and ".join(f"{nm} = {b:g}" for nm, _, _, b in close)
                + ": the data do not distinguish them from the bound (the information is small, not "
                "singular), and the Laplace error, which ignores the bound, is no interval; the "
                "posterior's interval is cut by the prior there"
            )
    return out


def start_walkers(
    problem: PosteriorProblem, minima: list[DolpFit], n_walkers: int, rng
) -> np.ndarray:
    """Starting positions (n_walkers, D) in sampler coordinates: balls around the least-squares
    minima.

    Parameters
    ----------
    problem : PosteriorProblem
    minima : list of DolpFit
        Least-squares minima (walkers are shared among them in turn); empty: the prior's centre.
    n_walkers : int
    rng : anything :func:`numpy.random.default_rng` accepts

    Returns
    -------
    ndarray (n_walkers, D)
        Starts strictly inside the prior box, D = the sampled dimensions.
    """
    rng = as_rng(rng)
    lo, hi, P, D = problem.lo, problem.hi, problem.P, problem.ndim
    lp = problem.log_post
    x = np.empty((n_walkers, D))
    which = np.arange(n_walkers) % max(len(minima), 1)
    m = int(np.isfinite(problem.dolp).sum())
    for w in range(n_walkers):
        if minima:
            f = minima[which[w]]
            centre = np.array([float(f.n), float(f.kappa), float(f.sigma)])[:P]
            err = np.nan_to_num(np.asarray(f.errors, float), nan=0.0)
        else:
            centre, err = (lo + hi) / 2, (hi - lo) / 4
        width = np.clip(err, 1e-6 * (hi - lo), 0.05 * (hi - lo))
        x[w, :P] = centre + 0.5 * width * rng.standard_normal(P)
        if lp.infers_noise:
            resid = np.sqrt(2 * float(minima[0].cost) / max(m - P, 1)) if minima else 0.01
            resid = np.sqrt(max(resid**2 - float(np.mean(lp.syst2)), resid**2 / 100))
            nb = problem.prior.noise_bounds
            x[w, -1] = (
                np.log(np.clip(resid, nb[0] * 1.01, nb[1] / 1.01)) + 0.1 * rng.standard_normal()
            )
    if lp.log_kappa:
        x[:, 1] = np.log(np.maximum(x[:, 1], KAPPA_FLOOR * 1.01))
    eps = 1e-9 * (lp.hi - lp.lo)
    return np.clip(x, lp.lo + eps, lp.hi - eps)


# -- checkpoints
# -----------------------------------------------------------------------------------------------
def _open_backends(backend, name, problem: PosteriorProblem, options: SamplerOptions):
    """One emcee backend per ensemble (or None), reset or checked against the stored digest.

    Returns (backends, resumed) with ``resumed[k]`` True when ensemble k continues a stored chain.
    """
    import emcee

    E, shape = options.n_ensembles, (options.n_walkers, problem.ndim)
    if backend is None:
        return [None] * E, [False] * E
    if isinstance(backend, (str, Path)):
        Path(backend).parent.mkdir(parents=True, exist_ok=True)
        bes = [
            emcee.backends.HDFBackend(str(backend), name=f"{name}/ensemble_{k}") for k in range(E)
        ]
    else:
        bes = list(backend) if isinstance(backend, (list, tuple)) else [backend]
        if len(bes) != E or not all(isinstance(b, emcee.backends.Backend) for b in bes):
            raise ValueError(f"backend must be a path or {E} emcee backend(s), one per ensemble")
    resumed = []
    for k, be in enumerate(bes):
        digest = problem.digest(options, k)
        if be.initialized and be.iteration > 0:
            where = f"{be.filename}:{be.name}" if hasattr(be, "filename") else f"backend {k}"
            stored = _stored_digest(be)
            if stored != digest and tuple(int(v) for v in be.shape) == shape:
                raise ValueError(
                    f"{where} was written for other data or settings (digest "
                    f"{str(stored)[:12]} != {digest[:12]}: data, geometries, noise, systematic, "
                    "covariance, sigma, priors, walkers or moves differ); resuming would mix two "
                    "posteriors: use another file or group name, or delete it"
                )
            if stored != digest:
                raise ValueError(
                    f"{where} holds a chain of shape {tuple(int(v) for v in be.shape)}, not "
                    f"{shape} "
                    "(other data or settings: other walkers or sampled parameters)"
                )
            resumed.append(True)
        else:
            be.reset(*shape)
            _store_digest(be, digest)
            resumed.append(False)
    return bes, resumed


def _stored_digest(be):
    if hasattr(be, "filename"):
        with be.open() as f:
            return f[be.name].attrs.get("scatterlab_digest")
    return getattr(be, "scatterlab_digest", None)


def _store_digest(be, digest):
    if hasattr(be, "filename"):
        with be.open("a") as f:
            f[be.name].attrs["scatterlab_digest"] = digest
    else:
        be.scatterlab_digest = digest


# -- run until converged
# ----------------------------------------------------------------------------------------
def run_ensembles(
    log_prob, ndim: int, starts, options: SamplerOptions, seeds, backends=None
) -> list:
    """Run ``len(seeds)`` independent emcee ensembles until converged (the *run* piece).

    Parameters
    ----------
    log_prob : callable (W, D) -> (W,)
        Vectorised log posterior.
    ndim : int
    starts : list of arrays (n_walkers, D) or None (None: continue the backend's chain)
    options : SamplerOptions
    seeds : sequence of int -- one per ensemble.
    backends : list of emcee backends or None

    Returns
    -------
    list of emcee.EnsembleSampler
        With ``options.n_steps`` each runs to that length; otherwise all are extended in blocks of
        ``options.block`` until each is ``min_tau_multiple`` tau long, tau is stable to 5 % and the
        between-ensemble R-hat is below 1.01, or ``max_steps`` is reached.
    """
    import emcee
    from threadpoolctl import threadpool_limits

    # the moves' linear algebra is on (walkers x D) matrices: BLAS threads only contend (measured with
    # sample_posterior on a busy 2-core machine: 89 s with OpenBLAS's threads, 8.4 s with one)
    with threadpool_limits(limits=1):
        return _run_ensembles(emcee, log_prob, ndim, starts, options, seeds, backends)


def _run_ensembles(emcee, log_prob, ndim, starts, options, seeds, backends) -> list:
    E = len(seeds)
    backends = backends if backends is not None else [None] * E
    moves = _emcee_moves(options.moves)
    samplers = []
    for k in range(E):
        s = emcee.EnsembleSampler(
            options.n_walkers, ndim, log_prob, vectorize=True, backend=backends[k], moves=moves
        )
        s.random_state = np.random.RandomState(int(seeds[k]) % 2**32).get_state()
        samplers.append(s)
    fixed = options.n_steps is not None
    target = options.n_steps if fixed else options.max_steps
    old_tau = np.inf
    pending = list(starts)
    while True:
        for k, s in enumerate(samplers):
            todo = target - s.iteration if fixed else min(options.block, target - s.iteration)
            if todo > 0:
                s.run_mcmc(
                    pending[k] if s.iteration == 0 else None, todo, progress=options.progress
                )
        if fixed or min(s.iteration for s in samplers) >= target:
            return samplers
        with np.errstate(
            invalid="ignore", divide="ignore"
        ):  # a constant chain: tau NaN, not converged
            tau = np.array([s.get_autocorr_time(tol=0) for s in samplers])  # (E, D)
        steps = min(s.iteration for s in samplers)
        burn = int(min(np.ceil(2 * np.max(tau)), steps // 2))
        chain = np.concatenate(
            [s.get_chain(discard=burn)[: steps - burn] for s in samplers], axis=1
        )
        agree = np.all(ensemble_rhat(chain, E) < RHAT_MAX)
        stable = np.all(np.abs(old_tau - tau) < 0.05 * tau)
        if steps >= options.min_tau_multiple * np.max(tau) and stable and agree:
            return samplers
        old_tau = tau


# -- diagnose
# --------------------------------------------------------------------------------------------------
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
    return [
        {"weight": float(counts[k] / W), "median": np.median(walker_medians[labels == k], 0)}
        for k in np.argsort(-counts)
    ]


def _physical_chain(problem: PosteriorProblem, x):
    """Sampler coordinates (S, W, D) -> chain (S, W, 3) and noise chain (S, W) or None."""
    S, W, D = x.shape
    p, s = problem.log_post.physical(x.reshape(-1, D))
    chain = np.empty((S * W, 3))
    chain[:, : problem.P] = p
    if problem.sigma is not None:
        chain[:, 2] = problem.sigma
    return chain.reshape(S, W, 3), None if s is None else s.reshape(S, W)


def _sampled(problem, chain, noise_chain):
    """The sampled coordinates (..., D') in physical units and their names."""
    names = list(PARAMETERS[: problem.P]) + (["noise"] if noise_chain is not None else [])
    x = chain[..., : problem.P]
    return (x if noise_chain is None else np.concatenate([x, noise_chain[..., None]], -1)), names


def _convergence(n_steps, tmax, acceptance, rhat, options, E) -> list[str]:
    """Reasons why the run is not converged (empty when it is)."""
    out = []
    if not n_steps >= options.min_tau_multiple * tmax:
        out.append(
            f"chain of {n_steps} steps is shorter than {options.min_tau_multiple:g} "
            "autocorrelation times "
            f"(tau = {tmax:.1f}); quantiles may be off: run longer (n_steps or max_steps)"
        )
    if not np.all((acceptance >= ACCEPTANCE[0]) & (acceptance <= ACCEPTANCE[1])):
        out.append(
            f"acceptance fraction(s) {np.round(acceptance, 2).tolist()} outside {list(ACCEPTANCE)}"
        )
    if not np.all(rhat < RHAT_MAX):
        what = (
            f"between the {E} independent ensembles"
            if E > 1
            else "between the halves of the one ensemble"
        )
        out.append(
            f"R-hat {np.round(rhat, 3).tolist()} {what} is not below {RHAT_MAX}: the chains "
            "disagree "
            "(other modes or too short)"
        )
    return out


def diagnose(
    problem: PosteriorProblem,
    samplers: list,
    options: SamplerOptions,
    minima: list,
    messages: list,
    rng,
    seconds: float = float("nan"),
) -> Posterior:
    """Burn-in, thinning, tau, ESS, between-ensemble R-hat, acceptance and modes ->
    :class:`Posterior`.

    Parameters
    ----------
    problem : PosteriorProblem
    samplers : list of emcee.EnsembleSampler
        The finished ensembles.
    options : SamplerOptions
    minima : list of DolpFit
        The least-squares minima that seeded the walkers.
    messages : list of str
        Notes collected so far (copied, not changed).
    rng : numpy.random.Generator
        Seeds the clustering of walkers into modes.
    seconds : float
        Sampling time [s] to record.

    Returns
    -------
    Posterior
        Thinned chains in physical units, tau, ESS, R-hat, acceptance, modes and messages.
    """
    E = len(samplers)
    n_steps = min(s.iteration for s in samplers)
    with np.errstate(invalid="ignore", divide="ignore"):  # a walker set that never moved: NaN
        tau = np.max([s.get_autocorr_time(tol=0) for s in samplers], axis=0)  # (D,), the slowest
    finite = np.isfinite(tau)
    # a NaN tau (a walker set that never moved) gives no burn-in estimate: discard half and say so
    tmax = float(np.max(tau[finite])) if finite.any() else float(n_steps)
    burn = int(min(np.ceil(2 * tmax), n_steps // 2))
    thin = max(1, int(tmax // 2))
    kept = len(range(burn + thin - 1, n_steps, thin))
    x = np.concatenate([s.get_chain(discard=burn, thin=thin)[:kept] for s in samplers], axis=1)
    lp = np.concatenate([s.get_log_prob(discard=burn, thin=thin)[:kept] for s in samplers], axis=1)
    raw = np.concatenate([s.get_chain(discard=burn)[: n_steps - burn] for s in samplers], axis=1)
    chain, noise_chain = _physical_chain(problem, x)
    raw_phys, _ = _sampled(problem, *_physical_chain(problem, raw))
    ess = effective_sample_size(raw_phys)
    rhat = ensemble_rhat(raw_phys, E)
    acceptance = np.array([np.mean(s.acceptance_fraction) for s in samplers])
    reasons = _convergence(n_steps, tmax, acceptance, rhat, options, E)
    if not finite.all():
        reasons.append("autocorrelation time undefined (NaN) for some parameter: not converged")
    messages = list(messages) + reasons
    half = chain[chain.shape[0] // 2 :, :, : problem.P]
    modes = _clusters(np.median(half, 0), np.sqrt(np.mean(np.var(half, 0), 0)), rng)
    for m in modes:
        if problem.sigma is not None:
            m["median"] = np.r_[m["median"], problem.sigma]
        m["median"] = np.asarray(m["median"], float)
    if len(minima) > 1 and len(modes) == 1:
        messages.append(
            f"the posterior has one mode: the walkers started at the {len(minima)} least-squares "
            "minima above mixed into one cluster (the minima are dips within one posterior mode, "
            "not separate modes)"
        )
    if len(modes) > 1:
        messages.append(
            "multimodal posterior: "
            + "; ".join(
                f"{m['weight']:.0%} of walkers near n={m['median'][0]:.4g}, "
                f"kappa={m['median'][1]:.4g}"
                for m in modes
            )
        )
    b = dict(DEFAULT_BOUNDS, **(problem.prior.bounds or {}))
    return Posterior(
        chain=chain,
        noise_chain=noise_chain,
        log_prob=lp,
        tau=tau,
        n_steps=int(n_steps),
        burn=burn,
        thin=thin,
        acceptance=float(np.mean(acceptance)),
        rhat=rhat,
        converged=not reasons,
        modes=modes,
        least_squares=minima,
        dolp=problem.dolp,
        theta_i=problem.theta_i,
        theta_r=problem.theta_r,
        phi=problem.phi,
        noise=problem.noise,
        sigma_known=problem.sigma,
        kappa_prior=problem.prior.kappa_prior,
        bounds={k: list(v) for k, v in b.items()},
        model_kw=dict(problem.model_kw),
        messages=messages,
        seconds=seconds,
        n_ensembles=E,
        ess=ess,
        convergence_reason="; ".join(reasons),
        systematic=problem.systematic,
        covariance=problem.covariance,
        noise_bounds=tuple(problem.prior.noise_bounds) if problem.log_post.infers_noise else None,
        correlated=problem.correlated,
    )


# -- the result
# --------------------------------------------------------------------------------------------------
@dataclass
class Posterior:
    """Posterior samples of (n, kappa, sigma) for one measurement vector, with diagnostics.

    Attributes
    ----------
    chain : ndarray (steps, n_ensembles * walkers, 3)
        Kept samples (after burn-in and thinning) of (n, kappa, sigma); sigma is constant when it
        was known.
        The walkers of ensemble k are the k-th contiguous block of axis 1.
    noise_chain : ndarray (steps, walkers) or None
        Samples of the DOLP noise level when it was a parameter.
    log_prob : ndarray (steps, walkers)
    tau : ndarray (D,) -- integrated autocorrelation time [steps] of the sampled coordinates
    (slowest ensemble).
    n_steps, burn, thin : int
    acceptance : float -- mean acceptance fraction.
    rhat : ndarray (D,) -- R-hat between the independent ensembles (:func:`ensemble_rhat`) of the
    sampled
        parameters (n, kappa[, sigma][, noise]).
    converged : bool -- run length >= min_tau_multiple * tau, acceptance in [0.15, 0.7] and R-hat <
    1.01;
        ``convergence_reason`` says what failed.
    modes : list of dict -- ``{"weight", "median": (3,)}`` per cluster of walkers; two or more:
    multimodal.
    least_squares : list of DolpFit -- the least-squares minima the walkers started from (best
    first).
    dolp, theta_i, theta_r, phi : the data and geometries.
    noise : float or None; sigma_known : float or None; kappa_prior : str; bounds : dict
    messages : list of str -- warnings raised during sampling, kept for the report.
    seconds : float -- wall time of the sampling.
    n_ensembles : int
    ess : ndarray (D,) -- effective sample size per sampled parameter
    (:func:`effective_sample_size`).
    systematic : ndarray (M,) or None; covariance : ndarray (M, M) or None -- the error model.
    noise_bounds : (low, high) or None -- prior range of the inferred noise (None when it was not
    inferred).
    correlated : ndarray (M,) or None -- the error shared by the whole series.
    fit_check : dict or None -- :meth:`goodness_of_fit` as computed when sampling (None with an
    inferred noise, or for a posterior built by hand).
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
    n_ensembles: int = 1
    ess: np.ndarray | None = None
    convergence_reason: str = ""
    systematic: np.ndarray | None = None
    covariance: np.ndarray | None = None
    noise_bounds: tuple | None = None
    correlated: np.ndarray | None = None
    fit_check: dict | None = None

    @property
    def samples(self) -> np.ndarray:
        """All kept samples flattened, (N, 3)."""
        return self.chain.reshape(-1, 3)

    @property
    def multimodal(self) -> bool:
        return len(self.modes) > 1

    @property
    def sampled_names(self) -> list[str]:
        """Names of the sampled parameters, the order of ``tau``, ``rhat`` and ``ess``."""
        P = 2 if self.sigma_known is not None else 3
        return list(PARAMETERS[:P]) + (["noise"] if self.noise_chain is not None else [])

    @property
    def n_effective(self) -> float:
        """Smallest effective sample size over the sampled parameters."""
        if self.ess is not None and np.any(np.isfinite(self.ess)):
            return float(np.nanmin(self.ess))
        return float(self.chain.shape[1] * (self.n_steps - self.burn) / np.max(self.tau))

    def quantiles(self, q) -> np.ndarray:
        """Quantiles ``q`` (K,) of each parameter -> (K, 3)."""
        return np.quantile(self.samples, q, axis=0)

    def interval(self, level: float = 0.68) -> np.ndarray:
        """Equal-tailed credible interval, (2, 3): lower and upper bounds of n, kappa, sigma.

        These are marginal *credible* intervals, one per parameter. For a fixed truth in a weakly identified
        problem they are not confidence intervals and can under-cover badly: in ``studies/thilak_tables.py``
        they contain copper in 0-4 % of trials at 68 %, where truths drawn from the prior are covered at
        the nominal rate and the likelihood-ratio region covers copper at 67-78 %.

        Parameters
        ----------
        level : float
            Credible level in (0, 1).

        Returns
        -------
        ndarray, shape (2, 3)
        """
        a = (1 - level) / 2
        return self.quantiles([a, 1 - a])

    def contraction(self) -> np.ndarray:
        r"""Posterior contraction of n, kappa, sigma (3,): :math:`1 - \mathrm{var}_{post} /
        \mathrm{var}_{prior}`.

        Near 1 the data determine the parameter; near 0 its interval is the prior's. The prior
        variance is that of the uniform (or log-uniform, for kappa with ``kappa_prior="log-uniform"``)
        prior on :attr:`bounds`; a known sigma has contraction 1.

        Returns
        -------
        ndarray, shape (3,)
        """
        prior_var = np.empty(3)
        for k, name in enumerate(PARAMETERS):
            lo, hi = self.bounds[name]
            if name == "kappa" and self.kappa_prior == "log-uniform":
                lo = max(lo, KAPPA_FLOOR)
                span = np.log(hi / lo)
                m1, m2 = (hi - lo) / span, (hi**2 - lo**2) / (2 * span)
                prior_var[k] = m2 - m1**2
            else:
                prior_var[k] = (hi - lo) ** 2 / 12
        out = 1.0 - np.var(self.samples, axis=0) / prior_var
        if self.sigma_known is not None:
            out[2] = 1.0
        return out

    def likelihood_ratio(self, points) -> np.ndarray:
        r"""Likelihood-ratio statistic of parameter points against the best fit within the prior box.

        :math:`\Delta(p) = 2\,[\max_q \log L(q) - \log L(p)]`, with an inferred noise profiled out
        (maximised over its prior range :attr:`noise_bounds`) at each point. By Wilks' theorem
        :math:`\Delta` at the truth is close to :math:`\chi^2_P` (with an inferred noise, see
        :meth:`region_threshold`), so :meth:`confidence_region` :math:`\{p : \Delta(p) \le t\}`
        covers a *fixed* truth at its nominal rate -- also where the data determine only a
        combination of n and kappa and the marginal credible intervals of :meth:`interval` follow
        the prior (see :meth:`contraction`). The best fit is the chain's and the least-squares
        minima's best point, polished by Nelder-Mead.

        Parameters
        ----------
        points : array (K, P) or (P,)
            (n, kappa) when sigma was known, (n, kappa, sigma) when it was sampled.

        Returns
        -------
        ndarray, shape (K,), or float
            :math:`\Delta` (dimensionless, >= 0); ``inf`` outside the prior box.
        """
        P = 2 if self.sigma_known is not None else 3
        pts = np.asarray(points, float)
        single = pts.ndim == 1
        pts = np.atleast_2d(pts)
        if pts.shape[-1] != P:
            raise ValueError(f"points must have {P} columns (n, kappa[, sigma]), got {pts.shape}")
        lo = np.array([self.bounds[name][0] for name in PARAMETERS[:P]])
        hi = np.array([self.bounds[name][1] for name in PARAMETERS[:P]])
        nll = self._profile_nll(P)
        _, best = self._best_fit(nll, P, lo, hi)
        inside = np.all((pts >= lo) & (pts <= hi), axis=1)
        out = np.full(pts.shape[0], np.inf)
        if inside.any():
            out[inside] = np.maximum(2.0 * (nll(pts[inside]) - best), 0.0)
        return float(out[0]) if single else out

    def _best_fit(self, nll, P, lo, hi):
        """The point of largest likelihood in the prior box, (P,), and its negative log likelihood:
        the chain's and the least-squares minima's best point, polished by Nelder-Mead."""
        from scipy.optimize import minimize

        starts = [self.samples[np.argmax(self.log_prob.ravel()), :P]]
        starts += [np.array([f.n, f.kappa, f.sigma][:P], float).ravel() for f in self.least_squares]
        values = nll(np.stack(starts))
        x0, best = starts[int(np.argmin(values))], float(np.min(values))

        def boxed(x):
            return float(nll(x[None])[0]) if np.all((x >= lo) & (x <= hi)) else np.inf

        polished = minimize(boxed, x0, method="Nelder-Mead", options={"xatol": 1e-9, "fatol": 1e-9})
        if float(polished.fun) < best:
            return np.asarray(polished.x, float), float(polished.fun)
        return np.asarray(x0, float), best

    def goodness_of_fit(self) -> dict | None:
        r"""Whether the data fit the model within their stated errors: the best fit's chi-square.

        :math:`\chi^2 = r^T V^{-1} r` at the point of largest likelihood in the prior box, with
        :math:`V` the likelihood's error covariance (noise, ``systematic``, ``correlated``,
        ``covariance``), and its p-value against :math:`\chi^2_{M-P}` (M measured geometries, P fitted
        parameters; a best fit held by the prior box makes it conservative). A p-value below
        :data:`FIT_P_MIN` says the errors are understated, the geometry is wrong (angles in other units,
        a wrong azimuth) or the model misses an error term: the intervals, which take the stated errors
        as true, are then too narrow. With an inferred noise the noise absorbs any misfit and there is
        nothing to test.

        Returns
        -------
        dict or None
            ``{"chi2": float, "dof": int, "p_value": float}``; None with an inferred noise or when there
            are no more geometries than parameters (``dof`` < 1).
        """
        from scipy import stats

        P = 2 if self.sigma_known is not None else 3
        M = int(np.isfinite(self.dolp).sum())
        if self.noise_bounds is not None or M - P < 1:
            return None
        lo = np.array([self.bounds[name][0] for name in PARAMETERS[:P]])
        hi = np.array([self.bounds[name][1] for name in PARAMETERS[:P]])
        forward, like = self._likelihood(P)

        def nll(x):
            return -like.log_likelihood(forward(np.asarray(x, float)[:, :P]), None)

        x, _ = self._best_fit(nll, P, lo, hi)
        chi2 = float(like.chi2(forward(x[None]))[0])
        return {"chi2": chi2, "dof": M - P, "p_value": float(stats.chi2.sf(chi2, M - P))}

    def confidence_region(self, points, level: float = 0.68):
        """Whether points lie in the joint likelihood-ratio confidence region at ``level``
        (:meth:`likelihood_ratio`).

        Parameters
        ----------
        points : array (K, P) or (P,)
            (n, kappa[, sigma]).
        level : float
            Confidence level in (0, 1).

        Returns
        -------
        ndarray of bool, shape (K,), or bool
        """
        inside = np.asarray(self.likelihood_ratio(points)) <= self.region_threshold(level)
        return bool(inside) if inside.ndim == 0 else inside

    def region_threshold(self, level: float = 0.68) -> float:
        r"""Threshold of :meth:`likelihood_ratio` for the joint confidence region at ``level``.

        With a known error model, :math:`\chi^2_P(\text{level})`. With an inferred noise the profiled
        statistic is :math:`\Delta = M \log(1 + \tfrac{P}{M-P} F)` with :math:`F \sim F(P, M - P)`
        (exact for a linear model with unknown variance; Wilks' :math:`\chi^2_P` holds only for
        :math:`M \gg P` and under-covers with four geometries: 38 % at 68 % for a paint, against 68 %
        with this threshold), so the threshold is that of :math:`F`.

        Parameters
        ----------
        level : float
            Confidence level in (0, 1).

        Returns
        -------
        float
            Threshold on :math:`\Delta` (dimensionless).
        """
        from scipy import stats

        if not 0 < level < 1:
            raise ValueError(f"level must be in (0, 1), got {level!r}")
        P = 2 if self.sigma_known is not None else 3
        if self.noise_bounds is None:
            return float(stats.chi2.ppf(level, P))
        M = int(np.isfinite(self.dolp).sum())
        return float(M * np.log1p(P / (M - P) * stats.f.ppf(level, P, M - P)))

    def _likelihood(self, P: int):
        """The forward model of the data's geometries and the likelihood of the posterior's error
        model (sigma fixed when it was known)."""
        sigma = self.sigma_known
        forward = DolpForward(self.theta_i, self.theta_r, self.phi, sigma=sigma, **self.model_kw)
        like = DolpLogPosterior(
            forward,
            np.asarray(self.dolp, float),
            None,
            None,
            fit_sigma=sigma is None,
            log_kappa=False,
            noise=self.noise if self.noise_bounds is None else None,
            systematic=self.systematic,
            covariance=self.covariance,
            correlated=self.correlated,
        )
        return forward, like

    def _profile_nll(self, P: int):
        """Negative log likelihood of points (K, P), an inferred noise maximised out on a fine grid of
        its log-uniform range (512 steps: the profile is within 1e-3 of its maximum)."""
        forward, like = self._likelihood(P)
        grid = None
        if like.infers_noise:
            grid = np.geomspace(*self.noise_bounds, 512)

        def nll(x):
            f = forward(np.asarray(x, float)[:, :P])
            if grid is None:
                return -like.log_likelihood(f, None)
            # every (point, noise) pair in one vectorised call: rows point-major, (K * G, M)
            ll = like.log_likelihood(np.repeat(f, grid.size, axis=0), np.tile(grid, len(f)))
            return -ll.reshape(len(f), grid.size).max(1)

        return nll

    def data_error(self) -> np.ndarray:
        """Standard deviation (M,) of the DOLP errors of the likelihood (noise median with an
        inferred noise)."""
        syst2 = 0.0 if self.systematic is None else self.systematic**2
        if self.correlated is not None:
            syst2 = syst2 + self.correlated**2
        if self.covariance is not None:
            return np.sqrt(np.diag(self.covariance) + syst2)
        s = self.noise if self.noise is not None else float(np.median(self.noise_chain))
        return np.sqrt(s**2 + syst2) * np.ones(self.dolp.size)

    def summary(self) -> dict:
        """Medians, 68 % and 95 % credible intervals, mean and std per parameter, with the
        least-squares
        value and its Laplace standard error beside them, ESS and R-hat of the sampled ones, and the
        diagnostics (JSON-ready)."""
        q = self.quantiles([0.025, 0.16, 0.5, 0.84, 0.975])
        ls = self.least_squares[0] if self.least_squares else None
        ess = dict(
            zip(
                self.sampled_names,
                np.asarray(
                    self.ess if self.ess is not None else np.full(len(self.sampled_names), np.nan)
                ).tolist(),
            )
        )
        rhat = dict(zip(self.sampled_names, np.asarray(self.rhat).tolist()))
        params = {}
        for k, name in enumerate(PARAMETERS):
            entry = {
                "median": q[2, k],
                "ci68": [q[1, k], q[3, k]],
                "ci95": [q[0, k], q[4, k]],
                "mean": float(self.samples[:, k].mean()),
                "std": float(self.samples[:, k].std()),
            }
            if ls is not None:
                entry["least_squares"] = float(getattr(ls, name))
                P = ls.covariance.shape[-1]
                entry["laplace_error"] = float(ls.errors[k]) if k < P else 0.0
            if name in ess:
                entry["ess"], entry["rhat"] = ess[name], rhat[name]
            params[name] = entry
        if self.noise_chain is not None:
            nq = np.quantile(self.noise_chain, [0.025, 0.16, 0.5, 0.84, 0.975])
            params["noise"] = {
                "median": nq[2],
                "ci68": [nq[1], nq[3]],
                "ci95": [nq[0], nq[4]],
                "ess": ess["noise"],
                "rhat": rhat["noise"],
            }
        return {
            "parameters": params,
            "diagnostics": self._diagnostics(ess),
            "prior": self._prior(),
            "goodness_of_fit": None if self.fit_check is None else dict(self.fit_check),
            "messages": list(self.messages),
        }

    def _diagnostics(self, ess) -> dict:
        return {
            "n_steps": self.n_steps,
            "burn": self.burn,
            "thin": self.thin,
            "walkers": int(self.chain.shape[1]),
            "n_ensembles": self.n_ensembles,
            "tau": self.tau.tolist(),
            "steps_over_tau": float(self.n_steps / np.max(self.tau)),
            "acceptance": self.acceptance,
            "rhat": np.asarray(self.rhat).tolist(),
            "rhat_method": "split R-hat between independent ensembles pooled over walkers",
            "ess": ess,
            "n_effective": self.n_effective,
            "converged": self.converged,
            "convergence_reason": self.convergence_reason,
            "multimodal": self.multimodal,
            "modes": [{"weight": m["weight"], "median": list(m["median"])} for m in self.modes],
            "seconds": self.seconds,
        }

    def _prior(self) -> dict:
        noise = (
            "covariance"
            if self.covariance is not None
            else "known"
            if self.noise is not None
            else "log-uniform parameter"
        )
        return {
            "kappa": self.kappa_prior,
            "bounds": self.bounds,
            "noise": noise,
            "systematic": None if self.systematic is None else self.systematic.tolist(),
        }

    def to_inference_data(self):
        """The kept chains as an ArviZ ``InferenceData`` (chains = walkers, draws = kept steps).

        Variables n, kappa, sigma (and noise when inferred); ``sample_stats.lp`` the log posterior;
        attrs
        ``n_ensembles``, ``walkers_per_ensemble``, ``burn``, ``thin``. Note that ArviZ's R-hat over
        walkers
        treats them as independent chains, which the walkers of one ensemble are not:
        ``Posterior.rhat``
        compares the ensembles.
        """
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            import arviz as az

        post = {name: self.chain[..., k].T for k, name in enumerate(PARAMETERS)}
        if self.noise_chain is not None:
            post["noise"] = self.noise_chain.T
        attrs = {
            "n_ensembles": self.n_ensembles,
            "walkers_per_ensemble": self.chain.shape[1] // self.n_ensembles,
            "burn": self.burn,
            "thin": self.thin,
            "converged": int(self.converged),
        }
        idata = az.from_dict(
            posterior=post,
            sample_stats={"lp": self.log_prob.T},
            observed_data={"dolp": self.dolp},
            dims={"dolp": ["geometry"]},
            attrs=attrs,
        )
        idata.posterior.attrs.update(attrs)
        return idata

    def predictive(
        self,
        rng=None,
        n_draws: int = 200,
        *,
        theta_i=None,
        theta_r=None,
        phi=None,
        with_noise: bool = False,
    ) -> np.ndarray:
        """Posterior-predictive DOLP (n_draws, M') at the data's geometries or at new ones.

        ``rng`` is anything :func:`numpy.random.default_rng` accepts. ``with_noise`` adds the
        likelihood's
        errors (only at the data's geometries when a systematic or covariance is part of it).
        """
        rng = as_rng(rng)
        new = theta_i is not None or theta_r is not None or phi is not None
        ti = self.theta_i if theta_i is None else np.atleast_1d(theta_i)
        tr = self.theta_r if theta_r is None else np.atleast_1d(theta_r)
        ph = self.phi if phi is None else np.broadcast_to(phi, ti.shape)
        idx = rng.integers(0, self.samples.shape[0], n_draws)
        y = DolpForward(ti, tr, ph, **self.model_kw)(self.samples[idx])
        if with_noise:
            if new and any(
                e is not None for e in (self.systematic, self.covariance, self.correlated)
            ):
                raise ValueError(
                    "with_noise at new geometries is undefined with a systematic, covariance or "
                    "correlated error"
                )
            if self.correlated is not None:
                y = y + rng.standard_normal(y.shape[:-1] + (1,)) * self.correlated
            if self.covariance is not None:
                C = self.covariance + np.diag(
                    0.0 if self.systematic is None else self.systematic**2
                )
                return y + rng.standard_normal(y.shape) @ np.linalg.cholesky(C).T
            s = (
                self.noise
                if self.noise is not None
                else self.noise_chain.ravel()[idx % self.noise_chain.size]
            )
            syst2 = 0.0 if self.systematic is None else self.systematic**2
            y = y + np.sqrt(np.asarray(s)[..., None] ** 2 + syst2) * rng.standard_normal(y.shape)
        return y


# -- the entry points
# ------------------------------------------------------------------------------------------------
def sample_posterior(
    dolp,
    theta_i,
    theta_r,
    noise=None,
    rng=None,
    *,
    phi=np.pi,
    sigma=None,
    systematic=None,
    covariance=None,
    correlated=None,
    prior: PriorOptions | None = None,
    sampler: SamplerOptions | None = None,
    backend=None,
    name: str = "posterior",
    **options,
) -> Posterior:
    r"""Sample the posterior of (n, kappa, sigma) given DOLP at M geometries.

    Three pieces: *start* (:func:`posterior_problem`, the least-squares minima, :func:`start_walkers`),
    *run until converged* (:func:`run_ensembles`) and *diagnose* (:func:`diagnose`).

    Parameters
    ----------
    dolp : array (M,)
        Measured DOLP in [0, 1] (a margin of ``max(0.05, 5 x the known error)`` is allowed for
        noise); NaN entries are masked. For many problems use :func:`sample_posteriors`.
    theta_i, theta_r : array (M,) [rad]
    noise : float or None
        DOLP noise standard deviation (> 0); ``None`` makes it a parameter (log-uniform on
        ``noise_bounds``), unless ``covariance`` is given.
    rng : anything :func:`numpy.random.default_rng` accepts
        Seeds the walkers' starts and emcee's moves (one seed per ensemble).
    phi : float or array (M,) [rad], default pi
    sigma : float, optional
        Known roughness (then only n and kappa are sampled).
    systematic : float or array (M,), optional
        Known systematic DOLP error standard deviation per geometry, added in quadrature; in
        ``[0, 1]``.
    covariance : array (M, M), optional
        Full DOLP error covariance (correlated errors across geometries), used instead of ``noise``:
        symmetric positive definite, variances <= 1 and eigenvalues >= 1e-24 (standard deviations
        in the range of ``noise``).
    correlated : array (M,), optional
        One error shared by the whole series [DOLP] (a correction's scale error), with any of the
        above: adds :math:`c\,c^\mathsf{T}` to the error covariance. Finite, ``|c| <= 1``.
    prior : PriorOptions, optional
        Or the keywords ``bounds``, ``kappa_prior``, ``noise_bounds``.
    sampler : SamplerOptions, optional
        Or the keywords ``n_walkers``, ``n_ensembles``, ``n_steps``, ``max_steps``, ``block``,
        ``min_tau_multiple``, ``moves`` (a shortcut string or emcee move objects), ``starts``,
        ``mode_delta_chi2``, ``progress``.
    backend : path, emcee backend or list of them, optional
        HDF5 file for emcee's backend (checkpoint and resume; group ``<name>/ensemble_<k>``), or
        emcee backend objects, one per ensemble. Resuming with other data or settings is a
        ValueError.
    name : str
        HDF5 group of the chains.
    **options
        The prior and sampler keywords above, and ``shadowing``, ``diffuse``, ``distribution``
        passed to :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    Posterior
        A :class:`ConvergenceWarning` is raised (and kept in ``messages``) when it is not converged.
    """
    rng = as_rng(rng)
    prior, opts, model_kw = _resolve_options(prior, sampler, dict(options))
    given = dict(
        phi=phi,
        sigma=sigma,
        systematic=systematic,
        covariance=covariance,
        correlated=correlated,
        prior=prior,
    )
    problem = posterior_problem(dolp, theta_i, theta_r, noise, model_kw=model_kw, **given)
    opts.validate(problem.ndim)
    backends, resumed = _open_backends(backend, name, problem, opts)
    messages: list[str] = []
    minima = _problem_minima(problem, opts, messages)
    starts = [None if r else start_walkers(problem, minima, opts.n_walkers, rng) for r in resumed]
    seeds = rng.integers(2**32, size=opts.n_ensembles)
    t0 = time.perf_counter()
    try:
        samplers = run_ensembles(problem.log_post, problem.ndim, starts, opts, seeds, backends)
    except np.linalg.LinAlgError as err:
        if backend is not None or opts.moves != "kde":
            raise
        # the KDE move's covariance of one half of the walkers is singular when they lie in a lower-
        # dimensional subspace (few walkers: 2 of 10 runs with 8 walkers for 3 parameters): one rerun
        # with differential-evolution moves, which need no covariance
        opts = replace(opts, moves="de")
        starts = [start_walkers(problem, minima, opts.n_walkers, rng) for _ in resumed]
        seeds = rng.integers(2**32, size=opts.n_ensembles)
        samplers = run_ensembles(problem.log_post, problem.ndim, starts, opts, seeds, backends)
        messages.append(f"emcee's KDE move failed ({type(err).__name__}); rerun with DE moves")
    post = diagnose(problem, samplers, opts, minima, messages, rng, time.perf_counter() - t0)
    if not post.converged:
        warnings.warn(post.convergence_reason, ConvergenceWarning, stacklevel=2)
    _check_fit(post)
    return post


def _check_fit(post: Posterior) -> None:
    """Store :meth:`Posterior.goodness_of_fit` in ``post.fit_check``; a misfit becomes a message and a
    :class:`MisfitWarning`."""
    post.fit_check = post.goodness_of_fit()
    g = post.fit_check
    if g is None or not g["p_value"] < FIT_P_MIN:
        return
    text = (
        f"the data do not fit the model within their stated errors: chi-square {g['chi2']:.4g} for "
        f"{g['dof']} degrees of freedom (p = {g['p_value']:.1e} < {FIT_P_MIN:g}), so the intervals, which "
        "take those errors as true, are too narrow; check the noise level, the geometry (angles in "
        "radians, phi = pi in the specular plane) and the model error (systematic=, or noise=None to "
        "infer the noise)"
    )
    post.messages.append(text)
    warnings.warn(text, MisfitWarning, stacklevel=3)


def _sample_task(task):
    y, seed, args, kw = task
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # kept in Posterior.messages
        warnings.simplefilter("ignore", MisfitWarning)  # kept too
        try:
            return sample_posterior(y, *args, rng=np.random.default_rng(seed), **kw)
        except (ValueError, np.linalg.LinAlgError) as err:
            # emcee's KDE move can meet a singular walker covariance, and a move can propose a NaN
            # parameter (both seen once in 576 problems of studies/dolp_vs_mom.py): one rerun from another
            # seed with differential-evolution moves. Invalid input raises the same error again.
            if kw.get("backend") is not None:
                raise
            sampler = kw.get("sampler")
            retry = (
                dict(kw, sampler=replace(sampler, moves="de"))
                if sampler is not None
                else dict(kw, moves="de")
            )
            post = sample_posterior(y, *args, rng=np.random.default_rng([seed, 1]), **retry)
            post.messages.append(
                f"first run failed ({type(err).__name__}: {err}); rerun with DE moves"
            )
            return post


def _per_problem(value, k, ndim_shared):
    """Row k of a per-problem array (one more axis than the shared form), or the shared value."""
    if value is None or np.ndim(value) <= ndim_shared:
        return value
    return np.asarray(value)[k]


def sample_posteriors(
    dolp,
    theta_i,
    theta_r,
    noise=None,
    rng=None,
    *,
    executor=None,
    backend=None,
    systematic=None,
    covariance=None,
    correlated=None,
    bounds=None,
    **kw,
) -> list[Posterior]:
    """:func:`sample_posterior` for each row of ``dolp`` (K, M) -- regions or pixels -- through an
    executor.

    Each problem gets its own seed drawn from ``rng`` (anything :func:`numpy.random.default_rng`
    accepts), so
    results do not depend on the executor. ``systematic`` may be (M,) shared or (K, M) per problem,
    and
    ``covariance`` (M, M) shared or (K, M, M). With ``backend`` (a directory) problem k is
    checkpointed in
    ``backend/problem_k.h5``. Convergence warnings are collected in each posterior's ``messages``
    rather than
    raised.

    Parameters
    ----------
    dolp : array (K, M)
        One measurement vector per problem.
    theta_i, theta_r : array (M,) [rad]
    noise : float or None
        As in :func:`sample_posterior`.
    rng : anything :func:`numpy.random.default_rng` accepts
    executor : Executor, optional
        From :func:`scatterlab.runtime.get_executor` (default serial).
    backend : path, optional
        Directory for one HDF5 checkpoint per problem.
    systematic : float, array (M,) or (K, M), optional
    covariance : array (M, M) or (K, M, M), optional
    correlated : array (M,) or (K, M), optional
    bounds : dict or sequence of K dicts (or None), optional
        Uniform prior ranges (as in :func:`sample_posterior`), shared or one per problem.
    **kw
        Other keywords of :func:`sample_posterior`.

    Returns
    -------
    list of Posterior
        One per row of ``dolp``, in order.
    """
    from scatterlab.runtime import get_executor

    rng = as_rng(rng)
    y = np.atleast_2d(np.asarray(dolp, float))
    empty = np.flatnonzero(~np.any(np.isfinite(y), axis=-1))
    if empty.size:  # refused here, before the batch is dispatched, instead of failing in a worker
        raise ValueError(
            f"dolp has {empty.size} problem(s) without a finite value (rows {empty[:10].tolist()}): "
            "a region without light has no posterior; leave those rows out"
        )
    seeds = rng.integers(2**63, size=y.shape[0])
    per_problem_bounds = isinstance(bounds, (list, tuple))
    if per_problem_bounds and len(bounds) != y.shape[0]:
        raise ValueError(
            f"bounds must be one dict or {y.shape[0]} (one per problem), got {len(bounds)}"
        )
    tasks = []
    for k, row in enumerate(y):
        kk = dict(
            kw,
            systematic=_per_problem(systematic, k, 1),
            covariance=_per_problem(covariance, k, 2),
            correlated=_per_problem(correlated, k, 1),
        )
        b = bounds[k] if per_problem_bounds else bounds
        if b is not None:
            kk["bounds"] = b
        if (
            backend is not None
        ):  # one file per problem: HDF5 files are not safe for concurrent writers
            kk.update(backend=str(Path(backend) / f"problem_{k}.h5"), name="posterior")
        tasks.append((row, int(seeds[k]), (theta_i, theta_r, noise), kk))
    ex = executor if executor is not None else get_executor("serial")
    posts = ex.map(_sample_task, tasks, desc="posteriors")
    bad = [p for p in posts if not p.converged]
    if bad:
        # each posterior keeps its reasons in ``messages``; one warning says that some exist
        warnings.warn(
            f"{len(bad)} of {len(posts)} posteriors not converged (see Posterior.messages)",
            ConvergenceWarning,
            stacklevel=2,
        )
    misfit = [p for p in posts if p.fit_check is not None and p.fit_check["p_value"] < FIT_P_MIN]
    if misfit:
        warnings.warn(
            f"{len(misfit)} of {len(posts)} posteriors: the data do not fit the model within their "
            f"stated errors (chi-square p < {FIT_P_MIN:g}; see Posterior.messages)",
            MisfitWarning,
            stacklevel=2,
        )
    return posts
