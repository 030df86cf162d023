"""Figs. 51-52: the near-normal limitation at theta_i = theta_r = 24 deg, and adaptive priors (Sec. 8.1.1).

Near normal incidence every material's DOLP is small (paint about 0.1), so the Ch. V priors (dielectric
centred at 0.65) call the paint metal. The text thresholds its no-turbulence and degraded DOLP at 0.08, read from
the no-turbulence histogram; Sec. 8.1.1 proposes priors re-centred from the histogram. Here the first half of
the EM iterations runs without priors and two-means on that corrected DOLP histogram re-centres the two priors
for the second half. Painted aluminium at D/r0 = 7.9 and painted steel at 12.9 (as the figures), simulated.

Full-mode run time (measured 24 Nov 2026, serial, load average 1.2-1.7 on the shared 2-core
machine): 32 s wall.
"""

import numpy as np
from scatterlab.studies._common import plate_observations, set_verdict

from scatterlab.characterization.pipeline import interior
from scatterlab.deconvolution import PRIOR_SETS, classification_errors
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "fig51_fig52",
    "title": "Near-normal classification (24 deg): fixed against adaptive DOLP priors",
    "reproduces": "Figs. 51-52 (Sec. 5.3.4) and the adaptive priors of Sec. 8.1.1",
}
THRESHOLD = 0.08


