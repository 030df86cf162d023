"""emcee side of the study ``dolp_vs_mom``: inversion bias and coverage with sample_posterior.

Helpers only (the runner skips modules whose name starts with ``_``). The exact (MoM) specular
DOLP at 30-60 deg goes through :func:`scatterlab.inversion.sample_posteriors`; the bias is the
posterior median minus the truth, the width the half width of the 68 % credible interval (about
one standard deviation when the posterior is Gaussian).
"""

import warnings

import numpy as np

from scatterlab.inversion import sample_posterior
from scatterlab.inversion.model_error import dolp_model_error, dolp_model_error_covariance

LEVELS = (0.68, 0.95)
FORMS = (
    "without",
    "independent",
    "correlated",
    "pipeline",
    "pipeline_any_material",
    "pipeline_rms",
)
CLASS = {"glass": "dielectric", "paint": "dielectric", "iron": "metal", "aluminium": "metal"}


def sampler_settings(quick):
    """emcee settings: walkers, steps (fixed length), ensembles, moves; quick mode is a smoke run.

    The moves are differential evolution ("de"): the default KDE move raised LinAlgError
    (singular KDE covariance) on one of the full run's held-out problems, whose walkers had
    collapsed onto a lower-dimensional set.

    Parameters
    ----------
    quick : bool

    Returns
    -------
    dict of :func:`scatterlab.inversion.sample_posterior` sampler keywords.
    """
    if quick:
        return {"n_walkers": 8, "n_steps": 100, "n_ensembles": 1, "moves": "de"}
    return {"n_walkers": 16, "n_steps": 400, "n_ensembles": 1, "moves": "de"}


def _one(task):
    """One posterior; a second seed if emcee fails, else the failure as a string (the study
    counts it as not covered and reports it). Seen in a full run: ``ValueError: At least one
    parameter value was NaN`` from emcee's compute_log_prob, and a singular KDE covariance."""
    y, th, noise, seeds, kw = task
    for seed in seeds:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return sample_posterior(y, th, th, noise, seed, **kw)
        except (ValueError, np.linalg.LinAlgError) as exc:
            err = f"{type(exc).__name__}: {exc}"
    return err


def _posteriors(y, th, noise, rng, executor, quick, **kw):
    """sample_posterior per row of ``y`` (K, M) through ``executor``; failures are strings."""
    seeds = rng.integers(2**63, size=(y.shape[0], 2))
    kw = dict(sampler_settings(quick), **kw)
    tasks = [(row, th, noise, [int(x) for x in sd], kw) for row, sd in zip(y, seeds)]
    return list(executor.map(_one, tasks))


def _quantiles(posts, q):
    """(K, len(q), 3) quantiles of each posterior; NaN for a failed one."""
    return np.array(
        [p.quantiles(q) if not isinstance(p, str) else np.full((len(q), 3), np.nan) for p in posts]
    )


def failures(posts):
    """The failure messages among ``posts`` (list of Posterior or str)."""
    return [p for p in posts if isinstance(p, str)]


def posterior_bias(data, truth, th, noises, rng, executor, quick):
    """Bias of the posterior median of (n, kappa, sigma) and the posterior width.

    Parameters
    ----------
    data : ndarray (C, M) -- noise-free exact DOLP of C roughness cells at M specular geometries.
    truth : ndarray (C, 3) -- true (n, kappa, sigma) per cell.
    th : ndarray (M,) [rad] -- the specular angles (theta_i = theta_r).
    noises : sequence of float -- DOLP noise standard deviations assumed by the likelihood.
    rng : anything :func:`numpy.random.default_rng` accepts.
    executor : Executor -- runs the posteriors.
    quick : bool -- emcee settings of :func:`sampler_settings`.

    Returns
    -------
    dict noise -> {"bias": (C, 3) median - truth, "width": (C, 3) half width of the 68 %
    interval, "exceeds": (C, 3) bool, |bias| > width}.
    """
    rng = np.random.default_rng(rng)
    out = {}
    for noise in noises:
        posts = _posteriors(np.clip(data, 0, 1), th, noise, rng, executor, quick)
        q = _quantiles(posts, [0.16, 0.5, 0.84])
        width = 0.5 * (q[:, 2] - q[:, 0])
        bias = q[:, 1] - truth
        out[noise] = {
            "bias": bias,
            "width": width,
            "exceeds": np.abs(bias) > width,
            "failed": failures(posts),
        }
    return out


