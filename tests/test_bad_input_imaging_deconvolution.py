"""Issue 20's reproducers in imaging and deconvolution: each is a ValueError naming the argument, or a correct
result; the extremes of the DOLP priors (c2^m up to 1e40, q = 1) stay finite and right."""

import numpy as np
import pytest

from scatterlab import imaging
from scatterlab.cli import main
from scatterlab.deconvolution import (
    PRIOR_SETS,
    SuperGaussianPrior,
    blind_deconvolve,
    classification_errors,
    classify_dolp,
    dolp_update,
    dolp_update_companion,
    map_objective,
)

A = imaging.ANGLES_0_45_90_135
GOOD = np.random.default_rng(0).poisson(100, (4, 16, 16)).astype(float)

CASES = [
    (lambda: imaging.phase_screen(32, 0.01, 0.1, 1, l0=np.nan), "l0"),
    (lambda: imaging.phase_screen(32, 0.01, 1e-300, 1), "r0"),
    (lambda: imaging.phase_screen(16, 1e-300, 0.1, 1), "too large for a screen"),
    (lambda: imaging.phase_screen(16, 0.01, 0.1, 1, L0=-np.inf), "L0"),
    (lambda: imaging.SlidingScreen(16, 0.01, 0.1, 1).window(np.nan), "shift"),
    (lambda: imaging.remove_piston_tilt(np.ones((8, 8)), np.zeros((8, 8), bool)), "mask"),
    (lambda: imaging.psf(np.zeros((8, 8))), "pupil"),
    (lambda: imaging.detect(np.ones((4, 4, 4)), 1, photons=10, read_noise=np.nan), "read_noise"),
    (lambda: imaging.detect(np.ones((4, 4, 4)), 1, photons=np.inf), "photons"),
    (lambda: imaging.detect(np.ones((4, 4, 4)), 1, photons=10, scale=-1), "scale"),
    # photons = 1e30 was numpy's "lam value too large": its Poisson sampler draws means up to 9.2e18
    (lambda: imaging.detect(np.ones((4, 4, 4)), 1, photons=1e30), r"photons .* in \(0, 1e\+18\]"),
    (
        lambda: imaging.detect(np.ones((4, 4, 4)), 1, photons=10, dark_current=1e19),
        r"dark_current .* 1e\+18",
    ),
    (lambda: imaging.detect(np.ones((4, 4, 4)), 1, photons=1e17, scale=0.01), "scale .* too small"),
    # NaN or negative T and weight gave NaN or a silently wrong update
    (lambda: dolp_update(np.array([np.nan, 5.0]), np.array([1.0, 1.0])), "T must be finite"),
    (lambda: dolp_update(np.array([-1.0, 5.0]), np.array([1.0, 1.0])), "T must be >= 0"),
    (lambda: dolp_update(np.array([5.0]), np.array([np.nan])), "Q must be finite"),
    (
        lambda: dolp_update(np.array([5.0]), np.array([1.0]), PRIOR_SETS["ch5"][0], np.nan),
        "weight must be finite",
    ),
    (
        lambda: dolp_update(np.array([5.0]), np.array([1.0]), PRIOR_SETS["ch5"][0], -1.0),
        "weight must be >= 0",
    ),
    (lambda: blind_deconvolve(np.zeros((4, 16, 16)), A, iterations=2), "no photons"),
    (lambda: blind_deconvolve(-GOOD, A, iterations=2), "no photons"),
    (lambda: blind_deconvolve(GOOD, A, psf0=np.full((32, 32), np.nan), iterations=2), "psf0"),
    (lambda: blind_deconvolve(GOOD, A, psf0=np.zeros((32, 32)), iterations=2), "psf0"),
    (lambda: blind_deconvolve(GOOD, A, psf0=-np.ones((32, 32)), iterations=2), "psf0"),
    (lambda: blind_deconvolve(GOOD, A, psf_radius=0, iterations=2), "psf_radius"),
    (lambda: blind_deconvolve(GOOD, A, psf_radius=1e6, iterations=2), "psf_radius"),
    (lambda: blind_deconvolve(GOOD, A, pad=-3, iterations=2), "pad"),
    (
        lambda: blind_deconvolve(
            GOOD, A, priors=PRIOR_SETS["ch5"], prior_weight=np.nan, iterations=2
        ),
        "prior_weight",
    ),
    (lambda: blind_deconvolve(GOOD, np.array([0, 45, 90, 135.0]), iterations=2), "radians"),
    (lambda: imaging.channel_images(np.ones((3, 8, 8)), A), r"stokes .*\(H, W, 3\)"),
    (lambda: imaging.dolp_aop_from_stokes(np.ones((3, 8, 8))), r"S .*\(H, W, 3\)"),
    (lambda: blind_deconvolve(GOOD, A, s0_start=-1.0, iterations=2), "s0_start"),
    (lambda: blind_deconvolve(GOOD, A, s0_start=0.0, iterations=2), "s0_start"),
    (lambda: blind_deconvolve(GOOD, A, dolp_start=np.nan, iterations=2), "dolp_start"),
    (lambda: blind_deconvolve(GOOD, A, aop=np.nan, iterations=2), "aop"),
    (lambda: blind_deconvolve(GOOD, A, iterations=-1), "iterations"),
    (lambda: blind_deconvolve(GOOD, A, iterations=2, tol=np.nan), "tol"),
    (lambda: imaging.short_exposure_mtf(np.array([0.5]), 2.0, alpha=5.0), "alpha"),
    (lambda: imaging.otf(np.zeros((8, 8))), "positive sum"),
    (lambda: imaging.mtf(np.zeros((8, 8))), "positive sum"),
    (lambda: classify_dolp(np.array([0.5, np.nan]), PRIOR_SETS["ch5"]), "dolp must be finite"),
    (
        lambda: classification_errors(
            np.zeros((4, 4), int), np.zeros((4, 4), int), mask=np.zeros((4, 4), bool)
        ),
        "mask",
    ),
    (lambda: SuperGaussianPrior(1e40, 0.3), "c2"),
    (lambda: SuperGaussianPrior(3.0, 1.5), "c3"),
]


