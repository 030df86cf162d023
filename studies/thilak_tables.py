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
branch of the (n, kappa) valley the runaway fits take. The posterior is computed exactly on an
(n, kappa) grid (flat prior on the text's box n in [0, 5], kappa in [0, 25], theta_r known, Gaussian
likelihood with the true noise): its 68 % highest-density region, and the 68 % likelihood-ratio
(Wilks, chi^2 with 2 degrees of freedom) confidence region of the same likelihood, are checked for
coverage of the true (n, kappa).

Run time: quick (24 trials per case) 55 s measured at load ~9 on the shared 2-core machine;
full (500/200 trials): 1027 s at load ~13 (before the posterior grid was chunked).
"""

import numpy as np
from scatterlab.studies._common import compare, set_verdict

from scatterlab.inversion import fit_dolp, thilak_two_step
from scatterlab.inversion.thilak import thilak_dop
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


def _coverage(y, ti, sd, quick, chunk=64):
    """Coverage of the true (n, kappa) by the 68 % HPD region of the grid posterior (flat prior on
    the box) and by the 68 % likelihood-ratio region (chi^2_2 = 2.30), for the trials ``y`` (K, M),
    in chunks of ``chunk`` trials (memory). Also the posterior medians (K, 2)."""
    grid_n, grid_k = (np.linspace(0.0, hi, k) for hi, k in zip((5.0, 25.0), GRIDS[quick]))
    beta = (ti + THETA_R) / 2
    g = thilak_dop(grid_n[:, None, None], grid_k[None, :, None], beta).reshape(-1, ti.size)
    parts = [
        _coverage_chunk(y[i : i + chunk], g, beta, sd, grid_n, grid_k)
        for i in range(0, len(y), chunk)
    ]
    hpd, lr, med = (np.concatenate(x) for x in zip(*parts))
    return float(hpd.mean()), float(lr.mean()), med


def _coverage_chunk(y, g, beta, sd, grid_n, grid_k):
    chi2 = ((g**2).sum(1)[:, None] - 2 * g @ y.T + (y**2).sum(1)[None, :]) / sd**2  # (G, K)
    chi2_true = (((thilak_dop(*COPPER, beta) - y) ** 2).sum(1)) / sd**2
    chi2_min = np.minimum(chi2.min(0), chi2_true)
    lr = chi2_true - chi2_min <= 2.30
    w = np.exp(-(chi2 - chi2_min) / 2)
    total = w.sum(0)
    w /= total
    ws = -np.sort(-w, axis=0)
    thresh = ws[np.argmax(np.cumsum(ws, axis=0) >= 0.68, axis=0), np.arange(y.shape[0])]
    hpd = np.exp(-(chi2_true - chi2_min) / 2) / total >= thresh
    wn = w.reshape(grid_n.size, grid_k.size, -1)
    med = [
        [grid[np.searchsorted(np.cumsum(m[:, k]), 0.5)] for k in range(y.shape[0])]
        for grid, m in ((grid_n, wn.sum(1)), (grid_k, wn.sum(0)))
    ]
    return hpd, lr, np.array(med).T


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
        hpd, lr, med = _coverage(y, ti, sd, ctx.quick)
    n_ok = th.n[th.ok]
    return {
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
        "coverage68_bayes_hpd": hpd,
        "coverage68_likelihood_ratio": lr,
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
    """Whether the coverages are consistent with 68 % (binomial, 2 standard errors)."""
    se = np.sqrt(0.68 * 0.32 / trials)
    parts = []
    for name, cov in (("The posterior's HPD region", hpd), ("the likelihood-ratio region", lrc)):
        low = [c for c in cov if c < 0.68 - 2 * se]
        parts.append(
            f"{name} is consistent with 68 % in {len(cov) - len(low)} of {len(cov)} cases "
            f"(binomial 2 SE = {2 * se:.0%} for {trials} trials)"
            + (f", under-covers in {len(low)}" if low else "")
        )
    return (
        "; ".join(parts) + ". Where a fixed truth sits in a weakly identified valley, Bayesian "
        "coverage is guaranteed only on average over the prior, so the likelihood-ratio "
        "(frequentist) region is shown beside it. "
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


def _figure(ctx, rows):
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
            ):
                yv = [
                    r["published"][f"rmse_{par}"] if src == "published" else r[src][par]["rmse"]
                    for _, r in sel
                ]
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
        diag = _diagnostics(ctx, 12 if ctx.quick else 200)
    ctx.metrics["diagnostics"] = diag
    ctx.say(_table(rows))
    _figure(ctx, rows)

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
        (np.sign(r["thilak"]["kappa"]["median"] - COPPER[1]), np.sign(r["published"]["kappa"] - COPPER[1]))
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
        "cases where the text's mean is above it in all 7. The tables are NOT reproduced."
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
        "kappa 3.768. With sd = 0.1 % of Pmax the method recovers copper almost exactly (far "
        "better than published); with the text's reading (sd 0.008-0.009 on DOPs of 0.036-0.078) "
        "it runs away more often than published; no reading reproduces both the size and the "
        "direction (kappa high) of the published bias. The text does not give the rest of "
        "Thilak's procedure (start, bounds, stopping rule, which restarts count), which is where "
        "the difference must lie: the forward model (Eq. 115) is tested equal to the Fresnel "
        "DOP, so the data are right."
    )
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
        + "Posterior medians are no better point estimates than least squares here (table)."
    )
    set_verdict(
        ctx,
        "not reproduced",
        f"mean n {min(ratio_n):.1f}-{max(ratio_n):.1f} x published; {inside}/{len(cmp)} means "
        f"inside 2 sigma; 68 % coverage HPD {min(hpd):.0%}-{max(hpd):.0%}, "
        f"LR {min(lrc):.0%}-{max(lrc):.0%}",
    )
