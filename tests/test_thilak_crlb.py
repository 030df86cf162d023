"""Cramer-Rao bounds of Thilak's (n, kappa, theta_r) and the two-step method's solver options,
against independent truths: the printed Eq. 115 differentiated numerically, the library's pBRDF
bound, the scatter of joint least squares in the linear regime, and hand-computed cases."""

import numpy as np
import pytest
from scipy import optimize

from scatterlab import study_runner
from scatterlab.inversion.design import crlb
from scatterlab.inversion.thilak import thilak_crlb, thilak_dop, thilak_jacobian, thilak_two_step

COPPER = (0.314, 3.544)
TR = np.radians(60.0)
TI10 = np.radians(np.linspace(35, 80, 10))


def _eq115(n, kappa, beta):
    # the printed formula with the errata's A and B, written out independently of the package
    s2, c = np.sin(beta) ** 2, np.cos(beta)
    d = n**2 - kappa**2 - s2
    root_c = np.sqrt(4 * n**2 * kappa**2 + d**2)
    a, b = np.sqrt((root_c + d) / 2), np.sqrt((root_c - d) / 2)
    return 2 * a * s2 * c / (a**2 * c**2 + s2**2 + b**2 * c**2)


def test_jacobian_matches_central_differences_of_the_printed_formula():
    beta = np.radians(np.linspace(40, 75, 8))
    h = 1e-6  # central differences: error ~h^2 f''' ~ 1e-12, rounding ~1e-16/h ~ 1e-10
    n, k = COPPER
    ref = np.stack(
        [
            _eq115(n + h, k, beta) - _eq115(n - h, k, beta),
            _eq115(n, k + h, beta) - _eq115(n, k - h, beta),
            _eq115(n, k, beta + h) - _eq115(n, k, beta - h),
        ],
        -1,
    ) / (2 * h)
    np.testing.assert_allclose(thilak_jacobian(*COPPER, beta), ref, rtol=1e-6, atol=1e-9)


def test_crlb_with_theta_r_known_equals_the_library_pbrdf_bound():
    # the pBRDF DOLP in the specular plane without a diffuse part is the facet DOLP at beta:
    # the library's bound (DolpForward's Jacobian, another code path) must agree
    ours = thilak_crlb(*COPPER, TR, TI10, 1e-3, theta_r_known=True)
    lib = crlb(*COPPER, 0.3, TI10, np.full(TI10.size, TR), 1e-3, sigma_known=True, diffuse="none")
    np.testing.assert_allclose(ours, lib, rtol=1e-6)


def test_joint_crlb_matches_the_scatter_of_joint_least_squares_in_the_linear_regime():
    # at noise 1e-6 the least-squares estimate of (n, kappa, theta_r) is linear in the noise and
    # efficient: its standard deviations equal the bound. 400 trials: the relative standard
    # error of a standard deviation is 1/sqrt(2 * 399) = 3.5 %; tolerance 4 SE = 14 %
    noise = 1e-6
    bound = thilak_crlb(*COPPER, TR, TI10, noise)
    rng = np.random.default_rng(3)
    clean = thilak_dop(*COPPER, (TI10 + TR) / 2)
    est = []
    for _ in range(400):
        y = clean + noise * rng.standard_normal(TI10.size)
        r = optimize.least_squares(
            lambda p, y=y: thilak_dop(p[0], p[1], (TI10 + p[2]) / 2) - y,
            [*COPPER, TR], method="lm", xtol=1e-15, ftol=1e-15,
        )  # fmt: skip
        est.append(r.x)
    np.testing.assert_allclose(np.std(est, 0, ddof=1), bound, rtol=0.14)


def test_crlb_scales_with_the_noise_and_rejects_bad_input():
    # I = J^T J / s^2: the bound is proportional to s (exact)
    b1, b2 = (thilak_crlb(*COPPER, TR, TI10, s) for s in (1e-3, 4e-3))
    np.testing.assert_allclose(b2, 4 * b1, rtol=1e-12)
    with pytest.raises(ValueError, match="noise"):
        thilak_crlb(*COPPER, TR, TI10, 0.0)
    with pytest.raises(ValueError, match="n must be > 0"):
        thilak_crlb(-0.1, 3.0, TR, TI10, 1e-3)
    with pytest.raises(ValueError, match="theta_i"):
        thilak_crlb(*COPPER, TR, TI10[:2], 1e-3)


@pytest.mark.parametrize(
    "opts",
    [
        {},
        {"solver": "trf", "tol": 1e-6, "max_nfev": 200},
        {"solver": "trf", "bounds": ((0, 10), (0, 25))},
        {"solver": "nelder-mead", "tol": 1e-10, "max_nfev": 4000},
    ],
)
def test_every_solver_recovers_copper_from_clean_data(opts):
    # hand case: noiseless data, the residual vanishes only at the truth (M = 10 determines it)
    y = thilak_dop(*COPPER, (TI10 + TR) / 2)
    fit = thilak_two_step(y, TI10, TR, np.random.default_rng(0), start=(0.5, 3.0), **opts)
    np.testing.assert_allclose([fit.n[0], fit.kappa[0], fit.theta_r[0]], [*COPPER, TR], rtol=1e-3)


