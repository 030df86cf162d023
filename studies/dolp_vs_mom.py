"""How right is the pBRDF's DOLP? Exact MoM solutions of 1-D rough surfaces against the model.

Incoherent averages over realizations of 1-D Gaussian rough surfaces (Gaussian correlation) of
the s- and p-polarized scattering coefficients, from :func:`scatterlab.mom.solve` (exact
two-medium formulation for glass 1.5 and green paint 1.39 - j0.34 at 15 points per wavelength
outside, at least 10 inside; the impedance (Leontovich) condition for iron 3.60 - j5.88 and
aluminium 1.44 - j16, whose error on the DOLP is measured once against the exact formulation for
iron in full mode; perfect conductor for the DHR part). The exact DOLP of unpolarized light is
(s - p)/(s + p) of the averaged coefficients, its standard error by the jackknife over
realizations (s and p come from the same surfaces).

The model is compared like for like in its 1-D form (:mod:`scatterlab.pbrdf.inplane`: 1-D slope
density, the same shadowing functions, the Hyde diffuse term as a 2-D Lambertian), shadowed and
unshadowed, with and without the diffuse term; and the inversion's own forward model (the 2-D
pBRDF in the specular plane) for the model-error table and the inversion bias. Without the diffuse
term the 1-D and 2-D models give the same DOLP (the facet's, Eq. 203); they differ only in the
specular fraction.

Cells (rms slope, sigma_h / lambda): (0.1, 0.1), (0.1, 0.25), (0.3, 0.1), (0.3, 0.25),
(0.3, 0.5), (0.6, 0.25), (0.6, 0.5), (0.6, 1.0): correlation lengths 0.24-3.5 wavelengths (the
surface of 40 wavelengths holds a taper of 10; longer correlation lengths, i.e. the very rough
regime at small slopes, need surfaces this study cannot afford on 2 cores). Incidence 10-70 deg
on these surfaces; 80 deg in a separate pass (full mode: every cell; quick mode: the PEC of one
cell) on surfaces of 150 wavelengths with a taper of 37.4 (the MoM's check asks g >= 37.04 at
80 deg: the Thorsos taper's power correction below 0.02), 2 realizations for glass and paint and
4 for the metals and the PEC, with a convergence check (full mode): cell (0.3, 0.25) again at
twice the length and taper (300 and 74.9; metals and PEC only, the exact formulation of glass
does not fit), the change in specular DOLP stated against the combined standard error. The
80 deg row extends the model-error table; the pipeline's 30-60 deg values do not depend on it.
Profiles are resampled at equal arc-length steps (1/15 wavelength) so the steep ones keep 10
points per wavelength inside glass. Exact powers are means over a 5 deg aperture (a few speckles
of each realization).

Full mode: 6 realizations per cell for glass and paint, 12 for iron, aluminium and the PEC,
40-wavelength surfaces; 22 min wall on the shared 2-core machine under a load average of 12-19
(MoM 14 min in a 2-worker process executor, ``run_study(..., executor=get_executor("processes",
workers=2))``; about 20 min on one idle core). Headline numbers (seed 17): the specular DOLP
error of the 1-D model (shadowed, diffuse) is within 0.015 for glass and paint at slope 0.1
(sigma_h 0.1-0.25 wavelength) at every angle 10-70 deg (20-23 % of all their (cell, angle)
points within 0.01), within 0.05 for iron and aluminium up to 60 deg (0.09 at 70 deg); it grows
to 0.26 (glass, paint) and 0.45 (iron) / 0.67 (aluminium) at slope 0.6, and is 0.08-0.24 for the
sub-wavelength correlation length of cell (0.3, 0.1) in every material. Standard errors are in
the report (median 0.01 for the dielectrics, 0.04 for the metals). The inversion of noise-free
exact specular DOLP (30-60 deg) is biased by more than the posterior width in most cells (the
table in the report). Coverage of the true (n, kappa) by 95 % intervals on held-out realizations
plus noise 0.002 and 0.01: 29 % without the model-error term, 92 % with it as independent errors
and 95 % correlated across geometries (pooled; per material 100 % glass and paint, 90-98 % iron,
71-89 % aluminium), material and roughness unknown to the pipeline. (The analysis after the MoM
was re-run once on the full run's saved ``mom_runs.npz`` after this coverage scheme replaced one
that selected the error by a fitted sigma, which covered 46-84 %. Those Laplace numbers are with
the first table, the rms over the heights.)

Second full run (23 Nov 2026, seed 17, same code for the MoM; the 10-70 deg MoM reproduced the
first run's coefficients for the four materials; the PEC's differ by up to 2e-4 of their peak):
the MoM at 10-70 deg 6 min wall and the 80 deg pass with its convergence check 44 min wall, both
in a 2-worker process executor on the shared machine under a load average of 7-11. The runner's
analysis was then stopped (deadline) and the emcee part run on the saved ``mom_runs.npz``
(``posterior_inversion``, serial executor, 25 min wall under the same load; 576 posteriors of 16
walkers x 400 steps, DE moves, none failed), and the 80 deg part on ``mom_runs_80deg.npz``
(``grazing_summary``). Headline numbers:

* emcee bias (sigma sampled, noise-free exact DOLP at 30-60 deg): |bias| exceeds the posterior
  width (half the 68 % interval) for n or kappa in 8 of 8 cells for every material at noise
  0.002 and 7-8 of 8 at 0.01; median |bias of n| 0.17 glass, 0.15 paint, 2.4-2.5 iron, 1.1-1.2
  aluminium (the metals are fitted as near-dielectrics: median |bias of kappa| 4.5 iron, 15
  aluminium), against widths of n of 0.004-0.16.
* emcee coverage of the true (n, kappa) on held-out realizations plus noise 0.002 and 0.01, 68 %
  / 95 % intervals, pooled over the materials (the table: largest error over the heights): 1 % /
  7 % without the term; 99 / 100 % with the independent term (sigma sampled, material and
  roughness unknown); 73 / 100 % correlated; 87 / 98 % in the pipeline's form (sigma known,
  material unknown), per material glass 97 / 100, paint 100 / 100, iron 62 / 94, aluminium 88 /
  100 % (iron's 68 % intervals are short of nominal). Aluminium's 71 % (independent, Laplace)
  was the Laplace approximation, not the term: with the term a metal's kappa posterior spans
  most of the prior, and the sampled intervals hold the truth.
* 80 deg (150-wavelength surfaces, taper 37.4): the exact specular DOLP against the model's
  (shadowed, diffuse) is off by up to 0.14 glass, 0.10 paint, 0.42 iron, 0.87 aluminium (the
  exact DOLP of rough aluminium grows to 0.13-0.93 against the model's 0.055, the Fresnel value
  of the facet at 80 deg); the rough PEC's DHR is 1 within 8e-3. Doubling the surface and the
  taper (cell 0.3/0.25) changes the DOLP by +0.009 iron (combined standard error 0.023) and
  -0.015 aluminium (0.060); the PEC's DHR there is 1 within 5e-3. On a flat surface the 80 deg
  MoM gives Fresnel's DOLP to 0.008 (glass, exact formulation), 0.006 (paint), 0.013 (iron,
  impedance condition; 0.010 at twice the length, 0.006 at 70 deg on 40 wavelengths) and 1e-4
  (aluminium): the reference's own systematic at 80 deg is about 0.01, far below the model's
  error there.

Third full run (24 Nov 2026, seed 17, one run of the study: ``scatterlab study run dolp_vs_mom
--seed 17 --workers 2``): the MoM coefficients of the second run, saved in the output folder with
the run's settings, were resumed (a run resumes ``mom_runs*.npz`` only when its settings -- mode,
seed, incidences, surfaces, cells -- match; otherwise it solves again), so the report covers every
part in one piece. The analysis took 570 s wall (emcee 542 s) in a 2-worker process executor at a
load average of about 3; with the MoM (6 + 44 min above) a full run from scratch takes about an
hour. emcee coverage (68 % / 95 %, pooled) with the term in the pipeline's form, now with the
material's class known (dielectric or metal, from the pipeline's classification): 70 / 97 %
(glass 62 / 100, paint 66 / 100, iron 59 / 88, aluminium 94 / 100); with the material unknown
87 / 98 % (the dielectrics over-cover: 100 / 100); with the rms over the heights in place of the
largest error 54 / 87 % (iron 38 / 56). The report also lists, per material, the (cell, angle)
points where the model is good to 0.01.

Quick mode (one cell, 2
realizations of 20 wavelengths, incidence 10-60 deg; at 80 deg the PEC of one 150-wavelength
surface; emcee 8 walkers x 100 steps, one noise level, one draw) computes real MoM numbers but
with standard errors of several 0.01, and its coverage numbers are a smoke test (a table from
one realization): 21 s before the emcee and 80 deg parts on an idle machine, 26 s with them
under a load average of 4.
"""

