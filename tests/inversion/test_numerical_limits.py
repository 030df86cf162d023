"""Fuzz defects at the limits of the inversion's inputs, checked against independent truths (the
printed Eq. 115 in 1000-digit arithmetic, its analytic large-index limit, the definition of the
Laplace covariance), with every warning an error:

* ``fit_dolp(zeros(4), zeros(4), zeros(4))``, a noise-free perfect fit at normal incidence where
  the DOLP is 0 for every parameter, gave NaN covariances and a RuntimeWarning (``0 * inf``) from
  the residual variance ``s^2 = 0``;
* ``thilak_dop(1e300, 0, 0.5)`` overflowed to NaN although Eq. 115 is defined for any real
  ``(n, kappa)``.
"""

import warnings

import mpmath
import numpy as np
import pytest

from scatterlab.inversion import IdentifiabilityWarning, fit_dolp
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.least_squares import _laplace_covariance
from scatterlab.inversion.thilak import thilak_dop


@pytest.fixture(autouse=True)
def _strict():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        yield


# -- fit_dolp at an exact fit ------------------------------------------------------------------
@pytest.mark.parametrize("kw", [{}, {"sigma": 0.2}, {"phi": 0.0}, {"sigma": 0.2, "phi": 0.0}])
def test_an_exact_fit_of_undetermined_parameters_reports_infinite_variances(kw):
    """At normal incidence R_s = R_p for every index: the DOLP is 0 whatever (n, kappa, sigma), so
    no parameter is determined: each variance is inf (NaN covariances), not NaN, although the
    residual variance estimate is exactly 0."""
    zeros = np.zeros(4)
    fit = fit_dolp(zeros, zeros, zeros, **kw)
    P = 2 if "sigma" in kw else 3
    assert fit.cost == 0
    assert not np.any(fit.identifiable)
    np.testing.assert_array_equal(np.diagonal(fit.covariance), np.full(P, np.inf))
    off = ~np.eye(P, dtype=bool)
    assert np.all(np.isnan(fit.covariance[off]))
    np.testing.assert_array_equal(fit.errors, np.full(P, np.inf))


def test_an_exact_fit_gives_determined_parameters_zero_and_undetermined_infinite_variance():
    """Laplace covariance s^2 (J^T J)^+ with s^2 = 2 cost / (M - P) = 0: a determined parameter
    has variance exactly 0. A lossless dielectric (kappa = 0, n = 1.5 > sin of every angle) has
    real Fresnel coefficients, so the DOLP is stationary in kappa: kappa's variance is inf."""
    ti = np.radians(np.r_[30.0, 40, 50, 60])
    forward = DolpForward(ti, ti, sigma=np.array([0.3]))
    cov, identifiable = _laplace_covariance(
        forward, np.array([[1.5, 0.0]]), np.ones((1, 4), bool), np.array([0.0]), None
    )
    np.testing.assert_array_equal(identifiable, [[True, False]])
    assert cov[0, 0, 0] == 0
    assert cov[0, 1, 1] == np.inf
    assert np.isnan(cov[0, 0, 1]) and np.isnan(cov[0, 1, 0])


# -- thilak_dop beyond the kernel's |eta| range ------------------------------------------------
def mp_eq115(n, kappa, beta):
    """Eq. 115 as printed with the errata's A and B, at 1000 digits (enough for the cancellation of
    sqrt(C) -/+ D at |eta| = 1e308)."""
    with mpmath.workdps(1000):
        n, k, b = mpmath.mpf(n), mpmath.mpf(kappa), mpmath.mpf(beta)
        c, s2 = mpmath.cos(b), mpmath.sin(b) ** 2
        D = n**2 - k**2 - s2
        C = 4 * n**2 * k**2 + D**2
        A = mpmath.sqrt((mpmath.sqrt(C) + D) / 2)
        B = mpmath.sqrt((mpmath.sqrt(C) - D) / 2)
        return float(2 * A * s2 * c / (A**2 * c**2 + s2**2 + B**2 * c**2))


INDICES = [
    (9.9e48, 0.0),  # just below the switch to the large-index form, and just above
    (1.01e49, 0.0),
    (3e49, 1e49),
    (1e60, 2.0),
    (1e300, 0.0),
    (-1e300, 0.5),  # any sign: Eq. 115 depends on n^2 and kappa^2
    (1e300, 1e300),
    (3.0, 1e300),
    (0.0, 1e300),
    (1.7e308, 0.0),
    (1.7e308, 1.7e308),
]
BETAS = [0.0, 1e-20, 0.5, 1.2, np.pi / 2 - 1e-12, np.pi / 2, 2.0, np.pi]


@pytest.mark.parametrize("n, kappa", INDICES)
def test_thilak_dop_at_huge_indices_is_the_printed_formula(n, kappa):
    got = thilak_dop(n, kappa, np.array(BETAS))
    assert np.all(np.isfinite(got))
    for value, beta in zip(got, BETAS):
        assert value == pytest.approx(mp_eq115(n, kappa, beta), rel=1e-13, abs=1e-305), beta


@pytest.mark.parametrize("n", [1e50, 1e100, 1e300, 1.7e308])
@pytest.mark.parametrize("beta", [0.3, 0.8, 1.3])
def test_thilak_dop_large_index_limit(n, beta):
    """|eta| -> inf (kappa = 0): A -> n, A^2 + B^2 -> n^2, so P -> 2 sin^2(b) / (n cos(b)),
    with relative error O(1/n^2)."""
    c, s2 = np.cos(beta), np.sin(beta) ** 2
    assert thilak_dop(n, 0.0, beta) == pytest.approx(2 * s2 / c / n, rel=1e-14)


def test_thilak_dop_fuzz_reproducer():
    """thilak_dop(1e300, 0, 0.5) was NaN (overflow); the limit is 2 sin^2(0.5)/(1e300 cos(0.5))."""
    got = thilak_dop(1e300, 0.0, 0.5)
    assert np.isfinite(got)
    assert got == pytest.approx(2 * np.sin(0.5) ** 2 / np.cos(0.5) / 1e300, rel=1e-14)
