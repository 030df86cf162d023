"""Property-based tests (hypothesis) of the photon-counting and prior entries over issue 20's extreme matrix:
zero-photon pixels, photon budgets from 1 to 1e9, prior coefficients c2^m up to 1e40 (m = 10, the
text's). Asserted: finiteness,
bounds, the MAP update maximizing its objective, and DOLP of zero light NaN (never a crash)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scatterlab import imaging
from scatterlab.deconvolution import SuperGaussianPrior, dolp_update, map_objective
from scatterlab.polarization import dolp

A = imaging.ANGLES_0_45_90_135
SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)


@SETTINGS
@given(
    photons=st.floats(1.0, 1e9),
    dark_fraction=st.floats(0.0, 1.0),
    read_noise=st.floats(0.0, 100.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_detection_and_stokes_of_zero_photon_pixels_stay_finite(
    photons, dark_fraction, read_noise, seed
):
    rng = np.random.default_rng(seed)
    S = np.zeros((8, 8, 3))  # (H, W, 3), Stokes axis last
    S[..., 0] = rng.uniform(0, 1, (8, 8)) * (
        rng.uniform(0, 1, (8, 8)) > dark_fraction
    )  # dark pixels: no light
    S[..., 1] = 0.5 * S[..., 0]
    counts = imaging.detect(
        imaging.channel_images(S, A), rng, photons=photons, read_noise=read_noise
    )
    assert np.all(np.isfinite(counts))
    est = imaging.stokes_from_channels(counts, A)
    assert np.all(np.isfinite(est))
    P = dolp(S)  # the convention: NaN exactly where there is no light, in [0, 1] elsewhere
    dark = S[..., 0] == 0
    assert np.all(np.isnan(P[dark])) and np.all((P[~dark] >= 0) & (P[~dark] <= 1))
    P_est = dolp(est)  # noisy estimates: NaN or finite, never inf
    assert not np.any(np.isinf(P_est))


@SETTINGS
@given(
    log_c2m=st.floats(0.0, 40.0),
    c3=st.floats(0.0, 1.0),
    T=st.floats(1e-3, 1e9),
    q=st.floats(0.0, 1.0),
    m=st.just(10),
)
def test_map_dolp_update_is_the_objective_maximum_up_to_huge_coefficients(log_c2m, c3, T, q, m):
    prior = SuperGaussianPrior(10 ** (log_c2m / m), c3, m)  # c2^m from 1 to 1e40
    P = dolp_update(np.array([T]), np.array([q * T]), prior)[0]
    assert np.isfinite(P) and 0 <= P <= 1
    grid = np.linspace(0, 1, 20001)
    with np.errstate(divide="ignore"):
        obj = map_objective(grid, T, q * T, prior)
        here = map_objective(np.array([P]), T, q * T, prior)[0]
    assert np.all(np.isfinite(prior.log_pdf(grid)))
    assert here >= np.max(obj) - 1e-6 * max(1.0, abs(np.max(obj)))


def _brute_force_max(T, Q, prior, weight=1.0):
    """Independent maximum of the complete-data objective: dense grids in log P and log(1 - P) (the
    optimum of a stiff prior can sit at P ~ 1e-16) plus a linear grid; no root finding."""
    tiny = np.geomspace(1e-40, 0.5, 400001)
    grid = np.concatenate([tiny, 1 - tiny, np.linspace(0, 1, 20001)])
    with np.errstate(divide="ignore"):
        return np.max(map_objective(grid, T, Q, prior, weight))


@pytest.mark.parametrize("c2", [1e15, 1e60, 1e90])
def test_map_dolp_update_at_the_analytic_optimum_of_stiff_m2_priors(c2):
    """With c3 = 0, m = 2 and one polarized photon the objective ln P - (c2 P)^2 peaks at
    P = 1/(sqrt(2) c2), from 7e-16 down to 7e-91: the solve must reach it in ln P."""
    prior = SuperGaussianPrior(c2, 0.0, 2)
    P = dolp_update(np.array([1.0]), np.array([1.0]), prior)[0]
    assert P == pytest.approx(1 / (np.sqrt(2) * c2), rel=1e-10)


def test_map_dolp_update_for_an_extremely_stiff_m2_prior():
    """The former strict xfail (the absolute 1e-13 tolerance stopped the Newton solve at P ~ 1e-13): for
    c2 = 1e15, m = 2, c3 = 0 and one photon the objective ln P - (c2 P)^2 peaks at P = 1/(sqrt(2) c2)
    (objective about -35.4)."""
    prior = SuperGaussianPrior(1e15, 0.0, 2)
    P = dolp_update(np.array([1.0]), np.array([1.0]), prior)[0]
    assert P == pytest.approx(
        1 / (np.sqrt(2) * 1e15), rel=1e-10
    )  # analytic d/dP = 1/P - 2 c2^2 P = 0
    best = _brute_force_max(1.0, 1.0, prior)
    assert map_objective(np.array([P]), 1.0, 1.0, prior)[0] >= best - 1e-9 * abs(best)


@SETTINGS
@given(
    log_c2=st.floats(0.0, 15.0),
    m=st.sampled_from([2, 4, 6]),
    c3=st.one_of(st.just(0.0), st.just(1.0), st.floats(0.0, 1.0)),
    T=st.one_of(st.just(1.0), st.floats(1e-3, 1e9)),
    q=st.one_of(st.just(0.0), st.just(1.0), st.floats(0.0, 1.0)),
)
def test_map_dolp_update_beats_a_brute_force_search_for_low_order_stiff_priors(log_c2, m, c3, T, q):
    """Orders below the text's m = 10 and c2 up to 1e15 (c2^m up to 1e90): the update's objective is at
    least the best of a dense log/linear grid (to 1e-9 relative: the grid cannot beat the true optimum)."""
    if m * log_c2 > 300:  # c2^m must stay <= 1e300 (the prior refuses more)
        log_c2 = 300 / m
    prior = SuperGaussianPrior(10**log_c2, c3, m)
    P = dolp_update(np.array([T]), np.array([q * T]), prior)[0]
    assert np.isfinite(P) and 0 <= P <= 1
    best = _brute_force_max(T, q * T, prior)
    with np.errstate(divide="ignore"):
        here = map_objective(np.array([P]), T, q * T, prior)[0]
    assert here >= best - 1e-9 * max(1.0, abs(best))