import warnings

import numpy as np
from scatterlab.studies._common import plt, set_verdict

from scatterlab.mom import TaperedWave, correlation_length_for_slope, rough_surface, solve
from scatterlab.pbrdf import Model
from scatterlab.pbrdf.inplane import dhr_pec_1d, dolp_1d, specular_lobe_1d

STUDY = {
    "id": "dolp_vs_mom",
    "title": "The pBRDF's DOLP against exact MoM solutions, and its effect on n and kappa",
    "reproduces": "own validation",
}

MATERIALS = (
    ("glass", 1.5 + 0j, "exact"),
    ("paint", 1.39 - 0.34j, "exact"),
    ("iron", 3.60 - 5.88j, "impedance"),
    ("aluminium", 1.44 - 16j, "impedance"),
)
PPW = 15
CELLS = (
    (0.1, 0.1),
    (0.1, 0.25),
    (0.3, 0.1),
    (0.3, 0.25),
    (0.3, 0.5),
    (0.6, 0.25),
    (0.6, 0.5),
    (0.6, 1.0),
)
THETA_S = np.radians(np.arange(-82.5, 82.51, 2.5))  # centres of the 5 deg detector apertures
_FINE = np.radians(np.arange(-85, 85.01, 0.5))
APERTURE = (np.abs(_FINE[None, :] - THETA_S[:, None]) <= np.radians(2.5) + 1e-9).astype(float)
APERTURE /= APERTURE.sum(1, keepdims=True)  # (S, fine): mean over the aperture
GL_X, GL_W = np.polynomial.legendre.leggauss(512)
NOISES = (0.002, 0.01)
INV_DEG = (30, 40, 50, 60)
VARIANTS = (
    ("ts_hyde", "torrance-sparrow", "hyde"),
    ("ts_none", "torrance-sparrow", "none"),
    ("none_hyde", "none", "hyde"),
    ("none_none", "none", "none"),
)


def cells(quick):
    """(slope, sigma_h / lambda) pairs simulated (see the module docstring)."""
    return [(0.3, 0.5)] if quick else list(CELLS)


def _solve_one(x, y, incs, pol, eta, method):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the sampling warnings are checked by the MoM tests
        sol = solve(x, y, 1.0, incs, polarization=pol, eta=eta, method=method)
    coef = sol.scattering_coefficient(_FINE).T @ APERTURE.T  # (I, S): 5 deg aperture means
    energy = np.sum(GL_W[:, None] * sol.scattering_coefficient(GL_X * np.pi / 2), 0) * np.pi / 2
    return coef, energy, sol


def surface(length, sigma_h, corr, rng):
    """A Gaussian rough profile sampled at equal arc-length steps of 1/PPW wavelength.

    Synthesised at a fine step (1/(4 PPW)) and resampled along its arc length, so that the
    longest pulse, which sets the sampling inside the medium, is 1/PPW even on steep slopes
    (equal steps in x would make the pulses of a slope-0.6 surface up to 2.5x longer)."""
    x, y = rough_surface(length, min(1 / (4 * PPW), corr / 4), sigma_h, corr, rng)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    s = np.arange(0.0, arc[-1], 1 / PPW)
    return np.interp(s, arc, x), np.interp(s, arc, y)


def simulate(cell, theta_i, length, realizations, rng, metal_realizations=None, materials=None):
    """MoM coefficients of one cell: {material: {"coef": (R, 2, I, S), "energy": (R, 2, I)}}, s
    (index 0) and p (1), wavelength 1. The first ``realizations`` surfaces serve every material;
    the metals and the PEC (impedance condition: cheap) get ``metal_realizations`` in all, their
    DOLP being small and noisier (s and p speckle differ). ``materials``: names to solve (default
    all four and the PEC). The taper is (length - 0.25)/4 (Thorsos: surface = 4 tapers)."""
    slope, h = cell
    corr = float(correlation_length_for_slope(h, slope))
    incs = [TaperedWave(t, (length - 0.25) / 4) for t in theta_i]
    mats = list(MATERIALS) + [("pec", None, "exact")]
    mats = [m for m in mats if materials is None or m[0] in materials]
    total = max(realizations, metal_realizations or realizations)
    out = {m[0]: {"coef": [], "energy": []} for m in mats}
    for r in range(total):
        x, y = surface(length, h, corr, rng)
        for name, eta, method in mats:
            if r >= realizations and method == "exact" and eta is not None:
                continue
            cs = [_solve_one(x, y, incs, pol, eta, method)[:2] for pol in ("s", "p")]
            out[name]["coef"].append([c[0] for c in cs])
            out[name]["energy"].append([c[1] for c in cs])
    return {k: {q: np.asarray(v[q]) for q in v} for k, v in out.items()}