def covered(posts, truth, level):
    """Whether equal-tailed credible intervals at ``level`` hold the true (n, kappa).

    A true kappa of 0 (glass) sits on the prior's edge, where an equal-tailed interval can never
    hold it: there the one-sided interval [0, q_level] is used, so only n is tested.

    Parameters
    ----------
    posts : list (K,) of Posterior, or str for a failed run (counted as not covered)
    truth : ndarray (2,) -- true (n, kappa).
    level : float in (0, 1)

    Returns
    -------
    ndarray (K,) bool.
    """
    a = (1 - level) / 2
    q = _quantiles(posts, [a, 1 - a, level])  # (K, 3, 3); NaN (failed): not covered
    lo, hi = q[:, 0, :2], q[:, 1, :2]
    if truth[1] == 0:
        lo, hi = lo.copy(), hi.copy()
        lo[:, 1], hi[:, 1] = np.where(np.isnan(q[:, 2, 1]), np.nan, 0.0), q[:, 2, 1]
    return np.all((lo <= truth) & (truth <= hi), -1)


def posterior_coverage(d0, truth, slopes, th, noises, draws, table, rng, executor, quick, name):
    """Coverage of the true (n, kappa) by the posterior's 68 % and 95 % intervals on held-out
    exact DOLP plus noise, for four error models.

    ``without``: noise only. ``independent``: ``systematic = dolp_model_error(th, th)`` (material
    and roughness unknown: the largest tabulated error), sigma sampled. ``correlated``:
    ``covariance = dolp_model_error_covariance(th, th) + noise^2 I``, sigma sampled.
    ``pipeline``: as :func:`scatterlab.characterization.estimation.region_posteriors` with
    ``model_error=True``: sigma known (the cell's slope), the material's class known (the
    pipeline's classification), ``systematic = dolp_model_error(th, th, sigma,
    material_class=...)``. ``pipeline_any_material``: the same with the class unknown (the largest
    error over all materials; the pipeline's form before the class was used).
    ``pipeline_rms``: as ``pipeline`` with the table's rms over the heights (``error_rms``)
    instead of their largest error.

    Parameters
    ----------
    d0 : ndarray (C, M) -- held-out exact DOLP (signed) of C cells at M specular geometries.
    truth : ndarray (2,) -- true (n, kappa) of the material.
    slopes : ndarray (C,) -- the cells' rms slopes.
    th : ndarray (M,) [rad]
    noises : sequence of float -- DOLP noise standard deviations (added and assumed known).
    draws : int -- noise draws per cell and noise level.
    table : dict -- the model-error table (from the other half of the realizations).
    rng, executor, quick : as :func:`posterior_bias`.
    name : str -- the material (a key of :data:`CLASS`), whose class the pipeline knows.

    Returns
    -------
    dict form -> level -> ndarray (len(noises) * draws * C,) bool, covered or not; and
    ``"failed"`` -> list of the failed runs' messages.
    """
    rng = np.random.default_rng(rng)
    t = dolp_model_error(th, th, table=table)
    C = dolp_model_error_covariance(th, th, table=table)
    hits = {f: {lv: [] for lv in LEVELS} for f in FORMS}
    failed = []
    for noise in noises:
        y = d0[None] + noise * rng.standard_normal((draws,) + d0.shape)
        y = np.clip(np.abs(y), 0, 1).reshape(-1, d0.shape[-1])
        sl = np.tile(slopes, draws)
        posts = {
            "without": _posteriors(y, th, noise, rng, executor, quick),
            "independent": _posteriors(y, th, noise, rng, executor, quick, systematic=t),
            "correlated": _posteriors(
                y, th, None, rng, executor, quick, covariance=C + noise**2 * np.eye(th.size)
            ),
        }
        rms = dict(table, error=table["error_rms"])
        for form, cls, tab in (
            ("pipeline", CLASS[name], table),
            ("pipeline_any_material", None, table),
            ("pipeline_rms", CLASS[name], rms),
        ):
            pipe = [None] * y.shape[0]
            for s in np.unique(sl):
                rows = np.flatnonzero(sl == s)
                te = dolp_model_error(th, th, s, material_class=cls, table=tab)
                ps = _posteriors(y[rows], th, noise, rng, executor, quick, systematic=te, sigma=s)
                for r, p in zip(rows, ps):
                    pipe[r] = p
            posts[form] = pipe
        failed += [m for ps in posts.values() for m in failures(ps)]
        for f, ps in posts.items():
            for lv in LEVELS:
                hits[f][lv].append(covered(ps, truth, lv))
    out = {f: {lv: np.concatenate(v) for lv, v in per.items()} for f, per in hits.items()}
    return dict(out, failed=failed)
