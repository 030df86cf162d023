r"""Fit of the pBRDF's (n, kappa, sigma) to a measured Mueller BRDF (16 elements, any geometry).

The data are a :class:`scatterlab.io.MuellerBRDF` (from :func:`scatterlab.io.read_mueller_brdf`): N
geometries ``(theta_i, theta_r, phi)`` in and out of the plane of incidence at one wavelength. The
model is :class:`scatterlab.pbrdf.Model` (Eq. 177): a specular microfacet term :math:`\Gamma\mathbf
M` and, by default, Hyde's diffuse term :math:`D M_{00}\mathbf e_{00}`.

Residuals, per geometry ``g`` and element ``jk``:

* absolute data: :math:`r_{g,jk} = (F^{model}_{g,jk} - F_{g,jk}) / w_{g,jk}` with ``w = std`` when
  the data have standard deviations, otherwise ``w = F_{g,00}`` of the data (a relative-error model:
  every element is measured to a fixed fraction of the total signal; ``F_00`` is floored at 1e-6 of
  its largest value);
* a dark geometry (``F_00 <= 0``: no light, so no normalised Mueller information) is dropped with a
  warning when the weights come from ``F_00`` (no ``std``) or the data are normalised -- weighted by
  its ``F_00`` it would count a million times more than the others; with ``std`` it is kept (its
  standard deviations weight it, and noise can make a faint ``F_00`` negative). Data dark at every
  geometry are refused;
* normalised data (no absolute scale): the 15 ratios :math:`F_{jk}/F_{00}`, divided by their ``std``
  if given.

Bounded nonlinear least squares (``scipy.optimize.least_squares``, trust-region reflective) from
several starting points (metal and dielectric minima), repeated with the circular elements flipped
to check the time convention; the covariance is :math:`s^2(J^TJ)^{-1}` with :math:`s^2 = 1` with
standard deviations and the residual variance without. A design that does not determine all three
parameters (rank-deficient Jacobian) gives an infinite covariance and a warning instead of a
confident answer. ``posterior_steps > 0`` samples the posterior with emcee (flat priors inside the
bounds, the Gaussian likelihood of the residuals above with :math:`s^2` fixed).

Depolarization: the specular term is a Jones (non-depolarizing) matrix, so all of the pBRDF's
depolarization comes from the diffuse term. The depolarization index (Gil and Bernabeu 1985)

.. math::  P_\Delta(\mathbf M) = \frac{\sqrt{\sum_{jk} M_{jk}^2 - M_{00}^2}}{\sqrt3\,M_{00}}

is 1 for a non-depolarizing and 0 for an ideal depolarizer; the fit reports :math:`1 - P_\Delta` of
the data and of the fitted model per geometry, and the fraction of the measured depolarization the
diffuse term explains, :math:`\sum(1 - P_\Delta^{model}) / \sum(1 - P_\Delta^{data})`. Noise adds to
:math:`\sum M_{jk}^2` and so hides depolarization of the order of the noise.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from scatterlab._checks import as_count, as_rng, check_starts
from scatterlab.ellipsometry.fit import (
    FIT_BOUNDS,
    IndexFitMixin,
    check_bounds,
    least_squares_from_starts,
)
from scatterlab.pbrdf import Model

__all__ = ["PBRDFFit", "fit_pbrdf", "depolarization_index"]

BOUNDS = FIT_BOUNDS
STARTS = ((0.5, 5.0), (1.5, 10.0), (3.0, 3.0), (1.5, 0.1))
_CIRCULAR = np.zeros((4, 4), bool)
_CIRCULAR[3, :3] = _CIRCULAR[:3, 3] = True


def depolarization_index(M) -> np.ndarray:
    """Depolarization index ``P_Delta`` (Gil and Bernabeu 1985; module docstring).

    Parameters
    ----------
    M : array_like (..., 4, 4)
        Mueller matrices (any scale).

    Returns
    -------
    ndarray (...)
        1 for non-depolarizing, 0 for an ideal depolarizer; in [0, 1] for physical matrices, NaN
        where ``M00 <= 0``, not clipped (noise can push it past 1).

    Raises
    ------
    ValueError
        If ``M`` is not of shape ``(..., 4, 4)``.
    """
    M = np.asarray(M, float)
    if M.shape[-2:] != (4, 4):
        raise ValueError(f"M must have shape (..., 4, 4), got {M.shape}")
    m00 = M[..., 0, 0]
    # divided by M00 first: squares of a matrix of 1e-177 (a smooth surface far off specular) underflow
    with np.errstate(divide="ignore", invalid="ignore"):
        N = M / np.where(m00 > 0, m00, 1.0)[..., None, None]
    total = np.sum(N * N, axis=(-2, -1)) - 1.0
    return np.where(m00 > 0, np.sqrt(np.maximum(total, 0)) / np.sqrt(3), np.nan)


@dataclass
class PBRDFFit(IndexFitMixin):
    """Result of :func:`fit_pbrdf`.

    Attributes
    ----------
    n, kappa, sigma : float
        Best fit (``eta = n - 1j*kappa``; ``sigma`` the per-axis rms facet slope).
    covariance : ndarray (3, 3)
        Of (n, kappa, sigma); ``inf`` where the data do not determine them; 0 in sigma's row and
        column when sigma was known.
    predicted : ndarray (N, 4, 4)
        The model at the data's geometries [1/sr] (normalised by its F00 for normalised data).
    residuals : ndarray (N, 4, 4)
        Weighted residuals (model - data) / w (NaN for elements not fitted: F00 of normalised data).
    element_rms : ndarray (4, 4)
        RMS weighted residual of each element over the geometries.
    cost : float
        Half the sum of squared weighted residuals.
    reduced_chi2 : float
        ``2 cost / dof``: about 1 when the standard deviations describe the scatter and the model
        fits.
    depolarization : dict
        ``measured`` and ``model`` (N,) ``1 - P_Delta``, ``explained`` (fraction, NaN when the data
        barely depolarize), ``measured_mean``, ``model_mean``.
    circular_flip_ratio : float
        Best-fit cost with the circular elements of the data sign-flipped (the other time
        convention) over the cost as read: well below 1 means the file is probably in the other
        convention.
    posterior : dict or None
        ``samples`` (S, 3) of (n, kappa, sigma), ``acceptance``, ``steps``, ``walkers`` when
        sampled.
    options : dict
        The fit's options; ``dropped`` lists the indices (into the data at the fitted wavelength)
        of the dark geometries left out, whose rows ``predicted`` and ``residuals`` do not have.
    """

    n: float
    kappa: float
    sigma: float
    covariance: np.ndarray
    predicted: np.ndarray
    residuals: np.ndarray
    element_rms: np.ndarray
    cost: float
    reduced_chi2: float
    dof: int
    success: bool
    determined: bool
    weighted: bool
    normalised: bool
    wavelength: float
    depolarization: dict
    circular_flip_ratio: float
    options: dict = field(default_factory=dict)
    posterior: dict | None = None

    def summary(self) -> dict:
        """Plain numbers for JSON.

        Returns
        -------
        dict
            Parameters, their errors and covariance, fit quality, per-element RMS residuals,
            depolarization, the time-convention check, the options and the posterior summary.
        """
        errors = dict(zip(("n", "kappa", "sigma"), self.errors.tolist()))
        if self.options.get("sigma_known") is not None:
            errors["sigma"] = None  # known, so no error: null, not 0
        out = {
            "n": self.n,
            "kappa": self.kappa,
            "sigma": self.sigma,
            "errors": errors,
            "covariance": self.covariance.tolist(),
            "cost": self.cost,
            "reduced_chi2": self.reduced_chi2,
            "dof": self.dof,
            "success": self.success,
            "determined": self.determined,
            "weighted_by_std": self.weighted,
            "normalised_data": self.normalised,
            "wavelength_m": self.wavelength,
            "element_rms": self.element_rms.tolist(),
            "circular_flip_ratio": self.circular_flip_ratio,
            "depolarization": {
                k: (v.tolist() if isinstance(v, np.ndarray) else v)
                for k, v in self.depolarization.items()
            },
            "options": self.options,
        }
        if self.posterior is not None:
            s = self.posterior["samples"]
            out["posterior"] = {
                "median": np.median(s, 0).tolist(),
                "std": s.std(0).tolist(),
                "acceptance": self.posterior["acceptance"],
                "steps": self.posterior["steps"],
            }
        return out


class _Problem:
    """Residuals of one data set against the pBRDF with fixed options (the state of the fit)."""

    def __init__(self, data, shadowing, diffuse, flip=False):
        self.data, self.shadowing, self.diffuse = data, shadowing, diffuse
        self.normalised = bool(data.normalised)
        M = data.mueller * np.where(_CIRCULAR, -1.0, 1.0) if flip else data.mueller
        self.used = np.ones((4, 4), bool)
        if self.normalised:
            self.used[0, 0] = False
        if data.std is not None:
            w = data.std.copy()
            if np.any(w[:, self.used] <= 0):
                raise ValueError(
                    "data.std must be > 0 for every fitted element (weights are 1/std)"
                )
        else:
            m00 = M[:, 0, 0]
            floor = 1e-6 * max(float(m00.max()), 1e-300)
            w = np.broadcast_to(np.maximum(m00, floor)[:, None, None], M.shape).copy()
            if self.normalised:
                w[:] = 1.0
        self.w = w
        self.y = M

    def model(self, n, kappa, sigma):
        """Model Mueller matrices (N, 4, 4); with arrays (W, 1) of parameters: (W, N, 4, 4)."""
        # a (1,)-array sigma reads the DHR from the 2-D table (1.6e-9 of F00 from the 1-D one that a
        # scalar sigma builds, 7x faster for a new sigma at every call)
        sigma = np.atleast_1d(sigma) if np.ndim(sigma) == 0 else sigma
        F = Model(sigma, shadowing=self.shadowing, diffuse=self.diffuse).mueller(
            n - 1j * kappa, self.data.theta_i, self.data.theta_r, self.data.phi
        )
        if self.normalised:
            with np.errstate(divide="ignore", invalid="ignore"):
                F = F / F[..., :1, :1]
            F = np.nan_to_num(F, nan=0.0, posinf=0.0, neginf=0.0)
        return F

    def weighted(self, F):
        return (F - self.y) / self.w

    def residual(self, p):
        return self.weighted(self.model(*p))[:, self.used].ravel()

    def log_likelihood(self, P, s2):
        """Gaussian log-likelihood of parameter rows ``P`` (W, 3), vectorised over the rows."""
        r = self.weighted(self.model(*(P.T[:, :, None])))[:, :, self.used]
        out = -0.5 * np.sum(r.reshape(len(P), -1) ** 2, axis=1) / s2
        return np.where(np.isfinite(out), out, -np.inf)


def _covariance(J, s2, widths):
    """``s2 (J^T J)^-1``, or inf when J is rank-deficient: singular values of J with its columns
    scaled to the bounds' widths (sensitivity over the allowed range) below 1e-6 of the largest
    (finite-difference noise of a parameter the residuals do not depend on is ~1e-8)."""
    sv = np.linalg.svd(J * widths, compute_uv=False)
    if sv.size < J.shape[1] or sv[-1] <= 1e-6 * sv[0]:
        return np.full((J.shape[1], J.shape[1]), np.inf), False
    return s2 * np.linalg.inv(J.T @ J), True


def _depolarization(y, F):
    dm, dp = 1 - depolarization_index(y), 1 - depolarization_index(F)
    total = float(np.nansum(dm))
    explained = float(np.nansum(dp) / total) if np.nanmean(dm) > 1e-3 else float("nan")
    return {
        "measured": dm,
        "model": dp,
        "measured_mean": float(np.nanmean(dm)),
        "model_mean": float(np.nanmean(dp)),
        "explained": explained,
    }


def _drop_dark(data):
    """The data without dark geometries (``F_00 <= 0``) where their weight would come from ``F_00``
    (module docstring), and the indices dropped; ValueError when every geometry is dark."""
    m00 = data.mueller[:, 0, 0]
    dark = ~(m00 > 0)
    if dark.all():
        raise ValueError(
            f"data (the Mueller BRDF) are dark at all {len(data)} geometries (F00 <= 0): there is "
            "no light to fit"
        )
    if not dark.any() or (data.std is not None and not data.normalised):
        return data, []
    dropped = np.flatnonzero(dark).tolist()
    warnings.warn(
        f"dropped {len(dropped)} of {len(data)} geometries of data with F00 <= 0 (no light: no "
        f"normalised Mueller information), at indices {dropped}",
        UserWarning,
        stacklevel=3,
    )
    return data.subset(~dark), dropped


def _select(data, wavelength):
    if wavelength is not None:
        return data.select(wavelength)
    if data.wavelengths.size > 1:
        have = ", ".join(f"{w:.6g}" for w in data.wavelengths)
        raise ValueError(
            f"the data hold several wavelengths ({have} m): choose one with wavelength="
        )
    return data


def fit_pbrdf(
    data,
    wavelength=None,
    *,
    shadowing: str = "torrance-sparrow",
    diffuse: str = "hyde",
    starts=STARTS,
    sigma0: float = 0.3,
    bounds=BOUNDS,
    posterior_steps: int = 0,
    walkers: int = 24,
    rng=None,
    sigma: float | None = None,
) -> PBRDFFit:
    """Fit n, kappa and sigma of the pBRDF to all 16 elements of a measured Mueller BRDF.

    Parameters
    ----------
    data : scatterlab.io.MuellerBRDF
        Geometries in and out of the plane of incidence; ``std`` (when present) weights the
        residuals.
    wavelength : float, optional [m]
        The wavelength to fit when the data hold several (required then).
    shadowing, diffuse : str
        Options of :class:`scatterlab.pbrdf.Model` (``diffuse="none"``: the specular microfacet term
        only, e.g. for NIST SCATMECH's ``Shadowed_Facet_BRDF_Model``).
    starts : sequence of (n, kappa)
        Starting points (the lowest final cost wins; metal and dielectric minima are both tried).
    sigma0 : float
        Starting roughness.
    bounds : ((n_lo, n_hi), (kappa_lo, kappa_hi), (sigma_lo, sigma_hi))
        Box of the fit, checked by :func:`scatterlab.ellipsometry.fit.check_bounds` (finite,
        ``lo < hi``, ``n_lo, kappa_lo >= 0``, sigma within ``[1e-4, 5]``).
    posterior_steps : int
        emcee steps per walker (0: no posterior). The first half is discarded as burn-in.
    walkers : int
        emcee walkers (>= 8).
    rng : None, int >= 0, SeedSequence, BitGenerator or Generator
        Seeds the walkers' start and emcee's moves.
    sigma : float, optional
        Known roughness (rms facet slope, within the bounds' sigma range), e.g. from profilometry:
        held fixed, so only n and kappa are fitted and sampled (its error and covariance are 0).
        Default: fitted.

    Returns
    -------
    PBRDFFit

    Warns
    -----
    UserWarning
        Dark geometries (``F00 <= 0``) dropped: how many and which (module docstring).

    Raises
    ------
    ValueError
        Several wavelengths and none chosen, a wavelength not in the data, data dark (``F00 <= 0``)
        at every geometry, empty, non-finite or negative ``starts``, bad bounds, a known ``sigma``
        outside the bounds, non-positive standard deviations of fitted elements, fewer data than
        parameters.
    """
    starts = [tuple(s) for s in check_starts(starts).tolist()]
    lo, hi = check_bounds(bounds)
    if posterior_steps < 0 or int(posterior_steps) != posterior_steps:
        raise ValueError(f"posterior_steps must be a non-negative integer, got {posterior_steps}")
    if posterior_steps:  # checked before the fit, not after it
        walkers = as_count(walkers, "walkers", 8)
        rng = as_rng(rng)
    if sigma is not None:
        sigma = float(sigma)
        if not lo[2] <= sigma <= hi[2]:  # also refuses NaN
            raise ValueError(
                f"sigma (the known roughness) must be within the bounds' [{lo[2]:g}, {hi[2]:g}], "
                f"got {sigma}"
            )
    data = _select(data, wavelength)
    data, dropped = _drop_dark(data)
    prob = _Problem(data, shadowing, diffuse)
    if prob.used.sum() * len(data) <= (3 if sigma is None else 2):
        raise ValueError(
            "fewer data than parameters: at least one geometry with all elements is needed"
        )
    best = _best_fit(prob, starts, sigma0, lo, hi, sigma)
    other = _best_fit(_Problem(data, shadowing, diffuse, flip=True), starts, sigma0, lo, hi, sigma)
    fit = _result(
        prob,
        best,
        data,
        dict(
            shadowing=shadowing,
            diffuse=diffuse,
            bounds=[list(b) for b in bounds],
            sigma_known=sigma,
            dropped=dropped,
        ),
        (lo, hi),
        posterior_steps,
        walkers,
        rng,
        sigma,
    )
    fit.circular_flip_ratio = float(other.cost / best.cost) if best.cost > 0 else float("inf")
    return fit


def _free(sigma, P) -> np.ndarray:
    """Parameter rows (..., 3) from the free ones (..., 2 or 3): a known ``sigma`` appended."""
    P = np.asarray(P, float)
    if sigma is None:
        return P
    return np.concatenate([P, np.full(P.shape[:-1] + (1,), sigma)], axis=-1)


def _best_fit(prob, starts, sigma0, lo, hi, sigma=None):
    """The lowest-cost least-squares solution over the starting points; with a known ``sigma`` over
    (n, kappa) only (``x`` then carries the known sigma as its third value, ``jac`` two columns)."""
    k = 3 if sigma is None else 2
    lo, hi = lo[:k], hi[:k]
    x0s = [
        np.clip([n0, k0, sigma0][:k], lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        for n0, k0 in starts
    ]
    best = least_squares_from_starts(
        lambda q: prob.residual(_free(sigma, q)), x0s, lo, hi, tol=1e-12, max_nfev=300
    )
    best.x = _free(sigma, best.x)
    return best


def _result(
    prob, best, data, options, bounds, posterior_steps, walkers, rng, sigma=None
) -> PBRDFFit:
    k = best.jac.shape[1]  # free parameters: 3, or 2 with a known sigma
    dof = max(1, best.fun.size - k)
    weighted = data.std is not None
    s2 = 1.0 if weighted else 2 * best.cost / dof
    cov, determined = _covariance(best.jac, s2, (bounds[1] - bounds[0])[:k])
    cov = np.pad(cov, ((0, 3 - k), (0, 3 - k)))  # a known sigma has no error
    if not determined:
        warnings.warn(
            f"the data do not determine {'n, kappa and sigma' if k == 3 else 'n and kappa'} "
            "together (rank-deficient Jacobian): the covariance is infinite; add geometries "
            "(several incidence angles, out of plane)",
            RuntimeWarning,
            stacklevel=3,
        )
    F = prob.model(*best.x)
    r = prob.weighted(F)
    r[:, ~prob.used] = np.nan
    rms = np.where(prob.used, np.sqrt(np.mean(np.where(prob.used, r, 0.0) ** 2, axis=0)), np.nan)
    fit = PBRDFFit(
        n=float(best.x[0]),
        kappa=float(best.x[1]),
        sigma=float(best.x[2]),
        covariance=cov,
        predicted=F,
        residuals=r,
        element_rms=rms,
        cost=float(best.cost),
        reduced_chi2=float(2 * best.cost / dof),
        dof=int(dof),
        success=bool(best.success),
        determined=determined,
        weighted=weighted,
        normalised=prob.normalised,
        wavelength=float(data.wavelength[0]),
        depolarization=_depolarization(prob.y, F),
        circular_flip_ratio=float("nan"),
        options=options,
    )
    if posterior_steps:
        fit.posterior = _sample(
            prob,
            best.x,
            cov if determined else None,
            s2,
            bounds,
            posterior_steps,
            walkers,
            rng,
            sigma,
        )
    return fit


def _sample(prob, x, cov, s2, bounds, steps, walkers, rng, sigma=None) -> dict:
    """emcee ensemble around the least-squares solution (flat priors inside ``bounds``); with a known
    ``sigma`` over (n, kappa) only, the samples' sigma column then that value."""
    import emcee

    rng = np.random.default_rng(rng)  # walkers and rng were checked by fit_pbrdf
    k = 3 if sigma is None else 2
    lo, hi = bounds[0][:k], bounds[1][:k]

    def log_prob(P):
        inside = np.all((P >= lo) & (P <= hi), axis=1)
        out = np.full(len(P), -np.inf)
        if inside.any():
            out[inside] = prob.log_likelihood(_free(sigma, P[inside]), s2)
        return out

    scale = np.sqrt(np.diag(cov))[:k] if cov is not None else 1e-3 * (hi - lo)
    p0 = x[:k] + 0.1 * scale * rng.standard_normal((walkers, k))
    p0 = np.clip(p0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
    sampler = emcee.EnsembleSampler(walkers, k, log_prob, vectorize=True)
    sampler.random_state = np.random.RandomState(int(rng.integers(2**32))).get_state()
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):  # small matrices: BLAS threads only contend (run_ensembles)
        sampler.run_mcmc(p0, int(steps), progress=False)
    samples = _free(sigma, sampler.get_chain(discard=int(steps) // 2, flat=True))
    return {
        "samples": samples,
        "acceptance": float(np.mean(sampler.acceptance_fraction)),
        "steps": int(steps),
        "walkers": int(walkers),
    }
