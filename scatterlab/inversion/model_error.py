r"""The pBRDF's DOLP model error, measured against exact (method-of-moments) solutions.

The inversion fits the pBRDF's DOLP (Eq. 203) to measurements. Where the facet model is wrong its
error is a systematic DOLP error the noise model does not know about, and the intervals of
:func:`~scatterlab.inversion.fit_dolp` and :func:`~scatterlab.inversion.sample_posterior` are too
narrow. :func:`dolp_model_error` gives that error as a standard deviation per geometry, for their
``systematic`` argument (added in quadrature to the noise):

.. code-block:: python

    C = dolp_model_error_covariance(theta_i, theta_r) + noise**2 * np.eye(M)
    fit = fit_dolp(dolp, theta_i, theta_r, covariance=C)
    post = sample_posterior(dolp, theta_i, theta_r, None, covariance=C)
    # or, errors taken independent across geometries:
    post = sample_posterior(dolp, theta_i, theta_r, noise,
                            systematic=dolp_model_error(theta_i, theta_r))

Give ``sigma`` and ``eta`` only when they are known independently: a roughness or index fitted
from the same specular DOLP is not (specular DOLP hardly constrains sigma, Fig. 58), and
selecting the error with it gave intervals that covered the truth in about half the held-out
cases. With both unknown (the largest tabulated error) and the correlated form, held-out exact
DOLP plus noise 0.005 was covered at 96 % (31 % without the term; test
``tests/inversion/test_model_error.py``).

Use the term with :func:`~scatterlab.inversion.sample_posterior` (as the characterization
pipeline does), not with ``fit_dolp``'s Laplace widths, for metals: with the term the posterior
of a metal's kappa is far from Gaussian (it spans most of the prior), and the Laplace interval at
the least-squares point (a near-dielectric fit) missed aluminium's true kappa in about a third
of the held-out cases (71 %, 50 % in a re-run), where the sampled posterior's interval
covers it.

Coverage with emcee (study ``dolp_vs_mom``, full run of 24 Nov 2026: held-out realizations of
the 8 roughness cells plus noise 0.002 and 0.01, 128 posteriors per form, 68 % / 95 % intervals
of (n, kappa); the four cases of a cell share its surfaces, so the binomial error of about 4 % /
2 % is a lower bound):

=====================================================  ===========  ==================================
error term                                             pooled       per material
=====================================================  ===========  ==================================
none                                                   2 / 8 %      0-3 / 3-12 %
``material_class`` known, ``sigma`` known (pipeline)   70 / 97 %    glass 62 / 100, paint 66 / 100,
                                                                    iron 59 / 88, aluminium 94 / 100
material unknown, ``sigma`` known                      87 / 98 %    glass 100 / 100, paint 97 / 100,
                                                                    iron 62 / 94, aluminium 88 / 100
both unknown                                           100 / 100 %  100 / 100 everywhere
=====================================================  ===========  ==================================

So give the class when it is known (the characterization pipeline takes it from its
classification): the intervals then cover at the nominal rates; without it the largest error
over all materials makes the dielectrics' intervals conservative. The root mean square over the
heights instead of their largest value (the table's ``error_rms``) under-covers: 54 / 87 %
pooled, iron 38 / 56 %.

The table (``scatterlab/data/model_error/dolp_mom.npz``) is written by the study
``studies/dolp_vs_mom.py`` (function ``model_error_table``; ``export_from_runs`` regenerates it, and
the tests' held-out DOLP, from a full run's saved ``mom_runs.npz``): incoherent averages over realizations
of 1-D Gaussian rough surfaces (exact two-medium MoM for glass 1.5 and paint 1.39 - j0.34, the
impedance condition for iron 3.60 - j5.88 and aluminium 1.44 - j16), both polarizations, the exact
DOLP :math:`(\sigma_s - \sigma_p)/(\sigma_s + \sigma_p)` against the inversion's forward model
(the pBRDF in the specular plane, Torrance-Sparrow shadowing, Hyde's diffuse term). For each
material, rms slope and geometry the entry is the largest absolute value of that difference over
the height-to-wavelength ratios simulated at that slope (the inversion does not know the height;
the root mean square over the heights, used first, under-stated the worst height by up to
sqrt(2) and left iron at slope 0.1 uncovered), which includes the MoM's own standard error.
Cells the MoM could not resolve (no signal) hold the material's largest entry. The 80 deg row,
where present (``length_80deg`` in the table), comes from longer surfaces (150 wavelengths,
taper 37.4) and fewer realizations.

Outside the tabulated range (the table's ``theta_i``, 10-70 or 10-80 deg; rms slopes 0.1-0.6)
the table is clamped to its edge: an extrapolation. The error is tabulated in the plane of
incidence only (``phi`` = pi forward, 0 backward).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from scatterlab._checks import as_angle, as_index, as_scalar, broadcast

__all__ = [
    "dolp_model_error",
    "dolp_model_error_covariance",
    "model_error_table",
    "TABLE_PATH",
]

CORRELATION_RANGE = (1e-6, 2 * np.pi)
"""Allowed correlation angle [rad] of :func:`dolp_model_error_covariance`."""

TABLE_PATH = Path(__file__).resolve().parents[1] / "data" / "model_error" / "dolp_mom.npz"


@lru_cache(maxsize=4)
def _load(path: str) -> dict:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def model_error_table(path=None) -> dict:
    """The tabulated DOLP model error.

    Parameters
    ----------
    path : str or Path, optional -- an npz written by the study ``dolp_vs_mom`` (default the
        shipped table, :data:`TABLE_PATH`).

    Returns
    -------
    dict with ``materials`` (K,) names, ``eta`` (K,) complex, ``slopes`` (L,), ``theta_i`` (I,)
    [rad], ``theta_s`` (S,) [rad, signed: negative is backward], ``error`` (K, L, I, S) the
    largest absolute DOLP model error over the simulated heights (what :func:`dolp_model_error`
    uses), ``error_rms`` (K, L, I, S) its root mean square over them (for reference: intervals
    built on it under-cover the metals, see the module docstring), both finite and >= 0, and the
    run's ``realizations``, ``length`` [wavelengths].
    """
    p = Path(TABLE_PATH if path is None else path)
    if not p.exists():
        raise ValueError(
            f"model-error table {p} not found: run the study dolp_vs_mom in full mode to write it"
        )
    return _load(str(p))


def _interp_axis(grid, x):
    """Indices and weights of linear interpolation on ``grid``, clamped to its ends."""
    x = np.clip(x, grid[0], grid[-1])
    if grid.size == 1:
        z = np.zeros(x.shape, int)
        return z, z, np.zeros(x.shape)
    j = np.clip(np.searchsorted(grid, x) - 1, 0, grid.size - 2)
    w = (x - grid[j]) / (grid[j + 1] - grid[j])
    return j, j + 1, w


def _nearest_material(eta, table_eta):
    """Index of the tabulated material nearest in log(eta) (magnitude and phase)."""
    d = np.abs(np.log(np.asarray(eta)[..., None]) - np.log(table_eta))
    return np.argmin(d, -1)


def _class_members(material_class, table_eta):
    """Indices of the tabulated materials of ``material_class`` (metal: n < kappa, i.e. a
    negative real part of the permittivity n^2 - kappa^2)."""
    if material_class not in ("dielectric", "metal"):
        raise ValueError(
            f"material_class must be 'dielectric', 'metal' or None, got {material_class!r}"
        )
    metal = table_eta.real < -table_eta.imag
    members = np.flatnonzero(metal if material_class == "metal" else ~metal)
    if members.size == 0:
        raise ValueError(f"the model-error table holds no {material_class}")
    return members


def dolp_model_error(
    theta_i, theta_r, sigma=None, eta=None, *, material_class=None, phi=np.pi, table=None
):
    r"""Systematic DOLP error standard deviation of the pBRDF at the given geometries.

    Parameters
    ----------
    theta_i, theta_r : array_like [rad] in ``[0, pi/2]``
    sigma : array_like, optional -- rms facet slope; None takes the largest error over the
        tabulated slopes (roughness unknown). Clamped to the tabulated 0.1-0.6.
    eta : complex array_like, optional -- index ``n - 1j*kappa``: the nearest tabulated material
        in :math:`\log\eta`; None takes the largest error over the materials (of
        ``material_class`` when given).
    material_class : {"dielectric", "metal"}, optional -- the material's class when known but not
        its index (the characterization pipeline's classification): the largest error over the
        tabulated materials of that class (metal: negative real permittivity,
        :math:`n < \kappa`). Only without ``eta``.
    phi : float or array_like [rad] -- ``pi`` (forward, the specular plane) or ``0`` (backward);
        out-of-plane geometries are not tabulated (ValueError).
    table : dict, optional -- from :func:`model_error_table` (default the shipped table).

    Returns
    -------
    ndarray, broadcast shape of the inputs: DOLP standard deviation (>= 0, finite), for the
    ``systematic`` argument of :func:`~scatterlab.inversion.fit_dolp` and
    :func:`~scatterlab.inversion.sample_posterior`. Incidences outside the table's ``theta_i``
    (10-70 deg, or 10-80 deg in a table with the 80 deg row) are clamped to its edge
    (extrapolated).
    """
    t = model_error_table() if table is None else table
    ti = as_angle(theta_i, "theta_i")
    tr = as_angle(theta_r, "theta_r")
    ph = np.asarray(phi, float)
    back = np.isclose(ph, 0.0) | np.isclose(ph, 2 * np.pi)
    if not np.all(back | np.isclose(ph, np.pi)):
        raise ValueError("phi must be pi (forward) or 0 (backward): the table is in-plane only")
    err = np.asarray(t["error"], float)  # (K, L, I, S)
    if material_class is not None:
        if eta is not None:
            raise ValueError("give eta or material_class, not both")
        err = err[_class_members(material_class, np.asarray(t["eta"]))]
    if eta is not None:
        k = _nearest_material(as_index(eta), np.asarray(t["eta"]))
    if sigma is not None:
        sig = np.asarray(sigma, float)
        if not np.all(np.isfinite(sig) & (sig > 0)):
            raise ValueError("sigma must be finite and > 0 (rms facet slope)")
    named = {"theta_i": ti, "theta_r": tr, "phi": ph}
    named.update({} if sigma is None else {"sigma": sig})
    named.update({} if eta is None else {"eta": k})
    shape = broadcast(**named)[0].shape  # a mismatch names the arguments and their shapes
    ts = np.where(back, -tr, tr)
    i0, i1, wi = _interp_axis(np.asarray(t["theta_i"]), np.broadcast_to(ti, shape))
    s0, s1, ws = _interp_axis(np.asarray(t["theta_s"]), np.broadcast_to(ts, shape))
    e = err if eta is not None else np.max(err, axis=0, keepdims=True)
    e = e if sigma is not None else np.max(e, axis=1, keepdims=True)
    kk = np.broadcast_to(k, shape) if eta is not None else np.zeros(shape, int)
    if sigma is not None:
        l0, l1, wl = _interp_axis(np.asarray(t["slopes"]), np.broadcast_to(sig, shape))
    else:
        l0 = l1 = np.zeros(shape, int)
        wl = np.zeros(shape)

    def at(li, ii):
        return e[kk, li, ii, s0] * (1 - ws) + e[kk, li, ii, s1] * ws

    along_i = [at(li, i0) * (1 - wi) + at(li, i1) * wi for li in (l0, l1)]
    return along_i[0] * (1 - wl) + along_i[1] * wl


def dolp_model_error_covariance(
    theta_i,
    theta_r,
    sigma=None,
    eta=None,
    *,
    material_class=None,
    phi=np.pi,
    correlation=np.radians(20.0),
    table=None,
):
    r"""Covariance (M, M) of the model error across M geometries.

    The facet model's error changes slowly with the geometry, so errors at nearby geometries are
    nearly equal, not independent: :math:`C_{jk} = t_j t_k \exp(-d_{jk}^2/(2c^2))` with
    :math:`t` from :func:`dolp_model_error` and :math:`d_{jk}^2 = (\theta_{i,j} - \theta_{i,k})^2
    + (\theta_{r,j} - \theta_{r,k})^2`. Add the noise variance on the diagonal and pass it as the
    ``covariance`` of :func:`~scatterlab.inversion.fit_dolp` or
    :func:`~scatterlab.inversion.sample_posterior` (with ``noise=None``).

    Parameters
    ----------
    theta_i, theta_r : array_like (M,) [rad]
    sigma, eta, material_class, phi, table : as :func:`dolp_model_error` (scalars for
        ``sigma`` and ``eta``).
    correlation : float [rad] -- correlation angle c, default 20 deg; a single float in
        ``[1e-6, 2 pi]`` rad (:data:`CORRELATION_RANGE`: below, ``d^2/c^2`` overflows; above a
        full turn the errors are all but fully correlated anyway, and such a value is usually
        degrees), else a ValueError.

    Returns
    -------
    ndarray (M, M), symmetric positive semi-definite [DOLP^2].
    """
    correlation = as_scalar(
        correlation, "correlation", CORRELATION_RANGE[0], CORRELATION_RANGE[1], unit=" [rad]"
    )
    ti = np.atleast_1d(as_angle(theta_i, "theta_i")).astype(float)
    tr = np.atleast_1d(as_angle(theta_r, "theta_r")).astype(float)
    ti, tr = np.broadcast_arrays(ti, tr)
    if ti.ndim != 1:
        raise ValueError("theta_i and theta_r must be 1-D arrays (M,) of geometries")
    t = dolp_model_error(ti, tr, sigma, eta, material_class=material_class, phi=phi, table=table)
    d2 = (ti[:, None] - ti[None, :]) ** 2 + (tr[:, None] - tr[None, :]) ** 2
    return t[:, None] * t[None, :] * np.exp(-d2 / (2 * correlation**2))
