"""Table 5 end to end: n and kappa of the painted plates from no-turbulence, degraded and corrected multi-angle
DOLP images (Ch. VII), simulated, against the text's measured Table 5.

Runs the characterization pipeline (the README's main job) on the bundled scene -- painted aluminium and
painted steel at 1550 nm, specular geometries 30-60 deg, D/r0 7.9 and 12.9 -- and compares the per-region
means and standard deviations of the per-pixel least-squares n and kappa with Table 5.

Like for like: the text's 250 deconvolution iterations (full mode; quick 30), roughness sigma = 0.3 known to
the inversion, the same value table5_synthetic uses (deviation: the text's samples have sigma < 1 deg,
measured from the specular lobe width). The text's central result is compared as a number: the paint's per-
pixel scatter (sd of n) shrinks 2.0-4.2x from degraded to corrected; so are the metals' mean kappa under
turbulence. Run time of the one-draw version: quick (48 px, 3 angles, 30 iterations) 45 s measured at load
~3.7 on the shared 2-core machine; full (128 px, 7 angles, 250 iterations): 260 s wall with ``--workers 2``
(28 Nov 2026, three blind starts, the scene default). Verdict "not reproduced": the paint's scatter of n
shrinks 1.22x, 0.58x, 1.16x and 1.12x from degraded to corrected (aluminium D/r0 7.9, 12.9, steel 7.9, 12.9;
none reaches the text's 2x), and the corrected metals' mean kappa is 53 % and 62 % below the published values
for aluminium, 13 % above and 15 % below for steel. The run with one blind start (24 Nov 2026, 186 s) had
1.1x, 0.5x, 2.3x and 2.2x, verdict "partly": averaging the starts' restorations lowered the corrected S0 and
DOLP errors of the default run, but the paint's per-pixel n scatters about as much as in the degraded image,
and more for aluminium at D/r0 12.9 (sd 0.77 against 0.44). The corrected paint's per-pixel means are within
0.07-0.23 of the truth in n (the report's table). (Those full runs drew the scene once; see below.)

Several draws (since 29 Nov 2026). The findings rested on one draw of the scene, and a ratio of two per-pixel
sds scatters from draw to draw: a quick-mode seed survey (seeds 1-8) found the four cases' shrink factors
anywhere in 0.2-2.8x and the verdict "partly" on seed 2 (steel D/r0 7.9 at 2.84x) and "not reproduced" on the
other 7. The study now runs DRAWS = 4 independent draws of the whole scene (scratches, screens, noise, start
PSFs; the first is the pipeline's report, images and table, the others :func:`run_plate` alone), and judges
the shrink by the geometric mean over the draws with a 95 % Student t interval on its log: a case reaches the
text's 2x only where the interval lies above 2, misses it only where it lies below, else it is not determined
at this run size; the headline gives the four cases pooled per draw (:func:`shrink_verdict`). The metals'
kappa is the mean of ours / published - 1 over the D/r0 and draws with a 95 % interval
(:func:`kappa_interval`). Survey after the change (quick, seeds 1-8): "not reproduced" on all 8, the pooled
shrink 0.68-1.01x with every 95 % interval below 2x (widest 0.39-1.60, seed 3); the seed-to-seed variance of a
case's mean log shrink matched the within-seed variance / 4 (independent draws) in three cases, and was 2.3
times it for steel D/r0 7.9 (seed 2's one draw at 2.84x). Corrected kappa vs published: aluminium -41 to +3 %
(intervals 33-184 % wide), steel -39 to +4 %; with the default seed 20101210 (pooled shrink 0.84x, 95 %
0.65-1.10) aluminium -65 % (-86 to -43 %) and steel -3 % (-15 to +10 %). Two of those 18 kappa intervals (seed
2's steel, -51 to -27 %, and seed 20101210's aluminium) miss the cross-seed mean (about -9 % steel, -12 %
aluminium), more than 95 % intervals should: the per-draw values are heavy-tailed (aluminium -0.87 to +0.68,
six of one run at -0.41 to -0.87), which a t interval over 6-8 of them under-covers, so the report calls them
rough. The draws are independent (a draw's numbers do not depend on the draws before it in the process:
checked). Run time of quick mode (4 draws; the first pays the screens' subharmonic integrals, cached for the
others): 35 s as the runner measures it, 43 s wall, alone at load ~2.5 (default seed); 40-53 s CPU, 77-85 s
wall while two runs shared the 2 cores at load ~4 (one draw: 18-25 s). Full mode, measured (29 Nov 2026, seed
20101210, ``--workers 2``): 506 s (the first draw with its report 135 s, the three further draws 370 s);
verdict "not reproduced": shrink 1.00x (95 % 0.71-1.38) and 0.90x (0.52-1.56) for aluminium at D/r0 7.9 and
12.9, 0.92x (0.51-1.66) and 0.76x (0.30-1.94) for steel, 0.89x (0.76-1.05) pooled, every interval below 2x;
corrected metal kappa against Table 5 aluminium -51 % (-66 to -37 %), steel +5 % (-5 to +14 %).
"""