def exact_dolp(coef):
    """DOLP (s - p)/(s + p) of the realization means and its jackknife standard error;
    ``coef`` (R, 2, ...)."""
    R = coef.shape[0]
    m = coef.mean(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = (m[0] - m[1]) / (m[0] + m[1])
        if R < 2:
            return d, np.full(d.shape, np.nan)
        loo = (coef.sum(0)[None] - coef) / (R - 1)
        dj = (loo[:, 0] - loo[:, 1]) / (loo[:, 0] + loo[:, 1])
    se = np.sqrt((R - 1) / R * np.sum((dj - dj.mean(0)) ** 2, 0))
    return d, se


def model_curves(eta, slope, theta_i):
    """Model DOLP (I, S) for the 1-D variants and the 2-D inversion model."""
    ti = theta_i[:, None]
    ts = THETA_S[None, :]
    out = {name: dolp_1d(eta, ti, ts, slope, shadowing=sh, diffuse=df) for name, sh, df in VARIANTS}
    phi = np.where(ts >= 0, np.pi, 0.0)
    out["pbrdf_2d"] = Model(slope).dolp(eta, ti, np.abs(ts), phi)
    return out


def _specular_index(theta_i):
    return np.array([int(np.argmin(np.abs(THETA_S - t))) for t in theta_i])


def _cell_task(task):
    """One cell on its own seed (module level: runs in the study's executor)."""
    cell, theta_i, length, reals, metal_reals, seed, *materials = task
    rng = np.random.default_rng(seed)
    return simulate(cell, theta_i, length, reals, rng, metal_reals, *materials)


def _run_cells(ctx, cell_list, theta_i, length, reals, metal_reals):
    """Every cell through ``ctx.executor`` (one seed per cell drawn from ``ctx.rng``)."""
    seeds = ctx.rng.integers(2**32, size=len(cell_list))
    tasks = [(c, theta_i, length, reals, metal_reals, int(sd)) for c, sd in zip(cell_list, seeds)]
    with ctx.step("mom"):
        out = list(ctx.executor.map(_cell_task, tasks))
    return dict(zip(cell_list, out))


def compare(runs, theta_i, half=None):
    """Per material and cell: exact DOLP, its stderr and the model variants (I, S)."""
    res = {}
    for name, eta, _ in MATERIALS:
        for cell, r in runs.items():
            coef = r[name]["coef"]
            if half is not None:
                R = coef.shape[0]
                coef = coef[: R // 2] if half == 0 else coef[R // 2 :]
            d, se = exact_dolp(coef)
            sp = _specular_index(theta_i)
            d_spec, se_spec = exact_dolp(coef[..., np.arange(sp.size), sp])
            res[name, cell] = {
                "exact": d,
                "se": se,
                "exact_spec": d_spec,
                "se_spec": se_spec,
                "power": coef.mean(0).sum(0),
                **model_curves(eta, cell[0], theta_i),
            }
    return res


def model_error_table(res, cell_list, theta_i, realizations, length):
    """The shipped model-error table from :func:`compare`'s results (2-D inversion model).

    ``error`` holds the largest |exact - model| over the height-to-wavelength ratios simulated
    at that slope (the pipeline knows the slope but not the height: a bound), ``error_rms`` the
    root mean square over those heights (the spread of the error over an unknown height: a
    calibrated standard deviation). The rms under-states the worst height by up to sqrt(2).

    Parameters
    ----------
    res : dict -- :func:`compare`'s output for the cells of ``cell_list``.
    cell_list : list of (slope, sigma_h / lambda)
    theta_i : ndarray (I,) [rad]
    realizations : (int, int) -- realizations behind the table (dielectrics, metals).
    length : float -- surface length [wavelengths].

    Returns
    -------
    dict of arrays, the layout of :func:`scatterlab.inversion.model_error.model_error_table`.
    """
    slopes = np.array(sorted({c[0] for c in cell_list}))
    err = np.full((2, len(MATERIALS), slopes.size, theta_i.size, THETA_S.size), np.nan)
    for k, (name, _, _) in enumerate(MATERIALS):
        for j, s in enumerate(slopes):
            diffs = np.array(
                [res[name, c]["exact"] - res[name, c]["pbrdf_2d"] for c in cell_list if c[0] == s]
            )
            with np.errstate(invalid="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: no signal, see below
                err[0, k, j] = np.nanmax(np.abs(diffs), 0)
                err[1, k, j] = np.sqrt(np.nanmean(diffs**2, 0))
        for e in err[:, k]:
            e[~np.isfinite(e)] = np.nanmax(e)
    return {
        "materials": np.array([m[0] for m in MATERIALS]),
        "eta": np.array([m[1] for m in MATERIALS]),
        "slopes": slopes,
        "theta_i": theta_i,
        "theta_s": THETA_S,
        "error": err[0],
        "error_rms": err[1],
        "realizations": np.array(realizations),
        "length": np.array(length),
    }


def write_model_error_table(path, table):
    """Write the table (regenerates ``scatterlab/data/model_error/dolp_mom.npz``)."""
    from scatterlab.runtime.results import write_npz

    write_npz(path, overwrite=True, **table)


def specular_summary(res, cell_list, theta_i):
    """Per material: the specular DOLP errors (cells, I) of each model, the largest, where
    |error| <= 0.01, and the largest error within the lobe over theta_r."""
    sp = _specular_index(theta_i)
    rows = np.arange(theta_i.size)
    out = {}
    for name, _, _ in MATERIALS:
        e = {
            v: np.array(
                [res[name, c]["exact"][rows, sp] - res[name, c][v][rows, sp] for c in cell_list]
            )
            for v in [x[0] for x in VARIANTS] + ["pbrdf_2d"]
        }
        se = np.array([res[name, c]["se_spec"] for c in cell_list])
        a = np.abs(e["ts_hyde"])
        k, i = np.unravel_index(np.nanargmax(a), a.shape)
        good_cells = [c for c, row in zip(cell_list, a) if np.all(row <= 0.01)]
        good_angles = {
            c: np.degrees(theta_i[row <= 0.01]).round().astype(int).tolist()
            for c, row in zip(cell_list, a)
            if np.any(row <= 0.01)
        }
        out[name] = {
            "errors": e,
            "se": se,
            "max_abs_error": float(a[k, i]),
            "max_at": (cell_list[k], float(np.degrees(theta_i[i]))),
            "max_se": float(se[k, i]),
            "fraction_within_0.01": float(np.mean(a <= 0.01)),
            "good_cells": good_cells,
            "good_angles": good_angles,
            "max_abs_error_by_variant": {v: float(np.nanmax(np.abs(x))) for v, x in e.items()},
            "median_se": float(np.nanmedian(se)),
            "lobe_max_abs_error": _lobe_error(res, name, cell_list),
        }
    return out


def _lobe_error(res, name, cell_list):
    """Largest |exact - model (1-D, shadowed, diffuse)| over theta_r where the exact power is at
    least 5 % of its peak for that incidence (the lobe a sensor sees)."""
    worst = 0.0
    for c in cell_list:
        r = res[name, c]
        w = r["power"] >= 0.05 * np.max(r["power"], axis=1, keepdims=True)
        worst = max(worst, float(np.nanmax(np.where(w, np.abs(r["exact"] - r["ts_hyde"]), 0))))
    return worst


def inversion_bias(res, cell_list, theta_i, name, eta):
    """Noise-free exact specular DOLP at 30-60 deg through fit_dolp: bias of (n, kappa, sigma)
    and the Laplace width at each noise level."""
    from scatterlab.inversion import fit_dolp

    idx = [int(np.argmin(np.abs(np.degrees(theta_i) - d))) for d in INV_DEG]
    th = theta_i[idx]
    data = np.array([np.abs(res[name, c]["exact_spec"][idx]) for c in cell_list])
    data = np.clip(data, 0.0, 1.0)
    truth = np.array([[eta.real, -eta.imag, c[0]] for c in cell_list])
    out = {}
    for noise in NOISES:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_dolp(data, th, th, noise=noise)
        p = np.stack([fit.n, fit.kappa, fit.sigma], -1)
        out[noise] = {"bias": p - truth, "width": fit.errors}
    return out


def coverage(res_fit, table, cell_list, theta_i, name, eta, draws, rng, quick=False):
    """Coverage of the truth (n, kappa) by 95 % Laplace intervals of fit_dolp on held-out exact
    DOLP plus noise, without and with the model-error term, independent across geometries
    (``systematic``) or correlated (``covariance``). The pipeline knows neither the material nor
    the roughness (specular DOLP does not determine sigma, Fig. 58): sigma = eta = None, the
    largest tabulated error."""
    from scatterlab.inversion import fit_dolp
    from scatterlab.inversion.model_error import dolp_model_error, dolp_model_error_covariance

    idx = [int(np.argmin(np.abs(np.degrees(theta_i) - d))) for d in INV_DEG]
    th = theta_i[idx]
    truth = np.array([eta.real, -eta.imag])
    d0 = np.array([res_fit[name, c]["exact_spec"][idx] for c in cell_list])  # (C, M)
    t = dolp_model_error(th, th, table=table)
    C = dolp_model_error_covariance(th, th, table=table)
    hits = {"without": [], "with": [], "with_correlated": []}
    for noise in NOISES[-1:] if quick else NOISES:
        y = np.clip(np.abs(d0[None] + noise * rng.standard_normal((draws,) + d0.shape)), 0, 1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fits = (
                fit_dolp(y, th, th, noise=noise),
                fit_dolp(y, th, th, noise=noise, systematic=t),
                fit_dolp(y, th, th, covariance=C + noise**2 * np.eye(th.size)),
            )
        for key, f in zip(hits, fits):
            p = np.stack([f.n, f.kappa], -1)
            ok = ~(np.abs(p - truth) > 1.96 * f.errors[..., :2])  # NaN error: undetermined
            hits[key].append(ok.all(-1).ravel())
    return {k: float(np.mean(np.concatenate(v))) for k, v in hits.items()}


def posterior_inversion(ctx, res, res_b, table, cell_list, theta_i, draws):
    """The emcee side (:mod:`scatterlab.studies._dolp_posterior`) for every material: bias of
    the posterior median against the posterior width on noise-free exact DOLP, and the coverage
    of the 68 % and 95 % intervals on held-out DOLP plus noise with the model-error term.

    Parameters
    ----------
    ctx : StudyContext -- its ``rng``, ``executor`` and ``quick``.
    res, res_b : dict -- :func:`compare` on all realizations and on the held-out half.
    table : dict -- the model-error table from the other half.
    cell_list : list of (slope, sigma_h / lambda)
    theta_i : ndarray (I,) [rad]
    draws : int -- noise draws per cell and noise level for the coverage.

    Returns
    -------
    (bias, cover): dicts by material, of :func:`~scatterlab.studies._dolp_posterior.posterior_bias`
    and :func:`~scatterlab.studies._dolp_posterior.posterior_coverage`.
    """
    from scatterlab.studies._dolp_posterior import posterior_bias, posterior_coverage

    idx = [int(np.argmin(np.abs(np.degrees(theta_i) - d))) for d in INV_DEG]
    th = theta_i[idx]
    noises = NOISES[-1:] if ctx.quick else NOISES
    slopes = np.array([c[0] for c in cell_list])
    bias, cover = {}, {}
    for name, eta, _ in MATERIALS:
        truth = np.array([[eta.real, -eta.imag, s] for s in slopes])
        data = np.array([np.abs(res[name, c]["exact_spec"][idx]) for c in cell_list])
        bias[name] = posterior_bias(data, truth, th, noises, ctx.rng, ctx.executor, ctx.quick)
        d0 = np.array([res_b[name, c]["exact_spec"][idx] for c in cell_list])
        cover[name] = posterior_coverage(
            d0,
            truth[0, :2],
            slopes,
            th,
            noises,
            draws,
            table,
            ctx.rng,
            ctx.executor,
            ctx.quick,
            name,
        )
    return bias, cover


def pec_energy(runs, cell_list, theta_i):
    """Rough PEC, both polarizations: exact DHR against the 1-D model's specular DHR and diffuse
    term; in the region where the model's diffuse term exceeds its specular one, the exact power
    against the model's (specular alone, and with the diffuse term), and the DOLP of the exact
    light there (jackknife standard errors)."""
    out = {}
    dth = np.radians(2.5)
    for c in cell_list:
        r = runs[c]["pec"]
        rho = dhr_pec_1d(theta_i, c[0])
        lobe = specular_lobe_1d(theta_i[:, None], THETA_S[None, :], c[0])
        diff = (1 - rho)[:, None] * np.cos(THETA_S)[None, :] / 2
        region = diff > lobe
        coef = r["coef"]  # (R, 2, I, S)
        summed = np.sum(np.where(region[None, None], coef, 0.0), -1)  # (R, 2, I)
        d, se = exact_dolp(summed)
        out[c] = {
            "dhr_s": r["energy"][:, 0].mean(0),
            "dhr_p": r["energy"][:, 1].mean(0),
            "model_specular_dhr": rho,
            "model_diffuse": 1 - rho,
            "region_exact_s": summed[:, 0].mean(0) * dth,
            "region_exact_p": summed[:, 1].mean(0) * dth,
            "region_model_specular": np.sum(np.where(region, lobe, 0), -1) * dth,
            "region_model_total": np.sum(np.where(region, lobe + diff, 0), -1) * dth,
            "dolp_diffuse_region": d,
            "dolp_diffuse_region_se": se,
        }
    return out


def iron_impedance_check(ctx, quick):
    """DOLP of one rough iron surface (20 wavelengths, slope 0.3, height 0.5): impedance condition
    at 15 points per wavelength against the exact formulation at 60 (8.7 inside)."""
    if quick:
        return None
    th = np.radians([20, 40, 60])
    x, y = rough_surface(20.0, 1 / 60, 0.5, correlation_length_for_slope(0.5, 0.3), ctx.rng)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    s = np.arange(0.0, arc[-1], 1 / 60)
    x, y = np.interp(s, arc, x), np.interp(s, arc, y)
    incs = [TaperedWave(t, 4.9) for t in th]
    d = {}
    with ctx.step("iron_impedance_check"):
        for method, step in (("exact", 1), ("impedance", 4)):
            c = [
                _solve_one(x[::step], y[::step], incs, pol, MATERIALS[2][1], method)[2]
                for pol in ("s", "p")
            ]
            s, p = (np.diag(ci.scattering_coefficient(th)) for ci in c)
            d[method] = (s - p) / (s + p)
    return float(np.max(np.abs(d["exact"] - d["impedance"])))


def render_current(ctx, cell):
    """pyvista: one rough aluminium surface (impedance condition, s-pol, 45 deg) extruded along z,
    coloured by |J| of its induced current."""
    x, y = surface(20.0, cell[1], correlation_length_for_slope(cell[1], cell[0]), ctx.rng)
    _, _, sol = _solve_one(
        x, y, [TaperedWave(np.radians(45), 4.9)], "s", MATERIALS[3][1], "impedance"
    )
    try:
        import pyvista as pv

        z = np.linspace(0, 4, 12)
        X, Z = np.meshgrid(x, z, indexing="ij")
        Y = np.broadcast_to(y[:, None], X.shape)
        grid = pv.StructuredGrid(X, Z, Y)
        J = np.abs(sol.current[:, 0]) / np.max(np.abs(sol.current[:, 0]))
        grid["|J| (normalised)"] = np.repeat(J[:, None], z.size, 1).ravel(order="F")
        pl = pv.Plotter(off_screen=True, window_size=(900, 420))
        pl.add_mesh(grid, scalars="|J| (normalised)", cmap="inferno", smooth_shading=True)
        pl.add_text(
            f"aluminium 1.44 - j16, slope {cell[0]}, sigma_h {cell[1]} wavelength: "
            "|J| for s-pol at 45 deg (tapered wave)",
            font_size=9,
        )
        pl.camera_position = [(-4, -14, 9), (0, 2, 0), (0, 0, 1)]
        pl.screenshot(str(ctx.out / "lobe_3d.png"))
        pl.close()
        ctx.add_image("lobe_3d")
        return True
    except Exception as exc:  # no OpenGL context: report it instead of failing the study
        ctx.say(f"The pyvista rendering failed on this machine: {type(exc).__name__}: {exc}")
        return False


STYLE = {
    "ts_hyde": ("C1", "-", "1-D model, shadowed + diffuse"),
    "ts_none": ("C2", "--", "1-D model, shadowed, no diffuse (facet DOLP)"),
    "none_hyde": ("C3", ":", "1-D model, unshadowed + diffuse"),
    "pbrdf_2d": ("C4", "-.", "2-D pBRDF (inversion's model)"),
}


def figure_specular(ctx, res, cell, theta_i):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 4, figsize=(16, 3.8), layout="constrained")
    sp = _specular_index(theta_i)
    rows = np.arange(theta_i.size)
    for ax, (name, _, _) in zip(axes, MATERIALS):
        r = res[name, cell]
        for v, (col, ls, lab) in STYLE.items():
            ax.plot(np.degrees(theta_i), r[v][rows, sp], ls, color=col, label=lab)
        ax.errorbar(
            np.degrees(theta_i),
            r["exact"][rows, sp],
            yerr=2 * r["se"][rows, sp],
            fmt="ko",
            ms=4,
            label="exact (MoM), 2 s.e.",
        )
        ax.set(title=name, xlabel=r"$\theta_i = \theta_r$ [deg]")
    axes[0].set_ylabel("DOLP")
    fig.legend(
        *axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=5, fontsize=7
    )
    fig.suptitle(f"specular DOLP, slope {cell[0]}, $\\sigma_h$ = {cell[1]} $\\lambda$")
    ctx.save_figure(fig, "dolp_specular")


def figure_theta_r(ctx, res, cell, theta_i, deg=50):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 4, figsize=(16, 3.8))
    i = int(np.argmin(np.abs(np.degrees(theta_i) - deg)))
    for ax, (name, _, _) in zip(axes, MATERIALS):
        r = res[name, cell]
        seen = r["power"][i] >= 1e-3 * np.max(r["power"][i])
        for v, (col, ls, lab) in STYLE.items():
            ax.plot(np.degrees(THETA_S), r[v][i], ls, color=col, label=lab)
        ax.errorbar(
            np.degrees(THETA_S[seen]),
            r["exact"][i, seen],
            yerr=2 * r["se"][i, seen],
            fmt="ko",
            ms=3,
            label="exact (MoM), 2 s.e.",
        )
        ax.set(
            title=name,
            xlabel=r"$\theta_s$ [deg] (specular at $\theta_i$)",
            ylabel="DOLP",
            ylim=(-0.3, 1.05),
        )
    axes[0].legend(fontsize=6)
    fig.suptitle(
        f"DOLP over the plane of incidence, $\\theta_i$ = {np.degrees(theta_i[i]):.0f} deg, "
        f"slope {cell[0]}, $\\sigma_h$ = {cell[1]} $\\lambda$ (exact where power >= 1e-3 of peak)"
    )
    ctx.save_figure(fig, "dolp_theta_r")


def figure_maps(ctx, summary, cell_list, theta_i):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 4, figsize=(16, 0.9 + 0.32 * len(cell_list) + 2), squeeze=False)
    labels = [f"{s:g} / {h:g}" for s, h in cell_list]
    for ax, (name, _, _) in zip(axes[0], MATERIALS):
        a = np.abs(summary[name]["errors"]["ts_hyde"])
        im = ax.imshow(
            a,
            aspect="auto",
            cmap="magma_r",
            vmin=0,
            vmax=0.1,
            origin="lower",
            extent=(
                np.degrees(theta_i[0]) - 5,
                np.degrees(theta_i[-1]) + 5,
                -0.5,
                len(cell_list) - 0.5,
            ),
        )
        for k in range(len(cell_list)):
            for j, t in enumerate(np.degrees(theta_i)):
                if a[k, j] <= 0.01:
                    ax.text(t, k, "ok", ha="center", va="center", fontsize=6, color="C2")
        ax.set_yticks(range(len(cell_list)), labels, fontsize=6)
        ax.set(title=name, xlabel=r"$\theta_i = \theta_r$ [deg]")
    axes[0, 0].set_ylabel(r"slope / $\sigma_h/\lambda$")
    fig.colorbar(im, ax=axes[0], label="|DOLP error| (1-D model, shadowed + diffuse)")
    ctx.save_figure(fig, "dolp_error_maps")


def figure_bias(ctx, bias, cell_list, pbias=None):
    """|bias| / width of n and kappa per cell: fit_dolp (filled) and sample_posterior (open)."""
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 2, figsize=(12, 3.8))
    x = np.arange(len(cell_list))
    noise = NOISES[-1]
    for ax, (j, par) in zip(axes, ((0, "n"), (1, "kappa"))):
        for k, (name, _, _) in enumerate(MATERIALS):
            b = bias[name][noise]
            ratio = np.abs(b["bias"][:, j]) / b["width"][:, j]
            ax.semilogy(x + 0.15 * k, ratio, "o", color=f"C{k}", label=f"{name}, fit_dolp")
            if pbias is not None and noise in pbias[name]:
                pb = pbias[name][noise]
                pr = np.abs(pb["bias"][:, j]) / pb["width"][:, j]
                ax.semilogy(x + 0.15 * k + 0.05, pr, "o", mfc="none", color=f"C{k}")
        ax.axhline(1, color="k", lw=0.8)
        ax.set_xticks(x, [f"{s:g}/{h:g}" for s, h in cell_list], rotation=90, fontsize=6)
        ax.set(
            ylabel=f"|bias of {par}| / posterior width",
            xlabel=r"slope / $\sigma_h/\lambda$",
            title=f"model-error bias vs 1-sigma width (DOLP noise {noise})",
        )
    axes[0].legend(fontsize=7)
    ctx.save_figure(fig, "inversion_bias")


