"""Report stage: ``results.h5``, ``summary.json``, one figure per plate and ``report.md``.

The truth is known in a simulation, so it stands beside every estimate, each interval says whether it covers
it, and the report checks the run against the acceptance numbers of the main job (paint within 0.05 of the
truth without turbulence, metal within one 68 % half-width, classification error <= 0.06, correction never
worse than the degraded image). Convergence warnings are printed beside the numbers they concern. Everything
is written atomically; ``report.md`` is written last and marks a finished run.
"""

from __future__ import annotations

import io
import json
import platform
import shutil
from dataclasses import asdict
from pathlib import Path

import numpy as np

from scatterlab.characterization.pipeline import image_kinds

__all__ = ["RunFolder", "plate_figure", "write_all", "acceptance_checks", "versions", "save_png"]

CLASS_COLOURS = (
    "#2e7d32",
    "#9e9e9e",
    "#1565c0",
)  # dielectric (paint) green, metal grey, second metal blue
# n and kappa map pixels whose fit stopped on the box's edge (magma has no cyan)
AT_BOUND_COLOUR = "#00e5ff"


class RunFolder:
    """The output folder of one run: refuses a finished run unless ``overwrite``; resumes an unfinished one.

    Parameters
    ----------
    out : path
    overwrite : bool
    """

    def __init__(self, out, overwrite: bool):
        self.path = Path(out)
        if self.path.exists() and not self.path.is_dir():
            raise ValueError(f"--out {self.path} exists and is not a folder")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            self.checkpoints = self.path / "checkpoints"
            self.checkpoints.mkdir(exist_ok=True)
        except OSError as exc:
            raise ValueError(f"--out {self.path} cannot be written: {exc.strerror}") from None
        self.report = self.path / "report.md"
        if self.report.exists() and not overwrite:
            raise FileExistsError(
                f"{self.report} exists (a finished run); pass overwrite=True (--force on the command line)"
            )
        if self.report.exists():
            self.report.unlink()  # from here on the folder holds an unfinished run


def versions() -> dict:
    """Versions of Python and of the packages a run's numbers depend on (written into summaries).

    Returns
    -------
    dict
        Name -> version string: ``python``, ``numpy``, ``scipy``, ``emcee``, ``scatterlab``.
    """
    import emcee
    import scipy

    import scatterlab

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "emcee": emcee.__version__,
        "scatterlab": getattr(scatterlab, "__version__", "unknown"),
    }


def save_png(fig, path: Path) -> None:
    """Write a matplotlib figure as PNG (90 dpi, tight bounding box) atomically, then close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : Path
        The PNG file (replaced if it exists).

    Returns
    -------
    None
    """
    import matplotlib.pyplot as plt

    from scatterlab.runtime.results import atomic_write_bytes

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue(), overwrite=True)


_versions, _save_png = versions, save_png  # the former private names


def mark_fit_bound(ax, maps, values) -> np.ndarray:
    """Paint the pixels whose per-pixel fit stopped on its box's edge in :data:`AT_BOUND_COLOUR`
    over a panel of the n or kappa map: there the value is the bound, not an estimate.

    Parameters
    ----------
    ax : matplotlib Axes
        The panel.
    maps : PixelMaps
        The per-pixel fits (``n``, ``kappa``, arrays (H, W)).
    values : ndarray, shape (H, W)
        The panel's image; NaN pixels (not measured) are left blank.

    Returns
    -------
    ndarray of bool, shape (H, W)
        The pixels marked.
    """
    from matplotlib.colors import ListedColormap

    from scatterlab.characterization.metrics import at_fit_bound

    on = at_fit_bound(maps.n, maps.kappa) & np.isfinite(values)
    ax.imshow(
        np.ma.masked_array(np.ones(on.shape), ~on),
        cmap=ListedColormap([AT_BOUND_COLOUR]),
        vmin=0,
        vmax=1,
        interpolation="nearest",
    )
    return on


def _title(key: str) -> str:
    if key == "truth":
        return "truth (object)"
    if key == "no_turbulence":
        return "no turbulence (restored)"
    if key == "no_turbulence_unrestored":
        return "no turbulence (raw)"
    case, kind = key.rsplit("_", 1)
    return f"D/r0 = {case.removeprefix('D_r0_')}, {kind}"


