"""Report of a pBRDF fit to a measured Mueller BRDF (``scatterlab fit-mueller``).

Figures, Markdown and metrics.

Imported by the command line only; matplotlib is imported inside the plotting functions.
"""

from __future__ import annotations

import platform
from pathlib import Path

import numpy as np

__all__ = ["write_fit_report", "plot_elements", "plot_residuals"]

_NAMES = [[f"m{j + 1}{k + 1}" for k in range(4)] for j in range(4)]


def _normalised(M):
    with np.errstate(divide="ignore", invalid="ignore"):
        return M / M[:, :1, :1]


def plot_elements(data, fit, path):
    """4x4 panels of measured against predicted elements (F00 absolute, log axes; the others
    normalised by F00), with the 1:1 line. Returns the figure path.

    Parameters
    ----------
    data : scatterlab.io.MuellerBRDF
        The measured Mueller BRDF (K geometries).
    fit : PBRDFFit
        The fit (``predicted`` (K, 4, 4)).
    path : str or Path
        PNG file to write.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    meas, pred = _normalised(data.mueller), _normalised(fit.predicted)
    fig, axes = plt.subplots(4, 4, figsize=(11, 10))
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.06, top=0.93, hspace=0.4, wspace=0.35)
    for j in range(4):
        for k in range(4):
            ax = axes[j, k]
            if (j, k) == (0, 0):
                x, y = data.mueller[:, 0, 0], fit.predicted[:, 0, 0]
                if data.normalised:
                    ax.text(
                        0.5,
                        0.5,
                        "normalised data:\nno absolute m11",
                        ha="center",
                        va="center",
                        transform=ax.transAxes,
                    )
                    ax.set_axis_off()
                    continue
                ax.set_xscale("log")
                ax.set_yscale("log")
                label = "m11 [1/sr]"
            else:
                x, y = meas[:, j, k], pred[:, j, k]
                label = f"{_NAMES[j][k]}/m11"
            if data.std is not None:
                err = data.std[:, j, k] / (1.0 if (j, k) == (0, 0) else data.mueller[:, 0, 0])
                ax.errorbar(x, y, xerr=err, fmt="o", ms=3, lw=0.8, color="C0")
            else:
                ax.plot(x, y, "o", ms=3, color="C0")
            lo, hi = np.nanmin(np.r_[x, y]), np.nanmax(np.r_[x, y])
            ax.plot([lo, hi], [lo, hi], "k-", lw=0.7)
            ax.set_title(label, fontsize=9)
            if j == 3:
                ax.set_xlabel("measured", fontsize=8)
            if k == 0:
                ax.set_ylabel("pBRDF fit", fontsize=8)
            ax.tick_params(labelsize=7)
    fig.suptitle(
        f"measured vs fitted pBRDF: n = {fit.n:.4g}, kappa = {fit.kappa:.4g}, sigma = "
        f"{fit.sigma:.4g}{' (known)' if _sigma_known(fit) else ''}"
    )
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_residuals(fit, path):
    """4x4 panels of the weighted residuals against the row of the data. Returns the figure path.

    Parameters
    ----------
    fit : PBRDFFit
        The fit (``residuals`` (K, 4, 4), ``element_rms`` (4, 4)).
    path : str or Path
        PNG file to write.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 4, figsize=(11, 8), sharex=True)
    fig.subplots_adjust(left=0.06, right=0.98, bottom=0.07, top=0.92, hspace=0.35, wspace=0.3)
    rows = np.arange(fit.residuals.shape[0])
    for j in range(4):
        for k in range(4):
            ax = axes[j, k]
            ax.axhline(0, color="k", lw=0.6)
            ax.plot(rows, fit.residuals[:, j, k], ".", ms=4)
            ax.set_title(f"{_NAMES[j][k]}: rms {fit.element_rms[j, k]:.3g}", fontsize=9)
            ax.tick_params(labelsize=7)
    for ax in axes[3]:
        ax.set_xlabel("row", fontsize=8)
    fig.suptitle(
        "weighted residuals (model - data) / "
        + ("std" if fit.weighted else ("1" if fit.normalised else "measured m11"))
    )
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def _markdown(data, fit, source, convention, seconds) -> str:
    """The report: data and model, estimates, warnings, depolarization, figures, file notes."""
    lines = [f"# pBRDF fit to {Path(source).name}", ""]
    lines += _estimates_section(data, fit, convention, seconds)
    lines += _posterior_and_warnings(fit)
    lines += _depolarization_section(fit.depolarization)
    lines += [
        "## Figures",
        "",
        "![measured vs predicted elements](elements.png)",
        "",
        "![weighted residuals per element](residuals.png)",
        "",
    ]
    if data.notes:
        lines += ["## Reading the file", ""] + [f"- {n}" for n in data.notes] + [""]
    return "\n".join(lines)


def _sigma_known(fit) -> bool:
    """Was the roughness given (``fit_pbrdf(sigma=...)``, ``--sigma``) rather than fitted?"""
    return fit.options.get("sigma_known") is not None


