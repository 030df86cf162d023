"""Fresnel coefficients against independent truths: analytic limits, boundary conditions,
energy conservation, 50-digit mpmath evaluations, and the sign conventions."""

import warnings

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scatterlab import fresnel, polarization

mpmath.mp.dps = 50

ETAS = [
    1.45025,
    3.23 - 4.35j,
    0.314 - 3.544j,
    1.44 - 16j,
    0.3,
    0.01 - 1000j,
    20.0,
    1 + 1e-9,
    2.5 - 1e-6j,
]


def mp_coefficients(eta, theta):
    """Eq. 45 at 50 digits, with the decaying branch of eta*cos(theta_t)."""
    e = mpmath.mpc(eta.real, eta.imag)
    t = mpmath.mpf(theta)
    c = mpmath.cos(t)
    u = mpmath.sqrt(e**2 - mpmath.sin(t) ** 2)
    if mpmath.im(u) > 0:  # exp(+jwt): the transmitted wave must decay, Im(u) <= 0
        u = -u
    rs = (c - u) / (c + u)
    rp = (e**2 * c - u) / (e**2 * c + u)
    return complex(rs), complex(rp)


@pytest.mark.parametrize("eta", ETAS)
@pytest.mark.parametrize("theta", [0.0, 0.3, 0.9, 1.3, 1.55, np.radians(89.99)])
def test_coefficients_match_50_digit_reference(eta, theta):
    rs, rp = fresnel.coefficients(eta, theta)
    rs_ref, rp_ref = mp_coefficients(complex(eta), theta)
    # relative to the coefficient's own size: covers eta -> 1, where r ~ 1e-10
    assert abs(rs - rs_ref) <= 1e-13 * max(abs(rs_ref), 1e-300) + 1e-15
    assert abs(rp - rp_ref) <= 1e-12 * max(abs(rp_ref), 1e-300) + 1e-15


def test_normal_incidence_rs_equals_rp_and_sign_convention():
    eta = np.array(ETAS, complex)
    rs, rp = fresnel.coefficients(eta, 0.0)
    np.testing.assert_allclose(rs, (1 - eta) / (1 + eta), rtol=1e-13)
    np.testing.assert_allclose(rp, -rs, rtol=1e-13)  # Eq. 45: rp = -rs at normal incidence
    Rs, Rp = fresnel.reflectances(eta, 0.0)
    np.testing.assert_allclose(Rs, Rp, rtol=1e-13)


def test_perfect_conductor_limit():
    rs, rp = fresnel.coefficients(1e8 - 1e8j, np.linspace(0, 1.5, 7))
    np.testing.assert_allclose(rs, -1, atol=1e-7)
    np.testing.assert_allclose(rp, 1, atol=1e-6)
    M = fresnel.mueller_matrix(1e8 - 1e8j, 0.0)
    np.testing.assert_allclose(M, np.diag([1, 1, -1, -1]), atol=1e-7)


@pytest.mark.parametrize("n", [1.2, 1.45025, 2.4, 4.0, 0.5, 0.8])
def test_rp_vanishes_at_brewster_for_lossless(n):
    tb = fresnel.brewster_angle(n)
    assert tb == pytest.approx(np.arctan(n))
    Rs, Rp = fresnel.reflectances(n, tb)
    assert Rp < 1e-28
    assert Rs > 0


@pytest.mark.parametrize("eta", [1.5, 3.23 - 4.35j, 1.44 - 16j, 0.314 - 3.544j])
def test_pseudo_brewster_is_the_minimum_of_rp(eta):
    t = float(fresnel.pseudo_brewster_angle(eta))
    grid = np.linspace(0, np.pi / 2, 200001)
    Rp = fresnel.reflectances(eta, grid)[1]
    assert t == pytest.approx(grid[np.argmin(Rp)], abs=2e-5)
    if np.imag(eta) == 0:
        assert t == pytest.approx(np.arctan(np.real(eta)), abs=1e-9)


def test_boundary_conditions_link_r_and_t():
    """Continuity of tangential E and H (Eq. 44): t_s = 1 + r_s, eta t_p = 1 + r_p."""
    eta = np.array(ETAS, complex)[:, None]
    theta = np.linspace(0, np.pi / 2, 11)[None, :]
    rs, rp = fresnel.coefficients(eta, theta)
    ts, tp = fresnel.transmission_coefficients(eta, theta)
    np.testing.assert_allclose(ts, 1 + rs, atol=1e-12)
    np.testing.assert_allclose(eta * tp, 1 + rp, atol=1e-12)


