"""The Markdown text of the characterization report, generated from the numbers (no fixed wording)."""

from __future__ import annotations

import math

from scatterlab.characterization.estimation import DETERMINED_CONTRACTION

__all__ = ["report_markdown"]


def _header(cfg, seconds, ideal) -> list:
    ideal_note = "" if ideal.label() == "none" else f" **Ideal stages: {ideal.label()}.**"
    return [
        f"# Characterization: {cfg.title}",
        "",
        f"{cfg.wavelength_um:g} um, specular geometries {cfg.geometry_deg} deg, "
        + (f"D/r0 {cfg.d_over_r0}, " if cfg.d_over_r0 else "no turbulent case, ")
        + f"{cfg.photons:g} photo-electrons at the brightest channel pixel, {cfg.read_noise:g} e- read noise, "
        f"{cfg.image_size}^2 pixels (2 per lambda/D), polarizers {cfg.polarizer_deg} deg, "
        + _psf_estimator(cfg)
        + f", priors {cfg.priors}, seed {cfg.seed}. Run time {seconds:.0f} s.{ideal_note}",
        "",
        _inversion_note(cfg),
        "",
        "The no-turbulence image is deconvolved with its known diffraction-limited PSF (`no turbulence`) "
        "and is the reference the others are compared with; `raw` is the same image without restoration. "
        "Images are keystone-corrected to object coordinates and aligned with the reference; statistics "
        "exclude a border of 1/16 of the image and the pixels an alignment brings in from beyond the "
        "camera's field (left blank in the figures), and region statistics a margin at the paint/metal "
        "edges. "
        "This is a simulation: the truth is shown beside every estimate."
        + _published_note(cfg)
        + " Data: `results.h5`; every number: `summary.json`.",
        "",
    ]


def _inversion_note(cfg) -> str:
    """What the inversion is given and what its intervals leave out: the roughness held at the truth, the
    same pBRDF making and inverting the data, and the restoration's settings."""
    model = (
        "The inversion adds the tabulated pBRDF model error (scene key `model_error`)."
        if cfg.model_error
        else "The same pBRDF renders the scene and inverts it, with no model error "
        "(scene key `model_error`): the paint's intervals are as narrow as the data allow, and on "
        "measured data, where the model is only an approximation, they are wider."
    )
    starts = (
        f"{cfg.blind_starts} random start PSFs per blind restoration, averaged"
        if cfg.blind_starts > 1
        else "one random start PSF per blind restoration"
    )
    return (
        "eta = n - j kappa is the complex index of refraction. The roughness (rms facet slope "
        f"{cfg.sigma_known:g}) is given to the inversion at its true value and only n and kappa are "
        f"estimated. {model} Restoration: {starts}; the self-calibration re-simulates each geometry "
        f"{cfg.calibration_replicates} times to measure the restoration's DOLP bias. The reference text is "
        "*Determining the index of refraction of an unknown object using passive polarimetric imagery "
        "degraded by atmospheric turbulence* (AFIT/DEE/ENG/10-12, 2010)."
    )


def _published_note(cfg) -> str:
    """The header's sentence on the reference text's published numbers, for plates that have them."""
    from scatterlab.characterization.reference_tables import TABLE4, TABLE5

    if not any(p.metal in TABLE4 or p.metal in TABLE5 for p in cfg.plates):
        return ""
    return (
        " Bracketed numbers in the classification and per-pixel tables are the reference text's measured "
        "Tables 4 and 5 (real plates: the trend to expect, not numbers to match)."
    )


def _psf_estimator(cfg) -> str:
    """How the turbulent images' PSFs were found, for the header."""
    if _uses_diversity(cfg):
        waves = cfg.phase_diversity_waves
        per = (
            ", ".join(f"+-{w:g} at D/r0 {d:g}" for w, d in zip(waves, cfg.d_over_r0))
            if isinstance(waves, list)
            else f"+-{waves:g}"
        )
        return (
            f"PSFs by phase diversity (two unpolarized cameras defocused by {per} waves, "
            f"{cfg.phase_diversity_share:.0%} of the light), then known-PSF EM"
        )
    refined = ", refined with a few-material object" if cfg.psf_refine == "layout" else ""
    return f"{cfg.iterations} EM iterations ({cfg.psf_model} PSFs{refined})"


