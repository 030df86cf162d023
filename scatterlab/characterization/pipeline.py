"""End-to-end characterization (Ch. VII): simulate -> deconvolve and classify -> invert -> report.

For each plate and each specular geometry of the scene, the painted plate is rendered with the pBRDF
(:func:`scatterlab.imaging.render_stokes`), imaged through a 4-channel division-of-amplitude polarimeter
without turbulence and at each D/r0 (one Kolmogorov phase screen per acquisition, shared by the channels),
with shot and read noise. Each acquisition gives three DOLP images: no turbulence, degraded (least-squares
Stokes of the blurred data) and corrected (blind deconvolution, EM, with the DOLP priors classifying each
pixel). The AOP is not estimated: observation is specular, where symmetry fixes it (Ch. VII). The simulated
geometries share one pixel grid, so registration is the identity here (real data would need the keystone
correction first). Then, per pixel, the DOLP over the geometries is inverted for n and kappa by
:func:`scatterlab.inversion.fit_dolp` (sigma known, as in the reference), and per region (paint, bare metal)
the posterior of the region-mean DOLP is sampled. Results go into one HDF5 file (images, maps, PSFs, chains)
and a Markdown report with the maps of the reference's figures. Only what ``estimate`` asks for is computed.
"""

from __future__ import annotations

import json
import time
import warnings
from pathlib import Path

import numpy as np

from scatterlab.characterization.scene_config import SceneConfig
from scatterlab.runtime.progress import progress

__all__ = ["characterize"]


def _acquire(S, angles, d_over_r0, cfg, rng):
    from scatterlab.imaging import channel_images, circular_pupil, detect, phase_screen, psf

    n = cfg.image_size // 2
    pupil = circular_pupil(n, n / 2)
    if d_over_r0 is None:
        h = psf(pupil, pad=2)
    else:
        h = psf(pupil, phase_screen(n, 1.0, n / d_over_r0, rng), pad=2)
    counts = detect(channel_images(S, angles, h), rng, photons=cfg.photons, read_noise=cfg.read_noise)
    return counts, h, pupil


