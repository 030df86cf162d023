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

Run time: quick (24 trials per case, 6 per candidate procedure and row) 22-24 s measured on the
2-core machine at load 0.4-4 (56 s at load ~5, beside a full run of this study); full (500/200
trials, 150 per candidate procedure and row, with the adaptive-sampler check): 481 s at load 2-3
(the candidate procedures take 296 s of it, fminsearch 79 s). Which of the three or four
closest procedures comes first changes with the random stream (the box n <= 10 scored 1.35 and
1.21 in two full runs), so the report names every procedure within 10 % of the closest. The
verdict is "partly" when the closest procedure reproduces the tables in kind (n and kappa biased
high in every row, typical factor at most 1.5) but not number for number.
"""

import time
import warnings

import numpy as np
from scatterlab.studies._common import compare, set_verdict

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
    return {
        "two_step_mc": {par: mc_stats(est[:, j], t) for j, (par, t) in enumerate(PARAMS)},
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
    rows = []
    for level, (_, trials) in LEVELS.items():
        trials = 24 if ctx.quick else trials
        for key in PUBLISHED[level]:
            res = _case(ctx, level, key, trials)
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
        + ", ".join(f"{r['thilak']['runaway_branch_kappa_median']:.2f}" for _, _, r in rows)
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
    best, scored = _procedures(ctx, rows)
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
    sb = scored[best]
    n_in, n_all = sb["inside_nk"] + sb["inside_theta"], sb["total_nk"] + sb["total_theta"]
    # "partly": reproduced in kind -- the bias of n and kappa in the published direction in every
    # row and within a typical factor 1.5 (stable across random streams, unlike the count inside)
    in_kind = sb["factor"] <= 1.5 and all(
        r["n"]["mean"] > COPPER[0] and r["kappa"]["mean"] > COPPER[1]
        for r in sb["results"].values()
    )
    verdict = "reproduced" if n_in == n_all else "partly" if in_kind else "not reproduced"
    ctx.say(
        _verdict_note(verdict, best, len(PROCEDURES), PROC_TRIALS[ctx.quick], inside == len(cmp))
    )
    set_verdict(
        ctx,
        verdict,
        f"closest of {len(PROCEDURES)} procedures, picked post hoc ({best}): n, kappa "
        f"typically {sb['factor']:.2f} x published, "
        f"{n_in}/{n_all} numbers inside 2 sigma (unconstrained LM: mean n "
        f"{min(ratio_n):.1f}-{max(ratio_n):.1f} x published); 68 % coverage HPD "
        f"{min(hpd):.0%}-{max(hpd):.0%}, LR {min(lrc):.0%}-{max(lrc):.0%}",
    )


def _two_step_verdict_text(inside, total):
    """Whether our own two-step estimator reproduces the tables' means, from the comparison."""
    if inside == total:
        return f"Our two-step estimator reproduces the tables: all {total} mean values inside."
    return (
        f"Our two-step estimator does not reproduce the tables ({inside} of {total} mean values "
        "inside)."
    )


def _verdict_note(verdict, best, n_procedures, trials, two_step_reproduces):
    """What the verdict rests on: the closest procedure is selected after the fact on the same
    trials it is scored on, so a "partly" or "reproduced" is for that post-hoc pick."""
    own = "reproduces" if two_step_reproduces else "does not reproduce"
    if verdict == "not reproduced":
        return (
            f'Verdict "not reproduced": our two-step estimator {own} the tables, and the closest '
            f"of {n_procedures} candidate procedures ('{best}') does not reproduce them in kind."
        )
    return (
        f"Verdict \"{verdict}\": this is for '{best}', a procedure picked after the fact as the "
        f"closest of {n_procedures} candidates on the same {trials} trials per row it is scored "
        "on (post-hoc selection: with so few trials the ranking changes with the random stream). "
        f"Our two-step estimator {own} the tables."
    )


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


