"""Tables 1 and 2: Thilak et al.'s Monte-Carlo experiments on copper, their two-step method against
bounded least squares, and the calibration of a Bayesian and a frequentist interval on the same data.

Copper eta = 0.314 - j3.544 (the errata's value), theta_r = 60 deg, 3/5/10/19 measurements over the
stated theta_i ranges (evenly spaced), DOP of smooth facets (Eq. 115 with the errata's A and B). Noise
as the text states it: Gaussian with a *variance* of 0.1 % (low) or 1 % (high) of the largest DOP of
the data set, 500 and 200 trials. The published "+/-" is read as the 95 % half-width of the mean,
1.96 std / sqrt(trials) (it reproduces the published RMSEs with the means).

Besides the tables the study measures why they are not reproduced: (a) the two-step fit from four
different starts (the least-squares minimum does not depend on the start), (b) the other readings of
"variance of 0.1 % of the maximum DOP" (sd = 0.1 % of Pmax; variance = 0.1 % of Pmax^2), (c) which
branch of the (n, kappa) valley the runaway fits take. The text does not give the rest of Thilak's
procedure, so (d) candidate procedures a 2007 paper could have used (``PROCEDURES``: LM from a
fixed start or from the truth, MATLAB's lsqnonlin and fminsearch default tolerances and evaluation
limits, bounded searches including Sec. 7.3's box n in [0, 5], kappa in [0, 25], runaway trials
discarded and redrawn) are each run on every published row and compared number by number (mean and
RMSE of n, kappa, theta_r; Monte-Carlo standard errors; the published RMSE's standard error from its
bias and spread); the closest is named and tabulated against the tables. (e) The Cramer-Rao bounds
of (n, kappa, theta_r) jointly and of (n, kappa) with theta_r known (step 1's situation), for both
noise readings, bound what any unbiased estimator can do.

The posterior is computed exactly on an
(n, kappa) grid (flat prior on the text's box n in [0, 5], kappa in [0, 25], theta_r known, Gaussian
likelihood with the true noise): its 68 % highest-density region, and the 68 % likelihood-ratio
(Wilks, chi^2 with 2 degrees of freedom) confidence region of the same likelihood, are checked for
coverage of the true (n, kappa). Why the old study's sampler (600 steps) reported 0-3.6 %
coverage is measured three ways: the grid posterior's marginal equal-tailed intervals (what the
sampler reported) on the same trials; the library's emcee path (600 steps and, in full mode, its
default adaptive run) against the grid's quantiles; and the coverage with truths drawn from the
prior, where Bayesian intervals must cover 68 %.

How the verdict is reached. The question is whether some candidate reproduces the tables in kind:
the published direction of the bias (n and kappa above copper in every row, as in all 7 published
rows) and its rough size (typical factor ours/published of the n and kappa means and RMSEs,
exp(median |ln ratio|), at most 1.5). Each candidate's factor carries a 95 % interval (a jackknife
over 10 groups of trials, or over single trials when a row has fewer, with Student's t), and a row's
bias counts as shown (above copper, as published) or opposite where its mean's 95 % t interval lies
above or below copper (rows of at least 18 trials; smaller samples miss the runaway trials that carry
the mean). A candidate is "yes" when its interval lies at or below 1.5 and every row's n and kappa are
shown above copper, "no" when a row is opposite or the interval lies above 1.5 with at least 18 trials
per row (with 6 the factor reads 1.16-1.34x high and its interval is centred there, so it cannot rule a
candidate out: a review found the box n <= 20 called "no" at 2.25 in quick mode, 1.35 on 150 trials),
"not determined" otherwise. The closest candidate is picked after the fact (an argmax over 11), so
it is rerun on fresh trials and judged there: "partly" (or "reproduced", every number inside) only
when the fresh run is "yes"; "not reproduced" when every candidate is "no"; otherwise the report
says "not determined at this run size" and the verdict field is "not reproduced" (nothing shown).
The report names every candidate whose factor is within the uncertainty of the closest one.

Measured (29 Nov 2026) from pools of 300 trials per row and procedure: the four closest (boxes
n <= 10 and n <= 20, lsqnonlin's defaults with either start of step 2) score 1.26-1.33 with n and
kappa above copper in every row; with 6 trials per row the factor reads 1.16-1.34x higher and its
interval spans about 1.5x either way, so quick mode cannot decide: in 200 quick-sized draws from the
pools the verdict was "not determined" in all 200 (the old argmax rule gave "partly" on 6 and "not
reproduced" on 7 of 13 quick seeds). With 150 fresh trials the rerun decided "partly" in only 23 of
40 draws (the rest "not determined"), hence 400 fresh trials in full mode (``FRESH_TRIALS``; the
standard error then shrinks by about 0.6). Full mode (29 Nov 2026, seed 20101210, ``--workers 2``, 206 s
at load ~1): verdict "partly". The closest on the ranking trials is the box n <= 10 (1.21, 95 % 1.07-1.37;
four more not told apart from it: lsqnonlin's defaults 1.28 and 1.24, the boxes n <= 5 and n <= 20 1.45 and
1.35); on 400 fresh trials per row it scores 1.33 (95 % 1.26-1.41), n and kappa above copper in 7 of 7 rows,
9 of 28 n and kappa numbers inside twice the combined standard error. Per candidate: yes 3, no 5, not
determined 3 of 11; with "yes" requiring every row's direction shown (re-run serially, 269 s): yes 1, no 5,
not determined 5, the same closest candidate, fresh score and verdict.

Run time: quick (24 trials per case, 6 per candidate procedure and row, 6 fresh) 10 s on the
2-core machine when idle, 27-45 s beside another run; full (500/200 trials, 150 per candidate
procedure and row, 400 fresh for the closest, with the adaptive-sampler check): 206 s with
``--workers 2`` at load ~1 (the fresh rerun 22 s of it); serially 481 s at load 2-3 before the fresh rerun
was added (the candidate procedures take 296 s of it, fminsearch 79 s).

Re-measured 29 Nov 2026 (quick, seeds 1-8, code unchanged): verdict "not reproduced" with "not determined at
this run size (6 trials per row)" on all 8, as the pooled draws above predict. The closest candidate (named
post hoc with the 6-8 others not told apart from it) changes with the seed; its fresh 6-trial score read
1.44-2.17x (95 % intervals 0.72-5.54 at the widest, 1.36-2.03 and 1.41-2.92 on seeds 7 and 8, both above the
full run's 1.33: the small-sample factor reads high, as said above), and 16-31 of 42 numbers lay inside 2
sigma. Run time 12-34 s wall (12-22 s CPU), two runs sharing the 2 cores.
"""

import time
import warnings

import numpy as np
from scatterlab.studies._common import compare, jackknife_se, set_verdict, t_factor

from scatterlab.inversion import ConvergenceWarning, fit_dolp, sample_posterior, thilak_two_step
from scatterlab.inversion.thilak import thilak_crlb, thilak_dop
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "thilak_tables",
    "title": "Thilak et al.'s copper Monte-Carlo tables: two-step vs least squares; interval coverage",
    "reproduces": "Tables 1 and 2 (Sec. 3.1.2.3)",
}

COPPER = (0.314, 3.544)
THETA_R = np.radians(60.0)
CONFIGS = {"3": (3, 55, 65), "5": (5, 50, 70), "10": (10, 35, 80), "19": (19, 35, 80)}
# published (n mean, +/-, RMSE_n, kappa mean, +/-, RMSE_kappa, theta_r mean, +/-, RMSE_theta_r)
PUBLISHED = {
    "low": {
        "3": (2.479, 0.301, 4.052, 7.837, 0.595, 8.254, 60.039, 0.008, 0.098),
        "5": (1.474, 0.254, 3.117, 5.734, 0.482, 5.911, 59.823, 0.120, 1.382),
        "10": (0.421, 0.075, 0.866, 3.768, 0.164, 1.822, 59.695, 0.130, 1.508),
    },
    "high": {
        "3": (7.865, 0.826, 9.610, 15.669, 1.353, 15.545, 59.904, 0.195, 1.409),
        "5": (6.918, 0.964, 9.580, 13.321, 1.361, 13.832, 59.701, 0.339, 2.461),
        "10": (3.319, 0.822, 6.637, 8.031, 1.177, 9.579, 59.815, 0.210, 1.525),
        "19": (1.310, 0.449, 3.378, 5.373, 0.719, 5.486, 59.281, 0.776, 5.629),
    },
}
PUB_KEYS = ["n", "n_pm", "rmse_n", "kappa", "kappa_pm", "rmse_kappa", "theta_r", "theta_r_pm",
            "rmse_theta_r"]  # fmt: skip
LEVELS = {"low": (1e-3, 500), "high": (1e-2, 200)}
NOISE_READINGS = {
    "variance = f Pmax (text)": lambda f, p: np.sqrt(f * p),
    "sd = f Pmax": lambda f, p: f * p,
    "variance = f Pmax^2": lambda f, p: np.sqrt(f) * p,
}
GRIDS = {False: (251, 501), True: (126, 251)}  # (n, kappa) grid points: full, quick


