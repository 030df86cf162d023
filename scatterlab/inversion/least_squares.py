r"""Least-squares inversion of (n, kappa, sigma) from multi-geometry DOLP (Sec. 7.2.2, Eqs.
199-204).

The forward model is the pBRDF DOLP of :class:`scatterlab.pbrdf.Model` (Eq. 203 in the specular
plane).
:func:`fit_dolp` solves, for every pixel of a batch at once,

.. math:: \min_{n,\kappa,\sigma} \sum_j [\mathcal P^{thy}(n - j\kappa, \sigma; \theta_{i,j},
\theta_{r,j}, \phi_j) - \mathcal P_j]^2

with a vectorised Levenberg-Marquardt iteration in numpy (analytic Jacobian, per-pixel damping,
bounds by projection), from several starting points so that the metal/dielectric ambiguity does not
trap a
pixel in a local minimum; the best start wins per pixel. NaN measurements are masked (left out of
the
residuals); a pixel with fewer valid measurements than unknowns is reported, not fitted. The
parameter
covariance is the Laplace approximation :math:`s^2 (J^TJ)^{-1}` at the solution (``noise`` given:
its
variance instead of the residual variance). :func:`fit_dolp_per_pixel` is the per-pixel
``scipy.optimize.least_squares`` baseline.

Default bounds follow the reference (n in [0, 5], kappa in [0, 25]); sigma in [0.01, 1.5].
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from scatterlab._checks import as_angle, as_azimuth, as_positive, check_starts
from scatterlab.inversion.design import inverse_information
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.options import DEFAULT_STARTS, FitOptions, resolve_options
from scatterlab.pbrdf import Model, facet_dolp

__all__ = [
    "fit_dolp",
    "fit_dolp_per_pixel",
    "DolpFit",
    "model_dolp",
    "DEFAULT_BOUNDS",
    "DEFAULT_STARTS",
    "DOLP_MARGIN",
    "IdentifiabilityWarning",
    "prepare_data",
    "parameter_bounds",
    "check_starts",
    "check_noise",
    "check_systematic",
    "check_covariance",
    "FitOptions",
]

PARAMETER_NAMES = ("n", "kappa", "sigma")
DEFAULT_BOUNDS = {"n": (0.0, 5.0), "kappa": (0.0, 25.0), "sigma": (0.01, 1.5)}
# a DOLP's standard deviation: below 1e-12 the whitened residuals overflow in squares, above 1 (the
# whole range of a DOLP) it says nothing
NOISE_RANGE = (1e-12, 1.0)
# largest upper bound of n and kappa: the forward model is tested without overflow up to |eta| = 1e6
# (the stability brief: kappa up to 1e3, |eta| up to 1e6); 1e300 overflowed in the Fresnel terms
INDEX_MAX = 1e6
DOLP_MARGIN = 0.05  # how far outside [0, 1] a measured DOLP may fall (noise) before it is refused


class IdentifiabilityWarning(UserWarning):
    """The data do not determine some parameter (singular Fisher information at the solution)."""


class BoundWarning(IdentifiabilityWarning):
    """A fit ended on a bound that is not a physical limit: the value there is the bound, not an
    estimate (``DolpFit.at_bound``)."""


def model_dolp(n, kappa, sigma, theta_i, theta_r, phi=np.pi, **model_kw) -> np.ndarray:
    """pBRDF DOLP for parameters ``(...)`` and geometries ``(M,)`` -> ``(..., M)``.

    Parameters
    ----------
    n, kappa, sigma : array_like (...)
        Index ``n - 1j*kappa`` (finite, ``n >= 0``, ``kappa >= 0``; ``n`` below 1e-6, the bound
        ``n = 0`` included, is evaluated at 1e-6) and rms facet slope (broadcast together).
    theta_i, theta_r : array (M,) [rad]
        Geometries.
    phi : float or array (M,) [rad], default pi (specular plane)
    **model_kw
        ``shadowing``, ``diffuse``, ``distribution`` of :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    ndarray (..., M)
        DOLP in [0, 1] (dimensionless), never NaN: the formula the fits use
        (:class:`~scatterlab.inversion.forward.DolpForward`). It is :meth:`scatterlab.pbrdf.Model.dolp`
        wherever light is reflected, its limit at an exactly grazing direction where the specular
        term diverges, and where no light is reflected (``F00 = 0``, where ``Model.dolp`` is NaN: ``eta
        = 1`` exactly, no interface; or both terms of the pBRDF vanish or underflow, e.g. far from the
        lobe of a smooth surface) the zero-light convention of ``DolpForward``: the facet's DOLP
        (:func:`~scatterlab.pbrdf.facet_dolp`, continuous at ``eta = 1``) times the specular fraction
        (:meth:`~scatterlab.pbrdf.Model.specular_fraction`, 1 where both terms vanish). At ``eta = 1``
        this is the limit ``eta -> 1``.

    Raises
    ------
    ValueError
        If ``n`` or ``kappa`` is negative or not finite.
    """
    n = np.maximum(as_positive(n, "n", allow_zero=True), 1e-6)[..., None]
    kappa = as_positive(kappa, "kappa", allow_zero=True)[..., None]
    sigma = np.asarray(sigma, float)[..., None]
    model = Model(sigma, **model_kw)
    eta = n - 1j * kappa
    d = model.dolp(eta, theta_i, theta_r, phi)
    dark = np.isnan(d)  # no reflected light: the DOLP of the light is undefined, the formula is not
    if np.any(dark):
        fraction = model.specular_fraction(theta_i, theta_r, phi)
        d = np.where(dark, facet_dolp(eta, theta_i, theta_r, phi) * fraction, d)
    return d


@dataclass
class DolpFit:
    """Result of :func:`fit_dolp` (arrays over the batch's leading axes).

    Attributes
    ----------
    n, kappa, sigma : ndarray
    covariance : ndarray (..., P, P) -- Laplace approximation; P = 3 (or 2 with sigma known).
    cost : ndarray -- half the sum of squared residuals.
    converged : ndarray of bool
    valid : ndarray of bool -- enough finite measurements to fit.
    iterations : int
    identifiable : ndarray of bool (..., P) or None
        Whether the data determine each parameter at the solution (non-singular Fisher
        information there); an unidentifiable parameter has an infinite variance in
        ``covariance`` (NaN covariances), never a silently finite one. Identifiable is local: a
        value within one Laplace error of a bound (kappa = 0.03 +/- 1.3 beside kappa = 0, where the
        DOLP is nearly stationary in kappa) is identifiable with a finite but large variance; the
        data then do not distinguish it from the bound, and the Gaussian covariance ignores the
        bound (:func:`~scatterlab.inversion.sample_posterior` says so in its messages).
    at_bound : ndarray of bool (..., P) or None
        Whether each parameter ended on a bound of the fit that is not a physical limit (every bound
        but kappa = 0, a lossless medium): there the value is the bound, not an estimate, and the
        covariance ignores the bound. A :class:`BoundWarning` says how many.
    """

    n: np.ndarray
    kappa: np.ndarray
    sigma: np.ndarray
    covariance: np.ndarray
    cost: np.ndarray
    converged: np.ndarray
    valid: np.ndarray
    iterations: int
    identifiable: np.ndarray | None = None
    at_bound: np.ndarray | None = None

    @property
    def eta(self) -> np.ndarray:
        return self.n - 1j * self.kappa

    @property
    def errors(self) -> np.ndarray:
        """1-sigma standard errors (..., P) from the covariance diagonal."""
        return np.sqrt(np.clip(np.diagonal(self.covariance, axis1=-2, axis2=-1), 0, None))


def prepare_data(dolp, theta_i, theta_r, phi=np.pi, *, margin: float = DOLP_MARGIN):
    """Validate DOLP data and geometries; returns ``(dolp (..., M), theta_i (M,), theta_r (M,), phi
    (M,))``.

    NaN entries of ``dolp`` are kept (they mark missing measurements). Infinite entries, and finite
    ones
    outside ``[-margin, 1 + margin]`` (a DOLP is in [0, 1]; ``margin`` allows for noise), raise a
    ValueError
    naming ``dolp``. Shared by the least-squares fit, the posterior sampler and the design
    functions.

    Parameters
    ----------
    dolp : array_like (..., M)
        Measured DOLP; NaN marks a missing measurement.
    theta_i, theta_r : array_like (M,) [rad]
        Geometries, in [0, pi/2].
    phi : float or array_like (M,) [rad]
        Azimuth of each geometry.
    margin : float
        Allowed excursion outside [0, 1] (>= 0).

    Returns
    -------
    tuple
        ``(dolp (..., M), theta_i (M,), theta_r (M,), phi (M,))`` as float arrays [rad].
    """
    try:
        y = np.asarray(dolp, float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"dolp must be numeric, got {dolp!r}") from exc
    ti = as_angle(theta_i, "theta_i").ravel()
    tr = as_angle(theta_r, "theta_r").ravel()
    try:
        ph = np.broadcast_to(np.asarray(phi, float), ti.shape)
    except ValueError as exc:
        raise ValueError(f"phi must be a float or one value per geometry ({ti.size})") from exc
    if ti.shape != tr.shape:
        raise ValueError("theta_i and theta_r must have one entry per measured geometry")
    as_azimuth(ph, "phi")
    if y.shape[-1:] != ti.shape:
        raise ValueError(
            f"dolp must have shape (..., {ti.size}) (one value per geometry), got {y.shape}"
        )
    if np.any(np.isinf(y)):
        raise ValueError(
            "dolp must be finite or NaN (NaN marks a missing measurement); got an infinite value"
        )
    if not (np.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin must be a non-negative float, got {margin!r}")
    bad = np.isfinite(y) & ((y < -margin) | (y > 1 + margin))
    if np.any(bad):
        raise ValueError(
            f"dolp must be in [0, 1] (within the noise margin {margin:g}); got "
            f"{int(bad.sum())} value(s) outside, e.g. {y[bad].ravel()[0]:.4g}. Set them to NaN to "
            "leave them out"
        )
    return y, ti, tr, ph


def parameter_bounds(bounds, P: int):
    """Validated lower and upper bounds ``(lo (P,), hi (P,))`` of (n, kappa[, sigma]).

    ``bounds`` maps any of ``"n"``, ``"kappa"``, ``"sigma"`` to ``(low, high)``; missing names take
    :data:`DEFAULT_BOUNDS`. An unknown name raises a ValueError naming it and the allowed ones.

    Parameters
    ----------
    bounds : dict or None
        ``{name: (low, high)}`` for ``"n"``, ``"kappa"``, ``"sigma"``: finite, ``low < high``,
        ``0 <= n, kappa <= 1e6`` (:data:`INDEX_MAX`) and sigma within ``[1e-3, 2.5]``.
    P : int
        Number of fitted parameters (2: n, kappa; 3: with sigma).

    Returns
    -------
    lo, hi : ndarray (P,)
        Lower and upper bounds (n, kappa dimensionless; sigma an rms slope).
    """
    bounds = dict(bounds or {})
    unknown = sorted(set(bounds) - set(DEFAULT_BOUNDS))
    if unknown:
        raise ValueError(
            f"bounds has unknown key(s) {unknown}; allowed keys are {sorted(DEFAULT_BOUNDS)}"
        )
    b = dict(DEFAULT_BOUNDS, **bounds)
    for name, pair in b.items():
        try:
            lo, hi = (float(v) for v in pair)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"bounds[{name!r}] must be (low, high), got {pair!r}") from exc
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(
                f"bounds[{name!r}] must be (low, high) with low < high, got {(lo, hi)}"
            )
    if b["n"][0] < 0 or b["kappa"][0] < 0 or b["sigma"][0] < 1e-3 or b["sigma"][1] > 2.5:
        raise ValueError("bounds must keep n >= 0, kappa >= 0 and sigma within [1e-3, 2.5]")
    for name in ("n", "kappa"):
        if b[name][1] > INDEX_MAX:
            raise ValueError(
                f"bounds[{name!r}] must have high <= {INDEX_MAX:g} (|eta| up to about 1e6, where the "
                f"DOLP model is evaluated without overflow), got {tuple(b[name])}"
            )
    lo = np.array([b["n"][0], b["kappa"][0], b["sigma"][0]][:P], float)
    hi = np.array([b["n"][1], b["kappa"][1], b["sigma"][1]][:P], float)
    return lo, hi


def check_noise(noise, name: str = "noise"):
    """A DOLP noise standard deviation: positive and finite (scalar or array), or None.

    Parameters
    ----------
    noise : float, array_like or None
        Standard deviation of the DOLP noise (dimensionless, > 0).
    name : str
        Argument name used in the error message.

    Returns
    -------
    ndarray or None
        ``noise`` as a float array (shape kept), or None.
    """
    if noise is None:
        return None
    try:
        arr = np.asarray(noise, float)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be a positive DOLP standard deviation, got {noise!r}"
        ) from exc
    if not np.all(np.isfinite(arr) & (arr >= NOISE_RANGE[0]) & (arr <= NOISE_RANGE[1])):
        raise ValueError(
            f"{name} must be a DOLP standard deviation in [{NOISE_RANGE[0]:g}, {NOISE_RANGE[1]:g}] "
            f"(or None), got {noise!r}"
        )
    return arr


def check_systematic(systematic, M: int):
    """A known systematic DOLP error standard deviation per geometry, or None.

    Parameters
    ----------
    systematic : float, array (M,) or None
        Standard deviations (DOLP, finite, in ``[0, 1]``: above 1, the whole range of a DOLP, it
        says nothing, and 1e200 overflowed in the variances).
    M : int
        Number of geometries.

    Returns
    -------
    ndarray (M,) or None
        The standard deviations broadcast to one per geometry (a copy).
    """
    if systematic is None:
        return None
    ok = not isinstance(systematic, (str, bytes)) and (
        np.ndim(systematic) == 0 or np.shape(systematic) == (M,)
    )
    try:
        t = np.broadcast_to(np.asarray(systematic, float), (M,)).copy() if ok else None
    except (TypeError, ValueError):
        t = None
    if t is None or not np.all(np.isfinite(t) & (t >= 0) & (t <= NOISE_RANGE[1])):
        raise ValueError(
            f"systematic must be a float or an array ({M},) of DOLP standard deviations in "
            f"[0, {NOISE_RANGE[1]:g}], got {systematic!r}"
        )
    return t


def check_covariance(covariance, noise, M: int):
    """A full DOLP error covariance across the M geometries, or None.

    Parameters
    ----------
    covariance : array (M, M) or None
        Finite, symmetric (to 1e-10 relative) and positive definite (DOLP^2), with variances
        (diagonal) at most 1 and eigenvalues at least 1e-24 (standard deviations in the range of
        ``noise``, ``[1e-12, 1]``; a smaller eigenvalue overflows the whitened fit).
    noise : object
        The caller's noise; giving both ``noise`` and ``covariance`` is a ValueError.
    M : int
        Number of geometries.

    Returns
    -------
    ndarray (M, M) or None
        The covariance, symmetrised ``(C + C^T) / 2``.
    """
    if covariance is None:
        return None
    if noise is not None:
        raise ValueError(
            "give either noise or covariance (the full DOLP error covariance), not both"
        )
    C = np.asarray(covariance, float)
    if C.shape != (M, M) or not np.all(np.isfinite(C)):
        raise ValueError(f"covariance must be a finite ({M}, {M}) matrix, got shape {C.shape}")
    if not np.allclose(C, C.T, rtol=1e-10, atol=0):
        raise ValueError("covariance must be symmetric")
    C = (C + C.T) / 2
    lo, hi = NOISE_RANGE
    if np.max(np.diag(C)) > hi**2:
        raise ValueError(
            f"covariance must have variances (diagonal) <= {hi**2:g} (DOLP standard deviations <= "
            f"{hi:g}), got {float(np.max(np.diag(C))):.3g}"
        )
    smallest = float(np.linalg.eigvalsh(C)[0])
    if smallest <= 0:
        raise ValueError("covariance must be positive definite")
    if smallest < lo**2:
        raise ValueError(
            f"covariance must have eigenvalues >= {lo**2:g} (DOLP standard deviations >= {lo:g}, "
            f"as noise), got a smallest eigenvalue {smallest:.3g}; add the noise variance to its "
            "diagonal"
        )
    return C


def _levenberg_marquardt(forward, y0, mask, p, lo, hi, active, max_iter, tol):
    """Bounded LM from starts ``p`` (N, P) for N pixels at once; returns (p, cost, converged,
    iterations).

    Converged pixels leave the working set, so an iteration costs in proportion to the pixels still
    moving.
    A pixel converges when a successful step changes the cost by less than ``tol`` (relative) or
    moves every
    parameter by less than ``1e-10`` of its bound range, or when the damping grows past 1e10 without
    success.
    """
    N, P = p.shape
    p = p.copy()
    cost = np.full(N, np.nan)
    done = ~active
    idx = np.flatnonzero(active)
    f, J = forward.value_and_jacobian(p[idx], rows=idx)
    r = np.where(mask[idx], f - y0[idx], 0.0)
    c = 0.5 * np.sum(r * r, -1)
    lam = np.full(idx.size, 1e-3)
    xtol = 1e-10 * (hi - lo)
    iterations = 0
    for _ in range(max_iter):
        if idx.size == 0:
            break
        m = mask[idx]
        J = np.where(m[..., None], J, 0.0)
        A = np.einsum("nmi,nmj->nij", J, J)
        g = np.einsum("nmi,nm->ni", J, r)
        pi = p[idx]
        # active bounds: a parameter on its bound whose descent direction leaves the box is held
        # there,
        # and the step is solved in the free subspace (projection alone stalls along the bound)
        held = ((pi <= lo) & (g > 0)) | ((pi >= hi) & (g < 0))
        free = ~held
        A = A * (free[:, :, None] & free[:, None, :]) + np.eye(P) * held[:, None, :]
        g = np.where(free, g, 0.0)
        diag = np.diagonal(A, axis1=-2, axis2=-1)
        A_damped = A + lam[:, None, None] * (np.eye(P) * (diag[:, None, :] + 1e-12))
        with np.errstate(all="ignore"):
            delta = -np.linalg.solve(A_damped, g[..., None])[..., 0]
        delta = np.where(np.isfinite(delta), delta, 0.0)
        p_new = np.clip(pi + delta, lo, hi)
        f_new, J_new = forward.value_and_jacobian(p_new, rows=idx)
        r_new = np.where(m, f_new - y0[idx], 0.0)
        c_new = 0.5 * np.sum(r_new * r_new, -1)
        better = c_new < c
        rel = np.where(better, (c - c_new) / np.maximum(c, 1e-300), 0.0)
        small_step = np.all(np.abs(p_new - pi) <= xtol, axis=-1)
        finished = (
            (better & ((rel < tol) | small_step))
            | (~better & (lam > 1e10))
            | (np.minimum(c, c_new) < 1e-30)
        )
        p[idx] = np.where(better[:, None], p_new, pi)
        r = np.where(better[:, None], r_new, r)
        J = np.where(better[:, None, None], J_new, J)
        c = np.where(better, c_new, c)
        lam = np.where(better, lam / 3, lam * 4)
        iterations += 1
        if np.any(finished):
            cost[idx[finished]] = c[finished]
            done[idx[finished]] = True
            keep = ~finished
            idx, r, J, c, lam = idx[keep], r[keep], J[keep], c[keep], lam[keep]
    cost[idx] = c  # not converged within max_iter: best point so far
    return p, cost, done, iterations


def fit_dolp(
    dolp,
    theta_i,
    theta_r,
    phi=np.pi,
    *,
    sigma=None,
    noise=None,
    systematic=None,
    covariance=None,
    options: FitOptions | None = None,
    **kw,
) -> DolpFit:
    """Batched bounded least squares of (n, kappa[, sigma]) to DOLP measured at M geometries.

    Every pixel runs a Levenberg-Marquardt iteration with its own damping, in one vectorised pass;
    the Jacobian is analytic in (n, kappa) (:class:`~scatterlab.inversion.forward.DolpForward`).
    Each start of ``options.starts`` is run for every pixel and the lowest cost wins per pixel.

    Parameters
    ----------
    dolp : array (..., M)
        Measured DOLP in [0, 1]; NaN entries are masked. Infinite values, and values outside [0, 1]
        by more than ``max(DOLP_MARGIN, 5 * noise)`` (0.05 without ``noise``), raise a ValueError:
        set them to NaN to leave them out.
    theta_i, theta_r : array (M,) [rad]
        M >= P, the number of fitted parameters.
    phi : float or array (M,) [rad], default pi (specular plane)
    sigma : float or array (...), optional
        Known roughness; when given only (n, kappa) are fitted. Its shape must broadcast to
        dolp's leading axes (a ValueError otherwise, before the fit runs).
    noise : float or array (...), optional
        DOLP noise standard deviation in ``[1e-12, 1]`` for the covariance (default: estimated from
        the residuals). Its shape must broadcast to dolp's leading axes.
    systematic : float or array (M,), optional
        Known systematic DOLP error standard deviation per geometry (in ``[0, 1]``), added in
        quadrature to
        ``noise`` (which must then be a scalar) or to ``covariance``: the fit is weighted
        (generalised least squares) and the covariance is in absolute units.
    covariance : array (M, M), optional
        Full DOLP error covariance (errors correlated across geometries), used instead of ``noise``:
        residuals are whitened with its Cholesky factor. NaN entries of ``dolp`` are then refused.
        Symmetric positive definite with variances <= 1 and eigenvalues >= 1e-24 (standard
        deviations in the range of ``noise``), else a ValueError naming ``covariance``.
    options : FitOptions, optional
        ``bounds``, ``starts``, ``sigma0``, ``max_iter``, ``tol``; each may also be given as a
        keyword (not both).
    **kw
        The :class:`FitOptions` keywords, and ``shadowing``, ``diffuse``, ``distribution`` passed to
        :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    DolpFit
        ``converged`` says the iteration stopped on its criteria; ``identifiable`` (..., P) says
        whether the data determine each parameter at the solution (non-singular Fisher information,
        see :func:`~scatterlab.inversion.design.inverse_information`). An undetermined parameter has
        an infinite variance (NaN covariances), and an :class:`IdentifiabilityWarning` says how many
        pixels are affected.
    """
    options, model_kw = resolve_options(dict(kw), {"options": (FitOptions, options)})
    noise = check_noise(noise)
    margin = DOLP_MARGIN if noise is None else max(DOLP_MARGIN, 5 * float(np.max(noise)))
    y, ti, tr, ph = prepare_data(dolp, theta_i, theta_r, phi, margin=margin)
    P = 3 if sigma is None else 2
    starts, lo, hi = _check_fit_setup(options, ti.size, P)
    batch, M = y.shape[:-1], y.shape[-1]
    # per-pixel arrays must broadcast to the batch (dolp's leading axes), checked before the fit runs
    _check_batch_shape(noise, "noise", batch, y.shape)
    if sigma is not None:
        try:
            sigma = np.asarray(sigma, float)
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"sigma must be a known rms slope (float or array), got {sigma!r}"
            ) from exc
        _check_batch_shape(sigma, "sigma", batch, y.shape)
    mask = np.isfinite(y)
    valid = mask.sum(-1) >= P
    sig_known = None if sigma is None else np.broadcast_to(sigma, batch)
    forward = DolpForward(
        ti, tr, ph, sigma=None if sigma is None else sig_known.ravel(), **model_kw
    )
    y0 = np.where(mask, y, 0.0).reshape(-1, M)
    whiten = _whitening(noise, systematic, covariance, mask)
    if whiten is not None:  # generalised least squares: residuals in units of their std
        forward, y0, noise = _Whitened(forward, whiten), y0 @ whiten.T, np.asarray(1.0)
    s0 = options.sigma0 if sigma is None else None
    p, cost, done, iterations = _best_of_starts(
        forward, y0, mask.reshape(-1, M), valid.ravel(), starts, s0, lo, hi, options
    )
    p, cost, done = p.reshape(batch + (P,)), cost.reshape(batch), done.reshape(batch)
    fit = _fit_result(forward, p, cost, done, iterations, mask, valid, noise, sig_known)
    fit.at_bound = _at_bound(p, lo, hi, valid)
    return fit


def _check_batch_shape(value, name: str, batch: tuple, dolp_shape: tuple) -> None:
    """A ValueError naming ``name`` unless its shape broadcasts to the batch shape (dolp's leading
    axes)."""
    if value is None:
        return
    shape = np.shape(value)
    try:
        ok = np.broadcast_shapes(shape, batch) == batch
    except ValueError:
        ok = False
    if not ok:
        raise ValueError(
            f"{name} must be a float or an array that broadcasts to dolp's leading axes {batch} "
            f"(one value per pixel; dolp has shape {dolp_shape}), got shape {shape}"
        )


def _at_bound(p, lo, hi, valid):
    """(..., P) bool: on a bound other than kappa = 0, with a BoundWarning counting them."""
    tol = 1e-9 * (hi - lo)
    low = p <= lo + tol
    low[..., 1] &= lo[1] > 0  # kappa = 0 is a lossless medium, a physical limit
    at = (low | (p >= hi - tol)) & valid[..., None]
    if np.any(at):
        P = p.shape[-1]
        where = ", ".join(
            f"{nm} ({int(at[..., k].sum())})"
            for k, nm in enumerate(PARAMETER_NAMES[:P])
            if at[..., k].any()
        )
        warnings.warn(
            f"the fit ended on a bound at {int(np.any(at, -1).sum())} of {int(valid.sum())} fitted "
            f"pixel(s), in {where}: there the value is the bound, not an estimate; widen "
            "FitOptions.bounds (see DolpFit.at_bound)",
            BoundWarning,
            stacklevel=3,
        )
    return at


def _check_fit_setup(options: FitOptions, M: int, P: int):
    """Validated starts (S, 2) and bounds ``lo, hi`` (P,) for P parameters from M geometries."""
    starts = check_starts(options.starts)
    options.validate()
    if M < P:
        raise ValueError(f"dolp has {M} geometries; at least {P} are needed to fit {P} parameters")
    lo, hi = parameter_bounds(options.bounds, P)
    return starts, lo, hi


def _fit_result(forward, p, cost, done, iterations, mask, valid, noise, sig_known) -> DolpFit:
    """Covariance, identifiability and the :class:`DolpFit` (NaN where a pixel is not valid)."""
    cov, identifiable = _laplace_covariance(forward, p, mask, cost, noise)
    identifiable = identifiable & valid[..., None]
    _warn_undetermined(valid, identifiable, p)
    nan = np.where(valid, 1.0, np.nan)
    sig_out = p[..., 2] if sig_known is None else sig_known
    return DolpFit(
        n=p[..., 0] * nan,
        kappa=p[..., 1] * nan,
        sigma=np.asarray(sig_out) * nan,
        covariance=cov * nan[..., None, None],
        cost=cost * nan,
        converged=done & valid,
        valid=valid,
        iterations=iterations,
        identifiable=identifiable,
    )


def _warn_undetermined(valid, identifiable, p):
    """An IdentifiabilityWarning naming the undetermined parameters and their pixel count (and
    whether kappa is undetermined because it is 0, where the DOLP is stationary in it)."""
    undetermined = valid & ~np.all(identifiable, -1)
    if not np.any(undetermined):
        return
    P = identifiable.shape[-1]
    names = [
        nm for k, nm in enumerate(PARAMETER_NAMES[:P]) if np.any(valid & ~identifiable[..., k])
    ]
    no_kappa = valid & ~identifiable[..., 1]
    at_zero = int(np.sum(no_kappa & (p[..., 1] <= 0)))
    why = (
        f"; kappa = 0 at {at_zero} of them, the lossless bound, where the DOLP is stationary in kappa"
        if at_zero
        else ""
    )
    warnings.warn(
        f"the data do not determine {', '.join(names)} at {int(undetermined.sum())} of "
        f"{int(valid.sum())} fitted pixel(s) (singular Fisher information at the solution{why}): "
        "their variance is reported as inf there; see DolpFit.identifiable",
        IdentifiabilityWarning,
        stacklevel=3,
    )


# costs below this (half the sum of squared, possibly whitened, residuals) are exact fits that differ
# by rounding: a DOLP residual of 1e-16 whitened by a noise of 1e-3 gives 1e-26 per geometry
EXACT_FIT_COST = 1e-20


def _best_of_starts(forward, y0, mask, valid, starts, sigma0, lo, hi, options: FitOptions):
    """Run LM from every start for the N flattened pixels; keep the lowest cost per pixel."""
    P = lo.size
    best_p = best_cost = best_done = None
    total_iter = 0
    # sigma fitted: every (n, kappa) start from each starting roughness (FitOptions.sigma_starts),
    # sigma0 first
    sigmas = [None] if sigma0 is None else list(dict.fromkeys((sigma0, *options.sigma_starts)))
    for s0, (n0, k0) in itertools.product(sigmas, starts):
        p = np.empty((valid.size, P))
        p[:, 0], p[:, 1] = n0, k0
        if s0 is not None:
            p[:, 2] = s0
        p = np.clip(p, lo, hi)
        p, cost, done, it = _levenberg_marquardt(
            forward, y0, mask, p, lo, hi, valid, options.max_iter, options.tol
        )
        total_iter += it
        if best_p is None:
            best_p, best_cost, best_done = p, cost, done
        else:
            take = cost < best_cost
            if s0 is not None and s0 != sigma0:
                # a further roughness start replaces sigma0's fit only where it fits clearly better:
                # between two exact fits (costs at rounding level) sigma0's stays, so a truth on a
                # bound (glass, kappa = 0) is not traded for a point beside it
                take = cost < best_cost * (1 - 1e-9) - EXACT_FIT_COST
            best_p = np.where(take[..., None], p, best_p)
            best_done = np.where(take, done, best_done)
            best_cost = np.where(take, cost, best_cost)
    return best_p, best_cost, best_done, total_iter


def _whitening(noise, systematic, covariance, mask):
    """Inverse Cholesky factor (M, M) of the DOLP error covariance, or None (unweighted fit)."""
    if systematic is None and covariance is None:
        return None
    M = mask.shape[-1]
    if covariance is not None:
        V = check_covariance(covariance, noise, M)
        if not np.all(mask):
            raise ValueError("covariance with missing (NaN) dolp entries: use sample_posterior")
    elif noise is None or np.ndim(noise):
        raise ValueError("systematic needs a scalar noise (or a covariance) to weight the fit")
    else:
        V = np.eye(M) * float(noise) ** 2
    t = check_systematic(systematic, M)
    L = np.linalg.cholesky(V + np.diag(np.zeros(M) if t is None else t**2))
    return np.linalg.inv(L)


class _Whitened:
    """A forward model whose values and Jacobian are multiplied by a whitening matrix (M, M)."""

    def __init__(self, forward, W):
        self.forward, self.W = forward, W

    def __call__(self, params, rows=None):
        return self.forward(params, rows) @ self.W.T

    def value_and_jacobian(self, params, rows=None):
        f, J = self.forward.value_and_jacobian(params, rows)
        return f @ self.W.T, np.einsum("ij,...jk->...ik", self.W, J)


def _laplace_covariance(forward, p, mask, cost, noise):
    """Laplace covariance s^2 (J^T J)^+ at the solutions ``p`` (..., P) and the identifiable
    parameters.

    Only the finite entries (the identifiable block) are scaled by ``s^2``: an undetermined
    parameter keeps its infinite variance (and NaN covariances) also where ``s^2 = 0`` (an exact,
    noise-free fit), where ``inf * 0`` would be NaN.
    """
    batch, P = p.shape[:-1], p.shape[-1]
    _, J = forward.value_and_jacobian(p.reshape(-1, P))
    J = J.reshape(batch + J.shape[-2:])
    J = np.where(mask[..., None], J, 0.0)
    m = mask.sum(-1)
    s2 = noise**2 if noise is not None else np.where(m > P, 2 * cost / np.maximum(m - P, 1), np.nan)
    A = np.einsum("...mi,...mj->...ij", J, J)
    cov, identifiable = inverse_information(A)
    finite = np.isfinite(cov)
    scaled = np.where(finite, cov, 0.0) * np.asarray(s2)[..., None, None]
    return np.where(finite, scaled, cov), identifiable


def fit_dolp_per_pixel(
    dolp,
    theta_i,
    theta_r,
    phi=np.pi,
    *,
    sigma=None,
    bounds=None,
    starts=DEFAULT_STARTS,
    sigma0: float = 0.3,
    **model_kw,
) -> DolpFit:
    """Baseline: one ``scipy.optimize.least_squares`` (trust-region reflective) per pixel and start.

    Same forward model, analytic Jacobian, starts and bounds as :func:`fit_dolp`, so that comparing
    the two
    measures batching alone. No covariance (NaN).

    Parameters
    ----------
    dolp : array (..., M)
        Measured DOLP; NaN entries are left out per pixel.
    theta_i, theta_r : array (M,) [rad]
    phi : float or array (M,) [rad], default pi
    sigma : float or array (...), optional
        Known roughness (then only n and kappa are fitted).
    bounds : dict, optional
        As in :class:`FitOptions`.
    starts : sequence of (n, kappa)
    sigma0 : float
        Starting roughness (finite, > 0).
    **model_kw
        ``shadowing``, ``diffuse``, ``distribution`` of :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    DolpFit
        Arrays over the leading axes of ``dolp``; ``covariance`` NaN, ``iterations`` 0.
    """
    y, ti, tr, ph = prepare_data(dolp, theta_i, theta_r, phi)
    starts = check_starts(starts)
    sigma0 = float(as_positive(sigma0, "sigma0"))
    fit_sigma = sigma is None
    P = 3 if fit_sigma else 2
    lo, hi = parameter_bounds(bounds, P)
    batch = y.shape[:-1]
    flat = y.reshape(-1, y.shape[-1])
    sig_flat = None if fit_sigma else np.broadcast_to(np.asarray(sigma, float), batch).ravel()
    out = np.full((flat.shape[0], 3), np.nan)
    cost = np.full(flat.shape[0], np.nan)
    for i, row in enumerate(flat):
        ok = np.isfinite(row)
        if ok.sum() < P:
            continue
        fwd = DolpForward(
            ti[ok], tr[ok], ph[ok], sigma=None if fit_sigma else sig_flat[i], **model_kw
        )
        target = row[ok]

        def res(p, fwd=fwd, target=target):
            return fwd(p) - target

        def jac(p, fwd=fwd):
            return fwd.value_and_jacobian(p)[1]

        best = None
        for n0, k0 in starts:
            x0 = np.clip([n0, k0] + ([sigma0] if fit_sigma else []), lo + 1e-9, hi - 1e-9)
            res_ = optimize.least_squares(
                res, x0, jac=jac, bounds=(lo, hi), xtol=1e-14, ftol=1e-14, gtol=1e-14
            )
            if best is None or res_.cost < best.cost:
                best = res_
        out[i, :P] = best.x
        if not fit_sigma:
            out[i, 2] = sig_flat[i]
        cost[i] = best.cost
    valid = np.isfinite(cost).reshape(batch)
    return DolpFit(
        n=out[:, 0].reshape(batch),
        kappa=out[:, 1].reshape(batch),
        sigma=out[:, 2].reshape(batch),
        covariance=np.full(batch + (P, P), np.nan),
        cost=cost.reshape(batch),
        converged=valid,
        valid=valid,
        iterations=0,
    )
