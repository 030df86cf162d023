"""Tables 1-2 study: the exact grid posterior behind the coverage numbers, against independent
truths (rejection sampling; calibration over truths drawn from the prior)."""

import numpy as np
import pytest

from scatterlab import study_runner
from scatterlab.inversion.thilak import thilak_dop

TT = study_runner.discover()["thilak_tables"].module


def _data(key, level, trials, seed):
    m, a, b = TT.CONFIGS[key]
    ti = np.radians(np.linspace(a, b, m))
    clean = thilak_dop(*TT.COPPER, (ti + TT.THETA_R) / 2)
    sd = float(np.sqrt(TT.LEVELS[level][0] * clean.max()))
    return ti, sd, clean + sd * np.random.default_rng(seed).standard_normal((trials, m))


def test_grid_quantiles_match_rejection_sampling():
    # independent method: uniform prior draws accepted with probability exp(-(chi2 - min)/2)
    ti, sd, y = _data("3", "low", 1, seed=4)
    q = TT.grid_coverage(y, ti, sd, quick=False)["q"][0]  # (2, 3)
    rng = np.random.default_rng(5)
    x = rng.uniform([0, 0], [5, 25], size=(400_000, 2))
    chi2 = ((thilak_dop(x[:, :1], x[:, 1:], (ti + TT.THETA_R) / 2) - y) ** 2).sum(1) / sd**2
    keep = rng.random(x.shape[0]) < np.exp(-(chi2 - chi2.min()) / 2)
    assert keep.sum() > 5000
    ref = np.quantile(x[keep], [0.16, 0.5, 0.84], axis=0).T  # (2, 3)
    # tolerance: two grid steps (0.02 in n, 0.05 in kappa, full grid) plus the Monte-Carlo
    # error of a quantile from > 5000 samples of a spread of ~3 (n) and ~6 (kappa): ~0.05 / 0.1
    np.testing.assert_allclose(q[0], ref[0], atol=0.1)
    np.testing.assert_allclose(q[1], ref[1], atol=0.25)


def test_grid_posterior_is_calibrated_over_truths_drawn_from_the_prior():
    # Bayesian coverage theorem: averaged over truths from the prior, 68 % regions cover 68 %.
    # 300 truths per geometry: binomial SE 2.7 %; tolerance 3 SE = 8 %
    res = TT.prior_calibration(True, 300, np.random.default_rng(8))
    for geometry in res.values():
        for name in ("hpd", "marginal_n", "marginal_kappa"):
            assert geometry[name] == pytest.approx(0.68, abs=0.08), (name, geometry)


def test_marginal_intervals_undercover_the_fixed_copper_truth():
    # the old 0-3.6 %: with copper fixed at the valley's end the marginal equal-tailed intervals
    # miss it, while the likelihood-ratio region keeps roughly its level (measured 64-80 %)
    ti, sd, y = _data("3", "low", 100, seed=9)
    c = TT.grid_coverage(y, ti, sd, quick=True)
    assert c["marginal"].mean(0).max() < 0.15
    assert 0.55 < c["lr"].mean() < 0.85