def figure_pec(ctx, energy, cell, theta_i):
    pyplot = plt()
    e = energy[cell]
    fig, (ax, bx) = pyplot.subplots(1, 2, figsize=(11, 3.8))
    deg = np.degrees(theta_i)
    ax.plot(deg, e["dhr_s"], "o-", label="exact DHR, s")
    ax.plot(deg, e["dhr_p"], "s--", label="exact DHR, p")
    ax.plot(deg, e["model_specular_dhr"], "k-", label=r"model specular DHR $\rho_1$")
    ax.plot(deg, e["model_diffuse"], "k:", label=r"model diffuse $1 - \rho_1$ (Eq. 176)")
    ax.plot(deg, e["region_exact_s"], "^-", label="exact power in diffuse region, s")
    ax.plot(deg, e["region_exact_p"], "v--", label="exact power in diffuse region, p")
    ax.plot(deg, e["region_model_specular"], "x-", color="grey", label="model there, specular")
    ax.plot(deg, e["region_model_total"], "+-", color="k", label="model there, with diffuse")
    ax.set(
        xlabel=r"$\theta_i$ [deg]",
        ylabel="power",
        title=f"rough PEC, slope {cell[0]}, $\\sigma_h$ = {cell[1]} $\\lambda$",
    )
    ax.legend(fontsize=6)
    bx.errorbar(deg, e["dolp_diffuse_region"], yerr=2 * e["dolp_diffuse_region_se"], fmt="o")
    bx.axhline(0, color="k", lw=0.5)
    bx.set(
        xlabel=r"$\theta_i$ [deg]",
        ylabel="DOLP (s - p)/(s + p)",
        title="PEC light where the model's diffuse term dominates",
    )
    ctx.save_figure(fig, "pec_dhr")


