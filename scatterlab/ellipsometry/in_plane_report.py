"""Report of an in-plane ellipsometry fit: the four normalised elements against the specular angle.

``scatterlab fit-ellipsometry FILE.csv`` reads the file with :func:`scatterlab.io.read_ellipsometry`,
fits (n, kappa, sigma) with :func:`scatterlab.ellipsometry.fit_mueller_elements` and writes here
``elements_vs_angle.png``, ``metrics.json`` and ``report.md`` (written last, atomically).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_in_plane_report"]

ELEMENT_NAMES = ("m12 = M01/M00", "m22 = M11/M00", "m33 = M22/M00", "m34 = M23/M00")


def plot_in_plane(data, fit, path, *, shadowing="torrance-sparrow", diffuse="hyde") -> Path:
    """Measured elements (with their standard deviations) and the fitted pBRDF against the angle.

    Parameters
    ----------
    data : scatterlab.io.EllipsometryData
        N angles, elements (N, 4).
    fit : MuellerFit
        The fit.
    path : str or Path
        PNG file to write.
    shadowing, diffuse : str
        The model options of the fit.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from scatterlab.ellipsometry.fit import model_elements

    deg = np.degrees(data.theta)
    grid = np.radians(np.linspace(max(deg.min() - 2, 0.1), min(deg.max() + 2, 89.5), 200))
    curve = model_elements(grid, fit.n, fit.kappa, fit.sigma, shadowing=shadowing, diffuse=diffuse)
    fig, axes = plt.subplots(2, 2, figsize=(9, 7), sharex=True)
    for k, ax in enumerate(axes.ravel()):
        err = None if data.std is None else data.std[:, k]
        ax.errorbar(deg, data.elements[:, k], yerr=err, fmt="o", ms=4, label="measured")
        ax.plot(np.degrees(grid), curve[:, k], "-", label="pBRDF fit")
        ax.set(title=ELEMENT_NAMES[k], ylabel="normalised element")
        if k >= 2:
            ax.set_xlabel("theta_i = theta_r [deg]")
    axes[0, 0].legend()
    fig.suptitle(f"n = {fit.n:.4g}, kappa = {fit.kappa:.4g}, sigma = {fit.sigma:.3g}")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def _bounds_text() -> str:
    """The fit's box, as the report states it: ``n in [0.01, 10], kappa in [0, 30], sigma in [0.01, 1.5]``."""
    from scatterlab.ellipsometry.fit import FIT_BOUNDS

    return ", ".join(
        f"{name} in [{lo:g}, {hi:g}]" for name, (lo, hi) in zip(("n", "kappa", "sigma"), FIT_BOUNDS)
    )


def goodness(data, fit) -> tuple[float, int, str]:
    """Reduced chi^2 (weighted data) or mean square residual, its degrees of freedom and a sentence.

    Parameters
    ----------
    data : scatterlab.io.EllipsometryData
    fit : MuellerFit

    Returns
    -------
    tuple
        ``(statistic, degrees of freedom, sentence)``.
    """
    dof = max(1, fit.residuals.size - (3 if fit.errors[2] > 0 else 2))
    stat = float(np.sum(fit.residuals**2) / dof)
    if data.std is not None:
        return stat, dof, f"reduced chi^2 {stat:.3g} ({dof} degrees of freedom)"
    return (
        stat,
        dof,
        (
            f"rms residual {np.sqrt(stat):.3g} ({dof} degrees of freedom; without standard deviations "
            "the errors take this scatter as the noise)"
        ),
    )


def write_in_plane_report(
    data,
    fit,
    out,
    *,
    source="",
    convention="exp(+jwt)",
    seconds=0.0,
    shadowing="torrance-sparrow",
    diffuse="hyde",
    overwrite: bool = False,
) -> Path:
    """Write ``elements_vs_angle.png``, ``metrics.json`` and ``report.md`` into ``out``.

    Parameters
    ----------
    data : scatterlab.io.EllipsometryData
        The data fitted.
    fit : MuellerFit
        Result of :func:`scatterlab.ellipsometry.fit_mueller_elements` on ``data``.
    out : str or Path
        Output folder (created).
    source : str
        The file the data came from.
    convention : str
        Time convention the file was read with.
    seconds : float
        Run time of the fit [s].
    shadowing, diffuse : str
        The model options of the fit.
    overwrite : bool
        Replace an existing report (otherwise FileExistsError).

    Returns
    -------
    Path
        ``report.md``.
    """
    from scatterlab.ellipsometry.report import report_folder, versions
    from scatterlab.runtime.results import write_json, write_text

    out, report = report_folder(out, overwrite)
    plot_in_plane(data, fit, out / "elements_vs_angle.png", shadowing=shadowing, diffuse=diffuse)
    stat, dof, sentence = goodness(data, fit)
    e = fit.errors
    sigma_err = f"{e[2]:.3g}" if e[2] > 0 else "known, held fixed"
    write_json(
        out / "metrics.json",
        {
            "source": str(source),
            "angles_deg": np.round(np.degrees(data.theta), 9),
            "wavelength_m": data.wavelength,
            "time_convention": convention,
            "n": fit.n,
            "kappa": fit.kappa,
            "sigma": fit.sigma,
            "errors_1sigma": e,
            "covariance": fit.covariance,
            "goodness": stat,
            "degrees_of_freedom": dof,
            "weighted": data.std is not None,
            "success": fit.success,
            "model": {"shadowing": shadowing, "diffuse": diffuse},
            "run_time_s": seconds,
            "notes": list(data.notes),
            "versions": versions(),
        },
        overwrite=True,
    )
    wl = "" if data.wavelength is None else f" at {data.wavelength * 1e6:.6g} um"
    lines = [
        f"# In-plane ellipsometry fit to {Path(source).name}",
        "",
        f"Data: {data.theta.size} specular angles{wl}, the four normalised elements "
        f"(M01, M11, M22, M23) / M00{', weighted by their standard deviations' if data.std is not None else ''}; "
        f"file read with time convention {convention}. Model: `pbrdf.Model(sigma, "
        f"shadowing={shadowing!r}, diffuse={diffuse!r})` in the specular plane.",
        "",
        "| parameter | value | 1-sigma |",
        "|---|---|---|",
        f"| n | {fit.n:.6g} | {e[0]:.3g} |",
        f"| kappa | {fit.kappa:.6g} | {e[1]:.3g} |",
        f"| sigma (rms facet slope) | {fit.sigma:.6g} | {sigma_err} |",
        "",
        f"Goodness: {sentence}; fit {'converged' if fit.success else 'did NOT converge'}; run time "
        f"{seconds:.1f} s. The 1-sigma errors are those of the linearised least squares "
        "(the Jacobian at the optimum): trustworthy when the fit is good and no parameter sits on a "
        f"bound ({_bounds_text()}).",
        "",
    ]
    if data.std is not None and stat > 4:
        lines += [
            f"**The model does not fit these data within their errors** (reduced chi^2 {stat:.3g}): "
            "the stated standard deviations are too small, the time convention is the other one "
            "(M23's sign; --time-convention), or the surface is not the pBRDF's (a diffuse or "
            "layered sample). The errors above are then too small.",
            "",
        ]
    lines += ["![elements against the angle](elements_vs_angle.png)", ""]
    if data.notes:
        lines += ["## Reading the file", ""] + [f"- {n}" for n in data.notes] + [""]
    return write_text(report, "\n".join(lines), overwrite=True)
