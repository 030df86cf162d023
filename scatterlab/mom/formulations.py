r"""One entry for the method of moments: both polarizations, perfect conductors and real materials.

Field :math:`\psi = E_z` (s-pol, Eq. 178) or :math:`H_z` (p-pol); medium 1 (vacuum, wavenumber k)
above an open profile or outside a closed body, medium 2 (index :math:`\eta = n - j\kappa`,
:math:`k_2 = k\eta`) below it or inside; :math:`\hat n` points into medium 1; unknowns :math:`\psi`
and :math:`U = \partial\psi_1/\partial n` on the surface. Green's theorem in each medium, with the
surface limits of the double layer (:math:`\pm\psi/2`; :mod:`scatterlab.mom.kernels` gives S and the
principal value D), reads

.. math:: \tfrac12\psi - D_1\psi + S_1U = \psi_{inc}, \qquad \tfrac12\psi + D_2\psi - \rho S_2U = 0

with the interface conditions :math:`\psi_2 = \psi_1` and :math:`\partial_n\psi_2 =
\rho\,\partial_n\psi_1`,
:math:`\rho = 1` (s) or :math:`\eta^2` (p: the tangential E is :math:`\partial_n
H_z/(j\omega\epsilon)`). This is the direct two-medium formulation of Tsang, Kong, Ding and Ao
(Scattering of Electromagnetic Waves: Numerical Simulations, 2001, Ch. 4), solved as one 2N x 2N
system.

* ``eta=None``, s-pol: :func:`~scatterlab.mom.efie.solve_tm` (EFIE, :math:`\psi = 0`), unchanged.
* ``eta=None``, p-pol: U = 0, the magnetic-field equation :math:`(\tfrac12 - D_1)\psi = \psi_{inc}`
  (second kind). For a closed body it fails near the interior Dirichlet resonances (zeros of
  :math:`J_n(ka)` for a circle -- a known property of the MFIE; open profiles have none), so
  CHIEF rows (:func:`chief_rows`: the field vanishes at points inside) are added and the
  overdetermined system is solved by least squares.
* ``method="impedance"`` (Leontovich): inside a good conductor the field is a wave travelling
  straight in,
  :math:`\partial_n\psi_2 = jk\eta\,\psi`, so :math:`U = jk\eta\psi` (s) or :math:`U = jk\psi/\eta`
  (p), and only medium 1 is discretised: one N x N system, about the cost of the perfect conductor.
  Exact for a flat interface up to :math:`\sqrt{\eta^2 - \sin^2\theta}\approx\eta`, i.e. a relative
  error in the reflection coefficient of order :math:`\sin^2\theta/(2|\eta|^2)`; needs
  :math:`|\eta|\gg1` and radii of curvature and roughness scales much larger than the skin depth
  :math:`\lambda/(2\pi\kappa)`. Measured errors (tests and
  ``studies/performance/perf_mom_materials.py``): aluminium 1.44 - 16j, 2e-4 in R at 60 deg (flat);
  iron 3.60 - 5.88j is already at the percent level and should use ``method="exact"``.

Truncated profiles in p. On an open profile the p-pol perfect conductor (and the impedance method
with a large :math:`|\eta|`) conserves energy less well than s at the same length: a PEC rough
surface lit by a tapered wave reflects less than 1. This is the truncation of the surface, not the
solver, the far field or the normalisation (measured on a slope-0.28 surface, 12.8 wavelengths, g =
L/4.5, 28.6 deg, studies in ``tests/mom/test_mom_truncation.py``):

* the deficit is converged in N (0.9791, 0.9799, 0.9801 at 20, 40, 80 points per wavelength),
  the flat plate reflects 1 within 4e-5 (0 and 28.6 deg), and ``incident_power`` equals the
  Poynting flux of the taper's plane-wave spectrum within 3e-5;
* the field scattered towards grazing does not vanish on a conductor in p (H_z doubles where E_z
  cancels in s), so it runs along the surface to its ends: 70-87 % of the deficit is found as
  power radiated below the profile past its ends (the lower half-plane far field of incident plus
  scattered field), the rest is lost on the profile near its ends, where the field below the
  truncated surface is not zero so the second-kind equation :math:`(\tfrac12 - D)\psi = \psi_{inc}`
  (extinction below) no longer enforces :math:`\partial_n\psi = 0` (the open-profile p-pol
  equation is not reciprocal under plane waves that light the ends: 8-52 % on a flat plate, against
  3e-4 in s, whose EFIE is the exact Dirichlet strip);
* the deficit falls as about :math:`L^{-1/2}` at a fixed taper (2.7 %, 1.9 %, 1.2 % for L = 4.5, 9,
  18 g on one surface), the fraction of the grazing lobe that the ends intercept; it grows with the
  slope.

:func:`solve` warns when :func:`edge_field_ratio`, :math:`\lambda(|\psi_1|^2 + |\psi_N|^2)/P_{inc}`,
exceeds 2e-3 (measured deficits 0.3-1.5 times it). Use a longer surface for the same taper (the
surface beyond the taper may be flat).
"""