def run_procedure(level, key, opts, trials, rng, reading="variance = f Pmax (text)"):
    """One candidate procedure on one published row: statistics of (n, kappa, theta_r [deg]).

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
    dict
        Per parameter the :func:`mc_stats`; ``redrawn``: trials replaced by a fresh draw.
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
    out = {par: mc_stats(est[:, j], truth) for j, (par, truth) in enumerate(PARAMS)}
    out["redrawn"] = redrawn
    return out


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
        ``inside_theta`` and ``total_theta``; ``factor``: the typical ratio ours/published of the
        n and kappa means and RMSEs, exp(median |ln ratio|).
    """
    cmp, logs = [], []
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
                if par != "theta_r":
                    logs.append(abs(np.log(res[par][stat] / pub[par][stat])))
    nk = [c for c in cmp if c["par"] != "theta_r"]
    th = [c for c in cmp if c["par"] == "theta_r"]
    return {
        "comparisons": cmp,
        "inside_nk": sum(c["inside"] for c in nk),
        "total_nk": len(nk),
        "inside_theta": sum(c["inside"] for c in th),
        "total_theta": len(th),
        "factor": float(np.exp(np.median(logs))),
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


def _procedures(ctx, rows):
    """Run every candidate procedure on every published row and report the closest one."""
    trials = PROC_TRIALS[ctx.quick]
    scored = {}
    for name, opts in PROCEDURES.items():
        with ctx.step(f"procedure: {name}"):
            res = {
                (level, key): r["two_step_mc"] if not opts
                else run_procedure(level, key, opts, trials, ctx.rng)
                for level, key, r in rows
            }  # fmt: skip
        scored[name] = {"results": res, **score_procedure(res)}
    best = min(scored, key=lambda k: scored[k]["factor"])
    ctx.metrics["procedures"] = {
        name: {
            "factor": s["factor"],
            "inside_nk": s["inside_nk"],
            "inside_theta": s["inside_theta"],
            "rows": {f"{lv}_{k}": v for (lv, k), v in s["results"].items()},
        }
        for name, s in scored.items()
    }
    ctx.metrics["closest_procedure"] = best
    ctx.say(_procedure_table(scored, rows))
    ctx.say(_best_table(scored[best]))
    ctx.say(_procedure_text(best, scored, ctx.quick))
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
    return best, scored


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
        "ours/published | n, kappa inside 2 sigma | theta_r inside |",
        "|---|" + "---|" * (len(keys) + 3),
    ]
    pub = [f"{p[0]:.2f} ({p[2]:.2f}) / {p[3]:.2f} ({p[5]:.2f})"
           for p in (PUBLISHED[lv][k] for lv, k in keys)]  # fmt: skip
    lines.append("| published | " + " | ".join(pub) + " | 1 | - | - |")
    for name, s in scored.items():
        cells = [
            f"{r['n']['mean']:.2f} ({r['n']['rmse']:.2f}) / "
            f"{r['kappa']['mean']:.2f} ({r['kappa']['rmse']:.2f})"
            for r in (s["results"][k] for k in keys)
        ]
        lines.append(
            f"| {name} | " + " | ".join(cells) + f" | {s['factor']:.2f} | {s['inside_nk']}/"
            f"{s['total_nk']} | {s['inside_theta']}/{s['total_theta']} |"
        )
    return "\n".join(lines)


def _best_table(s):
    """Published against the closest procedure, number by number, with the combined band."""
    lines = [
        "| quantity | published | ours | difference | 2 x combined SE | inside |",
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


def _procedure_text(best, scored, quick):
    """The report's conclusion on the procedures, generated from their scores."""
    s = scored[best]
    th = [c for c in s["comparisons"] if c["par"] == "theta_r" and "rmse" in c["name"]]
    ratio = [c["ours"] / c["published"] for c in th]
    th_best = max(scored, key=lambda k: scored[k]["inside_theta"])
    close = [k for k in scored if scored[k]["factor"] <= 1.1 * s["factor"] and k != best]
    fam = {}
    for name, opts in PROCEDURES.items():
        fam.setdefault(_kind(opts), []).append(scored[name]["factor"])
    high = [(r["kappa"]["mean"] > COPPER[1], r["n"]["mean"] > COPPER[0])
            for r in s["results"].values()]  # fmt: skip
    pub_rows = [p for rows in PUBLISHED.values() for p in rows.values()]
    pub_high = (sum(p[3] > COPPER[1] for p in pub_rows), sum(p[0] > COPPER[0] for p in pub_rows))
    worst = max(
        (c for c in s["comparisons"] if c["par"] != "theta_r" and not c["inside"]),
        key=lambda c: abs(c["diff"]) / c["band"],
        default=None,
    )
    reproduced = s["inside_nk"] == s["total_nk"] and s["inside_theta"] == s["total_theta"]
    return (
        f"Candidate procedures ({PROC_TRIALS[quick]} trials per row and procedure, noise as "
        "the text states it; the standard errors are Monte-Carlo ones, the published RMSE's "
        "from its bias and spread). Typical factor ours/published of the means and RMSEs of n "
        "and kappa, by family: "
        + "; ".join(f"{k} {min(v):.2f}-{max(v):.2f}" for k, v in fam.items())
        + f". The closest is '{best}' (factor {s['factor']:.2f}, {s['inside_nk']} of "
        f"{s['total_nk']} inside twice the combined standard error"
        + (
            "; within 10 % of it, not told apart by these trials: "
            + ", ".join(f"'{k}' ({scored[k]['factor']:.2f})" for k in close)
            if close
            else ""
        )
        + f"). Its mean kappa is above copper's in {sum(k for k, _ in high)} of {len(high)} "
        f"rows and its mean n in {sum(n for _, n in high)} (published: {pub_high[0]} and "
        f"{pub_high[1]} of {len(high)}). A procedure that "
        "stops the run along the (n, kappa) valley, by a search box or by stopping early, "
        "gives the published direction of the bias and roughly its size; one run to the "
        "least-squares minimum runs off along the valley with kappa low (our two-step), and "
        "discarding the runaway trials removes the bias altogether. "
        + (
            f"Its largest disagreement: {worst['name']}, {worst['ours']:.3g} against "
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
        "describe. "
        + (
            "The tables are reproduced by this procedure."
            if reproduced
            else "No candidate reproduces the tables number for number: the published means "
            "are reproduced only in kind (direction and rough size of the bias), which points "
            "to a search stopped short of the least-squares minimum (bounds or tolerances the "
            "paper does not state), not to a different model or noise reading."
        )
    )