@pytest.mark.parametrize("eta", [1.5, 1.0001, 4.0, 0.6, 3.23 - 4.35j, 0.2 - 5j, 1.44 - 16j])
def test_energy_conservation_R_plus_T(eta):
    """R + T = 1: for lossless media (with the cosine/impedance factors) and, by flux
    continuity at the interface, for absorbing ones."""
    theta = np.linspace(0, np.pi / 2, 181)
    Rs, Rp = fresnel.reflectances(eta, theta)
    Ts, Tp = fresnel.transmittances(eta, theta)
    np.testing.assert_allclose(Rs + Ts, 1, atol=1e-13)
    np.testing.assert_allclose(Rp + Tp, 1, atol=1e-13)


def test_total_internal_reflection_branch():
    n = 0.7
    theta = np.linspace(np.arcsin(n) + 1e-3, np.pi / 2, 50)
    u = fresnel.refraction_term(n, theta)
    assert np.all(u.real <= 1e-15) and np.all(-u.imag > 0)  # A = 0, B > 0: evanescent, decaying
    Rs, Rp = fresnel.reflectances(n, theta)
    np.testing.assert_allclose(Rs, 1, atol=1e-14)
    np.testing.assert_allclose(Rp, 1, atol=1e-14)


def test_refraction_term_errata_formula():
    """A, B of the corrected Eq. 49: A = sqrt((sqrt(C)+D)/2), B = sqrt((sqrt(C)-D)/2)."""
    n, k, th = 3.23, 4.35, 0.7
    D = n**2 - k**2 - np.sin(th) ** 2
    C = 4 * n**2 * k**2 + D**2
    A, B = np.sqrt((np.sqrt(C) + D) / 2), np.sqrt((np.sqrt(C) - D) / 2)
    u = fresnel.refraction_term(n - 1j * k, th)
    assert u == pytest.approx(A - 1j * B, rel=1e-14)
    # and Eq. 50 for Rs from A and B
    Rs = ((np.cos(th) - A) ** 2 + B**2) / ((np.cos(th) + A) ** 2 + B**2)
    assert fresnel.reflectances(n - 1j * k, th)[0] == pytest.approx(Rs, rel=1e-13)


def test_eq53_rp_from_rs():
    n, k = 3.23, 4.35
    th = np.linspace(0.01, 1.5, 20)
    u = fresnel.refraction_term(n - 1j * k, th)
    A, B = u.real, -u.imag
    st_ = np.sin(th) * np.tan(th)
    Rs, Rp = fresnel.reflectances(n - 1j * k, th)
    np.testing.assert_allclose(
        Rp, ((A - st_) ** 2 + B**2) / ((A + st_) ** 2 + B**2) * Rs, rtol=1e-12
    )


def test_mueller_matrix_eq55_equals_jones_conversion():
    eta = np.array(ETAS, complex)[:, None]
    theta = np.linspace(0, np.pi / 2, 7)[None, :]
    rs, rp = fresnel.coefficients(eta, theta)
    J = np.zeros(rs.shape + (2, 2), complex)
    J[..., 0, 0], J[..., 1, 1] = rs, rp
    np.testing.assert_allclose(
        fresnel.mueller_matrix(eta, theta), polarization.jones_to_mueller(J), atol=1e-14
    )
    # unpolarized light: DOP = (Rs - Rp)/(Rs + Rp), AOP = 0 (Eq. 57)
    S = polarization.apply(fresnel.mueller_matrix(1.5, 0.6), [1, 0, 0, 0])
    Rs, Rp = fresnel.reflectances(1.5, 0.6)
    assert polarization.dop(S) == pytest.approx((Rs - Rp) / (Rs + Rp))
    assert polarization.aop(S) == pytest.approx(0.0)


def test_index_from_permittivity_eq28():
    eta = 3.23 - 4.35j
    eps = eta**2
    wavelength = 1e-6
    omega = 2 * np.pi * fresnel.SPEED_OF_LIGHT / wavelength
    sigma = -eps.imag * omega * fresnel.EPSILON_0
    got = fresnel.index_from_permittivity(eps.real, sigma, wavelength)
    assert got == pytest.approx(eta, rel=1e-13)
    assert fresnel.index_from_permittivity(2.25) == pytest.approx(1.5)
    assert fresnel.complex_index(3.23, 4.35) == eta


