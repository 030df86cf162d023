r"""Thilak et al.'s two-step estimate of (n, kappa) and theta_r from DOP (Eqs. 115-117), the comparison baseline.

Forward model (Eq. 115, with the errata's A and B): the DOP of unpolarized light reflected by smooth facets
at the facet angle :math:`\beta = (\theta_i + \theta_r)/2`,

.. math:: P(n, \kappa, \beta) = \frac{2A\sin^2\beta\cos\beta}{A^2\cos^2\beta + \sin^4\beta + B^2\cos^2\beta},
   \quad A = \sqrt{(\sqrt C + D)/2},\ B = \sqrt{(\sqrt C - D)/2},\ C = 4n^2\kappa^2 + D^2,\
   D = n^2 - \kappa^2 - \sin^2\beta.

Step 1 (Eq. 116): unconstrained nonlinear least squares (Levenberg-Marquardt) of (n, kappa) with
:math:`\beta_j` from the nominal theta_r. Step 2 (Eq. 117): with (n, kappa) fixed, least squares of theta_r.
As the authors did, a solution outside the physical range (n or kappa < 0, theta_r outside (0, 90) deg) is
discarded and the fit restarted (from a random start drawn with ``rng``); after ``max_restarts`` the trial is
reported as failed (NaN). The text does not give the rest of the procedure, so the solver (LM,
trust-region reflective with an optional box, Nelder-Mead), its tolerances and evaluation limit,
and the start of step 2 are options (``studies/thilak_tables.py`` measures them against Tables
1-2). :func:`thilak_crlb` gives the Cramer-Rao bounds of (n, kappa, theta_r) for a design.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from scatterlab._checks import ETA_MIN, as_angle, as_finite, as_positive, as_rng, check_starts
from scatterlab.fresnel import smooth_dolp
from scatterlab.inversion.design import inverse_information

__all__ = ["thilak_dop", "thilak_two_step", "ThilakFit", "thilak_jacobian", "thilak_crlb"]


def thilak_dop(n, kappa, beta) -> np.ndarray:
    """Eq. 115 for any real (n, kappa) (the unconstrained fit may visit negative values); broadcasts.

    Eq. 115 depends on ``n`` and ``kappa`` through ``n^2``, ``kappa^2`` and ``(n kappa)^2`` only, and
    for ``n, kappa >= 0`` it is the smooth-facet DOLP ``(Rs - Rp)/(Rs + Rp)``: this evaluates the
    package's kernel :func:`scatterlab.fresnel.smooth_dolp` at ``|n| - j|kappa|`` (tested equal to
    the printed formula with the errata's A and B), continued as an odd function of ``cos(beta)``
    like the printed formula. Outside the kernel's range ``1e-50 <= |eta| <= 1e50`` it is the
    limit: 0 at ``n = kappa = 0`` (evaluated at ``|eta| = 1e-50``), and for
    ``max(|n|, |kappa|) > 1e49`` the large-index form of Eq. 115 (:func:`_large_index_dop`,
    relative error below ``|eta|^-2``), finite up to the largest floats.

    Parameters
    ----------
    n, kappa : array_like
        Real and imaginary parts of the index (any sign, finite) [dimensionless].
    beta : array_like [rad]
        Facet angle.

    Returns
    -------
    ndarray, broadcast shape, in ``[-1, 1]`` (``[0, 1]`` for ``beta`` in ``[0, pi/2]``).
    """
    n, kappa, beta = np.broadcast_arrays(
        np.abs(np.asarray(n, float)), np.abs(np.asarray(kappa, float)), np.asarray(beta, float)
    )
    c = np.cos(beta)  # the fit may visit beta > 90 deg, where Eq. 115 is odd in cos(beta)
    s2 = np.sin(beta) ** 2
    large = np.maximum(n, kappa) > LARGE_INDEX
    eta = np.where(large, 1.0, n - 1j * kappa)
    eta = np.where(np.abs(eta) < ETA_MIN, ETA_MIN, eta)  # n = kappa = 0: the limit |eta| -> 0
    P = smooth_dolp(eta, np.abs(c), s2, checked=True)[0]
    if np.any(large):
        P = np.where(large, _large_index_dop(n, kappa, np.abs(c), s2, large), P)
    return np.sign(c) * P


# beyond this max(|n|, |kappa|) Eq. 115 is evaluated in its large-index form (|eta| >= 1e49 there,
# and |eta| <= 1.5e49 < ETA_MAX below it, inside the range of smooth_dolp)
LARGE_INDEX = 1e49


def _large_index_dop(n, kappa, c, s2, large):
    r"""Eq. 115 for ``|eta| -> inf``: :math:`P = 2 n s^2 c / (|\eta|^2 c^2 + s^4)`.

    With :math:`u = \eta\sqrt{1 - s^2/\eta^2}`, :math:`A = n (1 + O(|\eta|^{-2}))` and
    :math:`|u|^2 = |\eta|^2 (1 + O(|\eta|^{-2}))`, so the relative error is below ``1e-97`` where it
    is used (``large``: ``max(n, kappa) > 1e49``). Written without overflow up to the largest
    floats as :math:`P = 2 (n/|\eta|)\, g(t)`, :math:`g(t) = t/(1 + t^2)` with
    :math:`t = c |\eta| / s^2` (``g(t) = g(1/t)``, so ``t > 1`` uses ``1/t = s^2/(c |eta|)``).

    Parameters
    ----------
    n, kappa : ndarray
        ``|n|``, ``|kappa|`` [dimensionless], one shape.
    c, s2 : ndarray
        ``|cos(beta)|`` and ``sin(beta)^2``, the same shape.
    large : ndarray of bool
        Where the result is used; elsewhere it is a finite placeholder.

    Returns
    -------
    ndarray in ``[0, 1]``, the shape of the inputs.
    """
    m = np.where(large, np.maximum(n, kappa), 1.0)
    r = np.hypot(n / m, kappa / m)  # |eta| = m r, r in [1, sqrt(2)] where large
    with np.errstate(over="ignore", divide="ignore"):  # t or 1/t is inf: g = 0 (normal, grazing)
        cm = c * m
        t = cm / s2 * r
        inv = s2 / cm / r
    q = np.where(t > 1, inv, t)  # in [0, 1]
    return 2 * (n / m / r) * (q / (1 + q * q))


@dataclass
class ThilakFit:
    """Estimates per trial (K,): ``n``, ``kappa``, ``theta_r`` [rad]; ``restarts`` used; ``ok`` physical.

    ``ok`` says the solution is physical (n, kappa >= 0, theta_r in (0, 90) deg), as in Thilak et al.'s
    procedure; it does not say the data determine it. Where the DOP barely depends on a parameter (a
    near-perfect conductor: kappa = 1e3 has a DOP below 1e-5 at 35-80 deg) the solver stops where the
    cost stops changing, far from the truth: :func:`thilak_crlb` gives the spread the data allow.
    """

    n: np.ndarray
    kappa: np.ndarray
    theta_r: np.ndarray
    restarts: np.ndarray
    ok: np.ndarray


SOLVERS = ("lm", "trf", "nelder-mead")


def _check_options(solver, bounds, tol, max_nfev):
    """Validate the solver options of :func:`thilak_two_step`; returns ``bounds`` as arrays."""
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if bounds is not None:
        allowed = (
            "bounds must be ((n_lo, n_hi), (kappa_lo, kappa_hi)), two pairs with 0 <= lo < hi "
            "(lo finite, hi may be inf), "
            f"and need solver='trf'; got {bounds!r}"
        )
        try:
            b = None if isinstance(bounds, (str, bytes)) else np.asarray(bounds, float)
        except (TypeError, ValueError) as exc:
            raise ValueError(allowed) from exc
        if (
            b is None
            or b.shape != (2, 2)
            or not np.all(np.isfinite(b[:, 0]))
            or np.any(np.isnan(b))
        ):
            raise ValueError(allowed)
        lo, hi = b.T
        if solver != "trf" or np.any(lo < 0) or np.any(hi <= lo):
            raise ValueError(allowed)
        bounds = (lo, hi)
    if tol is not None and not 0 < tol < 1:
        raise ValueError(f"tol must be in (0, 1), got {tol}")
    if max_nfev is not None and max_nfev < 1:
        raise ValueError(f"max_nfev must be a positive integer, got {max_nfev}")
    return bounds


def _minimise(resid, x0, solver, bounds, tol, max_nfev):
    """Least squares of ``resid`` from ``x0`` with one of :data:`SOLVERS` -> the solution."""
    if solver == "nelder-mead":
        opts = {"xatol": tol or 1e-4, "fatol": tol or 1e-4, "maxfev": max_nfev or 200 * len(x0)}
        r = optimize.minimize(
            lambda p: float(np.sum(resid(p) ** 2)), x0, method="Nelder-Mead", options=opts
        )
        return r.x
    kw = {"ftol": tol, "xtol": tol, "gtol": tol} if tol else {}
    if bounds is not None:
        x0 = np.clip(x0, bounds[0], bounds[1])
        kw["bounds"] = bounds
    return optimize.least_squares(resid, x0, method=solver, max_nfev=max_nfev, **kw).x


def _two_step_row(row, ti, tr0, x0, opts, tr_start):
    """Eqs. 116-117 for one trial from the start ``x0`` (step 2 from ``tr_start``)."""
    solver, bounds, tol, max_nfev = opts
    beta = (ti + tr0) / 2
    n, kap = _minimise(lambda p: thilak_dop(p[0], p[1], beta) - row, x0, *opts)
    step2 = (np.array([0.0]), np.array([np.pi / 2])) if bounds is not None else None
    (t_r,) = _minimise(
        lambda t: thilak_dop(n, kap, (ti + t[0]) / 2) - row, np.array([tr_start]), solver, step2,
        tol, max_nfev,
    )  # fmt: skip
    return n, kap, t_r


def thilak_two_step(
    dop,
    theta_i,
    theta_r_nominal,
    rng,
    *,
    start=(1.0, 1.0),
    max_restarts: int = 50,
    solver: str = "lm",
    bounds=None,
    tol: float | None = None,
    max_nfev: int | None = None,
    theta_r_start=None,
    margin: float = 0.5,
) -> ThilakFit:
    """Thilak et al.'s two-step method for each row of ``dop`` (K, M) measured at ``theta_i`` (M,).

    Parameters
    ----------
    dop : array (K, M) or (M,)
        Measured DOP, finite and in ``[-margin, 1 + margin]`` (a DOP is in [0, 1]; the margin
        admits additive noise, as in the Monte-Carlo trials of Tables 1-3).
    theta_i : array (M,) [rad]
    theta_r_nominal : float [rad] -- the known reflection angle of step 1 and the start of step 2.
    rng : numpy.random.Generator -- restarts.
    start : (n, kappa) of the first attempt.
    max_restarts : int
        Random restarts (n in [0, 5], kappa in [0, 10]) after an unphysical solution.
    solver : {"lm", "trf", "nelder-mead"}
        Levenberg-Marquardt (MINPACK), trust-region reflective (the analogue of MATLAB's
        ``lsqnonlin`` interior-reflective Newton method, the only one taking ``bounds``), or
        Nelder-Mead on the sum of squares (MATLAB's ``fminsearch``).
    bounds : ((n_lo, n_hi), (kappa_lo, kappa_hi)) or None
        Box of step 1 (step 2 is then bounded to theta_r in [0, 90] deg); a bounded solution is
        physical by construction, so it never restarts. Exactly two pairs with ``0 <= lo < hi``
        (``lo`` finite), only with ``solver="trf"``; anything else is a ValueError.
    tol : float or None
        Stopping tolerance on the relative change of the cost and of the parameters and on
        the gradient (``ftol``, ``xtol``, ``gtol``; for Nelder-Mead the absolute ``xatol`` and
        ``fatol``, default 1e-4); None keeps scipy's defaults (1e-8). MATLAB's defaults are
        1e-6 (``lsqnonlin``) and 1e-4 (``fminsearch``). In the flat (n, kappa) valley of few
        measurements the stopping point depends on it.
    max_nfev : int or None
        Function evaluations per fit (None: scipy's default; MATLAB's ``lsqnonlin`` stops at
        ``100 * 2``, ``fminsearch`` at ``200 * 2`` for two unknowns).
    theta_r_start : float [rad], "random" or None
        Start of step 2: None for ``theta_r_nominal``; "random" draws it uniformly in
        (0, 90) deg with ``rng`` for every attempt.
    margin : float
        Allowed excursion of ``dop`` outside [0, 1] (finite, >= 0; 0 requires [0, 1]).

    Returns
    -------
    ThilakFit

    Raises
    ------
    ValueError
        If ``dop`` has a NaN, an infinite value or a value outside ``[-margin, 1 + margin]``;
        ``start`` not a finite (n, kappa) pair with both >= 0; ``max_restarts`` not an integer >= 0.
    """
    margin = float(as_positive(margin, "margin", allow_zero=True))
    rng = as_rng(rng)
    start = check_starts([start], "start")[0]
    if isinstance(max_restarts, bool) or not isinstance(max_restarts, (int, np.integer)):
        raise ValueError(f"max_restarts must be an integer >= 0, got {max_restarts!r}")
    if max_restarts < 0:
        raise ValueError(f"max_restarts must be >= 0, got {max_restarts}")
    y = np.atleast_2d(as_finite(dop, "dop"))
    bad = (y < -margin) | (y > 1 + margin)
    if np.any(bad):
        raise ValueError(
            f"dop must be in [0, 1] (within margin = {margin:g}); got {int(bad.sum())} value(s) "
            f"outside, e.g. {y[bad][0]:.4g}"
        )
    ti = as_angle(theta_i, "theta_i").ravel()
    tr0 = float(as_angle(theta_r_nominal, "theta_r_nominal"))
    if y.shape[-1] != ti.size:
        raise ValueError(
            f"dop must have {ti.size} values per trial (one per theta_i), got shape {y.shape}"
        )
    if ti.size < 3:
        raise ValueError(
            "theta_i must hold at least 3 measurements (Eq. 116 has two unknowns plus theta_r)"
        )
    opts = (solver, _check_options(solver, bounds, tol, max_nfev), tol, max_nfev)
    if isinstance(theta_r_start, str) and theta_r_start != "random":
        raise ValueError(f"theta_r_start must be an angle, 'random' or None, got {theta_r_start!r}")
    if theta_r_start is not None and theta_r_start != "random":
        theta_r_start = float(as_angle(theta_r_start, "theta_r_start"))
    out = np.full((y.shape[0], 3), np.nan)
    restarts = np.zeros(y.shape[0], int)
    for k, row in enumerate(y):
        x0 = np.array(start, float)
        for _ in range(max_restarts + 1):
            t2 = tr0 if theta_r_start is None else theta_r_start
            t2 = rng.uniform(0, np.pi / 2) if t2 == "random" else t2
            n, kap, t_r = _two_step_row(row, ti, tr0, x0, opts, t2)
            if n >= 0 and kap >= 0 and 0 < t_r < np.pi / 2:
                out[k] = n, kap, t_r
                break
            restarts[k] += 1
            x0 = np.array([rng.uniform(0, 5), rng.uniform(0, 10)])
    ok = np.isfinite(out[:, 0])
    return ThilakFit(n=out[:, 0], kappa=out[:, 1], theta_r=out[:, 2], restarts=restarts, ok=ok)


def thilak_jacobian(n, kappa, beta) -> np.ndarray:
    """Derivatives of Eq. 115 in (n, kappa, beta) for n, kappa > 0 and beta in (0, 90) deg.

    The derivatives in n and kappa are analytic (those of
    :func:`scatterlab.fresnel.smooth_dolp`); the one in beta is a fourth-order central difference
    with step 1e-3 rad (truncation error ~1e-13 relative).

    Parameters
    ----------
    n, kappa : array_like
    beta : array_like [rad]

    Returns
    -------
    ndarray (..., 3), broadcast shape of the inputs plus (dP/dn, dP/dkappa, dP/dbeta [1/rad]).
    """
    n, kappa, beta = np.broadcast_arrays(*(np.asarray(a, float) for a in (n, kappa, beta)))
    _, grad = smooth_dolp(n - 1j * kappa, np.cos(beta), np.sin(beta) ** 2, gradient=True)
    h = 1e-3
    f = [thilak_dop(n, kappa, beta + s * h) for s in (-2, -1, 1, 2)]
    dbeta = (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * h)
    return np.concatenate([grad, dbeta[..., None]], -1)


def thilak_crlb(n, kappa, theta_r, theta_i, noise, *, theta_r_known: bool = False) -> np.ndarray:
    """Cramer-Rao bounds of (n, kappa, theta_r) from DOP measurements (Eq. 115) at ``theta_i``.

    Fisher information :math:`J^TJ/s^2` with :math:`J` the Jacobian of
    :math:`P(n, \\kappa, (\\theta_i + \\theta_r)/2)`; with ``theta_r_known`` the information of
    (n, kappa) alone, the situation of Thilak's step 1 (Eq. 116), where the angle is given.
    Directions the design does not determine get an infinite bound
    (:func:`scatterlab.inversion.design.inverse_information`).

    Parameters
    ----------
    n, kappa : float
        The truth, n > 0, kappa >= 0. For a dielectric (kappa = 0, n > sin of every angle) the DOP is
        stationary in kappa (the Fresnel coefficients are real there), so kappa gets an infinite
        bound: a boundary truth, where no unbiased estimator exists; the bounds of the other
        parameters are those with kappa known.
    theta_r : float [rad]
    theta_i : array (M,) [rad]
    noise : float
        DOP noise standard deviation (> 0). ``n``, ``kappa``, ``theta_r`` and ``noise`` are
        real scalars (an array or a string is a ValueError): call once per truth.
    theta_r_known : bool

    Returns
    -------
    ndarray (3,) or (2,)
        Standard deviations of (n, kappa[, theta_r]) (theta_r in rad).
    """
    for name, value in (("n", n), ("kappa", kappa), ("theta_r", theta_r), ("noise", noise)):
        if np.ndim(value) != 0:
            raise ValueError(
                f"{name} must be a single float (one truth per call), got shape {np.shape(value)}"
            )
        if isinstance(value, (str, bytes)):
            raise ValueError(f"{name} must be a single float (one truth per call), got {value!r}")
        try:
            float(value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{name} must be a single float, got {value!r}") from exc
    n, kappa, theta_r, noise = (float(v) for v in (n, kappa, theta_r, noise))
    if not (np.isfinite(noise) and noise > 0):
        raise ValueError(f"noise must be a positive DOP standard deviation, got {noise}")
    if not (np.isfinite(n) and np.isfinite(kappa) and n > 0 and kappa >= 0):
        raise ValueError(
            f"n must be > 0 and kappa >= 0 (eta = n - 1j*kappa, finite), got {n}, {kappa}"
        )
    ti = as_angle(theta_i, "theta_i").ravel()
    tr = float(as_angle(theta_r, "theta_r"))
    J = thilak_jacobian(n, kappa, (ti + tr) / 2) * np.array([1.0, 1.0, 0.5])  # dbeta/dtheta_r
    if theta_r_known:
        J = J[:, :2]
    if ti.size < J.shape[1]:
        raise ValueError(f"theta_i must hold at least {J.shape[1]} angles, got {ti.size}")
    cov, _ = inverse_information(J.T @ J / noise**2)
    return np.sqrt(np.clip(np.diagonal(cov), 0, None))
