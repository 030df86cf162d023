"""Tables 1 and 2: Thilak et al.'s Monte-Carlo experiments on copper, their two-step method against our
bounded least squares and posterior medians on the same noisy data.

Copper eta = 0.314 - j3.544 (the errata's value), theta_r = 60 deg, 3/5/10/19 measurements over the stated
theta_i ranges (evenly spaced), DOP of smooth facets (Eq. 115). Noise: Gaussian with variance 0.1 % (low) or
1 % (high) of the largest DOP of the data set, 500 and 200 trials. The published "+/-" is read as the 95 %
confidence half-width of the mean, 1.96 std / sqrt(trials) (it reproduces the published RMSEs with the means).
"""

import warnings

import numpy as np

from scatterlab.inversion import ConvergenceWarning, fit_dolp, sample_posteriors, thilak_two_step
from scatterlab.inversion.thilak import thilak_dop
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "thilak_tables",
    "title": "Thilak et al.'s copper Monte-Carlo tables: two-step vs least squares vs posterior",
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
LEVELS = {"low": (1e-3, 500), "high": (1e-2, 200)}


def _stats(x, truth):
    x = x[np.isfinite(x)]
    return {
        "mean": float(x.mean()),
        "ci95": float(1.96 * x.std(ddof=1) / np.sqrt(x.size)),
        "rmse": float(np.sqrt(np.mean((x - truth) ** 2))),
        "count": int(x.size),
    }