def _stats(x, truth):
    x = x[np.isfinite(x)]
    return {
        "mean": float(x.mean()),
        "ci95": float(1.96 * x.std(ddof=1) / np.sqrt(x.size)),
        "rmse": float(np.sqrt(np.mean((x - truth) ** 2))),
        "median": float(np.median(x)),
        "count": int(x.size),
    }


def grid_coverage(y, ti, sd, quick, truth=COPPER, chunk=64):
    """Coverage of the truth by the exact grid posterior (flat prior on the box) of trials ``y``.

    Parameters
    ----------
    y : array (K, M)
        Measured DOP per trial.
    ti : array (M,) [rad]
    sd : float
        Known noise standard deviation.
    quick : bool
        Selects the grid size (``GRIDS``).
    truth : (n, kappa) or array (K, 2)
        The true index of every trial.
    chunk : int
        Trials per block (memory).

    Returns
    -------
    dict
        ``hpd`` (K,) the truth inside the 68 % highest-density region; ``lr`` (K,) inside the 68 %
        likelihood-ratio region (chi^2_2 <= 2.30); ``marginal`` (K, 2) n and kappa inside their
        marginal equal-tailed 68 % intervals (what ``Posterior.interval(0.68)`` reports); ``q``
        (K, 2, 3) the marginal 16/50/84 % quantiles of n and kappa.
    """
    grid_n, grid_k = (np.linspace(0.0, hi, k) for hi, k in zip((5.0, 25.0), GRIDS[quick]))
    beta = (ti + THETA_R) / 2
    g = thilak_dop(grid_n[:, None, None], grid_k[None, :, None], beta).reshape(-1, ti.size)
    truth = np.broadcast_to(np.asarray(truth, float), (len(y), 2))
    parts = [
        _coverage_chunk(y[i : i + chunk], truth[i : i + chunk], g, beta, sd, grid_n, grid_k)
        for i in range(0, len(y), chunk)
    ]
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}


def _coverage_chunk(y, truth, g, beta, sd, grid_n, grid_k):
    """:func:`grid_coverage` for one block of trials ``y`` (K, M) with truths ``truth`` (K, 2)."""
    chi2 = ((g**2).sum(1)[:, None] - 2 * g @ y.T + (y**2).sum(1)[None, :]) / sd**2  # (G, K)
    model_true = thilak_dop(truth[:, :1], truth[:, 1:], beta)  # (K, M)
    chi2_true = ((model_true - y) ** 2).sum(1) / sd**2
    chi2_min = np.minimum(chi2.min(0), chi2_true)
    lr = chi2_true - chi2_min <= 2.30
    w = np.exp(-(chi2 - chi2_min) / 2)
    total = w.sum(0)
    w /= total
    ws = -np.sort(-w, axis=0)
    thresh = ws[np.argmax(np.cumsum(ws, axis=0) >= 0.68, axis=0), np.arange(y.shape[0])]
    hpd = np.exp(-(chi2_true - chi2_min) / 2) / total >= thresh
    wn = w.reshape(grid_n.size, grid_k.size, -1)
    q = np.array(
        [
            [
                [np.interp(p, np.cumsum(m[:, k]), grid) for p in (0.16, 0.5, 0.84)]
                for k in range(len(y))
            ]
            for grid, m in ((grid_n, wn.sum(1)), (grid_k, wn.sum(0)))
        ]
    ).transpose(1, 0, 2)  # (K, 2, 3)
    marginal = (q[:, :, 0] <= truth) & (truth <= q[:, :, 2])
    return {"hpd": hpd, "lr": lr, "marginal": marginal, "q": q}


def prior_calibration(quick, trials, rng):
    """Coverage when the truth is drawn from the prior (flat on the box) instead of fixed at copper.

    Bayesian intervals are calibrated on average over truths drawn from the prior; this measures
    it on the low-noise 3- and 10-measurement geometries.

    Parameters
    ----------
    quick : bool
    trials : int
        Truths drawn per geometry.
    rng : numpy.random.Generator

    Returns
    -------
    dict
        Per geometry: ``hpd``, ``marginal_n``, ``marginal_kappa`` coverage fractions.
    """
    out = {}
    for key in ("3", "10"):
        ti, sd, _ = _simulate(key, "low", 1, rng)
        truth = np.column_stack([rng.uniform(0, 5, trials), rng.uniform(0, 25, trials)])
        clean = thilak_dop(truth[:, :1], truth[:, 1:], (ti + THETA_R) / 2)
        y = clean + sd * rng.standard_normal(clean.shape)
        c = grid_coverage(y, ti, sd, quick, truth)
        out[f"low_{key}"] = {
            "hpd": float(c["hpd"].mean()),
            "marginal_n": float(c["marginal"][:, 0].mean()),
            "marginal_kappa": float(c["marginal"][:, 1].mean()),
        }
    return out


def _mcmc_check(ctx, trials, adaptive):
    """The library's emcee path against the exact grid posterior, on the same trials.

    Parameters
    ----------
    ctx : StudyContext
    trials : int
        Trials per case (low noise, 3 and 10 measurements).
    adaptive : bool
        Also run the library's default (extend until converged, ``n_steps=None``).

    Returns
    -------
    dict
        Per run kind (``"600 steps"`` as the old study ran it, ``"adaptive"``): ``max_dq_n``,
        ``max_dq_kappa`` (largest |sampler - grid| of the marginal 16/50/84 % quantiles),
        ``unconverged`` (fraction of chains the library flags), ``same_coverage`` (fraction of
        intervals that agree with the grid's on containing copper), ``seconds`` per chain.
    """
    kinds = {"600 steps": 600} | ({"adaptive": None} if adaptive else {})
    rec = {k: {"dq": [], "unconverged": [], "same": [], "seconds": []} for k in kinds}
    for key in ("3", "10"):
        ti, sd, y = _simulate(key, "low", trials, ctx.rng)
        grid = grid_coverage(y, ti, sd, ctx.quick)
        for kind, steps in kinds.items():
            r = rec[kind]
            for row, qg, cg in zip(y, grid["q"], grid["marginal"]):
                t0 = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", ConvergenceWarning)  # counted below
                    p = sample_posterior(row, ti, np.full(ti.size, THETA_R), sd, ctx.rng,
                                         sigma=0.3, diffuse="none", n_steps=steps)  # fmt: skip
                r["seconds"].append(time.perf_counter() - t0)
                qm = p.quantiles([0.16, 0.5, 0.84])[:, :2].T  # (2, 3)
                r["dq"].append(np.abs(qm - qg).max(1))
                r["unconverged"].append(not p.converged)
                r["same"].append(((qm[:, 0] <= COPPER) & (np.asarray(COPPER) <= qm[:, 2])) == cg)
    return {
        kind: {
            "max_dq_n": float(np.max(r["dq"], 0)[0]),
            "max_dq_kappa": float(np.max(r["dq"], 0)[1]),
            "median_dq_n": float(np.median(r["dq"], 0)[0]),
            "median_dq_kappa": float(np.median(r["dq"], 0)[1]),
            "unconverged": float(np.mean(r["unconverged"])),
            "same_coverage": float(np.mean(r["same"])),
            "seconds": float(np.mean(r["seconds"])),
            "chains": len(r["dq"]),
        }
        for kind, r in rec.items()
    }


def _simulate(key, level, trials, rng, reading="variance = f Pmax (text)"):
    m, a, b = CONFIGS[key]
    ti = np.radians(np.linspace(a, b, m))
    clean = thilak_dop(*COPPER, (ti + THETA_R) / 2)
    sd = float(NOISE_READINGS[reading](LEVELS[level][0], clean.max()))
    return ti, sd, clean + sd * rng.standard_normal((trials, m))


def _case(ctx, level, key, trials):
    """One published row: our two-step estimator, least squares and the grid posterior on the same
    trials. Returns the two-step estimates (K, 3) [n, kappa, theta_r (deg)] and the row's metrics."""
    ti, sd, y = _simulate(key, level, trials, ctx.rng)
    m = ti.size
    with ctx.step("two_step"):
        th = thilak_two_step(y, ti, THETA_R, ctx.rng)
    with ctx.step("least_squares"):
        ls = fit_dolp(y, ti, np.full(m, THETA_R), sigma=0.3, diffuse="none", noise=sd)
    with ctx.step("grid_posterior"):
        cov = grid_coverage(y, ti, sd, ctx.quick)
    med = cov["q"][:, :, 1]
    n_ok = th.n[th.ok]
    est = np.column_stack([th.n, th.kappa, np.degrees(th.theta_r)])
    return est, {
        "two_step_mc": row_stats(est),
        "noise_sd": sd,
        "trials": trials,
        "thilak": {
            "n": _stats(th.n, COPPER[0]),
            "kappa": _stats(th.kappa, COPPER[1]),
            "theta_r_deg": _stats(np.degrees(th.theta_r), 60.0),
            "restarts": int(th.restarts.sum()),
            "runaway_fraction_n_gt_10": float(np.mean(n_ok > 10)),
            "runaway_branch_kappa_median": float(np.median(th.kappa[th.ok][n_ok > 10]))
            if np.any(n_ok > 10)
            else float("nan"),
        },
        "least_squares": {"n": _stats(ls.n, COPPER[0]), "kappa": _stats(ls.kappa, COPPER[1])},
        "posterior_median": {
            "n": _stats(med[:, 0], COPPER[0]),
            "kappa": _stats(med[:, 1], COPPER[1]),
        },
        "coverage68_bayes_hpd": float(cov["hpd"].mean()),
        "coverage68_likelihood_ratio": float(cov["lr"].mean()),
        "coverage68_marginal_equal_tailed": cov["marginal"].mean(0).tolist(),  # n, kappa
        "published": dict(zip(PUB_KEYS, PUBLISHED[level][key])),
    }


