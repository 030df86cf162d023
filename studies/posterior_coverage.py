"""Calibration of the posterior credible intervals: empirical coverage against nominal level.

(Not named coverage.py: when studies/ was on sys.path that name shadowed the `coverage` package that
numba, imported by arviz through corner, probes.)

Repeated synthetic experiments with known truth (paint 1.39 - j0.34 and iron 3.6 - j5.88, sigma 0.3,
11 geometries: specular 30-60 deg plus an off-specular sweep at theta_i = 45 deg, DOLP noise 2e-3):
for each nominal level, the fraction of trials whose equal-tailed interval contains the truth, per
parameter, with the binomial standard error band. Calibrated intervals lie on the diagonal.

A third case checks the likelihood extensions the characterization pipeline relies on: paint whose
DOLP errors are correlated across geometries (sd 2e-3, correlation 0.7^|i-j|) plus a systematic
error of 1e-3 on the four off-specular geometries, sampled with ``covariance`` and ``systematic``.
In full mode the same data are also sampled with the naive independent noise of the same size, to
show what ignoring the correlation costs.

Full-mode run time (24 Nov 2026): not finished in 900 s serial on the shared 2-core machine (load
average 1-2.3; stopped). Quick mode runs 6 trials per case, about 40 s on 2 idle cores (8 trials took 54 s
on 27 Nov 2026, too near the minute a quick mode may take); full mode runs 200 per case,
with chains run until converged, plus the naive re-run of the correlated case: about 25-30 minutes
serial by that scaling (use ``--workers 2``).
"""

import warnings

import numpy as np
from scatterlab.studies._common import plt, set_verdict

from scatterlab.inversion import ConvergenceWarning, model_dolp, sample_posteriors

STUDY = {
    "id": "coverage",
    "title": "Calibration curve of the posterior credible intervals",
    "reproduces": "our own study: honest uncertainty",
}

TI = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
TR = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])
CASES = {
    "paint": (1.39, 0.34, 0.3),
    "iron": (3.6, 5.88, 0.3),
    "paint_correlated": (1.39, 0.34, 0.3),
}
LEVELS = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.68, 0.8, 0.9, 0.95])
NOISE = 2e-3
_i = np.arange(TI.size)
CORRELATED = NOISE**2 * 0.7 ** np.abs(
    _i[:, None] - _i[None, :]
)  # error covariance of the third case
SYSTEMATIC = np.r_[np.zeros(7), np.full(4, 1e-3)]


def coverage(posts, truth):
    """Fraction (levels, 3) of posteriors whose equal-tailed intervals contain the truth."""
    cover = np.empty((LEVELS.size, 3))
    for i, lv in enumerate(LEVELS):
        cover[i] = np.mean(
            [[lo <= t <= hi for lo, hi, t in zip(*p.interval(lv), truth)] for p in posts], 0
        )
    return cover


def simulate(ctx, name, truth, trials):
    """Noisy data (trials, M) and the sampler keywords of a case."""
    clean = model_dolp(*truth, TI, TR)
    if name != "paint_correlated":
        return clean + NOISE * ctx.rng.standard_normal((trials, TI.size)), {"noise": NOISE}
    V = CORRELATED + np.diag(SYSTEMATIC**2)
    y = clean + ctx.rng.standard_normal((trials, TI.size)) @ np.linalg.cholesky(V).T
    return y, {"noise": None, "covariance": CORRELATED, "systematic": SYSTEMATIC}


