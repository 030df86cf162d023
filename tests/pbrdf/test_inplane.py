"""The 1-D (in-plane) facet model against independent truths: the 1-D slope density's moments,
the smooth-surface Fresnel limit (textbook formulas written out here), the energy bound and the
flat PEC's unit DHR."""

import numpy as np
import pytest

from scatterlab.pbrdf.inplane import (
    dhr_pec_1d,
    dolp_1d,
    inplane_coefficients,
    shadowing_1d,
    slope_pdf_1d,
    specular_lobe_1d,
)

GLASS, IRON, AL = 1.5 + 0j, 3.6 - 5.88j, 1.44 - 16j


def fresnel(eta, theta):
    """Textbook Fresnel reflectances (Born & Wolf), independent of scatterlab.fresnel."""
    c = np.cos(theta)
    u = np.sqrt(eta**2 - np.sin(theta) ** 2)
    rs = (c - u) / (c + u)
    rp = (eta**2 * c - u) / (eta**2 * c + u)
    return abs(rs) ** 2, abs(rp) ** 2


@pytest.mark.parametrize("sigma", [0.05, 0.3, 1.0])
def test_slope_pdf_normalised_with_variance_sigma2(sigma):
    s = np.linspace(-15 * sigma, 15 * sigma, 20001)
    p = slope_pdf_1d(s, sigma)
    assert np.trapezoid(p, s) == pytest.approx(1.0, abs=1e-10)
    assert np.trapezoid(p * s * s, s) == pytest.approx(sigma**2, rel=1e-8)


@pytest.mark.parametrize("eta", [GLASS, IRON, AL])
@pytest.mark.parametrize("theta", np.radians([10, 40, 70, 80]))
def test_smooth_limit_integrates_to_fresnel(eta, theta):
    """sigma -> 0: the lobe becomes a delta at the specular angle carrying R_s, R_p."""
    ts = np.linspace(-np.pi / 2, np.pi / 2, 400001)
    cs, cp = inplane_coefficients(eta, theta, ts, 1e-3, diffuse="none")
    Rs, Rp = fresnel(eta, theta)
    # error O(sigma^2) from the facet-angle spread; 1e-4 absolute at sigma = 1e-3
    assert np.trapezoid(cs, ts) == pytest.approx(Rs, abs=1e-4)
    assert np.trapezoid(cp, ts) == pytest.approx(Rp, abs=1e-4)
    d = dolp_1d(eta, theta, theta, 1e-3)
    assert d == pytest.approx((Rs - Rp) / (Rs + Rp), abs=1e-6)


def test_flat_pec_dhr_is_one_and_lobe_matches_quadrature():
    assert dhr_pec_1d(np.radians([0, 30, 60]), 1e-3) == pytest.approx(1.0, abs=1e-6)
    # dhr_pec_1d (slope-space quadrature) against a fine trapezoid over theta_s of the lobe
    ts = np.linspace(-np.pi / 2, np.pi / 2, 200001)
    for sig in (0.1, 0.4):
        for th in np.radians([10, 50, 75]):
            for sh in ("torrance-sparrow", "smith", "none"):
                ref = np.trapezoid(specular_lobe_1d(th, ts, sig, sh), ts)
                assert dhr_pec_1d(th, sig, sh) == pytest.approx(ref, abs=2e-4), (sig, th, sh)


@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith"])
def test_energy_bound(shadowing):
    """With shadowing: scattered power <= 1 for every material, angle and roughness; = 1 for a PEC
    with the diffuse term (it is defined as the PEC's missing power)."""
    ts = np.linspace(-np.pi / 2, np.pi / 2, 20001)
    for sig in (0.1, 0.3, 0.6):
        for th in np.radians([0, 30, 60, 80]):
            rho = dhr_pec_1d(th, sig, shadowing)
            assert 0 < rho <= 1
            for eta in (GLASS, IRON, AL, "pec"):
                cs, cp = inplane_coefficients(eta, th, ts, sig, shadowing=shadowing)
                assert np.all(cs >= 0) and np.all(cp >= 0)
                assert np.trapezoid(cs, ts) <= 1 + 1e-3
                assert np.trapezoid(cp, ts) <= 1 + 1e-3
            cs, _ = inplane_coefficients("pec", th, ts, sig, shadowing=shadowing)
            assert np.trapezoid(cs, ts) == pytest.approx(1.0, abs=1e-3)


def test_unshadowed_dhr_exceeds_one_towards_grazing():
    """Without shadowing the facets that would face away are simply dropped, so rho_1 > 1 near
    grazing (as the 2-D Priest-Germer model); the diffuse term is then 0, never negative."""
    assert dhr_pec_1d(np.radians(75), 0.4, "none") > 1.05
    ts = np.linspace(-np.pi / 2, np.pi / 2, 2001)
    cs, cp = inplane_coefficients(IRON, np.radians(75), ts, 0.4, shadowing="none")
    lobe_s, _ = inplane_coefficients(
        IRON, np.radians(75), ts, 0.4, shadowing="none", diffuse="none"
    )
    assert np.array_equal(cs, lobe_s)