def _diagnostics(ctx, trials):
    """Start independence and the noise readings, on the low-noise 3- and 10-measurement cases."""
    out = {"start_spread": {}, "readings": {}}
    for key in ("3", "10"):
        ti, sd, y = _simulate(key, "low", trials, np.random.default_rng(ctx.seed))
        means = [
            float(np.nanmedian(thilak_two_step(y, ti, THETA_R, ctx.rng, start=s).n))
            for s in ((1.0, 1.0), COPPER, (1.0, 5.0), (3.0, 10.0))
        ]
        out["start_spread"][key] = float(np.ptp(means))
        for name in NOISE_READINGS:
            ti, sd, y = _simulate(key, "low", trials, np.random.default_rng(ctx.seed), name)
            th = thilak_two_step(y, ti, THETA_R, ctx.rng)
            out["readings"][f"{name}, M={key}"] = {
                "noise_sd": sd,
                "n_mean": float(np.nanmean(th.n)),
                "rmse_n": _stats(th.n, COPPER[0])["rmse"],
                "kappa_mean": float(np.nanmean(th.kappa)),
                "rmse_kappa": _stats(th.kappa, COPPER[1])["rmse"],
            }
    return out


def _calibration_text(hpd, lrc, trials):
    """Whether the coverages are consistent with 68 % (binomial, 2 standard errors, two-sided)."""
    se = np.sqrt(0.68 * 0.32 / trials)
    parts = []
    for name, cov in (("The posterior's HPD region", hpd), ("the likelihood-ratio region", lrc)):
        low = [c for c in cov if c < 0.68 - 2 * se]
        high = [c for c in cov if c > 0.68 + 2 * se]
        parts.append(
            f"{name} is consistent with 68 % in {len(cov) - len(low) - len(high)} of {len(cov)} "
            f"cases (binomial 2 SE = {2 * se:.0%} for {trials} trials)"
            + (f", under-covers in {len(low)}" if low else "")
            + (f", over-covers in {len(high)}" if high else "")
        )
    return (
        "; ".join(parts) + ". Where a fixed truth sits in a weakly identified valley, Bayesian "
        "coverage is guaranteed only on average over the prior, so the likelihood-ratio "
        "(frequentist) region is shown beside it. "
    )


def _median_vs_ls_text(rows):
    """Whether posterior medians beat least squares as point estimates, counted from the RMSEs."""
    parts = []
    for par in ("n", "kappa"):
        better = sum(
            r["posterior_median"][par]["rmse"] < r["least_squares"][par]["rmse"] for _, _, r in rows
        )
        parts.append(f"{par} in {better} of {len(rows)}")
    return (
        "The posterior median has a smaller RMSE than least squares for "
        + " and for ".join(parts)
        + " cases (table). "
    )


def _table(rows):
    lines = [
        "| noise | M | published n (RMSE) | two-step n (RMSE) | LS n (RMSE) | posterior median n "
        "(RMSE) | published kappa (RMSE) | two-step kappa (RMSE) | LS kappa (RMSE) | "
        "posterior median kappa (RMSE) | 68 % coverage: HPD / LR |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def cell(s):
        return f"{s['mean']:.3f} +/- {s['ci95']:.3f} ({s['rmse']:.3f})"

    for level, key, r in rows:
        p = r["published"]
        lines.append(
            f"| {level} | {key} | {p['n']:.3f} +/- {p['n_pm']:.3f} ({p['rmse_n']:.3f}) | "
            f"{cell(r['thilak']['n'])} | {cell(r['least_squares']['n'])} | "
            f"{cell(r['posterior_median']['n'])} | "
            f"{p['kappa']:.3f} +/- {p['kappa_pm']:.3f} ({p['rmse_kappa']:.3f}) | "
            f"{cell(r['thilak']['kappa'])} | {cell(r['least_squares']['kappa'])} | "
            f"{cell(r['posterior_median']['kappa'])} | "
            f"{r['coverage68_bayes_hpd']:.0%} / {r['coverage68_likelihood_ratio']:.0%} |"
        )
    return "\n".join(lines)


def _figure(ctx, rows, best):
    """RMSE of n and kappa against the number of measurements: published, ours, the closest
    candidate procedure ``best`` (its name and ``{(level, key): run_procedure(...)}``)."""
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 2, figsize=(11, 4))
    for ax, par in zip(axes, ("n", "kappa")):
        for level, mk in (("low", "o"), ("high", "s")):
            sel = [(int(k), r) for lv, k, r in rows if lv == level]
            x = [s[0] for s in sel]
            for src, style, label in (
                ("published", ("k", "--"), "published"),
                ("thilak", ("C0", "-"), "two-step (ours)"),
                ("least_squares", ("C1", "-"), "bounded LS"),
                ("posterior_median", ("C2", ":"), "posterior median"),
                ("best", ("C3", "-."), best[0]),
            ):
                yv = [
                    r["published"][f"rmse_{par}"] if src == "published"
                    else best[1][(level, str(m))][par]["rmse"] if src == "best"
                    else r[src][par]["rmse"]
                    for m, r in sel
                ]  # fmt: skip
                ax.semilogy(
                    x, yv, color=style[0], ls=style[1], marker=mk, label=f"{label} ({level})"
                )
        ax.set(xlabel="number of measurements", ylabel=f"RMSE of {par}", title=par)
    axes[0].legend(fontsize=6)
    ctx.save_figure(fig, "thilak_rmse")


