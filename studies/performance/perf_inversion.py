"""Inversion cost: batched least squares vs the per-pixel scipy baseline on an image, at equal solutions.

A 250 x 316 x 7 image (Ch. VII's specular angles 30-60 deg; three materials; DOLP noise 0.01; sigma known,
as in the reference's characterization) is solved by :func:`fit_dolp` in one pass. The per-pixel
``scipy.optimize.least_squares`` baseline (same forward model, analytic Jacobian, starts and bounds) is timed
on a random subset of pixels in the same run and its per-pixel time scaled to the image. Equal solutions are
checked on that subset (cost and parameters). Also: batched time against image size, and with sigma fitted
(11 geometries, seven specular and four off specular).

The accuracy knob of the sigma fit, ``FitOptions.sigma_starts`` (further starting roughnesses), is swept on
noiseless pixels (n 1.1-4.5, kappa 0.01-20, sigma 0.02-1.2, log-uniform; five specular geometries 30-70 deg):
the truth fits exactly, so a DOLP residual above 1e-6 is a local minimum. Reported per setting: local minima,
pixels with sigma off by more than 0.05, and the run time with its ratio to ``sigma0`` alone.

Full-mode run time (measured 25 Nov 2026, serial, the shared 2-core machine running a second job):
183 s wall. Sigma known, the batched fit is 295x faster than the per-pixel baseline. Sigma fitted, the
batched fit also runs from the ``sigma_starts`` (three times the starts of the baseline, which keeps
``sigma0`` alone) and is still 53x faster; its cost is at least as low at 88 % of the pixels and a
little higher at the rest (noise 0.01 leaves sigma poorly determined by these geometries: nearby minima
of near-equal cost; ``batched_cost_excess_max_relative`` gives the largest excess). The
``sigma_starts`` sweep, 400 pixels: from ``sigma0`` alone 92 local minima (62 with sigma off by more
than 0.05) in 1.1 s; with the default (0.05, 1.0) 33 (17) in 3.0 s (2.6x); three or four further
starts 30 (15) and 28 (14) at 2.9x and 3.7x: the default takes most of the gain.
"""

import time
import warnings

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.inversion import FitOptions, fit_dolp, fit_dolp_per_pixel, model_dolp
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "perf_inversion",
    "title": "Batched vs per-pixel least squares of (n, kappa, sigma)",
    "reproduces": "own performance study",
}

TRUTHS = np.array([(1.39, 0.34), (1.44, 16.0), (3.6, 5.88)])
SIGMA = 0.3
# FitOptions.sigma_starts settings swept (sigma0 = 0.3 is always the first start); the default is the second
SIGMA_STARTS = ((), (0.05, 1.0), (0.02, 0.1, 1.0), (0.02, 0.08, 0.6, 1.2))


def image(rng, shape, theta_i, theta_r, sigma=SIGMA):
    labels = rng.integers(0, 3, shape)
    t = TRUTHS[labels]
    return model_dolp(t[..., 0], t[..., 1], sigma, theta_i, theta_r) + 0.01 * rng.standard_normal(
        shape + (theta_i.size,)
    )