def test_shadowing_limits_and_specular_dolp_is_the_facet_dolp():
    # V-groove masking is 1 at the specular direction for moderate angles, and falls towards
    # grazing observation
    assert shadowing_1d(np.radians(30), np.radians(30), 0.3) == 1.0
    assert shadowing_1d(np.radians(30), np.radians(89), 0.3) < 0.1
    assert shadowing_1d(0.2, 0.5, 0.3, "none") == 1.0
    # without the diffuse term the DOLP is Fresnel's at beta = (theta_i + theta_s)/2
    ti, ts = np.radians(40), np.radians(60)
    Rs, Rp = fresnel(IRON, np.radians(50))
    assert dolp_1d(IRON, ti, ts, 0.3, diffuse="none") == pytest.approx(
        (Rs - Rp) / (Rs + Rp), abs=1e-12
    )
    # the diffuse term only lowers it
    assert dolp_1d(IRON, ti, ts, 0.3) < dolp_1d(IRON, ti, ts, 0.3, diffuse="none")


def test_bad_input():
    with pytest.raises(ValueError, match="sigma"):
        slope_pdf_1d(0.1, -1)
    with pytest.raises(ValueError, match="theta_s"):
        dolp_1d(GLASS, 0.3, 2.0, 0.3)
    with pytest.raises(ValueError, match="shadowing"):
        dhr_pec_1d(0.3, 0.3, "blinn")
    with pytest.raises(ValueError, match="eta"):
        dolp_1d(1.5 + 0.1j, 0.3, 0.3, 0.3)
    with pytest.raises(ValueError, match="diffuse"):
        dolp_1d(GLASS, 0.3, 0.3, 0.3, diffuse="reciprocal")


@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith"])
@pytest.mark.parametrize("sigma", [0.05, 0.3, 1.0])
def test_dhr_at_grazing_incidence_is_the_limit_one(shadowing, sigma):
    """theta_i -> pi/2: G -> 0 but G tan(theta_i) has a finite limit on the lit facets (s < 0):
    Torrance-Sparrow G tan |s| -> 2, Smith G tan -> sqrt(2 pi)/sigma, so rho_1 -> 2 int_(-inf)^0 p_1
    = 1 and (sqrt(2 pi)/sigma) int_(-inf)^0 |s| p_1 = 1 (dhr_pec_1d's docstring). Exactly pi/2
    gives 1; the quadrature just below approaches it linearly in the distance to grazing."""
    assert dhr_pec_1d(np.pi / 2, sigma, shadowing) == 1.0
    assert np.all(dhr_pec_1d([0.3, np.pi / 2], sigma, shadowing)[1] == 1.0)
    gaps = np.radians([1e-1, 1e-2, 1e-3])
    err = 1 - dhr_pec_1d(np.pi / 2 - gaps, sigma, shadowing)
    assert np.all(err >= 0) and np.all(err < 5 * gaps)  # 89.9, 89.99, 89.999 deg: within 5 gap
    assert np.all(err[1:] <= err[:-1] / 5)  # converging, O(gap)


def test_unshadowed_dhr_at_grazing_follows_its_divergence():
    """Without shadowing rho_1 ~ 1/2 + sigma tan(theta_i)/sqrt(2 pi) (half the lit slopes plus the
    (1 - s tan) moment): the quadrature at 89.99 deg matches it, and numpy.pi/2 (6e-17 below the
    true angle) gives its finite value there, as the 2-D dhr_beckmann does."""
    from scatterlab.pbrdf import dhr_beckmann

    sigma = 0.3
    near = np.radians(89.99)
    assert dhr_pec_1d(near, sigma, "none") == pytest.approx(
        0.5 + sigma * np.tan(near) / np.sqrt(2 * np.pi), rel=1e-5
    )
    at = dhr_pec_1d(np.pi / 2, sigma, "none")
    assert np.isfinite(at)
    assert at == pytest.approx(0.5 + sigma * np.tan(np.pi / 2) / np.sqrt(2 * np.pi), rel=1e-12)
    assert at == pytest.approx(dhr_beckmann(np.pi / 2, sigma, "none"), rel=1e-6)


@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith"])
def test_coefficients_at_exactly_grazing_incidence_are_the_limit(shadowing):
    """theta_i = pi/2 exactly: the lobe is finite, a PEC's integrates to the limit 1 (dhr_pec_1d's
    docstring), the diffuse term vanishes, a metal scatters less than the PEC, and the coefficients
    join those at 89.999 deg continuously."""
    ts = np.linspace(-np.pi / 2, np.pi / 2, 400001)
    sigma = 0.3
    cs, cp = inplane_coefficients("pec", np.pi / 2, ts, sigma, shadowing=shadowing)
    assert np.all(np.isfinite(cs)) and np.all(cs >= 0)
    assert np.trapezoid(cs, ts) == pytest.approx(1.0, abs=1e-4)
    for eta in (GLASS, IRON, AL):
        ms, mp = inplane_coefficients(eta, np.pi / 2, ts, sigma, shadowing=shadowing)
        assert np.all(np.isfinite(ms)) and np.all(np.isfinite(mp))
        assert 0 < np.trapezoid(mp, ts) <= np.trapezoid(ms, ts) <= 1 + 1e-4
        near_s, _ = inplane_coefficients(eta, np.radians(89.999), ts, sigma, shadowing=shadowing)
        # O(gap) approach: 1.7e-5 rad from grazing, the L1 change is a few times that
        assert np.trapezoid(np.abs(near_s - ms), ts) < 1e-3
    d = dolp_1d(IRON, np.pi / 2, np.radians([-30.0, 0.0, 45.0]), sigma, shadowing=shadowing)
    assert np.all(np.isfinite(d)) and np.all((d >= 0) & (d <= 1))


def test_unshadowed_coefficients_refuse_exactly_grazing_incidence_by_name():
    with pytest.raises(ValueError, match="theta_i.*shadowing"):
        inplane_coefficients(IRON, np.pi / 2, 0.0, 0.3, shadowing="none")