def characterize(cfg: SceneConfig, out, *, overwrite: bool = False, executor=None) -> Path:
    """Run the pipeline for ``cfg`` into the folder ``out``; returns the report path.

    Writes ``results.h5`` (groups per plate and case), ``report.md`` with PNG figures and ``summary.json``.
    Refuses to overwrite an existing report unless ``overwrite``.
    """
    import h5py

    from scatterlab.deconvolution import PRIOR_SETS, blind_deconvolve, classification_errors
    from scatterlab.imaging import painted_plate, render_stokes, stokes_from_channels
    from scatterlab.inversion import ConvergenceWarning, fit_dolp, sample_posteriors
    from scatterlab.runtime.results import write_json

    cfg.validate()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    report = out / "report.md"
    if report.exists() and not overwrite:
        raise FileExistsError(f"{report} exists; pass overwrite=True (CLI: --force)")
    t_start = time.perf_counter()
    rng = np.random.default_rng(cfg.seed)
    angles = np.radians(cfg.polarizer_deg)
    theta = np.radians(cfg.geometry_deg)
    cases = [("no_turbulence", None)] + [(f"D_r0_{x:g}", float(x)) for x in cfg.d_over_r0]
    priors = None if cfg.priors == "none" else PRIOR_SETS[cfg.priors]
    want_classes = "classes" in cfg.estimate and priors is not None
    summary: dict = {"title": cfg.title, "cases": [c for c, _ in cases], "plates": {}}
    tmp = out / "results.h5.part"
    with h5py.File(tmp, "w") as f5:
        f5.attrs["config"] = json.dumps(cfg.__dict__, default=lambda o: o.__dict__)
        for plate in cfg.plates:
            g_plate = f5.create_group(plate.metal)
            metal = plate.metal_n - 1j * plate.metal_kappa
            paint = plate.paint_n - 1j * plate.paint_kappa
            base = painted_plate(cfg.image_size, metal=metal, paint=paint, metal_roughness=plate.metal_roughness,
                                 paint_roughness=plate.paint_roughness, theta=theta[0], rng=rng)
            labels = base.labels
            g_plate["labels"] = labels
            dolp = {c: {"degraded": [], "corrected": [], "truth": []} for c, _ in cases}
            classes = {c: [] for c, _ in cases}
            for k, th in enumerate(progress(theta, desc=f"{plate.metal}: geometries")):
                base.theta_i = base.theta_r = float(th)
                S = render_stokes(base)
                truth_dolp = np.hypot(S[1], S[2]) / np.maximum(S[0], 1e-300)
                for case, dr0 in cases:
                    counts, h, pupil = _acquire(S, angles, dr0, cfg, rng)
                    Sd = stokes_from_channels(counts, angles)
                    deg = np.clip(np.hypot(Sd[1], Sd[2]) / np.maximum(Sd[0], 1e-9), 0, 1)
                    res = blind_deconvolve(counts, angles, pupil=pupil, iterations=cfg.iterations,
                                           priors=priors if want_classes else None, psf_radius=cfg.image_size / 4)
                    dolp[case]["degraded"].append(deg)
                    dolp[case]["corrected"].append(res.dolp)
                    dolp[case]["truth"].append(truth_dolp)
                    if want_classes:
                        classes[case].append(res.classes)
                    g = g_plate.require_group(case).create_group(f"theta_{cfg.geometry_deg[k]:g}")
                    g["counts"] = counts.astype(np.float32)
                    g["s0_degraded"] = Sd[0]
                    g["s0_corrected"] = res.s0
                    g["dolp_degraded"] = deg
                    g["dolp_corrected"] = res.dolp
                    g["dolp_truth"] = truth_dolp
                    g["psf_true"] = h
                    g["psf_estimated"] = res.psfs[0]
                    g["loglik"] = res.loglik
                    if want_classes:
                        g["classes"] = res.classes
            psum: dict = {}
            metal_lab = labels > 0
            for case, _ in cases:
                cs: dict = {}
                for kind in ("degraded", "corrected"):
                    err = np.sqrt(np.mean((np.stack(dolp[case][kind]) - np.stack(dolp[case]["truth"])) ** 2))
                    cs[f"dolp_rmse_{kind}"] = float(err)
                if want_classes:
                    mid = len(theta) // 2
                    cs["classification"] = classification_errors(classes[case][mid], metal_lab.astype(int),
                                                                 metal_classes=tuple(range(1, len(priors))))
                if "n_kappa" in cfg.estimate:
                    for kind in ("degraded", "corrected"):
                        y = np.moveaxis(np.stack(dolp[case][kind]), 0, -1)  # (H, W, M)
                        fit = fit_dolp(y, theta, theta, sigma=cfg.sigma_known)
                        g_plate[case][f"n_{kind}"] = fit.n
                        g_plate[case][f"kappa_{kind}"] = fit.kappa
                        g_plate[case][f"n_kappa_errors_{kind}"] = fit.errors
                        for region, sel in (("paint", ~metal_lab), (plate.metal, metal_lab)):
                            cs[f"{region}_{kind}"] = {"n_mean": float(np.nanmean(fit.n[sel])),
                                                      "n_std": float(np.nanstd(fit.n[sel])),
                                                      "kappa_mean": float(np.nanmean(fit.kappa[sel])),
                                                      "kappa_std": float(np.nanstd(fit.kappa[sel]))}
                if "posterior" in cfg.estimate:
                    y = np.moveaxis(np.stack(dolp[case]["corrected"]), 0, -1)
                    regions = [("paint", ~metal_lab), (plate.metal, metal_lab)]
                    means = np.stack([y[sel].mean(0) for _, sel in regions])
                    noise = [max(float(y[sel].std(0).mean()) / np.sqrt(sel.sum()), 1e-4) for _, sel in regions]
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", ConvergenceWarning)
                        posts = [sample_posteriors(means[i:i + 1], theta, theta, noise[i], rng, sigma=cfg.sigma_known,
                                                   n_steps=cfg.posterior_steps, executor=executor)[0]
                                 for i in range(len(regions))]
                    for (region, _), post in zip(regions, posts):
                        gg = g_plate[case].create_group(f"posterior_{region}")
                        gg["chain"] = post.chain
                        gg.attrs["summary"] = json.dumps(post.summary(), default=float)
                        s = post.summary()["parameters"]
                        cs[f"posterior_{region}"] = {p: [s[p]["median"], *s[p]["ci68"]] for p in ("n", "kappa")}
                psum[case] = cs
            summary["plates"][plate.metal] = psum
            _plate_figure(out, plate.metal, labels, dolp, classes if want_classes else None, g_plate, cases, cfg,
                          overwrite)
    summary["seconds"] = time.perf_counter() - t_start
    final = out / "results.h5"
    if final.exists() and not overwrite:
        tmp.unlink()
        raise FileExistsError(f"{final} exists; pass overwrite=True")
    tmp.replace(final)  # atomic: a run interrupted before here leaves no half-written results.h5
    write_json(out / "summary.json", summary, overwrite=overwrite)
    return _write_report(out, cfg, summary, overwrite)


