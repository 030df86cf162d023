"""Table 5 on synthetic data: n and kappa of paint, aluminium and steel from noisy specular DOLP at 1550 nm.

Three regions (green paint 1.39 - j0.34, aluminium 1.44 - j16, steel 3.60 - j5.88; sigma = 0.3 known, the
value the table5 study's simulated plates use, so that the two studies are comparable; the text's samples
have sigma < 1 deg), specular angles 30-60 deg in 5 deg steps, per-pixel DOLP noise
0.01. Per pixel: batched bounded least squares (the reference's interior-reflective Newton on n in [0, 5],
kappa in [0, 25]); per region: the posterior of the region's mean DOLP (noise 0.01/sqrt(pixels)), with its
uncertainty report. Compared with Table 5's no-turbulence rows (measured, so also affected by oxidation and
calibration; see the report).

Run time: quick 23 s measured at load ~2 on the shared 2-core machine; full (2000 pixels per region,
chains run until converged): 218 s wall at load ~3 (24 Nov 2026; 175 s of it the three region
posteriors), verdict "not reproduced": 0 of 6 no-turbulence means inside 2 u of the published ones
(synthetic data from the accepted indices against measured plates; see the report).
Quick mode (30 pixels) does not judge: its bands are 8x wider, its verdict is "not reproduced".
"""

import warnings

import numpy as np
from scatterlab.studies._common import compare, set_verdict

from scatterlab.inversion import ConvergenceWarning, fit_dolp, model_dolp, sample_posteriors
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
        "| region | truth | LS E[n] (std) | LS E[kappa] (std) | posterior n, 68 % | posterior kappa, 68 % | "
        "published E[n] (std) | published E[kappa] (std) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    entries = {}
    for k, name in enumerate(names):
        n, kap = fit.n[k], fit.kappa[k]
        s = posts[k].summary()["parameters"]
        pub = PUBLISHED[name]
        ctx.metrics[name] = {
            "truth": truth[k].tolist(),
            "ls_mean_n": float(n.mean()),
            "ls_std_n": float(n.std()),
            "ls_mean_kappa": float(kap.mean()),
            "ls_std_kappa": float(kap.std()),
            "ls_converged": float(fit.converged[k].mean()),
            "posterior_n": [s["n"]["median"], *s["n"]["ci68"]],
            "posterior_kappa": [s["kappa"]["median"], *s["kappa"]["ci68"]],
            "posterior_converged": posts[k].converged,
            "published_no_turbulence": list(pub),
        }
        lines.append(
            f"| {name} | {truth[k, 0]:.2f} - j{truth[k, 1]:.2f} | {n.mean():.3f} ({n.std():.3f}) | "
            f"{kap.mean():.3f} ({kap.std():.3f}) | {s['n']['median']:.3f} [{s['n']['ci68'][0]:.3f}, "
            f"{s['n']['ci68'][1]:.3f}] | {s['kappa']['median']:.3f} [{s['kappa']['ci68'][0]:.3f}, "
            f"{s['kappa']['ci68'][1]:.3f}] | {pub[0]:.3f} ({pub[1]:.3f}) | {pub[2]:.3f} ({pub[3]:.3f}) |"
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
    ctx.say("\n".join(lines))
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6, 4.5))
    for k, name in enumerate(names):
        ax.plot(
            fit.n[k], fit.kappa[k], ".", ms=2, alpha=0.4, color=f"C{k}", label=f"{name}, per pixel"
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
    ax.set(
        xlabel="n",
        ylabel=r"$\kappa$",
        xlim=(0, 5),
        ylim=(0, 25),
        title="per-pixel least squares (stars: truth)",
    )
    ax.legend(fontsize=7)
    ctx.save_figure(fig, "table5_synthetic")
    for name in names:
        ctx.add_image(f"posteriors/{name}_corner")
    _findings(ctx, names)


def _findings(ctx, names):
    """Our LS means against Table 5's no-turbulence rows, and the per-pixel scatter."""
    m = ctx.metrics
    cmp = []
    for name in names:
        pub = PUBLISHED[name]
        root = np.sqrt(m["pixels"])
        cmp.append(
            compare(f"{name} E[n]", pub[0], m[name]["ls_mean_n"], 0.0, m[name]["ls_std_n"] / root)
        )
        cmp.append(
            compare(
                f"{name} E[kappa]",
                pub[2],
                m[name]["ls_mean_kappa"],
                0.0,
                m[name]["ls_std_kappa"] / root,
            )
        )
    m["comparisons"] = cmp
    inside = sum(c["inside"] for c in cmp)
    ratio = m["paint"]["ls_std_n"] / PUBLISHED["paint"][1]
    ctx.say(
        "Our per-pixel least-squares means against Table 5's no-turbulence rows (band: 2 x our "
        "standard error sd/sqrt(pixels); the text gives only per-pixel sd, not the uncertainty of "
        "its means, which over thousands of pixels is far smaller than the sd): "
        + " ".join(c["text"] for c in cmp)
        + f" {inside} of {len(cmp)} inside. Per pixel (noise {NOISE}), the paint's n and kappa "
        f"scatter by {m['paint']['ls_std_n']:.2f} and {m['paint']['ls_std_kappa']:.2f} (std), "
        f"{ratio:.2f} x the text's paint n scatter (1.27); the metals' scatter is larger "
        f"(aluminium n, kappa std {m['aluminium']['ls_std_n']:.2f}, "
        f"{m['aluminium']['ls_std_kappa']:.2f}; steel {m['steel']['ls_std_n']:.2f}, "
        f"{m['steel']['ls_std_kappa']:.2f}): for metals Rs ~ Rp at 30-60 deg, so the DOLP is "
        "small and flat, the reason the text gives for its metal errors. "
        + (
            "The text's measured paint scatter is well above what DOLP noise of 0.01 produces, so "
            "its data carried larger errors (the text names oxidation and small DOLPs). "
            if ratio < 0.5
            else ""
        )
        + "The 68 % posterior intervals above say how well each pooled region is known "
        "(posteriors/index.md). The text's means are of measured plates, ours of synthetic data "
        "with the literature indices, so a difference is expected where the real plates differ."
    )
    verdict, judged = _verdict(inside, len(cmp), m["pixels"], ctx.quick)
    ctx.say(judged)
    set_verdict(
        ctx,
        verdict,
        ("quick mode cannot judge: " if ctx.quick else "")
        + f"{inside}/{len(cmp)} no-turbulence means inside 2u ({m['pixels']} px per region); "
        f"paint sd(n) {ratio:.2f} x published",
    )


def _verdict(inside, total, pixels, quick):
    """The verdict from the comparison, and a sentence saying what it rests on.

    In quick mode the few pixels make the 2u bands sqrt(FULL_PIXELS / pixels) times wider than
    the full run's, so a mean can fall inside by chance: quick mode does not judge and its verdict is
    "not reproduced" (nothing shown reproduced); the full run's comparison decides.
    """
    if quick:
        return "not reproduced", (
            f"Quick mode ({pixels} pixels per region) cannot judge: its 2u bands are "
            f"{np.sqrt(FULL_PIXELS / pixels):.0f} x wider than the full run's, so {inside} of {total} "
            'inside says little; the verdict is "not reproduced" until the full run shows more.'
        )
    verdict = "reproduced" if inside == total else "partly" if inside else "not reproduced"
    return verdict, f'Verdict "{verdict}": {inside} of {total} means inside 2u.'
