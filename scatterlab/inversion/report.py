"""MCMC uncertainty reports: corner plot, traces, posterior-predictive DOLP band, credible-interval
table.

:func:`posterior_report` writes, for one :class:`~scatterlab.inversion.Posterior`, into ``out/``:
``<name>_corner.png`` (the ``corner`` package), ``<name>_trace.png``, ``<name>_predictive.png`` and
``<name>.md`` (medians, 68/95 % credible intervals beside the least-squares value and its Laplace
error, and
the diagnostics). :func:`report_index` writes ``index.md`` over several. Files are written
atomically and
never overwrite silently. matplotlib and corner are imported here only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from scatterlab._checks import as_rng
from scatterlab.inversion.posterior import FIT_P_MIN, KAPPA_FLOOR, PARAMETERS, Posterior
from scatterlab.runtime.results import atomic_write_bytes, write_text

__all__ = ["posterior_report", "report_index", "summary_table", "prior_line"]

LABELS = {"n": "n", "kappa": r"$\kappa$", "sigma": r"$\sigma$"}


def _save(fig, path: Path, overwrite: bool) -> None:
    import io

    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)


def summary_table(post: Posterior, truth=None) -> str:
    """Markdown table: median, 68 % and 95 % intervals, least squares +/- Laplace error (and
    truth).

    Parameters
    ----------
    post : Posterior
    truth : (n, kappa, sigma), optional
        True values (simulations), shown in an extra column.

    Returns
    -------
    str
        The Markdown table.
    """
    s = post.summary()["parameters"]
    head = "| parameter | median | 68 % interval | 95 % interval | least squares +/- Laplace |"
    sep = "|---|---|---|---|---|"
    if truth is not None:
        head += " truth |"
        sep += "---|"
    rows = [head, sep]
    for k, name in enumerate(PARAMETERS):
        p = s[name]
        if name == "sigma" and post.sigma_known is not None:  # not sampled: say so, not "0.3 +/- 0"
            row = f"| sigma | {post.sigma_known:.4g} (known, not sampled) | | | |"
            rows.append(row + (f" {truth[k]:.4g} |" if truth is not None else ""))
            continue
        row = (
            f"| {name} | {p['median']:.4g} | [{p['ci68'][0]:.4g}, {p['ci68'][1]:.4g}] | "
            f"[{p['ci95'][0]:.4g}, {p['ci95'][1]:.4g}] | "
            f"{p.get('least_squares', float('nan')):.4g} +/- "
            f"{p.get('laplace_error', float('nan')):.2g} |"
        )
        if truth is not None:
            row += f" {truth[k]:.4g} |"
        rows.append(row)
    if "noise" in s:
        rows.append(
            f"| noise | {s['noise']['median']:.3g} | [{s['noise']['ci68'][0]:.3g}, "
            f"{s['noise']['ci68'][1]:.3g}] | | |" + (" |" if truth is not None else "")
        )
    return "\n".join(rows)


def posterior_report(
    post: Posterior,
    out,
    name: str = "posterior",
    *,
    rng=None,
    truth=None,
    overwrite: bool = False,
    title: str | None = None,
    notes=(),
) -> Path:
    """Write the figures, ``<name>.json`` (the summary) and the Markdown report of one posterior.

    Parameters
    ----------
    post : Posterior
    out : path -- directory for ``<name>.md``, ``<name>.json`` and the PNG figures.
    name : str
    rng : anything :func:`numpy.random.default_rng` accepts
        Draws the posterior-predictive band; ``None`` takes fresh entropy, so give a seed for a
        reproducible figure.
    truth : (n, kappa, sigma), optional -- shown beside the estimates (simulations).
    overwrite : bool -- replace existing files (otherwise FileExistsError).
    title : str, optional
        The report's heading (default ``"Posterior: <name>"``).
    notes : sequence of str
        Lines about the data (source, error model, how the file was read), listed under the heading.

    Returns
    -------
    Path
        The written ``<name>.md``.
    """
    import matplotlib

    from scatterlab.runtime.results import write_json

    matplotlib.use("Agg", force=False)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    P = 2 if post.sigma_known is not None else 3
    labels = [LABELS[p] for p in PARAMETERS[:P]]
    _save(_corner_figure(post, labels, truth), out / f"{name}_corner.png", overwrite)
    _save(_trace_figure(post, labels), out / f"{name}_trace.png", overwrite)
    _save(
        _predictive_figure(post, as_rng(rng)),
        out / f"{name}_predictive.png",
        overwrite,
    )
    write_json(out / f"{name}.json", post.summary(), overwrite=overwrite)
    path = out / f"{name}.md"
    write_text(path, _markdown(post, name, truth, title, notes), overwrite=overwrite)
    return path


def _corner_figure(post, labels, truth):
    import logging

    import corner

    P = len(labels)
    # corner logs "Too few points to create valid contours" on the root logger for a narrow
    # posterior; the panel then shows the samples without contours, which is all that needs saying
    logging.disable(logging.WARNING)
    try:
        return corner.corner(
            post.samples[:, :P],
            labels=labels,
            quantiles=[0.16, 0.5, 0.84],
            show_titles=True,
            truths=None if truth is None else list(truth)[:P],
            title_fmt=".3g",
        )
    finally:
        logging.disable(logging.NOTSET)


def _trace_figure(post, labels):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(labels), 1, figsize=(7, 1.8 * len(labels)), sharex=True)
    axes = np.atleast_1d(axes)
    steps = np.arange(post.chain.shape[0]) * post.thin + post.burn
    for k, ax in enumerate(axes):
        ax.plot(steps, post.chain[:, :, k], lw=0.4, alpha=0.4, color="k")
        ax.set_ylabel(labels[k])
    axes[-1].set_xlabel("step (after burn-in, thinned)")
    fig.suptitle(
        f"traces: tau = {np.round(post.tau, 1).tolist()}, acceptance {post.acceptance:.2f}"
    )
    return fig


def _predictive_figure(post, rng):
    import matplotlib.pyplot as plt

    order = np.argsort(post.theta_i + 1e-3 * post.theta_r)
    pred = post.predictive(rng, 400)[:, order]
    lo, mid, hi = np.quantile(pred, [0.025, 0.5, 0.975], axis=0)
    x = np.arange(post.dolp.size)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.fill_between(x, lo, hi, color="C0", alpha=0.3, label="95 % posterior predictive (model)")
    ax.plot(x, mid, color="C0", label="posterior median model")
    err = post.data_error()[order]
    ax.errorbar(x, post.dolp[order], yerr=err, fmt="o", color="k", ms=3, label="data +/- error")
    ticks = [
        f"{np.degrees(a):.0f}/{np.degrees(b):.0f}"
        for a, b in zip(post.theta_i[order], post.theta_r[order])
    ]
    ax.set_xticks(x, ticks, rotation=60, fontsize=7)
    ax.set_xlabel(r"$\theta_i / \theta_r$ [deg]")
    ax.set_ylabel("DOLP")
    ax.legend(fontsize=7)
    return fig


def _markdown(post, name, truth, title=None, notes=()) -> str:
    d = post.summary()["diagnostics"]
    ess = ", ".join(f"{k} {round(v) if np.isfinite(v) else v}" for k, v in d["ess"].items())
    state = "converged" if d["converged"] else "**not converged**: " + d["convergence_reason"]
    lines = [f"# {title or f'Posterior: {name}'}", ""]
    if notes:
        lines += [f"- {n}" for n in notes] + [""]
    lines += [summary_table(post, truth), ""]
    # what qualifies every number of the table, right under it: the fit under the stated errors and the
    # sampler's warnings
    g = post.fit_check
    if g is not None:
        lines += [
            f"Goodness of fit under the stated errors: chi-square {g['chi2']:.2f} for {g['dof']} degrees of "
            f"freedom, p = {g['p_value']:.2g}"
            + (
                " (**the data do not fit the model within these errors**)."
                if g["p_value"] < FIT_P_MIN
                else "."
            ),
            "",
        ]
    if post.messages:
        lines += ["**Warnings:**", ""] + [f"- {m}" for m in post.messages] + [""]
    lines += [prior_line(post), ""]  # the ranges the intervals of the table are drawn within
    lines += [
        f"Diagnostics: {d['n_steps']} steps x {d['walkers']} walkers, burn-in {d['burn']}, "
        f"thin {d['thin']}; tau = {np.round(d['tau'], 1).tolist()} "
        f"(run = {d['steps_over_tau']:.0f} tau); acceptance {d['acceptance']:.2f}; "
        f"R-hat between {d['n_ensembles']} ensembles "
        f"{np.round(d['rhat'], 3).tolist()}; effective samples {ess}; {state}; "
        f"{_modes_text(post, d)}; {d['seconds']:.1f} s.",
        "",
    ]
    for kind in ("corner", "trace", "predictive"):
        lines += [f"![{kind}]({name}_{kind}.png)", ""]
    return "\n".join(lines)


def _modes_text(post, d) -> str:
    """The posterior's modes, and the least-squares minima beside them when there are several."""
    text = "**multimodal** posterior" if d["multimodal"] else "one posterior mode"
    k = len(post.least_squares)
    return text + (f" (from {k} least-squares minima, see the warnings)" if k > 1 else "")