def test_bounded_search_stops_on_the_box_when_the_minimum_lies_outside():
    # data of eta = 8 - j12 with the box n <= 5: the solution must sit on the face n = 5 at the
    # kappa that minimises the residual along that face (found here by a dense 1-D scan); tight
    # tolerances, because the valley is so flat that the default ftol stops short of the face
    ti = np.radians(np.linspace(55, 65, 3))
    beta = (ti + TR) / 2
    y = thilak_dop(8.0, 12.0, beta)
    fit = thilak_two_step(y, ti, TR, np.random.default_rng(0), solver="trf",
                          bounds=((0, 5), (0, 25)), start=(1.0, 1.0), tol=1e-12)  # fmt: skip
    k = np.linspace(0, 25, 250_001)
    k_best = k[np.argmin(((thilak_dop(5.0, k[:, None], beta) - y) ** 2).sum(1))]
    assert fit.n[0] == pytest.approx(5.0, abs=1e-6)
    assert fit.kappa[0] == pytest.approx(k_best, abs=1e-3)


def test_solver_options_are_validated():
    y = thilak_dop(*COPPER, (TI10 + TR) / 2)
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="solver"):
        thilak_two_step(y, TI10, TR, rng, solver="bfgs")
    with pytest.raises(ValueError, match="bounds"):
        thilak_two_step(y, TI10, TR, rng, bounds=((0, 5), (0, 25)))  # LM takes no bounds
    with pytest.raises(ValueError, match="bounds"):
        thilak_two_step(y, TI10, TR, rng, solver="trf", bounds=((0, 5), (3, 1)))
    with pytest.raises(ValueError, match="tol"):
        thilak_two_step(y, TI10, TR, rng, tol=0.0)
    with pytest.raises(ValueError, match="max_nfev"):
        thilak_two_step(y, TI10, TR, rng, max_nfev=0)


TT = study_runner.discover()["thilak_tables"].module


def test_mc_stats_of_a_hand_computed_sample():
    # x = 1, 2, 3, 6 about the truth 2: mean 3, sd sqrt(14/3); e^2 = 1, 0, 1, 16 (mean 4.5,
    # sd sqrt(59)), RMSE sqrt(4.5)
    s = TT.mc_stats(np.array([1.0, 2.0, 3.0, 6.0, np.nan]), 2.0)
    assert s["count"] == 4
    assert s["mean"] == pytest.approx(3.0)
    assert s["se_mean"] == pytest.approx(np.sqrt(14 / 3) / 2)
    assert s["rmse"] == pytest.approx(np.sqrt(4.5))
    assert s["se_rmse"] == pytest.approx(np.sqrt(59) / (2 * np.sqrt(4.5) * 2))


def test_published_plus_minus_is_the_95_percent_half_width_of_the_mean():
    # independent check of the reading: with sd = (+/-) sqrt(trials) / 1.96 and the published
    # bias, sqrt(bias^2 + sd^2) must give the published RMSE column. Tolerance 7 %: the
    # "+/-" is printed to 3 decimals (0.008 for theta_r at low noise, M = 3, is +/-6 % rounding)
    for level, rows in TT.PUBLISHED.items():
        for key in rows:
            pub = TT.published_se(level, key)
            for par, truth in TT.PARAMS:
                p = pub[par]
                sd = p["se_mean"] * np.sqrt(TT.LEVELS[level][1])
                rmse = np.hypot(p["mean"] - truth, sd)
                assert rmse == pytest.approx(p["rmse"], rel=0.07), (level, key, par)


def test_step_two_start_is_honoured_and_validated():
    # hand case: clean data, step 2 started 10 deg away still returns the true theta_r
    y = thilak_dop(*COPPER, (TI10 + TR) / 2)
    fit = thilak_two_step(y, TI10, TR, np.random.default_rng(0), theta_r_start=np.radians(50))
    assert fit.theta_r[0] == pytest.approx(TR, abs=1e-7)
    with pytest.raises(ValueError, match="theta_r_start"):
        thilak_two_step(y, TI10, TR, np.random.default_rng(0), theta_r_start="fixed")
    with pytest.raises(ValueError, match="theta_r_start"):
        thilak_two_step(y, TI10, TR, np.random.default_rng(0), theta_r_start=2.0)


def test_crlb_of_a_dielectric():
    # kappa = 0 (glass): below the critical angle the Fresnel coefficients are real, so the DOP is
    # stationary in kappa and kappa's bound is infinite. n's and theta_r's bounds are then those of
    # the two-parameter problem, from a central-difference Jacobian of the test's own Eq. 115.
    glass = thilak_crlb(1.5, 0.0, TR, TI10, 1e-3)
    assert np.isinf(glass[1]) and np.all(np.isfinite(glass[[0, 2]]))

    def dop(n, tr):
        return _eq115(n, 0.0, (TI10 + tr) / 2)

    h = 1e-6
    J = np.stack(
        [
            (dop(1.5 + h, TR) - dop(1.5 - h, TR)) / (2 * h),
            (dop(1.5, TR + h) - dop(1.5, TR - h)) / (2 * h),
        ],
        axis=1,
    )
    expected = np.sqrt(np.diag(np.linalg.inv(J.T @ J / 1e-3**2)))
    np.testing.assert_allclose(glass[[0, 2]], expected, rtol=1e-5)
    # a nearly lossless material: kappa's bound grows as 1/kappa, n's stays finite
    b1, b2 = (thilak_crlb(1.5, k, TR, TI10, 1e-3) for k in (1e-4, 1e-6))
    assert b2[1] == pytest.approx(100 * b1[1], rel=1e-3)
    with pytest.raises(ValueError, match="kappa >= 0"):
        thilak_crlb(1.5, -1e-3, TR, TI10, 1e-3)
