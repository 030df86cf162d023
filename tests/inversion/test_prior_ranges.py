"""Prior ranges of the posterior, shared or one per problem (``sample_posteriors(bounds=...)``).

Independent truth: simulation-based calibration (Cook, Gelman & Rubin 2006). When the truths are drawn from
the prior the posterior uses, its credible intervals cover them at exactly their nominal rate -- even for
metals at 30-60 deg, whose DOLP fixes only a ridge of (n, kappa) and whose marginal intervals miss a fixed
truth under a wide prior (``test_confidence_region.py``).
"""

import warnings

import numpy as np
import pytest

from scatterlab.inversion import ConvergenceWarning, model_dolp, sample_posteriors
from scatterlab.runtime import get_executor

THETA = np.radians([30.0, 40.0, 50.0, 60.0])
SIGMA = 0.3
METAL_BOX = {"n": (0.5, 4.0), "kappa": (4.0, 17.0)}


def test_intervals_cover_truths_drawn_from_the_prior_at_the_nominal_rate():
    rng = np.random.default_rng(5)
    trials = 48
    truths = np.column_stack([rng.uniform(*METAL_BOX[q], trials) for q in ("n", "kappa")])
    y = np.stack([model_dolp(n, k, SIGMA, THETA, THETA) for n, k in truths])
    y = y + 5e-3 * rng.standard_normal(y.shape)
    with warnings.catch_warnings(), get_executor("processes", workers=2) as ex:
        warnings.simplefilter("ignore", ConvergenceWarning)
        posts = sample_posteriors(
            y, THETA, THETA, 5e-3, rng, sigma=SIGMA, n_steps=400, executor=ex, bounds=METAL_BOX
        )
    se = np.sqrt(np.array([0.68 * 0.32, 0.95 * 0.05]) / trials)
    for q in (0, 1):  # n, then kappa: the ridge leaves both to the prior, yet they are calibrated
        rates = [
            np.mean(
                [
                    p.interval(lv)[0, q] <= t[q] <= p.interval(lv)[1, q]
                    for p, t in zip(posts, truths)
                ]
            )
            for lv in (0.68, 0.95)
        ]
        assert np.all(np.abs(np.array(rates) - [0.68, 0.95]) <= 3 * se), (q, rates)


def test_each_problem_keeps_its_own_prior_range():
    truth = (1.5, 0.3)  # a paint
    y = np.tile(model_dolp(*truth, SIGMA, THETA, THETA), (2, 1))
    narrow = {"n": (1.45, 1.55), "kappa": (0.25, 0.35)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        wide, tight = sample_posteriors(
            y, THETA, THETA, 2e-2, 1, sigma=SIGMA, n_steps=300, bounds=[None, narrow]
        )
    lo, hi = tight.interval(0.99)
    assert narrow["n"][0] <= lo[0] and hi[0] <= narrow["n"][1]
    assert narrow["kappa"][0] <= lo[1] and hi[1] <= narrow["kappa"][1]
    wlo, whi = wide.interval(0.68)
    assert whi[1] - wlo[1] > hi[1] - lo[1]  # the default range leaves kappa wider


def test_a_bounds_list_of_the_wrong_length_is_refused():
    y = np.tile(model_dolp(1.5, 0.3, SIGMA, THETA, THETA), (2, 1))
    with pytest.raises(ValueError, match="bounds must be one dict or 2"):
        sample_posteriors(y, THETA, THETA, 2e-2, 1, sigma=SIGMA, n_steps=50, bounds=[None])