def _plate_figure(out, name, labels, dolp, classes, g_plate, cases, cfg, overwrite):
    import io

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from scatterlab.runtime.results import atomic_write_bytes

    mid = len(cfg.geometry_deg) // 2
    rows = ["S0 / DOLP truth", "DOLP degraded", "DOLP corrected"]
    extra = []
    if classes is not None:
        extra.append("classes")
    if "n_kappa" in cfg.estimate:
        extra += ["n corrected", "kappa corrected"]
    ncol = len(cases)
    fig, axes = plt.subplots(len(rows) + len(extra), ncol, figsize=(3.2 * ncol, 3.0 * (len(rows) + len(extra))),
                             squeeze=False)
    for j, (case, _) in enumerate(cases):
        axes[0, j].imshow(dolp[case]["truth"][mid], vmin=0, vmax=1)
        axes[1, j].imshow(dolp[case]["degraded"][mid], vmin=0, vmax=1)
        axes[2, j].imshow(dolp[case]["corrected"][mid], vmin=0, vmax=1)
        r = 3
        if classes is not None:
            axes[r, j].imshow(classes[case][mid], cmap="tab10", vmin=0, vmax=9)
            r += 1
        if "n_kappa" in cfg.estimate:
            axes[r, j].imshow(g_plate[case]["n_corrected"][()], vmin=0, vmax=5)
            axes[r + 1, j].imshow(g_plate[case]["kappa_corrected"][()], vmin=0, vmax=25)
        axes[0, j].set_title(case, fontsize=9)
    for i, lab in enumerate(rows + extra):
        axes[i, 0].set_ylabel(lab, fontsize=9)
    for a in axes.ravel():
        a.set_xticks([])
        a.set_yticks([])
    fig.suptitle(f"{name} plate, theta = {cfg.geometry_deg[mid]} deg (maps: all geometries)")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    atomic_write_bytes(Path(out) / f"{name}.png", buf.getvalue(), overwrite=overwrite)


def _write_report(out, cfg, summary, overwrite):
    from scatterlab.runtime.results import write_text

    lines = [f"# Characterization: {cfg.title}", "",
             f"Geometries {cfg.geometry_deg} deg (specular), D/r0 {cfg.d_over_r0}, {cfg.photons:g} photo-electrons "
             f"peak, polarizers {cfg.polarizer_deg} deg, {cfg.iterations} EM iterations, priors {cfg.priors}. "
             f"Run time {summary['seconds']:.0f} s. Data: `results.h5`; numbers: `summary.json`.", ""]
    for plate, psum in summary["plates"].items():
        lines += [f"## {plate} plate", "", "| case | DOLP RMSE degraded | DOLP RMSE corrected | classification error "
                  "(corrected) | paint n, kappa (corrected, mean +/- std) | metal n, kappa (corrected) |",
                  "|---|---|---|---|---|---|"]
        for case, cs in psum.items():
            cls = cs.get("classification", {}).get("total_error", float("nan"))
            pc = cs.get("paint_corrected", {})
            mc = cs.get(f"{plate}_corrected", {})

            def fmt(d):
                return (f"{d['n_mean']:.2f} +/- {d['n_std']:.2f}, {d['kappa_mean']:.2f} +/- {d['kappa_std']:.2f}"
                        if d else "-")
            lines.append(f"| {case} | {cs['dolp_rmse_degraded']:.3f} | {cs['dolp_rmse_corrected']:.3f} | {cls:.3f} | "
                         f"{fmt(pc)} | {fmt(mc)} |")
        lines += ["", f"![{plate}]({plate}.png)", ""]
        post = {c: cs for c, cs in psum.items() if "posterior_paint" in cs}
        if post:
            lines += ["Posterior (region-mean corrected DOLP), median and 68 % interval:", ""]
            for case, cs in post.items():
                for region in ("paint", plate):
                    p = cs[f"posterior_{region}"]
                    lines.append(f"- {case}, {region}: n {p['n'][0]:.3f} [{p['n'][1]:.3f}, {p['n'][2]:.3f}], "
                                 f"kappa {p['kappa'][0]:.3f} [{p['kappa'][1]:.3f}, {p['kappa'][2]:.3f}]")
            lines.append("")
    return write_text(Path(out) / "report.md", "\n".join(lines), overwrite=overwrite)