def _errors_table(psum, estimate="blind") -> list:
    lines = [
        "| image | DOLP RMSE vs truth | DOLP RMSE vs no turbulence | S0 rel. RMSE vs truth | "
        "S0 rel. RMSE vs no turbulence | PSF estimate: L1 from the true PSF |",
        "|---|---|---|---|---|---|",
    ]
    for key, cs in psum.items():
        psf = f"{cs['psf_l1_error']:.2f}" if "psf_l1_error" in cs else "--"
        if "psf_l1_diffraction_limited" in cs:
            psf += f" ({cs['psf_l1_diffraction_limited']:.2f})"
        lines.append(
            f"| {key} | {cs['dolp_rmse_truth']:.3f} | {cs['dolp_rmse_no_turbulence']:.3f} | "
            f"{cs['s0_relative_rmse_truth']:.3f} | {cs['s0_relative_rmse_no_turbulence']:.3f} | "
            f"{psf} |"
        )
    lines += [
        "",
        f"PSF L1: the {estimate} estimate's distance from the PSF the data were blurred with, after the best "
        "integer shift, mean over the geometries (0 = the true PSF, 2 = disjoint); in brackets the "
        "diffraction-limited PSF's, what an estimate that knows nothing of the turbulence would score. "
        "S0 rel. RMSE: the RMS difference of the flux-matched S0 from its target, divided by the target's "
        "mean S0 over the image's interior.",
    ]
    return lines + _away_from_edges_table(psum)


def _away_from_edges_table(psum) -> list:
    """The errors against the truth without the paint/metal edges, and what the difference means."""
    keys = ("dolp_rmse_truth_away_from_edges", "s0_relative_rmse_truth_away_from_edges")
    rows = {k: cs for k, cs in psum.items() if all(q in cs for q in keys)}
    if not rows:
        return []
    lines = [
        "",
        "The same errors against the truth away from the paint/metal edges (the eroded region masks of "
        "the n, kappa statistics below; S0 with the same flux scale and normaliser):",
        "",
        "| image | DOLP RMSE vs truth, away from edges | S0 rel. RMSE vs truth, away from edges |",
        "|---|---|---|",
    ]
    lines += [f"| {k} | {cs[keys[0]]:.3f} | {cs[keys[1]]:.3f} |" for k, cs in rows.items()]
    ref = rows.get("no_turbulence")
    if ref is not None and ref["s0_relative_rmse_truth"] > 0:
        share = 1 - (ref[keys[1]] / ref["s0_relative_rmse_truth"]) ** 2
        lines += [
            "",
            f"Even without turbulence the S0 error against the truth is {ref['s0_relative_rmse_truth']:.3f} "
            f"over the field and {ref[keys[1]]:.3f} away from the edges: {share:.1%} of its square sits "
            "on the edges, where the metal's step in brightness meets a camera that resolves lambda/D "
            "and a keystone correction that interpolates each camera column over 1/cos(theta) object "
            "columns. No restoration removes that part; the error away from edges is the restoration's.",
        ]
    return lines


def _classification_table(plate, psum, mid_deg, priors="ch7") -> list:
    from scatterlab.characterization.reference_tables import TABLE4

    # Table 4 is two classes at 50 deg: beside another geometry or the three classes of Ch. VI it
    # would compare unlike things
    comparable = mid_deg == 50 and priors in ("ch5", "ch7")
    classes = (
        " (its three classes, aluminium group, iron group and dielectric, counted as metal or "
        "dielectric)"
        if priors == "ch6"
        else ""
    )
    lines = [
        "",
        f"Classification at {mid_deg} deg{classes} against the no-turbulence classification, in "
        "Table 4's columns (wrongly metal per dielectric pixel, wrongly dielectric per metal pixel, "
        "total over all pixels), and the total error against the true labels"
        + (
            ":"
            if comparable
            else f". Table 4's published values (two classes at 50 deg) are not shown: this scene "
            f"classifies at {mid_deg} deg with the {priors} priors."
        ),
        "",
        "| image | wrongly metal | wrongly dielectric | total"
        + (" [Table 4]" if comparable else "")
        + " | corr. coef. | RMSE | total vs labels |",
        "|---|---|---|---|---|---|---|",
    ]
    for key, cs in psum.items():
        c = cs.get("classification_vs_no_turbulence")
        if c is None or key.startswith("no_turbulence"):
            continue
        ref = TABLE4.get(plate, {}).get(key) if comparable else None
        refs = f" [{ref[2]:.4f}]" if ref else ""
        lines.append(
            f"| {key} | {c['false_metal_rate']:.4f} | {c['false_dielectric_rate']:.4f} | "
            f"{c['total_error']:.4f}{refs} | {c['correlation']:.4f} | {c['rmse']:.4f} | "
            f"{cs['classification_vs_labels']['total_error']:.4f} |"
        )
    return lines


