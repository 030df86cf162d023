"""Property-based tests (hypothesis) over the public physics of fresnel, polarization and pbrdf.

The extreme matrix of issue 20: theta from 0 to exactly 90 deg (and 89.99), sigma from 1e-3 to 1.5,
kappa from 0 to 1e3, n below 1, |eta| from 1e-8 to 1e6 (all phases of a passive medium), the three
shadowing functions and three diffuse terms. Asserted: finiteness, bounds (reflectances and DOLP in
[0, 1], DOLP NaN exactly where there is no light, the facet's where the lobe diverges at exact
grazing), Mueller realizability (Cloude), energy (shadowed DHR <= 1; no medium reflects more than a
perfect conductor), reciprocity of the specular term.
Examples are derandomized (fixed seed) so a failure reproduces.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scatterlab import fresnel, polarization
from scatterlab.pbrdf import PEC, Model, dolp_smooth_facet, facet_dolp

SETTINGS = settings(max_examples=150, deadline=None, derandomize=True)
PBRDF_SETTINGS = settings(max_examples=80, deadline=None, derandomize=True)
HALF_PI = np.pi / 2

polar_angles = st.one_of(
    st.just(0.0), st.just(HALF_PI), st.just(float(np.radians(89.99))), st.floats(0.0, HALF_PI)
)
azimuths = st.one_of(st.just(0.0), st.just(np.pi), st.floats(0.0, 2 * np.pi))
sigmas = st.one_of(st.just(1e-3), st.just(1.5), st.floats(np.log(1e-3), np.log(1.5)).map(np.exp))
shadowings = st.sampled_from(["torrance-sparrow", "smith", "none"])
diffuses = st.sampled_from(["hyde", "reciprocal", "none"])


@st.composite
def etas(draw):
    """n in [0, 20], kappa in {0} or [0, 1e3]; or |eta| log-uniform in [1e-8, 1e6], any passive phase."""
    if draw(st.booleans()):
        n = draw(st.floats(0.0, 20.0))
        kappa = draw(st.one_of(st.just(0.0), st.floats(0.0, 1e3)))
        if abs(complex(n, kappa)) < 1e-8:
            n = 1e-8
        return complex(n, -kappa)
    mag = 10 ** draw(st.floats(-8.0, 6.0))
    phase = draw(st.floats(-HALF_PI, 0.0))
    return complex(mag * np.cos(phase), min(mag * np.sin(phase), 0.0))


PBRDF_CASES = dict(
    eta=etas(),
    theta_i=polar_angles,
    theta_r=polar_angles,
    phi=azimuths,
    sigma=sigmas,
    shadowing=shadowings,
)


@SETTINGS
@given(eta=etas(), theta=polar_angles)
def test_fresnel_bounds_order_and_realizability(eta, theta):
    rs, rp = fresnel.coefficients(eta, theta)
    Rs, Rp = fresnel.reflectances(eta, theta)
    assert np.isfinite(rs) and np.isfinite(rp)
    assert 0 <= Rp <= 1 and 0 <= Rs <= 1
    assert (
        abs(Rs - abs(rs) ** 2) <= 1e-12 and abs(Rp - abs(rp) ** 2) <= 1e-12
    )  # not hidden by clipping
    assert Rp <= Rs * (1 + 1e-12) + 1e-15  # |r_p| <= |r_s| for every passive medium
    M = fresnel.mueller_matrix(eta, theta)
    assert np.all(np.isfinite(M)) and polarization.is_physical_mueller(M, atol=1e-9)
    d = dolp_smooth_facet(eta, theta)
    assert 0 <= d <= 1


@PBRDF_SETTINGS
@given(**PBRDF_CASES, diffuse=diffuses)
def test_pbrdf_finite_realizable_bounded(eta, theta_i, theta_r, phi, sigma, shadowing, diffuse):
    m = Model(sigma, shadowing=shadowing, diffuse=diffuse)
    F = m.mueller(eta, theta_i, theta_r, phi)
    assert np.all(np.isfinite(F)) and F[0, 0] >= 0
    if F[0, 0] > 0:
        assert polarization.is_physical_mueller(F / F[0, 0], atol=1e-9)
    d = m.dolp(eta, theta_i, theta_r, phi)
    if m.diverges(theta_i, theta_r, phi) and eta != 1:
        # the lobe diverges at exact grazing: F holds 0 for it, the DOLP is its limit, the facet's
        assert d == pytest.approx(facet_dolp(eta, theta_i, theta_r, phi), abs=1e-12)
    elif F[0, 0] > 0:
        assert 0 <= d <= 1
        assert d == pytest.approx(np.hypot(F[1, 0], F[2, 0]) / F[0, 0], abs=1e-9)
    else:
        assert np.isnan(d)
    assert 0 <= facet_dolp(eta, theta_i, theta_r, phi) <= 1
    # energy: a medium never reflects more than a perfect conductor in the same geometry
    assert F[0, 0] <= m.mueller(PEC, theta_i, theta_r, phi)[0, 0] * (1 + 1e-9)


@PBRDF_SETTINGS
@given(**PBRDF_CASES)
def test_specular_term_reciprocity(eta, theta_i, theta_r, phi, sigma, shadowing):
    """F(theta_r -> theta_i) = Q F^T Q, Q = diag(1, 1, 1, -1): includes exact backscatter (phi = 0,
    theta_i = theta_r drawn as the same endpoint) and |eta| down to 1e-8."""
    m = Model(sigma, shadowing=shadowing, diffuse="none")
    F = m.mueller(eta, theta_i, theta_r, phi)
    R = m.mueller(eta, theta_r, theta_i, phi)
    Q = np.diag([1.0, 1, 1, -1])
    np.testing.assert_allclose(R, Q @ F.T @ Q, rtol=1e-9, atol=1e-12 * max(F[0, 0], 1e-300))


@SETTINGS
@given(eta=etas(), theta=polar_angles, sigma=sigmas, shadowing=shadowings)
def test_backscatter_reciprocity_and_symmetry(eta, theta, sigma, shadowing):
    """Exact backscatter: the facet is normal to the beam, r_p = -r_s, and F = Q F^T Q itself."""
    F = Model(sigma, shadowing=shadowing, diffuse="none").mueller(eta, theta, theta, 0.0)
    Q = np.diag([1.0, 1, 1, -1])
    np.testing.assert_allclose(F, Q @ F.T @ Q, rtol=1e-9, atol=1e-12 * max(F[0, 0], 1e-300))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(theta=polar_angles, sigma=sigmas, shadowing=st.sampled_from(["torrance-sparrow", "smith"]))
def test_shadowed_dhr_is_an_albedo(theta, sigma, shadowing):
    """Energy: the specular DHR of a shadowed PEC surface is in [0, 1]; with the Hyde diffuse term,
    PEC total is exactly 1 (int D cos = 1 - rho)."""
    m = Model(sigma, shadowing=shadowing)
    rho = m.dhr_pec(theta)
    assert 0 <= rho <= 1
    assert rho + np.pi * m.diffuse_factor(theta, 0.0) == pytest.approx(1.0, abs=1e-12)
