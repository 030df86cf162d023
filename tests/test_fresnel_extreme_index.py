"""The DOLP kernel and the reduced-coefficient derivatives over the whole valid range
``1e-50 <= |eta| <= 1e50``, against independent truths: Eq. 45 evaluated in 300-digit arithmetic
and differentiated by central differences there, the analytic normal-incidence limits, and no
numpy warning (warnings are errors here).

Fuzz defects: ``smooth_dolp(1e41, 1.0, gradient=True)`` gave a NaN gradient (the squared reduced
coefficients underflowed) for ``1e41 <= |eta| <= 1e50``; at normal incidence with ``|eta| < 1e-12``
the analytic derivatives were wrong (``du/deta`` floored at ``|u| = 1e-12`` although ``u = eta``,
and the ``drp`` numerator cancelled): gradient ``[-2e20, 0]`` at ``eta = 1e-20`` instead of 0,
``drs = -2e-8, drp = -2e20`` instead of ``-2, +2``."""

import warnings

import mpmath
import numpy as np
import pytest

from scatterlab import fresnel

DPS = 300


@pytest.fixture(autouse=True)
def _strict():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def mp_dolp(n, kappa, theta):
    """(Rs - Rp)/(Rs + Rp) from Eq. 45 as printed, decaying branch of u = eta cos(theta_t)."""
    e = mpmath.mpc(n, -kappa)
    c, s = mpmath.cos(theta), mpmath.sin(theta)
    u = mpmath.sqrt(e**2 - s**2)
    if mpmath.re(u) < 0 or (mpmath.re(u) == 0 and mpmath.im(u) > 0):
        u = -u
    Rs = abs((c - u) / (c + u)) ** 2
    Rp = abs((e**2 * c - u) / (e**2 * c + u)) ** 2
    return (Rs - Rp) / (Rs + Rp)


def mp_dolp_and_gradient(eta, theta):
    """DOLP and (d/dn, d/dkappa) by central differences with a step of 1e-100 |eta| at 300 digits
    (truncation error ~1e-200 relative); one-sided (second order) at n = 0 or kappa = 0, the
    edges of the passive half-plane."""
    with mpmath.workdps(DPS):
        n, k, t = mpmath.mpf(eta.real), mpmath.mpf(-eta.imag), mpmath.mpf(theta)
        h = mpmath.mpf(10) ** -100 * abs(mpmath.mpc(n, k))
        P = mp_dolp(n, k, t)

        def derivative(f, x):
            if x > h:
                return (f(x + h) - f(x - h)) / (2 * h)
            return (-3 * f(x) + 4 * f(x + h) - f(x + 2 * h)) / (2 * h)

        gn = derivative(lambda x: mp_dolp(x, k, t), n)
        gk = derivative(lambda x: mp_dolp(n, x, t), k)
        return float(P), np.array([float(gn), float(gk)])


HUGE = [1e41 + 0j, 3e43 - 1e43j, 1e45 - 3e44j, 7e47 - 7e47j, 9e49 - 4e49j, -1e50j, 1e50 + 0j]
TINY = [1e-12 + 0j, 1e-20 + 0j, 1e-20 - 3e-20j, 2e-30 - 1e-31j, -1e-40j, 1e-50 + 0j]
ORDINARY = [3.23 - 4.35j, 1.5 + 0j, 1e6 - 2e5j, 0.3 - 1e-3j]
ANGLES = [1e-30, 1e-9, 0.2, 0.9, 1.4, np.pi / 2 - 1e-9]


@pytest.mark.parametrize("eta", HUGE + TINY + ORDINARY)
def test_smooth_dolp_and_its_gradient_match_a_300_digit_reference(eta):
    theta = np.array(ANGLES)
    P, g = fresnel.smooth_dolp(eta, np.cos(theta), np.sin(theta) ** 2, gradient=True)
    assert P.shape == theta.shape and g.shape == theta.shape + (2,)
    assert np.all(np.isfinite(P)) and np.all(np.isfinite(g))
    for k, t in enumerate(theta):
        P_ref, g_ref = mp_dolp_and_gradient(eta, t)
        # relative accuracy, even where the DOLP is 1e-100 (|eta| = 1e50) or 1e-120 (|eta| = 1e-50)
        assert P[k] == pytest.approx(P_ref, rel=1e-12, abs=1e-300), (eta, t)
        scale = max(np.max(np.abs(g_ref)), 1e-300)
        np.testing.assert_allclose(g[k], g_ref, rtol=0, atol=1e-11 * scale, err_msg=f"{eta} {t}")


