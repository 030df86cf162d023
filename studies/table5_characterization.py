"""Table 5 end to end: n and kappa of the painted plates from no-turbulence, degraded and corrected multi-angle
DOLP images (Ch. VII), simulated, against the text's measured Table 5.

Runs the characterization pipeline (the README's main job) on the bundled scene -- painted aluminium and
painted steel at 1550 nm, specular geometries 30-60 deg, D/r0 7.9 and 12.9 -- and compares the per-region
means and standard deviations of the per-pixel least-squares n and kappa with Table 5.

Like for like: the text's 250 deconvolution iterations (full mode; quick 30), roughness sigma = 0.3
known to the inversion, the same value table5_synthetic uses (deviation: the text's samples have
sigma < 1 deg, measured from the specular lobe width). The text's central result is compared as a
number: the paint's per-pixel scatter (sd of n) shrinks 2.0-4.2x from degraded to corrected; so are
the metals' mean kappa under turbulence. Run time: quick (48 px, 3 angles, 30 iterations) 45 s measured at
load ~3.7 on the shared 2-core machine; full (128 px, 7 angles, 250 iterations): 260 s wall with ``--workers 2``
(28 Nov 2026, three blind starts, the scene default). Verdict "not reproduced": the paint's scatter of n shrinks
1.22x, 0.58x, 1.16x and 1.12x from degraded to corrected (aluminium D/r0 7.9, 12.9, steel 7.9, 12.9; none
reaches the text's 2x), and the corrected metals' mean kappa is 53 % and 62 % below the published values for
aluminium, 13 % above and 15 % below for steel. The run with one blind start (24 Nov 2026, 186 s) had 1.1x,
0.5x, 2.3x and 2.2x, verdict "partly": averaging the starts' restorations lowered the corrected S0 and DOLP
errors of the default run, but the paint's per-pixel n scatters about as much as in the degraded image, and
more for aluminium at D/r0 12.9 (sd 0.77 against 0.44). The corrected paint's per-pixel means are within
0.07-0.23 of the truth in n (the report's table).
"""

import numpy as np
from scatterlab.studies._common import compare, set_verdict

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
        cfg.image_size, cfg.geometry_deg, cfg.iterations = 48, [30, 45, 60], 30
    else:
        cfg.iterations = 250  # the text's deconvolution iterations (Figs. 49 and 54)
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
                # null in summary.json (NaN): no pixel of the eroded region was measured at every
                # geometry (a small image whose alignment shifted it beyond the field); shown as nan
                d = {
                    q: (np.nan if v is None else v)
                    for q, v in summary["plates"][plate][key][region].items()
                }
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
    if any("| nan" in line for line in lines):
        ctx.say(
            "nan: no pixel of that region was measured at every geometry (the alignment shifted it beyond "
            "the camera's field), so its per-pixel statistics are undefined."
        )
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
    _findings(ctx, summary, cfg)


def _shrink_text(kept, total):
    """Whether the paint's scatter shrink is reproduced: in all, none or ``kept`` of ``total``."""
    if kept == total:
        return f"Reproduced in all {total} cases. "
    if kept == 0:
        return "NOT reproduced in any case. "
    return f"Reproduced in {kept} of {total} cases, NOT in the other {total - kept}. "


def _findings(ctx, summary, cfg):
    """The text's central numbers against ours: paint scatter shrink factor, metal kappa."""
    m = ctx.metrics
    shrink, kap = [], []
    for plate in summary["plates"]:
        for x in cfg.d_over_r0:
            deg, cor = f"D_r0_{x:g}_degraded", f"D_r0_{x:g}_corrected"
            pub = TABLE5[plate]["paint"]
            ours = m[plate]["paint"][deg]["n_std"] / max(m[plate]["paint"][cor]["n_std"], 1e-12)
            shrink.append(
                compare(
                    f"{plate} D/r0 {x:g} paint sd(n) degraded/corrected",
                    pub[deg][1] / pub[cor][1],
                    ours,
                )
            )
            pk = TABLE5[plate]["metal"][cor][2]
            kap.append(
                compare(
                    f"{plate} D/r0 {x:g} corrected metal E[kappa]",
                    pk,
                    m[plate][plate][cor]["kappa_mean"],
                )
            )
    m["paint_scatter_shrink"] = shrink
    m["metal_kappa_corrected"] = kap
    ratio = [c["ours"] for c in shrink]
    pub_ratio = [c["published"] for c in shrink]
    rel = [c["diff"] / c["published"] for c in kap]
    kept = sum(1 for c in shrink if c["ours"] >= 2.0)
    ctx.say(
        "The text's central result, the paint's per-pixel scatter of n shrinking after correction: "
        f"published {min(pub_ratio):.1f}-{max(pub_ratio):.1f}x, ours "
        + ", ".join(f"{r:.2f}x" for r in ratio)
        + f" ({kept} of {len(ratio)} cases reach the text's lower end, 2x). "
        + _shrink_text(kept, len(ratio))
        + "Corrected metal kappa against Table 5: "
        + "; ".join(
            f"{c['name'].split(' corrected')[0]} ours {c['ours']:.2f}, published "
            f"{c['published']:.2f} "
            + (f"({r:+.0%})" if np.isfinite(r) else "(no metal pixel fitted: no mean)")
            for c, r in zip(kap, rel)
        )  # fmt: skip
        + (
            f". Quick mode ({cfg.image_size} px, {len(cfg.geometry_deg)} angles, {cfg.iterations} "
            "iterations) is not like for like; the full mode is"
            if ctx.quick
            else ""
        )
        + ". The text gives no uncertainty of its means beyond the per-pixel sd, and its plates "
        "are measured (oxide, calibration), ours simulated with the literature indices "
        f"({', '.join(f'{p.metal} {p.metal_n} - j{p.metal_kappa}' for p in cfg.plates)}), so the "
        "metal comparison is against a different truth; the table lists our errors against ours. "
        "Bare metals stay poorly determined (Rs ~ Rp at 30-60 deg leaves their DOLP small, the "
        "text's reason). The pipeline's report (characterization/report.md) has the DOLP, S0 and "
        "classification errors behind these numbers."
    )
    # a case whose corrected metal has no fitted pixel has no mean (NaN): said, not min/max'ed into nan
    finite = [r for r in rel if np.isfinite(r)]
    kappa_range = (
        f"{min(finite):+.0%}..{max(finite):+.0%} vs published"
        if finite
        else "not measured (no metal pixel fitted)"
    ) + (
        f" ({len(rel) - len(finite)} of {len(rel)} without a mean)"
        if len(finite) < len(rel)
        else ""
    )
    set_verdict(
        ctx,
        "reproduced" if kept == len(ratio) else "partly" if kept else "not reproduced",
        f"paint sd(n) shrink {min(ratio):.1f}-{max(ratio):.1f}x (published "
        f"{min(pub_ratio):.1f}-{max(pub_ratio):.1f}x); corrected metal kappa {kappa_range}",
    )
