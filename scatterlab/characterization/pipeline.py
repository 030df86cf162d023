"""End-to-end characterization (Ch. VII): simulate -> deconvolve and classify -> register -> invert -> report.

For each plate and each specular geometry of the scene, the painted plate (object coordinates: labels 0 paint,
1 bare metal, 2 scratches) is rendered with the pBRDF (:func:`scatterlab.imaging.render_stokes`) as a distant
camera sees it (foreshortened by cos theta), and imaged by a 4-channel division-of-amplitude polarimeter without
turbulence and through one Kolmogorov phase screen per D/r0 (tilt kept), with shot and read noise. The
no-turbulence image is the reference and is not deconvolved; each turbulent acquisition gives a degraded image
(least-squares Stokes of the data, classified by the DOLP thresholds of the priors) and a corrected one (blind
EM deconvolution started from a random Kolmogorov PSF as in Sec. 5.3.2, Schulz pupil PSFs by default, the DOLP
priors classifying each pixel). The AOP is not estimated: observation is specular, where symmetry fixes it.
Every image is keystone-corrected to object coordinates and aligned with the no-turbulence image
(:mod:`scatterlab.characterization.registration`). Per pixel, the DOLP over the geometries is inverted for n and
kappa by :func:`scatterlab.inversion.fit_dolp` (sigma known, as in the reference); per region (paint, bare
metal) the posterior of the region-mean DOLP is sampled, its noise a parameter (floor: the pixel scatter over
sqrt(pixels)). Errors are computed against the object and against
the no-turbulence image, the corrected estimate first re-imaged through the diffraction-limited PSF. Results go
into one HDF5 file (images, maps, PSFs, chains) and a Markdown report with the tables and maps of the
reference's Tables 4-5 and Figs. 49-61. Only what ``estimate`` asks for is computed.
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
    """Channel counts of Stokes images S (3, H, W) through the pupil (half the image size) without turbulence
    (``d_over_r0`` None) or through one Kolmogorov screen (tilt kept: registration removes it)."""
    from scatterlab.imaging import channel_images, circular_pupil, detect, phase_screen, psf

    n = cfg.image_size // 2
    pupil = circular_pupil(n, n / 2)
    if d_over_r0 is None:
        h = psf(pupil, pad=2)
    else:
        h = psf(pupil, phase_screen(n, 1.0, n / d_over_r0, rng), pad=2)
    counts = detect(channel_images(S, angles, h), rng, photons=cfg.photons, read_noise=cfg.read_noise)
    return counts, h, pupil


def _stokes_dolp(counts, angles):
    from scatterlab.imaging import stokes_from_channels

    S = stokes_from_channels(counts, angles)
    return S[0], np.clip(np.hypot(S[1], S[2]) / np.maximum(S[0], 1e-9), 0, 1)


def _task_key(task) -> str:
    """Digest of everything a deconvolution depends on (data, settings, priors, seed): its checkpoint name."""
    import hashlib

    h = hashlib.sha1(np.ascontiguousarray(task["counts"]).tobytes())
    h.update(np.ascontiguousarray(task["angles"]).tobytes())
    h.update(repr((task["iterations"], task["priors"], task.get("adaptive"), task.get("psf_model"),
                   task["seed"])).encode())
    return h.hexdigest()[:20]


def _correct_task(task):
    """One blind deconvolution (module-level so that process executors can run it). With ``checkpoint`` (a
    folder) the result is read from there when an earlier, interrupted run computed it, and written there
    atomically otherwise."""
    ckpt = Path(task["checkpoint"]) / f"{_task_key(task)}.npz" if task.get("checkpoint") else None
    if ckpt is not None and ckpt.exists():
        from scatterlab.deconvolution import SuperGaussianPrior

        with np.load(ckpt, allow_pickle=False) as z:
            out = {k: z[k] for k in ("s0", "dolp", "psf", "loglik")}
            out["classes"] = z["classes"] if "classes" in z else None
            out["priors"] = tuple(SuperGaussianPrior(c2, c3, int(m), str(name))
                                  for (c2, c3, m), name in zip(z["prior_params"], z["prior_names"])) or None
        return out
    out = _deconvolve(task)
    if ckpt is not None:
        from scatterlab.runtime.results import write_npz

        arrays = {k: out[k] for k in ("s0", "dolp", "psf", "loglik")}
        if out["classes"] is not None:
            arrays["classes"] = out["classes"]
        pri = out["priors"] or ()
        arrays["prior_params"] = np.array([[p.c2, p.c3, p.m] for p in pri], float).reshape(-1, 3)
        arrays["prior_names"] = np.array([p.name for p in pri], dtype="U32")
        write_npz(ckpt, overwrite=True, **arrays)
    return out


def _deconvolve(task):
    """Blind deconvolution of one acquisition. Adaptive priors (Sec. 8.1.1): the first half of the iterations
    runs without priors (ML), the priors are re-centred on the histogram of that corrected DOLP, and the second
    half continues from the ML estimates with them."""
    from scatterlab.deconvolution import adaptive_priors, blind_deconvolve, initial_psf, object_grid

    counts, angles, pupil = task["counts"], task["angles"], task["pupil"]
    H, W = counts.shape[1:]
    radius = H / 4
    priors = task["priors"]
    kw = dict(psf_radius=radius, psf_mode=task.get("psf_model", "em"), pupil=pupil)
    psf0 = initial_psf(pupil, object_grid((H, W), radius), rng=task["seed"])
    iterations = task["iterations"]
    loglik = []
    starts = {}
    if priors and task.get("adaptive"):
        first = blind_deconvolve(counts, angles, psf0=psf0, iterations=iterations // 2, **kw)
        priors = adaptive_priors(first.dolp, base=priors)
        psf0, loglik = first.psfs[0], list(first.loglik[:-1])
        starts = dict(s0_start=first.s0, dolp_start=first.dolp)
        iterations -= iterations // 2
    res = blind_deconvolve(counts, angles, psf0=psf0, iterations=iterations, priors=priors, **starts, **kw)
    return {"s0": res.s0, "dolp": res.dolp, "classes": res.classes, "psf": res.psfs[0],
            "loglik": np.r_[loglik, res.loglik], "priors": priors}


def observe(plate, labels, thetas, cfg: SceneConfig, rng, *, priors=None, executor=None, adaptive=False,
            cases=None, checkpoint=None) -> list:
    """Simulate, correct and register one plate at each specular geometry.

    Parameters
    ----------
    plate : Plate -- materials and roughness; labels : int array (H, W) in object coordinates (0 paint, 1 metal,
        2 scratch); thetas : iterable of theta_i = theta_r [rad]; priors : DOLP priors for the classification
        (None: no classes); adaptive : re-centre the priors on each acquisition's DOLP histogram (Sec. 8.1.1);
        cases : [(name, D/r0 or None)], default no turbulence + ``cfg.d_over_r0``; checkpoint : folder where
        each deconvolution is saved as it finishes, and read back by a rerun after an interruption.

    Returns
    -------
    list (one per theta) of dicts: ``truth_dolp``, ``truth_s0`` (object coordinates) and per case name a dict
    with ``s0``/``dolp``/``classes`` for ``degraded`` and (turbulent cases) ``corrected``, the true and
    estimated PSFs, the log-likelihood history and the registration shifts [pixels]. The no-turbulence images
    are not deconvolved (they are the reference the others are compared with, as in the text).
    """
    from scatterlab.characterization.registration import apply_shift, foreshorten, keystone_correct, register
    from scatterlab.deconvolution import classify_dolp
    from scatterlab.imaging import Scene, convolve, render_stokes
    from scatterlab.runtime import get_executor

    angles = np.radians(cfg.polarizer_deg)
    cases = cases if cases is not None else [("no_turbulence", None)] + [(f"D_r0_{x:g}", float(x))
                                                                       for x in cfg.d_over_r0]
    metal = plate.metal_n - 1j * plate.metal_kappa
    paint = plate.paint_n - 1j * plate.paint_kappa
    materials = [paint, metal, metal]
    # scratches: bare metal of the plate's roughness (an isotropic pBRDF cannot give their wire-grid
    # polarization, and a smoother scratch would outshine the plate, which the measured images do not show)
    rough = [plate.paint_roughness, plate.metal_roughness, plate.metal_roughness]
    if cases[0][1] is not None:
        raise ValueError("cases must start with the no-turbulence case (name, None): it is the registration "
                         "reference and the diffraction-limited system")
    obs, tasks = [], []
    for th in thetas:
        th = float(th)
        S_obj = render_stokes(Scene(labels, materials, rough, th, th, np.pi))
        S_cam = render_stokes(Scene(foreshorten(labels, th), materials, rough, th, th, np.pi))
        o = {"theta": th, "truth_s0": S_obj[0], "truth_dolp": np.hypot(S_obj[1], S_obj[2]) / np.maximum(S_obj[0], 1e-300)}
        for name, dr0 in cases:
            counts, h, pupil = _acquire(S_cam, angles, dr0, cfg, rng)
            o[name] = {"counts": counts, "psf_true": h, "d_over_r0": dr0}
            if dr0 is not None:
                tasks.append(((len(obs), name), {"counts": counts, "angles": angles, "pupil": pupil,
                                                 "iterations": cfg.iterations, "priors": priors, "adaptive": adaptive,
                                                 "psf_model": cfg.psf_model, "checkpoint": checkpoint,
                                                 "seed": int(rng.integers(2**63))}))
        obs.append(o)
    ex = executor if executor is not None else get_executor("serial")
    results = ex.map(_correct_task, [t for _, t in tasks], desc=f"{plate.metal}: deconvolution")
    done = {key: r for (key, _), r in zip(tasks, results)}

    def classes_to_object(cls, th, shift):
        return apply_shift(keystone_correct(cls.astype(float), th, order=0), shift, order=0).astype(int)

    for k, o in enumerate(obs):
        th = o["theta"]
        ref = None  # the no-turbulence S0 in object coordinates: every other image is aligned with it
        for name, dr0 in cases:
            c = o[name]
            s0, dolp = _stokes_dolp(c["counts"], angles)
            s0_reg, (dolp_reg,), shift = register(s0, dolp[None], th, reference=ref)
            ref = s0_reg if ref is None else ref
            c["degraded"] = {"s0": s0_reg, "dolp": dolp_reg, "shift": shift}
            if priors:
                c["degraded"]["classes"] = classes_to_object(classify_dolp(dolp, priors), th, shift)
            if (k, name) in done:
                r = done[(k, name)]
                # the object estimate also seen through the no-turbulence (diffraction-limited) system, to
                # compare like with like against the no-turbulence image
                b0, b1 = convolve(np.stack([r["s0"], r["dolp"] * r["s0"]]), o[cases[0][0]]["psf_true"])
                others = np.stack([r["dolp"], b0, np.clip(b1 / np.maximum(b0, 1e-9), 0, 1)])
                s0_reg, (dolp_reg, b0_reg, bdolp_reg), sh = register(r["s0"], others, th, reference=ref)
                c["corrected"] = {"s0": s0_reg, "dolp": dolp_reg, "shift": sh, "psf": r["psf"],
                                  "loglik": r["loglik"], "priors": r["priors"], "reimaged_s0": b0_reg,
                                  "reimaged_dolp": bdolp_reg}
                if r["classes"] is not None:
                    c["corrected"]["classes"] = classes_to_object(r["classes"], th, sh)
    return obs


def interior(shape, margin):
    """Boolean mask of the pixels at least ``margin`` from the image edges (registration repeats edges)."""
    m = np.zeros(shape, bool)
    m[margin:shape[0] - margin, margin:shape[1] - margin] = True
    return m


def _rmse(a, b, sel):
    return float(np.sqrt(np.mean((a - b)[sel] ** 2)))


def characterize(cfg: SceneConfig, out, *, overwrite: bool = False, executor=None) -> Path:
    """Run the pipeline for ``cfg`` into the folder ``out``; returns the report path.

    Writes ``results.h5`` (groups per plate, geometry and case), ``report.md`` with PNG figures and
    ``summary.json``. Refuses to overwrite an existing report unless ``overwrite``.
    """
    import h5py

    from scatterlab.deconvolution import PRIOR_SETS, classification_errors
    from scatterlab.imaging import painted_plate
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
    theta = np.radians(cfg.geometry_deg)
    cases = [("no_turbulence", None)] + [(f"D_r0_{x:g}", float(x)) for x in cfg.d_over_r0]
    priors = None if cfg.priors == "none" or "classes" not in cfg.estimate else PRIOR_SETS[cfg.priors]
    mid = int(np.argmin(np.abs(np.asarray(cfg.geometry_deg) - 50)))  # Table 4 / Figs. 49-50 geometry
    sel = interior((cfg.image_size, cfg.image_size), max(2, cfg.image_size // 16))
    summary: dict = {"title": cfg.title, "cases": [c for c, _ in cases], "plates": {}}
    # deconvolutions are checkpointed as they finish: an interrupted run resumes where it stopped (same seed
    # and scene give the same data, hence the same checkpoint names); removed once the results are written
    checkpoints = out / "checkpoints"
    checkpoints.mkdir(exist_ok=True)
    tmp = out / "results.h5.part"
    with h5py.File(tmp, "w") as f5:
        f5.attrs["config"] = json.dumps(cfg.__dict__, default=lambda o: o.__dict__)
        for plate in progress(cfg.plates, desc="plates"):
            g_plate = f5.create_group(plate.metal)
            labels = painted_plate(cfg.image_size, theta=theta[0], rng=rng).labels
            g_plate["labels"] = labels
            obs = observe(plate, labels, theta, cfg, rng, priors=priors, executor=executor, cases=cases,
                          checkpoint=checkpoints)
            metal_lab = labels > 0
            psum: dict = {}
            # the images compared: no turbulence; per D/r0 degraded and corrected
            kinds = [("no_turbulence", "no_turbulence", "degraded")]
            for case, _ in cases[1:]:
                kinds += [(f"{case}_degraded", case, "degraded"), (f"{case}_corrected", case, "corrected")]
            for key, case, kind in kinds:
                stack = np.stack([o[case][kind]["dolp"] for o in obs])  # (M, H, W)
                truth = np.stack([o["truth_dolp"] for o in obs])
                ref = np.stack([o["no_turbulence"]["degraded"]["dolp"] for o in obs])
                seen = "reimaged_" if kind == "corrected" else ""  # like with like against the reference
                sel3 = np.broadcast_to(sel, stack.shape)
                cs = {"dolp_rmse_truth": _rmse(stack, truth, sel3),
                      "dolp_rmse_no_turbulence": _rmse(np.stack([o[case][kind][seen + "dolp"] for o in obs]), ref, sel3)}
                s0_ref = np.stack([o["no_turbulence"]["degraded"]["s0"] for o in obs])
                for name, s0, target in (("truth", np.stack([o[case][kind]["s0"] for o in obs]),
                                          np.stack([o["truth_s0"] for o in obs])),
                                         ("no_turbulence", np.stack([o[case][kind][seen + "s0"] for o in obs]), s0_ref)):
                    s0 = s0 * target[:, sel].sum() / max(s0[:, sel].sum(), 1e-300)  # flux normalised
                    cs[f"s0_relative_rmse_{name}"] = _rmse(s0, target, sel3) / float(target[:, sel].mean())
                if priors is not None:
                    cls = obs[mid][case][kind]["classes"]
                    metal_classes = tuple(range(1, len(priors)))
                    cs["classification_vs_no_turbulence"] = classification_errors(
                        cls, obs[mid]["no_turbulence"]["degraded"]["classes"], metal_classes=metal_classes, mask=sel)
                    cs["classification_vs_labels"] = classification_errors(
                        cls, metal_lab.astype(int), metal_classes=metal_classes, mask=sel)
                if "n_kappa" in cfg.estimate:
                    fit = fit_dolp(np.moveaxis(stack, 0, -1), theta, theta, sigma=cfg.sigma_known)
                    g = g_plate.require_group(key)
                    g["n"], g["kappa"], g["n_kappa_errors"] = fit.n, fit.kappa, fit.errors
                    for region, rsel, (tn, tk) in (("paint", ~metal_lab & sel, (plate.paint_n, plate.paint_kappa)),
                                                   (plate.metal, (labels == 1) & sel, (plate.metal_n, plate.metal_kappa))):
                        cs[region] = {"n_mean": float(np.nanmean(fit.n[rsel])), "n_std": float(np.nanstd(fit.n[rsel])),
                                      "kappa_mean": float(np.nanmean(fit.kappa[rsel])),
                                      "kappa_std": float(np.nanstd(fit.kappa[rsel])),
                                      "n_median_abs_error": float(np.nanmedian(np.abs(fit.n[rsel] - tn))),
                                      "kappa_median_abs_error": float(np.nanmedian(np.abs(fit.kappa[rsel] - tk))),
                                      "index_median_abs_error": float(np.nanmedian(np.hypot(fit.n[rsel] - tn,
                                                                                           fit.kappa[rsel] - tk)))}
                if "posterior" in cfg.estimate and (kind == "corrected" or case == "no_turbulence"):
                    y = np.moveaxis(stack, 0, -1)
                    regions = [("paint", ~metal_lab & sel), (plate.metal, (labels == 1) & sel)]
                    means = np.stack([y[r].mean(0) for _, r in regions])  # (regions, geometries)
                    # the noise of a region-mean DOLP is a parameter: pixels are correlated by the PSF and the
                    # halo biases them alike, so the pixel scatter / sqrt(pixels) is only its floor (with fewer
                    # than three geometries the data cannot carry a noise parameter, and the floor is used)
                    floor = min(max(float(y[r].std(0).mean()) / np.sqrt(r.sum()), 1e-4) for _, r in regions)
                    noise = None if theta.size >= 3 else floor
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", ConvergenceWarning)
                        posts = sample_posteriors(means, theta, theta, noise, rng, sigma=cfg.sigma_known,
                                                  noise_bounds=(floor, 0.5), n_steps=cfg.posterior_steps,
                                                  executor=executor)
                    for (region, _), post in zip(regions, posts):
                        gg = g_plate.require_group(key).create_group(f"posterior_{region}")
                        gg["chain"] = post.chain
                        gg.attrs["summary"] = json.dumps(post.summary(), default=float)
                        s = post.summary()["parameters"]
                        cs[f"posterior_{region}"] = {p: [s[p]["median"], *s[p]["ci68"]] for p in ("n", "kappa", "noise")
                                                     if p in s}
                psum[key] = cs
            for o, deg in zip(obs, cfg.geometry_deg):
                gt = g_plate.create_group(f"theta_{deg:g}")
                gt["dolp_truth"] = o["truth_dolp"]
                for case, _ in cases:
                    gc = gt.create_group(case)
                    c = o[case]
                    gc["counts"] = c["counts"].astype(np.float32)
                    gc["psf_true"] = c["psf_true"]
                    for kind in ("degraded", "corrected"):
                        if kind not in c:
                            continue
                        for name in ("s0", "dolp", "classes", "psf", "loglik", "shift"):
                            if c[kind].get(name) is not None:
                                gc[f"{name}_{kind}"] = c[kind][name]
            summary["plates"][plate.metal] = psum
            _plate_figure(out, plate.metal, labels, obs, g_plate, kinds, cfg, mid, overwrite)
    summary["seconds"] = time.perf_counter() - t_start
    final = out / "results.h5"
    if final.exists() and not overwrite:
        tmp.unlink()
        raise FileExistsError(f"{final} exists; pass overwrite=True")
    tmp.replace(final)  # atomic: a run interrupted before here leaves no half-written results.h5
    write_json(out / "summary.json", summary, overwrite=overwrite)
    report = _write_report(out, cfg, summary, overwrite)
    import shutil

    shutil.rmtree(checkpoints, ignore_errors=True)
    return report


def _plate_figure(out, name, labels, obs, g_plate, kinds, cfg, mid, overwrite):
    """Figs. 49-50 and 59-61 in one sheet: S0, DOLP and classes at the middle geometry, n and kappa maps
    (all geometries), one column per image kind (no turbulence; degraded and corrected per D/r0)."""
    import io

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from scatterlab.runtime.results import atomic_write_bytes

    rows = ["S0", "DOLP"]
    if "classes" in obs[mid]["no_turbulence"]["degraded"]:
        rows.append("classes")
    if "n_kappa" in cfg.estimate:
        rows += ["n", "kappa"]
    fig, axes = plt.subplots(len(rows), len(kinds), figsize=(2.8 * len(kinds), 2.7 * len(rows)), squeeze=False)
    for j, (key, case, kind) in enumerate(kinds):
        im = obs[mid][case][kind]
        for i, row in enumerate(rows):
            ax = axes[i, j]
            if row == "S0":
                ax.imshow(np.sqrt(np.clip(im["s0"], 0, None)), cmap="gray")
            elif row == "DOLP":
                ax.imshow(im["dolp"], vmin=0, vmax=1)
            elif row == "classes":
                ax.imshow(im["classes"], cmap="tab10", vmin=0, vmax=9, interpolation="nearest")
            elif row == "n":
                ax.imshow(g_plate[key]["n"][()], vmin=0, vmax=5)
            else:
                ax.imshow(g_plate[key]["kappa"][()], vmin=0, vmax=25)
            ax.set_xticks([])
            ax.set_yticks([])
        axes[0, j].set_title(key.replace("_", " "), fontsize=8)
    for i, row in enumerate(rows):
        axes[i, 0].set_ylabel(row, fontsize=9)
    fig.suptitle(f"{name} plate: images at theta = {cfg.geometry_deg[mid]} deg (sqrt S0); n, kappa from all "
                 "geometries; object coordinates", fontsize=9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    atomic_write_bytes(Path(out) / f"{name}.png", buf.getvalue(), overwrite=overwrite)


def _write_report(out, cfg, summary, overwrite):
    from scatterlab.characterization.reference_tables import TABLE4, TABLE5
    from scatterlab.runtime.results import write_text

    mid = int(np.argmin(np.abs(np.asarray(cfg.geometry_deg) - 50)))
    lines = [f"# Characterization: {cfg.title}", "",
             f"{cfg.wavelength_um:g} um, geometries {cfg.geometry_deg} deg (specular), D/r0 {cfg.d_over_r0}, "
             f"{cfg.photons:g} photo-electrons "
             f"peak, {cfg.image_size}^2 pixels, polarizers {cfg.polarizer_deg} deg, {cfg.iterations} EM iterations "
             f"({cfg.psf_model} PSFs), "
             f"priors {cfg.priors}, sigma {cfg.sigma_known} (known). Run time {summary['seconds']:.0f} s. "
             "Data: `results.h5`; numbers: `summary.json`. Images are keystone-corrected to object coordinates and "
             "aligned with the no-turbulence image; statistics exclude a border of 1/16 of the image. "
             "Reference values in brackets are the text's measured Tables 4 and 5 (real plates, so they show "
             "the trend to expect, not numbers to match).", ""]
    for plate, psum in summary["plates"].items():
        lines += [f"## {plate} plate", "", "Errors against the object (truth) and against the no-turbulence image "
                  "(corrected estimates re-imaged through the diffraction-limited PSF first; S0 flux-normalised):", "",
                  "| image | DOLP RMSE vs truth | DOLP RMSE vs no turbulence | S0 rel. RMSE vs truth | "
                  "S0 rel. RMSE vs no turbulence |", "|---|---|---|---|---|"]
        for key, cs in psum.items():
            lines.append(f"| {key} | {cs['dolp_rmse_truth']:.3f} | {cs['dolp_rmse_no_turbulence']:.3f} | "
                         f"{cs['s0_relative_rmse_truth']:.3f} | {cs['s0_relative_rmse_no_turbulence']:.3f} |")
        if any("classification_vs_no_turbulence" in cs for cs in psum.values()):
            lines += ["", f"Classification at {cfg.geometry_deg[mid]} deg against the no-turbulence classification "
                      "(Table 4's columns) and, last column, the total error against the true labels:", "",
                      "| image | wrongly metal | wrongly dielectric | total | corr. coef. | RMSE | total vs labels |",
                      "|---|---|---|---|---|---|---|"]
            for key, cs in psum.items():
                c = cs.get("classification_vs_no_turbulence")
                if c is None or key == "no_turbulence":
                    continue
                ref = TABLE4.get(plate, {}).get(key)
                refs = f" [{ref[2]:.4f}]" if ref else ""
                lines.append(f"| {key} | {c['false_metal']:.4f} | {c['false_dielectric']:.4f} | "
                             f"{c['total_error']:.4f}{refs} | {c['correlation']:.4f} | {c['rmse']:.4f} | "
                             f"{cs['classification_vs_labels']['total_error']:.4f} |")
        if any("paint" in cs for cs in psum.values()):
            lines += ["", "n and kappa per region, mean and standard deviation over the pixels (Table 5), and the "
                      "median over the pixels of |eta - eta_true| (truth: the scene's indices):", "",
                      "| image | paint E[n] | sd | E[kappa] | sd | metal E[n] | sd | E[kappa] | sd | "
                      "paint median abs. error | metal median abs. error |",
                      "|---|---|---|---|---|---|---|---|---|---|---|"]
            for key, cs in psum.items():
                cells = []
                for region, rkey in (("paint", "paint"), (plate, "metal")):
                    d = cs[region]
                    ref = TABLE5.get(plate, {}).get(rkey, {}).get(key)
                    vals = (d["n_mean"], d["n_std"], d["kappa_mean"], d["kappa_std"])
                    cells += [f"{v:.3f}" + (f" [{r:.3g}]" if ref else "") for v, r in zip(vals, ref or vals)]
                cells += [f"{cs[r]['index_median_abs_error']:.3f}" for r in ("paint", plate)]
                lines.append(f"| {key} | " + " | ".join(cells) + " |")
        lines += ["", f"![{plate}]({plate}.png)", ""]
        post = {c: cs for c, cs in psum.items() if "posterior_paint" in cs}
        if post:
            lines += ["Posterior of the region-mean DOLP over the geometries (its noise inferred too), median and 68 % "
                      "interval:", ""]
            for key, cs in post.items():
                for region in ("paint", plate):
                    p = cs[f"posterior_{region}"]
                    lines.append(f"- {key}, {region}: n {p['n'][0]:.3f} [{p['n'][1]:.3f}, {p['n'][2]:.3f}], "
                                 f"kappa {p['kappa'][0]:.3f} [{p['kappa'][1]:.3f}, {p['kappa'][2]:.3f}]"
                                 + (f", DOLP noise {p['noise'][0]:.4f}" if "noise" in p else ""))
            lines.append("")
    return write_text(Path(out) / "report.md", "\n".join(lines), overwrite=overwrite)
