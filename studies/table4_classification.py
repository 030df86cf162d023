"""Table 4: metal/dielectric classification of the painted plates at theta_i = theta_r = 50 deg, D/r0 = 7.9,
10.5 and 12.9, degraded (DOLP threshold 0.30) against corrected (EM with the Ch. V DOLP priors).

Simulated plates (the reference's were measured): green paint on aluminium and on steel with bare-metal "s"
and "t" strokes and scratches, sigma 0.3, 1550 nm, 4-channel division-of-amplitude polarimeter, one Kolmogorov
screen per acquisition. As in the text the no-turbulence classification is the truth of Table 4's columns; the
true labels are scored too. Each D/r0 is repeated over independent screens (mean and spread reported).
"""

import numpy as np
from scatterlab.studies._common import plate_observations

from scatterlab.characterization.pipeline import interior
from scatterlab.characterization.reference_tables import TABLE4
from scatterlab.deconvolution import PRIOR_SETS, classification_errors
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "table4",
    "title": "Metal/dielectric classification at 50 deg through turbulence (Table 4)",
    "reproduces": "Table 4 (Sec. 5.3.3), Figs. 49-50",
}
COLS = ("false_metal", "false_dielectric", "total_error", "correlation", "rmse")


def run(ctx):
    size, its, reps = (48, 40, 1) if ctx.quick else (128, 250, 3)
    d_r0 = [7.9, 10.5, 12.9]
    with ctx.step("simulate_and_correct"):
        data = plate_observations(
            ctx, 50.0, d_r0, priors=PRIOR_SETS["ch5"], iterations=its, size=size, reps=reps
        )
    sel = interior((size, size), max(2, size // 16))
    lines = [
        "| plate | image | wrongly metal | wrongly dielectric | total [published] | corr. coef. [published] | "
        "RMSE | total vs true labels |",
        "|---|---|---|---|---|---|---|---|",
    ]
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    for ax, (plate, d) in zip(axes, data.items()):
        metal = (d["labels"] > 0).astype(int)
        res = {}
        for x in d_r0:
            for kind in ("degraded", "corrected"):
                key = f"D_r0_{x:g}_{kind}"
                vs_ref = [
                    classification_errors(
                        o[f"D_r0_{x:g}"][kind]["classes"],
                        o["no_turbulence"]["degraded"]["classes"],
                        mask=sel,
                    )
                    for o in d["obs"]
                ]
                vs_lab = [
                    classification_errors(o[f"D_r0_{x:g}"][kind]["classes"], metal, mask=sel)[
                        "total_error"
                    ]
                    for o in d["obs"]
                ]
                mean = {c: float(np.mean([v[c] for v in vs_ref])) for c in COLS}
                mean["spread_total"] = float(np.std([v["total_error"] for v in vs_ref]))
                mean["total_vs_labels"] = float(np.mean(vs_lab))
                res[key] = mean
                pub = TABLE4[plate][key]
                lines.append(
                    f"| {plate} | {key} | {mean['false_metal']:.4f} | {mean['false_dielectric']:.4f} | "
                    f"{mean['total_error']:.4f} +/- {mean['spread_total']:.4f} [{pub[2]:.4f}] | "
                    f"{mean['correlation']:.4f} [{pub[3]:.4f}] | {mean['rmse']:.4f} | {mean['total_vs_labels']:.4f} |"
                )
        res["no_turbulence_vs_labels"] = float(
            np.mean(
                [
                    classification_errors(
                        o["no_turbulence"]["degraded"]["classes"], metal, mask=sel
                    )["total_error"]
                    for o in d["obs"]
                ]
            )
        )
        ctx.metrics[plate] = res
        for kind, mk, col in (("degraded", "o", "C0"), ("corrected", "s", "C1")):
            ax.plot(
                d_r0,
                [res[f"D_r0_{x:g}_{kind}"]["total_error"] for x in d_r0],
                mk + "-",
                color=col,
                label=f"{kind} (ours, simulated)",
            )
            ax.plot(
                d_r0,
                [TABLE4[plate][f"D_r0_{x:g}_{kind}"][2] for x in d_r0],
                mk + "--",
                mfc="none",
                color=col,
                label=f"{kind} (Table 4, measured)",
            )
        ax.set(
            title=f"{plate} plate, 50 deg",
            xlabel="D/r0",
            ylabel="fraction misclassified vs no turbulence",
        )
        ax.legend(fontsize=7)
    ctx.save_figure(fig, "table4_classification")
    ctx.say("\n".join(lines))
    better = {
        p: [
            ctx.metrics[p][f"D_r0_{x:g}_corrected"]["total_error"]
            <= ctx.metrics[p][f"D_r0_{x:g}_degraded"]["total_error"]
            for x in d_r0
        ]
        for p in data
    }
    ctx.metrics["corrected_not_worse"] = better
    ctx.say(
        f"{size}^2 pixels, {its} EM iterations, {reps} screen(s) per D/r0. The corrected classification is at "
        f"least as good as the degraded threshold in {sum(map(sum, better.values()))} of {2 * len(d_r0)} cases. "
        "The reference found the improvement marginal at these D/r0 (total errors 0.04-0.06 either way); on "
        "the simulated plates the errors are larger because the bright metal's diffraction and turbulence halo "
        "lowers the DOLP of paint near the strokes (the no-turbulence image is the truth here, so the "
        f"no-turbulence map itself errs by {ctx.metrics[next(iter(data))]['no_turbulence_vs_labels']:.3f} "
        "against the true labels on the first plate)."
    )
