r"""Fits of the pBRDF to measured, normalised Mueller elements in the specular geometry (Sec. 4.4).

The measured elements are :math:`M_{01}/M_{00}, M_{11}/M_{00}, M_{22}/M_{00}, M_{23}/M_{00}` against
the angle :math:`\theta = \theta_i = \theta_r` (observation in the specular plane, :math:`\phi =
\pi`), as in Figs. 41-42. The model is :class:`scatterlab.pbrdf.Model` (Eq. 177): in the specular
plane its normalised elements are :math:`\Gamma M_{jk}/[(\Gamma + D) M_{00}]`, so the roughness
enters through the diffuse fraction. Bounded nonlinear least squares
(``scipy.optimize.least_squares``, trust-region reflective) from several starting points; the
covariance of the parameters is :math:`s^2 (J^T J)^{-1}` with :math:`s^2` the residual variance (or
the given standard errors as weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from scatterlab._checks import ETA_MAX, ETA_MIN, as_angle, as_finite, as_positive, check_starts
from scatterlab.fresnel import mueller_matrix
from scatterlab.pbrdf import Model

__all__ = [
    "ELEMENTS",
    "ELEMENT_TOLERANCE",
    "FIT_BOUNDS",
    "IndexFitMixin",
    "normalised_elements",
    "model_elements",
    "fit_mueller_elements",
    "MuellerFit",
    "least_squares_from_starts",
    "check_bounds",
    "STD_MIN",
]

ELEMENTS = ((0, 1), (1, 1), (2, 2), (2, 3))
ELEMENT_TOLERANCE = 0.05  # normalised elements may exceed [-1, 1] by this much (measurement noise)
# fit_mueller_elements' default box for (n, kappa, sigma): a parameter at one of these values is a bound,
# not an estimate (kappa = 0, a dielectric, is physical)
FIT_BOUNDS = ((0.01, 10.0), (0.0, 30.0), (0.01, 1.5))
SIGMA_RANGE = (1e-4, 5.0)  # the rms slopes the pBRDF accepts (scatterlab.pbrdf.Model)
# smallest standard error of a normalised element (in [-1, 1], known to ~1e-16 in double precision):
# below it the weights 1/std make J^T J overflow (std = 1e-300) and add nothing but rounding
STD_MIN = 1e-15


def check_bounds(bounds, name: str = "bounds") -> tuple[np.ndarray, np.ndarray]:
    """Validated box ``((n_lo, n_hi), (kappa_lo, kappa_hi), (sigma_lo, sigma_hi))`` of a pBRDF fit.

    Shared by :func:`fit_mueller_elements` and :func:`scatterlab.ellipsometry.fit_pbrdf`.

    Parameters
    ----------
    bounds : array_like (3, 2)
        Finite, ``lo < hi`` for each parameter; ``n_lo >= 0`` and ``kappa_lo >= 0`` (the domain of
        ``eta = n - 1j*kappa``) with ``|eta|`` of the box's corners within ``[1e-50, 1e50]``
        (:data:`scatterlab._checks.ETA_MIN`, ``ETA_MAX``); sigma within ``[1e-4, 5]``.
    name : str
        The argument's name in the messages.

    Returns
    -------
    lo, hi : ndarray (3,)
        Lower and upper bounds of (n, kappa, sigma).

    Raises
    ------
    ValueError
        Any of the conditions above violated (the message names ``name`` and the allowed range).
    """
    form = f"{name} must be ((n_lo, n_hi), (kappa_lo, kappa_hi), (sigma_lo, sigma_hi))"
    try:
        arr = np.asarray(bounds, float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{form}, got {bounds!r}") from exc
    if arr.shape != (3, 2):
        raise ValueError(f"{form}: shape (3, 2), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{form} with finite values (no NaN or inf), got {bounds!r}")
    lo, hi = arr.T
    if np.any(~(lo < hi)):
        raise ValueError(f"{form} with lo < hi for each parameter, got {bounds!r}")
    if lo[0] < 0 or lo[1] < 0:
        raise ValueError(
            f"{form} with n_lo >= 0 and kappa_lo >= 0 (eta = n - 1j*kappa), got {bounds!r}"
        )
    if np.hypot(lo[0], lo[1]) < ETA_MIN or np.hypot(hi[0], hi[1]) > ETA_MAX:
        raise ValueError(
            f"{form} with {ETA_MIN:g} <= |n - 1j*kappa| <= {ETA_MAX:g} at the corners (n_lo, kappa_lo) "
            f"and (n_hi, kappa_hi), got {bounds!r}"
        )
    s_lo, s_hi = SIGMA_RANGE
    if lo[2] < s_lo or hi[2] > s_hi:
        raise ValueError(f"{form} with sigma within [{s_lo:g}, {s_hi:g}], got {bounds!r}")
    return lo.copy(), hi.copy()


def normalised_elements(M) -> np.ndarray:
    """The four in-plane elements normalised by the first.

    Parameters
    ----------
    M : array_like (..., 4, 4)
        Mueller matrices (any scale), finite.

    Returns
    -------
    ndarray (..., 4)
        ``(M01, M11, M22, M23) / M00`` (0-based; ``m12, m22, m33, m34`` in 1-based names), the
        correctly rounded ratio wherever it is a finite double, also for a subnormal ``M00``
        (``M00 = 1e-310`` with elements of 1e-310 gives ratios near 1); NaN, without a warning,
        where ``M00 == 0`` (no light: the ratios are undefined).

    Raises
    ------
    ValueError
        If ``M`` is not of shape ``(..., 4, 4)`` or not finite, or if a ratio exceeds the largest
        double (1.8e308), e.g. ``M00 = 1e-310`` with ``M11 = 0.5``: a physical Mueller matrix has
        ``|Mjk| <= M00``, so such an ``M00`` is not a measured intensity of that matrix.
    """
    M = as_finite(M, "M")
    if M.shape[-2:] != (4, 4):
        raise ValueError(f"M must have shape (..., 4, 4), got {M.shape}")
    m00 = M[..., 0, 0]
    dark = m00 == 0
    m00 = np.where(dark, 1.0, m00)
    # IEEE division is correctly rounded: it overflows only where the ratio itself is beyond the
    # double range (finite inputs: inf marks exactly those), which is refused below
    with np.errstate(over="ignore"):
        out = np.stack([M[..., j, k] / m00 for j, k in ELEMENTS], -1)
    huge = np.isinf(out)
    if np.any(huge):
        idx = np.argwhere(huge)[0]
        j, k = ELEMENTS[idx[-1]]
        where = tuple(int(i) for i in idx[:-1])
        raise ValueError(
            f"M[{', '.join(map(str, where + (j, k)))}] / M[{', '.join(map(str, where + (0, 0)))}] = "
            f"{M[where + (j, k)]:.6g} / {M[where + (0, 0)]:.6g} exceeds the largest double "
            f"(1.8e308): M must have |Mjk| / M00 <= 1.8e308 (a physical Mueller matrix has "
            f"|Mjk| <= M00)"
        )
    return np.where(dark[..., None], np.nan, out)


def model_elements(
    theta, n, kappa, sigma, *, shadowing="torrance-sparrow", diffuse="hyde"
) -> np.ndarray:
    """pBRDF normalised elements in the specular geometry.

    Parameters
    ----------
    theta : array_like (N,) [rad]
        ``theta_i = theta_r``, observation in the specular plane (``phi = pi``).
    n, kappa : float
        Complex index ``n - 1j*kappa``.
    sigma : float
        Per-axis rms facet slope.
    shadowing, diffuse : str
        Options of :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    ndarray (N, 4)
        ``(M01, M11, M22, M23) / M00`` (see :func:`normalised_elements`); NaN where no light is
        reflected (``eta = 1``, the index of the incidence medium: ``M00 = 0``). At exactly grazing
        ``theta = pi/2`` the specular term diverges (:meth:`scatterlab.pbrdf.Model.diverges`) and
        dominates, so the ratios are its finite limit, those of the smooth surface's Fresnel matrix
        at grazing incidence (``r_s = r_p = -1``: ``(0, 1, 1, 0)``), as ``Model.dolp`` returns its
        limit there; ``Model.mueller`` holds 0 for that term, which gave the diffuse term's
        ``(0, 0, 0, 0)``.
    """
    model = Model(sigma, shadowing=shadowing, diffuse=diffuse)
    eta = n - 1j * kappa
    F = model.mueller(eta, theta, theta, np.pi)
    out = normalised_elements(F)
    grazing = np.broadcast_to(model.diverges(theta, theta, np.pi), out.shape[:-1])
    if np.any(
        grazing
    ):  # the specular term's limit: in the specular plane, the Fresnel matrix (Eq. 55)
        t = np.broadcast_to(theta, out.shape[:-1])[grazing]
        out[grazing] = normalised_elements(mueller_matrix(eta, t))
    return out


class IndexFitMixin:
    """``eta`` and ``errors`` of a fit result with ``n``, ``kappa`` and ``covariance``."""

    @property
    def eta(self) -> complex:
        """Complex index ``n - 1j*kappa``."""
        return complex(self.n, -self.kappa)

    @property
    def errors(self) -> np.ndarray:
        """1-sigma standard errors of (n, kappa, sigma) (sqrt of the covariance diagonal)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0, None))