def plate_figure(out, result, cfg) -> Path:
    """S0, DOLP and classes at the geometry nearest 50 deg, n and kappa maps (all geometries), one column per
    image after a column of the truth (the object), each row with one colour scale and its colour bar, and
    the class map with a legend (Figs. 49-50, 59-61).

    Parameters
    ----------
    out : path
        Output folder.
    result : PlateResult
    cfg : SceneConfig

    Returns
    -------
    Path
        The PNG written (``<metal>.png``).
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from scatterlab.plotting import headless_pyplot

    plt = headless_pyplot()
    kinds = image_kinds(cfg)
    mid = int(np.argmin(np.abs(np.asarray(cfg.geometry_deg) - 50)))
    o = result.observations[mid]
    rows = ["S0", "DOLP"] + (["classes"] if o.images[kinds[-1][1:]].classes is not None else [])
    rows += ["n", "kappa"] if "n_kappa" in cfg.estimate else []
    columns = [("truth", None, None)] + kinds  # the object the simulation knows, first
    fig, axes = plt.subplots(
        len(rows),
        len(columns),
        figsize=(2.6 * len(columns) + 1, 2.5 * len(rows)),
        squeeze=False,
        layout="constrained",
    )
    ncls = 1 + len(cfg.priors == "ch6" and (1, 2) or (1,))
    cmap_cls = ListedColormap(CLASS_COLOURS[:ncls])
    # the no-turbulence classification, shown in its column and naming the metal's class in the truth's
    ref_classes = _ref_classes(result, mid, cfg) if "classes" in rows else None
    truth = _truth_panels(result.plate, result.labels, o, kinds[0][1:], ref_classes)
    # one grey scale for every S0 panel, so the colour bar reads for all of them
    s0_top = max(
        float(np.nanpercentile(np.sqrt(np.clip(o.images[(case, kind)].s0, 0, None)), 99.5))
        for _, case, kind in kinds
    )
    # n and kappa on twice the plate's largest true value, within the fit's box (n 0-5, kappa 0-25): on
    # the box alone steel's kappa of 5.88 and the paint's 0.34 were the same dark colour
    index_top, extend = _index_scales(result.plate)
    # S0 is clipped at its 99.5th percentile; a signed DOLP can leave [0, 1]
    extend.update(S0="max", DOLP="both")
    for j, (key, case, kind) in enumerate(columns):
        img = o.images[(case, kind)] if key != "truth" else None
        maps = result.estimates[key].get("maps") if key != "truth" else None
        for i, row in enumerate(rows):
            ax = axes[i, j]
            if row == "S0":
                s0 = truth["S0"] if img is None else _measured_only(img.s0, img)
                im = ax.imshow(np.sqrt(np.clip(s0, 0, None)), cmap="gray", vmin=0, vmax=s0_top)
            elif row == "DOLP":
                im = ax.imshow(
                    truth["DOLP"] if img is None else _measured_only(img.dolp, img),
                    vmin=0,
                    vmax=1,
                    cmap="viridis",
                )
            elif row == "classes":
                if img is None:
                    classes = truth["classes"]
                else:
                    classes = img.classes if key != "no_turbulence" else ref_classes
                im = ax.imshow(
                    # not measured (-1, or beyond the camera's field): left blank
                    np.ma.masked_array(
                        classes, (classes < 0) | (img is not None and _unmeasured(img))
                    ),
                    cmap=cmap_cls,
                    vmin=-0.5,
                    vmax=ncls - 0.5,
                    interpolation="nearest",
                )
            else:
                values = (
                    truth[row]
                    if img is None
                    else _measured_everywhere(result, case, kind, maps, row)
                )
                im = ax.imshow(values, vmin=0, vmax=index_top[row], cmap="magma")
                if maps is not None:
                    mark_fit_bound(ax, maps, values)
            ax.set_xticks([])
            ax.set_yticks([])
            if j == len(columns) - 1 and row != "classes":
                fig.colorbar(
                    im,
                    ax=axes[i, :],
                    shrink=0.8,
                    label={"S0": "sqrt(S0) [sqrt(e-)]"}.get(row, row),
                    extend=extend[row],
                )
        axes[0, j].set_title(_title(key), fontsize=10)
    for i, row in enumerate(rows):
        axes[i, 0].set_ylabel(row, fontsize=11)
    if "n" in rows:
        axes[rows.index("n"), -1].legend(
            handles=[Patch(color=AT_BOUND_COLOUR, label="fit on its\nbox's edge")],
            loc="center left",
            bbox_to_anchor=(1.02, 0.5),
            fontsize=8,
        )
    if "classes" in rows:
        names = ["dielectric"] + (["aluminium", "iron"] if cfg.priors == "ch6" else ["metal"])
        axes[rows.index("classes"), -1].legend(
            handles=[Patch(color=c, label=n) for c, n in zip(CLASS_COLOURS, names)],
            loc="center left",
            bbox_to_anchor=(1.02, 0.5),
            fontsize=8,
        )
    fig.suptitle(
        f"{result.plate.metal} plate: images at theta = {cfg.geometry_deg[mid]} deg; "
        + ("n, kappa from all geometries; " if "n" in rows else "")
        + "object coordinates",
        fontsize=9,
    )
    path = Path(out) / f"{result.plate.metal}.png"
    _save_png(fig, path)
    return path


def _measured_everywhere(result, case, kind, maps, row):
    """A per-pixel map (n or kappa, fitted over all geometries) blank where any geometry's image did not
    measure the pixel."""
    values = np.asarray(getattr(maps, row), float)
    for o in result.observations:
        m = getattr(o.images[(case, kind)], "measured", None)
        if m is not None:
            values = np.where(m, values, np.nan)
    return values


def _unmeasured(img):
    """Bool (H, W) of the pixels ``img`` did not measure, or False when it measured all."""
    m = getattr(img, "measured", None)
    return False if m is None else ~m


def _measured_only(values, img):
    """``values`` with the pixels ``img`` did not measure (beyond the camera's field after registration)
    set to NaN, which the figure leaves blank."""
    m = getattr(img, "measured", None)
    return values if m is None else np.where(m, values, np.nan)


def _index_scales(plate) -> tuple:
    """Colour-scale tops of the n and kappa maps -- twice the plate's largest true value, within the fit's
    box -- and the colour bars' ``extend`` ("max" when a map can exceed its top)."""
    from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

    tops, extend = {}, {}
    for q, truths in (
        ("n", (plate.metal_n, plate.paint_n)),
        ("kappa", (plate.metal_kappa, plate.paint_kappa)),
    ):
        box = DEFAULT_BOUNDS[q][1]
        tops[q] = float(min(box, 2.0 * max(truths))) if max(truths) > 0 else box
        extend[q] = "max" if tops[q] < box else "neither"
    return tops, extend


def _truth_panels(plate, labels, o, reference, ref_classes=None) -> dict:
    """The object's panels for the figure: S0 scaled to the reference image's flux, DOLP, classes, n, kappa.

    The true classes (given ``ref_classes``, the no-turbulence classification) put the plate's metal and
    its scratches, bare metal, in the class the no-turbulence image gives most of it: with the Ch. VI
    priors that names the metal's group.
    """
    metal = np.asarray(labels) > 0
    scale = np.nansum(o.images[reference].s0) / max(float(np.nansum(o.truth_s0)), 1e-300)
    panels = {"S0": o.truth_s0 * scale, "DOLP": o.truth_dolp}
    if ref_classes is not None:
        ref = np.asarray(ref_classes)
        votes = np.bincount(ref[metal & (ref > 0)].ravel(), minlength=2)[1:]
        panels["classes"] = np.where(metal, int(np.argmax(votes)) + 1 if votes.sum() else 1, 0)
    panels["n"] = np.where(metal, plate.metal_n, plate.paint_n).astype(float)
    panels["kappa"] = np.where(metal, plate.metal_kappa, plate.paint_kappa).astype(float)
    return panels


def _ref_classes(result, mid, cfg):
    from scatterlab.characterization.metrics import reference_classes
    from scatterlab.deconvolution import PRIOR_SETS

    return reference_classes(result.observations[mid], PRIOR_SETS[cfg.priors])


def _write_h5(path: Path, cfg, results) -> None:
    import h5py

    tmp = path.with_suffix(".h5.part")
    with h5py.File(tmp, "w") as f5:
        f5.attrs["config"] = json.dumps(asdict(cfg))
        for res in results:
            g = f5.create_group(res.plate.metal)
            g["labels"] = res.labels
            for key, est in res.estimates.items():
                if not est:
                    continue
                gk = g.require_group(key)
                if "maps" in est:
                    gk["n"], gk["kappa"], gk["n_kappa_errors"] = (
                        est["maps"].n,
                        est["maps"].kappa,
                        est["maps"].errors,
                    )
                for r in est.get("regions", ()):
                    name = res.plate.metal if r.name == "metal" else r.name
                    gr = gk.create_group(f"posterior_{name}")
                    gr["chain"] = r.chain
                    gr.attrs["summary"] = json.dumps(r.parameters)
                    gr.attrs["converged"] = r.converged
            for o, deg in zip(res.observations, cfg.geometry_deg):
                gt = g.create_group(f"theta_{deg:g}")
                gt["dolp_truth"], gt["s0_truth"] = o.truth_dolp, o.truth_s0
                for case, acq in o.acquisitions.items():
                    gc = gt.create_group(case)
                    gc["counts"] = acq.counts.astype(np.float32)
                    gc["psf_true"] = acq.psf_true
                    for (c, kind), img in o.images.items():
                        if c != case:
                            continue
                        rest = o.restorations[(c, kind)]
                        for name, val in (
                            ("s0", img.s0),
                            ("dolp", img.dolp),
                            ("classes", img.classes),
                            ("shift", img.shift),
                            ("psf", rest.psf),
                            ("loglik", rest.loglik),
                            ("loglik_classes", rest.loglik_classes),
                        ):
                            if val is not None:
                                gc[f"{name}_{kind}"] = val
    tmp.replace(path)


def _interval_and_truth(e) -> str:
    """``median [lo, hi], truth t`` with enough decimals that a miss does not print as a hit."""
    from scatterlab.characterization.report_text import decimals_for

    d = decimals_for(e["truth"], *e["ci68"])
    return f"{e['median']:.{d}f} [{e['ci68'][0]:.{d}f}, {e['ci68'][1]:.{d}f}], truth {e['truth']:.{d}f}"


def acceptance_checks(cfg, results) -> list:
    """The main job's acceptance numbers, checked against the truth: list of (check, value, passed).

    Parameters
    ----------
    cfg : SceneConfig
    results : list of PlateResult

    Returns
    -------
    list of (str, str, bool)
        (check, the number it rests on, passed).
    """
    out, statements = [], []
    for res in results:
        p, m = res.plate, res.metrics
        nt = m.get("no_turbulence", {})
        if "paint" in nt:
            for q in ("n", "kappa"):
                err = abs(nt["paint"][f"{q}_mean"] - nt["paint"][f"{q}_truth"])
                out.append(
                    (
                        f"{p.metal}: paint per-pixel mean {q} within 0.05 of the truth (no turbulence)",
                        f"|error| {err:.3f}",
                        err <= 0.05,
                    )
                )
        for region in ("paint", p.metal):
            post = nt.get(f"posterior_{region}")
            if not post:
                continue
            for q in ("n", "kappa"):
                e = post[q]
                if region == "paint":
                    # item 3: the paint's region mean within 0.05; its interval is one calibrated
                    # statement among those counted below
                    err = abs(e["median"] - e["truth"])
                    out.append(
                        (
                            f"{p.metal}: paint posterior median of {q} within 0.05 of the truth "
                            "(no turbulence)",
                            _interval_and_truth(e),
                            err <= 0.05,
                        )
                    )
                    statements.append((e["covers68"], e["covers95"]))
                else:
                    # item 3: the metal within one 68 % half-width of its own posterior
                    out.append(
                        (
                            f"{p.metal}: {region} posterior 68 % interval of {q} covers the truth "
                            "(no turbulence)",
                            _interval_and_truth(e),
                            bool(e["covers68"]),
                        )
                    )
            j = post.get("joint")
            if j is not None:
                statements.append((j["covers68"], j["covers95"]))
        for case, _ in [(c, None) for c in cfg.d_over_r0]:
            key = f"D_r0_{case:g}"
            cor, deg = m.get(f"{key}_corrected", {}), m.get(f"{key}_degraded", {})
            c = cor.get("classification_vs_no_turbulence")
            if c:
                out.append(
                    (
                        f"{p.metal}, D/r0 = {case:g}: corrected vs no-turbulence classification error "
                        "<= 0.06",
                        f"{c['total_error']:.4f}",
                        c["total_error"] <= 0.06,
                    )
                )
            d = deg.get("classification_vs_no_turbulence")
            if c and d:
                out.append(
                    (
                        f"{p.metal}, D/r0 = {case:g}: corrected better than degraded in "
                        "classification error",
                        f"{c['total_error']:.4f} vs {d['total_error']:.4f}" + _pixel_counts(c, d),
                        c["total_error"] < d["total_error"],
                    )
                )
            for metric in (
                "dolp_rmse_truth",
                "dolp_rmse_no_turbulence",
                "s0_relative_rmse_truth",
                "s0_relative_rmse_no_turbulence",
                "dolp_rmse_truth_away_from_edges",
                "s0_relative_rmse_truth_away_from_edges",
            ):
                if metric not in cor or metric not in deg:
                    continue  # a summary written before the metric existed
                out.append(
                    (
                        f"{p.metal}, D/r0 = {case:g}: corrected better than degraded in {metric}",
                        f"{cor[metric]:.4f} vs {deg[metric]:.4f}",
                        cor[metric] < deg[metric],
                    )
                )
            for region in ("paint", p.metal):
                if region in cor:
                    a, b = (
                        cor[region]["index_median_abs_error"],
                        deg[region]["index_median_abs_error"],
                    )
                    out.append(
                        (
                            f"{p.metal}, D/r0 = {case:g}: deconvolution does not worsen the {region}'s "
                            "median |eta error|",
                            f"{a:.3f} vs {b:.3f}",
                            a <= b,
                        )
                    )
    out += _calibration_checks(statements)
    return out


def _pixel_counts(c, d) -> str:
    """Two classification errors as pixel counts, "(393 vs 377 of 12 544 pixels)", each of the pixels its
    image measured when those differ (summaries before 28 Nov 2026 do not count them: "")."""
    if "pixels" not in c or "pixels" not in d:
        return ""

    def wrong(e):
        return round(e["total_error"] * e["pixels"])

    def count(n):
        return f"{n:,}".replace(",", " ")

    if c["pixels"] == d["pixels"]:
        return f" ({wrong(c)} vs {wrong(d)} of {count(c['pixels'])} pixels)"
    return f" ({wrong(c)} of {count(c['pixels'])} vs {wrong(d)} of {count(d['pixels'])} pixels)"


def _calibration_checks(statements) -> list:
    """The no-turbulence 68 % and 95 % statements (paint intervals, joint regions) judged together.

    A calibrated 68 % statement misses its truth one time in three, so a check that every one covers
    would demand intervals too wide. What one run can judge is whether the misses are more than calibrated
    statements give: the check fails when at least that many misses has binomial probability below 0.05
    (the statements about one region are correlated, which widens the true spread; the coverage study
    judges calibration over many seeds).
    """
    from scipy.stats import binom

    out = []
    for i, (level, p_miss) in enumerate(((68, 0.32), (95, 0.05))):
        if not statements:
            break
        total = len(statements)
        missed = sum(not s[i] for s in statements)
        chance = float(binom.sf(missed - 1, total, p_miss))
        out.append(
            (
                f"no turbulence: the {level} % statements (paint intervals, joint regions) miss the truth "
                "no more often than calibrated ones would (probability of that many misses >= 0.05)",
                f"{missed} of {total} miss (expected {p_miss * total:.1f}; probability {chance:.2f})",
                chance >= 0.05,
            )
        )
    return out


def write_all(folder: RunFolder, cfg, results, *, seconds: float, ideal) -> Path:
    """Write ``results.h5``, ``summary.json`` and ``report.md`` (last); remove the checkpoints.

    Parameters
    ----------
    folder : RunFolder
    cfg : SceneConfig
    results : list of PlateResult
    seconds : float
        Run time [s].
    ideal : Ideal
        Stages replaced by their ideal versions (recorded).

    Returns
    -------
    Path
        ``report.md``.
    """
    from scatterlab.characterization.report_text import report_markdown
    from scatterlab.runtime.results import write_json, write_text

    _write_h5(folder.path / "results.h5", cfg, results)
    checks = acceptance_checks(cfg, results)
    summary = {
        "title": cfg.title,
        "scene": asdict(cfg),
        "seed": cfg.seed,
        "versions": _versions(),
        "ideal": ideal.label(),
        "seconds": seconds,
        "cases": ["no_turbulence"] + [f"D_r0_{x:g}" for x in cfg.d_over_r0],
        "plates": {r.plate.metal: r.metrics for r in results},
        "checks": [{"check": c, "value": v, "passed": bool(ok)} for c, v, ok in checks],
    }
    write_json(folder.path / "summary.json", summary, overwrite=True)
    text = report_markdown(cfg, results, checks, seconds=seconds, ideal=ideal)
    report = write_text(folder.report, text, overwrite=True)
    shutil.rmtree(folder.checkpoints, ignore_errors=True)
    return report