@pytest.mark.parametrize("case, name", CASES)
def test_bad_input_is_a_value_error_naming_the_problem(case, name):
    with pytest.raises(ValueError, match=name):
        case()


def test_detect_at_its_largest_photon_count():
    """photons = 1e18 (the largest allowed) with the largest dark current: drawn, finite."""
    out = imaging.detect(np.ones((1, 2, 2)), 1, photons=1e18, dark_current=1e18)
    assert np.all(np.isfinite(out)) and abs(out.mean() / 1e18 - 1) < 1e-6


def test_negative_seed_is_named(capsys):
    assert main(["study", "run", "fig4", "--quick", "--seed", "-5"]) == 2
    assert "--seed" in capsys.readouterr().err


def test_dolp_update_at_q_equal_one_takes_the_best_root():
    """At q = Q/T = 1 the MAP update is the objective's maximum on [0, 1] (brute force on a fine grid), and
    the companion-matrix reference agrees."""
    prior = PRIOR_SETS["ch5"][0]
    P = np.linspace(0, 1, 200001)
    best = P[np.argmax(map_objective(P, 10.0, 10.0, prior))]
    assert dolp_update(np.array([10.0]), np.array([10.0]), prior)[0] == pytest.approx(
        best, abs=1e-5
    )
    assert dolp_update_companion(10.0, 10.0, prior) == pytest.approx(best, abs=1e-5)


def test_huge_prior_coefficients_stay_finite():
    """c2^m = 1e40: the log-density is finite (never -inf or NaN) and the MAP update stays in [0, 1] and equals
    the brute-force maximum of the objective."""
    prior = SuperGaussianPrior(1e4, 0.3)  # c2^10 = 1e40
    lp = prior.log_pdf(np.array([0.0, 0.3, 1.0]))
    assert np.all(np.isfinite(lp)) and lp[1] == 0 and lp[0] < -1e29
    T = np.array([1e3, 1e6])
    Q = np.array([500.0, 2e5])
    P = dolp_update(T, Q, prior)
    assert np.all((P >= 0) & (P <= 1))
    grid = np.linspace(0, 1, 400001)
    for t, q, p in zip(T, Q, P):
        o = map_objective(grid, t, q, prior)
        assert map_objective(np.array([p]), t, q, prior)[0] >= o.max() - 1e-6 * abs(o.max())


def test_a_compact_psf_over_a_dark_scene_gives_non_negative_channels():
    """The FFT's round-off left -7e-16 in the dark part of a blurred scene, which detect then refused as
    a negative intensity: intensities are >= 0, and the light is conserved (unit-sum PSF)."""
    y, x = np.mgrid[:64, :64] - 32
    h = np.exp(-(x * x + y * y) / 8.0)
    h /= h.sum()
    S = np.zeros((64, 64, 3))
    S[40:50, 40:50] = [5.0, -1.0, 0.5]
    ch = imaging.channel_images(S, A, h)
    assert ch.min() >= 0
    np.testing.assert_allclose(ch.sum(axis=(1, 2)), imaging.channel_images(S, A).sum(axis=(1, 2)))
    assert imaging.detect(ch, 1, photons=1e4).min() >= 0


def test_long_exposure_mtf_clips_frequencies_like_the_others():
    nu = np.array([-0.1, 0.0, 1.2])
    np.testing.assert_allclose(imaging.long_exposure_mtf(nu, 2.0), [1.0, 1.0, 0.0], atol=1e-12)


def test_a_phase_screen_depends_on_lengths_only_through_their_ratio_to_r0():
    """dx and r0 in any unit (1e-200 or 1e300) give the same screen: they overflowed or divided by zero."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = imaging.phase_screen(16, 0.01, 0.1, 1)
        for scale in (1e-200, 1e290):
            np.testing.assert_allclose(
                imaging.phase_screen(16, 0.01 * scale, 0.1 * scale, 1), a, atol=1e-12
            )
