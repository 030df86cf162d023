"""pBRDF throughput: in-plane DOLP, the 3x3 block and the full 4x4 Mueller matrix, against pySCATMECH.

Ours: vectorised evaluations per second at N geometries on one core. Peer: NIST SCATMECH's
Shadowed_Facet_BRDF_Model through pySCATMECH, one call per geometry (its interface), on a subset of the
same geometries; the results are compared element by element (relative to m00) so the ratio is at equal
results. Goals (issue 3): >= 20x the peer's evaluations per second, >= 1e6 in-plane DOLP per second.

Measured 29 Nov 2026 (serial, shared 2-core machine at load average 2.0-2.7; three runs each,
alternating with the code before that day's speed-ups, commit c5926e8; median and range): quick
mode in-plane DOLP x33.4 (32.7-35.3), DOLP (any geometry) x27.1 (27.1-28.9), 3x3 x30.5
(29.9-31.3), 4x4 x27.4 (25.6-29.2); full mode x32.9 (32.5-33.9), x27.6 (27.3-27.9), x29.7
(29.6-30.5), x28.0 (27.4-28.1); the peer 3.9e5-4.1e5 matrices per second. Before: x17.3, x11.6,
x13.8, x12.5 (quick) and x17.3, x11.7, x14.1, x13.3 (full). Full-mode run time 1.7-1.8 s (3.0-3.2
s before).
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.pbrdf import Model
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.runtime import best_time

STUDY = {
    "id": "perf_pbrdf",
    "title": "pBRDF throughput against pySCATMECH",
    "reproduces": "own benchmark",
}


def run(ctx):
    n = 2 * 10**5 if ctx.quick else 10**6
    n_peer = 300 if ctx.quick else 3000
    rng = ctx.rng
    eta, sigma = 3.6 - 5.88j, 0.3
    s_peer = float(f"{np.sqrt(2) * sigma:.6g}")
    sigma = s_peer / np.sqrt(2)  # the peer parses 6 significant digits
    ti = rng.uniform(np.radians(10), np.radians(85), n)
    tr = rng.uniform(np.radians(10), np.radians(85), n)
    ph = rng.uniform(0, 2 * np.pi, n)
    model = Model(sigma)
    spec = Model(sigma, diffuse="none")  # the peer has no diffuse term
    model.dolp(eta, ti[:10], tr[:10])
    ours = {}
    with ctx.step("ours"):
        ours["in-plane DOLP"] = n / best_time(lambda: model.dolp(eta, ti, tr), repeat=3)
        ours["DOLP (any geometry)"] = n / best_time(lambda: model.dolp(eta, ti, tr, ph), repeat=3)
        ours["3x3"] = n / best_time(lambda: spec.mueller_linear(eta, ti, tr, ph), repeat=3)
        ours["4x4"] = n / best_time(lambda: spec.mueller(eta, ti, tr, ph), repeat=3)
    for k, v in ours.items():
        ctx.metrics[f"ours_evals_per_s_{k}"] = v
    try:
        from pySCATMECH.brdf import BRDF_Model
    except ImportError:
        ctx.say("pySCATMECH is not installed (test extra): only our throughput is reported.")
        peer_rate = None
    else:
        peer = BRDF_Model(
            "Shadowed_Facet_BRDF_Model",
            substrate=complex(eta.real, -eta.imag),
            sdf="Gaussian_Slope_Distribution_Function",
            shadow="Torrance_Sparrow_Shadow_Function",
        )
        peer.setParameter("sdf.s", s_peer)
        D = np.diag([1.0, 1, -1, 1])

        def peer_all():
            return [
                peer.MuellerBRDF(a, b, np.pi - c)
                for a, b, c in zip(ti[:n_peer], tr[:n_peer], ph[:n_peer])
            ]

        with ctx.step("peer"):
            peer_rate = n_peer / best_time(peer_all, repeat=3)
            S = D @ np.array([np.array(m) for m in peer_all()]) @ D
        F = spec.mueller(eta, ti[:n_peer], tr[:n_peer], ph[:n_peer])
        ok = S[:, 0, 0] > 1e-250
        diff = float(np.max(np.abs(F[ok] - S[ok]) / S[ok, 0, 0][:, None, None]))
        ctx.metrics["peer_evals_per_s"] = peer_rate
        ctx.metrics["max_difference_relative_to_m00"] = diff
        for k, v in ours.items():
            ctx.metrics[f"ratio_{k}"] = v / peer_rate
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6.5, 3.5))
    names = list(ours)
    ax.bar(range(len(names)), [ours[k] for k in names], label="scatterlab (vectorised, 1 core)")
    if peer_rate:
        ax.axhline(peer_rate, color="r", label="pySCATMECH (per call)")
        ax.axhline(20 * peer_rate, color="r", ls="--", label="goal: 20x peer")
    ax.axhline(1e6, color="k", ls=":", label="goal: 1e6 in-plane DOLP/s")
    ax.set_xticks(range(len(names)), names, fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("evaluations / s")
    ax.legend(fontsize=7)
    ctx.save_figure(fig, "perf_pbrdf")
    text = (
        "Evaluations per second at {:.0e} geometries: ".format(n)
        + ", ".join(f"{k} {v:.2g}" for k, v in ours.items())
        + "."
    )
    if peer_rate:
        text += (
            f" pySCATMECH: {peer_rate:.2g} Mueller matrices per second (per-call interface), at a maximum "
            f"difference of {ctx.metrics['max_difference_relative_to_m00']:.1e} of m00. Ratios: "
            + ", ".join(f"{k} x{ours[k] / peer_rate:.1f}" for k in ours)
            + "."
        )
        short = [k for k in ours if ours[k] / peer_rate < 20]
        if short:
            text += (
                " Below the 20x goal: "
                + ", ".join(short)
                + " -- the numpy implementation is bound by "
                "memory passes over ~100 temporaries per element; a compiled kernel would be needed to go "
                "further."
            )
    ctx.say(text)
    headline = f"in-plane DOLP {ours['in-plane DOLP']:.2g}/s (goal >= 1e6/s)"
    if peer_rate:
        headline += (
            f"; vs pySCATMECH (per call): 4x4 Mueller {ours['4x4'] / peer_rate:.1f}x, 3x3 "
            f"{ours['3x3'] / peer_rate:.1f}x (goal >= 20x) at max difference "
            f"{ctx.metrics['max_difference_relative_to_m00']:.1e} of m00"
        )
    else:
        headline += "; pySCATMECH not installed, no peer ratio"
    set_verdict(ctx, "own study", headline)