def run(ctx):
    rows, case_est = [], {}
    for level, (_, trials) in LEVELS.items():
        trials = 24 if ctx.quick else trials
        for key in PUBLISHED[level]:
            case_est[(level, key)], res = _case(ctx, level, key, trials)
            ctx.metrics[f"{level}_{key}"] = res
            rows.append((level, key, res))
    with ctx.step("diagnostics"):
        diag = _diagnostics(ctx, 6 if ctx.quick else 200)
    ctx.metrics["diagnostics"] = diag
    ctx.say(_table(rows))

    cmp = []
    for level, key, r in rows:
        p, t = r["published"], r["thilak"]
        for par, pub, pm in (("n", p["n"], p["n_pm"]), ("kappa", p["kappa"], p["kappa_pm"])):
            cmp.append(
                compare(
                    f"{level} noise, M = {key}, mean {par}",
                    pub,
                    t[par]["mean"],
                    pm / 1.96,
                    t[par]["ci95"] / 1.96,
                )  # fmt: skip
            )
    inside = sum(c["inside"] for c in cmp)
    ctx.metrics["comparisons"] = cmp
    ratio_n = [r["thilak"]["n"]["mean"] / r["published"]["n"] for _, _, r in rows]
    kbias = [
        (np.sign(r["thilak"]["kappa"]["median"] - COPPER[1]),
         np.sign(r["published"]["kappa"] - COPPER[1]))
        for _, _, r in rows
    ]  # fmt: skip
    run_frac = [r["thilak"]["runaway_fraction_n_gt_10"] for _, _, r in rows]
    ctx.say(
        f"Two-step method against the tables: {inside} of {len(cmp)} mean values (n and kappa, 7 "
        "cases) lie inside twice the combined standard error of the two means. Our mean n is "
        f"{min(ratio_n):.2f}-{max(ratio_n):.2f} x the published one; {min(run_frac):.0%}-"
        f"{max(run_frac):.0%} of the trials run off to n > 10. The published means run off along "
        "the metal branch of the (n, kappa) valley (n and kappa both above the truth); ours along "
        "the dielectric branch (median kappa of the runaway trials "
        + ", ".join(_median_or_none(r["thilak"]["runaway_branch_kappa_median"]) for _, _, r in rows)
        + f"), so our median kappa is below the truth in {sum(a < 0 for a, _ in kbias)} of 7 "
        "cases where the text's mean is above it in all 7. "
        + _two_step_verdict_text(inside, len(cmp))
    )
    spread = diag["start_spread"]
    rd = diag["readings"]
    ctx.say(
        "Why, by measurement: (a) the estimate does not depend on the start: four starts ((1, 1), "
        "the truth, (1, 5), (3, 10)) give medians of n that differ by at most "
        f"{max(spread.values()):.2g}, so the runaway is where the least-squares minimum of Eq. 116 "
        "lies for these data, not an optimiser failure; (b) the noise reading: "
        + "; ".join(
            f"{name}: sd {v['noise_sd']:.2g}, mean n {v['n_mean']:.3g} (RMSE {v['rmse_n']:.3g}), "
            f"mean kappa {v['kappa_mean']:.3g}"
            for name, v in rd.items()
        )
        + ". Published low noise: M = 3 n 2.479 (4.052), kappa 7.837; M = 10 n 0.421 (0.866), "
        "kappa 3.768. The forward model (Eq. 115) is tested equal to the Fresnel DOP, so the "
        "data are right; the text does not give the rest of Thilak's procedure (start, bounds, "
        "stopping rule, which restarts count): the candidates are measured below."
    )
    with ctx.step("crlb"):
        bounds = crlb_rows()
    ctx.metrics["crlb"] = bounds
    table, text = _crlb_text(bounds)
    ctx.say(table)
    ctx.say(text)
    best, scored, fresh, verdict, state = _procedures(ctx, rows, case_est)
    _figure(ctx, rows, (best, scored[best]["results"]))
    hpd = [r["coverage68_bayes_hpd"] for _, _, r in rows]
    lrc = [r["coverage68_likelihood_ratio"] for _, _, r in rows]
    ctx.metrics["coverage68_bayes_hpd_range"] = [min(hpd), max(hpd)]
    ctx.metrics["coverage68_likelihood_ratio_range"] = [min(lrc), max(lrc)]
    ctx.say(
        "Interval calibration on the same trials (exact grid posterior, flat prior on the text's "
        "box n in [0, 5], kappa in [0, 25]): the 68 % highest-density region contains the true "
        f"(n, kappa) in {min(hpd):.0%}-{max(hpd):.0%} of the trials, the 68 % likelihood-ratio "
        f"confidence region (chi^2_2 <= 2.30) in {min(lrc):.0%}-{max(lrc):.0%}. "
        + _calibration_text(hpd, lrc, rows[0][2]["trials"])
        + _median_vs_ls_text(rows)
    )
    _explain_old_coverage(ctx, rows)
    ctx.say(_verdict_note(verdict, state, best, scored, fresh, ctx.quick, inside == len(cmp)))
    fi = fresh["interval"]
    set_verdict(
        ctx,
        verdict,
        f"in kind (n, kappa biased as published, typically within {KIND_FACTOR:g}x): "
        + {"shown": "shown", "ruled out": "ruled out"}.get(
            state, f"not determined at this run size ({PROC_TRIALS[ctx.quick]} trials per row)"
        )
        + f"; closest of {len(PROCEDURES)} procedures, picked post hoc ({best}, "
        f"{len(not_told_apart(scored, best))} more not told apart), on {FRESH_TRIALS[ctx.quick]} "
        f"fresh trials per row: n, kappa typically {fresh['factor']:.2f} x published (95 % "
        f"{fi['low']:.2f}-{fi['high']:.2f}), {fresh['inside_nk'] + fresh['inside_theta']}/"
        f"{fresh['total_nk'] + fresh['total_theta']} numbers inside 2 sigma (unconstrained LM: mean n "
        f"{min(ratio_n):.1f}-{max(ratio_n):.1f} x published); 68 % coverage HPD "
        f"{min(hpd):.0%}-{max(hpd):.0%}, LR {min(lrc):.0%}-{max(lrc):.0%}",
    )


def _median_or_none(value):
    """A runaway median for the report: "none" where no trial ran away (the median of nothing is NaN)."""
    return "none" if not np.isfinite(value) else f"{value:.2f}"


def _two_step_verdict_text(inside, total):
    """Whether our own two-step estimator reproduces the tables' means, from the comparison."""
    if inside == total:
        return f"Our two-step estimator reproduces the tables: all {total} mean values inside."
    return (
        f"Our two-step estimator does not reproduce the tables ({inside} of {total} mean values "
        "inside)."
    )


def _verdict_note(verdict, state, best, scored, fresh, quick, two_step_reproduces):
    """What the verdict rests on. The closest procedure is selected after the fact, so a "partly" or
    "reproduced" rests on its rerun on fresh trials, a "not reproduced" on every candidate ruled
    out; anything else is not determined at this run size and shows nothing."""
    own = "reproduces" if two_step_reproduces else "does not reproduce"
    n, trials = len(scored), PROC_TRIALS[quick]
    fi = fresh["interval"]
    on_fresh = (
        f"'{best}', picked after the fact as the closest of {n} candidates on {trials} trials per "
        f"row, scores {fresh['factor']:.2f} (95 % {fi['low']:.2f}-{fi['high']:.2f}) on "
        f"{FRESH_TRIALS[quick]} fresh trials per row"
    )
    if state == "shown":
        text = (
            f'Verdict "{verdict}": {on_fresh}, an interval below {KIND_FACTOR:g} with no row biased '
            "opposite to the published: "
            + ("the tables are reproduced number for number." if verdict == "reproduced"
               else "the tables are reproduced in kind, not number for number.")
        )  # fmt: skip
    elif state == "ruled out":
        text = (
            f'Verdict "not reproduced": every one of the {n} candidates has its factor\'s 95 % '
            f"interval above {KIND_FACTOR:g} or a row's bias determined opposite to the published, "
            "so none reproduces the tables, not even in kind."
        )
    else:
        text = (
            f'Verdict "not reproduced" because nothing is shown, not because the tables are ruled '
            f"out: whether a candidate reproduces them in kind is not determined at this run size. "
            f"{on_fresh[0].upper() + on_fresh[1:]}"
            + (
                f", an interval that contains {KIND_FACTOR:g}."
                if fresh["in_kind"] == "not determined"
                else " and is ruled out there, but not every other candidate is (table above)."
            )
        )
    return text + f" Our two-step estimator {own} the tables."


def _explain_old_coverage(ctx, rows):
    """Why the old 600-step sampler's 68 % intervals covered copper in 0-3.6 % of the trials."""
    marg = np.array([r["coverage68_marginal_equal_tailed"] for _, _, r in rows])  # (cases, 2)
    trials = "/".join(str(t) for t in dict.fromkeys(r["trials"] for _, _, r in rows))  # low/high
    n_prior = 48 if ctx.quick else 400
    with ctx.step("prior_calibration"):
        prior = prior_calibration(ctx.quick, n_prior, ctx.rng)
    with ctx.step("mcmc_check"):
        mc = _mcmc_check(ctx, 1 if ctx.quick else 2, adaptive=not ctx.quick)
    ctx.metrics["coverage68_marginal_equal_tailed_range"] = [float(marg.min()), float(marg.max())]
    ctx.metrics["prior_calibration"] = prior
    ctx.metrics["mcmc_check"] = mc
    se = np.sqrt(0.68 * 0.32 / n_prior)
    ctx.say(
        "Why the old study's sampler (sample_posteriors, 600 steps) reported 68 % intervals "
        "containing copper in 0-3.6 % of the trials, by measurement. (1) It reported the marginal "
        "equal-tailed intervals of n and kappa (Posterior.interval), not a joint region; the exact "
        "grid posterior's marginal equal-tailed 68 % intervals cover copper in "
        f"{marg.min():.0%}-{marg.max():.0%} of the same {trials} trials per case (n: "
        + ", ".join(f"{m[0]:.0%}" for m in marg)
        + "; kappa: "
        + ", ".join(f"{m[1]:.0%}" for m in marg)
        + ", cases in table order), so the low number is mainly a property of the posterior, "
        "not of the sampler. The cause is the shape of the problem: with few measurements the "
        "likelihood is a long valley, most of the flat prior's area along it lies far from "
        "copper, and copper sits at the valley's end next to the bound n = 0, so central "
        "intervals of the marginals exclude it. (2) The 600-step chains were also short: "
        + _mcmc_text(mc, ctx.quick)
        + " (3) Bayesian intervals are calibrated only on average over truths drawn from the "
        "prior: drawing (n, kappa) uniformly on the box (same geometries and noise), the grid "
        "posterior's marginal intervals cover "
        + "; ".join(
            f"{k}: n {v['marginal_n']:.0%}, kappa {v['marginal_kappa']:.0%}, HPD {v['hpd']:.0%}"
            for k, v in prior.items()
        )
        + f" (68 % +/- {2 * se:.0%}, binomial 2 SE, {n_prior} truths). For a fixed truth at the "
        "valley's end, as copper is here, the likelihood-ratio region above is the calibrated "
        "statement; the marginal credible intervals are not confidence intervals."
    )