def sample(ctx, y, kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return sample_posteriors(
            y,
            TI,
            TR,
            kw.pop("noise"),
            ctx.rng,
            n_steps=400 if ctx.quick else None,
            executor=ctx.executor,
            **kw,
        )


def run(ctx):
    trials = 6 if ctx.quick else 200
    pyplot = plt()
    fig, axes = pyplot.subplots(1, len(CASES), figsize=(15, 4.2))
    se = np.sqrt(LEVELS * (1 - LEVELS) / trials)
    for ax, (name, truth) in zip(axes, CASES.items()):
        y, kw = simulate(ctx, name, truth, trials)
        with ctx.step(f"sample_{name}"):
            posts = sample(ctx, y, kw)
        cover = coverage(posts, truth)
        ax.fill_between(
            LEVELS, LEVELS - 2 * se, LEVELS + 2 * se, color="0.85", label="nominal +/- 2 s.e."
        )
        for k, par in enumerate(("n", "kappa", "sigma")):
            ax.plot(LEVELS, cover[:, k], "o-", label=par)
        ax.plot([0, 1], [0, 1], "k:", lw=0.8)
        ax.set(
            xlabel="nominal level", ylabel="empirical coverage", title=f"{name} ({trials} trials)"
        )
        z = np.abs(cover - LEVELS[:, None]) / se[:, None]
        ctx.metrics[name] = {
            "levels": LEVELS.tolist(),
            "coverage": cover.tolist(),
            "max_abs_z": float(z.max()),
            "converged_fraction": float(np.mean([p.converged for p in posts])),
            "multimodal_fraction": float(np.mean([p.multimodal for p in posts])),
            "median_ess_min": float(np.median([p.n_effective for p in posts])),
        }
        if name == "paint_correlated" and not ctx.quick:
            with ctx.step(
                "sample_naive"
            ):  # the same data, errors taken as independent with the same sd
                naive = sample(
                    ctx, y, {"noise": float(np.sqrt(np.mean(np.diag(CORRELATED) + SYSTEMATIC**2)))}
                )
            nc = coverage(naive, truth)
            ax.plot(
                LEVELS, nc[:, 1], "x--", color="0.4", label="kappa, errors taken as independent"
            )
            ctx.metrics["paint_correlated"]["naive_coverage"] = nc.tolist()
            ctx.metrics["paint_correlated"]["naive_max_abs_z"] = float(
                (np.abs(nc - LEVELS[:, None]) / se[:, None]).max()
            )
    axes[0].legend(fontsize=7)
    axes[-1].legend(fontsize=7)
    ctx.save_figure(fig, "coverage")
    m = ctx.metrics
    texts = {name: case_text(name, m[name], trials, judged=not ctx.quick) for name in CASES}
    ctx.say(
        f"Empirical coverage against nominal level, {trials} trials per case (binomial s.e. "
        f"{se[LEVELS == 0.5][0]:.2f} at level 0.5); deviations in binomial standard errors over "
        f"10 levels x 3 parameters, up to about {CHANCE_Z:g} expected from chance alone for 30 "
        "correlated checks. Convergence: run length, acceptance, R-hat between two independent "
        "ensembles.\n\n"
        + "\n".join(f"- {t}" for t, _ in texts.values())
        + (
            "\n\nTaking the correlated errors as independent gives "
            f"{m['paint_correlated']['naive_max_abs_z']:.1f} standard errors."
            if "naive_max_abs_z" in m["paint_correlated"]
            else ""
        )
    )
    set_verdict(
        ctx,
        "own study",
        f"{trials} trials: " + "; ".join(f"{name} {short}" for name, (_, short) in texts.items()),
    )


CHANCE_Z = 3.0  # largest |z| over 30 correlated checks expected from chance alone (about 2.5-3)
CONVERGED_MIN = 0.5  # below this fraction of converged runs, a case's coverage is not judged


def case_text(name, case, trials, judged=True):
    """One case's calibration statement, generated from its coverage numbers.

    Parameters
    ----------
    name : str
        Case name.
    case : dict
        ``levels``, ``coverage`` (levels x 3: n, kappa, sigma), ``max_abs_z`` and
        ``converged_fraction``.
    trials : int
        Trials per case.
    judged : bool
        False (quick mode): a handful of trials with short chains is a smoke test, whose binomial
        standard errors mean nothing; the deviation is recorded, not judged.

    Returns
    -------
    text : str
        The sentence: calibrated / under-covers / over-covers (worst nominal -> empirical level and
        parameter), with the share of converged runs and a caveat when it is below CONVERGED_MIN.
    short : str
        The same verdict in a few words for the headline.
    """
    levels = np.asarray(case["levels"])
    cover = np.asarray(case["coverage"])
    se = np.sqrt(levels * (1 - levels) / trials)
    z = (cover - levels[:, None]) / se[:, None]
    i, k = np.unravel_index(np.argmax(np.abs(z)), z.shape)
    worst = (
        f"{('n', 'kappa', 'sigma')[k]} at nominal {levels[i]:g}: {cover[i, k]:.2f}, "
        f"{z[i, k]:+.1f} s.e."
    )
    if case["max_abs_z"] <= CHANCE_Z:
        short = f"calibrated (max {case['max_abs_z']:.1f} s.e.)"
        text = f"{name}: consistent with calibrated coverage (largest deviation {worst})"
    else:
        kind = "UNDER-covers" if z[i, k] < 0 else "OVER-covers"
        short = f"{kind.lower()} ({worst})"
        text = f"{name}: {kind}, beyond chance (largest deviation {worst})"
    conv = case["converged_fraction"]
    if not judged:
        text = (
            f"{name}: recorded, not judged ({trials} trials of a quick run are too few; largest "
            f"deviation {worst})"
        )
        short = "not judged (quick)"
    if conv < CONVERGED_MIN:
        text = (
            f"{name}: NOT judged -- only {conv:.0%} of the runs converged, so its coverage "
            f"(largest deviation {worst}) describes unconverged chains, not the posterior"
        )
        short = f"not judged ({conv:.0%} converged)"
    else:
        text += f"; {conv:.0%} of the runs converged"
    return text + ".", short
