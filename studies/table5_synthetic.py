"""Table 5 on synthetic data: n and kappa of paint, aluminium and steel from noisy specular DOLP at 1550 nm.

Three regions (green paint 1.39 - j0.34, aluminium 1.44 - j16, steel 3.60 - j5.88; sigma = 0.3 known, the
value the table5 study's simulated plates use, so that the two studies are comparable; the text's samples
have sigma < 1 deg), specular angles 30-60 deg in 5 deg steps, per-pixel DOLP noise
0.01. Per pixel: batched bounded least squares (the reference's interior-reflective Newton on n in [0, 5],
kappa in [0, 25]); per region: the posterior of the region's mean DOLP (noise 0.01/sqrt(pixels)), with its
uncertainty report. Compared with Table 5's no-turbulence rows (measured, so also affected by oxidation and
calibration; see the report).

A mean over pixels whose fit ended on a bound of the box is not a measurement (the value there is
the bound): a region's means are compared only when at most 1/sqrt(pixels) of its pixels are on a
bound (see ``bound_limit``), and the report gives the share per region. Posteriors that did not
converge are flagged beside their intervals.

Run time: quick 6 s at load ~0.5 on the shared 2-core machine (29 Nov 2026; 23 s at load ~2 before);
full (2000 pixels per region, chains run until converged): 19 s wall at load ~2.5 (29 Nov 2026; 12 s
of it the three region posteriors; 218 s at load ~3 on 24 Nov 2026), verdict "not reproduced": 0 of 6
no-turbulence means inside 2 u of the published ones: the paint's two outside, the metals' four not
scored (51 % of the aluminium and 42 % of the steel pixels on a bound; synthetic data from the
accepted indices against measured plates; see the report).
Quick mode (30 pixels) does not judge: its bands are 8x wider, its verdict is "not reproduced".
"""

import warnings

import numpy as np
from scatterlab.studies._common import compare, set_verdict

from scatterlab.inversion import (
    DEFAULT_BOUNDS,
    ConvergenceWarning,
    fit_dolp,
    model_dolp,
    sample_posteriors,
)
from scatterlab.inversion.report import posterior_report, report_index
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "table5_synthetic",
    "title": "Characterization of paint, aluminium and steel from synthetic specular DOLP",
    "reproduces": "Table 5 (Sec. 7.3), no-turbulence rows, on synthetic data",
}

MATERIALS = {"paint": (1.39, 0.34), "aluminium": (1.44, 16.0), "steel": (3.60, 5.88)}
# Table 5, no-turbulence row: E[n], std n, E[kappa], std kappa (paint: the aluminium plate's paint area)
PUBLISHED = {
    "aluminium": (3.8614, 1.487, 11.1757, 3.7652),
    "steel": (3.8649, 1.6921, 5.7123, 1.6088),
    "paint": (2.2467, 1.2717, 1.4073, 1.4859),
}
FULL_PIXELS = 2000  # per region, full mode
SIGMA = 0.3  # as the characterization pipeline's plates (table5); the text's samples: < 1 deg
NOISE = 0.01


