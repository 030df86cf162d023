"""MoM against its asymptotic limits, both polarizations.

(a) Small roughness (k sigma_h = 0.1, l = 1 wavelength, theta_i = 30 deg): the incoherent MoM
    scattering coefficient against first-order perturbation theory (SPM1) for the PEC and for
    glass (n = 1.5), SPM1 evaluated both with the Gaussian spectrum (ensemble) and with the
    realizations' own periodograms (the same incoherent estimator on both sides, a control
    variate that removes most of the Monte-Carlo scatter).
(b) Large smooth bodies: PEC circular cylinders of growing ka against physical optics
    (Kirchhoff) in the reflection zone (120-180 deg), and the back-scatter against the
    geometric-optics pi a.

Quick mode: fewer realizations and radii (about 30 s); full mode about 3 minutes.
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.mom.asymptotics import compare_physical_optics, compare_spm1
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "mom_limits",
    "title": "MoM vs first-order perturbation theory and physical optics",
    "reproduces": "own validation: small-roughness and smooth limits",
}

GLASS = 1.5


def run(ctx):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 3, figsize=(16, 4.2))
    spm = {}
    with ctx.step("spm1"):
        for j, (pol, eta) in enumerate((("s", None), ("p", None), ("s", GLASS), ("p", GLASS))):
            count, length = (8, 20.0) if ctx.quick else ((32, 30.0) if eta is None else (16, 20.0))
            out = compare_spm1(pol, eta, count, length, ctx.rng)
            th, incoh, ref, ens = (out[k] for k in ("theta_s", "mom", "spm1", "spm1_ensemble"))
            name = f"{pol}_{'pec' if eta is None else 'glass'}"
            spm[name] = {
                "realizations": count,
                "total_ratio_to_spm1_periodogram": out["ratio"],
                "total_ratio_jackknife_se": out["ratio_se"],
                "total_ratio_to_spm1_ensemble": float(
                    np.trapezoid(incoh, th) / np.trapezoid(ens, th)
                ),
            }
            ax = axes[0] if eta is None else axes[1]
            ax.semilogy(np.degrees(th), incoh, color=f"C{j}", label=f"MoM {pol}")
            ax.semilogy(np.degrees(th), ref, "--", color=f"C{j}", label=f"SPM1 {pol}")
    for ax, what in zip(axes[:2], ("PEC", "glass n=1.5")):
        ax.set(xlabel="theta_s [deg]", ylabel="incoherent coefficient [1/rad]", title=what)
        ax.legend(fontsize=7)
    ctx.metrics["spm1"] = spm
    po = {}
    kas = (10, 30) if ctx.quick else (10, 20, 40, 60, 100)
    with ctx.step("physical_optics"):
        for pol in ("s", "p"):
            rows = [compare_physical_optics(pol, ka) for ka in kas]
            po[pol] = [
                {"ka": ka, "l2_vs_po": r[0], "back_over_pi_a": r[1]} for ka, r in zip(kas, rows)
            ]
            axes[2].loglog(kas, [r[0] for r in rows], "o-", label=f"{pol}-pol")
    axes[2].set(xlabel="ka", ylabel="rel. L2 MoM vs PO (120-180 deg)", title="PEC cylinder")
    axes[2].legend(fontsize=7)
    ctx.metrics["physical_optics"] = po
    ctx.save_figure(fig, "mom_limits")
    ratios = {k: v["total_ratio_to_spm1_periodogram"] for k, v in spm.items()}
    ctx.say(
        "Small roughness (k sigma_h = 0.1): the incoherent power the MoM scatters is "
        + ", ".join(
            f"{v['total_ratio_to_spm1_periodogram']:.3f} +- {v['total_ratio_jackknife_se']:.3f}"
            for v in spm.values()
        )
        + f" times SPM1's ({', '.join(ratios)}; SPM1 on the realizations' own periodograms; +- the "
        "jackknife standard error over the realizations, "
        + ", ".join(f"{v['realizations']}" for v in spm.values())
        + " of them), and "
        + ", ".join(f"{v['total_ratio_to_spm1_ensemble']:.2f}" for v in spm.values())
        + " times the ensemble SPM1 (Monte-Carlo scatter of the few realizations). "
        f"Large PEC cylinders approach physical optics in the reflection zone: relative L2 "
        f"{po['s'][0]['l2_vs_po']:.3f} -> {po['s'][-1]['l2_vs_po']:.4f} (s) and "
        f"{po['p'][0]['l2_vs_po']:.3f} -> {po['p'][-1]['l2_vs_po']:.3f} (p) from ka = {kas[0]} to "
        f"{kas[-1]}; back-scatter / (pi a) = {po['s'][-1]['back_over_pi_a']:.4f} (s), "
        f"{po['p'][-1]['back_over_pi_a']:.4f} (p) at ka = {kas[-1]}. Kirchhoff omits the "
        "shadow-boundary and creeping currents, which are stronger for the p-pol (Neumann) "
        "problem, so p converges more slowly."
    )
    set_verdict(
        ctx,
        "own study",
        "MoM / SPM1 incoherent power "
        + ", ".join(
            f"{k} {v['total_ratio_to_spm1_periodogram']:.3f} +- {v['total_ratio_jackknife_se']:.3f}"
            for k, v in spm.items()
        )
        + f"; PEC cylinder vs physical optics at ka {kas[-1]}: relative L2 {po['s'][-1]['l2_vs_po']:.3f} (s), "
        f"{po['p'][-1]['l2_vs_po']:.3f} (p)",
    )