GRAZING_DEG = 80.0
GRAZING_CHECK_CELL = (0.3, 0.25)


def _grazing_settings(quick):
    """The 80 deg pass: cells, length [wavelengths], realizations (dielectrics, metals and PEC),
    materials (None: all), and whether to run the convergence check. The MoM's taper check asks
    g >= 37.04 wavelengths at 80 deg (power correction below 0.02) and a surface of 4 g: 150
    wavelengths, taper 37.4. Quick mode solves the PEC of one cell (its energy is the check)."""
    if quick:
        return [(0.3, 0.5)], 150.0, 0, 1, ("pec",), False
    return list(CELLS), 150.0, 2, 4, None, True


def run_grazing(ctx):
    """MoM at 80 deg incidence on 150-wavelength surfaces and, in full mode, the convergence
    check: the cell ``GRAZING_CHECK_CELL`` again on surfaces and tapers twice as long (metals and
    PEC, impedance condition: the exact formulation of glass at 300 wavelengths does not fit).

    Parameters
    ----------
    ctx : StudyContext

    Returns
    -------
    (runs, check): {cell: {material: {"coef", "energy"}}} as :func:`simulate` for theta_i = 80
    deg, and the doubled run of the check cell (same layout, or None in quick mode).
    """
    cell_list, length, reals, metal_reals, mats, check = _grazing_settings(ctx.quick)
    th = np.radians([GRAZING_DEG])
    seeds = ctx.rng.integers(2**32, size=len(cell_list) + 1)
    tasks = [(c, th, length, reals, metal_reals, int(sd), mats) for c, sd in zip(cell_list, seeds)]
    if check:
        tasks.append(
            (GRAZING_CHECK_CELL, th, 2 * length, 0, 4, int(seeds[-1]), ("iron", "aluminium", "pec"))
        )
    with ctx.step("mom_80deg"):
        out = list(ctx.executor.map(_cell_task, tasks))
    return dict(zip(cell_list, out)), (out[-1] if check else None)


def grazing_summary(runs, check):
    """Specular DOLP at 80 deg, exact (jackknife s.e.) against the 1-D model (shadowed, diffuse)
    and the 2-D inversion model, per material and cell; the PEC's DHR (energy: exactly 1); and
    the convergence check (DOLP at twice the length and taper minus DOLP at the standard ones).

    Parameters
    ----------
    runs : dict -- :func:`run_grazing`'s first output.
    check : dict or None -- its second.

    Returns
    -------
    dict: "rows" list of (material, cell, exact, se, model_1d, model_2d); "pec_dhr_dev" largest
    |DHR - 1|; "check" list of (material, dolp_150, se_150, dolp_300, se_300) or None.
    """
    th = np.radians([GRAZING_DEG])
    sp = _specular_index(th)
    etas = dict((m[0], m[1]) for m in MATERIALS)
    rows, dev = [], 0.0
    for c, per in runs.items():
        for name, r in per.items():
            if name == "pec":
                dev = max(dev, float(np.max(np.abs(r["energy"].mean(0) - 1))))
                continue
            d, se = exact_dolp(r["coef"][..., 0, sp[0]])
            mod = model_curves(etas[name], c[0], th)
            rows.append(
                (
                    name,
                    c,
                    float(d),
                    float(se),
                    *(float(mod[v][0, sp[0]]) for v in ("ts_hyde", "pbrdf_2d")),
                )
            )
    out = {"rows": rows, "pec_dhr_dev": dev, "check": None}
    if check is not None:
        out["check"] = []
        for name, r in check.items():
            if name == "pec":
                out["pec_dhr_dev_300"] = float(np.max(np.abs(r["energy"].mean(0) - 1)))
                continue
            a = exact_dolp(runs[GRAZING_CHECK_CELL][name]["coef"][..., 0, sp[0]])
            b = exact_dolp(r["coef"][..., 0, sp[0]])
            out["check"].append((name, *(float(x) for x in (*a, *b))))
    return out


def _report_grazing(ctx, g):
    """Report and metrics of :func:`grazing_summary`."""
    m = ctx.metrics
    m["pec_80deg_max_dhr_deviation"] = g["pec_dhr_dev"]
    text = (
        f"Incidence {GRAZING_DEG:.0f} deg (surfaces of 150 wavelengths, taper 37.4): the rough "
        f"PEC's DHR is 1 within {g['pec_dhr_dev']:.1e} (energy)."
    )
    if g["rows"]:
        lines = [
            "| material | cell | exact (s.e.) | 1-D model | 2-D pBRDF |",
            "|---|---|---|---|---|",
        ]
        for name, c, d, se, m1, m2 in g["rows"]:
            lines.append(
                f"| {name} | {c[0]:g} / {c[1]:g} | {d:.3f} ({se:.3f}) | {m1:.3f} | {m2:.3f} |"
            )
        err = {n: max(abs(r[2] - r[4]) for r in g["rows"] if r[0] == n) for n, *_ in MATERIALS}
        m["max_abs_dolp_error_80deg"] = err
        text += (
            " Specular DOLP, exact minus model, largest per material: "
            + ", ".join(f"{n} {e:.3f}" for n, e in err.items())
            + ":\n\n"
            + "\n".join(lines)
        )
    if g["check"]:
        diffs = [(n, b - a, np.hypot(sa, sb)) for n, a, sa, b, sb in g["check"]]
        m["convergence_80deg"] = [[n, d, se] for n, d, se in diffs]
        text += (
            f"\n\nConvergence at {GRAZING_DEG:.0f} deg, cell {GRAZING_CHECK_CELL}: doubling the "
            "surface (300 wavelengths) and the taper (74.9) changes the specular DOLP by "
            + ", ".join(f"{n} {d:+.3f} (combined s.e. {se:.3f})" for n, d, se in diffs)
            + f"; the PEC's DHR there is 1 within {g.get('pec_dhr_dev_300', float('nan')):.1e}."
        )
    ctx.say(text)