def run(ctx):
    rng = ctx.rng
    theta = np.radians(np.arange(30, 61, 5))
    shape = (50, 64) if ctx.quick else (250, 316)
    subset = 40 if ctx.quick else 300
    y = image(rng, shape, theta, theta)
    with ctx.step("batched_image"):
        t0 = time.perf_counter()
        fit = fit_dolp(y, theta, theta, sigma=SIGMA)
        t_batch = time.perf_counter() - t0
    flat = y.reshape(-1, theta.size)
    pick = rng.choice(flat.shape[0], subset, replace=False)
    with ctx.step("per_pixel_subset"):
        t0 = time.perf_counter()
        base = fit_dolp_per_pixel(flat[pick], theta, theta, sigma=SIGMA)
        t_pix = (time.perf_counter() - t0) / subset
    fn, fk, fc = (getattr(fit, a).reshape(-1)[pick] for a in ("n", "kappa", "cost"))
    same = np.abs(fc - base.cost) <= 1e-9 * np.maximum(base.cost, 1e-12) + 1e-15
    npix = flat.shape[0]
    ctx.metrics.update(
        {
            "image_shape": [*shape, theta.size],
            "batched_s": t_batch,
            "batched_us_per_pixel": 1e6 * t_batch / npix,
            "per_pixel_us_per_pixel": 1e6 * t_pix,
            "per_pixel_image_s_extrapolated": t_pix * npix,
            "speedup": t_pix * npix / t_batch,
            "subset": subset,
            "equal_cost_fraction": float(same.mean()),
            "max_param_difference_equal_cost": float(
                np.max(np.abs(np.r_[fn - base.n, fk - base.kappa])[np.r_[same, same]])
            )
            if same.any()
            else float("nan"),
            "batched_lower_cost_fraction": float(np.mean(fc < base.cost * (1 - 1e-9))),
            "converged_fraction": float(fit.converged.mean()),
        }
    )

    sizes = [(10, 10), (20, 25), (50, 64)] + ([] if ctx.quick else [(100, 126), (250, 316)])
    times = []
    with ctx.step("scaling"):
        for sh in sizes:
            yy = image(rng, sh, theta, theta)
            t0 = time.perf_counter()
            fit_dolp(yy, theta, theta, sigma=SIGMA)
            times.append(time.perf_counter() - t0)
    ctx.metrics["scaling"] = {f"{a}x{b}": t for (a, b), t in zip(sizes, times)}

    ti = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
    tr = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])
    y3 = image(rng, (20, 20) if ctx.quick else (100, 100), ti, tr).reshape(-1, ti.size)
    with ctx.step("sigma_fitted"):
        t0 = time.perf_counter()
        f3 = fit_dolp(y3, ti, tr)
        tb3 = (time.perf_counter() - t0) / y3.shape[0]
        k = 20 if ctx.quick else 100
        t0 = time.perf_counter()
        b3 = fit_dolp_per_pixel(y3[:k], ti, tr)
        tp3 = (time.perf_counter() - t0) / k
    ctx.metrics["sigma_fitted"] = {
        "speedup": tp3 / tb3,
        "batched_us_per_pixel": 1e6 * tb3,
        "per_pixel_us_per_pixel": 1e6 * tp3,
        "batched_cost_not_worse_fraction": float(
            np.mean(f3.cost[:k] <= b3.cost * (1 + 1e-6) + 1e-15)
        ),
        "batched_cost_excess_max_relative": float(np.max(f3.cost[:k] / b3.cost - 1.0)),
    }

    ctx.metrics["sigma_starts"] = sigma_starts_sweep(rng, 100 if ctx.quick else 400, ctx)

    pyplot = plt()
    fig, (ax, ax2) = pyplot.subplots(1, 2, figsize=(11, 4))
    npx = [a * b for a, b in sizes]
    ax.loglog(npx, times, "o-", label="batched fit_dolp")
    ax.loglog(
        npx, [t_pix * p for p in npx], "s--", label="per-pixel scipy (measured per pixel x pixels)"
    )
    ax.set(
        xlabel="pixels (7 angles each)",
        ylabel="time [s]",
        title="least squares of (n, kappa), sigma known",
    )
    ax.legend(fontsize=8)
    rows = ctx.metrics["sigma_starts"]["rows"]
    ax2.plot(
        [r["time_s"] for r in rows], [r["local_minima"] for r in rows], "o-", label="local minima"
    )
    ax2.plot(
        [r["time_s"] for r in rows],
        [r["sigma_off"] for r in rows],
        "s--",
        label="|sigma error| > 0.05",
    )
    for i, r in enumerate(rows):
        tag = f"{len(r['sigma_starts'])} more" + (" (default)" if i == 1 else "")
        ax2.annotate(
            tag,
            (r["time_s"], r["local_minima"]),
            (3, 6 + 8 * (i % 2)),
            textcoords="offset points",
            fontsize=7,
        )
    ax2.legend(fontsize=8)
    ax2.set(
        xlabel="time [s]",
        ylabel=f"pixels of {ctx.metrics['sigma_starts']['pixels']} (noiseless)",
        title="sigma fitted: FitOptions.sigma_starts",
        ylim=(0, None),
    )
    ctx.save_figure(fig, "perf_inversion")
    m = ctx.metrics
    ctx.say(
        f"{shape[0]} x {shape[1]} x 7 image: batched {m['batched_s']:.1f} s ({m['batched_us_per_pixel']:.0f} us/pixel) "
        f"against {m['per_pixel_us_per_pixel']:.0f} us/pixel for per-pixel scipy, a speed-up of {m['speedup']:.0f}x "
        f"(goal 50x). On the {subset} compared pixels {m['equal_cost_fraction']:.0%} reach the same cost (to 1e-9), "
        f"parameters there agreeing to {m['max_param_difference_equal_cost']:.1e}; the batched fit is lower in "
        f"{m['batched_lower_cost_fraction']:.0%}. With sigma fitted (11 geometries) the speed-up is "
        f"{m['sigma_fitted']['speedup']:.0f}x."
    )
    ss = m["sigma_starts"]
    ctx.say(
        f"Sigma fitted from five specular geometries, {ss['pixels']} noiseless pixels: "
        + "; ".join(
            f"sigma starts {r['label']}: {r['local_minima']} local minima ({r['sigma_off']} with sigma off "
            f"by > 0.05), {r['time_s']:.2f} s ({r['time_ratio']:.1f}x)"
            for r in ss["rows"]
        )
        + "."
    )
    default = ss["rows"][1]  # SIGMA_STARTS[1] is FitOptions' default
    set_verdict(
        ctx,
        "own study",
        f"batched fit {m['speedup']:.0f}x per-pixel scipy ({m['batched_us_per_pixel']:.0f} vs "
        f"{m['per_pixel_us_per_pixel']:.0f} us/pixel; same cost at {m['equal_cost_fraction']:.0%}); sigma fitted "
        f"{m['sigma_fitted']['speedup']:.0f}x; default sigma_starts {default['local_minima']} local minima of "
        f"{ss['pixels']} (sigma0 alone {ss['rows'][0]['local_minima']}) at {default['time_ratio']:.1f}x the time",
    )