def _estimates_section(data, fit, convention, seconds) -> list[str]:
    """What was fitted, the estimates with 1-sigma errors and the goodness of fit."""
    e = fit.errors
    if fit.weighted:
        goodness = f"Reduced chi^2 = {fit.reduced_chi2:.4g} ({fit.dof} degrees of freedom)"
    else:
        goodness = (
            f"RMS residual {np.sqrt(fit.reduced_chi2):.3g}"
            + ("" if fit.normalised else " of the measured m11")
            + f" ({fit.dof} degrees of freedom); without standard deviations the errors take this "
            "scatter as the noise"
        )
    return [
        f"Data: {len(data)} geometries at {fit.wavelength * 1e6:.6g} um "
        f"({'normalised elements' if fit.normalised else 'absolute elements'}"
        f"{', weighted by their standard deviations' if fit.weighted else ''}); file read with "
        f"time convention {convention}. Model: `pbrdf.Model(sigma, "
        f"shadowing={fit.options['shadowing']!r}, "
        f"diffuse={fit.options['diffuse']!r})`, all {15 if fit.normalised else 16} elements.",
        "",
        "| parameter | value | 1-sigma |",
        "|---|---|---|",
        f"| n | {fit.n:.6g} | {e[0]:.3g} |",
        f"| kappa | {fit.kappa:.6g} | {e[1]:.3g} |",
        f"| sigma (rms facet slope) | {fit.sigma:.6g} | "
        + ("known, held fixed |" if _sigma_known(fit) else f"{e[2]:.3g} |"),
        "",
        goodness
        + f"; fit {'converged' if fit.success else 'did NOT converge'}; run time {seconds:.1f} s.",
        "",
    ]


def _posterior_and_warnings(fit) -> list[str]:
    """The emcee summary (when sampled), undetermined parameters and a time-convention hint."""
    lines = []
    if fit.posterior is not None:
        post = fit.posterior
        med, sd = np.median(post["samples"], 0), post["samples"].std(0)
        lines += [
            f"Posterior (emcee, {post['walkers']} walkers x {post['steps']} steps, first half "
            f"discarded; acceptance {post['acceptance']:.2f}): n = {med[0]:.6g} +- {sd[0]:.3g}, "
            f"kappa = {med[1]:.6g} +- {sd[1]:.3g}, "
            + (
                f"sigma = {med[2]:.6g} known"
                if _sigma_known(fit)
                else f"sigma = {med[2]:.6g} +- {sd[2]:.3g}"
            )
            + " (median +- standard deviation).",
            "",
        ]
    if not fit.determined:
        lines += [
            "**The data do not determine all three parameters** (rank-deficient Jacobian): the "
            "errors are infinite. Add incidence angles or out-of-plane geometries.",
            "",
        ]
    if fit.circular_flip_ratio < 0.25:
        lines += [
            f"**Time convention?** The data fit {1 / fit.circular_flip_ratio:.3g} times better (in "
            "cost) with their circular elements sign-flipped: the file is probably in the other "
            "time convention (`--time-convention`).",
            "",
        ]
    return lines


def _depolarization_section(dep: dict) -> list[str]:
    """Measured and model depolarization, and the share the diffuse term explains."""
    explained = dep["explained"]
    if np.isfinite(explained):
        share = (
            f"The pBRDF's diffuse term explains {100 * explained:.0f} % of the measured "
            "depolarization."
        )
    else:
        share = "The sample barely depolarizes (mean < 1e-3)."
    return [
        "## Depolarization",
        "",
        f"Mean depolarization 1 - P_Delta: measured {dep['measured_mean']:.4g}, pBRDF "
        f"{dep['model_mean']:.4g}. "
        + share
        + " (Noise adds to the sum of squared elements and hides depolarization of its own size.)",
        "",
    ]


def report_folder(out, overwrite: bool) -> tuple[Path, Path]:
    """The output folder (created) and its ``report.md``; FileExistsError if that exists unless
    ``overwrite``.

    Parameters
    ----------
    out : str or Path
        Output folder.
    overwrite : bool
        Replace an existing report.

    Returns
    -------
    tuple of Path
        ``(out, out / "report.md")``.
    """
    out = Path(out)
    report = out / "report.md"
    if report.exists() and not overwrite:
        raise FileExistsError(f"{report} exists; pass overwrite=True (--force on the command line)")
    out.mkdir(parents=True, exist_ok=True)
    return out, report


def versions() -> dict:
    """Versions of scatterlab, numpy, scipy and Python, for a report's metrics.

    Returns
    -------
    dict
        Package name -> version string.
    """
    import scipy

    import scatterlab

    return {
        "scatterlab": getattr(scatterlab, "__version__", "unknown"),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "python": platform.python_version(),
    }


def write_fit_report(
    data, fit, out, *, source="", convention="exp(+jwt)", seconds=0.0, overwrite: bool = False
) -> Path:
    """Write ``elements.png``, ``residuals.png``, ``metrics.json`` and ``report.md`` into ``out``.

    Parameters
    ----------
    data : scatterlab.io.MuellerBRDF
        The data fitted (one wavelength).
    fit : PBRDFFit
    out : str or Path
        Output folder (created).
    source : str
        The file the data came from.
    convention : str
        Time convention the file was read with.
    seconds : float
        Run time of the fit [s], recorded.
    overwrite : bool
        Replace an existing report (otherwise FileExistsError).

    Returns
    -------
    Path
        ``report.md``.
    """
    from scatterlab.runtime.results import write_json, write_text

    out, report = report_folder(out, overwrite)
    plot_elements(data, fit, out / "elements.png")
    plot_residuals(fit, out / "residuals.png")
    metrics = {
        "source": str(source),
        "geometries": len(data),
        "time_convention": convention,
        "fit": fit.summary(),
        "run_time_s": seconds,
        "notes": list(data.notes),
        "versions": versions(),
    }
    write_json(out / "metrics.json", metrics, overwrite=True)
    return write_text(report, _markdown(data, fit, source, convention, seconds), overwrite=True)