def _mcmc_text(mc, quick):
    """One sentence per run kind of :func:`_mcmc_check`."""
    parts = []
    for kind, v in mc.items():
        parts.append(
            f"{kind}: the library flags {v['unconverged']:.0%} of {v['chains']} chains as not "
            f"converged; their 16/50/84 % quantiles differ from the exact grid's by a median "
            f"{v['median_dq_n']:.2f} (max {v['max_dq_n']:.2f}) in n and {v['median_dq_kappa']:.2f} "
            f"(max {v['max_dq_kappa']:.2f}) in kappa, and agree with the grid on whether copper is "
            f"inside in {v['same_coverage']:.0%} of the intervals ({v['seconds']:.0f} s a chain)"
        )
    return (
        "; ".join(parts)
        + ". The old study silenced the ConvergenceWarning. Where the maximum is large (above "
        "~1 in n), a chain stayed on one branch of the valley (walkers start at the "
        "least-squares minima)"
        + (
            "; quick mode runs only the 600-step chains, full mode also the library's default "
            "adaptive run."
            if quick
            else "."
        )
    )


RANDOM_STEP2 = "lsqnonlin defaults, step 2 from a random theta_r"
FIXED_STEP2 = "lsqnonlin defaults (TRF, tol 1e-6, 200 evaluations)"  # same, step 2 from step 1's
# Candidate procedures for the unpublished part of Thilak's estimator: name -> keywords of
# thilak_two_step, plus "redraw": (n_max, kappa_max), trials beyond which are discarded and
# replaced by a fresh noise draw (a reading of "ignored and the algorithm restarted").
PROCEDURES = {
    "LM from (1, 1), random restart if unphysical (ours)": {},
    "LM from the truth": {"start": COPPER},
    FIXED_STEP2: {"solver": "trf", "tol": 1e-6, "max_nfev": 200},
    RANDOM_STEP2: {
        "solver": "trf", "tol": 1e-6, "max_nfev": 200, "theta_r_start": "random"},
    "fminsearch defaults (Nelder-Mead, tol 1e-4, 400 evaluations)": {"solver": "nelder-mead"},
    "fminsearch from the truth": {"solver": "nelder-mead", "start": COPPER},
    "bounded n in [0, 5], kappa in [0, 25] (Sec. 7.3's box)": {
        "solver": "trf", "bounds": ((0, 5), (0, 25))},
    "bounded as Sec. 7.3, lsqnonlin tolerances (1e-6, 200 evaluations)": {
        "solver": "trf", "bounds": ((0, 5), (0, 25)), "tol": 1e-6, "max_nfev": 200},
    "bounded n in [0, 10], kappa in [0, 25]": {"solver": "trf", "bounds": ((0, 10), (0, 25))},
    "bounded n in [0, 20], kappa in [0, 25]": {"solver": "trf", "bounds": ((0, 20), (0, 25))},
    "LM, trials with n > 10 or kappa > 25 discarded and redrawn": {"redraw": (10.0, 25.0)},
}  # fmt: skip
PROC_TRIALS = {True: 6, False: 150}  # trials per published row and procedure: quick, full
# trials per row of the closest procedure's rerun on fresh trials (it is judged on these, not on the
# trials it was picked on): quick, full. Full mode needs ~400 to put the interval of a factor of
# 1.3 below KIND_FACTOR (jackknife standard error of ln factor 0.04-0.07 measured at 150, so about
# 0.03-0.04 at 400)
FRESH_TRIALS = {True: 6, False: 400}
JACKKNIFE_GROUPS = 10
KIND_FACTOR = 1.5  # "in kind": n and kappa means and RMSEs typically within this factor
# The fewest trials of a row whose mean's t interval decides the direction of its bias. The estimates
# are skewed (30-40 % runaway trials carry the mean), and a small sample that misses the runaways
# has a tight interval below copper: drawn from 300-trial pools of the eight procedures whose mean
# is above copper in every row, some row came out determined below in 12-19 % of 400 draws of 6
# trials, 1-5 % of 12, 0-2 % of 18 and 0-1 % of 24.
MIN_SIGN_TRIALS = 18
PARAMS = (("n", COPPER[0]), ("kappa", COPPER[1]), ("theta_r", 60.0))  # theta_r in deg


def mc_stats(x, truth):
    """Mean and RMSE of the finite estimates ``x`` with their Monte-Carlo standard errors.

    Parameters
    ----------
    x : array (K,)
        Estimates (NaN for failed trials, left out).
    truth : float

    Returns
    -------
    dict
        ``mean``, ``se_mean`` (sd / sqrt(K)), ``rmse``, ``se_rmse`` (delta method:
        sd(e^2) / (2 RMSE sqrt(K)), e = x - truth), ``count``.
    """
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    k = x.size
    e2 = (x - truth) ** 2
    rmse = float(np.sqrt(e2.mean()))
    return {
        "mean": float(x.mean()),
        "se_mean": float(x.std(ddof=1) / np.sqrt(k)),
        "rmse": rmse,
        "se_rmse": float(e2.std(ddof=1) / (2 * rmse * np.sqrt(k))) if rmse > 0 else 0.0,
        "count": int(k),
    }


def published_se(level, key):
    """Standard errors of the published means and RMSEs of (n, kappa, theta_r).

    The published "+/-" is 1.96 sd / sqrt(trials), so the mean's standard error is it / 1.96.
    The RMSE's is the delta-method value for Gaussian estimates with the published bias b and
    sd s: sqrt(2 s^4 + 4 s^2 b^2) / (2 RMSE sqrt(trials)); the real estimates are skewed, so this
    is a lower bound on it.

    Returns
    -------
    dict
        Per parameter: ``mean``, ``se_mean``, ``rmse``, ``se_rmse``.
    """
    p = dict(zip(PUB_KEYS, PUBLISHED[level][key]))
    trials = LEVELS[level][1]
    out = {}
    for par, truth in PARAMS:
        mean, pm, rmse = p[par], p[f"{par}_pm"], p[f"rmse_{par}"]
        s = pm / 1.96 * np.sqrt(trials)
        b = mean - truth
        se_r = np.sqrt(2 * s**4 + 4 * s**2 * b**2) / (2 * rmse * np.sqrt(trials))
        out[par] = {"mean": mean, "se_mean": pm / 1.96, "rmse": rmse, "se_rmse": float(se_r)}
    return out


def procedure_estimates(level, key, opts, trials, rng, reading="variance = f Pmax (text)"):
    """One candidate procedure on one published row: its estimates, trial by trial.

    Parameters
    ----------
    level, key : str
        Noise level and configuration (``PUBLISHED``); noise as the text states it.
    opts : dict
        An entry of ``PROCEDURES``.
    trials : int
    rng : numpy.random.Generator
    reading : str
        The reading of the noise definition (``NOISE_READINGS``).

    Returns
    -------
    est : array (trials, 3)
        n, kappa, theta_r [deg] of every trial (a runaway trial of a "redraw" procedure replaced).
    redrawn : int
        Trials replaced by a fresh draw.
    """
    opts = dict(opts)
    redraw = opts.pop("redraw", None)
    ti, _, y = _simulate(key, level, trials, rng, reading)

    def estimate(data):
        fit = thilak_two_step(data, ti, THETA_R, rng, **opts)
        return np.column_stack([fit.n, fit.kappa, np.degrees(fit.theta_r)])

    est = estimate(y)
    redrawn = 0
    for _ in range(50 if redraw else 0):
        bad = ~((est[:, 0] <= redraw[0]) & (est[:, 1] <= redraw[1]))
        if not bad.any():
            break
        redrawn += int(bad.sum())
        est[bad] = estimate(_simulate(key, level, int(bad.sum()), rng, reading)[2])
    return est, redrawn


def row_stats(est):
    """:func:`mc_stats` of n, kappa and theta_r [deg] from estimates ``est`` (K, 3)."""
    return {par: mc_stats(est[:, j], truth) for j, (par, truth) in enumerate(PARAMS)}


def run_procedure(level, key, opts, trials, rng, reading="variance = f Pmax (text)"):
    """One candidate procedure on one published row: statistics of (n, kappa, theta_r [deg]).

    Parameters
    ----------
    level, key, opts, trials, rng, reading
        As :func:`procedure_estimates`.

    Returns
    -------
    dict
        Per parameter the :func:`mc_stats`; ``redrawn``: trials replaced by a fresh draw.
    """
    est, redrawn = procedure_estimates(level, key, opts, trials, rng, reading)
    return row_stats(est) | {"redrawn": redrawn}


def typical_factor(results):
    """The typical ratio ours/published of the n and kappa means and RMSEs over the published rows,
    exp(median |ln ratio|) (1 for a procedure equal to the tables).

    Parameters
    ----------
    results : dict
        ``{(level, key): row_stats(...)}`` (at least ``mean`` and ``rmse`` of n and kappa).

    Returns
    -------
    float
    """
    logs = [
        abs(np.log(res[par][stat] / PUBLISHED[level][key][PUB_KEYS.index(name)]))
        for (level, key), res in results.items()
        for par in ("n", "kappa")
        for stat, name in (("mean", par), ("rmse", f"rmse_{par}"))
    ]
    return float(np.exp(np.median(logs)))


