"""MoM for both polarizations and real materials: error against run time for each accuracy knob.

(a) points per wavelength inside and outside a glass cylinder (ka = 10) against the exact series;
(b) exact two-medium formulation vs the impedance (Leontovich) condition for iron and aluminium
    cylinders, error against the exact series vs run time;
(c) taper width (surface length 4 g) on rough glass: energy balance |R + T - 1| vs run time;
(d) impedance vs exact on one rough aluminium surface (the difference of the scattering
    coefficients; the exact one at 6 points per wavelength in the metal), and the cost of the
    impedance condition against the PEC solve of the same 150-wavelength surface (100 in quick mode;
    five incidences), measured in one run;
(e) cost growth with N for LU and forward-backward (p-pol PEC, glass).

Full-mode run time (measured 24 Nov 2026, serial, load average 2.7-1.8 on the shared 2-core
machine): 70 s wall.
"""

import time
import warnings

import numpy as np
from scatterlab.studies._common import plt, set_verdict

from scatterlab.mom import (
    PlaneWave,
    TaperedWave,
    correlation_length_for_slope,
    cylinder_echo_width,
    rough_surface,
    solve,
    solve_tm,
)

STUDY = {
    "id": "perf_mom_materials",
    "title": "MoM materials and polarizations: error vs run time",
    "reproduces": "own performance study",
}

K = 2 * np.pi
PHI = np.radians(np.arange(0, 181))
GLASS, IRON, ALUMINIUM = 1.5, 3.60 - 5.88j, 1.44 - 16j


def cylinder_run(ka, ppw, pol, eta, method="exact"):
    """(relative L2 error against the series, seconds, unknowns) for a circle at ppw per free-space
    wavelength."""
    a = ka / K
    n = max(int(np.ceil(2 * np.pi * a * ppw)), 16)
    t = 2 * np.pi * (np.arange(n) + 0.5) / n
    t0 = time.perf_counter()
    with warnings.catch_warnings():  # coarse sampling on purpose
        warnings.simplefilter("ignore", UserWarning)
        sol = solve(
            a * np.cos(t),
            a * np.sin(t),
            1.0,
            PlaneWave(np.pi / 2),
            closed=True,
            polarization=pol,
            eta=eta,
            method=method,
        )
    ew = sol.echo_width(np.pi / 2 - PHI)
    secs = time.perf_counter() - t0
    ex = cylinder_echo_width(ka, PHI, polarization=pol, eta=eta)
    return float(np.linalg.norm(ew - ex) / np.linalg.norm(ex)), secs, n


def sweep_sampling(ctx, ax):
    rows = []
    for pol in ("s", "p"):
        for ppw_in in (6, 10) if ctx.quick else (6, 8, 10, 14, 20, 28):
            err, secs, n = cylinder_run(10, ppw_in * GLASS, pol, GLASS)
            rows.append(
                {
                    "pol": pol,
                    "ppw_inside": ppw_in,
                    "ppw_outside": ppw_in * GLASS,
                    "error": err,
                    "seconds": secs,
                    "unknowns": 2 * n,
                }
            )
        sel = [r for r in rows if r["pol"] == pol]
        ax.loglog(
            [r["seconds"] for r in sel], [r["error"] for r in sel], "o-", label=f"glass {pol}-pol"
        )
        for r in sel:
            ax.annotate(str(r["ppw_inside"]), (r["seconds"], r["error"]), fontsize=7)
    ax.set(
        xlabel="run time [s]",
        ylabel="relative L2 error",
        title="glass cylinder ka=10 (labels: ppw inside)",
    )
    ax.legend(fontsize=7)
    return rows


def sweep_metals(ctx, ax):
    rows = []
    for name, eta, ka in (("iron", IRON, 5.0), ("aluminium", ALUMINIUM, 2.0)):
        for pol in ("s", "p"):
            for method, ppws in (
                ("exact", (6, 10) if ctx.quick else (6, 8, 10, 14)),
                ("impedance", (10, 20) if ctx.quick else (10, 20, 40, 80)),
            ):
                sel = []
                for ppw in ppws:
                    out = ppw * abs(eta) if method == "exact" else ppw
                    err, secs, n = cylinder_run(ka, out, pol, eta, method)
                    sel.append(
                        {
                            "metal": name,
                            "ka": ka,
                            "pol": pol,
                            "method": method,
                            "ppw": ppw,
                            "error": err,
                            "seconds": secs,
                            "unknowns": n * (2 if method == "exact" else 1),
                        }
                    )
                rows += sel
                ax.loglog(
                    [r["seconds"] for r in sel],
                    [r["error"] for r in sel],
                    "o-" if method == "exact" else "s--",
                    label=f"{name} {pol} {method}",
                )
    ax.set(
        xlabel="run time [s]",
        ylabel="relative L2 error",
        title="metal cylinders: exact vs impedance",
    )
    ax.legend(fontsize=6)
    return rows