def run(ctx):
    rng = ctx.rng
    theta = np.radians(np.arange(30, 61, 5))
    pixels = 30 if ctx.quick else FULL_PIXELS
    names = list(MATERIALS)
    ctx.metrics["pixels"] = pixels
    truth = np.array([MATERIALS[k] for k in names])
    clean = model_dolp(truth[:, 0], truth[:, 1], SIGMA, theta, theta)  # (3, 7)
    y = clean[:, None, :] + NOISE * rng.standard_normal((3, pixels, theta.size))
    with ctx.step("least_squares_per_pixel"):
        fit = fit_dolp(y, theta, theta, sigma=SIGMA, noise=NOISE)
    with ctx.step("posterior_per_region"), warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        posts = sample_posteriors(
            y.mean(1),
            theta,
            theta,
            NOISE / np.sqrt(pixels),
            rng,
            sigma=SIGMA,
            n_steps=300 if ctx.quick else None,
            executor=ctx.executor,
        )
    lines = [
        "| region | truth | LS E[n] (std) | LS E[kappa] (std) | LS pixels on a bound | "
        "posterior n, 68 % | posterior kappa, 68 % | published E[n] (std) | "
        "published E[kappa] (std) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    entries = {}
    for k, name in enumerate(names):
        n, kap = fit.n[k], fit.kappa[k]
        s = posts[k].summary()["parameters"]
        pub = PUBLISHED[name]
        bound = bound_shares(fit.n[k], fit.kappa[k], fit.at_bound[k])
        ctx.metrics[name] = {
            "truth": truth[k].tolist(),
            "ls_mean_n": float(n.mean()),
            "ls_std_n": float(n.std()),
            "ls_mean_kappa": float(kap.mean()),
            "ls_std_kappa": float(kap.std()),
            "ls_converged": float(fit.converged[k].mean()),
            "ls_bound": bound,
            "posterior_n": [s["n"]["median"], *s["n"]["ci68"]],
            "posterior_kappa": [s["kappa"]["median"], *s["kappa"]["ci68"]],
            "posterior_converged": posts[k].converged,
            "posterior_convergence_reason": posts[k].convergence_reason,
            "published_no_turbulence": list(pub),
        }
        # a posterior that did not converge: its intervals may be off, so say so beside them
        flag = "" if posts[k].converged else " **not converged**"
        lines.append(
            f"| {name} | {truth[k, 0]:.2f} - j{truth[k, 1]:.2f} | {n.mean():.3f} ({n.std():.3f}) | "
            f"{kap.mean():.3f} ({kap.std():.3f}) | {_bound_cell(bound)} | "
            f"{s['n']['median']:.3f} [{s['n']['ci68'][0]:.3f}, {s['n']['ci68'][1]:.3f}]{flag} | "
            f"{s['kappa']['median']:.3f} [{s['kappa']['ci68'][0]:.3f}, "
            f"{s['kappa']['ci68'][1]:.3f}]{flag} | {pub[0]:.3f} ({pub[1]:.3f}) | "
            f"{pub[2]:.3f} ({pub[3]:.3f}) |"
        )
        with ctx.step(f"report_{name}"):
            posterior_report(
                posts[k],
                ctx.out / "posteriors",
                name,
                rng=rng,
                truth=(*truth[k], SIGMA),
                overwrite=True,
            )
        entries[name] = posts[k]
    report_index(
        ctx.out / "posteriors",
        entries,
        title="Table 5 (synthetic): posterior per region",
        overwrite=True,
    )
    ctx.say("\n".join(lines) + "\n\n" + posterior_flags(ctx.metrics, names))
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(8.2, 4.5), layout="constrained")
    (n_lo, n_hi), (k_lo, k_hi) = DEFAULT_BOUNDS["n"], DEFAULT_BOUNDS["kappa"]
    # the fit's box: a pixel on its edge (x) is the bound, not an estimate
    ax.add_patch(
        pyplot.Rectangle((n_lo, k_lo), n_hi - n_lo, k_hi - k_lo, fill=False, ls="--", lw=0.8)
    )
    for k, name in enumerate(names):
        edge = fit.at_bound[k].any(-1)
        ax.plot(
            fit.n[k][~edge],
            fit.kappa[k][~edge],
            ".",
            ms=2,
            alpha=0.4,
            color=f"C{k}",
            label=f"{name}, per pixel",
        )
        if edge.any():
            ax.plot(
                fit.n[k][edge],
                fit.kappa[k][edge],
                "x",
                ms=5,
                alpha=0.7,
                color=f"C{k}",
                label=f"{name}, on a bound ({_pct(edge.mean())})",
            )
        ax.plot(*truth[k], "*", ms=14, color=f"C{k}", mec="k")
        pub = PUBLISHED[name]
        ax.errorbar(
            pub[0],
            pub[2],
            xerr=pub[1],
            yerr=pub[3],
            fmt="s",
            color=f"C{k}",
            mfc="none",
            label=f"{name}, Table 5 (measured)",
        )
    pad_n, pad_k = 0.02 * (n_hi - n_lo), 0.02 * (k_hi - k_lo)
    ax.set(
        xlabel="n",
        ylabel=r"$\kappa$",
        xlim=(n_lo - pad_n, n_hi + pad_n),
        ylim=(k_lo - pad_k, k_hi + pad_k),
        title="per-pixel least squares (stars: truth; dashed: the fit's bounds)",
    )
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    ctx.save_figure(fig, "table5_synthetic")
    for name in names:
        ctx.add_image(f"posteriors/{name}_corner")
    _findings(ctx, names)


