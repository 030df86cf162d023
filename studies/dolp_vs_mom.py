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
points where the model is good to 0.01 (since 29 Nov 2026: where a 95 % interval shows it).

How the comparison is summarised (since 29 Nov 2026). The exact DOLP is a Monte-Carlo mean over
realizations, so its error against the model carries noise; the largest error over the (cell,
angle) points, which the report and headline used to give, picks out that noise: a 13-seed survey
of quick mode (2 realizations) found it at 0.033-0.116 for glass, 0.039-0.094 paint, 0.076-0.587
iron and 0.058-0.621 aluminium, 9-10 of 13 seeds within 2 of their standard errors of the 13-seed
mean. Now every number carries its jackknife standard error over the realizations
(:func:`pooled_error`; cells add as independent): the mean error exact - model over the points
and its rms with the realizations' noise removed (the jackknife's bias correction of the mean
square; without it the noise adds se^2 to every point's square), in the headline as "mean / rms
+- s.e."; per point the error +- s.e. in a table, a point said to be within 0.01 of the model or
off by more only where its 95 % interval (Student t over the realizations) says so, the rest
undetermined at the run's resolution, which the report states (median s.e. and t x s.e. per
material); a model variant named better than the others only beyond the 95 % interval of the
paired difference (identical variants -- no diffuse term, with or without shadowing -- count as
one); and the rms over the lobe instead of its largest error. The jackknife's s.e. of a mean
square is conservative (Efron-Stein): the scatter is 0.79-0.94 of it in the tests' Monte Carlo,
0.6-1.0 across the seeds below. The full-mode numbers above are the largest errors of those runs
(the old summary). Re-run with this summary (29 Nov 2026, seed 20101210, ``--workers 2``, 864 s at
load ~2.5): over the 56 (cell, angle) points, mean / rms +- s.e. glass +0.041 +- 0.004 / 0.115 +- 0.010,
paint +0.044 +- 0.004 / 0.104 +- 0.010, iron +0.133 +- 0.009 / 0.175 +- 0.011, aluminium +0.116 +- 0.008 /
0.192 +- 0.012 (every rms resolved from zero); points shown within 0.01: 6, 5, 4, 3 of 56, shown off by
more: 26, 24, 27, 26; median s.e. of a point 0.008, 0.009, 0.039, 0.054; emcee 95 % coverage of (n, kappa)
7 % without and 97 % with the model-error term. At 80 deg the largest error per material is 0.18 (s.e.
0.08) glass, 0.16 (0.06) paint, 0.29 (0.04) iron and 0.72 (0.06) aluminium.