def run(ctx):
    size, its = (48, 40) if ctx.quick else (128, 250)
    d_r0 = [[7.9], [12.9]]
    sel = interior((size, size), max(2, size // 16))
    with ctx.step("fixed_priors"):
        fixed = plate_observations(
            ctx, 24.0, d_r0, priors=PRIOR_SETS["ch5"], iterations=its, size=size
        )
    with ctx.step("adaptive_priors"):
        adapt = plate_observations(
            ctx, 24.0, d_r0, priors=PRIOR_SETS["ch5"], iterations=its, size=size, adaptive=True
        )
    pyplot = plt()
    fig, axes = pyplot.subplots(2, 5, figsize=(15, 6.4))
    lines = [
        "| plate | classification | total error vs true labels | paint called metal | metal called paint |",
        "|---|---|---|---|---|",
    ]
    for row, plate in enumerate(fixed):
        labels = fixed[plate]["labels"]
        metal = (labels > 0).astype(int)
        case = f"D_r0_{d_r0[row][0]:g}"
        of, oa = fixed[plate]["obs"][0], adapt[plate]["obs"][0]
        maps = {
            "no turbulence, P < 0.08": (of["no_turbulence"]["degraded"]["dolp"] < THRESHOLD).astype(
                int
            ),
            "degraded, P < 0.08": (of[case]["degraded"]["dolp"] < THRESHOLD).astype(int),
            "corrected, Ch. V priors": (of[case]["corrected"]["classes"] > 0).astype(int),
            "corrected, adaptive priors": (oa[case]["corrected"]["classes"] > 0).astype(int),
        }
        # total error of the trivial map that calls every pixel paint: the metal share
        res = {"all_paint_error": float(metal[sel].mean())}
        for name, m in maps.items():
            e = classification_errors(m, metal, mask=sel)
            paint = sel & (metal == 0)
            res[name] = {
                "total": e["total_error"],
                "paint_called_metal": float(m[paint].mean()),
                "metal_called_paint": float(1 - m[sel & (metal == 1)].mean()),
            }
            lines.append(
                f"| {plate} | {name} | {e['total_error']:.3f} | {res[name]['paint_called_metal']:.3f} | "
                f"{res[name]['metal_called_paint']:.3f} |"
            )
        pr = oa[case]["corrected"]["priors"]
        res["adaptive_centres"] = [p.c3 for p in pr]
        res["adaptive_half_widths"] = [1 / p.c2 for p in pr]
        res["paint_dolp_no_turbulence"] = float(
            np.median(of["no_turbulence"]["degraded"]["dolp"][sel & (metal == 0)])
        )
        ctx.metrics[plate] = res
        axes[row, 0].imshow(of["no_turbulence"]["degraded"]["dolp"], vmin=0, vmax=0.3)
        axes[row, 0].set_title(f"{plate}: DOLP, no turbulence", fontsize=8)
        for j, (name, m) in enumerate(maps.items(), start=1):
            axes[row, j].imshow(m, cmap="gray_r", vmin=0, vmax=1, interpolation="nearest")
            axes[row, j].set_title(
                f"{name}\n(dark = metal), error {res[name]['total']:.2f}", fontsize=8
            )
    for a in axes.ravel():
        a.set_xticks([])
        a.set_yticks([])
    ctx.save_figure(fig, "fig51_fig52")
    ctx.say("\n".join(lines))
    al = ctx.metrics["aluminium"]
    ctx.say(
        f"At 24 deg the paint's no-turbulence DOLP is about {al['paint_dolp_no_turbulence']:.2f}, far below the "
        "Ch. V dielectric prior (0.65 +/- 0.32): the fixed priors call "
        f"{al['corrected, Ch. V priors']['paint_called_metal']:.0%} of the paint metal (aluminium plate) -- the "
        "limitation of Figs. 51i and 52i. Priors re-centred on the corrected DOLP histogram (two-means, centres "
        f"{', '.join(f'{c:.3f}' for c in al['adaptive_centres'])}) bring the error to "
        f"{al['corrected, adaptive priors']['total']:.3f} against {al['corrected, Ch. V priors']['total']:.3f} "
        f"(degraded image thresholded at 0.08: {al['degraded, P < 0.08']['total']:.3f}; no-turbulence image: "
        f"{al['no turbulence, P < 0.08']['total']:.3f})."
    )
    verdict, headline, text = adaptive_verdict(ctx.metrics)
    ctx.say(text)
    set_verdict(ctx, verdict, headline)


def adaptive_verdict(metrics):
    """Verdict, headline and sentence for the adaptive priors, generated from the error table.

    Parameters
    ----------
    metrics : dict
        Per plate (e.g. ``"aluminium"``, ``"steel"``): the rows ``"corrected, Ch. V priors"``,
        ``"corrected, adaptive priors"`` and ``"no turbulence, P < 0.08"`` (each with ``"total"`` and
        ``"paint_called_metal"``) and ``"all_paint_error"`` (total error of calling every pixel paint).

    Returns
    -------
    verdict, headline, text : str
        "reproduced" when the fixed priors call most of the paint metal (the limitation shown) and the
        adaptive priors beat both the fixed priors and the trivial all-paint map on every plate;
        "partly" when the limitation is shown but the adaptive priors miss either; else "not reproduced".
    """
    plates = [k for k, v in metrics.items() if isinstance(v, dict) and "all_paint_error" in v]
    shown = all(metrics[p]["corrected, Ch. V priors"]["paint_called_metal"] > 0.5 for p in plates)
    beats_fixed = [
        p
        for p in plates
        if metrics[p]["corrected, adaptive priors"]["total"]
        < metrics[p]["corrected, Ch. V priors"]["total"]
    ]
    beats_trivial = [
        p
        for p in plates
        if metrics[p]["corrected, adaptive priors"]["total"] < metrics[p]["all_paint_error"]
    ]
    parts = []
    for p in plates:
        m = metrics[p]
        a = m["corrected, adaptive priors"]
        parts.append(
            f"{p}: adaptive {a['total']:.3f} (paint called metal {a['paint_called_metal']:.0%}), "
            f"fixed {m['corrected, Ch. V priors']['total']:.3f}, all-paint map "
            f"{m['all_paint_error']:.3f}, no-turbulence threshold "
            f"{m['no turbulence, P < 0.08']['total']:.3f}"
        )
    n = len(plates)
    text = (
        f"Total errors -- {'; '.join(parts)}. The adaptive priors beat the fixed priors on "
        f"{len(beats_fixed)} of {n} plates and the trivial map that calls every pixel paint on "
        f"{len(beats_trivial)} of {n}"
    )
    if len(beats_trivial) < n:
        text += (
            ": where they do not, the adaptive classification is worse than no classification, "
            "so the correction of Sec. 8.1.1 is not shown to work there."
        )
    else:
        text += "."
    if shown and len(beats_fixed) == n and len(beats_trivial) == n:
        verdict = "reproduced"
    elif shown:
        verdict = "partly"
    else:
        verdict = "not reproduced"
    short = "; ".join(
        f"{p} {metrics[p]['corrected, adaptive priors']['total']:.3f} vs "
        f"{metrics[p]['all_paint_error']:.3f}"
        for p in plates
    )
    headline = (
        f"fixed Ch. V priors call paint metal (limitation {'shown' if shown else 'NOT shown'}); "
        f"adaptive priors beat fixed on {len(beats_fixed)}/{n} plates, the all-paint map on "
        f"{len(beats_trivial)}/{n} (adaptive vs all-paint error: {short})"
    )
    return verdict, headline, text