@dataclass
class MuellerFit(IndexFitMixin):
    """Result of :func:`fit_mueller_elements`: best-fit index and roughness with 1-sigma errors."""

    n: float
    kappa: float
    sigma: float
    covariance: np.ndarray
    residuals: np.ndarray
    cost: float
    success: bool
    starts: int


def _checked_data(theta, measured, std, tolerance):
    """Validated ``(theta, measured, weights)`` of :func:`fit_mueller_elements`."""
    theta = as_angle(theta, "theta")
    y = as_finite(measured, "measured")
    if y.shape != (theta.size, 4):
        raise ValueError(f"measured must have shape ({theta.size}, 4), got {y.shape}")
    if np.any(np.abs(y) > 1 + tolerance):
        row, col = np.argwhere(np.abs(y) > 1 + tolerance)[0]
        raise ValueError(
            f"measured[{row}, {col}] = {y[row, col]:.6g}: normalised elements must lie in [-1, 1] "
            f"(within tolerance={tolerance})"
        )
    if std is None:
        w = np.ones_like(y)
    else:
        s = as_finite(std, "std")
        if s.shape != y.shape:
            raise ValueError(f"std must have the shape of measured {y.shape}, got {s.shape}")
        if np.any(s < STD_MIN):
            raise ValueError(
                f"std (standard errors of the normalised elements) must be >= {STD_MIN:g}, got "
                f"{float(s.min()):.3g}"
            )
        w = 1.0 / s
    return theta, y, w