import numpy as np
from scatterlab.studies._common import set_verdict, t_factor

from scatterlab.characterization import characterize, default_scene
from scatterlab.characterization.pipeline import run_plate
from scatterlab.characterization.reference_tables import TABLE5
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "table5",
    "title": "Characterization of the painted plates through turbulence (Table 5)",
    "reproduces": "Table 5 and Figs. 59-61 (Sec. 7.3)",
}
# independent draws of the whole scene behind the findings (the shrink of the paint's scatter and the metals'
# kappa), quick and full mode: one draw's shrink factor ranged 0.2-2.8x over seeds (seed survey, 29 Nov 2026)
DRAWS = {"quick": 4, "full": 4}
TEXT_SHRINK = 2.0  # the lower end of the text's shrink of the paint's sd(n), degraded to corrected


def _nan(v):
    """summary.json's null (a NaN written out) back to NaN, in a region's statistics."""
    return {q: (np.nan if x is None else x) for q, x in v.items()} if isinstance(v, dict) else v


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
    # further independent draws of the scene (scratches, screens, noise, start PSFs) for the findings:
    # the pipeline's report and the table below are of the first draw
    draws = [
        {
            pl: {k: {r: _nan(v) for r, v in cases.items()} for k, cases in m.items()}
            for pl, m in summary["plates"].items()
        }
    ]
    with ctx.step("further_draws"):
        for _ in range(DRAWS["quick" if ctx.quick else "full"] - 1):
            rng = np.random.default_rng(ctx.rng.integers(2**63))
            draws.append(
                {p.metal: run_plate(p, cfg, rng, executor=ctx.executor).metrics for p in cfg.plates}
            )
    keys = ["no_turbulence"] + [
        f"D_r0_{x:g}_{k}" for k in ("degraded", "corrected") for x in cfg.d_over_r0
    ]
    pyplot = plt()
    fig, axes = pyplot.subplots(2, 2, figsize=(11, 7))
    lines = [
        "First draw of the scene (the pipeline's report and images are of it too):\n",
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
    _findings(ctx, draws, cfg)


def shrink_interval(deg_sd, cor_sd, threshold=TEXT_SHRINK):
    """Geometric-mean shrink deg_sd / cor_sd over independent draws with its 95 % interval, and whether
    that interval lies above ``threshold`` ("reaches"), below it ("below") or contains it ("not
    determined").

    Parameters
    ----------
    deg_sd, cor_sd : array_like, shape (R,)
        Per-pixel sd of n, degraded and corrected, one per draw; draws where either is not a positive
        finite number (no pixel measured) are left out.
    threshold : float
        The factor the interval is compared with.

    Returns
    -------
    dict
        ``ratio`` (geometric mean), ``low``, ``high`` (95 %: Student t over the draws on the log ratio),
        ``draws`` (used), ``per_draw`` (the ratios, NaN where left out) and ``status``.
    """
    deg_sd, cor_sd = np.asarray(deg_sd, float), np.asarray(cor_sd, float)
    ok = np.isfinite(deg_sd) & np.isfinite(cor_sd) & (deg_sd > 0) & (cor_sd > 0)
    per_draw = np.where(ok, deg_sd / np.where(ok, cor_sd, 1.0), np.nan)
    logs = np.log(per_draw[ok])
    if logs.size == 0:
        ratio = low = high = float("nan")
    else:
        mean = float(np.mean(logs))
        half = (
            t_factor(logs.size) * float(np.std(logs, ddof=1)) / np.sqrt(logs.size)
            if logs.size > 1
            else float("inf")
        )
        ratio, low, high = (
            float(np.exp(mean)),
            float(np.exp(mean - half)),
            float(np.exp(mean + half)),
        )
    status = (
        "reaches" if low >= threshold else "below" if high < threshold else "not determined"
    )  # NaN compares False: no draw leaves it not determined
    return {
        "ratio": ratio,
        "low": low,
        "high": high,
        "draws": int(logs.size),
        "per_draw": per_draw.tolist(),
        "status": status,
    }


def shrink_verdict(cases, pooled):
    """The verdict on the text's central result from the shrink intervals of the cases and pooled.

    "reproduced" when every case's interval lies above the text's 2x, "partly" when some do, "not
    reproduced" otherwise; then the headline's word says whether the pooled interval shows the shrink
    below 2x or leaves it not determined at this run size (nothing is shown either way).

    Parameters
    ----------
    cases : list of dict
        :func:`shrink_interval` per (plate, D/r0).
    pooled : dict
        :func:`shrink_interval` of the cases' geometric mean per draw.

    Returns
    -------
    (verdict, word) : (str, str)
    """
    reach = sum(c["status"] == "reaches" for c in cases)
    if reach == len(cases):
        return "reproduced", f"above {TEXT_SHRINK:g}x in every case"
    if reach:
        return "partly", f"above {TEXT_SHRINK:g}x in {reach} of {len(cases)} cases"
    if pooled["status"] == "below":
        return "not reproduced", f"below {TEXT_SHRINK:g}x"
    return "not reproduced", f"not determined at this run size ({pooled['draws']} draws)"


def _fmt_shrink(c):
    if not np.isfinite(c["ratio"]):
        return "no draw measured"
    if not np.isfinite(c["high"]):
        return f"{c['ratio']:.2f}x (one draw: no interval)"
    return f"{c['ratio']:.2f}x (95 % {c['low']:.2f}-{c['high']:.2f})"


def _findings(ctx, draws, cfg):
    """The text's central numbers against ours, over the independent draws of the scene: the paint's
    scatter shrink factor (geometric mean over the draws, Student t interval on its log) and the
    metals' corrected kappa (mean relative difference over the draws +- its standard error)."""
    m = ctx.metrics
    plates = list(draws[0])
    cases, kap, names, per_draw_logs = [], [], [], []
    for plate in plates:
        for x in cfg.d_over_r0:
            deg, cor = f"D_r0_{x:g}_degraded", f"D_r0_{x:g}_corrected"
            pub = TABLE5[plate]["paint"]
            c = shrink_interval(
                [d[plate][deg]["paint"]["n_std"] for d in draws],
                [d[plate][cor]["paint"]["n_std"] for d in draws],
            )
            c.update(
                name=f"{plate} D/r0 {x:g} paint sd(n) degraded/corrected",
                published=pub[deg][1] / pub[cor][1],
            )
            cases.append(c)
            per_draw_logs.append(np.log(c["per_draw"]))
            pk = TABLE5[plate]["metal"][cor][2]
            rel = np.array([d[plate][cor][plate]["kappa_mean"] / pk - 1 for d in draws])
            kap.append({"plate": plate, "d_r0": x, "published": pk, "relative": rel.tolist()})
            names.append(f"{plate} D/r0 {x:g}")
    # pooled: the cases' geometric mean per draw (the cases of one draw share its plates' layouts)
    logs = np.array(per_draw_logs)  # (cases, draws)
    full = np.all(np.isfinite(logs), axis=0)
    pooled = shrink_interval(np.exp(logs[:, full].mean(axis=0)), np.ones(int(full.sum())))
    m["paint_scatter_shrink"] = cases
    m["paint_scatter_shrink_pooled"] = pooled
    m["metal_kappa_corrected"] = kap
    m["draws"] = len(draws)
    kappa_plate = {
        plate: kappa_interval(
            [r for k in kap if k["plate"] == plate for r in k["relative"]],
            len(kap) // len(plates) * len(draws),
        )
        for plate in plates
    }
    m["metal_kappa_corrected_relative"] = kappa_plate
    pub_ratio = [c["published"] for c in cases]
    verdict, word = shrink_verdict(cases, pooled)
    status = {
        s: sum(c["status"] == s for c in cases) for s in ("reaches", "below", "not determined")
    }
    ctx.say(
        "The text's central result, the paint's per-pixel scatter of n shrinking after correction "
        f"(published {min(pub_ratio):.1f}-{max(pub_ratio):.1f}x), over {len(draws)} independent draws "
        "of the scene (scratches, screens, noise, start PSFs), as the geometric mean of the draws' "
        "shrink factors with its 95 % interval (Student t over the draws on the log): "
        + "; ".join(f"{n} {_fmt_shrink(c)}" for n, c in zip(names, cases))
        + f"; over all {len(cases)} cases {_fmt_shrink(pooled)}. A case's interval above the text's "
        f"lower end, {TEXT_SHRINK:g}x, shows the shrink reproduced, below it shows it not reproduced; "
        f"here {status['reaches']} above, {status['below']} below and {status['not determined']} "
        "not determined at this run size (the interval contains 2x: the draws scatter too much for "
        f"{len(draws)} of them to decide). One draw's factors scattered over 0.2-2.8x across seeds "
        "(seed survey of the one-draw version, 29 Nov 2026), so a single draw cannot judge a case. "
        + "Corrected metal kappa against Table 5 (mean over the D/r0 and draws of ours / published "
        "- 1, with its 95 % interval, a rough one: the values are heavy-tailed, and over a 9-seed "
        "survey 2 of 18 such intervals missed the cross-seed mean): "
        + "; ".join(_kappa_text(p, kappa_plate[p]) for p in plates)
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
    set_verdict(
        ctx,
        verdict,
        f"paint sd(n) shrink {_fmt_shrink(pooled)} over {len(cases)} cases x {len(draws)} draws, "
        f"{word} (published {min(pub_ratio):.1f}-{max(pub_ratio):.1f}x); corrected metal kappa vs "
        "published " + ", ".join(_kappa_text(p, kappa_plate[p]) for p in plates),
    )


def kappa_interval(values, of):
    """Mean of a plate's corrected kappa relative to the published one, ours / published - 1, over its
    D/r0 and draws, with a 95 % Student t interval treating the values as independent.

    The D/r0 of one draw share the plate's layout but not the screens; over the seed survey of
    29 Nov 2026 (8 seeds x 4 draws) the two D/r0 of a draw correlated -0.23 (aluminium) and +0.12
    (steel), and the values are heavy-tailed (aluminium -0.84 to +0.68), so a standard error from
    the 4 per-draw means understated the seed-to-seed scatter (-41 % +- 7 % on one seed, +3 % +- 6 %
    on another): all values count.

    Parameters
    ----------
    values : array_like
        ours / published - 1 per (D/r0, draw); NaN where no metal pixel was fitted.
    of : int
        How many values there would be with every one measured.

    Returns
    -------
    dict
        ``mean``, ``half_width`` (95 %; inf below two values), ``values`` (finite) and ``of``.
    """
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    half = (
        t_factor(v.size) * float(np.std(v, ddof=1)) / np.sqrt(v.size)
        if v.size > 1
        else float("inf")
    )
    return {
        "mean": float(np.mean(v)) if v.size else float("nan"),
        "half_width": half,
        "values": int(v.size),
        "of": int(of),
    }


def _kappa_text(plate, k):
    """One plate's corrected metal kappa against the published value, in words when unmeasured."""
    if not k["values"]:
        return f"{plate} not measured (no metal pixel fitted in any draw)"
    mean, half = k["mean"], k["half_width"]
    interval = (
        f" (95 % {mean - half:+.0%}..{mean + half:+.0%})"
        if np.isfinite(half)
        else " (one value: no interval)"
    )
    missing = (
        f", {k['of'] - k['values']} of {k['of']} without a mean" if k["values"] < k["of"] else ""
    )
    return f"{plate} {mean:+.0%}{interval}{missing}"
