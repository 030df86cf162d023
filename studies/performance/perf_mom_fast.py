"""Fast MoM path (banded matrix + FFT far interactions, s-pol PEC): error vs run time vs its knobs.

(a) knobs on one rough surface of N unknowns (2000 quick, 4000 full) against dense LU: the
    strong-interaction band width, the Taylor order of the far kernel and the GMRES tolerance;
    error of the current and of the scattering coefficient (relative L2 over -89..89 deg);
(b) cost growth with N for dense LU and the fast path in the same run (and their ratio);
(c) one long surface solved in one piece: 10^4 unknowns (quick) or 10^5 (full: 10,000
    wavelengths at 10 per wavelength), with its energy balance R (1 for a PEC; the far field
    integrated by FFT, :func:`scatterlab.mom.fast.scattered_power`).

Surfaces: Gaussian heights sigma_h = 0.3 wavelength, rms slope 0.3, 10 points per wavelength,
Thorsos taper g = L/4. Measured on the shared 2-core machine: full mode 448 s (the 10^5 solve
285 s, 64 GMRES iterations, Taylor order 17, R = 0.99988); quick mode 65 s wall under load (19 s
of CPU).
"""

import time

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.mom import TaperedWave, correlation_length_for_slope, rough_surface, solve_tm
from scatterlab.mom.fast import FastOptions, scattered_power
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "perf_mom_fast",
    "title": "Fast MoM path (BMIA/CAG): error vs run time, cost growth, 10^5 unknowns",
    "reproduces": "own performance study",
}

SIGMA_H, SLOPE, PPW = 0.3, 0.3, 10
ANGLES = np.radians(np.linspace(-89, 89, 357))


def surface(n, rng):
    """A rough profile of n points at PPW per wavelength (wavelength 1) and its tapered waves."""
    x, y = rough_surface(
        n / PPW, 1 / PPW, SIGMA_H, correlation_length_for_slope(SIGMA_H, SLOPE), rng
    )
    x0 = 0.5 * (x[0] + x[-1])
    return x, y, [TaperedWave(np.radians(t), n / PPW / 4, x0=x0) for t in (20, 60)]


def _errors(ref, sol):
    cur = np.linalg.norm(sol.current - ref.current, axis=0) / np.linalg.norm(ref.current, axis=0)
    a, b = ref.scattering_coefficient(ANGLES), sol.scattering_coefficient(ANGLES)
    coef = np.linalg.norm(b - a, axis=0) / np.linalg.norm(a, axis=0)
    return float(np.max(cur)), float(np.max(coef))


def knobs(ctx, ax, rng):
    n = 2000 if ctx.quick else 4000
    x, y, incs = surface(n, rng)
    t0 = time.perf_counter()
    ref = solve_tm(x, y, 1.0, incs)
    t_lu = time.perf_counter() - t0
    if ctx.quick:
        grid = [("band", 3.0, None, 1e-6), ("band", 5.0, None, 1e-6), ("order", 5.0, 4, 1e-6)]
        grid += [("tol", 5.0, None, 1e-3)]
    else:
        grid = [("band", b, None, 1e-6) for b in (2.0, 3.0, 5.0, 8.0)]
        grid += [("order", 5.0, m, 1e-6) for m in (2, 4, 6, 8)]
        grid += [("tol", 5.0, None, t) for t in (1e-2, 1e-3, 1e-4)]
    rows = []
    for knob, band, order, tol in grid:
        opts = FastOptions(band=band, order=order, tol=tol, dense_below=0)
        t0 = time.perf_counter()
        sol = solve_tm(x, y, 1.0, incs, solver="fast", fast=opts)
        secs = time.perf_counter() - t0
        e_cur, e_coef = _errors(ref, sol)
        rows.append(
            {
                "knob": knob,
                "band_wavelengths": band,
                "order": sol.info["order"],
                "tol": tol,
                "iterations": sol.info["iterations"],
                "current_error": e_cur,
                "coefficient_error": e_coef,
                "seconds": secs,
            }
        )
    for knob, mark in (("band", "o-"), ("order", "s-"), ("tol", "^-")):
        sel = [r for r in rows if r["knob"] == knob]
        ax.loglog([r["seconds"] for r in sel], [r["current_error"] for r in sel], mark, label=knob)
    ax.axvline(t_lu, color="k", ls=":", label="dense LU")
    ax.set(xlabel="run time [s]", ylabel="rel. L2 error of the current", title=f"knobs, N={n}")
    ax.legend(fontsize=7)
    return {"unknowns": n, "lu_seconds": t_lu, "rows": rows}