def fit_mueller_elements(
    theta,
    measured,
    *,
    std=None,
    sigma=None,
    fit_sigma: bool = True,
    starts=((0.5, 5.0), (1.5, 10.0), (3.0, 3.0), (1.5, 0.1)),
    sigma0: float = 0.3,
    bounds=None,
    shadowing="torrance-sparrow",
    diffuse="hyde",
    tolerance: float = ELEMENT_TOLERANCE,
) -> MuellerFit:
    """Fit (n, kappa[, sigma]) of the pBRDF to normalised Mueller elements at specular angles.

    Parameters
    ----------
    theta : array_like (N,) [rad]
        theta_i = theta_r of each measurement.
    measured : array_like (N, 4)
        ``(M01, M11, M22, M23) / M00`` (see :func:`normalised_elements`), in [-1, 1] up to
        ``tolerance``.
    std : array_like (N, 4), optional
        Standard errors used as weights, finite and ``>= 1e-15`` (:data:`STD_MIN`: below the
        double-precision resolution of elements in [-1, 1], where ``1/std`` overflows the fit).
    sigma : float, optional
        Known roughness (required when ``fit_sigma`` is False; the starting value otherwise).
    fit_sigma : bool
        Fit the roughness too (otherwise it is held at ``sigma``).
    starts : sequence of (n, kappa)
        Starting points; the best final cost wins (metal/dielectric ambiguity).
    sigma0 : float
        Starting roughness when ``sigma`` is not given (finite, > 0).
    bounds : ((n_lo, n_hi), (k_lo, k_hi), (s_lo, s_hi)), optional
        Box of the fit (default :data:`FIT_BOUNDS`), checked by :func:`check_bounds`: finite,
        ``lo < hi``, ``n_lo, k_lo >= 0``, sigma within ``[1e-4, 5]``; the sigma bounds are checked
        but unused when ``fit_sigma`` is False.
    shadowing, diffuse : str
        Options of :class:`scatterlab.pbrdf.Model`.
    tolerance : float
        How far normalised elements may lie outside [-1, 1] (noise) before the data are refused
        (finite, >= 0).

    Returns
    -------
    MuellerFit
        ``n``, ``kappa``, ``sigma``, ``covariance`` (3, 3) (zero row and column for a fixed sigma),
        weighted ``residuals`` (N, 4), ``cost``, ``success``.

    Raises
    ------
    ValueError
        Angles outside [0, pi/2], ``measured`` of the wrong shape, non-finite, or outside [-1, 1]
        beyond ``tolerance``; ``std`` below 1e-15 or of the wrong shape; no ``sigma`` with
        ``fit_sigma=False``; empty, non-finite or negative ``starts``; bad ``bounds`` (see
        :func:`check_bounds`); ``sigma``, ``sigma0`` or ``tolerance`` out of range.
    """
    tolerance = float(as_positive(tolerance, "tolerance", allow_zero=True))
    theta, y, w = _checked_data(theta, measured, std, tolerance)
    starts = check_starts(starts)
    lo, hi = check_bounds(FIT_BOUNDS if bounds is None else bounds)
    if not fit_sigma and sigma is None:
        raise ValueError("sigma must be given when fit_sigma is False")
    if sigma is None:
        s0 = float(as_positive(sigma0, "sigma0"))
    else:
        s0 = float(as_positive(sigma, "sigma"))

    def residual(p):  # weighted model - measured, p = (n, kappa[, sigma])
        s = p[2] if fit_sigma else s0
        pred = model_elements(theta, p[0], p[1], s, shadowing=shadowing, diffuse=diffuse)
        return ((pred - y) * w).ravel()

    P = 3 if fit_sigma else 2
    lo, hi = lo[:P], hi[:P]
    x0s = [np.clip([n0, k0, s0][:P], lo + 1e-9, hi - 1e-9) for n0, k0 in starts]
    best = least_squares_from_starts(residual, x0s, lo, hi, tol=1e-15, max_nfev=2000)
    cov = _covariance(best.jac, 1.0 if std is not None else 2 * best.cost / _dof(best))
    x = best.x
    return MuellerFit(
        n=float(x[0]),
        kappa=float(x[1]),
        sigma=float(x[2] if fit_sigma else s0),
        covariance=cov if fit_sigma else np.pad(cov, ((0, 1), (0, 1))),
        residuals=best.fun.reshape(-1, 4),
        cost=float(best.cost),
        success=bool(best.success),
        starts=len(starts),
    )