def prior_line(post: Posterior) -> str:
    """The priors of the posterior in one sentence: each parameter's range and shape, and the noise's.

    Parameters
    ----------
    post : Posterior

    Returns
    -------
    str
        E.g. ``"Priors: n uniform on [0, 5]; kappa uniform on [0, 25]; sigma uniform on [0.01, 1.5];
        DOLP noise known."``
    """
    parts = []
    for name in PARAMETERS:
        lo, hi = post.bounds[name]
        if name == "sigma" and post.sigma_known is not None:
            parts.append(f"sigma known ({post.sigma_known:g}, not sampled)")
        elif name == "kappa" and post.kappa_prior == "log-uniform":
            parts.append(f"kappa log-uniform on [{max(lo, KAPPA_FLOOR):g}, {hi:g}]")
        else:
            parts.append(f"{name} uniform on [{lo:g}, {hi:g}]")
    if post.noise_bounds is not None:
        parts.append(
            f"DOLP noise log-uniform on [{post.noise_bounds[0]:g}, {post.noise_bounds[1]:g}]"
        )
    else:
        parts.append("DOLP error known (not sampled)")
    return (
        "Priors: "
        + "; ".join(parts)
        + ". Where the data constrain a parameter little its interval follows this prior."
    )


def report_index(
    out, entries: dict, *, title: str = "Posterior reports", overwrite: bool = False
) -> Path:
    """``index.md`` linking reports: ``entries`` maps a name to its Posterior.

    Parameters
    ----------
    out : str or Path
        Directory of the reports.
    entries : dict of str -> Posterior
        Report name (``<name>.md``) and its posterior.
    title : str
        Heading.
    overwrite : bool
        Replace an existing ``index.md``.

    Returns
    -------
    Path
        The written ``index.md``.
    """
    out = Path(out)
    lines = [
        f"# {title}",
        "",
        "| region | n (68 %) | kappa (68 %) | sigma (68 %) | converged | modes |",
        "|---|---|---|---|---|---|",
    ]
    for name, post in entries.items():
        s = post.summary()
        cells = []
        for p in PARAMETERS:
            q = s["parameters"][p]
            cells.append(f"{q['median']:.3g} [{q['ci68'][0]:.3g}, {q['ci68'][1]:.3g}]")
        lines.append(
            f"| [{name}]({name}.md) | "
            + " | ".join(cells)
            + f" | {s['diagnostics']['converged']} | {len(post.modes)} |"
        )
    return write_text(out / "index.md", "\n".join(lines) + "\n", overwrite=overwrite)
