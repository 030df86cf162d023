"""Ellipsometry accuracy against run time: number of repeats, ECM azimuth-fit tolerance, and the
throughput of applying a calibration to Mueller-matrix images (vs a per-pixel loop).

Full-mode run time (measured 24 Nov 2026, serial, load average 3.7-3.4 on the shared 2-core
machine): 20 s wall.
"""

import time

import numpy as np
from scatterlab.studies._common import (
    REF_TRUE_AZ,
    calibrate,
    imperfect_1064_instrument,
    set_verdict,
)

from scatterlab.plotting import headless_pyplot as plt
from scatterlab.polarization import diattenuator, linear_retarder
from scatterlab.runtime import best_time

STUDY = {
    "id": "perf_ecm",
    "title": "Ellipsometry: repeats and ECM tolerance vs error vs time; image throughput",
    "reproduces": "own performance study",
}


def run(ctx):
    rng = ctx.rng
    inst = imperfect_1064_instrument()
    sample = linear_retarder(0.9, 0.35) @ diattenuator(0.8, 0.3, 1.1)
    pyplot = plt()
    fig, (ax1, ax2) = pyplot.subplots(1, 2, figsize=(11, 4))
    repeats_list = (1, 4, 16, 64) if ctx.quick else (1, 4, 16, 64, 256, 1024)
    trials = 4 if ctx.quick else 20
    rows = []
    with ctx.step("repeats"):
        for rep in repeats_list:
            errs, t0 = [], time.perf_counter()
            for _ in range(trials):
                cal = calibrate(inst, rng, 1e-2, repeats=rep)
                B = inst.measure(sample, rng, noise=1e-2, repeats=rep)[0]
                errs.append(np.sqrt(np.mean((cal.mueller(B) - sample) ** 2)))
            rows.append(
                {
                    "repeats": rep,
                    "rms_error": float(np.mean(errs)),
                    "time_s": (time.perf_counter() - t0) / trials,
                }
            )
    ax1.loglog([r["time_s"] for r in rows], [r["rms_error"] for r in rows], "o-")
    for r in rows:
        ax1.annotate(str(r["repeats"]), (r["time_s"], r["rms_error"]), fontsize=7)
    ax1.set(
        xlabel="time per calibration + measurement [s]",
        ylabel="RMS Mueller error",
        title="repeats (noise 1e-2)",
    )
    tols = (1e-2, 1e-4, 1e-6, 1e-9, 1e-12)
    trows = []
    with ctx.step("tolerance"):
        for tol in tols:
            t = best_time(
                lambda: calibrate(
                    inst, np.random.default_rng(0), 0.0, fit_tolerance=tol, refine=False
                ),
                repeat=3,
            )
            cal = calibrate(inst, np.random.default_rng(0), 0.0, fit_tolerance=tol, refine=False)
            err = float(
                np.degrees(
                    np.max(np.abs(np.array([r["azimuth"] for r in cal.references]) - REF_TRUE_AZ))
                )
            )
            trows.append({"tolerance": tol, "azimuth_error_deg": err, "time_s": t})
    ax2.loglog(
        [r["time_s"] for r in trows], [max(r["azimuth_error_deg"], 1e-16) for r in trows], "s-"
    )
    ax2.set(
        xlabel="ECM time [s]",
        ylabel="max azimuth error [deg]",
        title="azimuth-fit tolerance (no noise)",
    )
    ctx.save_figure(fig, "perf_ecm")
    cal = calibrate(inst, rng, 0.0)
    n_px = 10**5 if ctx.quick else 10**6
    B = inst.intensities(sample) + 1e-3 * rng.standard_normal((n_px, 4, 4))
    with ctx.step("images"):
        rate = n_px / best_time(lambda: cal.mueller(B), repeat=3)
        n_loop = 2000
        loop_rate = n_loop / best_time(
            lambda: [cal._Ainv @ b @ cal._Winv for b in B[:n_loop]], repeat=3
        )
    ctx.metrics.update(
        {
            "repeats": rows,
            "tolerance": trows,
            "image_pixels_per_s": rate,
            "loop_pixels_per_s": loop_rate,
            "image_speedup": rate / loop_rate,
        }
    )
    slope = np.polyfit(
        np.log([r["repeats"] for r in rows]), np.log([r["rms_error"] for r in rows]), 1
    )[0]
    ctx.metrics["error_vs_repeats_slope"] = float(slope)
    ctx.say(
        f"Repeats: the RMS Mueller error falls as repeats^{slope:.2f} (ideal -0.5): "
        + ", ".join(
            f"{r['repeats']}: {r['rms_error']:.1e} in {r['time_s'] * 1e3:.0f} ms" for r in rows
        )
        + ". The computing time is that of the ECM fit and hardly depends on the repeats; on an instrument the "
        "cost of repeats is acquisition time, proportional to their number."
    )
    ctx.say(
        "ECM azimuth-fit tolerance (noise-free data): "
        + ", ".join(
            f"{r['tolerance']:.0e}: {r['azimuth_error_deg']:.1e} deg in {r['time_s'] * 1e3:.0f} ms"
            for r in trows
        )
        + "."
    )
    ctx.say(
        f"Applying a calibration to a Mueller-matrix image: {rate:.2g} pixels/s vectorised vs {loop_rate:.2g} "
        f"pixels/s in a per-pixel loop (x{rate / loop_rate:.0f}); target >= 1e6 pixels/s."
    )
    set_verdict(
        ctx,
        "own study",
        f"Mueller error ~ repeats^{slope:.2f} (ideal -0.5); calibrated images at {rate:.2g} pixels/s, "
        f"{rate / loop_rate:.0f}x a per-pixel loop (target >= 1e6 pixels/s)",
    )