def test_extreme_inputs_finite_and_bounded():
    n = np.geomspace(0.01, 20, 25)[:, None, None]
    kappa = np.r_[0, np.geomspace(1e-6, 1e3, 24)][None, :, None]
    theta = np.r_[np.linspace(0, np.pi / 2, 30), np.radians(89.99)][None, None, :]
    eta = n - 1j * kappa
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rs, rp = fresnel.coefficients(eta, theta)
        Rs, Rp = fresnel.reflectances(eta, theta)
        Ts, Tp = fresnel.transmittances(eta, theta)
        M = fresnel.mueller_matrix(eta, theta)
    for a in (rs, rp, Rs, Rp, Ts, Tp, M):
        assert np.all(np.isfinite(a))
    assert np.all((Rs >= 0) & (Rs <= 1) & (Rp >= 0) & (Rp <= 1))
    # grazing: R -> 1 for any medium other than vacuum
    np.testing.assert_allclose(Rs[..., -2], 1, atol=1e-12)
    np.testing.assert_allclose(Rp[..., -2], 1, atol=1e-12)


def test_eta_one_is_no_interface():
    rs, rp = fresnel.coefficients(1.0, np.array([0, 0.5, np.pi / 2]))
    assert np.all(rs == 0) and np.all(rp == 0)


@settings(max_examples=300, deadline=None)
@given(n=st.floats(0.01, 20), kappa=st.floats(0, 1e3), theta=st.floats(0, np.pi / 2))
def test_property_bounds_order_and_realizability(n, kappa, theta):
    eta = n - 1j * kappa
    Rs, Rp = fresnel.reflectances(eta, theta)
    assert 0 <= Rp <= 1 and 0 <= Rs <= 1
    assert Rp <= Rs * (1 + 1e-12) + 1e-15  # |r_p| <= |r_s| for every passive medium
    M = fresnel.mueller_matrix(eta, theta)
    assert polarization.is_physical_mueller(M, atol=1e-9)
    assert M[0, 0] >= abs(M[0, 1]) - 1e-15


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: fresnel.coefficients(1.5 + 0.1j, 0.3), "eta"),
        (lambda: fresnel.coefficients(np.nan, 0.3), "eta"),
        (lambda: fresnel.reflectances(1.5, -0.1), "theta"),
        (lambda: fresnel.reflectances(1.5, np.pi / 2 + 1e-9), "theta"),
        (lambda: fresnel.reflectances(1.5, np.nan), "theta"),
        (lambda: fresnel.reflectances(np.ones(3), np.ones(4) * 0.1), "shapes"),
        (lambda: fresnel.complex_index(1.5, -0.2), "kappa"),
        (lambda: fresnel.brewster_angle(3 - 1j), "lossless"),
        (lambda: fresnel.index_from_permittivity(2.0, 1e3), "wavelength"),
    ],
)
def test_bad_input_raises_value_error_naming_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ---------------------------------------------------------------- issue 20: the valid |eta| range
TINY_ETAS = [-2.207e-8j, 1e-8 + 0j, 3e-6 - 2e-6j, 1e-4 - 1e-5j, 5e-3 + 0j, 0.0 - 0.009j]


@pytest.mark.parametrize("eta", TINY_ETAS)
@pytest.mark.parametrize("theta", [0.0, 5.825e-9, 1e-5, 0.3, 1.2, np.radians(89.99), np.pi / 2])
def test_tiny_index_matches_50_digit_reference(eta, theta):
    """|eta| < 0.01: (n^2 - 1) - kappa^2 + cos^2 cancelled (R = 1.188 at eta = -2.2e-8j)."""
    rs, rp = fresnel.coefficients(eta, theta)
    rs_ref, rp_ref = mp_coefficients(complex(eta), theta)
    assert abs(rs - rs_ref) <= 1e-13 * abs(rs_ref) + 1e-15
    assert abs(rp - rp_ref) <= 1e-12 * abs(rp_ref) + 1e-15
    Rs, Rp = fresnel.reflectances(eta, theta)
    assert Rs == pytest.approx(abs(rs_ref) ** 2, abs=1e-13)
    assert Rp == pytest.approx(abs(rp_ref) ** 2, abs=1e-13)


def test_issue20_tiny_index_reproducer_does_not_create_energy():
    M = fresnel.mueller_matrix(-2.207e-8j, 5.825e-9)
    assert M[0, 0] == pytest.approx(1.0, abs=1e-13)  # n = 0: a lossless plasma reflects everything
    assert polarization.is_physical_mueller(M, atol=1e-12)