def growth(ctx, ax, rng):
    rows = []
    for n in (1000, 2000) if ctx.quick else (1000, 2000, 4000, 8000):
        x, y, incs = surface(n, rng)
        incs = incs[:1]
        t0 = time.perf_counter()
        ref = solve_tm(x, y, 1.0, incs)
        t_lu = time.perf_counter() - t0
        t0 = time.perf_counter()
        sol = solve_tm(x, y, 1.0, incs, solver="fast", fast=FastOptions(dense_below=0))
        t_fast = time.perf_counter() - t0
        e_cur, e_coef = _errors(ref, sol)
        rows.append(
            {
                "unknowns": n,
                "lu_seconds": t_lu,
                "fast_seconds": t_fast,
                "ratio_lu_over_fast": t_lu / t_fast,
                "current_error": e_cur,
                "coefficient_error": e_coef,
            }
        )
    ns = [r["unknowns"] for r in rows]
    ax.loglog(ns, [r["lu_seconds"] for r in rows], "o-", label="dense LU")
    ax.loglog(ns, [r["fast_seconds"] for r in rows], "s-", label="fast")
    ax.set(xlabel="unknowns N", ylabel="fill + solve [s]", title="cost growth (one incidence)")
    ax.legend(fontsize=7)
    return rows


def big(ctx, rng):
    n = 10_000 if ctx.quick else 100_000
    x, y, incs = surface(n, rng)
    t0 = time.perf_counter()
    sol = solve_tm(x, y, 1.0, incs[0], solver="fast")
    secs = time.perf_counter() - t0
    t0 = time.perf_counter()
    power = scattered_power(sol)
    return {
        "unknowns": n,
        "wavelengths": n / PPW,
        "seconds": secs,
        "setup_seconds": sol.timings["fill"],
        "iterations": sol.info["iterations"][0],
        "order": sol.info["order"],
        "band_pulses": sol.info["band_pulses"],
        "residual": float(sol.residual[0]),
        "solver": sol.solver,
        "energy": power,
        "energy_seconds": time.perf_counter() - t0,
    }


def run(ctx):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 2, figsize=(11, 4.2))
    with ctx.step("knobs"):
        ctx.metrics["knobs"] = kn = knobs(ctx, axes[0], ctx.rng)
    with ctx.step("growth"):
        ctx.metrics["growth"] = gr = growth(ctx, axes[1], ctx.rng)
    with ctx.step("big"):
        ctx.metrics["big"] = bg = big(ctx, ctx.rng)
    ctx.save_figure(fig, "perf_mom_fast")
    default = [r for r in kn["rows"] if r["knob"] == "band" and r["band_wavelengths"] == 5.0][0]
    last = gr[-1]
    ctx.say(
        f"On {kn['unknowns']} unknowns the fast path with its defaults (band 5 wavelengths, order "
        f"{default['order']}, GMRES to 1e-6) differs from dense LU by {default['current_error']:.1e} "
        f"in the current and {default['coefficient_error']:.1e} in the scattering coefficient, in "
        f"{default['seconds']:.1f} s against {kn['lu_seconds']:.1f} s for LU (two incidences). "
        f"At {last['unknowns']} unknowns (one incidence) LU takes {last['lu_seconds']:.1f} s and the "
        f"fast path {last['fast_seconds']:.1f} s (ratio {last['ratio_lu_over_fast']:.1f}, same run). "
        f"A {bg['wavelengths']:.0f}-wavelength surface ({bg['unknowns']} unknowns) solved in one "
        f"piece in {bg['seconds']:.0f} s ({bg['iterations']} GMRES iterations, Taylor order "
        f"{bg['order']}, residual {bg['residual']:.1e}); its reflected power is {bg['energy']:.5f} "
        f"(|R - 1| = {abs(bg['energy'] - 1):.1e})."
    )
    set_verdict(
        ctx,
        "own study",
        f"fast path vs dense LU at {kn['unknowns']} unknowns: current error {default['current_error']:.1e}, "
        f"{default['seconds']:.1f} s vs {kn['lu_seconds']:.1f} s; {bg['unknowns']} unknowns in "
        f"{bg['seconds']:.0f} s, R - 1 = {bg['energy'] - 1:+.1e}",
    )