def sweep_taper(ctx, ax, rng):
    rows = []
    xq, wq = np.polynomial.legendre.leggauss(1024)
    ths = xq * np.pi / 2
    for g in (5.0, 10.0) if ctx.quick else (5.0, 10.0, 20.0, 40.0):
        x, y = rough_surface(4 * g, 1 / 15, 0.3, correlation_length_for_slope(0.3, 0.3), rng)
        for pol in ("s", "p"):
            t0 = time.perf_counter()
            sol = solve(
                x,
                y,
                1.0,
                [TaperedWave(t, g) for t in np.radians([20, 50])],
                polarization=pol,
                eta=GLASS,
            )
            R = np.sum(wq[:, None] * sol.scattering_coefficient(ths), 0) * np.pi / 2
            T = np.sum(wq[:, None] * sol.transmission_coefficient(ths), 0) * np.pi / 2
            rows.append(
                {
                    "g": g,
                    "length": 4 * g,
                    "pol": pol,
                    "energy_error": float(np.max(np.abs(R + T - 1))),
                    "seconds": time.perf_counter() - t0,
                }
            )
    for pol in ("s", "p"):
        sel = [r for r in rows if r["pol"] == pol]
        ax.loglog(
            [r["seconds"] for r in sel],
            [max(r["energy_error"], 1e-7) for r in sel],
            "o-",
            label=pol,
        )
    ax.set(
        xlabel="run time [s]", ylabel="max |R + T - 1|", title="rough glass, taper g (length 4 g)"
    )
    ax.legend(fontsize=7)
    return rows


def impedance_vs_exact(ctx, rng):
    """One rough aluminium surface, both formulations; and the impedance/PEC cost ratio on a long
    one."""
    length, g = (8.0, 2.0) if ctx.quick else (20.0, 5.0)
    x, y = rough_surface(length, 1 / 96, 0.2, correlation_length_for_slope(0.2, 0.2), rng)
    ths = np.radians(np.linspace(-85, 85, 171))
    inc = [TaperedWave(np.radians(20), g)]
    out = {}
    for pol in ("s", "p"):
        t0 = time.perf_counter()
        with warnings.catch_warnings():  # 6 points per wavelength in the metal (warns below 8)
            warnings.simplefilter("ignore", UserWarning)
            ex = solve(x, y, 1.0, inc, polarization=pol, eta=ALUMINIUM)
        t_ex = time.perf_counter() - t0
        t0 = time.perf_counter()
        ibc = solve(x[::4], y[::4], 1.0, inc, polarization=pol, eta=ALUMINIUM, method="impedance")
        t_ibc = time.perf_counter() - t0
        a, b = ex.scattering_coefficient(ths), ibc.scattering_coefficient(ths)
        out[pol] = {
            "relative_l2_difference": float(np.linalg.norm(a - b) / np.linalg.norm(a)),
            "exact_seconds": t_ex,
            "impedance_seconds": t_ibc,
            "exact_unknowns": 2 * x.size,
            "impedance_unknowns": x[::4].size,
        }
    # cost against the PEC solve of the same 150-wavelength surface, five incidences, in one run
    length = 100.0 if ctx.quick else 150.0
    x, y = rough_surface(length, 0.1, 1.0, correlation_length_for_slope(1.0, 0.3), rng)
    incs = [TaperedWave(t, length / 4) for t in np.radians([10, 30, 45, 60, 75])]
    times = {"pec_s": [], "al_impedance_s": [], "al_impedance_p": [], "pec_p": []}
    for _ in range(1 if ctx.quick else 3):
        for key, call in (
            ("pec_s", lambda: solve_tm(x, y, 1.0, incs)),
            ("al_impedance_s", lambda: solve(x, y, 1.0, incs, eta=ALUMINIUM, method="impedance")),
            (
                "al_impedance_p",
                lambda: solve(x, y, 1.0, incs, eta=ALUMINIUM, method="impedance", polarization="p"),
            ),
            ("pec_p", lambda: solve(x, y, 1.0, incs, polarization="p")),
        ):
            t0 = time.perf_counter()
            call()
            times[key].append(time.perf_counter() - t0)
    med = {k: float(np.median(v)) for k, v in times.items()}
    out["cost_long_surface"] = med | {"length_wavelengths": length}
    out["cost_long_surface"] |= {
        "ratio_impedance_s_over_pec": med["al_impedance_s"] / med["pec_s"],
        "ratio_impedance_p_over_pec": med["al_impedance_p"] / med["pec_s"],
    }
    return out


