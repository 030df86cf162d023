"""Table 4: metal/dielectric classification of the painted plates at theta_i = theta_r = 50 deg, D/r0 = 7.9,
10.5 and 12.9, degraded (DOLP threshold 0.30) against corrected (EM with the Ch. V DOLP priors), each
refined by linear unmixing of the Stokes images (:func:`scatterlab.deconvolution.classify_unmixing`).

Simulated plates (the reference's were measured): green paint on aluminium and on steel with bare-metal "s"
and "t" strokes and scratches, sigma 0.3, 1550 nm, 4-channel division-of-amplitude polarimeter, one Kolmogorov
screen per acquisition. As in the text the no-turbulence classification is the truth of Table 4's columns; the
true labels are scored too. Each D/r0 is repeated over independent screens (mean and spread reported).

Like for like: the text's "wrongly metal" and "wrongly dielectric" columns are normalised by the size of
the true class (its totals imply a constant dielectric share c = 0.60 for aluminium, 0.51 for steel;
data/reference/table4_classification.csv), so the study reports the same class-size-normalised rates,
``false_metal_rate`` (per true dielectric pixel) and ``false_dielectric_rate`` (per true metal pixel)
of :func:`scatterlab.deconvolution.classification_errors` -- the columns
``scatterlab.characterization.metrics.score_plate`` reports -- and the total as a fraction of all
pixels, with our own metal share beside the text's implied one. Deviations: simulated plates, the
interior of the image only, and (quick) 48 px and 40 EM iterations instead of the text's 250.
Whether correcting helps is judged on the paired change (corrected minus degraded, the same screens),
with the spread over the screens: quick mode runs 4 screens per D/r0, because with one screen only the
pixel-binomial error was left, about a third of the screen-to-screen scatter, and "at least as good in
6 of 6" on one seed read "4 of 6" on another (seed survey, 28 Nov 2026).
Run time on the shared 2-core machine: quick (4 screens) 16-19 s at load ~4; full (128 px, 250
iterations, 4 screens, as many as quick mode since 29 Nov 2026) 99 s with ``--workers 2`` at load ~1 (3
screens: 175 s at load ~7).

Full run of 29 Nov 2026 (seed 20101210, 4 screens, the unmixed classes and overlap registration): verdict
"partly". Total errors 0.059-0.186 corrected and 0.110-0.348 degraded against the published 0.040-0.058 (1.3-6.1
x); 3 of 12 rows lie inside Student's t for 4 screens (3.18) times the combined uncertainty. Correcting helps:
the paired change over the 6 cases is -0.107 +/- 0.016 (95 %), and each case is better beyond its own 95 %
interval (-0.051 to -0.162). The dominant error type agrees with the text in 5 of 12 rows.

Rows and error types decided by their intervals (29 Nov 2026). A seed survey of quick mode (seeds 1-8) gave
"not reproduced" on 7 seeds and "partly" on seed 5, whose only row "inside" was aluminium D/r0 7.9 corrected
at 3.9 x the published total, 3.0 of its u from it with Student t 3.18: a band (0.12) three times the
published total (0.040) cannot tell agreement from a factor 4. A row now agrees only when it lies inside a
band narrower than the published total (:func:`_row_status`; the rest inside are "not resolved"), and the
dominant error type counts as published or opposite only where the 95 % interval of the paired per-screen
difference of the two rates excludes zero (:func:`_dominant`; it was the sign of the mean, and read 0-3 of
12 over the survey). Survey after the change: "not reproduced" on all 8 seeds, 0 of 12 rows agreeing (seed
5: 1 not resolved), the dominant type shown as published in 0 and opposite in 5-8 of 12. Full mode re-run
(seed 20101210, ``--workers 2``, 150 s wall, 191 s CPU at load ~2.5): "partly" as before, 2 of 12 rows agree
(D/r0 7.9 corrected, both plates; aluminium D/r0 10.5 corrected, 0.109 against 0.056, is inside a band of
0.067: not resolved), the dominant type as published in 1 of 12, opposite in 5, not resolved in 6 (the old
"5 of 12" counted signs of means within the noise). Quick mode run time: 24-35 s CPU, 20-47 s as the
runner measures it with two runs sharing the 2 cores (27-80 s wall under other load).

Full runs of 27 Nov 2026 (seed 20101210), total error against the no-turbulence classification at D/r0
7.9 / 10.5 / 12.9 (the published 0.040-0.058), with the registration by circular or overlap correlation:

| | Al degraded | Al corrected | steel degraded | steel corrected |
|---|---|---|---|---|
| DOLP classes, circular | 0.35 / 0.43 / 0.45 | 0.20 / 0.31 / 0.33 | 0.20 / 0.24 / 0.25 | 0.11 / 0.19 / 0.20 |
| unmixed, overlap | 0.12 / 0.25 / 0.26 | 0.065 / 0.13 / 0.12 | 0.13 / 0.24 / 0.28 | 0.090 / 0.14 / 0.15 |

The corrected images are still 1.5-2.9 times the published totals. This plate's strokes and scratches are
thin next to the blur at D/r0 10.5-12.9, so most pixels are mixed, and what remains is paint called metal
beside them and metal called paint inside them. (With the materials' vectors taken over eroded regions
instead of the purest fifth, steel's degraded totals were 0.21 / 0.35 / 0.37.)
"""