def _findings(ctx, names):
    """Our LS means against Table 5's no-turbulence rows, and the per-pixel scatter."""
    m = ctx.metrics
    root = np.sqrt(m["pixels"])
    limit = bound_limit(m["pixels"])
    cmp = []
    for name in names:
        pub = PUBLISHED[name]
        share = m[name]["ls_bound"]["share"]
        for key, k in (("n", 0), ("kappa", 2)):
            c = compare(
                f"{name} E[{key}]",
                pub[k],
                m[name][f"ls_mean_{key}"],
                0.0,
                m[name][f"ls_std_{key}"] / root,
            )
            cmp.append(score_on_bounds(c, share, limit))
    m["comparisons"] = cmp
    m["bound_share_limit"] = limit
    inside = sum(bool(c["inside"]) for c in cmp)
    unscored = sum(not c["scored"] for c in cmp)
    scored = len(cmp) - unscored
    ratio = m["paint"]["ls_std_n"] / PUBLISHED["paint"][1]
    ctx.say(bound_text(m, names, limit))
    ctx.say(
        "Our per-pixel least-squares means against Table 5's no-turbulence rows (band: 2 x our "
        "standard error sd/sqrt(pixels); the text gives only per-pixel sd, not the uncertainty of "
        "its means, which over thousands of pixels is far smaller than the sd): "
        + " ".join(c["text"] for c in cmp)
        + f" {inside} of {scored} scored inside"
        + (f" ({unscored} of {len(cmp)} not scored: pixels on a bound)" if unscored else "")
        + f". Per pixel (noise {NOISE}), the paint's n and kappa "
        f"scatter by {m['paint']['ls_std_n']:.2f} and {m['paint']['ls_std_kappa']:.2f} (std), "
        f"{ratio:.2f} x the text's paint n scatter (1.27); the metals' scatter is larger "
        f"(aluminium n, kappa std {m['aluminium']['ls_std_n']:.2f}, "
        f"{m['aluminium']['ls_std_kappa']:.2f}; steel {m['steel']['ls_std_n']:.2f}, "
        f"{m['steel']['ls_std_kappa']:.2f}, bound pixels included): for metals Rs ~ Rp at 30-60 "
        "deg, so the DOLP is small and flat, the reason the text gives for its metal errors. "
        + (
            "The text's measured paint scatter is well above what DOLP noise of 0.01 produces, so "
            "its data carried larger errors (the text names oxidation and small DOLPs). "
            if ratio < 0.5
            else ""
        )
        + "The 68 % posterior intervals above say how well each pooled region is known "
        "(posteriors/index.md) where their chains converged. The text's means are of measured "
        "plates, ours of synthetic data with the literature indices, so a difference is expected "
        "where the real plates differ."
    )
    verdict, judged = _verdict(inside, len(cmp), m["pixels"], ctx.quick, unscored)
    ctx.say(judged)
    set_verdict(
        ctx,
        verdict,
        ("quick mode cannot judge: " if ctx.quick else "")
        + f"{inside}/{len(cmp)} no-turbulence means inside 2u"
        + (f", {unscored} not scored (on a bound)" if unscored else "")
        + f" ({m['pixels']} px per region); paint sd(n) {ratio:.2f} x published",
    )


def bound_shares(n, kappa, at_bound):
    """Share of one region's pixels whose fit ended on a bound of its box.

    Parameters
    ----------
    n, kappa : ndarray (pixels,)
        The per-pixel fits.
    at_bound : ndarray of bool (pixels, 2)
        ``DolpFit.at_bound`` of the region (n, kappa; kappa = 0 is a physical limit, not counted).

    Returns
    -------
    dict
        ``share`` (pixels with either parameter on a bound; the other one was then fitted with its
        partner pinned, so neither is an estimate), ``n``, ``kappa`` (per parameter), ``pixels``,
        and ``off_bound_mean_n``, ``off_bound_mean_kappa`` (mean of the other pixels, NaN if none).
    """
    at = np.asarray(at_bound, bool)
    edge = at.any(-1)
    free = ~edge
    return {
        "share": float(edge.mean()),
        "n": float(at[:, 0].mean()),
        "kappa": float(at[:, 1].mean()),
        "pixels": int(edge.sum()),
        "off_bound_mean_n": float(np.mean(n[free])) if free.any() else float("nan"),
        "off_bound_mean_kappa": float(np.mean(kappa[free])) if free.any() else float("nan"),
    }


def bound_limit(pixels):
    """Largest share of a region's pixels on a bound at which its mean is still scored: 1/sqrt(N).

    At a pixel on a bound the value is the bound; its least-squares minimum lies beyond it by an
    unknown amount. Were that amount only the per-pixel scatter sd, a share f of such pixels would
    move the mean by about f sd, which stays within the mean's standard error sd/sqrt(N) only for
    f <= 1/sqrt(N) (18 % at 30 pixels, 2.2 % at 2000). Beyond that the mean says where the box was
    drawn, not what the data say.

    Parameters
    ----------
    pixels : int
        Pixels N of the region.

    Returns
    -------
    float
        The largest share of pixels on a bound (0-1).
    """
    return float(1.0 / np.sqrt(pixels))


def score_on_bounds(c, share, limit):
    """The comparison ``c``, not scored when more than ``limit`` of its pixels are on a bound.

    Parameters
    ----------
    c : dict
        A comparison from ``compare``.
    share, limit : float
        The share of the region's pixels on a bound, and the largest share scored (:func:`bound_limit`).

    Returns
    -------
    dict
        A copy of ``c`` with ``scored``, ``bound_share`` and ``inside_band`` (the band's own answer);
        when not scored, ``inside`` is None (neither pass nor fail) and ``text`` says why.
    """
    c = dict(c, scored=bool(share <= limit), inside_band=c["inside"], bound_share=float(share))
    if not c["scored"]:
        c["inside"] = None
        c["text"] = (
            f"{c['name']}: published {c['published']:.4g}, ours {c['ours']:.4g}: not scored "
            f"({_pct(share)} of its pixels on a bound, above the {_pct(limit)} a mean tolerates)."
        )
    return c


