"""The MAP DOLP update against independent truths, and the priors / DOLP inputs the classifiers accept.

* :func:`dolp_update` is the maximum of the complete-data objective Q ln P + (T - Q) ln(1 - P) + w ln Pi(P) on
  [0, 1], found by brute force on a grid -- for every prior of PRIOR_SETS over photon totals 1e-5 .. 1e300 and
  DOLP ratios q = Q/T including q = 1 (Q == T, where the update once returned 1), and for stiff and
  high-order priors the constructor accepts (c2^m up to 1e300), photon totals down to 1e-300 and weights up
  to 1e300, with no warning;
* classify_dolp honours numpy masked arrays (the DOLP images of the imaging module) and names the remedy for
  NaN; the priors arguments take the names of PRIOR_SETS; blind_deconvolve's NaN error names ``mask``.

The brute force is independent of the solver: the objective (map_objective, a direct evaluation) on a grid
linear in P and geometric toward 0 and 1, with q and c3 added, then on a 2001-point grid between the
neighbours of the best point. The objective is concave in P (a sum of concave terms: m even, w >= 0), so its
maximum lies between those neighbours and the second grid resolves it to 1e-3 of the first's spacing.
Tolerances: map_objective sums non-positive terms, so its relative rounding is a few ulps times the number of
operations in its largest term -- the prior's exp(m ln|c2 (P - c3)|) carries m ln(c2 |P - c3|) ulps of
relative error, at most ~40 for PRIOR_SETS (c2^m <= 3e15, 5e-15 measured) and ~700 for c2^m = 1e300 (2e-13
measured) -- hence 1e-13 and 1e-12 relative.
"""

import warnings

import numpy as np
import pytest

from scatterlab.deconvolution import (
    PRIOR_SETS,
    SuperGaussianPrior,
    adaptive_priors,
    blind_deconvolve,
    classify_dolp,
    classify_unmixing,
    dolp_update,
    dolp_update_companion,
    map_objective,
)

_LIN = np.linspace(0.0, 1.0, 20001)
_TAIL = np.geomspace(1e-300, 1e-3, 1001)
_GRID = np.unique(np.r_[_LIN, _TAIL, 1 - _TAIL])


def _objective(P, T, Q, prior, weight):
    """The objective divided by T + w (the same maximiser), so that T and w up to 1e300 stay finite."""
    alpha, beta = T / (T + weight), weight / (T + weight)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        return map_objective(P, alpha, alpha * (Q / T), prior, beta)


def _brute_force_max(T, Q, prior, weight=1.0):
    """(best objective, its P): a grid, then a 2001-point grid between the neighbours of its best point
    on the base grid (q and c3, added to it, can lie within an ulp of one of its points)."""
    g = np.unique(np.r_[_GRID, min(Q / T, 1.0), prior.c3])
    o = _objective(g, T, Q, prior, weight)
    k = int(np.argmax(o))
    below, above = _GRID[_GRID < g[k]], _GRID[_GRID > g[k]]
    fine = np.linspace(below[-1] if below.size else g[k], above[0] if above.size else g[k], 2001)
    of = _objective(fine, T, Q, prior, weight)
    kf = int(np.argmax(of))
    return (of[kf], fine[kf]) if of[kf] >= o[k] else (o[k], g[k])


def _deficit(P, T, Q, prior, weight=1.0):
    """How far below the brute-force maximum the objective at P lies, relative to it, and how far P lies
    from the brute-force maximiser (not a test where the objective is flat to its rounding over a range)."""
    best, best_P = _brute_force_max(T, Q, prior, weight)
    here = _objective(np.array([P]), T, Q, prior, weight)[0]
    return (best - here) / max(abs(best), 1e-300), abs(P - best_P)


_ALL_PRIORS = [(key, p) for key, ps in PRIOR_SETS.items() for p in ps]
_T_SWEEP = np.r_[10.0 ** np.arange(-5.0, 12.01, 0.25), 10.0 ** np.arange(16.0, 301.0, 12.0)]
_Q_RATIOS = np.array([0.0, 1e-12, 1e-3, 0.035, 0.15, 0.3, 0.5, 0.65, 0.7, 0.9, 0.99, 1 - 1e-9, 1.0])