@pytest.mark.parametrize("eta", [1e4 - 3e3j, 1e6 + 0j, 2e5 - 1e6j])
@pytest.mark.parametrize("theta", [0.0, 0.7, 1.5, np.radians(89.99)])
def test_huge_index_matches_50_digit_reference(eta, theta):
    rs, rp = fresnel.coefficients(eta, theta)
    rs_ref, rp_ref = mp_coefficients(complex(eta), theta)
    assert abs(rs - rs_ref) <= 1e-13
    assert abs(rp - rp_ref) <= 1e-12


def test_ends_of_the_valid_range_are_the_physical_limits():
    """|eta| = 1e50 is a perfect conductor (rs = -1, rp = 1), |eta| = 1e-50 reflects totally."""
    theta = np.array([0.0, 0.4, 1.2, np.pi / 2])
    rs, rp = fresnel.coefficients(9e49 - 4e49j, theta)
    np.testing.assert_allclose(rs, -1, atol=1e-14)
    np.testing.assert_allclose(rp, 1, atol=1e-14)
    for eta in (1e-50 + 0j, -1e-50j, 1e-50 - 1e-50j):
        Rs, Rp = fresnel.reflectances(eta, theta)
        np.testing.assert_allclose(Rs, 1, atol=1e-14)
        np.testing.assert_allclose(Rp, 1, atol=1e-14)
        assert np.all(np.isfinite(fresnel.mueller_matrix(eta, theta)))


@pytest.mark.parametrize("eta", [1e78 + 0j, 1e51 + 0j, 1e-51 + 0j, 0.0, 0j])
def test_outside_the_valid_range_raises_naming_eta_and_the_range(eta):
    with pytest.raises(ValueError, match=r"eta.*1e-50.*1e\+50"):
        fresnel.reflectances(eta, 0.3)


def test_zero_real_part_is_a_lossless_plasma():
    """n = 0 is allowed (eta purely imaginary): total reflection at every angle, R + T = 1."""
    theta = np.linspace(0, np.pi / 2, 13)
    Rs, Rp = fresnel.reflectances(-2.5j, theta)
    np.testing.assert_allclose(Rs, 1, atol=1e-14)
    np.testing.assert_allclose(Rp, 1, atol=1e-14)
    Ts, Tp = fresnel.transmittances(-2.5j, theta)
    np.testing.assert_allclose(Ts + Tp, 0, atol=1e-14)


# ---------------------------------------------------------------- the reduced-coefficient kernel
@pytest.mark.parametrize("eta", ETAS + TINY_ETAS[:3])
def test_reduced_coefficients_times_one_minus_eta2_are_the_coefficients(eta):
    theta = np.linspace(0, 1.5, 11)
    red = fresnel.reduced_coefficients(eta, np.cos(theta), np.sin(theta) ** 2)
    refs = map(np.array, zip(*(mp_coefficients(complex(eta), t) for t in theta)))
    for r, r_ref in zip((red.rs, red.rp), refs):
        np.testing.assert_allclose((1 - eta**2) * r, r_ref, rtol=1e-12, atol=1e-15)
    e = mpmath.mpc(complex(eta).real, complex(eta).imag)
    np.testing.assert_allclose(red.scale, float(abs(1 - e**2) ** 2), rtol=1e-14)


@pytest.mark.parametrize("eta", [3.23 - 4.35j, 1.5 - 0.01j, 0.314 - 3.544j, 1 - 0.2j, 0.6 - 1e-3j])
def test_smooth_dolp_gradient_equals_central_differences(eta):
    theta = np.radians([5, 30, 55, 80, 89])
    P, g = fresnel.smooth_dolp(eta, np.cos(theta), gradient=True)
    h = 1e-7
    for k, step in enumerate((h, -1j * h)):
        up = fresnel.smooth_dolp(eta + step, np.cos(theta))[0]
        dn = fresnel.smooth_dolp(eta - step, np.cos(theta))[0]
        np.testing.assert_allclose(g[:, k], (up - dn) / (2 * h), rtol=1e-6, atol=1e-8)
    Rs, Rp = fresnel.reflectances(eta, theta)
    np.testing.assert_allclose(P, (Rs - Rp) / (Rs + Rp), rtol=1e-12, atol=1e-15)


def test_smooth_dolp_is_continuous_at_eta_one_and_zero_for_a_conductor():
    c = np.cos(np.radians([10, 40, 70]))
    at_one, near_one = fresnel.smooth_dolp(1.0, c)[0], fresnel.smooth_dolp(1 + 1e-9, c)[0]
    np.testing.assert_allclose(at_one, near_one, rtol=1e-7)
    assert np.all(fresnel.smooth_dolp("pec", c)[0] == 0)
    with pytest.raises(ValueError, match="cos_theta"):
        fresnel.smooth_dolp(1.5, 1.2)