def run(ctx):
    rng = ctx.rng
    pyplot = plt()
    rows = []
    for level, (var_frac, trials) in LEVELS.items():
        trials = 40 if ctx.quick else trials
        n_post = 4 if ctx.quick else 60
        for key, pub in PUBLISHED[level].items():
            m, a, b = CONFIGS[key]
            ti = np.radians(np.linspace(a, b, m))
            clean = thilak_dop(*COPPER, (ti + THETA_R) / 2)
            sd = np.sqrt(var_frac * clean.max())
            y = clean + sd * rng.standard_normal((trials, m))
            with ctx.step(f"{level}_{key}_thilak"):
                th = thilak_two_step(y, ti, THETA_R, rng)
            with ctx.step(f"{level}_{key}_least_squares"):
                ls = fit_dolp(y, ti, np.full(m, THETA_R), sigma=0.3, diffuse="none", noise=sd)
            with ctx.step(f"{level}_{key}_posterior"), warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                posts = sample_posteriors(
                    y[:n_post],
                    ti,
                    np.full(m, THETA_R),
                    sd,
                    rng,
                    sigma=0.3,
                    diffuse="none",
                    n_steps=600 if ctx.quick else 2000,
                    executor=ctx.executor,
                )
            med = np.array([p.quantiles([0.5])[0, :2] for p in posts])
            cover = np.mean(
                [
                    [lo <= t <= hi for lo, hi, t in zip(*p.interval(0.68)[:, :2], COPPER)]
                    for p in posts
                ],
                0,
            )
            res = {
                "noise_sd": float(sd),
                "trials": trials,
                "posterior_trials": n_post,
                "thilak": {
                    "n": _stats(th.n, COPPER[0]),
                    "kappa": _stats(th.kappa, COPPER[1]),
                    "theta_r_deg": _stats(np.degrees(th.theta_r), 60.0),
                    "restarts": int(th.restarts.sum()),
                },
                "least_squares": {
                    "n": _stats(ls.n, COPPER[0]),
                    "kappa": _stats(ls.kappa, COPPER[1]),
                },
                "posterior_median": {
                    "n": _stats(med[:, 0], COPPER[0]),
                    "kappa": _stats(med[:, 1], COPPER[1]),
                    "coverage68": cover.tolist(),
                },
                "published": dict(
                    zip(
                        [
                            "n",
                            "n_pm",
                            "rmse_n",
                            "kappa",
                            "kappa_pm",
                            "rmse_kappa",
                            "theta_r",
                            "theta_r_pm",
                            "rmse_theta_r",
                        ],
                        pub,
                    )
                ),
            }
            ctx.metrics[f"{level}_{key}"] = res
            rows.append((level, key, res))

    lines = [
        "| noise | M | published n (RMSE) | Thilak n (RMSE) | LS n (RMSE) | posterior n (RMSE) | "
        "published kappa (RMSE) | Thilak kappa (RMSE) | LS kappa (RMSE) | posterior kappa (RMSE) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for level, key, r in rows:
        p = r["published"]

        def cell(s):
            return f"{s['mean']:.3f} +/- {s['ci95']:.3f} ({s['rmse']:.3f})"

        lines.append(
            f"| {level} | {key} | {p['n']:.3f} +/- {p['n_pm']:.3f} ({p['rmse_n']:.3f}) | "
            f"{cell(r['thilak']['n'])} | {cell(r['least_squares']['n'])} | {cell(r['posterior_median']['n'])} | "
            f"{p['kappa']:.3f} +/- {p['kappa_pm']:.3f} ({p['rmse_kappa']:.3f}) | {cell(r['thilak']['kappa'])} | "
            f"{cell(r['least_squares']['kappa'])} | {cell(r['posterior_median']['kappa'])} |"
        )
    ctx.say("\n".join(lines))

    fig, axes = pyplot.subplots(1, 2, figsize=(11, 4))
    for ax, par in zip(axes, ("n", "kappa")):
        for level, mk in (("low", "o"), ("high", "s")):
            sel = [(int(k), r) for lv, k, r in rows if lv == level]
            x = [s[0] for s in sel]
            ax.semilogy(
                x,
                [r["published"][f"rmse_{par}"] for _, r in sel],
                "k" + mk + "--",
                label=f"published ({level})",
            )
            ax.semilogy(
                x,
                [r["thilak"][par]["rmse"] for _, r in sel],
                "C0" + mk + "-",
                label=f"two-step ({level})",
            )
            ax.semilogy(
                x,
                [r["least_squares"][par]["rmse"] for _, r in sel],
                "C1" + mk + "-",
                label=f"bounded LS ({level})",
            )
            ax.semilogy(
                x,
                [r["posterior_median"][par]["rmse"] for _, r in sel],
                "C2" + mk + ":",
                label=f"posterior median ({level})",
            )
        ax.set(xlabel="number of measurements", ylabel=f"RMSE of {par}", title=par)
    axes[0].legend(fontsize=6)
    ctx.save_figure(fig, "thilak_rmse")
    low10 = ctx.metrics["low_10"]
    cov = np.mean([r["posterior_median"]["coverage68"] for _, _, r in rows], 0)
    ctx.metrics["posterior_coverage68_mean"] = cov.tolist()
    ctx.say(
        f"Low noise, 10 measurements: the two-step method's RMSE of n is {low10['thilak']['n']['rmse']:.3f} "
        f"(published {low10['published']['rmse_n']:.3f}); bounded least squares "
        f"{low10['least_squares']['n']['rmse']:.3f}, posterior median {low10['posterior_median']['n']['rmse']:.3f}. "
        "With this much noise (sd 0.009-0.03 on DOPs below 0.08) the data barely constrain (n, kappa) along "
        "the metal valley: the unconstrained two-step fit runs far along it (means well above the truth, as "
        "published, with occasional huge outliers in our runs), bounded least squares is capped by n <= 5, "
        "kappa <= 25, and the posterior is mostly prior along the valley, so its median is pulled to the "
        "middle of the prior -- a poor point estimate but an honest one: its 68 % intervals contain the truth "
        f"in {cov[0]:.0%} (n) and {cov[1]:.0%} (kappa) of the trials. The tables' lesson holds in all three: "
        "a handful of specular DOP values at this noise cannot determine a metal's index."
    )