@pytest.mark.parametrize("key, prior", _ALL_PRIORS, ids=[f"{k}-{p.name}" for k, p in _ALL_PRIORS])
def test_map_dolp_update_is_the_brute_force_maximum_for_every_prior_set(key, prior):
    """T from 1e-5 to 1e300 (quarter decades to 1e12, where the q = 1 failure lay: 2e8 - 9e8 for the Ch. V
    metal prior), 13 ratios q including 0 and Q == T: 1209 cases per prior, every one within 1e-13 of the
    brute-force maximum (worst measured 4.4e-15 over all priors; the former solver missed it by 18-61 %
    in 1-3 cases per prior)."""
    TT, qq = np.meshgrid(_T_SWEEP, _Q_RATIOS, indexing="ij")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        P = dolp_update(TT, qq * TT, prior)
    assert np.all((P >= 0) & (P <= 1))
    found = [_deficit(p, t, q * t, prior)[0] for t, q, p in zip(TT.ravel(), qq.ravel(), P.ravel())]
    assert max(found) <= 1e-13, max(found)


def test_map_dolp_update_at_q_equal_one_is_interior_where_the_prior_pulls_it_in():
    """The reviewer's case: the Ch. V metal prior, Q = T = 5e8. The objective T ln P - (7.2 (P - 0.15))^10
    peaks at 0.953773 (fine grid of 2e6 + 1 points; the companion matrix: 0.9537728674), not at 1."""
    prior = PRIOR_SETS["ch5"][1]
    g = np.linspace(0, 1, 2_000_001)
    for T in (2e8, 5e8, 8e8):
        P = dolp_update(np.array([T]), np.array([T]), prior)[0]
        best = g[np.argmax(map_objective(g, T, T, prior))]
        assert abs(P - best) <= 1e-6, (T, P, best)
        assert P == pytest.approx(dolp_update_companion(T, T, prior), abs=1e-10)
    assert dolp_update(np.array([5e8]), np.array([5e8]), prior)[0] == pytest.approx(
        0.9537728674, abs=1e-9
    )


@pytest.mark.parametrize("key, prior", [kp for kp in _ALL_PRIORS if kp[1].name != "dielectric"])
def test_map_dolp_update_at_q_equal_one_matches_the_companion_matrix(key, prior):
    """Q == T from 1 to 1e9 for the metal-like priors: the companion-matrix roots agree to 1e-9 (for the
    dielectric priors, c3 >= 0.65, their root cluster near c3 costs the companion matrix up to 3e-7 here, so
    the brute force above is their reference)."""
    T = 10 ** np.linspace(0, 9, 73)
    ours = dolp_update(T, T, prior)
    ref = np.array([dolp_update_companion(t, t, prior) for t in T])
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-9)


@pytest.mark.parametrize("c2, m", [(9.0, 300), (7.0, 200), (20.0, 100), (200.0, 50)])
def test_map_dolp_update_for_high_order_priors(c2, m):
    """c2^m from 1e115 to 1e286 (accepted by the constructor): a = w m c2^m / T was once capped at 1e200,
    which moved the root (c2 = 9, m = 300: 0.7143 for the maximum at 0.6100)."""
    prior = SuperGaussianPrior(c2, 0.5, m=m)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        P = dolp_update(np.array([100.0]), np.array([90.0]), prior)[0]
    deficit, distance = _deficit(P, 100.0, 90.0, prior)
    assert deficit <= 1e-12
    assert distance <= 1e-6