from __future__ import annotations

import time
import warnings

import numpy as np
from scipy import linalg

from scatterlab._checks import as_index, as_positive
from scatterlab.mom.efie import (
    Solution,
    check_incidence_list,
    check_incidences,
    check_sampling,
    contour,
    solve_tm,
)
from scatterlab.mom.incidence import TaperedWave
from scatterlab.mom.kernels import arclength_contour, hankel2, layer_matrices

__all__ = ["TruncationWarning", "edge_field_ratio", "solve"]


def _linear_solve(A, V, solver, tol, max_iter, block, interleave):
    """LU (one factorisation for all columns of V) or block forward-backward with the LU
    fallback."""
    from scatterlab.mom.solvers import forward_backward

    if solver == "lu":
        return linalg.lu_solve(linalg.lu_factor(A, check_finite=False), V, check_finite=False), "lu"
    if solver != "fb":
        raise ValueError(f"solver must be 'lu' or 'fb', got {solver!r}")
    order = np.arange(A.shape[0])
    if interleave:  # keep (psi_n, U_n) of one pulse together so the blocks follow the surface
        half = A.shape[0] // 2
        order = np.stack([order[:half], order[half:]], 1).ravel()
    U, info = forward_backward(
        A[np.ix_(order, order)], V[order], tol=tol, max_iter=max_iter, block=block
    )
    if info["converged"]:
        out = np.empty_like(U)
        out[order] = U
        return out, "fb"
    warnings.warn(
        f"forward-backward did not converge ({info['reason']}); falling back to LU", stacklevel=3
    )
    return linalg.lu_solve(
        linalg.lu_factor(A, check_finite=False), V, check_finite=False
    ), "lu (fallback)"


def _system(c, k, polarization, eta, method, band):
    """The matrix, and how to split its solution into (U, psi): returns (A, split)."""
    N = c.size
    I2 = 0.5 * np.eye(N)
    if eta is None:  # p-pol PEC: (1/2 - D1) psi = psi_inc, U = 0
        _, D1 = layer_matrices(c, k, single=False, band=band)
        return I2 - D1, lambda X: (np.zeros_like(X), X)
    S1, D1 = layer_matrices(c, k, band=band)
    if method == "impedance":
        if polarization == "s":  # unknown U, psi = U / (jk eta)
            A = (I2 - D1) / (1j * k * eta) + S1
            return A, lambda X: (X, X / (1j * k * eta))
        beta = 1j * k / eta  # p: unknown psi, U = jk psi / eta
        return I2 - D1 + beta * S1, lambda X: (beta * X, X)
    S2, D2 = layer_matrices(c, k * eta, band=band)
    rho = 1.0 if polarization == "s" else eta * eta
    A = np.block([[I2 - D1, S1], [I2 + D2, -rho * S2]])
    return A, lambda X: (X[N:], X[:N])