Quick mode (one cell (0.3, 0.5), 12 realizations for glass and paint and 24 for the metals and
the PEC (the impedance condition is cheap; the metals' DOLP is the noisier), 20 wavelengths,
incidence 10-60 deg; at 80 deg the PEC of one 150-wavelength surface; emcee 8 walkers x 100
steps, one noise level, one draw; its coverage numbers are a smoke test). Resolution: median s.e.
of one point 0.008 glass, 0.010 paint, 0.024 iron, 0.029 aluminium, so a point can show a model
error of about 0.02 (dielectrics) and 0.05-0.06 (metals); the mean and rms over the 6 points to
+-0.002-0.006 (dielectrics) and +-0.01-0.03 (metals). Headline over 13 seeds (20101210, 1-12):
mean / rms glass +0.021 / 0.029 (ranges +0.012-0.031 / 0.017-0.047, typical s.e. 0.004 / 0.007),
paint +0.019 / 0.028 (0.009-0.029 / 0.018-0.043), iron +0.053 / 0.062 (0.040-0.071 /
0.039-0.082, s.e. 0.014 / 0.022), aluminium +0.024 / 0.026 (0.006-0.041 / 0.000-0.064, s.e.
0.014 / 0.025; a noise-corrected mean square within its noise prints as an upper limit, rms < x). Seeds within 2
s.e. of the 13-seed mean: 11, 13, 13, 13 of 13 for the mean and 11, 11, 13, 13 for the rms; on 30
further seeds (glass and paint only) 90-97 %, the seed-to-seed scatter 0.70-0.82 of the stated
s.e. What quick mode can conclude for this cell: the exact DOLP lies above the 1-D model's on
average (mean error beyond 2 s.e. on 13 of 13 seeds for glass and iron, 30 of 30 more for glass;
11 of 13 paint, 28 of 30 more; 7 of 13 aluminium, whose sign this size does not settle); the rms's
95 % interval excludes zero on 9, 7, 2, 0 of 13 seeds (glass, paint, iron, aluminium: the
conservative s.e. of a mean square); single (cell, angle) points and the ranking of the model
variants are mostly undetermined at this size. Run time 21 s on a quiet
machine (MoM 8 s; the MoM was 2 s with 2 realizations), 43-49 s under a load average of 6, and
up to 100 s while two runs shared the 2 cores with other work (the 2-realization version took
22-69 s then).

Re-measured 29 Nov 2026 (quick, seeds 1-8, code unchanged): "own study" on all 8; mean error glass
+0.012..+0.028 (s.e. 0.003-0.005), paint +0.009..+0.026 (0.004-0.006), iron +0.040..+0.066 (0.010-0.018),
aluminium +0.006..+0.034 (0.010-0.017); seed-to-seed sd of the mean 0.006 (glass, paint: 1.5 and 1.2 x the
typical stated s.e., which 8 seeds pin only to about +-40 %; the 30-seed figures above are the firmer ones),
0.009 iron and 0.010 aluminium (0.7 x). Mean beyond 2 s.e. on 8, 7, 8, 3 of 8 seeds; the rms resolved from
zero on 5, 4, 1, 0 of 8 (else printed as an upper limit). Run time: 24 s alone with single-threaded BLAS
(``OPENBLAS_NUM_THREADS=1``; MoM 9 s) but 81 s alone with the default BLAS threads at a load of ~3 from
other work (MoM 64 s, 96 s CPU: OpenBLAS threads contending for the 2 cores), and 115-197 s with two runs
in parallel: over a minute whenever the machine is shared, which this study does not control.
"""

import warnings

import numpy as np
from scatterlab.studies._common import jackknife_se, plt, set_verdict, t_factor

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


def dolp_loo(coef):
    """DOLP (s - p)/(s + p) of the realization means and of the means with each realization left
    out.

    Parameters
    ----------
    coef : ndarray (R, 2, ...) -- s (index 0) and p (1) coefficients of R realizations.

    Returns
    -------
    (d, loo): ndarray (...) and ndarray (R, ...) (R = 0 below two realizations).
    """
    R = coef.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        m = coef.mean(0)
        d = (m[0] - m[1]) / (m[0] + m[1])
        if R < 2:
            return d, np.empty((0,) + d.shape)
        loo = (coef.sum(0)[None] - coef) / (R - 1)
        return d, (loo[:, 0] - loo[:, 1]) / (loo[:, 0] + loo[:, 1])


def exact_dolp(coef):
    """DOLP (s - p)/(s + p) of the realization means and its jackknife standard error;
    ``coef`` (R, 2, ...)."""
    d, loo = dolp_loo(coef)
    return d, jackknife_se(loo)


def pooled_error(cells):
    """Mean and root-mean-square of the error exact - model over the points of independent cells,
    with standard errors from the jackknife over each cell's realizations.

    The mean square of a Monte-Carlo estimate carries its variance (E[e^2] = e_true^2 + se^2):
    the jackknife's bias correction, R Q - (R - 1) mean(Q_loo), removes it, so the rms below
    estimates the model's error, not the run's noise. Cells are independent (own surfaces): their
    variances add, weighted by their points.

    Parameters
    ----------
    cells : iterable of (exact, loo, model) -- exact (P,) DOLP of the realization means at a
        cell's P points, loo (R, P) the same with each realization left out (:func:`dolp_loo`),
        model (..., P) one or more model variants. Points where the exact DOLP is not finite are
        left out.

    Returns
    -------
    dict: "mean", "mean_se", "ms", "ms_se", "rms", "rms_se" arrays shaped model.shape[:-1]
    (rms = sqrt(max(ms, 0)), rms_se = ms_se / (2 sqrt(max(ms, ms_se))): no finer than
    sqrt(ms_se) / 2 while ms is within its noise); "ms_diff_se" (..., ...) the standard error of
    ms[v] - ms[w] (paired: the same surfaces); "points"; "realizations" (the fewest of a cell).
    """
    parts, shape = [], ()
    for exact, loo, model in cells:
        model = np.asarray(model, float)
        shape = model.shape[:-1]
        ok = np.isfinite(exact) & np.all(np.isfinite(loo), 0)
        if not ok.any() or loo.shape[0] < 2:
            continue
        R = loo.shape[0]
        e = exact[ok] - model[..., ok]
        el = loo[:, ok][(slice(None),) + (None,) * (model.ndim - 1)] - model[..., ok]
        q, ql = np.mean(e**2, -1), np.mean(el**2, -1)
        ql_diff = ql[..., :, None] - ql[..., None, :] if model.ndim > 1 else ql[..., None, None]
        parts.append(
            (
                ok.sum(),
                R,
                e.mean(-1),
                jackknife_se(el.mean(-1)) ** 2,
                R * q - (R - 1) * ql.mean(0),
                jackknife_se(ql) ** 2,
                jackknife_se(ql_diff) ** 2,
            )
        )
    if not parts:
        nan = np.full(shape, np.nan)
        return {k: nan for k in ("mean", "mean_se", "ms", "ms_se", "rms", "rms_se")} | {
            "ms_diff_se": np.full(shape * 2 or (1, 1), np.nan),
            "points": 0,
            "realizations": 0,
        }
    p = np.array([x[0] for x in parts], float)
    w = p / p.sum()

    def pool(j, var=False):
        return sum((wi**2 if var else wi) * x[j] for wi, x in zip(w, parts))

    ms, ms_se = pool(4), np.sqrt(pool(5, True))
    rms = np.sqrt(np.maximum(ms, 0.0))
    return {
        "mean": pool(2),
        "mean_se": np.sqrt(pool(3, True)),
        "ms": ms,
        "ms_se": ms_se,
        "rms": rms,
        "rms_se": ms_se / (2 * np.sqrt(np.maximum(ms, ms_se))),
        "ms_diff_se": np.sqrt(pool(6, True)),
        "points": int(p.sum()),
        "realizations": min(x[1] for x in parts),
    }


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
    """Per material and cell: exact DOLP (I, S), its jackknife standard error and leave-one-out
    values (R, I, S), the same at the specular geometry (``*_spec``), and the model variants."""
    res = {}
    for name, eta, _ in MATERIALS:
        for cell, r in runs.items():
            coef = r[name]["coef"]
            if half is not None:
                R = coef.shape[0]
                coef = coef[: R // 2] if half == 0 else coef[R // 2 :]
            d, loo = dolp_loo(coef)
            sp = _specular_index(theta_i)
            rows = np.arange(sp.size)
            res[name, cell] = {
                "exact": d,
                "se": jackknife_se(loo),
                "loo": loo,
                "exact_spec": d[rows, sp],
                "se_spec": jackknife_se(loo[:, rows, sp]),
                "loo_spec": loo[:, rows, sp],
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


TOL = 0.01  # the accuracy asked of the model's DOLP in the report's per-point statements


def specular_summary(res, cell_list, theta_i):
    """Per material: the specular DOLP errors exact - model (cells, I) of each model variant with
    their jackknife standard errors; the mean and rms over the (cell, angle) points with standard
    errors (:func:`pooled_error`: the rms with the realizations' noise removed); which points a
    95 % interval shows within ``TOL`` of the model (1-D, shadowed, diffuse) or off by more, the
    rest undetermined at the run's resolution; the rms by variant and which one is smallest beyond
    the noise of the paired difference; and the rms error within the lobe over theta_r.

    Parameters
    ----------
    res : dict -- :func:`compare`'s output for the cells of ``cell_list``.
    cell_list : list of (slope, sigma_h / lambda)
    theta_i : ndarray (I,) [rad]

    Returns
    -------
    dict by material of dicts (see :func:`_report` for their use).
    """
    sp = _specular_index(theta_i)
    rows = np.arange(theta_i.size)
    names = [x[0] for x in VARIANTS] + ["pbrdf_2d"]
    out = {}
    for name, _, _ in MATERIALS:
        e = {
            v: np.array([res[name, c]["exact_spec"] - res[name, c][v][rows, sp] for c in cell_list])
            for v in names
        }
        se = np.array([res[name, c]["se_spec"] for c in cell_list])
        spec = pooled_error(
            (
                res[name, c]["exact_spec"],
                res[name, c]["loo_spec"],
                [res[name, c][v][rows, sp] for v in names],
            )
            for c in cell_list
        )
        t = t_factor(spec["realizations"])
        a = np.abs(e["ts_hyde"])
        within, off = a + t * se <= TOL, a - t * se > TOL
        ms, d_se = spec["ms"], spec["ms_diff_se"]
        same = [[np.allclose(e[v], e[w], equal_nan=True) for w in names] for v in names]
        best = [  # smaller than every variant that differs, beyond the paired difference's noise
            v
            for j, v in enumerate(names)
            if not all(same[j])
            and all(ms[k] - ms[j] > t * d_se[j, k] for k in range(len(names)) if not same[j][k])
        ]
        out[name] = {
            "errors": e,
            "se": se,
            "t": t,
            "realizations": spec["realizations"],
            **{q: float(spec[q][0]) for q in ("mean", "mean_se", "rms", "rms_se", "ms", "ms_se")},
            "points": spec["points"],
            "within": within,
            "off": off,
            "median_se": float(np.nanmedian(se)),
            "by_variant": {
                v: {q: float(spec[q][j]) for q in ("ms", "ms_se", "rms", "rms_se")}
                for j, v in enumerate(names)
            },
            "best_variant": " = ".join(best) or None,
            "all_variants_equal": all(map(all, same)),
            "lobe": _lobe_error(res, name, cell_list),
        }
    return out


def _lobe_error(res, name, cell_list):
    """rms of exact - model (1-D, shadowed, diffuse) over theta_r where the exact power is at least
    5 % of its peak for that incidence (the lobe a sensor sees), :func:`pooled_error`."""
    parts = []
    for c in cell_list:
        r = res[name, c]
        w = r["power"] >= 0.05 * np.max(r["power"], axis=1, keepdims=True)
        parts.append((r["exact"][w], r["loo"][:, w], r["ts_hyde"][w]))
    return pooled_error(parts)


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
    open_ = {k: [] for k in hits}  # an undetermined interval: the whole range, which covers
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
            open_[key].append((~np.isfinite(f.errors[..., :2])).any(-1).ravel())
    out = {k: float(np.mean(np.concatenate(v))) for k, v in hits.items()}
    out.update({f"undetermined_{k}": float(np.mean(np.concatenate(v))) for k, v in open_.items()})
    return out


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

        from scatterlab.plotting import offscreen_plotter

        z = np.linspace(0, 4, 12)
        X, Z = np.meshgrid(x, z, indexing="ij")
        Y = np.broadcast_to(y[:, None], X.shape)
        grid = pv.StructuredGrid(X, Z, Y)
        J = np.abs(sol.current[:, 0]) / np.max(np.abs(sol.current[:, 0]))
        grid["|J| (normalised)"] = np.repeat(J[:, None], z.size, 1).ravel(order="F")
        with offscreen_plotter((900, 420)) as pl:
            pl.add_mesh(grid, scalars="|J| (normalised)", cmap="inferno", smooth_shading=True)
            pl.add_text(
                f"aluminium 1.44 - j16, slope {cell[0]}, sigma_h {cell[1]} wavelength: "
                "|J| for s-pol at 45 deg (tapered wave)",
                font_size=9,
            )
            pl.camera_position = [(-4, -14, 9), (0, 2, 0), (0, 0, 1)]
            pl.screenshot(str(ctx.out / "lobe_3d.png"))
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
                if summary[name]["within"][k, j]:
                    ax.text(t, k, "ok", ha="center", va="center", fontsize=6, color="C2")
                elif summary[name]["off"][k, j]:
                    ax.text(t, k, "x", ha="center", va="center", fontsize=6, color="C0")
        ax.set_yticks(range(len(cell_list)), labels, fontsize=6)
        ax.set(title=name, xlabel=r"$\theta_i = \theta_r$ [deg]")
    axes[0, 0].set_ylabel(r"slope / $\sigma_h/\lambda$")
    fig.colorbar(im, ax=axes[0], label="|DOLP error| (1-D model, shadowed + diffuse)")
    fig.suptitle(
        f"ok: 95 % interval within {TOL}; x: off by more than {TOL} beyond the noise; "
        "blank: undetermined at this run's resolution",
        fontsize=8,
    )
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
        err = {
            n: max(((abs(r[2] - r[4]), r[3]) for r in g["rows"] if r[0] == n), key=lambda x: x[0])
            for n, *_ in MATERIALS
        }
        m["max_abs_dolp_error_80deg"] = {n: e for n, (e, _) in err.items()}
        m["max_abs_dolp_error_80deg_se"] = {n: se for n, (_, se) in err.items()}
        text += (
            " Specular DOLP, exact minus model, largest per material (with that point's s.e.; "
            "the largest of several noisy points is biased up by about their s.e.): "
            + ", ".join(f"{n} {e:.3f} (s.e. {se:.3f})" for n, (e, se) in err.items())
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
        return np.radians(np.arange(10, 61, 10)), 20.0, 12, 24, 4
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
        f"specular DOLP error of the 1-D model vs MoM (exact - model) over {m['glass_points']} "
        "(cell, angle) points, mean / rms with the realizations' noise removed, +- s.e.: "
        + ", ".join(
            f"{n} {_pm(summary[n]['mean'], summary[n]['mean_se'], signed=True)} / "
            f"{rms_short(summary[n], summary[n]['t'])}"
            for n, _, _ in MATERIALS
        )
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
        m[f"{name}_specular_rms_error"] = s["rms"]
        m[f"{name}_specular_rms_error_se"] = s["rms_se"]
        m[f"{name}_specular_mean_error"] = s["mean"]
        m[f"{name}_specular_mean_error_se"] = s["mean_se"]
        m[f"{name}_points_shown_within_{TOL}"] = int(s["within"].sum())
        m[f"{name}_points_shown_off_by_more"] = int(s["off"].sum())
        m[f"{name}_points"] = s["points"]
        m[f"{name}_rms_error_by_model"] = s["by_variant"]
        m[f"{name}_smallest_error_model_beyond_noise"] = s["best_variant"]
        m[f"{name}_median_se"] = s["median_se"]
        m[f"{name}_specular_rms_error_resolved"] = rms_interval(s["ms"], s["ms_se"], s["t"])[2]
        m[f"{name}_lobe_rms_error"] = {
            q: float(s["lobe"][q]) for q in ("ms", "ms_se", "rms", "rms_se")
        }
        m[f"{name}_specular_error_1d"] = s["errors"]["ts_hyde"].tolist()
        m[f"{name}_specular_se"] = s["se"].tolist()
        for noise, b in bias[name].items():
            m[f"{name}_bias_noise{noise}"] = b["bias"].tolist()
            m[f"{name}_width_noise{noise}"] = b["width"].tolist()
        m[f"{name}_coverage95_without_model_error"] = cover[name]["without"]
        m[f"{name}_coverage95_with_model_error"] = cover[name]["with"]
        m[f"{name}_coverage95_with_correlated_model_error"] = cover[name]["with_correlated"]
        m[f"{name}_coverage95_undetermined_share"] = {
            k: cover[name].get(f"undetermined_{k}", 0.0)
            for k in ("without", "with", "with_correlated")
        }
    for c, e in energy.items():
        m[f"pec_{c[0]}_{c[1]}"] = {k: np.asarray(v).tolist() for k, v in e.items()}


def _fmt_cells(cl):
    return ", ".join(f"({s:g}, {h:g})" for s, h in cl) if cl else "none"


def _fmt_points(mask, cell_list, theta_i):
    """'(slope, h) a, b deg; ...' for the (cell, angle) points where ``mask`` (C, I) holds."""
    deg = np.degrees(theta_i).round().astype(int)
    txt = "; ".join(
        f"({c[0]:g}, {c[1]:g}) {', '.join(map(str, deg[row]))} deg"
        for c, row in zip(cell_list, mask)
        if row.any()
    )
    return txt or "none"


def _pm(value, se, signed=False):
    value = 0.0 if abs(value) < 5e-4 else value  # no "-0.000" (NaN stays NaN)
    return f"{value:+.3f} +- {se:.3f}" if signed else f"{value:.3f} +- {se:.3f}"


def rms_interval(ms, ms_se, t):
    """95 % interval of an rms from its noise-corrected mean square: the interval ms +- t ms_se
    through the square root (0 where it reaches below zero).

    Parameters
    ----------
    ms, ms_se : float -- :func:`pooled_error`'s mean square and its standard error.
    t : float -- the coverage factor (:func:`~scatterlab.studies._common.t_factor`).

    Returns
    -------
    (low, high, resolved): floats and whether the mean square is above zero beyond the noise.
    """
    low = np.sqrt(max(ms - t * ms_se, 0.0))
    return float(low), float(np.sqrt(max(ms, 0.0) + t * ms_se)), bool(ms - t * ms_se > 0)


def rms_text(s, t):
    """'0.027 +- 0.003 (95 % interval 0.020-0.034)' for ``s`` holding "ms", "ms_se", "rms",
    "rms_se" as :func:`pooled_error`; where the interval reaches zero, '< 0.082 (95 %)': a
    noise-corrected mean square within its noise (below zero on about half the draws when the noise
    exceeds the error) gives no rms to print, only its upper limit."""
    low, high, resolved = rms_interval(float(s["ms"]), float(s["ms_se"]), t)
    if not resolved:
        return f"< {high:.3f} (95 %)"
    return f"{_pm(float(s['rms']), float(s['rms_se']))} (95 % interval {low:.3f}-{high:.3f})"


def rms_short(s, t):
    """The headline's rms: '0.027 +- 0.003', or '< 0.082' where it is not resolved from zero."""
    low, high, resolved = rms_interval(float(s["ms"]), float(s["ms_se"]), t)
    return _pm(float(s["rms"]), float(s["rms_se"])) if resolved else f"< {high:.3f}"


def _report(ctx, summary, bias, cover, energy, cell_list, theta_i, iron_check, table_path):
    m = ctx.metrics
    deg = np.degrees(theta_i)
    ctx.say(
        f"{len(cell_list)} cell{'' if len(cell_list) == 1 else 's'} (slope, sigma_h/lambda), "
        f"{m['realizations_per_cell_dielectrics']} realization(s) for glass and paint, "
        f"{m['realizations_per_cell_metals_and_pec']} for iron, aluminium and the PEC, of "
        f"{m['surface_length_wavelengths']:.0f} wavelengths each, incidence "
        f"{deg[0]:.0f}-{deg[-1]:.0f} deg; DOLP errors are exact minus model at the specular "
        "geometry unless said otherwise (exact powers are means over a 5 deg aperture, which "
        "averages a few speckles of each realization; the model is taken at its centre), "
        "model = the 1-D facet model with Torrance-Sparrow "
        "shadowing and the Hyde diffuse term. The exact DOLP is a Monte-Carlo mean over the "
        "realizations: every number below carries its standard error (s.e., jackknife over the "
        "realizations), intervals are 95 % (Student t over the realizations), and the rms over "
        "the (cell, angle) points has the realizations' noise removed (jackknife bias correction "
        "of the mean square), so it estimates the model's error, not this run's noise."
        + (
            ""
            if iron_check is None
            else f" The impedance condition changes iron's DOLP by at "
            f"most {iron_check:.3f} against the exact formulation (one surface, 20-60 deg)."
        )
    )
    ctx.say(
        "Resolution of this run (median s.e. of one point's exact DOLP; the smallest model error a "
        "point can show, t x s.e.): "
        + ", ".join(
            f"{n} {s['median_se']:.3f} ({s['t'] * s['median_se']:.3f}, {s['realizations']} "
            "realizations)"
            for n, s in summary.items()
        )
        + f". A point is said to be within {TOL} of the model only if its whole 95 % interval is, "
        f"off by more than {TOL} only if the interval excludes +-{TOL}; the rest is undetermined "
        "at this resolution, not good or bad."
    )
    head = "".join(f" {d:.0f} deg |" for d in deg)
    lines = [f"| material | cell |{head}", "|---|---|" + "---|" * deg.size]
    for name, s in summary.items():
        for c, e, se in zip(cell_list, s["errors"]["ts_hyde"], s["se"]):
            lines.append(
                f"| {name} | {c[0]:g} / {c[1]:g} | "
                + " | ".join(_pm(x, y, signed=True) for x, y in zip(e, se))
                + " |"
            )
    ctx.say("Specular DOLP error exact - model (+- s.e.):\n\n" + "\n".join(lines))
    for name, s in summary.items():
        undetermined = s["points"] - int(s["within"].sum()) - int(s["off"].sum())
        best, lobe, t = s["best_variant"], s["lobe"], s["t"]
        resolved = rms_interval(s["ms"], s["ms_se"], t)[2]
        if s["all_variants_equal"]:
            variants = "the variants give the same DOLP here."
        elif best:
            variants = (
                f"{best} is smaller than every other beyond the 95 % interval of the paired "
                "difference."
            )
        else:
            variants = (
                "no variant's error is smaller than all the others' beyond the noise of the paired "
                "differences."
            )
        ctx.say(
            f"**{name}**: over the {s['points']} (cell, angle) points the specular DOLP error is "
            f"{_pm(s['mean'], s['mean_se'], signed=True)} on average, rms {rms_text(s, t)}"
            + (
                ""
                if resolved
                else ": not resolved from zero by its own interval (the jackknife's s.e. of a mean "
                "square is conservative; the mean error is the sharper statement here"
                + (
                    f", and single points below are shown off by more than {TOL}, so the model does "
                    "differ from the exact DOLP)"
                    if s["off"].any()
                    else ")"
                )
            )
            + f". Shown within {TOL}: "
            f"{_fmt_points(s['within'], cell_list, theta_i)}; shown off by more than {TOL}: "
            f"{_fmt_points(s['off'], cell_list, theta_i)}; undetermined: {undetermined} point(s). "
            "rms error by model: "
            + ", ".join(f"{k} {_pm(v['rms'], v['rms_se'])}" for k, v in s["by_variant"].items())
            + f"; {variants} Over theta_r, within the lobe (exact power >= 5 % of its peak; "
            f"{lobe['points']} points) the rms error is "
            f"{_pm(float(lobe['rms']), float(lobe['rms_se']))}."
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

    def undetermined(c):
        shares = [c.get(f"undetermined_{k}", 0.0) for k in ("without", "with", "with_correlated")]
        if not any(shares):
            return ""
        return (
            " [undetermined, so counted as covering: "
            + " / ".join(f"{100 * x:.0f} %" for x in shares)
            + " of the fits]"
        )

    cov = ", ".join(
        f"{n} {100 * c['without']:.0f} % -> {100 * c['with']:.0f} % "
        f"({coverage_verdict(c['with'], 0.95, units)}; {100 * c['with_correlated']:.0f} % "
        f"correlated, {coverage_verdict(c['with_correlated'], 0.95, units)}){undetermined(c)}"
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
        f"its {units} roughness cells (the independent units). A fit whose n or kappa the data "
        "do not determine (its Laplace error infinite or NaN) has the whole range as its interval, "
        "which covers; the bracket after a material gives how many fits were so, without / with / "
        "correlated, since such a coverage says nothing of the interval's width. The shipped "
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