def _dof(res) -> int:
    """Degrees of freedom (>= 1) of a least-squares result: residuals minus parameters."""
    return max(1, res.fun.size - res.jac.shape[1])


def _covariance(J, s2) -> np.ndarray:
    """``s2 (J^T J)^-1`` (P, P); infinite where ``J^T J`` is singular."""
    try:
        return np.linalg.inv(J.T @ J) * s2
    except np.linalg.LinAlgError:
        return np.full((J.shape[1], J.shape[1]), np.inf)


def least_squares_from_starts(residual, x0s, lo, hi, *, tol: float, max_nfev: int):
    """The lowest-cost bounded least-squares solution over several starting points.

    Trust-region reflective (``scipy.optimize.least_squares``, ``x_scale="jac"``) from each start;
    the first of equal costs wins.

    Parameters
    ----------
    residual : callable
        ``residual(x) -> ndarray (K,)``, the weighted residuals of parameters ``x`` (P,).
    x0s : sequence of ndarray (P,)
        Starting points, strictly inside the bounds.
    lo, hi : array_like (P,)
        Bounds of the parameters.
    tol : float
        ``xtol = ftol = gtol`` of the solver.
    max_nfev : int
        Evaluation limit per start.

    Returns
    -------
    scipy.optimize.OptimizeResult
        The best result (``x``, ``cost``, ``fun``, ``jac``, ``success``).
    """
    best = None
    for x0 in x0s:
        res = optimize.least_squares(
            residual,
            x0,
            bounds=(lo, hi),
            method="trf",
            x_scale="jac",
            xtol=tol,
            ftol=tol,
            gtol=tol,
            max_nfev=max_nfev,
        )
        if best is None or res.cost < best.cost:
            best = res
    return best