def solve(
    x,
    y,
    wavelength,
    incidence,
    *,
    polarization: str = "s",
    eta=None,
    closed: bool = False,
    method: str = "exact",
    solver: str = "lu",
    tol: float = 1e-6,
    max_iter: int = 50,
    block: int = 256,
    min_points_per_wavelength: float = 5.0,
    band: float = 2.0,
    fast=None,
) -> Solution:
    """Scattering by a rough profile or a closed body, s- or p-polarized, PEC or a real material.

    Parameters
    ----------
    x, y : array (N,) [m] -- contour points (open profile with increasing x, or closed
        counter-clockwise).
    wavelength : float [m] -- in medium 1 (vacuum).
    incidence : PlaneWave, TaperedWave or a non-empty list of them (one factorisation
        for all).
    polarization : "s" (E along z, Eq. 178) or "p" (H along z).
    eta : complex, optional -- index n - j kappa of the medium below / inside; None is a perfect
        conductor.
    closed : bool
    method : "exact" (two-medium, both media sampled) or "impedance" (Leontovich, for |eta| >> 1;
        module docstring for its validity).
    solver : "lu", "fb" (block forward-backward with the LU fallback) or "fast" (s-pol PEC open
        profiles only: :mod:`scatterlab.mom.fast`).
    tol, max_iter, block : forward-backward controls.
    min_points_per_wavelength : below this (longest pulse) in either medium raises ValueError; a
        median pulse longer than 1/8 of the wavelength in a medium warns. Inside, the wavelength is
        lambda / |eta|.
    band : half-width of the near-field quadrature band in wavelengths of each medium.
    fast : FastOptions, optional -- knobs of ``solver="fast"``.

    Returns
    -------
    Solution -- ``current`` U, ``surface_field`` psi, far field, scattering and transmission
    coefficients.

    Warns
    -----
    TruncationWarning (a UserWarning) -- p-pol open profile whose ends keep a large field (:func:`edge_field_ratio` >
    2e-3): the scattering coefficient then integrates to less than 1 for a lossless conductor
    (power lost at the truncation, module docstring "Truncated profiles in p"); use a longer
    surface.
    """
    _check_choices(polarization, method, solver, eta)
    as_positive(band, "band")
    as_positive(min_points_per_wavelength, "min_points_per_wavelength")
    controls = {"solver": solver, "tol": tol, "max_iter": max_iter, "block": block}
    if eta is None and polarization == "s":
        mppw = min_points_per_wavelength
        return solve_tm(
            x,
            y,
            wavelength,
            incidence,
            closed,
            min_points_per_wavelength=mppw,
            fast=fast,
            **controls,
        )
    eta = None if eta is None else complex(as_index(eta, "eta"))
    wavelength = float(as_positive(wavelength, "wavelength"))
    k = 2 * np.pi / wavelength
    c = arclength_contour(contour(x, y, closed))
    _check_media(c, wavelength, eta, method, min_points_per_wavelength)
    incs = check_incidence_list(incidence)
    check_incidences(incs, c, k)
    U, psi, res, timings, used = _fill_and_solve(
        c, k, incs, (polarization, eta, method, band), tuple(controls.values())
    )
    if polarization == "p" and not c.closed:
        _warn_truncation(c, k, incs, psi)
    single = not isinstance(incidence, (list, tuple))
    return Solution(
        contour=c,
        k=k,
        current=U[:, 0] if single else U,
        incidences=incs,
        residual=res,
        timings=timings,
        solver=used,
        surface_field=psi[:, 0] if single else psi,
        polarization=polarization,
        eta=eta,
        method=method if eta is not None else "exact",
        quadrature="smooth",
    )


_EDGE_FIELD_WARN = 2e-3  # lambda |psi(ends)|^2 / P_inc above which a p-pol open profile warns


