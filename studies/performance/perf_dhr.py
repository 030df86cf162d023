"""DHR accuracy against run time: quadrature order, and table size vs interpolation error.

(a) The slope-space quadrature of scatterlab.pbrdf.dhr with n Gauss-Legendre nodes per piece (outer and inner)
against a 48-node reference; error is the maximum absolute difference over 19 angles, time is per angle.
(b) The (theta, ln sigma) spline table of each shadowing function at several grid sizes: maximum error against
the quadrature at random points (relative where the unshadowed DHR exceeds 1), build time, and lookup time per
point (2-D spline and the per-model 1-D cache). (c) Smith shadowing, tabulated since issue 20: pBRDF time per
geometry with the shipped table against the per-point quadrature it used before, in one run.

Full-mode run time (measured 24 Nov 2026, serial, load average 2.3-2.0 on the shared 2-core
machine): 155 s wall.
"""

import time

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.pbrdf import PEC, Model, dhr_beckmann, dhr_table
from scatterlab.pbrdf.dhr import DHRTable
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.runtime import best_time

STUDY = {
    "id": "perf_dhr",
    "title": "DHR quadrature order and table size: error against run time",
    "reproduces": "own performance study",
}


def run(ctx):
    pyplot = plt()
    fig, (ax1, ax2) = pyplot.subplots(1, 2, figsize=(11, 4))
    theta = np.radians(np.linspace(0, 89.9, 19))
    orders = (6, 8, 12, 16, 24) if ctx.quick else (6, 8, 10, 12, 16, 20, 24, 32)
    quad = {}
    with ctx.step("quadrature"):
        for sigma in (0.01, 0.3, 1.0):
            ref = dhr_beckmann(theta, sigma, n_outer=48, n_inner=48)
            errs, times = [], []
            for n in orders:
                t = (
                    best_time(lambda: dhr_beckmann(theta, sigma, n_outer=n, n_inner=n), repeat=3)
                    / theta.size
                )
                errs.append(
                    float(np.max(np.abs(dhr_beckmann(theta, sigma, n_outer=n, n_inner=n) - ref)))
                )
                times.append(t)
            quad[sigma] = (errs, times)
            ax1.loglog(times, np.maximum(errs, 1e-17), "o-", label=rf"$\sigma$ = {sigma}")
            ctx.metrics[f"quadrature_error_sigma{sigma}"] = dict(zip(map(str, orders), errs))
            ctx.metrics[f"quadrature_time_per_angle_s_sigma{sigma}"] = dict(
                zip(map(str, orders), times)
            )
    ax1.set(xlabel="time per angle [s]", ylabel="max |error|", title="quadrature nodes per piece")
    ax1.legend()
    rows, smith = _tables(ctx, ax2)
    model = Model(0.3)
    model.dhr_pec(0.1)
    big_t = ctx.rng.uniform(0, np.pi / 2, 10**5)
    ctx.metrics["lookup_1d_cache_s_per_point"] = (
        best_time(lambda: model.dhr_pec(big_t), repeat=3) / big_t.size
    )
    ax2.set(
        xlabel="build time [s]",
        ylabel="max |error| at random points",
        title="table size (2 pieces)",
    )
    ax2.legend(fontsize=7)
    ctx.metrics["tables"] = rows
    ctx.metrics["smith"] = smith
    ctx.save_figure(fig, "perf_dhr")
    e16 = {s: quad[s][0][orders.index(16)] for s in quad}
    ctx.say(
        "Quadrature: spectral convergence once the integral is split at the kinks and folds of the shadowing "
        f"function; 16 nodes per piece (the default) give errors {e16[0.01]:.1e}, {e16[0.3]:.1e}, {e16[1.0]:.1e} "
        f"for sigma = 0.01, 0.3, 1.0 at {quad[0.3][1][orders.index(16)] * 1e3:.1f} ms per angle."
    )
    ctx.say(
        "Tables (shadowing n_theta x n_sigma: max error at random points / build time / lookup per point): "
        + "; ".join(
            f"{r['shadowing']} {r['n_theta']}x{r['n_sigma']}: {r['max_error']:.1e} / "
            f"{r['build_s']:.1f} s / {r['lookup_s_per_point'] * 1e9:.0f} ns"
            for r in rows
        )
        + f". The shipped tables are 65x121 (stated error <= 1e-6, 1.5e-6 at cell centres for 'none'); "
        f"a model with scalar sigma resamples its table once into a 1-D cache: "
        f"{ctx.metrics['lookup_1d_cache_s_per_point'] * 1e9:.0f} ns per lookup."
    )
    ctx.say(
        f"Smith shadowing with a diffuse term: {smith['model_s_per_geometry'] * 1e6:.2f} us per geometry "
        f"(shipped table) against {smith['quadrature_s_per_angle'] * 1e3:.1f} ms for the per-point quadrature "
        f"it used before, a ratio of {smith['speedup']:.0f} (Torrance-Sparrow: "
        f"{smith['torrance_sparrow_s_per_geometry'] * 1e6:.2f} us, ratio "
        f"{smith['ratio_to_torrance_sparrow']:.2f}); the shipped Smith table's error at "
        f"{smith['n_points']} random points is {smith['shipped_max_error']:.1e}."
    )
    set_verdict(
        ctx,
        "own study",
        f"16 nodes per piece: DHR error <= {max(e16.values()):.1e} at "
        f"{quad[0.3][1][orders.index(16)] * 1e3:.1f} ms per angle; Smith table {smith['speedup']:.0f}x faster "
        f"than the quadrature (error {smith['shipped_max_error']:.1e})",
    )


