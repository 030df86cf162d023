"""MoM energy balance: the integrated scattering coefficient of rough PEC surfaces against incidence and slope.

Full-mode run time (measured 24 Nov 2026, serial, load average 2.0-2.5 on the shared 2-core
machine): 128 s wall.
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.mom import TaperedWave, correlation_length_for_slope, rough_surface, solve_tm
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "mom_energy",
    "title": "MoM energy conservation vs incidence angle and roughness",
    "reproduces": "own validation: conservation of energy (Tsang et al.'s passive-sensing grade)",
}


def run(ctx):
    angles = np.radians([0, 15, 30, 45, 60, 70, 75, 80])
    slopes = (0.1, 0.3, 0.6) if ctx.quick else (0.1, 0.2, 0.3, 0.4, 0.6)
    length = 150.0 if ctx.quick else 300.0
    reals = 1 if ctx.quick else 4
    xq, wq = np.polynomial.legendre.leggauss(2048)
    ths = xq * np.pi / 2
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6.5, 4.2))
    worst = {}
    for slope in slopes:
        l = correlation_length_for_slope(0.5, slope)
        e = []
        for _ in range(reals):
            x, y = rough_surface(length, 0.1 if slope <= 0.4 else 0.05, 0.5, l, ctx.rng)
            ok = [
                t
                for t in angles
                if np.cos(t) * length / 4 * 2 * np.pi >= 10
                and (1 + 2 * np.tan(t) ** 2) / (2 * (2 * np.pi * length / 4 * np.cos(t)) ** 2)
                <= 0.02
            ]
            with ctx.step(f"slope_{slope}"):
                sol = solve_tm(x, y, 1.0, [TaperedWave(t, length / 4) for t in ok])
            e.append(np.sum(wq[:, None] * sol.scattering_coefficient(ths), 0) * np.pi / 2)
        e = np.mean(e, 0)
        ax.plot(np.degrees(ok), e - 1, "o-", label=f"slope {slope}")
        ctx.metrics[f"slope_{slope}"] = {f"{np.degrees(t):.0f}": float(v) for t, v in zip(ok, e)}
        worst[slope] = float(np.max(np.abs(e - 1)))
    ax.axhspan(-0.005, 0.005, color="0.9", label="0.5 % band")
    ax.set(
        xlabel=r"$\theta_i$ [deg]",
        ylabel="integrated coefficient - 1",
        title=f"{length:.0f}-wavelength surfaces",
    )
    ax.legend(fontsize=7)
    ctx.save_figure(fig, "mom_energy")
    ctx.metrics["worst_abs_deviation"] = worst
    ctx.say(
        "Largest |energy - 1| per rms slope: "
        + ", ".join(f"{k}: {v:.1e}" for k, v in worst.items())
        + ". Angles whose taper fails the validity check for this surface length are left out (the solver "
        "refuses them)."
    )
    set_verdict(
        ctx,
        "own study",
        "largest deviation of the rough PEC's integrated coefficient from 1: "
        + ", ".join(f"slope {k} {v:.1e}" for k, v in worst.items())
        + f" ({length:.0f} wavelengths, {reals} realization(s); band 0.5 %)",
    )
