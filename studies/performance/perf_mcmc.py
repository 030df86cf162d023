"""MCMC cost: chain length vs error of the posterior quantiles vs time, and effective samples per second
for the three proposal sets (KDE + DE, DE + snooker, stretch).

Paint (1.39 - j0.34, sigma 0.3), 11 geometries, DOLP noise 2e-3. The reference quantiles (16/50/84 %) come
from a long chain in the same run; the error of a shorter chain is the largest quantile deviation in units
of the reference posterior standard deviation, averaged over independent repeats. Each run is one emcee
ensemble (``n_ensembles=1``): the cost of one; sample_posterior's default runs two independent ensembles for
the between-ensemble R-hat, at twice the sampling cost.

Full-mode run time (measured 24 Nov 2026, serial, load average 1.8-2.3 on the shared 2-core
machine): 347 s wall.
"""

import time
import warnings

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.inversion import ConvergenceWarning, model_dolp, sample_posterior
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "perf_mcmc",
    "title": "MCMC length vs quantile error vs time; effective samples per second",
    "reproduces": "own performance study",
}

TI = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
TR = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])
NOISE = 2e-3


def run(ctx):
    rng = ctx.rng
    y = model_dolp(1.39, 0.34, 0.3, TI, TR) + NOISE * rng.standard_normal(TI.size)
    q = [0.16, 0.5, 0.84]
    warnings.simplefilter("ignore", ConvergenceWarning)
    with ctx.step("reference_chain"):
        ref = sample_posterior(
            y, TI, TR, NOISE, rng, n_steps=3000 if ctx.quick else 20000, n_ensembles=1
        )
    ref_q, ref_sd = ref.quantiles(q), ref.samples.std(0)
    lengths = [100, 200, 400, 800] if ctx.quick else [100, 200, 400, 800, 1600, 3200, 6400]
    repeats = 2 if ctx.quick else 5
    rows = {}
    with ctx.step("length_sweep"):
        for moves in ("kde", "de", "stretch"):
            out = []
            for L in lengths:
                errs, secs = [], []
                for _ in range(repeats):
                    t0 = time.perf_counter()
                    p = sample_posterior(
                        y, TI, TR, NOISE, rng, n_steps=L, moves=moves, n_ensembles=1
                    )
                    secs.append(time.perf_counter() - t0)
                    errs.append(float(np.max(np.abs(p.quantiles(q) - ref_q) / ref_sd)))
                out.append(
                    {
                        "steps": L,
                        "quantile_error_sd": float(np.mean(errs)),
                        "time_s": float(np.mean(secs)),
                        "tau_max": float(np.max(p.tau)),
                        "ess_per_s": p.n_effective / p.seconds,
                    }
                )
            rows[moves] = out
    ctx.metrics["reference"] = {
        "steps": ref.n_steps,
        "tau": ref.tau.tolist(),
        "ess_per_s": ref.n_effective / ref.seconds,
    }
    ctx.metrics["sweep"] = rows
    longest = {m: r[-1] for m, r in rows.items()}
    ctx.metrics["ess_per_s_longest"] = {m: r["ess_per_s"] for m, r in longest.items()}
    ctx.metrics["tau_longest"] = {m: r["tau_max"] for m, r in longest.items()}
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6, 4))
    for m, r in rows.items():
        ax.loglog([x["time_s"] for x in r], [x["quantile_error_sd"] for x in r], "o-", label=m)
    ax.set(
        xlabel="run time [s]",
        ylabel="max quantile error [posterior sd]",
        title="chain length vs error",
    )
    ax.legend()
    ctx.save_figure(fig, "perf_mcmc")
    t = ctx.metrics["tau_longest"]
    e = ctx.metrics["ess_per_s_longest"]
    ctx.say(
        f"Longest chains: tau = {t['kde']:.0f} (KDE + DE), {t['de']:.0f} (DE), {t['stretch']:.0f} (stretch) steps; "
        f"effective samples per second {e['kde']:.0f}, {e['de']:.0f}, {e['stretch']:.0f}. "
        f"The most effective samples per second in this run: {max(e, key=e.get)}. The quantile error falls "
        "with chain length as the figure shows; below a few tau it is dominated by the start."
    )
    set_verdict(
        ctx,
        "own study",
        f"{lengths[-1]} steps: effective samples/s KDE + DE {e['kde']:.0f}, DE {e['de']:.0f}, stretch "
        f"{e['stretch']:.0f} (tau {t['kde']:.0f}, {t['de']:.0f}, {t['stretch']:.0f} steps); quantile error "
        + ", ".join(f"{k} {r[-1]['quantile_error_sd']:.2f}" for k, r in rows.items())
        + " posterior sd",
    )