def factor_interval(estimates, groups=None):
    """The typical factor of a procedure with its Monte-Carlo uncertainty.

    The standard error of ln(factor) is a delete-a-group jackknife over the trials: the trials of
    every row are split into ``groups`` consecutive groups and group g is left out of every row at
    once (the rows are independent draws, so this is a valid grouping); the 95 % interval is
    exp(ln factor +/- t se) with Student's t for the number of groups. The factor is a median, and
    leaving out one trial at a time overstates its standard error with many trials (measured from
    300-trial pools at 50 trials per row: 1.3-1.5x the scatter; 10 groups: 1.1-1.3x).

    Parameters
    ----------
    estimates : dict
        ``{(level, key): array (K, 3)}`` of n, kappa, theta_r [deg] per trial.
    groups : int, optional
        Jackknife groups; default ``JACKKNIFE_GROUPS`` or one trial each when a row has fewer.

    Returns
    -------
    dict
        ``factor``, ``se_log``, ``low``, ``high`` (95 %), ``groups``.
    """
    groups = groups or min(JACKKNIFE_GROUPS, *(len(e) for e in estimates.values()))
    factor = typical_factor({k: row_stats(e) for k, e in estimates.items()})
    split = {k: np.array_split(np.arange(len(e)), groups) for k, e in estimates.items()}
    loo = [
        np.log(
            typical_factor(
                {k: row_stats(np.delete(e, split[k][g], 0)) for k, e in estimates.items()}
            )
        )
        for g in range(groups)
    ]
    se = float(jackknife_se(loo))
    half = t_factor(groups) * se
    return {
        "factor": factor,
        "se_log": se,
        "low": float(factor * np.exp(-half)),
        "high": float(factor * np.exp(half)),
        "groups": groups,
    }


def bias_signs(results):
    """The direction of the bias of the mean n and kappa in every row, where the run determines it.

    Parameters
    ----------
    results : dict
        ``{(level, key): row_stats(...)}``.

    Returns
    -------
    dict
        ``{(level, key): {"n": s, "kappa": s}}``, s = +1 where the mean's 95 % Student t interval
        lies above copper's value, -1 where it lies below, 0 where it contains it or the row has
        fewer than ``MIN_SIGN_TRIALS`` trials (not determined).
    """
    out = {}
    for row, res in results.items():
        out[row] = {}
        for par, truth in PARAMS[:2]:
            m = res[par]
            half = t_factor(m["count"]) * m["se_mean"] if m["count"] >= MIN_SIGN_TRIALS else np.inf
            out[row][par] = int(m["mean"] - half > truth) - int(m["mean"] + half < truth)
    return out


def judge_in_kind(interval, signs, trials, threshold=KIND_FACTOR):
    """Whether a procedure reproduces the tables in kind: the published direction of the bias
    (n and kappa above copper in every row, as in all 7 published rows) and its rough size
    (typical factor at most ``threshold``), judged with the run's Monte-Carlo uncertainty.

    Parameters
    ----------
    interval : dict
        :func:`factor_interval` (``low``, ``high``).
    signs : dict
        :func:`bias_signs`.
    trials : int
        The fewest trials of any row.
    threshold : float

    Returns
    -------
    str
        "yes" when the factor's 95 % interval lies at or below ``threshold`` and every row's bias of
        n and kappa is determined in the published direction (a direction not contradicted is not
        shown); "no" when some row's bias is determined opposite, or when the interval lies above
        ``threshold`` and every row has at least ``MIN_SIGN_TRIALS`` trials (with fewer the factor
        reads high -- 1.16-1.34x at 6 trials per row, the runaway trials that carry the means being
        missed -- and its interval is centred on that bias, so it cannot rule a procedure out);
        "not determined" otherwise.
    """
    flat = [s for row in signs.values() for s in row.values()]
    if any(s < 0 for s in flat) or (trials >= MIN_SIGN_TRIALS and interval["low"] > threshold):
        return "no"
    if interval["high"] <= threshold and all(s > 0 for s in flat):
        return "yes"
    return "not determined"


def study_verdict(confirmed, candidates, all_inside):
    """The study's verdict from the in-kind judgements (:func:`judge_in_kind`).

    The closest procedure is picked after the fact, so a positive claim rests on its rerun on fresh
    trials (``confirmed``), not on the trials it was picked on; a negative one needs every
    candidate ruled out (each on its own trials: ruling all out needs no correction for the pick).

    Parameters
    ----------
    confirmed : str
        The closest procedure's judgement on fresh trials.
    candidates : sequence of str
        Every candidate's judgement on the trials that ranked them.
    all_inside : bool
        Every number of the fresh rerun inside its combined 2-sigma band.

    Returns
    -------
    verdict : str
        "reproduced", "partly" or "not reproduced".
    in_kind : str
        "shown", "ruled out" or "not determined" (at this run size; the verdict is then
        "not reproduced": nothing is shown).
    """
    if confirmed == "yes":
        return ("reproduced" if all_inside else "partly"), "shown"
    if all(c == "no" for c in candidates):
        return "not reproduced", "ruled out"
    return "not reproduced", "not determined"


def score_procedure(results):
    """Compare one procedure's rows with the tables.

    Parameters
    ----------
    results : dict
        ``{(level, key): run_procedure(...)}``.

    Returns
    -------
    dict
        ``comparisons`` (one :func:`compare` per row, parameter and statistic); ``inside_nk`` and
        ``total_nk`` (the n and kappa means and RMSEs inside the combined 2-sigma band);
        ``inside_theta`` and ``total_theta``; ``factor``: :func:`typical_factor`.
    """
    cmp = []
    for (level, key), res in results.items():
        pub = published_se(level, key)
        for par, _ in PARAMS:
            for stat in ("mean", "rmse"):
                c = compare(
                    f"{level} noise, M = {key}, {stat} {par}", pub[par][stat], res[par][stat],
                    pub[par][f"se_{stat}"], res[par][f"se_{stat}"],
                )  # fmt: skip
                c["par"] = par
                cmp.append(c)
    nk = [c for c in cmp if c["par"] != "theta_r"]
    th = [c for c in cmp if c["par"] == "theta_r"]
    return {
        "comparisons": cmp,
        "inside_nk": sum(c["inside"] for c in nk),
        "total_nk": len(nk),
        "inside_theta": sum(c["inside"] for c in th),
        "total_theta": len(th),
        "factor": typical_factor(results),
    }


def crlb_rows():
    """Cramer-Rao bounds for every published row under two readings of the noise.

    Returns
    -------
    dict
        ``{f"{level}_{key}": {reading: {"noise_sd", "joint" (n, kappa, theta_r [deg]),
        "theta_r_known" (n, kappa)}}}`` for the text's reading and sd = f Pmax.
    """
    out = {}
    for level, rows in PUBLISHED.items():
        for key in rows:
            m, a, b = CONFIGS[key]
            ti = np.radians(np.linspace(a, b, m))
            pmax = float(thilak_dop(*COPPER, (ti + THETA_R) / 2).max())
            out[f"{level}_{key}"] = {}
            for reading in ("variance = f Pmax (text)", "sd = f Pmax"):
                sd = float(NOISE_READINGS[reading](LEVELS[level][0], pmax))
                joint = thilak_crlb(*COPPER, THETA_R, ti, sd) * [1, 1, 180 / np.pi]
                known = thilak_crlb(*COPPER, THETA_R, ti, sd, theta_r_known=True)
                out[f"{level}_{key}"][reading] = {
                    "noise_sd": sd, "joint": joint.tolist(), "theta_r_known": known.tolist()
                }  # fmt: skip
    return out