def _pixel_table(plate, psum) -> list:
    from scatterlab.characterization.reference_tables import TABLE5

    first = next(cs for cs in psum.values() if "paint" in cs)
    lines = [
        "",
        "n and kappa per pixel: mean and standard deviation over each region (Table 5) and the "
        "median over its pixels of |eta - eta_true|. Truth: paint "
        f"{first['paint']['n_truth']:.2f} - j{first['paint']['kappa_truth']:.2f}, {plate} "
        f"{first[plate]['n_truth']:.2f} - j{first[plate]['kappa_truth']:.2f}. The last columns give "
        "the share of pixels fitted on a bound of the fit (n 0 or 5, kappa 0 or 25): their values are "
        "the bound, not a measurement, and a mean over many of them says little.",
        "",
        "| image | paint E[n] | sd | E[kappa] | sd | metal E[n] | sd | E[kappa] | sd | "
        "paint median abs. error | metal median abs. error | paint / metal pixels at a bound |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for key, cs in psum.items():
        if "paint" not in cs:
            continue
        cells = []
        for region, rkey in (("paint", "paint"), (plate, "metal")):
            d = cs[region]
            ref = TABLE5.get(plate, {}).get(rkey, {}).get(key)
            vals = (d["n_mean"], d["n_std"], d["kappa_mean"], d["kappa_std"])
            cells += [
                f"{v:.3f}" + (f" [{r:.3g}]" if ref else "") for v, r in zip(vals, ref or vals)
            ]
        cells += [f"{cs[r]['index_median_abs_error']:.3f}" for r in ("paint", plate)]
        cells.append(
            " / ".join(
                f"{100 * cs[r].get('share_at_fit_bound', 0.0):.0f} %" for r in ("paint", plate)
            )
        )
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return lines


def decimals_for(truth, *ends, least: int = 3, most: int = 6) -> int:
    """Decimals that keep ``truth`` apart from the interval ``ends`` when printed (3 unless the truth
    lies within a unit of the last digit of an end: a miss by 4e-4 must not print as a hit).

    Parameters
    ----------
    truth : float
    *ends : float
        Interval ends.
    least, most : int
        Range of decimals.

    Returns
    -------
    int
    """
    d = least
    while d < most and any(abs(truth - e) < 10.0**-d for e in ends):
        d += 1
    return d


def _with_truth(e) -> str:
    """``median [lo, hi]`` of a posterior entry, with enough decimals to tell its truth from the ends."""
    d = decimals_for(e["truth"], *e["ci68"], *e["ci95"])
    return f"{e['median']:.{d}f} [{e['ci68'][0]:.{d}f}, {e['ci68'][1]:.{d}f}]", d


def _prior_text(plate) -> str:
    """The posteriors' prior ranges, for the sentence above the posterior table."""
    ranges = [
        f"{'paint' if r == 'paint' else plate.metal} n in {list(b['n'])}, kappa in {list(b['kappa'])}"
        for r in ("paint", "metal")
        for b in [plate.prior_bounds(r)]
    ]
    return "Uniform prior: " + "; ".join(ranges) + "."


def _posterior_lines(plate, psum, prior_text="") -> list:
    post = {k: cs for k, cs in psum.items() if "posterior_paint" in cs}
    if not post:
        return []
    lines = [
        "",
        "Posterior of n and kappa from each region's mean DOLP over the geometries (its error from "
        "the self-calibration's re-simulations, or from the pixel scatter and the edge sensitivity "
        "plus an inferred noise): median, 68 % and 95 % intervals, the truth, whether the intervals "
        "cover it, and whether the truth lies in the joint (n, kappa) likelihood-ratio region at "
        "68 / 95 %. Where the data fix only a combination of n and kappa (for aluminium "
        "at these geometries; the note below the table says when), the marginal intervals follow the prior and "
        "the joint region is the calibrated statement." + (f" {prior_text}" if prior_text else ""),
        "",
        "| image | region | n [68 %] | n 95 % | kappa [68 %] | kappa 95 % | truth | covered 68 / 95 % "
        "| joint region 68 / 95 % |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    notes = []
    for key, cs in post.items():
        for region in ("paint", plate):
            p = cs[f"posterior_{region}"]
            n, k = p["n"], p["kappa"]
            cov = " ".join(
                f"{q}: {'yes' if p[q]['covers68'] else '**no**'}/"
                f"{'yes' if p[q]['covers95'] else '**no**'}"
                for q in ("n", "kappa")
            )
            flag = "" if p["converged"] else " (not converged)"
            j = p.get("joint")
            joint = (
                "-"
                if j is None
                else f"{'yes' if j['covers68'] else '**no**'}/{'yes' if j['covers95'] else '**no**'}"
            )
            (n68, dn), (k68, dk) = _with_truth(n), _with_truth(k)
            lines.append(
                f"| {key} | {region}{flag} | {n68} | [{n['ci95'][0]:.{dn}f}, {n['ci95'][1]:.{dn}f}] "
                f"| {k68} | [{k['ci95'][0]:.{dk}f}, {k['ci95'][1]:.{dk}f}] | "
                f"{n['truth']:.{max(dn - 1, 2)}f} - j{k['truth']:.{max(dk - 1, 2)}f} | {cov} | {joint} |"
            )
            notes += [f"- **{key}, {region}:** {w}" for w in p["warnings"]]
    return lines + ([""] + notes if notes else [])


def report_markdown(cfg, results, checks, *, seconds, ideal) -> str:
    """The whole ``report.md``: per plate the error, classification, n/kappa and posterior tables, the figure,
    and the acceptance checks with the number each rests on.

    Parameters
    ----------
    cfg : SceneConfig
    results : list of PlateResult
    checks : list of (str, str, bool)
        From :func:`~scatterlab.characterization.report.acceptance_checks`.
    seconds : float
        Run time [s].
    ideal : Ideal

    Returns
    -------
    str
        Markdown.
    """
    import numpy as np

    lines = _header(cfg, seconds, ideal)
    mid_deg = cfg.geometry_deg[int(np.argmin(np.abs(np.asarray(cfg.geometry_deg) - 50)))]
    for res in results:
        plate, psum = res.plate.metal, res.metrics
        lines += [
            f"## {plate} plate",
            "",
            "Errors against the object (truth) and against the restored "
            "no-turbulence image (S0 flux-normalised per geometry, each exposed for itself):",
            "",
        ]
        lines += _errors_table(psum, _estimate_name(cfg))
        if any("classification_vs_no_turbulence" in cs for cs in psum.values()):
            lines += _classification_table(plate, psum, mid_deg, cfg.priors)
        if any("paint" in cs for cs in psum.values()):
            lines += _pixel_table(plate, psum)
        lines += _posterior_lines(plate, psum, _prior_text(res.plate))
        lines += ["", f"![{plate}]({plate}.png)", "", _figure_caption(plate, mid_deg, cfg), ""]
    if checks:
        failed = sum(not ok for _, _, ok in checks)
        lines += [
            "## Checks against the truth",
            "",
            f"{len(checks) - failed} of {len(checks)} checks pass"
            + (":" if not failed else f"; **{failed} fail**:"),
            "",
            "The checks are the accuracy this scene is held to (docs/characterization_accuracy.md). A "
            "calibrated 68 % interval misses its truth one time in "
            "three, so the paint's no-turbulence intervals and the joint regions are not checked one by "
            "one (the posterior tables say whether each covers): they are checked together, for more "
            "misses than calibrated statements would give. The binomial chance counts them as "
            "independent; the statements of one posterior (its n, its kappa, its joint region) tend to "
            "miss together, which makes many misses likelier than that chance says, so the check errs "
            "toward failing. The metal's 68 % intervals are checked one by one (the "
            "truth within one half-width of the posterior).",
            "",
            "| check | value | result |",
            "|---|---|---|",
        ]
        lines += [f"| {c} | {v} | {'pass' if ok else '**FAIL**'} |" for c, v, ok in checks]
        lines += _failure_notes(results, checks, ideal, _estimate_name(cfg))
    return "\n".join(lines) + "\n"


def _figure_caption(plate, mid_deg, cfg) -> str:
    """What the plate figure shows, row by row and column by column."""
    from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

    (n_lo, n_hi), (k_lo, k_hi) = DEFAULT_BOUNDS["n"], DEFAULT_BOUNDS["kappa"]
    rows = "S0 (square root, one grey scale for all panels), DOLP"
    rows += ", classes" if "classes" in cfg.estimate else ""
    rows += (
        ", and n and kappa fitted pixel by pixel over all geometries (scaled to twice the plate's true "
        "values within the fit's box; cyan where the fit stopped on the box's edge, n "
        f"{n_lo:g} or {n_hi:g}, kappa {k_lo:g} or {k_hi:g}: the best fit to that pixel's DOLP lies "
        "beyond the box, and the value shown is the bound, not an estimate)"
        if "n_kappa" in cfg.estimate
        else ""
    )
    return (
        f"*Figure: the {plate} plate at theta = {mid_deg:g} deg in object coordinates. Rows: {rows}. "
        f"Scale: {cfg.image_size} object pixels across; an object pixel is the patch of plate a camera "
        "pixel sees head-on, half a lambda/D, so the diffraction-limited resolution lambda/D spans 2 "
        "object pixels vertically (across the plane of incidence) and 2/cos(theta) horizontally "
        f"({2 / math.cos(math.radians(mid_deg)):.1f} here), where the camera sees the plate foreshortened. "
        "Columns: the object (truth), the no-turbulence image restored with its PSF and raw, then each "
        "D/r0's degraded and corrected images. Blank pixels were brought in from beyond the camera's "
        "field by the alignment (not measured); an arrow on a colour bar means values beyond it are "
        "clipped.*"
    )


def _estimate_name(cfg) -> str:
    return "phase-diversity" if _uses_diversity(cfg) else "blind"


def _uses_diversity(cfg) -> bool:
    waves = cfg.phase_diversity_waves
    return any(w > 0 for w in (waves if isinstance(waves, list) else [waves]))


def _pixel_bound_note(results, failed) -> str:
    """The Cramer-Rao bound of one metal pixel at each image's own pixel scatter, for the plates whose
    median |eta error| check failed: where it exceeds the fit's box, no estimator places a pixel."""
    from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

    rows = []
    for res in results:
        metal = res.plate.metal
        cases = [
            c.split("D/r0 = ")[1].split(":")[0]
            for c in failed
            if "median |eta error|" in c and f"the {metal}'s" in c and c.startswith(f"{metal},")
        ]
        keys = ["no_turbulence"]
        for case in cases:
            keys += [f"D_r0_{case}_degraded", f"D_r0_{case}_corrected"]
        parts = []
        for key in keys:
            d = res.metrics.get(key, {}).get(metal, {})
            if "pixel_crlb_kappa" not in d:
                continue
            name = key.replace("D_r0_", "D/r0 = ").replace("_", " ")
            parts.append(
                f"{name} {d['pixel_dolp_scatter']:.4f}: n +-{d['pixel_crlb_n']:.3g}, "
                f"kappa +-{d['pixel_crlb_kappa']:.3g}"
            )
        if cases and parts:
            rows.append(f"{metal}: " + "; ".join(parts))
    if not rows:
        return ""
    (n_lo, n_hi), (k_lo, k_hi) = DEFAULT_BOUNDS["n"], DEFAULT_BOUNDS["kappa"]
    return (
        "\n- **What one pixel can tell.** The Cramer-Rao bound of one pixel of the true metal, at each "
        "image's own pixel scatter (the robust spread of the region's DOLP, RMS over the geometries): "
        + "; ".join(rows)
        + f". Where a bound exceeds the fit's box (n {n_lo:g}-{n_hi:g}, kappa {k_lo:g}-{k_hi:g}), no "
        "estimator places a single pixel, and the median of the pixel fits says where in the box they "
        "land rather than how accurate the image is."
    )


def _ghost_counts(results) -> str:
    """This run's wrongly-metal pixels of each corrected image against its degraded image's, with the
    pixels scored, as a sentence that says whether the corrected images add ghosts."""
    parts, more = [], False
    for res in results:
        for key, cor in res.metrics.items():
            if not key.endswith("_corrected"):
                continue
            deg = res.metrics.get(key.replace("_corrected", "_degraded"), {})
            c = cor.get("classification_vs_no_turbulence")
            d = deg.get("classification_vs_no_turbulence")
            if not c or not d:
                continue
            case = key.removesuffix("_corrected").replace("D_r0_", "D/r0 = ")
            scored = [f"{x['pixels']:,}".replace(",", " ") for x in (c, d)]
            ghosts = [round(x["false_metal"] * x["pixels"]) for x in (c, d)]
            more |= ghosts[0] > ghosts[1]
            parts.append(
                f"{res.plate.metal}, {case}: {ghosts[0]} against {ghosts[1]} in the degraded image, "
                f"of {scored[0]} and {scored[1]} pixels scored"
            )
    if not parts:
        return ""
    counts = "; ".join(parts)
    if more:
        return f"What a corrected image adds is its ghosts, pixels wrongly metal: {counts}."
    return (
        f"The corrected images here have no more pixels wrongly metal than the degraded ones ({counts}): "
        "their excess is metal called paint, at the edges and scratches."
    )


def _failure_notes(results, checks, ideal, estimate="blind") -> list:
    """What the failed checks mean: the cause measured in this run, or what one run can and cannot show."""
    failed = [c for c, _, ok in checks if not ok]
    notes = []
    after = [c for c in failed if "D/r0" in c]
    if after and not ideal.psf and estimate == "phase-diversity":
        notes.append(
            f"- **{len(after)} failure{'s' if len(after) > 1 else ''} after deconvolution.** The "
            "turbulent images were restored with the PSFs phase diversity found (L1 distances from the "
            "true PSFs in the table above). Measured on the default scene's aluminium at 50 deg, +-1 "
            "wave found the PSF at D/r0 7.9 (L1 0.18-0.19, classification 0.032 after 2000 iterations, "
            "true PSF 0.023). At 12.9 even +-2 waves stop far from it (L1 0.6-1.0). On a smaller "
            "plate a fit started at the true phase stays close to it at a better likelihood than cold "
            "starts reach with the same effort, but longer searches and random restarts come within "
            "10-25 % of that likelihood with PSFs as far off as before: the maximum-likelihood object "
            "absorbs much of a wrong PSF. On this scene 1000 iterations per stage instead of 300 did "
            "not close the gap (`docs/characterization_accuracy.md`)."
        )
    elif after and not ideal.psf:
        dist = ", ".join(
            f"{res.plate.metal} {key.removesuffix('_corrected').replace('D_r0_', 'D/r0 = ')}: "
            f"{cs['psf_l1_error']:.2f}"
            for res in results
            for key, cs in res.metrics.items()
            if "psf_l1_error" in cs
        )
        plural = "s" if len(after) > 1 else ""
        metals = {res.plate.metal for res in results}
        text = (
            f"- **{len(after)} failure{plural} after deconvolution.** The blind PSF estimates' L1 "
            f"distance from the true PSFs (0 = the true PSF, 2 = disjoint): {dist}. A wrong PSF leaves "
            "ghost copies of the scratches and of the metal's edges in the corrected images (parallel "
            "lines and streaks in the S0 and DOLP maps). Averaging the restorations of several random "
            "starts (scene key `blind_starts`) lowers them, since they change place with the start, "
            "but does not remove them; with the true PSF over the whole field the same restoration "
            "leaves none."
        )
        if any("median |eta error|" in c and any(f"the {m}'s" in c for m in metals) for c in after):
            text += (
                "\n- **The metal's per-pixel |eta error|** is another matter: a metal's DOLP is a few "
                "hundredths, a pixel's noise is of that order, and any deconvolution raises the noise of "
                "a pixel while the blur of the degraded image averages it. The paint's polarized light "
                "is many times the metal's own, and the share of its halo a restoration leaves in the "
                "metal raises the metal's DOLP as much as the blur does. Measured once on the bundled "
                "default scene (`docs/characterization_accuracy.md`; not this run's numbers): "
                "aluminium at D/r0 7.9, +0.005-0.026 after correction, +0.004-0.020 degraded, on a true "
                "0.003-0.016. With the true PSF the same restoration worsens the median too (aluminium "
                "9.60 against 9.51 at D/r0 7.9, 13.64 against 11.90 at 12.9; on another draw of its "
                "steel plate 1.51 against 1.21 and 1.71 against 1.42), and for aluminium the median "
                "does not rank DOLP errors: removing the degraded image's metal bias (from the truth) "
                "raises it from 9.51 to 13.07, since the per-pixel fit runs along the ridge of equal "
                "DOLP to its bounds whatever the error. The metal's measurement is its region "
                "posterior."
            )
            text += _pixel_bound_note(results, after)
        if any("classification" in c for c in after):
            text += (
                "\n- **The classification** unmixes the Stokes images, which puts the plate's edges "
                "where they are in the degraded and the corrected images alike. Neither classifies the "
                "scratches, one or two pixels wide: the blur leaves them less than half metal, and they "
                "are most of the classification error left in both images. "
                + _ghost_counts(results)
                + " Measured once on the bundled default scene (`docs/characterization_accuracy.md`), "
                "the true PSF with the same restoration leaves 42 and 223 of 12 544 pixels wrong "
                "against the degraded image's 377 and 397: the blind PSF holds it back."
            )
        text += (
            "\n- **What identifies the PSF.** Two defocused cameras beside the polarimeter (phase "
            "diversity, scene key `phase_diversity_waves`) identified the PSF of the bundled default "
            "scene at D/r0 7.9 but not at 12.9 (`docs/characterization_accuracy.md`)."
        )
        notes.append(text)
    # a metal's marginal interval follows the prior along its ridge of equal DOLP where the data
    # determine the parameter only partly (contraction below DETERMINED_CONTRACTION): its note says so;
    # a miss where the data do determine it is the error model's, and says that instead
    ridge, determined = [], []
    for res in results:
        post = res.metrics.get("no_turbulence", {}).get(f"posterior_{res.plate.metal}") or {}
        for q in ("n", "kappa"):
            check = f"{res.plate.metal}: {res.plate.metal} posterior 68 % interval of {q} covers"
            if not any(c.startswith(check) for c in failed):
                continue
            c = post.get(q, {}).get("contraction")
            weak = c is not None and c < DETERMINED_CONTRACTION
            flag = "" if post.get("converged", True) else ", its posterior not converged"
            (ridge if weak else determined).append(f"{res.plate.metal}'s {q}{flag}")
    if ridge:
        notes.append(
            f"- **{len(ridge)} of the metals' marginal 68 % intervals miss the truth where the data "
            f"determine the parameter only partly ({', '.join(ridge)}).** A metal's DOLP at these "
            "geometries fixes only a combination of n and kappa: its marginal interval follows the "
            "prior along that ridge (the note below its posterior table gives the contraction) and is "
            "not a calibrated statement; its joint (n, kappa) region is."
        )
    if determined:
        notes.append(
            f"- **{len(determined)} of the metals' marginal 68 % intervals miss the truth where the data "
            f"do determine the parameter ({', '.join(determined)}; posterior contraction at least "
            f"{DETERMINED_CONTRACTION:g}).** This is not the ridge: the interval is narrower than the "
            "errors left in the data, or a 68 % interval missing as it will one time in three, or, where "
            "the posterior is marked not converged, a chain too short to place it. The "
            "posterior table says whether the joint region covers; the coverage study "
            "(`studies/characterization_coverage.py`) measures the calibration over many seeds."
        )
    if any("statements" in c for c in failed):
        notes.append(
            "- **More statements miss the truth than calibrated ones would.** The intervals or regions "
            "that miss (posterior table) are narrower than the errors left in the data: the error model "
            "misses a term this scene has. The coverage study (`studies/characterization_coverage.py`) "
            "measures their calibration over many seeds."
        )
    return ["", "What the failures mean:", "", *notes] if notes else []
