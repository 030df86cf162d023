"""Throughput of vectorised Fresnel reflectances and Jones-to-Mueller conversion.

Benchmark, not a test: evaluations per second at 10^6 elements for
``fresnel.reflectances`` and ``polarization.jones_to_mueller``, compared in the
same run with a straightforward per-element Python loop (cmath for Fresnel, the
explicit Eq. 133 sums for the Mueller matrix) timed on a subset and scaled. The
loop results are also compared with the vectorised ones (max abs difference),
so the speed-up is at equal results.

Full-mode run time (measured 24 Nov 2026, serial, load average 4.0-3.9 on the shared 2-core
machine): 8 s wall.
"""

import cmath
import math

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab import fresnel, polarization
from scatterlab.runtime import best_time

STUDY = {
    "id": "perf_fresnel",
    "title": "Vectorised Fresnel and Jones-to-Mueller throughput vs a Python loop",
    "reproduces": "own benchmark",
}


def _loop_reflectances(eta, theta):
    out = []
    for e, t in zip(eta, theta):
        c = math.cos(t)
        u = cmath.sqrt(e * e - math.sin(t) ** 2)
        if u.imag > 0:
            u = -u if u.real <= 0 else u.conjugate()
        rs = (c - u) / (c + u)
        rp = (e * e * c - u) / (e * e * c + u)
        out.append((abs(rs) ** 2, abs(rp) ** 2))
    return out


def _loop_mueller(J):
    out = []
    for j in J:
        a, b, c, d = j[0, 0], j[0, 1], j[1, 0], j[1, 1]
        M = [[0.0] * 4 for _ in range(4)]
        M[0][0] = 0.5 * (abs(a) ** 2 + abs(b) ** 2 + abs(c) ** 2 + abs(d) ** 2)
        M[0][1] = 0.5 * (abs(a) ** 2 + abs(c) ** 2 - abs(b) ** 2 - abs(d) ** 2)
        M[2][2] = (a * d.conjugate()).real + (b * c.conjugate()).real
        M[2][3] = (a * d.conjugate()).imag - (b * c.conjugate()).imag
        out.append(M)
    return out


def run(ctx):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = 10**5 if ctx.quick else 10**6
    n_loop = 2 * 10**3 if ctx.quick else 2 * 10**4
    rng = ctx.rng
    eta = rng.uniform(0.1, 5, n) - 1j * rng.uniform(0, 10, n)
    theta = rng.uniform(0, np.pi / 2, n)
    J = rng.normal(size=(n, 2, 2)) + 1j * rng.normal(size=(n, 2, 2))
    res = {}
    with ctx.step("fresnel"):
        t_vec = best_time(lambda: fresnel.reflectances(eta, theta), repeat=3)
        t_loop = best_time(
            lambda: _loop_reflectances(eta[:n_loop].tolist(), theta[:n_loop].tolist()), repeat=3
        )
        Rs, Rp = fresnel.reflectances(eta[:n_loop], theta[:n_loop])
        ref = np.array(_loop_reflectances(eta[:n_loop].tolist(), theta[:n_loop].tolist()))
        res["fresnel"] = (n / t_vec, n_loop / t_loop, float(np.max(np.abs(ref - np.c_[Rs, Rp]))))
    with ctx.step("jones_to_mueller"):
        t_vec = best_time(lambda: polarization.jones_to_mueller(J), repeat=3)
        t_loop = best_time(lambda: _loop_mueller(J[:n_loop]), repeat=3)
        Mv = polarization.jones_to_mueller(J[:n_loop])
        Ml = np.array(_loop_mueller(J[:n_loop]))
        keep = [(0, 0), (0, 1), (2, 2), (2, 3)]
        diff = max(float(np.max(np.abs(Mv[:, i, k] - Ml[:, i, k]))) for i, k in keep)
        # the loop computes 4 of 16 elements; scale its time to the full matrix conservatively (x1)
        res["jones_to_mueller"] = (n / t_vec, n_loop / t_loop, diff)
    for name, (vec, loop, diff) in res.items():
        ctx.metrics[f"{name}_evals_per_s"] = vec
        ctx.metrics[f"{name}_loop_evals_per_s"] = loop
        ctx.metrics[f"{name}_speedup"] = vec / loop
        ctx.metrics[f"{name}_max_abs_diff_vs_loop"] = diff
    ctx.metrics["n_elements"] = n
    fig, ax = plt.subplots(figsize=(5, 3))
    names = list(res)
    ax.bar(np.arange(2) - 0.2, [res[k][0] for k in names], 0.4, label="vectorised")
    ax.bar(np.arange(2) + 0.2, [res[k][1] for k in names], 0.4, label="Python loop")
    ax.set_xticks(range(2), names)
    ax.set_yscale("log")
    ax.set_ylabel("evaluations / s")
    ax.legend()
    ctx.save_figure(fig, "throughput")
    ctx.say(
        f"At {n:.0e} elements: Fresnel reflectances {res['fresnel'][0]:.3g}/s vectorised vs "
        f"{res['fresnel'][1]:.3g}/s in a Python loop (x{res['fresnel'][0] / res['fresnel'][1]:.0f}, max abs "
        f"difference {res['fresnel'][2]:.1e}); Jones-to-Mueller {res['jones_to_mueller'][0]:.3g}/s (all 16 "
        f"elements) vs {res['jones_to_mueller'][1]:.3g}/s for a loop computing only 4 elements "
        f"(x{res['jones_to_mueller'][0] / res['jones_to_mueller'][1]:.0f}). Ratios measured in the same run."
    )
    mt = ctx.metrics
    set_verdict(
        ctx,
        "own study",
        f"at {n:.0e} elements, vectorised vs Python loop: Fresnel {mt['fresnel_speedup']:.0f}x "
        f"({mt['fresnel_evals_per_s']:.2g}/s, max difference {mt['fresnel_max_abs_diff_vs_loop']:.1e}), "
        f"Jones-to-Mueller {mt['jones_to_mueller_speedup']:.0f}x (difference "
        f"{mt['jones_to_mueller_max_abs_diff_vs_loop']:.1e})",
    )
