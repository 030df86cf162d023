"""Fig. 55: three-class classification (aluminium group / iron group / dielectric) with the Ch. VI priors, at
theta_i = theta_r = 55 deg; painted aluminium at D/r0 = 7.9, painted steel at 12.9 (Figs. 54-55), simulated.

The text gives no numbers for Fig. 55, only statements: the steel plate's classification is
"excellent" and the aluminium plate's errors sit at scratches and at the metal/paint boundary. The
study measures both (correct fraction; share of the errors within 2 pixels of a boundary) and says
which hold. Scratches are not simulated (isotropic pBRDF). A class map with a single class does not
classify, and the report says so instead of scoring it; every correct fraction is shown beside that of
a map calling every pixel paint. The claims rest on REALIZATIONS (4) independent turbulence and noise
draws of each plate, not on one: the S0 error's change after correction (Fig. 54) is called a gain, and
the aluminium errors concentrated at the boundary, only where the 95 % Student t interval of the mean
over the draws excludes no gain (or the 1.5x enrichment). With one draw, a seed survey found the
verdict "partly" on 8 of 13 seeds and "not reproduced" on 5, and the S0 claims swapping plates. Run
time on the shared 2-core machine: quick 5.8 s (29 Nov 2026, 4 draws); full (128 px, 250 iterations)
about 80 s.
"""

import numpy as np
from scatterlab.studies._common import plate_observations, set_verdict, t_factor

from scatterlab.characterization.pipeline import interior
from scatterlab.characterization.report import CLASS_COLOURS
from scatterlab.deconvolution import PRIOR_SETS
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "fig55",
    "title": "Aluminium / iron / dielectric classification through turbulence (Ch. VI)",
    "reproduces": "Figs. 54-55 (Sec. 6.3)",
}
NAMES = ("dielectric", "aluminium group", "iron group")