def cost_growth(ctx, ax):
    rows = []
    for n in (500, 1000) if ctx.quick else (500, 1000, 2000, 4000):
        row = {"points": n}
        for key, kw in (
            ("pec_p_lu", {"polarization": "p"}),
            ("pec_p_fb", {"polarization": "p", "solver": "fb"}),
            ("glass_s_lu", {"eta": GLASS}),
            ("glass_s_fb", {"eta": GLASS, "solver": "fb"}),
        ):
            if key.startswith("glass") and n > (500 if ctx.quick else 2000):
                continue
            ppw = 15 if key.startswith("glass") else 10  # glass: 10 points per wavelength inside
            x, y = rough_surface(n / ppw, 1 / ppw, 0.3, correlation_length_for_slope(0.3, 0.3), 1)
            sol = solve(x, y, 1.0, TaperedWave(np.radians(30), n / ppw / 4), **kw)
            row[key] = sol.timings["fill"] + sol.timings["solve"]
            row[key + "_solve"] = sol.timings["solve"]
        rows.append(row)
    for key in ("pec_p_lu", "pec_p_fb", "glass_s_lu", "glass_s_fb"):
        sel = [r for r in rows if key in r]
        ax.loglog([r["points"] for r in sel], [r[key] for r in sel], "o-", label=key)
    ax.set(xlabel="surface points N", ylabel="fill + solve [s]", title="cost growth")
    ax.legend(fontsize=7)
    return rows


def run(ctx):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 4, figsize=(20, 4.2))
    with ctx.step("sampling"):
        ctx.metrics["glass_cylinder_sampling"] = sweep_sampling(ctx, axes[0])
    with ctx.step("metals"):
        ctx.metrics["metal_cylinders"] = sweep_metals(ctx, axes[1])
    with ctx.step("taper"):
        ctx.metrics["rough_glass_taper"] = sweep_taper(ctx, axes[2], ctx.rng)
    with ctx.step("impedance_vs_exact"):
        ctx.metrics["impedance_vs_exact"] = imp = impedance_vs_exact(ctx, ctx.rng)
    with ctx.step("cost_growth"):
        ctx.metrics["cost_growth"] = cost_growth(ctx, axes[3])
    ctx.save_figure(fig, "perf_mom_materials")
    cost = imp["cost_long_surface"]
    glass10 = [r for r in ctx.metrics["glass_cylinder_sampling"] if r["ppw_inside"] == 10]
    s_imp, p_imp = imp["s"], imp["p"]
    ctx.say(
        f"Glass cylinder (ka = 10) at 10 points per wavelength inside: relative L2 error "
        f"{glass10[0]['error']:.1e} (s) and {glass10[1]['error']:.1e} (p). On a rough aluminium "
        f"surface the impedance condition differs from the exact formulation by "
        f"{s_imp['relative_l2_difference']:.1e} (s) and {p_imp['relative_l2_difference']:.1e} (p) "
        f"in the scattering coefficient, at {s_imp['impedance_seconds']:.2f} s against "
        f"{s_imp['exact_seconds']:.1f} s. On a {cost['length_wavelengths']:.0f}-wavelength surface "
        "(10 points per wavelength, five incidences) the impedance condition costs "
        f"{cost['ratio_impedance_s_over_pec']:.2f}x (s) and "
        f"{cost['ratio_impedance_p_over_pec']:.2f}x (p) the PEC solve (median of the repeats, "
        "one run)."
    )
    set_verdict(
        ctx,
        "own study",
        f"glass cylinder at 10 points per wavelength inside: error {glass10[0]['error']:.1e} (s), "
        f"{glass10[1]['error']:.1e} (p); impedance vs exact on rough aluminium {s_imp['relative_l2_difference']:.1e} "
        f"(s), {p_imp['relative_l2_difference']:.1e} (p), at {cost['ratio_impedance_s_over_pec']:.2f}x the PEC "
        "solve's cost (s)",
    )
