"""Blind deconvolution cost: iterations vs DOLP/S0 error vs time, and the cost of one EM iteration over four
channels against one scikit-image Richardson-Lucy iteration on one channel of the same size (same run).

Full-mode run time (measured 24 Nov 2026, serial, load average 3.4-3.3 on the shared 2-core
machine): 9 s wall.
"""

import time

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.deconvolution import blind_deconvolve
from scatterlab.imaging import ANGLES_0_45_90_135, channel_images, detect
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.runtime import best_time

STUDY = {
    "id": "perf_deconvolution",
    "title": "EM blind deconvolution: iterations vs error vs time; cost vs Richardson-Lucy",
    "reproduces": "own performance study",
}


def gaussian_psf(n, sd):
    yy, xx = np.mgrid[0:n, 0:n]
    g = np.exp(-((yy - n // 2) ** 2 + (xx - n // 2) ** 2) / (2 * sd * sd))
    return g / g.sum()


def two_material_scene(n, rng):
    lab = np.zeros((n, n), int)
    for _ in range(8):
        r, c = rng.integers(0, n - n // 6, 2)
        lab[r : r + n // 6, c : c + n // 8] = 1
    s0 = np.where(lab == 1, 2.0, 1.0)
    P = np.where(lab == 1, 0.05, 0.6)
    return np.stack([s0, P * s0, np.zeros_like(s0)], axis=-1), P


def run(ctx):
    from skimage.restoration import richardson_lucy

    rng = ctx.rng
    n = 64 if ctx.quick else 128
    S, P = two_material_scene(n, rng)
    h = gaussian_psf(n, 2.0)
    counts = detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=5e3)
    rows = []
    with ctx.step("iterations"):
        for it in (5, 10, 20, 40) if ctx.quick else (5, 10, 20, 40, 80, 160):
            t0 = time.perf_counter()
            res = blind_deconvolve(counts, ANGLES_0_45_90_135, iterations=it, psf_radius=n / 8)
            secs = time.perf_counter() - t0
            s0 = S[..., 0] * res.s0.mean() / S[..., 0].mean()
            rows.append(
                {
                    "iterations": it,
                    "seconds": secs,
                    "dolp_rmse": float(np.sqrt(np.mean((res.dolp - P) ** 2))),
                    "s0_relative_rmse": float(np.sqrt(np.mean((res.s0 - s0) ** 2)) / s0.mean()),
                }
            )
    ctx.metrics["iterations"] = rows

    m = 128 if ctx.quick else 512
    Sm, _ = two_material_scene(m, rng)
    hm = gaussian_psf(m, 2.0)
    cm = detect(channel_images(Sm, ANGLES_0_45_90_135, hm), rng, photons=5e3)
    with ctx.step("per_iteration_cost"):
        small = hm[m // 2 - 8 : m // 2 + 9, m // 2 - 8 : m // 2 + 9]
        t_rl = best_time(lambda: richardson_lucy(cm[0], small, num_iter=1, clip=False), repeat=5)
        per_iter = {}
        for boundary in ("periodic", "reeves"):
            # the difference of 4 and 0 iterations: set-up (initial Stokes images, first forward model) excluded
            t4 = best_time(
                lambda: blind_deconvolve(
                    cm, ANGLES_0_45_90_135, iterations=4, psf_radius=m / 8, boundary=boundary
                ),
                repeat=3,
            )
            t0 = best_time(
                lambda: blind_deconvolve(
                    cm, ANGLES_0_45_90_135, iterations=0, psf_radius=m / 8, boundary=boundary
                ),
                repeat=3,
            )
            per_iter[boundary] = max(t4 - t0, 1e-9) / 4
    ctx.metrics["per_iteration"] = {
        "size": m,
        "rl_1_channel_s": t_rl,
        **{f"em_4_channels_{b}_s": v for b, v in per_iter.items()},
        **{f"ratio_{b}": v / t_rl for b, v in per_iter.items()},
        "reeves_grid": m + 2 * int(np.ceil(m / 8)),
    }
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6, 4))
    ax.loglog([r["seconds"] for r in rows], [r["dolp_rmse"] for r in rows], "o-", label="DOLP RMSE")
    ax.loglog(
        [r["seconds"] for r in rows],
        [r["s0_relative_rmse"] for r in rows],
        "s-",
        label="S0 relative RMSE",
    )
    ax.set(xlabel="run time [s]", ylabel="error", title=f"{n} x {n}, 4 channels, blind (EM PSF)")
    ax.legend()
    ctx.save_figure(fig, "perf_deconvolution")
    r = ctx.metrics["per_iteration"]
    ctx.say(
        f"One blind EM iteration over four {m} x {m} channels (S0, DOLP and PSF updates) costs "
        f"{r['em_4_channels_periodic_s'] * 1e3:.0f} ms with periodic boundaries, {r['ratio_periodic']:.1f}x one "
        f"scikit-image Richardson-Lucy iteration on one channel ({r['rl_1_channel_s'] * 1e3:.0f} ms; goal 4x), and "
        f"{r['em_4_channels_reeves_s'] * 1e3:.0f} ms ({r['ratio_reeves']:.1f}x) with Reeves boundaries on the "
        f"{r['reeves_grid']}^2 object grid. DOLP error {rows[0]['dolp_rmse']:.3f} after {rows[0]['iterations']} "
        f"iterations, {rows[-1]['dolp_rmse']:.3f} after {rows[-1]['iterations']}."
    )
    set_verdict(
        ctx,
        "own study",
        f"one blind EM iteration (4 channels, {m}^2) costs {r['ratio_periodic']:.1f}x one scikit-image RL "
        f"iteration on one channel (goal <= 4x); DOLP RMSE {rows[-1]['dolp_rmse']:.3f} after "
        f"{rows[-1]['iterations']} iterations in {rows[-1]['seconds'] * 1e3:.0f} ms ({n}^2)",
    )