def run(ctx):
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    size, its = (48, 40) if ctx.quick else (128, 250)
    d_r0 = [[7.9], [12.9]]
    priors = PRIOR_SETS["ch6"]  # (dielectric, aluminium, iron)
    sel = interior((size, size), max(2, size // 16))
    with ctx.step("simulate_and_correct"):
        data = plate_observations(
            ctx, 55.0, d_r0, priors=priors, iterations=its, size=size, reps=REALIZATIONS
        )
    pyplot = plt()
    fig, axes = pyplot.subplots(2, 3, figsize=(10, 6.8), layout="constrained")
    cmap = ListedColormap(CLASS_COLOURS[: len(NAMES)])  # categorical: one colour per class
    lines = ["| plate | image | region | " + " | ".join(NAMES) + " |", "|---|---|---|---|---|---|"]
    expected = {"aluminium": 1, "steel": 2}
    for row, (plate, d) in enumerate(data.items()):
        labels = d["labels"]
        edge = _boundary_band(labels, 2)
        case = f"D_r0_{d_r0[row][0]:g}"
        o = d["obs"][0]
        # the score of a map calling every pixel paint: what a one-class map gets for nothing
        res = {"all_paint_correct": float(np.sum(sel & (labels == 0)) / sel.sum())}
        for j, (name, cls) in enumerate(
            (
                ("no turbulence", o["no_turbulence"]["degraded"]["classes"]),
                ("degraded", o[case]["degraded"]["classes"]),
                ("corrected", o[case]["corrected"]["classes"]),
            )
        ):
            frac = {}
            for region, rsel in (
                ("paint", sel & (labels == 0)),
                ("bare metal", sel & (labels > 0)),
            ):
                f = np.bincount(cls[rsel], minlength=3) / rsel.sum()
                frac[region] = f.tolist()
                lines.append(
                    f"| {plate} | {name} | {region} | " + " | ".join(f"{v:.3f}" for v in f) + " |"
                )
            correct = (
                np.sum(cls[sel & (labels == 0)] == 0)
                + np.sum(cls[sel & (labels > 0)] == expected[plate])
            ) / sel.sum()
            frac["correct"] = float(correct)
            frac["classes_present"] = [NAMES[c] for c in np.unique(cls[sel])]
            wrong = sel & (((labels == 0) & (cls != 0)) | ((labels > 0) & (cls != expected[plate])))
            frac["boundary_pixel_share"] = float(np.sum(sel & edge) / sel.sum())
            frac["error_share_at_boundary"] = (
                float(np.sum(wrong & edge) / np.sum(wrong)) if wrong.any() else float("nan")
            )
            res[name] = frac
            axes[row, j].imshow(
                cls,
                cmap=cmap,
                vmin=-0.5,
                vmax=len(NAMES) - 0.5,
                interpolation="nearest",
            )
            one = frac["classes_present"]
            axes[row, j].set_title(
                f"{plate}: {name}\n"
                + (
                    f"one class only ({one[0]}): no classification"
                    if len(one) == 1
                    else f"{correct:.0%} correct"
                ),
                fontsize=8,
            )
            axes[row, j].set_xticks([])
            axes[row, j].set_yticks([])
        # Fig. 54 and the boundary share over the independent turbulence and noise realizations: one
        # realization's numbers move with the seed by several times any within-image error (a seed
        # survey: the S0 change -0.125 on one seed, -0.034 on another)
        changes, enrichment = [], []
        for ob in d["obs"]:
            ref = ob["no_turbulence"]["degraded"]["s0"]
            err = {k: _rel_rmse(ob[case][k]["s0"], ref, sel) for k in ("degraded", "corrected")}
            changes.append(err["corrected"] - err["degraded"])
            cls = ob[case]["corrected"]["classes"]
            wrong = sel & (((labels == 0) & (cls != 0)) | ((labels > 0) & (cls != expected[plate])))
            band = np.sum(sel & edge) / sel.sum()
            if wrong.any():
                enrichment.append(float(np.sum(wrong & edge) / np.sum(wrong) / band))
        ref = o["no_turbulence"]["degraded"]["s0"]
        for kind in ("degraded", "corrected"):  # the first realization's, shown in the figure
            res[f"s0_rel_rmse_{kind}"] = _rel_rmse(o[case][kind]["s0"], ref, sel)
        res["s0_rel_rmse_change_reps"] = changes
        res["s0_rel_rmse_change_mean"] = float(np.mean(changes))
        res["s0_rel_rmse_change_se"] = _mean_se(changes)
        res["boundary_enrichment_reps"] = enrichment
        ctx.metrics[plate] = res
    ctx.metrics["realizations"] = REALIZATIONS
    fig.legend(
        handles=[Patch(facecolor=c, edgecolor="k", label=n) for c, n in zip(CLASS_COLOURS, NAMES)],
        loc="outside lower center",
        ncol=len(NAMES),
        fontsize=9,
        title="class",
        title_fontsize=9,
    )
    ctx.save_figure(fig, "fig55")
    ctx.say(
        "Fractions of each region given each class (0 dielectric, 1 aluminium group, 2 iron group; the "
        "no-turbulence and degraded maps take the class of largest prior density at the measured DOLP):\n\n"
        + "\n".join(lines)
    )
    _findings(ctx, sel, data)


def _rel_rmse(x, ref, sel):
    """RMSE of ``x`` against ``ref`` over ``sel``, both scaled to unit mean there, over rms(ref)."""
    a, b = x[sel] / np.mean(x[sel]), ref[sel] / np.mean(ref[sel])
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def _mean_se(values):
    """Standard error of the mean of independent realizations' values (NaN with fewer than two)."""
    v = np.asarray(values, float)
    return float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else float("nan")


def _boundary_band(labels, width):
    """Pixels within ``width`` pixels of the metal/paint boundary, (N, N) bool."""
    from scipy import ndimage

    metal = labels > 0
    return ndimage.binary_dilation(metal, iterations=width) & ~ndimage.binary_erosion(
        metal, iterations=width
    )


IMAGES = ("no turbulence", "degraded", "corrected")


def _findings(ctx, sel, data):
    m = ctx.metrics
    al, st = m["aluminium"], m["steel"]
    edge_share = al["corrected"]["error_share_at_boundary"]
    steel_one = _one_class(st["corrected"])
    excellent = st["corrected"]["correct"] >= 0.95 and not steel_one
    band_share = al["corrected"]["boundary_pixel_share"]
    edge_label, enrichment = boundary_concentration(edge_share, band_share)
    reps_label, reps_mean, reps_half = boundary_over_realizations(al["boundary_enrichment_reps"])
    at_edges = reps_label == "concentrated"
    s0_text, s0_labels = s0_change_text(m, ("aluminium", "steel"), m["realizations"])
    for p, label in s0_labels.items():
        m[p]["s0_change"] = label
    ctx.say(
        "Correct fraction after correction: "
        + ", ".join(
            f"{p} plate {_score(m[p]['corrected'])} (degraded {_score(m[p]['degraded'])}, "
            f"no turbulence {_score(m[p]['no turbulence'])})"
            for p in ("aluminium", "steel")
        )
        + ". "
        + baseline_text(m, ("aluminium", "steel"))
        + " The text calls the steel result excellent: "
        + (
            "ours is at least 95 % correct, consistent. "
            if excellent
            else f"ours is a single class ({st['corrected']['classes_present'][0]}), no "
            "classification at all: NOT excellent. "
            if steel_one
            else f"ours is {1 - st['corrected']['correct']:.1%} wrong, NOT excellent. "
        )
        + "The text puts the aluminium errors at scratches and at the metal/paint boundary: "
        + (
            f"{edge_share:.0%} of our corrected aluminium errors lie within 2 pixels of the "
            f"boundary, a band holding {band_share:.0%} of the pixels: "
            + (
                "consistent (the halo of the bright metal lowers the paint's DOLP and the "
                "paint's light raises the metal's)"
                if at_edges
                else "our errors are "
                + ("only borderline" if edge_label == "borderline" else "NOT")
                + " concentrated at the boundary "
                f"({enrichment:.2f}x the band's pixel share; concentrated needs >= "
                f"{ENRICHMENT:g}x and at least min(50 %, twice the band share)) (paint wrongly "
                f"classified: {1 - al['corrected']['paint'][0]:.0%}, bare metal wrongly "
                f"classified: {1 - al['corrected']['bare metal'][1]:.0%})"
            )
            if np.isfinite(edge_share)
            else "our corrected aluminium map has no errors"
        )
        + f". Over {len(al['boundary_enrichment_reps'])} turbulence realizations the enrichment is "
        f"{reps_mean:.2f} +/- {reps_half:.2f} (95 %, Student t): "
        + (
            f"concentrated (above {ENRICHMENT:g}x)"
            if reps_label == "concentrated"
            else f"NOT concentrated (below {ENRICHMENT:g}x)"
            if reps_label == "not concentrated"
            else f"not determined (the interval contains {ENRICHMENT:g}x), so not shown"
        )
        + ". "
        + s0_text
        + " Scratches (which polarise like a wire grid) need an anisotropic surface model the "
        "isotropic pBRDF does not have, so that error source is not simulated."
    )
    verdict = (
        "reproduced"
        if excellent and at_edges
        else "partly"
        if excellent or at_edges
        else "not reproduced"
    )
    set_verdict(
        ctx,
        verdict,
        f"correct after correction: Al {_score(al['corrected'], 2)}, steel "
        f"{_score(st['corrected'], 2)} (text: steel excellent); Al errors within 2 px of "
        f"the boundary {edge_share:.0%}, a band of {band_share:.0%} of the pixels "
        f"({enrichment:.2f}x; over {m['realizations']} realizations {reps_mean:.2f} +/- "
        f"{reps_half:.2f}: {reps_label})",
    )


def _one_class(frac):
    """Whether a class map gives every scored pixel the same class."""
    return len(frac["classes_present"]) == 1


def _score(frac, digits=3):
    """A map's correct fraction, or what it is when the map has one class only."""
    if _one_class(frac):
        return "one class only"
    return f"{frac['correct']:.{digits}f}"


def baseline_text(m, plates):
    """Sentences on the maps that do not classify: a single class over the whole plate, or no
    better than calling every pixel paint.

    Parameters
    ----------
    m : dict
        The study's metrics: per plate ``all_paint_correct`` and, per image of :data:`IMAGES`,
        ``correct`` and ``classes_present``.
    plates : sequence of str

    Returns
    -------
    str
    """
    single, below = [], []
    for p in plates:
        for name in IMAGES:
            frac = m[p][name]
            if _one_class(frac):
                single.append((p, name, frac))
            elif frac["correct"] <= m[p]["all_paint_correct"]:
                below.append(f"{p} {name} ({frac['correct']:.3f})")
    out = (
        "A map calling every pixel paint would score "
        + ", ".join(f"{m[p]['all_paint_correct']:.3f} on the {p} plate" for p in plates)
        + "."
    )
    for p in plates:
        maps = [(name, frac) for q, name, frac in single if q == p]
        if maps:
            out += " " + _single_class_text(p, maps)
    if below:
        out += " No better than calling every pixel paint: " + ", ".join(below) + "."
    return out


def _single_class_text(plate, maps):
    """The sentence on a plate's single-class maps, ``maps`` [(image name, fractions)]."""
    names = [name for name, _ in maps]
    many = len(maps) > 1
    keys = [(f["classes_present"][0], f"{f['correct']:.3f}") for _, f in maps]

    def share(cls, score):
        truly = "paint" if cls == NAMES[0] else cls
        return f"{score} correct is only the share of the plate that truly is {truly}"

    if len(set(keys)) == 1:
        scores = f"{'their' if many else 'its'} {share(*keys[0])}"
    else:
        scores = "; ".join(f"the {name} map's {share(*k)}" for name, k in zip(names, keys))
    return (
        f"The {plate} plate's {' and '.join(names)} map{'s' if many else ''} "
        f"ha{'ve' if many else 's'} a single class: every scored pixel is "
        f"{' or '.join(sorted({k[0] for k in keys}))} (paint and bare metal alike in the table), "
        f"so {'they do' if many else 'it does'} not classify; {scores}, not a classification "
        "result."
    )


def s0_change_label(change, se, k=2.0):
    """Whether the change of the S0 error after correction exceeds k standard errors.

    Parameters
    ----------
    change, se : float
        Corrected minus degraded relative RMSE, and its standard error.
    k : float
        Coverage factor.

    Returns
    -------
    str
        "lower" or "higher" beyond k standard errors, else "within noise" (also when either is
        not finite).
    """
    if not (np.isfinite(change) and np.isfinite(se)) or abs(change) <= k * se:
        return "within noise"
    return "lower" if change < 0 else "higher"


def s0_change_text(m, plates, reps, k=None):
    """The Fig. 54 sentence: the S0 error degraded -> corrected per plate, the mean change over the
    realizations with its standard error, and whether the correction lowered it beyond k standard
    errors on every plate.

    Parameters
    ----------
    m : dict
        The study's metrics: per plate ``s0_rel_rmse_degraded``, ``s0_rel_rmse_corrected`` (the
        first realization's), ``s0_rel_rmse_change_mean`` and ``s0_rel_rmse_change_se`` (over the
        realizations).
    plates : sequence of str
    reps : int
        Number of realizations.
    k : float, optional
        Coverage factor (default: the 95 % Student t factor of ``reps`` realizations).

    Returns
    -------
    text : str
    labels : dict
        {plate: "lower" | "higher" | "within noise"}
    """
    k = t_factor(reps) if k is None else k
    labels, parts = {}, []
    for p in plates:
        d, c = m[p]["s0_rel_rmse_degraded"], m[p]["s0_rel_rmse_corrected"]
        change, se = m[p]["s0_rel_rmse_change_mean"], m[p]["s0_rel_rmse_change_se"]
        labels[p] = s0_change_label(change, se, k)
        parts.append(f"{p} {d:.3f} -> {c:.3f} (mean change {change:+.3f} +/- {se:.3f})")
    lower = [p for p in plates if labels[p] == "lower"]
    higher = [p for p in plates if labels[p] == "higher"]
    noise = [p for p in plates if labels[p] == "within noise"]
    if higher:
        verdict = (
            f"higher after correction on the {' and '.join(higher)} plate by more than {k:.2f} "
            "standard errors, contrary to the text"
        )
    elif not noise:
        verdict = (
            f"lower after correction on every plate by more than {k:.2f} standard errors: the "
            "correction restores detail the turbulence removed, as the text says"
        )
    elif lower:
        verdict = (
            f"lower by more than {k:.2f} standard errors on the {' and '.join(lower)} plate, as the "
            f"text says; on the {' and '.join(noise)} plate the change is within noise (at most "
            f"{k:.2f} standard errors), so this run does not show the correction restoring detail "
            "there"
        )
    else:
        verdict = (
            f"the change is within noise (at most {k:.2f} standard errors) on every plate, so this "
            "run does not show the correction restoring detail"
        )
    text = (
        "Fig. 54 (S0): relative RMSE against the no-turbulence S0, degraded -> corrected (the "
        f"figure's realization; the mean change over {reps} independent turbulence and noise "
        "realizations +/- its standard error, judged at "
        f"{k:.2f} standard errors, the 95 % Student t factor): "
        + "; ".join(parts)
        + f": {verdict}."
    )
    return text, labels


ENRICHMENT = 1.5  # error share / band pixel share needed to call the errors concentrated
REALIZATIONS = (
    4  # independent turbulence and noise draws per plate: the claims rest on their spread
)


def boundary_over_realizations(enrichments):
    """Whether the corrected aluminium errors concentrate at the boundary, over the realizations.

    Parameters
    ----------
    enrichments : sequence of float
        Each realization's error share in the boundary band over the band's pixel share.

    Returns
    -------
    label : str
        "concentrated" when the mean's 95 % Student t interval lies above :data:`ENRICHMENT`,
        "not concentrated" when it lies below, "not determined" when it contains it (or fewer than
        two realizations have errors).
    mean, half : float
        The mean and the interval's half width.
    """
    v = np.asarray(enrichments, float)
    if v.size < 2:
        return "not determined", float(np.mean(v)) if v.size else float("nan"), float("inf")
    mean, half = float(v.mean()), t_factor(v.size) * _mean_se(v)
    if mean - half >= ENRICHMENT:
        return "concentrated", mean, half
    if mean + half < ENRICHMENT:
        return "not concentrated", mean, half
    return "not determined", mean, half


def boundary_concentration(edge_share, band_share):
    """Whether the classification errors concentrate in the boundary band.

    Parameters
    ----------
    edge_share : float
        Fraction of the errors inside the band (NaN when there are no errors).
    band_share : float
        Fraction of all pixels inside the band.

    Returns
    -------
    label : str
        "concentrated" (share >= ENRICHMENT x band share and >= min(0.5, 2 x band share)),
        "borderline" (enrichment within 20 % below ENRICHMENT), "not concentrated", or
        "no errors".
    enrichment : float
        edge_share / band_share (NaN without errors).
    """
    if not np.isfinite(edge_share):
        return "no errors", float("nan")
    ratio = edge_share / band_share if band_share > 0 else float("inf")
    if ratio >= ENRICHMENT and edge_share >= min(0.5, 2 * band_share):
        return "concentrated", ratio
    if ratio >= 0.8 * ENRICHMENT:
        return "borderline", ratio
    return "not concentrated", ratio