def _settings(quick):
    """Incidences, surface length, realizations (all, metals), noise draws per cell."""
    if quick:
        return np.radians(np.arange(10, 61, 10)), 20.0, 2, 2, 4
    return np.radians(np.arange(10, 71, 10)), 40.0, 6, 12, 40


def run(ctx):
    theta_i, length, reals, metal_reals, draws = _settings(ctx.quick)
    cell_list = cells(ctx.quick)
    settings = run_settings(ctx)
    runs = resume_runs(ctx.out / "mom_runs.npz", settings)
    if runs is None:
        runs = _run_cells(ctx, cell_list, theta_i, length, reals, metal_reals)
        save_runs(ctx.out / "mom_runs.npz", runs, settings)
    else:
        ctx.rng.integers(2**32, size=len(cell_list))  # the cells' seeds: same stream as a run
        ctx.say("MoM at 10-70 deg resumed from this folder's `mom_runs.npz` (same settings).")
    grazing = resume_runs(ctx.out / "mom_runs_80deg.npz", settings)
    if grazing is None:
        grazing, check = run_grazing(ctx)
        save_runs(ctx.out / "mom_runs_80deg.npz", grazing, settings)
        if check is not None:
            save_runs(ctx.out / "mom_runs_80deg_check.npz", {GRAZING_CHECK_CELL: check}, settings)
    else:
        ctx.rng.integers(2**32, size=len(_grazing_settings(ctx.quick)[0]) + 1)
        check = resume_runs(ctx.out / "mom_runs_80deg_check.npz", settings)
        check = None if check is None else check[GRAZING_CHECK_CELL]
        ctx.say("MoM at 80 deg resumed from this folder's `mom_runs_80deg*.npz`.")
    analyse(ctx, runs, theta_i, length, (reals, metal_reals), draws, (grazing, check))


def run_settings(ctx):
    """What the saved MoM coefficients depend on: a run resumes them only when these match.

    Parameters
    ----------
    ctx : StudyContext

    Returns
    -------
    str, JSON of the study id, mode, seed and the MoM settings of both passes.
    """
    import json

    theta_i, length, reals, metal_reals, _ = _settings(ctx.quick)
    g_cells, g_len, g_reals, g_metal, g_mats, g_check = _grazing_settings(ctx.quick)
    return json.dumps(
        {
            "study": STUDY["id"],
            "quick": ctx.quick,
            "seed": ctx.seed,
            "theta_i_deg": np.round(np.degrees(theta_i), 6).tolist(),
            "length": length,
            "realizations": [reals, metal_reals],
            "cells": [list(c) for c in cells(ctx.quick)],
            "ppw": PPW,
            "grazing": [[list(c) for c in g_cells], g_len, g_reals, g_metal, g_mats, g_check],
        },
        sort_keys=True,
    )


def resume_runs(path, settings):
    """The coefficients saved at ``path`` by a run with the same ``settings``, else None.

    Parameters
    ----------
    path : Path -- an npz written by :func:`save_runs`.
    settings : str -- :func:`run_settings` of this run.

    Returns
    -------
    dict as :func:`load_runs`, or None (no file, or other settings: the MoM is solved again).
    """
    if not path.exists():
        return None
    with np.load(path) as z:
        saved = str(z["__settings__"]) if "__settings__" in z.files else None
    return load_runs(path) if saved == settings else None


def save_runs(path, runs, settings=None):
    """The raw MoM coefficients of every cell (re-analysis without re-solving), written
    atomically, with the run's :func:`run_settings` for :func:`resume_runs`."""
    from scatterlab.runtime.results import write_npz

    arrays = {
        f"{name}|{c[0]}|{c[1]}|{q}": v
        for c, per in runs.items()
        for name, d in per.items()
        for q, v in d.items()
    }
    if settings is not None:
        arrays["__settings__"] = np.array(settings)
    write_npz(path, overwrite=True, **arrays)


def load_runs(path):
    """Inverse of :func:`save_runs`: {(slope, height): {material: {"coef", "energy"}}}."""
    runs = {}
    with np.load(path) as z:
        for key in z.files:
            if key == "__settings__":
                continue
            name, sl, h, q = key.split("|")
            runs.setdefault((float(sl), float(h)), {}).setdefault(name, {})[q] = z[key]
    return runs


def extend_table(table, grazing, length=150.0):
    """The model-error table with the 80 deg row of the grazing pass (first half of its
    realizations), when that pass solved every material on the table's slopes; else ``table``.

    Parameters
    ----------
    table : dict -- :func:`model_error_table`'s output (incidences below 80 deg).
    grazing : dict or None -- :func:`run_grazing`'s first output.
    length : float -- the grazing surfaces' length [wavelengths].

    Returns
    -------
    dict, the same layout with ``theta_i`` (I + 1,) and ``error`` (K, L, I + 1, S), plus
    ``length_80deg``.
    """
    names = [m[0] for m in MATERIALS]
    if not grazing or any(n not in per for per in grazing.values() for n in names):
        return table
    cl = list(grazing)
    if sorted({c[0] for c in cl}) != list(table["slopes"]):
        return table
    th = np.radians([GRAZING_DEG])
    row = model_error_table(compare(grazing, th, half=0), cl, th, table["realizations"], length)
    out = dict(table, theta_i=np.r_[table["theta_i"], th], length_80deg=np.array(length))
    for key in ("error", "error_rms"):
        if key in table:
            out[key] = np.concatenate([table[key], row[key]], 2)
    return out