def edge_field_ratio(c, k, incs, psi):
    """lambda (|psi_first|^2 + |psi_last|^2) / P_inc per incidence (NaN without a finite power).

    The truncation indicator of a p-polarized open profile (module docstring, "Truncated
    profiles in p"): the surface field left at its two ends, in units of the incident power.

    Parameters
    ----------
    c : Contour -- an open profile.
    k : float [rad/m]
    incs : list of incidences (K).
    psi : ndarray (N, K) -- surface field.

    Returns
    -------
    ndarray (K,) -- dimensionless.
    """
    psi = psi.reshape(c.size, -1)
    out = np.full(psi.shape[1], np.nan)
    for j, inc in enumerate(incs):
        if isinstance(inc, TaperedWave):
            out[j] = (
                2 * np.pi / k * (abs(psi[0, j]) ** 2 + abs(psi[-1, j]) ** 2) / inc.incident_power(k)
            )
    return out


class TruncationWarning(UserWarning):
    """A p-polarized open profile left a large field at its ends (:func:`edge_field_ratio` above
    2e-3): power is lost at the truncation."""


def truncation_message(ratio: float, theta_deg: float, where: str = "") -> str:
    """The text of a :class:`TruncationWarning`: the largest edge-field ratio and its incidence.

    Parameters
    ----------
    ratio : float -- :func:`edge_field_ratio`, dimensionless.
    theta_deg : float -- its incidence angle [deg].
    where : str -- what the ratio is the largest of (e.g. "in 40 of 40 partitions"), or empty.

    Returns
    -------
    str
    """
    scope = f" {where}" if where else ""
    return (
        f"p-polarized open profile: the surface field at the ends of the profile is large{scope}, "
        f"lambda |H_z(ends)|^2 / P_inc = {ratio:.3g} (theta_i = {theta_deg:.1f} deg): fields "
        "scattered towards grazing do not vanish on a conductor in p and reach the truncation, where "
        "power is lost (the integrated scattering coefficient falls short of 1 by about 0.3-1.5 times "
        "this ratio, and the shortfall falls only as L^-1/2 with the surface length L at a fixed "
        "taper): use a longer surface for the same g"
    )


def _warn_truncation(c, k, incs, psi):
    """TruncationWarning when a p-pol open profile leaves a large field at its ends (power lost)."""
    ratio = edge_field_ratio(c, k, incs, psi)
    if np.all(~(ratio > _EDGE_FIELD_WARN)):
        return
    j = int(np.nanargmax(ratio))
    warnings.warn(
        truncation_message(ratio[j], np.degrees(incs[j].theta)), TruncationWarning, stacklevel=3
    )


def _fill_and_solve(c, k, incs, physics, controls):
    """Matrix fill and linear solve: returns U, psi (N, K), residuals (K,), timings, solver used.

    ``physics`` = (polarization, eta, method, band); ``controls`` = (solver, tol, max_iter, block).
    """
    polarization, eta, method, band = physics
    solver, tol, max_iter, block = controls
    t0 = time.perf_counter()
    A, split = _system(c, k, polarization, eta, method, band)
    t_fill = time.perf_counter() - t0
    V = np.stack([inc.field(c.x, c.y, k) for inc in incs], axis=1)
    if A.shape[0] == 2 * c.size:
        V = np.concatenate([V, np.zeros_like(V)])
    t0 = time.perf_counter()
    if eta is None and c.closed:  # p-pol PEC body: the MFIE with CHIEF rows, least squares
        rows, rhs = chief_rows(c, k, incs)
        A, V = np.vstack([A, rows]), np.vstack([V, rhs])
        X, used = linalg.lstsq(A, V, lapack_driver="gelsy", check_finite=False)[0], "lstsq (CHIEF)"
    else:
        X, used = _linear_solve(
            A, V, solver, tol, max_iter, block, interleave=A.shape[0] == 2 * c.size
        )
    t_solve = time.perf_counter() - t0
    res = np.linalg.norm(A @ X - V, axis=0) / np.linalg.norm(V, axis=0)
    U, psi = split(X)
    return U, psi, res, {"fill": t_fill, "solve": t_solve}, used