@pytest.mark.parametrize("eta", [1e41, 1e45 - 3e44j, 1e50 + 0j, -1e50j])
@pytest.mark.parametrize("c", [1.0, 0.99, 0.5, 1e-3, 0.0])
def test_fuzz_reproducer_huge_index_gradient_is_finite(eta, c):
    P, g = fresnel.smooth_dolp(eta, c, gradient=True)
    assert np.isfinite(P) and np.all(np.isfinite(g))
    assert 0 <= P <= 1


@pytest.mark.parametrize(
    "eta", [1e-50, 1e-30, 1e-20, 1e-12, 1e-20 - 1e-20j, -1e-30j, 1.5, 3.23 - 4.35j, 1e41, 1e50]
)
def test_dolp_and_its_gradient_vanish_at_normal_incidence(eta):
    """R_s = R_p at theta = 0 for every eta (Eq. 45: rp = -rs), so the DOLP is identically 0 there
    and so is its gradient (it was -2e20 at eta = 1e-20)."""
    P, g = fresnel.smooth_dolp(eta, 1.0, gradient=True)
    assert P == 0
    np.testing.assert_array_equal(g, [0.0, 0.0])


@pytest.mark.parametrize("eta", [1e-50, 1e-30, 1e-20, 1e-12, 1e-20 - 3e-20j, -1e-30j, 0.5, 2 - 1j])
def test_reduced_derivatives_at_normal_incidence_are_the_analytic_limit(eta):
    """At theta = 0: u = eta, rs' = 1/(1 + eta)^2, rp' = -1/(1 + eta)^2, so
    drs'/deta = -2/(1 + eta)^3 and drp'/deta = +2/(1 + eta)^3 (-> -2, +2 as eta -> 0)."""
    red = fresnel.reduced_coefficients(eta, 1.0, 0.0, derivative=True)
    assert red.rs == pytest.approx(1 / (1 + eta) ** 2, rel=1e-14)
    assert red.rp == pytest.approx(-1 / (1 + eta) ** 2, rel=1e-14)
    assert red.drs == pytest.approx(-2 / (1 + eta) ** 3, rel=1e-14)
    assert red.drp == pytest.approx(2 / (1 + eta) ** 3, rel=1e-14)


def mp_reduced_derivatives(eta, theta):
    """d/deta of r/(1 - eta^2), r from Eq. 45 as printed, by central differences (the reduced
    coefficients are holomorphic in eta, so any direction of the step will do) at 300 digits."""
    with mpmath.workdps(DPS):
        e0, t = mpmath.mpc(eta.real, eta.imag), mpmath.mpf(theta)
        c, s = mpmath.cos(t), mpmath.sin(t)

        def reduced(e):
            u = mpmath.sqrt(e**2 - s**2)
            if mpmath.re(u) < 0 or (mpmath.re(u) == 0 and mpmath.im(u) > 0):
                u = -u
            f = 1 - e**2
            return (c - u) / (c + u) / f, (e**2 * c - u) / (e**2 * c + u) / f

        # step along the imaginary axis where kappa > 0 (a real step would leave n >= 0 at n = 0)
        h = mpmath.mpf(10) ** -100 * abs(e0) * (1j if eta.imag < 0 else 1)
        up, dn = reduced(e0 + h), reduced(e0 - h)
        return [complex((a - b) / (2 * h)) for a, b in zip(up, dn)]


@pytest.mark.parametrize("eta", TINY[:5] + [3.23 - 4.35j, 1.5 + 0j, 1e6 - 2e5j, 2e40 - 1e40j])
@pytest.mark.parametrize("theta", [0.0, 1e-9, 0.3, 1.2])
def test_reduced_derivatives_match_a_300_digit_reference(eta, theta):
    red = fresnel.reduced_coefficients(eta, np.cos(theta), np.sin(theta) ** 2, derivative=True)
    drs_ref, drp_ref = mp_reduced_derivatives(complex(eta), theta)
    assert abs(red.drs - drs_ref) <= 1e-12 * abs(drs_ref), (eta, theta)
    assert abs(red.drp - drp_ref) <= 1e-12 * abs(drp_ref), (eta, theta)