def analyse(ctx, runs, theta_i, length, reals, draws, grazing=(None, None)):
    """Everything after the MoM: comparisons, table, inversion, energy, figures, report.

    Parameters
    ----------
    ctx : StudyContext
    runs : dict -- {cell: {material: {"coef", "energy"}}} from :func:`simulate`.
    theta_i : ndarray (I,) [rad]
    length : float -- surface length [wavelengths].
    reals : (int, int) -- realizations (dielectrics, metals and PEC).
    draws : int -- noise draws per cell for the Laplace coverage (emcee: draws // 20, >= 2).
    grazing : (dict or None, dict or None) -- :func:`run_grazing`'s output (80 deg).

    Returns
    -------
    None (figures, metrics and the report go to ``ctx``).
    """
    from scatterlab.inversion.model_error import TABLE_PATH

    cell_list = list(runs)
    reals, metal_reals = reals
    with ctx.step("compare"):
        res = compare(runs, theta_i)
        res_a, res_b = compare(runs, theta_i, half=0), compare(runs, theta_i, half=1)
        table = model_error_table(res_a, cell_list, theta_i, (reals // 2, metal_reals // 2), length)
        write_model_error_table(ctx.out / "dolp_mom.npz", extend_table(table, grazing[0]))
        summary = specular_summary(res, cell_list, theta_i)
    with ctx.step("inversion"):
        bias = {n: inversion_bias(res, cell_list, theta_i, n, e) for n, e, _ in MATERIALS}
        cover = {
            n: coverage(res_b, table, cell_list, theta_i, n, e, draws, ctx.rng, ctx.quick)
            for n, e, _ in MATERIALS
        }
    with ctx.step("inversion_emcee"):
        pbias, pcover = posterior_inversion(
            ctx, res, res_b, table, cell_list, theta_i, 1 if ctx.quick else max(2, draws // 20)
        )
    with ctx.step("pec_energy"):
        energy = pec_energy(runs, cell_list, theta_i)
    iron_check = iron_impedance_check(ctx, ctx.quick)
    rep = (0.3, 0.5) if (0.3, 0.5) in cell_list else cell_list[0]
    with ctx.step("figures"):
        figure_specular(ctx, res, rep, theta_i)
        figure_theta_r(ctx, res, rep, theta_i)
        figure_maps(ctx, summary, cell_list, theta_i)
        figure_bias(ctx, bias, cell_list, pbias)
        figure_pec(ctx, energy, rep, theta_i)
    with ctx.step("lobe_3d"):
        ctx.metrics["current_rendered"] = render_current(ctx, rep)
    _metrics(
        ctx,
        summary,
        bias,
        cover,
        energy,
        cell_list,
        theta_i,
        length,
        (reals, metal_reals),
        iron_check,
    )
    _report(ctx, summary, bias, cover, energy, cell_list, theta_i, iron_check, TABLE_PATH)
    _report_posterior(ctx, pbias, pcover, cell_list)
    if grazing[0]:
        _report_grazing(ctx, grazing_summary(*grazing))
    m = ctx.metrics
    set_verdict(
        ctx,
        "own study",
        "largest specular DOLP error of the 1-D model vs MoM: "
        + ", ".join(f"{n} {m[f'{n}_max_abs_dolp_error']:.3f}" for n, _, _ in MATERIALS)
        + (
            "; posterior coverage not judged in quick mode (smoke test)"
            if ctx.quick
            else f"; emcee 95 % coverage of (n, kappa) {m['posterior_coverage95_without']:.0%} without, "
            f"{m['posterior_coverage95_pipeline']:.0%} with the model-error term (pipeline form)"
        ),
    )


def _metrics(ctx, summary, bias, cover, energy, cell_list, theta_i, length, reals, iron_check):
    m = ctx.metrics
    m["cells_slope_height"] = [list(c) for c in cell_list]
    m["theta_i_deg"] = np.degrees(theta_i).tolist()
    m["surface_length_wavelengths"] = length
    m["realizations_per_cell_dielectrics"], m["realizations_per_cell_metals_and_pec"] = reals
    m["iron_impedance_vs_exact_max_dolp_difference"] = iron_check
    for name, s in summary.items():
        m[f"{name}_max_abs_dolp_error"] = s["max_abs_error"]
        m[f"{name}_max_error_at"] = [list(s["max_at"][0]), s["max_at"][1]]
        m[f"{name}_max_error_se"] = s["max_se"]
        m[f"{name}_fraction_within_0.01"] = s["fraction_within_0.01"]
        m[f"{name}_cells_within_0.01_all_angles"] = [list(c) for c in s["good_cells"]]
        m[f"{name}_max_abs_error_by_model"] = s["max_abs_error_by_variant"]
        m[f"{name}_median_se"] = s["median_se"]
        m[f"{name}_lobe_max_abs_error"] = s["lobe_max_abs_error"]
        m[f"{name}_specular_error_1d"] = s["errors"]["ts_hyde"].tolist()
        m[f"{name}_specular_se"] = s["se"].tolist()
        for noise, b in bias[name].items():
            m[f"{name}_bias_noise{noise}"] = b["bias"].tolist()
            m[f"{name}_width_noise{noise}"] = b["width"].tolist()
        m[f"{name}_coverage95_without_model_error"] = cover[name]["without"]
        m[f"{name}_coverage95_with_model_error"] = cover[name]["with"]
        m[f"{name}_coverage95_with_correlated_model_error"] = cover[name]["with_correlated"]
    for c, e in energy.items():
        m[f"pec_{c[0]}_{c[1]}"] = {k: np.asarray(v).tolist() for k, v in e.items()}


def _fmt_cells(cl):
    return ", ".join(f"({s:g}, {h:g})" for s, h in cl) if cl else "none"


def _report(ctx, summary, bias, cover, energy, cell_list, theta_i, iron_check, table_path):
    m = ctx.metrics
    deg = np.degrees(theta_i)
    ctx.say(
        f"{len(cell_list)} cells (slope, sigma_h/lambda), "
        f"{m['realizations_per_cell_dielectrics']} realization(s) for glass and paint, "
        f"{m['realizations_per_cell_metals_and_pec']} for iron, aluminium and the PEC, of "
        f"{m['surface_length_wavelengths']:.0f} wavelengths each, incidence "
        f"{deg[0]:.0f}-{deg[-1]:.0f} deg; DOLP errors are exact minus model at the specular "
        "geometry unless said otherwise (exact powers are means over a 5 deg aperture, which "
        "averages a few speckles of each realization; the model is taken at its centre), "
        "model = the 1-D facet model with Torrance-Sparrow "
        "shadowing and the Hyde diffuse term."
        + (
            ""
            if iron_check is None
            else f" The impedance condition changes iron's DOLP by at "
            f"most {iron_check:.3f} against the exact formulation (one surface, 20-60 deg)."
        )
    )
    for name, s in summary.items():
        best = min(s["max_abs_error_by_variant"], key=s["max_abs_error_by_variant"].get)
        (sl, h), t = s["max_at"]
        ctx.say(
            f"**{name}**: largest specular DOLP error {s['max_abs_error']:.3f} (standard error "
            f"{s['max_se']:.3f}) at slope {sl:g}, sigma_h/lambda {h:g}, {t:.0f} deg; "
            f"{100 * s['fraction_within_0.01']:.0f} % of the (cell, angle) points are within "
            f"0.01; cells within 0.01 at every angle: {_fmt_cells(s['good_cells'])}; the "
            "model is good to 0.01 at: "
            + (
                "; ".join(
                    f"({c[0]:g}, {c[1]:g}) {', '.join(map(str, d))} deg"
                    for c, d in s["good_angles"].items()
                )
                or "no (cell, angle)"
            )
            + ". Median "
            f"standard error {s['median_se']:.3f}. Largest error by model: "
            + ", ".join(f"{k} {v:.3f}" for k, v in s["max_abs_error_by_variant"].items())
            + f" (smallest: {best}). Over theta_r, within the lobe (exact power >= 5 % of its "
            f"peak) the largest error is {s['lobe_max_abs_error']:.3f}."
        )
    _report_inversion(ctx, bias, cover, table_path)
    _report_pec(ctx, energy)


def coverage_verdict(rate, level, units):
    """Whether a coverage ``rate`` is nominal for ``level`` within two binomial standard errors
    of ``units`` independent cases.

    Parameters
    ----------
    rate : float in [0, 1] -- the fraction of intervals holding the truth.
    level : float in (0, 1) -- the nominal level.
    units : int -- independent cases (here the roughness cells: the cases of one cell share its
        surfaces).

    Returns
    -------
    str: "nominal", "over-covers" or "under-covers".
    """
    band = 2 * np.sqrt(level * (1 - level) / units)
    if rate > level + band:
        return "over-covers"
    return "under-covers" if rate < level - band else "nominal"


def _report_inversion(ctx, bias, cover, table_path):
    lines = [
        "| material | noise | median abs bias n | median width n | bias > width (n) | "
        "median abs bias kappa | median width kappa | bias > width (kappa) | median abs bias "
        "sigma |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, per in bias.items():
        for noise, b in per.items():
            ab, w = np.abs(b["bias"]), b["width"]
            lines.append(
                f"| {name} | {noise} | {np.nanmedian(ab[:, 0]):.3g} | {np.nanmedian(w[:, 0]):.3g}"
                f" | {np.mean(ab[:, 0] > w[:, 0]) * 100:.0f} % | {np.nanmedian(ab[:, 1]):.3g} | "
                f"{np.nanmedian(w[:, 1]):.3g} | {np.mean(ab[:, 1] > w[:, 1]) * 100:.0f} % | "
                f"{np.nanmedian(ab[:, 2]):.3g} |"
            )
    ctx.say(
        "Inversion of the exact specular DOLP at 30, 40, 50, 60 deg (noise-free, fit_dolp with "
        "sigma free; width = Laplace 1-sigma at the stated DOLP noise; an undetermined "
        "parameter has width NaN):\n\n" + "\n".join(lines)
    )
    units = len(next(iter(bias.values()))[NOISES[0]]["bias"])  # the roughness cells
    cov = ", ".join(
        f"{n} {100 * c['without']:.0f} % -> {100 * c['with']:.0f} % "
        f"({coverage_verdict(c['with'], 0.95, units)}; {100 * c['with_correlated']:.0f} % "
        f"correlated, {coverage_verdict(c['with_correlated'], 0.95, units)})"
        for n, c in cover.items()
    )
    ctx.say(
        "Coverage of the true (n, kappa) by 95 % intervals on held-out realizations plus noise "
        f"({', '.join(str(x) for x in NOISES)}), without -> with the model-error term as "
        "independent per-geometry errors (dolp_model_error as fit_dolp's systematic) and, in "
        "brackets, correlated across geometries (dolp_model_error_covariance, 20 deg); "
        "material and roughness unknown to the pipeline (the largest tabulated error); the "
        f"table from the other half of the realizations: {cov}; pooled over the materials "
        + ", ".join(
            f"{k} {100 * np.mean([c[k] for c in cover.values()]):.0f} %"
            for k in ("without", "with", "with_correlated")
        )
        + f". Nominal is 95 %; per material the verdict allows two binomial standard errors of "
        f"its {units} roughness cells (the independent units). The shipped "
        f"table is {table_path.name}; this run wrote its own as dolp_mom.npz."
    )


def _report_posterior(ctx, pbias, pcover, cell_list):
    """Report and metrics of :func:`posterior_inversion` (bias table, cells with bias > width,
    coverage per material, error model and level)."""
    from scatterlab.studies._dolp_posterior import FORMS, LEVELS, sampler_settings

    m = ctx.metrics
    lines = [
        "| material | noise | median abs bias n / width | median abs bias kappa / width | "
        "median abs bias sigma / width | cells with bias > width (n or kappa) |",
        "|---|---|---|---|---|---|",
    ]
    for name, per in pbias.items():
        for noise, b in per.items():
            ab, w = np.abs(b["bias"]), b["width"]
            bad = [c for c, e in zip(cell_list, b["exceeds"][:, :2].any(-1)) if e]
            lines.append(
                f"| {name} | {noise} | "
                + " | ".join(
                    f"{np.median(ab[:, j]):.3g} / {np.median(w[:, j]):.3g}" for j in range(3)
                )
                + f" | {len(bad)} of {len(cell_list)}: {_fmt_cells(bad)} |"
            )
            m[f"{name}_posterior_bias_noise{noise}"] = b["bias"].tolist()
            m[f"{name}_posterior_width_noise{noise}"] = b["width"].tolist()
    ctx.say(
        "The same noise-free exact DOLP through sample_posterior (emcee, "
        f"{sampler_settings(ctx.quick)}, sigma sampled): bias = posterior median - truth, width "
        "= half the 68 % credible interval:\n\n" + "\n".join(lines)
    )
    rows = []
    units = len(cell_list)
    for f in FORMS:
        per = {lv: np.concatenate([pcover[n][f][lv] for n in pcover]) for lv in LEVELS}
        cells = ", ".join(
            f"{n} {100 * np.mean(pcover[n][f][0.68]):.0f} / {100 * np.mean(pcover[n][f][0.95]):.0f}"
            for n in pcover
        )
        off = [
            f"{n} {lv:.0%} {v}"
            for n in pcover
            for lv in LEVELS
            if (v := coverage_verdict(np.mean(pcover[n][f][lv]), lv, units)) != "nominal"
        ]
        pooled = " / ".join(
            coverage_verdict(np.mean(per[lv]), lv, units * len(pcover)) for lv in LEVELS
        )
        rows.append(
            f"| {f} | {100 * np.mean(per[0.68]):.0f} % | {100 * np.mean(per[0.95]):.0f} % | "
            f"{pooled} | {cells} | {', '.join(off) or 'none'} |"
        )
        for lv in LEVELS:
            m[f"posterior_coverage{int(100 * lv)}_{f}"] = float(np.mean(per[lv]))
            for n in pcover:
                m[f"{n}_posterior_coverage{int(100 * lv)}_{f}"] = float(np.mean(pcover[n][f][lv]))
    failed = [x for n in pcover for x in pcover[n]["failed"]]
    failed += [x for per in pbias.values() for b in per.values() for x in b["failed"]]
    m["posterior_failures"] = len(failed)
    ctx.say(
        f"sample_posterior failed (two seeds) in {len(failed)} of the runs (counted as not "
        "covered)" + (f", e.g. {failed[0]}." if failed else ".")
    )
    ctx.say(
        "Coverage of the true (n, kappa) by sample_posterior's equal-tailed 68 % / 95 % credible "
        "intervals (glass: kappa = 0 on the prior's edge, one-sided [0, q]) on held-out "
        "realizations plus noise, per error model: without the term; independent "
        "(systematic = dolp_model_error(th, th), sigma sampled); correlated (covariance = "
        "dolp_model_error_covariance(th, th) + noise^2 I); pipeline (region_posteriors with "
        "model_error=True: sigma known, the material's class known from the classification, "
        "systematic = dolp_model_error(th, th, sigma, material_class=...)); "
        "pipeline_any_material (the same, class unknown: the largest error over all "
        "materials); pipeline_rms (as pipeline with the rms over the simulated heights instead "
        "of the largest error). Verdicts allow two binomial standard errors of the independent "
        f"units: the {units} roughness cells per material ({units * len(pcover)} pooled), since "
        "the cases of one cell share its surfaces:\n\n"
        "| error model | 68 % | 95 % | pooled verdict 68 / 95 % | per material 68 / 95 % | "
        "per material, not nominal |\n|---|---|---|---|---|---|\n" + "\n".join(rows)
    )


def _report_pec(ctx, energy):
    e = list(energy.values())
    dev = max(float(np.max(np.abs(np.r_[x["dhr_s"], x["dhr_p"]] - 1))) for x in e)

    def cat(key):
        return np.concatenate([x[key] for x in e])

    exact = 0.5 * (cat("region_exact_s") + cat("region_exact_p"))
    spec, tot = cat("region_model_specular"), cat("region_model_total")
    diffuse = cat("model_diffuse")
    frac = (exact - spec) / np.maximum(tot - spec, 1e-12)
    big = diffuse > 0.02
    dolp, se = cat("dolp_diffuse_region"), cat("dolp_diffuse_region_se")
    k = int(np.nanargmax(np.abs(dolp)))
    ctx.say(
        f"Rough PEC: the exact DHR is 1 within {dev:.1e} in both polarizations (energy check). "
        f"The model's diffuse term (Eq. 176, 1 - rho_1) is {np.min(diffuse):.3f}-"
        f"{np.max(diffuse):.3f} over the cells and angles. In the angles where it exceeds the "
        f"specular term, the exact power (mean of s and p) is {np.min(exact):.1e} to "
        f"{np.max(exact):.1e}, against {np.min(spec):.1e} to {np.max(spec):.1e} from the "
        f"specular term alone and {np.min(tot):.1e} to {np.max(tot):.1e} with the diffuse term "
        f"(sums over the exact DHR's angles: total exact {np.sum(exact):.2e}, model specular "
        f"{np.sum(spec):.2e}, model with diffuse {np.sum(tot):.2e}); the diffuse "
        f"term accounts for a median {np.nanmedian(frac[big]) if big.any() else float('nan'):.2f} "
        "of the exact excess over the specular term there (1: the diffuse term is that light; "
        "where the diffuse term is above 0.02). The light there has DOLP (s - p)/(s + p) up to "
        f"{dolp[k]:.3f} (standard error {se[k]:.3f}), median |DOLP| "
        f"{np.nanmedian(np.abs(dolp)):.3f}: "
        + (
            "unpolarized within 0.05, as the model assumes."
            if np.nanmax(np.abs(dolp)) < 0.05
            else "not unpolarized: off the lobe s and p scatter differently even from a PEC "
            "(p stronger where the DOLP is negative), which an unpolarized diffuse term cannot "
            "describe."
        )
    )


def export_from_runs(
    runs_path,
    table_path,
    heldout_path,
    theta_i_deg=range(10, 71, 10),
    length=40.0,
    grazing_path=None,
):
    """Regenerate the shipped model-error table (first half of the realizations of a full run's
    ``mom_runs.npz``, and its 80 deg row from ``mom_runs_80deg.npz`` when given) and the tests'
    held-out specular DOLP at 30-60 deg (second half).

    Parameters
    ----------
    runs_path, grazing_path : path -- a full run's ``mom_runs.npz`` and ``mom_runs_80deg.npz``.
    table_path, heldout_path : path -- where to write the table and the held-out DOLP.
    theta_i_deg : sequence of float [deg] -- the run's incidences (without 80).
    length : float -- the run's surface length [wavelengths].

    Returns
    -------
    None
    """
    from scatterlab.runtime.results import write_npz

    runs = load_runs(runs_path)
    theta_i = np.radians(np.asarray(list(theta_i_deg), float))
    cell_list = list(runs)
    res_a = compare(runs, theta_i, half=0)
    res_b = compare(runs, theta_i, half=1)
    n = {m[0]: runs[cell_list[0]][m[0]]["coef"].shape[0] for m in MATERIALS}
    reals = (n["glass"] // 2, n["iron"] // 2)
    table = model_error_table(res_a, cell_list, theta_i, reals, length)
    grazing = None if grazing_path is None else load_runs(grazing_path)
    write_model_error_table(table_path, extend_table(table, grazing))
    idx = [int(np.argmin(np.abs(np.degrees(theta_i) - d))) for d in INV_DEG]
    names = [m[0] for m in MATERIALS]
    write_npz(
        heldout_path,
        overwrite=True,
        materials=np.array(names),
        eta=np.array([m[1] for m in MATERIALS]),
        cells=np.array(cell_list),
        theta_deg=np.array(INV_DEG, float),
        dolp=np.array([[res_b[k, c]["exact_spec"][idx] for c in cell_list] for k in names]),
        se=np.array([[res_b[k, c]["se_spec"][idx] for c in cell_list] for k in names]),
    )