def chief_points(c, count: int):
    """Interior points of a closed contour for CHIEF (Schenck 1968): the contour shrunk towards its
    centroid by irregular factors in (0.1, 0.8) (golden-ratio sequences, so no symmetry line of a
    circle is favoured), kept where they are inside (even-odd ray casting).

    Parameters
    ----------
    c : Contour -- closed.
    count : int -- number of candidate points.

    Returns
    -------
    px, py : ndarrays (P,) [m], P <= count.
    """
    golden = (np.sqrt(5) - 1) / 2
    j = np.arange(1, count + 1)
    idx = np.floor((j * golden) % 1 * c.size).astype(int)
    fac = 0.1 + 0.7 * ((j * golden * golden + 0.31) % 1)
    cx, cy = np.mean(c.x), np.mean(c.y)
    px, py = cx + fac * (c.x[idx] - cx), cy + fac * (c.y[idx] - cy)
    x1, y1, x2, y2 = c.x, c.y, np.roll(c.x, -1), np.roll(c.y, -1)
    crosses = ((y1[None] > py[:, None]) != (y2[None] > py[:, None])) & (
        px[:, None]
        < x1[None]
        + (py[:, None] - y1[None]) * (x2 - x1)[None] / np.where(y2 == y1, 1, y2 - y1)[None]
    )
    inside = np.sum(crosses, axis=1) % 2 == 1
    return px[inside], py[inside]


def chief_rows(c, k, incs):
    r"""CHIEF rows of the p-pol PEC body: inside the body the exterior representation vanishes,
    :math:`-\int\partial_{n'}G(\mathbf p, \mathbf r')\psi\,ds' = \psi_{inc}(\mathbf p)`.

    Added to the MFIE :math:`(\tfrac12 - D)\psi = \psi_{inc}`, they remove its interior
    (Dirichlet) resonances, where :math:`J_n(ka) = 0` for a circle: at ka = 20 (J_15(20) = 8e-4)
    the plain MFIE was 2.4 % off the series at 10 points per wavelength.

    Parameters
    ----------
    c : Contour -- closed, normals outward.
    k : float [rad/m]
    incs : list of incidences.

    Returns
    -------
    rows : ndarray (P, N) complex; rhs : ndarray (P, K) complex.
    """
    px, py = chief_points(c, 8 + c.size // 10)
    dx = c.x[None, :] - px[:, None]
    dy = c.y[None, :] - py[:, None]
    R = np.hypot(dx, dy)
    D = 0.25j * k * hankel2(1, k * R) * (c.nx[None] * dx + c.ny[None] * dy) / R * c.ds[None]
    rhs = np.stack([inc.field(px, py, k) for inc in incs], axis=1)
    return -D, rhs


def _check_choices(polarization, method, solver, eta):
    """ValueError for an unknown polarization, method or solver (the fast path: s-pol PEC)."""
    if polarization not in ("s", "p"):
        raise ValueError(
            f"polarization must be 's' (E along z) or 'p' (H along z), got {polarization!r}"
        )
    if method not in ("exact", "impedance"):
        raise ValueError(f"method must be 'exact' or 'impedance', got {method!r}")
    if solver == "fast" and not (eta is None and polarization == "s"):
        raise ValueError(
            "solver='fast' handles the s-pol perfect conductor (eta=None, polarization='s') "
            "only; use solver='lu' or 'fb'"
        )


def _check_media(c, wavelength, eta, method, min_ppw):
    """Sampling outside and (exact formulation) inside; warn when the impedance condition is used
    on a poor conductor."""
    check_sampling(c, wavelength, min_ppw, "outside")
    if eta is not None and method == "exact":
        check_sampling(
            c,
            wavelength / abs(eta),
            min_ppw,
            f"inside (lambda / |eta| = "
            f"{wavelength / abs(eta):.3g}, in the wavelength's unit; or method='impedance' for a good "
            "conductor)",
        )
    if eta is not None and method == "impedance" and abs(eta) < 3:
        warnings.warn(
            f"the impedance condition needs |eta| >> 1, got |eta| = {abs(eta):.2f}: expect "
            "errors of several percent (use method='exact')",
            stacklevel=3,
        )