def test_map_dolp_update_for_a_prior_of_c2_m_1e300_and_a_tiny_total_warns_not():
    """c2 = 1e30, m = 10, T = 1e-10: a = 1e311 overflows a float. The maximum lies within
    (|q - c3| / (a c3 (1 - c3)))^(1/9) ~ 1e-35 of c3 = 0.5, i.e. at 0.5 in floats."""
    prior = SuperGaussianPrior(1e30, 0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        P = dolp_update(np.array([1e-10, 1e-10, 1e-10]), np.array([5e-11, 2e-11, 1e-10]), prior)
    np.testing.assert_array_equal(P, 0.5)


def test_map_dolp_update_for_stiff_priors_extreme_totals_and_weights():
    """Priors with c2^m from 1e-300 to 1e300 (m 2, 10, 300; c3 0 .. 1), T from 1e-300 to 1e300, weights 0 to
    1e300: no warning, a DOLP in [0, 1] and the brute-force maximum of the objective (divided by T + w) to
    1e-12 in every one of the 4320 cases (2e-13 measured; 104k cases of a wider sweep agreed too)."""
    Ts = np.array([1e-300, 1e-5, 1.0, 1e5, 1e300])
    qs = np.array([0.0, 1e-16, 0.1, 0.5, 0.9, 1.0])
    TT, qq = np.meshgrid(Ts, qs, indexing="ij")
    worst, cases = 0.0, 0
    for m in (2, 10, 300):
        for c3 in (0.0, 0.035, 0.5, 1.0):
            for log_c2m in (-300, 0, 150, 300):
                prior = SuperGaussianPrior(10 ** (log_c2m / m), c3, m)
                for w in (0.0, 1.0, 1e300):
                    with warnings.catch_warnings():
                        warnings.simplefilter("error")
                        P = dolp_update(TT, qq * TT, prior, weight=w)
                    assert np.all((P >= 0) & (P <= 1))
                    for t, q, p in zip(TT.ravel(), qq.ravel(), P.ravel()):
                        worst = max(worst, _deficit(p, t, q * t, prior, w)[0])
                        cases += 1
    assert cases == 4320
    assert worst <= 1e-12, worst


def test_classify_dolp_gives_masked_pixels_no_class():
    """The imaging module's DOLP image masks the pixel without light: class -1 there, whatever lies under
    the mask (here 0.0, which would read as metal)."""
    from scatterlab import imaging

    S = np.zeros((2, 2, 3))
    S[..., 0] = [[0, 10], [10, 10]]
    S[..., 1] = [[0, 5], [1, 1]]
    dolp, _ = imaging.dolp_aop_from_stokes(S)
    np.testing.assert_array_equal(classify_dolp(dolp, PRIOR_SETS["ch5"]), [[-1, 0], [1, 1]])
    under = np.ma.array([0.0, 0.6, 0.1], mask=[True, False, False])
    np.testing.assert_array_equal(classify_dolp(under, PRIOR_SETS["ch5"]), [-1, 0, 1])
    with pytest.raises(ValueError, match="dolp must be finite.*masked array"):
        classify_dolp(np.array([0.5, np.nan]), PRIOR_SETS["ch5"])
    with pytest.raises(ValueError, match="dolp must be finite"):  # unmasked NaN in a masked array
        classify_dolp(np.ma.array([0.5, np.nan], mask=[False, False]), PRIOR_SETS["ch5"])


def test_classify_unmixing_treats_masked_pixels_as_unmeasured():
    rng = np.random.default_rng(0)
    lab = np.zeros((8, 8), int)
    lab[:, 4:] = 1
    s0 = np.where(lab == 1, 12.0, 1.0) * (1 + 0.01 * rng.standard_normal((8, 8)))
    P = np.where(lab == 1, 0.01, 0.88)
    mask = np.zeros((8, 8), bool)
    mask[2, 2] = True
    got = classify_unmixing(np.ma.array(s0, mask=mask), np.ma.array(P, mask=mask), 1 - lab)
    assert got[2, 2] == -1
    np.testing.assert_array_equal(got[~mask], (1 - lab)[~mask])


def test_priors_by_name():
    """The names of PRIOR_SETS, as scene files and the command line give them, wherever priors are taken."""
    d = np.ones((4, 12, 12)) * 50.0
    d[:, 3:6, 3:9] = [[[80.0]], [[40.0]], [[20.0]], [[60.0]]]
    th = np.radians([0.0, 45.0, 90.0, 135.0])
    by_name = blind_deconvolve(d, th, iterations=2, psf_radius=2, priors="ch5")
    by_set = blind_deconvolve(d, th, iterations=2, psf_radius=2, priors=PRIOR_SETS["ch5"])
    assert by_name.priors == PRIOR_SETS["ch5"]
    np.testing.assert_array_equal(by_name.classes, by_set.classes)
    np.testing.assert_array_equal(by_name.dolp, by_set.dolp)
    P = np.array([0.02, 0.19, 0.7])
    np.testing.assert_array_equal(classify_dolp(P, "ch6"), classify_dolp(P, PRIOR_SETS["ch6"]))
    v = np.r_[np.full(20, 0.1), np.full(20, 0.7)] + np.linspace(0, 0.02, 40)
    assert adaptive_priors(v, base="ch5") == adaptive_priors(v)
    for call in (
        lambda: blind_deconvolve(d, th, iterations=1, priors="ch8"),
        lambda: classify_dolp(P, "ch8"),
    ):
        with pytest.raises(ValueError, match=r"priors must be .*\['ch5', 'ch6', 'ch7'\].*'ch8'"):
            call()
    with pytest.raises(ValueError, match="priors must be"):
        blind_deconvolve(d, th, iterations=1, priors=[0.3])


def test_nan_data_error_names_the_mask():
    """NaN data: the error points to ``mask`` (zero counts alone read as DOLP 0, i.e. metal), and that
    remedy runs."""
    d = np.ones((4, 10, 10)) * 30.0
    d[:, 4, 4] = np.nan
    th = np.radians([0.0, 45.0, 90.0, 135.0])
    with pytest.raises(ValueError, match=r"data must be finite: 1 pixel.*mask=") as err:
        blind_deconvolve(d, th, iterations=1)
    assert "mark missing pixels with 0 photons" not in str(err.value)
    good = np.isfinite(d).all(axis=0)
    r = blind_deconvolve(np.nan_to_num(d), th, iterations=1, psf_radius=2, mask=good)
    assert np.all(np.isfinite(r.s0))