def _crlb_text(bounds):
    """The report's paragraph on the Cramer-Rao bounds, from :func:`crlb_rows`."""
    lines = [
        "| noise | M | published RMSE n / kappa / theta_r (deg) | CRLB joint (text noise) | "
        "CRLB joint (sd = f Pmax) | CRLB n / kappa, theta_r known (text noise) |",
        "|---|---|---|---|---|---|",
    ]
    below_theta, ratio_theta, above_known, above_sd = [], [], [], []
    for name, b in bounds.items():
        level, key = name.split("_")
        p = dict(zip(PUB_KEYS, PUBLISHED[level][key]))
        text, sdr = b["variance = f Pmax (text)"], b["sd = f Pmax"]
        pub = (p["rmse_n"], p["rmse_kappa"], p["rmse_theta_r"])
        lines.append(
            f"| {level} | {key} | {pub[0]:.3g} / {pub[1]:.3g} / {pub[2]:.3g} | "
            + " | ".join(" / ".join(f"{v:.3g}" for v in c) for c in (text["joint"], sdr["joint"]))
            + " | " + " / ".join(f"{v:.3g}" for v in text["theta_r_known"]) + " |"
        )  # fmt: skip
        below_theta.append(pub[2] < sdr["joint"][2])
        ratio_theta.append(sdr["joint"][2] / pub[2])
        above_known.append([pub[j] / text["theta_r_known"][j] for j in range(2)])
        above_sd.append(pub[0] / sdr["theta_r_known"][0])
    above_known = np.array(above_known)
    return "\n".join(lines), (
        "Cramer-Rao bounds (Fisher information of Eq. 115 in (n, kappa, theta_r), Gaussian noise; "
        "table above). Estimated jointly, theta_r cannot be determined to better than "
        f"{min(ratio_theta):.3g}-{max(ratio_theta):.3g} x the published theta_r RMSE even with "
        "the smaller noise reading (sd = f Pmax), and the published theta_r RMSE is below that "
        f"bound in {sum(below_theta)} of {len(below_theta)} rows: no estimator unbiased for "
        "(n, kappa, theta_r) can produce it. The two-step method escapes the bound because step "
        "1 is given the true theta_r (Eq. 116, 'beta assumed known') and step 2 starts from it, "
        "so its theta_r is the input returned, not a measurement. With theta_r known, the "
        "published RMSEs of n and kappa are "
        f"{above_known[:, 0].min():.2g}-{above_known[:, 0].max():.2g} x and "
        f"{above_known[:, 1].min():.2g}-{above_known[:, 1].max():.2g} x the bounds at the "
        "text's noise"
        + (
            f" (below the bound for kappa in {int(np.sum(above_known[:, 1] < 1))} of "
            f"{len(above_known)} rows: only a biased or constrained estimator can do that)"
            if np.any(above_known < 1)
            else ""
        )
        + ": the bound is local, and at this noise the problem is far from linear, so the "
        "RMSE of n and kappa is set by where the estimator stops along the (n, kappa) valley, "
        "not by the bound. With the other reading (sd = f Pmax) the published RMSE of n is "
        f"{min(above_sd):.3g}-{max(above_sd):.3g} x its bound while our LM reaches the bound "
        "(diagnostics (b) above), so that reading cannot produce the tables."
    )


def _judged(results, estimates):
    """One procedure's scores (:func:`score_procedure`) with its factor's interval, its rows' bias
    signs and the in-kind judgement."""
    interval, signs = factor_interval(estimates), bias_signs(results)
    trials = min(len(e) for e in estimates.values())
    return {
        "results": results,
        **score_procedure(results),
        "interval": interval,
        "signs": signs,
        "in_kind": judge_in_kind(interval, signs, trials),
    }


def _run_judged(opts, rows, trials, rng):
    """Run one candidate procedure on every published row and judge it (:func:`_judged`)."""
    est, res = {}, {}
    for level, key, _ in rows:
        est[(level, key)], redrawn = procedure_estimates(level, key, opts, trials, rng)
        res[(level, key)] = row_stats(est[(level, key)]) | {"redrawn": redrawn}
    return _judged(res, est)


def not_told_apart(scored, best):
    """The procedures whose factor differs from the closest one's by at most its Monte-Carlo
    uncertainty: |ln f - ln f_best| <= t sqrt(se^2 + se_best^2) (independent trials, 95 %).

    Parameters
    ----------
    scored : dict
        ``{name: {"interval": factor_interval(...)}}``.
    best : str

    Returns
    -------
    list of str
        Their names, ``best`` left out.
    """
    b = scored[best]["interval"]
    out = []
    for name, s in scored.items():
        i = s["interval"]
        k = t_factor(min(i["groups"], b["groups"]))
        if name != best and abs(np.log(i["factor"] / b["factor"])) <= k * np.hypot(
            i["se_log"], b["se_log"]
        ):
            out.append(name)
    return out


def _procedure_metrics(s):
    """The metrics of one judged procedure."""
    signs = [v for row in s["signs"].values() for v in row.values()]
    return {
        "factor": s["factor"],
        "factor_95": [s["interval"]["low"], s["interval"]["high"]],
        "factor_se_log": s["interval"]["se_log"],
        "in_kind": s["in_kind"],
        "bias_high_determined": sum(v > 0 for v in signs),
        "bias_low_determined": sum(v < 0 for v in signs),
        "inside_nk": s["inside_nk"],
        "inside_theta": s["inside_theta"],
    }


def _procedures(ctx, rows, case_est):
    """Run every candidate procedure on every published row, name the closest one and those not told
    apart from it, and judge the closest again on fresh trials (it was picked on the first ones).

    Returns
    -------
    best : str
    scored : dict
        ``{name: _judged(...)}`` on the trials that ranked them.
    fresh : dict
        ``_judged(...)`` of ``best`` on fresh trials.
    verdict, state : str
        :func:`study_verdict`.
    """
    trials = PROC_TRIALS[ctx.quick]
    scored = {}
    for name, opts in PROCEDURES.items():
        with ctx.step(f"procedure: {name}"):
            if opts:
                scored[name] = _run_judged(opts, rows, trials, ctx.rng)
            else:  # our two-step estimator: the trials of the table above
                res = {(level, key): r["two_step_mc"] for level, key, r in rows}
                scored[name] = _judged(res, case_est)
    best = min(scored, key=lambda k: scored[k]["factor"])
    with ctx.step("closest procedure, fresh trials"):
        fresh = _run_judged(PROCEDURES[best], rows, FRESH_TRIALS[ctx.quick], ctx.rng)
    ctx.metrics["procedures"] = {
        name: _procedure_metrics(s)
        | {"rows": {f"{lv}_{k}": v for (lv, k), v in s["results"].items()}}
        for name, s in scored.items()
    }
    ctx.metrics["closest_procedure"] = best
    ctx.metrics["not_told_apart_from_closest"] = not_told_apart(scored, best)
    ctx.metrics["closest_procedure_fresh_trials"] = _procedure_metrics(fresh)
    all_inside = (
        fresh["inside_nk"] + fresh["inside_theta"] == fresh["total_nk"] + fresh["total_theta"]
    )
    verdict, state = study_verdict(
        fresh["in_kind"], [s["in_kind"] for s in scored.values()], all_inside
    )
    ctx.metrics["in_kind"] = state
    ctx.say(_procedure_table(scored, rows))
    ctx.say(_best_table(fresh))
    ctx.say(_procedure_text(best, scored, fresh, state, ctx.quick))
    with ctx.step("closest procedure, other noise readings"):
        other = {
            reading: score_procedure({
                (level, key): run_procedure(level, key, PROCEDURES[best], trials, ctx.rng, reading)
                for level, key, _ in rows
            })
            for reading in list(NOISE_READINGS)[1:]
        }  # fmt: skip
    ctx.metrics["closest_procedure_other_readings"] = {
        k: {"factor": v["factor"], "inside_nk": v["inside_nk"]} for k, v in other.items()
    }
    ctx.say(_readings_text(best, scored[best], other))
    return best, scored, fresh, verdict, state


def _readings_text(best, s, other):
    """Which reading of the noise definition the closest procedure needs, from the scores."""
    ti = np.radians(np.linspace(0.0, 89.9, 9000))
    curve_max = float(thilak_dop(*COPPER, ti).max())
    data_max = [
        float(thilak_dop(*COPPER, (np.radians(np.linspace(a, b, m)) + THETA_R) / 2).max())
        for m, a, b in CONFIGS.values()
    ]
    return (
        f"The noise reading, with the closest procedure ('{best}'): the text's reading "
        f"(variance = f Pmax) gives a typical factor {s['factor']:.2f} and {s['inside_nk']}/"
        f"{s['total_nk']} n and kappa numbers inside 2 sigma; "
        + "; ".join(
            f"{name}: factor {v['factor']:.3g}, {v['inside_nk']}/{v['total_nk']} inside"
            for name, v in other.items()
        )
        + ". 'Maximum DOP value' read as the maximum of the copper DOP curve over all angles "
        f"({curve_max:.3f}) instead of the data set's ({min(data_max):.3f}-{max(data_max):.3f}) "
        f"changes the noise sd by at most {np.sqrt(curve_max / min(data_max)) - 1:.0%} (variance "
        "reading), small against the factors above."
    )


def _procedure_table(scored, rows):
    """One line per procedure: mean n and kappa (RMSE) per row, and the agreement counts."""
    keys = [(lv, k) for lv, k, _ in rows]
    head = " | ".join(f"{lv} {k}" for lv, k in keys)
    lines = [
        f"| procedure (mean n / mean kappa, RMSE in brackets) | {head} | typical factor "
        "ours/published (95 %) | in kind | n, kappa inside 2 sigma | theta_r inside |",
        "|---|" + "---|" * (len(keys) + 4),
    ]
    pub = [f"{p[0]:.2f} ({p[2]:.2f}) / {p[3]:.2f} ({p[5]:.2f})"
           for p in (PUBLISHED[lv][k] for lv, k in keys)]  # fmt: skip
    lines.append("| published | " + " | ".join(pub) + " | 1 | - | - | - |")
    for name, s in scored.items():
        cells = [
            f"{r['n']['mean']:.2f} ({r['n']['rmse']:.2f}) / "
            f"{r['kappa']['mean']:.2f} ({r['kappa']['rmse']:.2f})"
            for r in (s["results"][k] for k in keys)
        ]
        i = s["interval"]
        lines.append(
            f"| {name} | "
            + " | ".join(cells)
            + f" | {s['factor']:.2f} ({i['low']:.2f}-{i['high']:.2f}) | "
            f"{s['in_kind']} | {s['inside_nk']}/{s['total_nk']} | {s['inside_theta']}/{s['total_theta']} |"
        )
    return "\n".join(lines)