import numpy as np
from scatterlab.studies._common import (
    compare,
    paired_change,
    plate_observations,
    set_verdict,
    t_factor,
)

from scatterlab.characterization.pipeline import interior
from scatterlab.characterization.reference_tables import TABLE4
from scatterlab.deconvolution import PRIOR_SETS, classification_errors
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "table4",
    "title": "Metal/dielectric classification at 50 deg through turbulence (Table 4)",
    "reproduces": "Table 4 (Sec. 5.3.3), Figs. 49-50",
}
COLS = (
    "false_metal_rate",
    "false_dielectric_rate",
    "total_error",
    "correlation",
    "rmse",
    "metal_share",
)
IMPLIED_METAL_SHARE = {"aluminium": 0.40, "steel": 0.49}


def run(ctx):
    size, its, reps = (48, 40, 4) if ctx.quick else (128, 250, 4)
    d_r0 = [7.9, 10.5, 12.9]
    with ctx.step("simulate_and_correct"):
        data = plate_observations(
            ctx, 50.0, d_r0, priors=PRIOR_SETS["ch5"], iterations=its, size=size, reps=reps
        )
    sel = interior((size, size), max(2, size // 16))
    k_cover = t_factor(reps) if reps > 1 else 2.0  # 95 % for a spread over `reps` screens
    lines = [
        "| plate | image | wrongly metal (per dielectric px) [published] | wrongly dielectric (per metal "
        "px) [published] | total [published] | corr. coef. [published] | metal share [implied] | "
        "total vs true labels |",
        "|---|---|---|---|---|---|---|---|",
    ]
    cmp, dominant = [], []
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 2, figsize=(10, 4.4), sharey=True, layout="constrained")
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
                mean["spread_total"] = float(
                    np.std([v["total_error"] for v in vs_ref], ddof=min(1, reps - 1))
                )
                mean["per_screen_total"] = [float(v["total_error"]) for v in vs_ref]
                mean["per_screen_dielectric_minus_metal"] = [
                    float(v["false_dielectric_rate"] - v["false_metal_rate"]) for v in vs_ref
                ]
                mean["total_vs_labels"] = float(np.mean(vs_lab))
                u = max(mean["spread_total"] / np.sqrt(reps), _binomial_u(mean["total_error"], sel))
                mean["u_total"] = float(u)
                res[key] = mean
                pub = TABLE4[plate][key]
                lines.append(
                    f"| {plate} | {key} | {mean['false_metal_rate']:.4f} [{pub[0]:.4f}] | "
                    f"{mean['false_dielectric_rate']:.4f} [{pub[1]:.4f}] | "
                    f"{mean['total_error']:.4f} +/- {u:.4f} [{pub[2]:.4f}] | "
                    f"{mean['correlation']:.4f} [{pub[3]:.4f}] | {mean['metal_share']:.3f} "
                    f"[{IMPLIED_METAL_SHARE[plate]:.2f}] | {mean['total_vs_labels']:.4f} |"
                )
                cmp.append(
                    compare(
                        f"{plate} {key} total error", pub[2], mean["total_error"], 0.0, u, k=k_cover
                    )
                )
                dominant.append(
                    _dominant(mean["per_screen_dielectric_minus_metal"], pub[1] > pub[0])
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
            ax.errorbar(
                d_r0,
                [res[f"D_r0_{x:g}_{kind}"]["total_error"] for x in d_r0],
                yerr=[res[f"D_r0_{x:g}_{kind}"]["u_total"] for x in d_r0],
                fmt=mk + "-",
                color=col,
                capsize=3,
                label=f"{kind} (ours, simulated; +- u as in the table)",
            )
            ax.plot(
                d_r0,
                [TABLE4[plate][f"D_r0_{x:g}_{kind}"][2] for x in d_r0],
                mk + "--",
                mfc="none",
                color=col,
                label=f"{kind} (Table 4, measured)",
            )
        ax.set(title=f"{plate} plate, 50 deg", xlabel="D/r0")
    axes[0].set_ylabel("fraction misclassified vs no turbulence")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=8)
    ctx.save_figure(fig, "table4_classification")
    ctx.say("\n".join(lines))
    change = {p: [_paired_change(ctx.metrics[p], x, sel) for x in d_r0] for p in data}
    ctx.metrics["corrected_minus_degraded"] = change
    tally = _change_tally(change)
    for c in cmp:
        c["status"] = _row_status(c)
    ctx.metrics["comparisons"] = cmp
    ctx.metrics["dominant_error_type"] = dominant
    inside = sum(c["status"] == "agrees" for c in cmp)
    unresolved = sum(c["status"] == "not resolved" for c in cmp)
    as_pub, opposite = dominant.count("as published"), dominant.count("opposite")
    ratio = [c["ours"] / c["published"] for c in cmp]
    kinds = [f"D_r0_{x:g}_{k}" for x in d_r0 for k in ("degraded", "corrected")]
    shares = {p: np.mean([ctx.metrics[p][k]["metal_share"] for k in kinds]) for p in data}
    ctx.say(
        f"{size}^2 pixels, {its} EM iterations, {reps} screen(s) per D/r0. Total error against the "
        f"text: {inside} of {len(cmp)} rows agree, inside {k_cover:.2f} x the combined uncertainty (ours, the +/- in "
        f"the table: the standard deviation over the {reps} screen(s) / sqrt({reps}), at least the "
        "pixel-binomial error, which underestimates it because errors cluster; the text gives "
        f"none) with a band narrower than the published total; {len(cmp) - inside - unresolved} lie "
        f"outside it and {unresolved} are not resolved (inside, "
        "but with a band wider than the published total itself, which cannot tell that total from "
        "zero or from twice it: not counted as agreement); ours is "
        f"{min(ratio):.1f}-{max(ratio):.1f} x the published total. "
        + _share_text(shares, IMPLIED_METAL_SHARE)
        + " The dominant error type (wrongly dielectric vs wrongly metal, per class; decided where "
        "the 95 % interval of their paired difference over the screens excludes zero) is as in the "
        f"text in {as_pub} of {len(dominant)} rows, the opposite in {opposite}, not resolved in "
        f"{len(dominant) - as_pub - opposite}. Corrected against degraded "
        f"(the same screens, so the change is paired): {tally} (the text: marginal changes, totals "
        "0.040-0.058 either way). " + _cause(ctx.metrics, data, d_r0, size)
    )
    set_verdict(
        ctx,
        "reproduced"
        if inside == len(cmp)
        else "partly"
        if inside or 2 * as_pub >= len(dominant)
        else "not reproduced",
        f"total error {min(ratio):.1f}-{max(ratio):.1f} x published (0.040-0.058); {inside}/{len(cmp)} "
        f"agree within {k_cover:.2f}u"
        + (f" ({unresolved} more inside a band too wide to resolve)" if unresolved else "")
        + "; dominant error type shown as published "
        f"in {as_pub}/{len(dominant)}, opposite in {opposite}/{len(dominant)}",
    )


def _row_status(c):
    """A total-error comparison (:func:`studies._common.compare`): "agrees" when ours lies inside its
    band and the band is narrower than the published total (so the comparison could tell that total
    from zero or from twice it), "not resolved" when inside a wider band, "differs" when outside."""
    if not c["inside"]:
        return "differs"
    return "agrees" if c["band"] < abs(c["published"]) else "not resolved"


def _dominant(per_screen_diff, published_dielectric):
    """Whether our dominant error type is the text's, from the per-screen differences of the two
    rates (wrongly dielectric minus wrongly metal, per class): "as published" or "opposite" where the
    95 % interval of their mean excludes zero (:func:`studies._common.paired_change`), else "not
    resolved" (always with one screen)."""
    d = np.asarray(per_screen_diff, float)
    w = paired_change(np.zeros_like(d), d)["word"]
    if w == "no change resolved":
        return "not resolved"
    return "as published" if (w == "higher") == bool(published_dielectric) else "opposite"


def _paired_change(res, x, sel):
    """Corrected minus degraded total error at D/r0 ``x`` and its standard error.

    Both images come from the same screens, so the standard error is that of the mean paired difference
    over the screens (at least the pixel-binomial error of the two totals, which is all one screen gives).

    Parameters
    ----------
    res : dict
        One plate's metrics (``D_r0_<x>_<kind>`` with ``total_error`` and ``per_screen_total``).
    x : float
        D/r0.
    sel : ndarray of bool, shape (H, W)
        Scored pixels.

    Returns
    -------
    dict
        ``d_r0``, ``change`` (corrected minus degraded, a fraction of the scored pixels), ``se`` and
        ``factor``, the 95 % coverage factor (Student t over the screens; 2 for one screen's binomial error).
    """
    deg, cor = res[f"D_r0_{x:g}_degraded"], res[f"D_r0_{x:g}_corrected"]
    c = paired_change(deg["per_screen_total"], cor["per_screen_total"])
    binom = np.hypot(_binomial_u(deg["total_error"], sel), _binomial_u(cor["total_error"], sel))
    several = len(deg["per_screen_total"]) > 1
    return {
        "d_r0": x,
        "change": c["mean"],
        "se": float(max(c["se"] if several else 0.0, binom)),
        "factor": c["half_width"] / c["se"] if several else 2.0,
        "per_screen": np.subtract(cor["per_screen_total"], deg["per_screen_total"]).tolist(),
    }


def _change_tally(changes):
    """Say how the corrected classification compares with the degraded one: the mean change over all
    cases and, per case, whether it is better, worse, or neither beyond the 95 % interval of its paired
    change.

    Parameters
    ----------
    changes : dict
        ``{plate: [_paired_change(...) per D/r0]}``.

    Returns
    -------
    str
        The sentence. The mean's standard error treats the plates as independent and, within a plate,
        the screen repetitions: the D/r0 of one repetition are scored against the same no-turbulence
        classification, so they are averaged per repetition first. With one repetition it falls back
        to the cases' own errors, taken as independent.
    """
    flat = [c for cs in changes.values() for c in cs]
    reps = min(len(c["per_screen"]) for c in flat)
    if reps > 1:
        per_plate = [np.mean([c["per_screen"] for c in cs], axis=0) for cs in changes.values()]
        means = [float(np.mean(v)) for v in per_plate]
        ses = [float(np.std(v, ddof=1) / np.sqrt(v.size)) for v in per_plate]
        mean = float(np.mean(means))
        se = float(np.sqrt(np.sum(np.square(ses))) / len(ses))
        half = t_factor(reps) * se
    else:
        mean = float(np.mean([c["change"] for c in flat]))
        se = float(np.sqrt(np.sum([c["se"] ** 2 for c in flat])) / len(flat))
        half = 2.0 * se
    better = sum(c["change"] < -c["factor"] * c["se"] for c in flat)
    worse = sum(c["change"] > c["factor"] * c["se"] for c in flat)
    word = "better" if mean + half < 0 else "worse" if mean - half > 0 else "no change resolved"
    return (
        f"on average over the {len(flat)} cases {mean:+.3f} +/- {half:.3f} (95 %; {word}); case by "
        f"case better beyond its 95 % interval in {better} of {len(flat)}, worse in {worse}, and within "
        f"the noise in {len(flat) - better - worse} (changes +/- their 95 % half-widths: "
        + ", ".join(f"{c['change']:+.3f} +/- {c['factor'] * c['se']:.3f}" for c in flat)
        + "; a count of cases crossing their thresholds moves with the draw, the mean is the stable "
        "statement)"
    )


def _share_text(ours, implied, tol=0.05):
    """Whether the totals are like for like: they are fractions of all pixels, so they weight the
    two per-class rates by the metal share, ours (``{plate: share}``) against the text's implied
    one; shares differing by more than ``tol`` make the totals not comparable in that respect."""
    off = [p for p in ours if abs(ours[p] - implied[p]) > tol]
    shares = "; ".join(f"{p} {ours[p]:.3f} against {implied[p]:.2f}" for p in ours)
    if not off:
        return (
            f"Our metal share matches the text's implied one within {tol} ({shares}), so the "
            "totals weight the two rates alike."
        )
    return (
        "The totals are fractions of all pixels, so they weight the two rates by the metal share: "
        f"ours against the text's implied ({shares}) differs by more than {tol} for "
        f"{', '.join(off)}, so there the totals are not like for like (the per-class rates are)."
    )


def _binomial_u(p, sel):
    """Pixel-binomial standard error of an error fraction ``p`` over the scored pixels ``sel``."""
    return float(np.sqrt(max(p * (1 - p), 1e-12) / max(int(np.sum(sel)), 1)))


def _cause(metrics, data, d_r0, size):
    """What the numbers say about the excess error: truth map or paint/metal confusion (``size``: image
    side [pixels])."""
    keys = [f"D_r0_{x:g}_{k}" for x in d_r0 for k in ("degraded", "corrected")]
    parts = []
    for plate in data:
        fm = np.mean([metrics[plate][k]["false_metal_rate"] for k in keys])
        fd = np.mean([metrics[plate][k]["false_dielectric_rate"] for k in keys])
        parts.append(
            f"{plate}: no-turbulence map vs true labels {metrics[plate]['no_turbulence_vs_labels']:.3f}, "
            f"mean wrongly-metal rate {fm:.2f}, wrongly-dielectric rate {fd:.2f}"
        )
    return (
        "Where the excess comes from: " + "; ".join(parts) + ". The truth map is not the cause "
        "where its own error is small next to the totals; the excess is paint classified as metal "
        "(and, on steel, metal as paint): through turbulence the bright metal's halo spreads over the "
        "paint and mixes the two DOLPs. How far that reaches relative to the plate depends on the "
        f"image size ({size} px here, 48 in quick mode and 128 in full); the study does not separate that "
        "effect."
    )
