"""Table 5 end to end: n and kappa of the painted plates from no-turbulence, degraded and corrected multi-angle
DOLP images (Ch. VII), simulated, against the text's measured Table 5.

Runs the characterization pipeline (the README's main job) on the bundled scene -- painted aluminium and
painted steel at 1550 nm, specular geometries 30-60 deg, D/r0 7.9 and 12.9 -- and compares the per-region
means and standard deviations of the per-pixel least-squares n and kappa with Table 5.
"""

import numpy as np

from scatterlab.characterization import characterize, default_scene
from scatterlab.characterization.reference_tables import TABLE5
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "table5",
    "title": "Characterization of the painted plates through turbulence (Table 5)",
    "reproduces": "Table 5 and Figs. 59-61 (Sec. 7.3)",
}


def run(ctx):
    cfg = default_scene()
    cfg.seed = ctx.seed
    cfg.estimate = [
        "classes",
        "n_kappa",
    ]  # posteriors: the main job's report; here the Table 5 statistics
    if ctx.quick:
        cfg.image_size, cfg.geometry_deg, cfg.iterations = 48, [30, 40, 50, 60], 30
    with ctx.step("characterize"):
        characterize(cfg, ctx.out / "characterization", overwrite=True, executor=ctx.executor)
    import json

    summary = json.loads((ctx.out / "characterization" / "summary.json").read_text())
    keys = ["no_turbulence"] + [
        f"D_r0_{x:g}_{k}" for k in ("degraded", "corrected") for x in cfg.d_over_r0
    ]
    pyplot = plt()
    fig, axes = pyplot.subplots(2, 2, figsize=(11, 7))
    lines = [
        "| plate | region | image | E[n] (sd) [published] | E[kappa] (sd) [published] | |E[n] - n| | "
        "|E[kappa] - kappa| | median per-pixel abs(eta - eta_true) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    truths = {"paint": (cfg.plates[0].paint_n, cfg.plates[0].paint_kappa)}
    for i, plate in enumerate(summary["plates"]):
        p = next(pl for pl in cfg.plates if pl.metal == plate)
        truths[plate] = (p.metal_n, p.metal_kappa)
        ctx.metrics[plate] = {}
        for j, (region, rkey) in enumerate((("paint", "paint"), (plate, "metal"))):
            ax = axes[i, j]
            err = {}
            for x, key in enumerate(keys):
                d = summary["plates"][plate][key][region]
                pub = TABLE5[plate][rkey].get(key)
                tn, tk = truths[region]
                err[key] = {
                    "n_error": abs(d["n_mean"] - tn),
                    "kappa_error": abs(d["kappa_mean"] - tk),
                    **d,
                }
                lines.append(
                    f"| {plate} | {region} | {key} | {d['n_mean']:.3f} ({d['n_std']:.3f})"
                    + (f" [{pub[0]:.3f} ({pub[1]:.3f})]" if pub else "")
                    + f" | {d['kappa_mean']:.3f} ({d['kappa_std']:.3f})"
                    + (f" [{pub[2]:.3f} ({pub[3]:.3f})]" if pub else "")
                    + f" | {err[key]['n_error']:.3f} | {err[key]['kappa_error']:.3f} | "
                    f"{d['index_median_abs_error']:.3f} |"
                )
                ax.errorbar(
                    x - 0.1,
                    d["n_mean"],
                    d["n_std"],
                    fmt="o",
                    color="C0",
                    label="n (ours)" if x == 0 else None,
                )
                ax.errorbar(
                    x + 0.1,
                    d["kappa_mean"],
                    d["kappa_std"],
                    fmt="s",
                    color="C1",
                    label="kappa (ours)" if x == 0 else None,
                )
                if pub:
                    ax.errorbar(
                        x - 0.25,
                        pub[0],
                        pub[1],
                        fmt="o",
                        mfc="none",
                        color="C0",
                        alpha=0.6,
                        label="n (Table 5)" if x == 0 else None,
                    )
                    ax.errorbar(
                        x + 0.25,
                        pub[2],
                        pub[3],
                        fmt="s",
                        mfc="none",
                        color="C1",
                        alpha=0.6,
                        label="kappa (Table 5)" if x == 0 else None,
                    )
            ax.axhline(truths[region][0], color="C0", ls=":")
            ax.axhline(truths[region][1], color="C1", ls=":")
            ax.set_xticks(
                range(len(keys)), [k.replace("_", " ") for k in keys], rotation=25, fontsize=7
            )
            ax.set(
                title=f"{plate} plate, {region} region", ylim=(0, 25 if region != "paint" else 6)
            )
            ax.legend(fontsize=6)
            ctx.metrics[plate][region] = err
    ctx.save_figure(fig, "table5")
    ctx.add_image("characterization/aluminium")
    ctx.add_image("characterization/steel")
    ctx.say("\n".join(lines))
    paint = {
        k: float(
            np.mean(
                [ctx.metrics[pl]["paint"][k]["index_median_abs_error"] for pl in summary["plates"]]
            )
        )
        for k in keys
    }
    kappa = {
        k: float(np.mean([ctx.metrics[pl]["paint"][k]["kappa_error"] for pl in summary["plates"]]))
        for k in keys
    }
    ctx.metrics["paint_index_median_abs_error"] = paint
    ctx.metrics["paint_kappa_mean_error"] = kappa
    ctx.say(
        "Paint, averaged over both plates -- median per-pixel |eta - eta_true|: "
        + ", ".join(f"{k} {v:.2f}" for k, v in paint.items())
        + "; |E[kappa] - 0.34|: "
        + ", ".join(f"{k} {v:.2f}" for k, v in kappa.items())
        + ". Correction brings the paint's kappa and "
        "complex index back toward the no-turbulence values at both D/r0, as the text's corrected rows do "
        "(its degraded paint n 2.24-2.38, corrected 1.28-1.39). The bare metals stay poorly determined "
        "(n pinned at the bounds in many pixels): Rs ~ Rp at 30-60 deg leaves their DOLP small, the reason the "
        "text gives for its metal errors. The pipeline's own report (characterization/report.md) gives the "
        "DOLP, S0 and classification errors behind these numbers."
    )