def _best_table(s):
    """Published against the closest procedure, number by number, with the combined band."""
    lines = [
        "| quantity | published | closest procedure, fresh trials | difference | 2 x combined SE | inside |",
        "|---|---|---|---|---|---|",
    ]
    for c in s["comparisons"]:
        lines.append(
            f"| {c['name']} | {c['published']:.4g} | {c['ours']:.4g} | {c['diff']:+.3g} | "
            f"{c['band']:.3g} | {'yes' if c['inside'] else 'no'} |"
        )
    return "\n".join(lines)


def _kind(opts):
    """The family of a candidate procedure: how (if at all) it stops the run along the valley."""
    if "redraw" in opts:
        return "runaway trials discarded and redrawn"
    if "bounds" in opts:
        return "bounded search"
    if "tol" in opts:
        return "early stopping (MATLAB tolerances)"
    if opts.get("solver") == "nelder-mead":
        return "Nelder-Mead"
    return "run to the least-squares minimum (LM)"


def _max_rmse(scored_one, par):
    """The largest RMSE of ``par`` over the published rows of one scored procedure."""
    return max(r[par]["rmse"] for r in scored_one["results"].values())


def _step2_text(random, fixed, total_theta):
    """How step 2 started from a random theta_r compares with the same procedure started from
    step 1's theta_r (both scored procedures), generated from their theta_r scores."""
    r_max, f_max = _max_rmse(random, "theta_r"), _max_rmse(fixed, "theta_r")
    return (
        "With the true theta_r given to step 1, step 2 started there moves little from it; "
        f"started at random ('{RANDOM_STEP2}': {random['inside_theta']} of {total_theta} "
        f"inside, theta_r RMSE up to {r_max:.2g} deg, against {fixed['inside_theta']} of "
        f"{total_theta} and {f_max:.2g} deg for the same procedure started from step 1's "
        "theta_r)"
        + (
            " it sometimes lands in another minimum"
            if r_max > 1.5 * f_max
            else " it changes little"
        )
    )


def _procedure_text(best, scored, fresh, state, quick):
    """The report's conclusion on the procedures, generated from their scores: ``scored`` on the
    trials that ranked them, ``fresh`` the closest one (``best``) on fresh trials, ``state`` the
    in-kind conclusion of :func:`study_verdict`."""
    s = scored[best]
    th = [c for c in s["comparisons"] if c["par"] == "theta_r" and "rmse" in c["name"]]
    ratio = [c["ours"] / c["published"] for c in th]
    th_best = max(scored, key=lambda k: scored[k]["inside_theta"])
    close = not_told_apart(scored, best)
    fam = {}
    for name, opts in PROCEDURES.items():
        fam.setdefault(_kind(opts), []).append(scored[name]["factor"])
    worst = max(
        (c for c in fresh["comparisons"] if c["par"] != "theta_r" and not c["inside"]),
        key=lambda c: abs(c["diff"]) / c["band"],
        default=None,
    )
    i, fi = s["interval"], fresh["interval"]
    return (
        f"Candidate procedures ({PROC_TRIALS[quick]} trials per row and procedure, noise as "
        "the text states it; the standard errors are Monte-Carlo ones, the published RMSE's "
        "from its bias and spread; the factor's 95 % interval is a jackknife over the trials with "
        "Student's t). Typical factor ours/published of the means and RMSEs of n "
        "and kappa, by family: "
        + "; ".join(
            f"{k} {min(v):.2f}" + ("" if len(v) == 1 else f"-{max(v):.2f}") for k, v in fam.items()
        )
        + f". The closest is '{best}' (factor {s['factor']:.2f}, 95 % {i['low']:.2f}-{i['high']:.2f}), "
        "picked after the fact on these trials; "
        + (
            "not told apart from it by them (difference of ln factor within t x its standard "
            "error): " + ", ".join(f"'{k}' ({scored[k]['factor']:.2f})" for k in close)
            if close
            else "every other candidate is told apart from it by them"
        )
        + f". Rerun on {FRESH_TRIALS[quick]} fresh trials per row it scores {fresh['factor']:.2f} "
        f"(95 % {fi['low']:.2f}-{fi['high']:.2f}), {fresh['inside_nk']} of {fresh['total_nk']} n and "
        "kappa numbers inside twice the combined standard error (table above). "
        + _signs_text(fresh["signs"], quick)
        + " Measured outside this run (29 Nov 2026, 300 trials per row and procedure): a procedure "
        "that stops the run along the (n, kappa) valley, by a search box or by stopping early, "
        "gives the published direction of the bias (n and kappa above copper in every row) and "
        "roughly its size (the four closest, the boxes n <= 10 and n <= 20 and lsqnonlin's "
        "defaults with either start of step 2, 1.26-1.33); one run to the least-squares minimum "
        "runs off along the valley with kappa low (our two-step, 3.6), and discarding the runaway "
        "trials removes the bias of n but leaves kappa low (3.7). "
        + (
            f"The fresh run's largest disagreement: {worst['name']}, {worst['ours']:.3g} against "
            f"{worst['published']:.3g} ({abs(worst['diff']) / worst['band']:.1f} x the band). "
            if worst
            else ""
        )
        + f"theta_r: {s['inside_theta']} of {s['total_theta']} inside; its theta_r RMSE is "
        f"{min(ratio):.2g}-{max(ratio):.2g} x the published one; the best procedure for "
        f"theta_r ('{th_best}') has {scored[th_best]['inside_theta']} of "
        f"{s['total_theta']} theta_r means and RMSEs inside. "
        + _step2_text(scored[RANDOM_STEP2], scored[FIXED_STEP2], s["total_theta"])
        + ", so the published theta_r scatter depends on a step 2 the text does not "
        "describe. " + _in_kind_text(state, scored, fresh, quick)
    )


def _signs_text(signs, quick):
    """Where the fresh run determines the direction of the bias of n and kappa (:func:`bias_signs`)."""
    if FRESH_TRIALS[quick] < MIN_SIGN_TRIALS:
        return (
            f"With {FRESH_TRIALS[quick]} trials per row the direction of a row's bias is not judged "
            f"(fewer than {MIN_SIGN_TRIALS}: such a sample can miss the runaway trials that carry "
            "the mean)."
        )
    count = {
        par: (sum(r[par] > 0 for r in signs.values()), sum(r[par] < 0 for r in signs.values()))
        for par in ("n", "kappa")
    }
    return (
        "Its mean lies above copper's (95 % t interval) in "
        + " and ".join(
            f"{hi} of {len(signs)} rows for {par}, below in {lo}" for par, (hi, lo) in count.items()
        )
        + " (published: above in every row)."
    )


def _in_kind_text(state, scored, fresh, quick):
    """The report's sentence on whether a candidate reproduces the tables in kind."""
    tally = {
        w: sum(s["in_kind"] == w for s in scored.values()) for w in ("yes", "no", "not determined")
    }
    head = (
        f"In kind (the published direction of the bias and its rough size, typical factor at most "
        f"{KIND_FACTOR:g}, judged with the Monte-Carlo uncertainty: the factor's interval below or "
        f"above {KIND_FACTOR:g}, a row's mean determined below copper), per candidate on the "
        f"ranking trials: yes {tally['yes']}, no {tally['no']}, not determined {tally['not determined']} "
        f"of {len(scored)}; the closest on fresh trials: {fresh['in_kind']}. "
    )
    if state == "shown":
        return (
            head
            + (
                "No candidate reproduces the tables number for number"
                if fresh["inside_nk"] + fresh["inside_theta"]
                < fresh["total_nk"] + fresh["total_theta"]
                else "The closest reproduces the tables number for number on fresh trials"
            )
            + (
                ": the published means are reproduced in kind (direction and rough size of the bias), "
                "which points to a search stopped short of the least-squares minimum (bounds or "
                "tolerances the paper does not state), not to a different model or noise reading."
            )
        )
    if state == "ruled out":
        return head + (
            "No candidate reproduces the tables, not even in kind: every one has its factor's "
            f"interval above {KIND_FACTOR:g} or a row's bias below copper."
        )
    return head + (
        "Whether a candidate reproduces the tables in kind is not determined at this run size "
        f"({PROC_TRIALS[quick]} trials per row): it is neither shown on fresh trials nor ruled out "
        "for every candidate"
        + (
            f". With {PROC_TRIALS[quick]} trials the factor also reads high (measured from 300-trial pools: by "
            "1.16-1.34x for the closest candidates) and its interval spans about 1.5x either way; "
            f"full mode's {FRESH_TRIALS[False]} fresh trials per row are sized to decide (from the pools, "
            "not yet measured in a full run)"
            if quick
            else ""
        )
        + "."
    )