def _bound_cell(bound):
    if not bound["pixels"]:
        return "0 %"
    parts = [f"{key} {_pct(bound[key])}" for key in ("n", "kappa") if bound[key]]
    return f"{_pct(bound['share'])} ({', '.join(parts)})"


def bound_text(m, names, limit):
    """The sentence on the pixels whose fit ended on a bound, region by region.

    Parameters
    ----------
    m : dict
        The study's metrics, ``m[region]["ls_bound"]`` from :func:`bound_shares`.
    names : list of str
        The regions.
    limit : float
        The largest share of pixels on a bound at which a mean is scored.

    Returns
    -------
    str
    """
    bad = [x for x in names if m[x]["ls_bound"]["share"] > limit]
    parts = []
    for x in names:
        b = m[x]["ls_bound"]
        parts.append(
            f"{x} {_bound_cell(b)}"
            + (
                f", the other pixels averaging n "
                f"{b['off_bound_mean_n']:.2f}, kappa {b['off_bound_mean_kappa']:.2f}"
                if b["pixels"]
                else ""
            )
        )
    (n_lo, n_hi), (k_lo, k_hi) = DEFAULT_BOUNDS["n"], DEFAULT_BOUNDS["kappa"]
    return (
        f"Pixels whose least-squares fit ended on a bound of its box (n in [{n_lo:g}, {n_hi:g}], "
        f"kappa in [{k_lo:g}, {k_hi:g}]; kappa = 0 is a physical limit and not counted): "
        + "; ".join(parts)
        + ". There the value is the bound, not an estimate, so a mean over many such pixels is not "
        "a measurement: it says where the box was drawn. A mean is compared only when at most "
        f"1/sqrt(pixels) = {_pct(limit)} of its region's pixels are on a bound (were the minima "
        "of those pixels only one per-pixel sd beyond the bound, a share f of them would bias the "
        "mean by about f x sd, below the mean's standard error sd/sqrt(pixels) only for "
        "f <= 1/sqrt(pixels); minima further out bias it more); "
        + (
            f"the means of {' and '.join(bad)} are not scored."
            if bad
            else "every region passes this test, so every mean is scored."
        )
    )


def posterior_flags(m, names):
    """The note flagging posteriors whose chains did not converge (their intervals may be off).

    Parameters
    ----------
    m : dict
        The study's metrics, ``m[region]["posterior_converged"]`` and
        ``["posterior_convergence_reason"]``.
    names : list of str
        The regions.

    Returns
    -------
    str
        Markdown: a sentence and one bullet per region not converged.
    """
    bad = [x for x in names if not m[x]["posterior_converged"]]
    if not bad:
        return "Every region's posterior converged."
    return (
        f"**Not converged**: the posteriors of {' and '.join(bad)} (marked in the table). Their "
        "intervals are provisional: the quantiles of a chain that did not meet its convergence "
        "criteria may be off (posteriors/<region>.md).\n\n"
        + "\n".join(f"- {x}: {m[x]['posterior_convergence_reason']}" for x in bad)
    )


def _pct(x):
    """A share as a percentage: whole per cent, one decimal below 10 % (the 2.2 % limit at 2000 px)."""
    return f"{100 * x:.0f} %" if x == 0 or 100 * x >= 9.95 else f"{100 * x:.1f} %"


def _verdict(inside, total, pixels, quick, unscored=0):
    """The verdict from the comparison, and a sentence saying what it rests on.

    In quick mode the few pixels make the 2u bands sqrt(FULL_PIXELS / pixels) times wider than
    the full run's, so a mean can fall inside by chance: quick mode does not judge and its verdict is
    "not reproduced" (nothing shown reproduced); the full run's comparison decides. ``unscored``
    comparisons (their means rest on pixels on a bound) count as neither inside nor outside, but
    "reproduced" needs every one of the ``total`` inside.
    """
    skipped = f" ({unscored} not scored: pixels on a bound)" if unscored else ""
    if quick:
        return "not reproduced", (
            f"Quick mode ({pixels} pixels per region) cannot judge: its 2u bands are "
            f"{np.sqrt(FULL_PIXELS / pixels):.0f} x wider than the full run's, so {inside} of {total} "
            f'inside{skipped} says little; the verdict is "not reproduced" until the full run '
            "shows more."
        )
    verdict = "reproduced" if inside == total else "partly" if inside else "not reproduced"
    return verdict, f'Verdict "{verdict}": {inside} of {total} means inside 2u{skipped}.'