def sigma_starts_sweep(rng, pixels, ctx):
    """Local minima and run time of the sigma fit for each setting of ``FitOptions.sigma_starts``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the true (n, kappa, sigma) of each pixel.
    pixels : int
        Number of noiseless pixels.
    ctx : StudyContext
        Times the step.

    Returns
    -------
    dict
        ``pixels`` and ``rows``: per setting its ``label``, ``local_minima`` (DOLP residual > 1e-6),
        ``sigma_off`` (|sigma error| > 0.05), ``median_residual_of_minima``, ``time_s`` and
        ``time_ratio`` (to ``sigma0`` alone).
    """
    th = np.radians([30.0, 40.0, 50.0, 60.0, 70.0])
    truth = np.c_[
        rng.uniform(1.1, 4.5, pixels),
        np.exp(rng.uniform(np.log(0.01), np.log(20), pixels)),
        np.exp(rng.uniform(np.log(0.02), np.log(1.2), pixels)),
    ]
    y = model_dolp(truth[:, 0], truth[:, 1], truth[:, 2], th, th)  # (pixels, 5)
    rows = []
    with ctx.step("sigma_starts"), warnings.catch_warnings():
        warnings.simplefilter(
            "ignore"
        )  # some metals' kappa is undetermined: a warning, counted below
        for extra in SIGMA_STARTS:
            t0 = time.perf_counter()
            fit = fit_dolp(y, th, th, options=FitOptions(sigma_starts=extra))
            elapsed = time.perf_counter() - t0
            resid = np.max(
                np.abs(model_dolp(fit.n, fit.kappa, fit.sigma, th, th) - y),
                axis=-1,
            )
            minima = resid > 1e-6
            rows.append(
                {
                    "label": "0.3 + (" + ", ".join(f"{v:g}" for v in extra) + ")",
                    "sigma_starts": list(extra),
                    "local_minima": int(minima.sum()),
                    "sigma_off": int(np.sum(np.abs(fit.sigma - truth[:, 2]) > 0.05)),
                    "median_residual_of_minima": float(np.median(resid[minima]))
                    if minima.any()
                    else 0.0,
                    "time_s": elapsed,
                }
            )
    for r in rows:
        r["time_ratio"] = r["time_s"] / rows[0]["time_s"]
    return {"pixels": pixels, "rows": rows}