def _tables(ctx, ax):
    """Table size against interpolation error (vs quadrature at random points) for every shadowing."""
    quick = ctx.quick
    rng = ctx.rng
    n_pts = 40 if quick else 400
    th = rng.uniform(0, np.radians(89.5), n_pts)
    sg = np.exp(rng.uniform(np.log(1e-3), np.log(1.5), n_pts))
    plans = {
        "torrance-sparrow": ((17, 31), (33, 61))
        if quick
        else ((17, 31), (33, 61), (49, 91), (65, 121)),
        "none": ((17, 31),) if quick else ((17, 31), (33, 61), (49, 91), (65, 121)),
        "smith": ((17, 31),) if quick else ((17, 31), (33, 61), (65, 121)),
    }
    rows = []
    refs = {}
    with ctx.step("tables"):
        for shadowing, sizes in plans.items():
            ref = np.array([dhr_beckmann(a, b, shadowing) for a, b in zip(th, sg)])
            refs[shadowing] = ref
            errs, builds = [], []
            for nt, ns in sizes:
                t0 = time.perf_counter()
                table = DHRTable(shadowing, n_theta=nt, n_sigma=ns, cache=False)
                build = time.perf_counter() - t0
                err = float(np.max(np.abs(table(th, sg) - ref) / np.maximum(1.0, ref)))
                big_t = rng.uniform(0, np.pi / 2, 10**5)
                lookup = best_time(lambda: table(big_t, 0.3), repeat=3) / big_t.size
                rows.append(
                    {
                        "shadowing": shadowing,
                        "n_theta": nt,
                        "n_sigma": ns,
                        "max_error": err,
                        "build_s": build,
                        "lookup_s_per_point": lookup,
                    }
                )
                errs.append(err)
                builds.append(build)
            ax.loglog(builds, errs, "s-", label=shadowing)
    with ctx.step("smith"):
        shipped = float(np.max(np.abs(dhr_table("smith")(th, sg) - refs["smith"])))
        m = Model(0.3, shadowing="smith")
        ti, tr = rng.uniform(0, 1.5, 10**4), rng.uniform(0, 1.5, 10**4)
        ph = rng.uniform(0, 2 * np.pi, 10**4)
        per_geometry = best_time(lambda: m.mueller(PEC, ti, tr, ph), repeat=3) / ti.size
        ts = Model(0.3)
        ts_geometry = best_time(lambda: ts.mueller(PEC, ti, tr, ph), repeat=3) / ti.size
        quad_t = best_time(lambda: dhr_beckmann(th[:10], 0.3, "smith"), repeat=3) / 10
        smith = {
            "shipped_max_error": shipped,
            "n_points": n_pts,
            "model_s_per_geometry": per_geometry,
            "torrance_sparrow_s_per_geometry": ts_geometry,
            "quadrature_s_per_angle": quad_t,
            "speedup": quad_t / per_geometry,
            "ratio_to_torrance_sparrow": per_geometry / ts_geometry,
        }
    return rows, smith
