"""The pBRDF against independent truths: conservation (Eq. 175) by an independent hemisphere
cubature, limits (smooth surface Eq. 55, Priest-Germer Eq. 134), reciprocity, realizability,
mirror symmetry, fast paths against the full matrix, extreme and bad inputs."""

import warnings

import numpy as np
import pytest

from scatterlab import fresnel, polarization
from scatterlab.pbrdf import PEC, Model, dolp_thilak

ETA = 3.23 - 4.35j


@pytest.mark.parametrize("diffuse", ["hyde", "reciprocal"])
@pytest.mark.parametrize("sigma", [0.1, 0.3, 0.6])
@pytest.mark.parametrize("theta_deg", [0, 30, 60, 80])
def test_pec_full_model_conserves_energy_eq175(diffuse, sigma, theta_deg, hemisphere_integral):
    """int F00 cos(theta_r) d omega = 1 for a PEC (specular + diffuse). The specular lobe is integrated by
    adaptive cubature over outgoing directions, independently of the slope-space DHR quadrature; the
    tolerance is the table's stated error (<= 1e-6) plus the cubature's."""
    m = Model(sigma, diffuse=diffuse)
    ti = np.radians(theta_deg)
    total = hemisphere_integral(
        lambda tr, ph: m.mueller(PEC, np.full_like(tr, ti), tr, ph)[..., 0, 0]
    )
    assert total == pytest.approx(1.0, abs=2e-6)


@pytest.mark.parametrize("sigma", [0.1, 0.4])
@pytest.mark.parametrize("theta_deg", [20, 70])
def test_dhr_table_equals_independent_hemisphere_integral(sigma, theta_deg, hemisphere_integral):
    m = Model(sigma, diffuse="none")
    ti = np.radians(theta_deg)
    spec = hemisphere_integral(
        lambda tr, ph: m.mueller(PEC, np.full_like(tr, ti), tr, ph)[..., 0, 0]
    )
    assert m.dhr_pec(ti) == pytest.approx(spec, abs=1e-6)


def test_smooth_surface_limit_integrated_lobe_is_eq55(hemisphere_integral):
    """sigma -> 0: the lobe integrated over the hemisphere tends to the smooth-surface Mueller matrix
    (Eq. 55), with an O(sigma^2) depolarization from the frame rotations of tilted facets."""
    ti = np.radians(40)
    dev = []
    for sigma in (0.002, 0.001):
        m = Model(sigma, diffuse="none")
        M = hemisphere_integral(
            lambda tr, ph: m.mueller(ETA, np.full_like(tr, ti), tr, ph).reshape(-1, 16),
            full_circle=True,
            rtol=1e-9,
            atol=1e-11,
        )
        dev.append(np.max(np.abs(M.reshape(4, 4) - fresnel.mueller_matrix(ETA, ti))))
    assert dev[1] < 3e-5
    assert 3.0 < dev[0] / dev[1] < 5.0  # quadratic convergence in sigma


def test_shadowing_none_is_priest_germer_eq134():
    ti, tr, phi = np.radians([20, 45, 70]), np.radians([35, 45, 10]), np.array([np.pi, 2.0, 0.5])
    sigma = 0.25
    F = Model(sigma, shadowing="none", diffuse="none").mueller(ETA, ti, tr, phi)
    cos2b = np.cos(ti) * np.cos(tr) + np.sin(ti) * np.sin(tr) * np.cos(phi)
    cb = np.sqrt((1 + cos2b) / 2)
    ct = (np.cos(ti) + np.cos(tr)) / (2 * cb)  # Eq. 130: theta is the facet tilt
    f = (
        1
        / (2 * np.pi)
        / (4 * sigma**2)
        / ct**4
        * np.exp(-(1 / ct**2 - 1) / (2 * sigma**2))
        / (np.cos(tr) * np.cos(ti))
    )
    Rs, Rp = fresnel.reflectances(ETA, np.arccos(cb))
    np.testing.assert_allclose(F[:, 0, 0], f * (Rs + Rp) / 2, rtol=1e-12)


def test_torrance_sparrow_shadowing_only_attenuates():
    rng = np.random.default_rng(3)
    ti, tr, phi = rng.uniform(0, 1.5, 500), rng.uniform(0, 1.5, 500), rng.uniform(0, 2 * np.pi, 500)
    ts = Model(0.3, diffuse="none").mueller(ETA, ti, tr, phi)[..., 0, 0]
    pg = Model(0.3, shadowing="none", diffuse="none").mueller(ETA, ti, tr, phi)[..., 0, 0]
    assert np.all(ts <= pg * (1 + 1e-12))
    near_normal = (ti < 0.3) & (tr < 0.3)
    np.testing.assert_allclose(
        ts[near_normal], pg[near_normal], rtol=1e-12
    )  # G = 1 away from grazing


def test_specular_term_reciprocity():
    """F(theta_r -> theta_i) = Q F^T Q, Q = diag(1, 1, 1, -1), for the specular term in our bases."""
    rng = np.random.default_rng(4)
    ti, tr, phi = rng.uniform(0, 1.5, 200), rng.uniform(0, 1.5, 200), rng.uniform(0, 2 * np.pi, 200)
    m = Model(0.35, diffuse="none")
    Q = np.diag([1.0, 1, 1, -1])
    F = m.mueller(ETA, ti, tr, phi)
    R = m.mueller(ETA, tr, ti, phi)
    np.testing.assert_allclose(R, Q @ np.swapaxes(F, -1, -2) @ Q, atol=1e-13 * F[..., :1, :1].max())


def test_reciprocal_diffuse_is_reciprocal_and_hyde_is_not():
    ti, tr = np.radians(20), np.radians(70)
    for diffuse, expect in [("reciprocal", True), ("hyde", False)]:
        m = Model(0.5, diffuse=diffuse)
        a = m.mueller(PEC, ti, tr, 1.0)[0, 0]
        b = m.mueller(PEC, tr, ti, 1.0)[0, 0]
        assert np.isclose(a, b, rtol=1e-12) == expect


def test_phi_mirror_flips_exactly_the_off_diagonal_blocks():
    rng = np.random.default_rng(5)
    ti, tr, phi = rng.uniform(0, 1.5, 100), rng.uniform(0, 1.5, 100), rng.uniform(0, 2 * np.pi, 100)
    m = Model(0.3)
    S = np.diag([1.0, 1, -1, -1])
    np.testing.assert_allclose(
        m.mueller(ETA, ti, tr, 2 * np.pi - phi), S @ m.mueller(ETA, ti, tr, phi) @ S, atol=1e-14
    )


def test_realizable_mueller_matrices():
    rng = np.random.default_rng(6)
    ti, tr, phi = rng.uniform(0, 1.5, 300), rng.uniform(0, 1.5, 300), rng.uniform(0, 2 * np.pi, 300)
    for diffuse in ["none", "hyde"]:
        F = Model(0.4, diffuse=diffuse).mueller(ETA, ti, tr, phi)
        scale = np.maximum(F[..., 0, 0], 1e-300)[..., None, None]
        assert np.all(polarization.is_physical_mueller(F / scale, atol=1e-9))


def test_fast_paths_agree_with_full_matrix_to_rounding():
    m = Model(0.3, diffuse="hyde")
    ti, tr = np.radians(np.linspace(0, 89, 40)), np.radians(np.linspace(89, 0, 40))
    # one off-plane point in the batch sends the whole batch through the general path
    full = m.mueller(ETA, np.r_[ti, 0.3], np.r_[tr, 0.3], np.r_[np.full(ti.size, np.pi), 1.0])[:-1]
    fast = m.mueller(ETA, ti, tr, np.pi)
    np.testing.assert_allclose(fast, full, rtol=1e-12, atol=1e-14 * full[..., 0, 0].max())
    rng = np.random.default_rng(7)
    ti, tr, phi = rng.uniform(0, 1.5, 100), rng.uniform(0, 1.5, 100), rng.uniform(0, 2 * np.pi, 100)
    F = m.mueller(ETA, ti, tr, phi)
    scale = F[..., :1, :1]  # "to rounding": relative to the matrix's own size
    assert np.all(np.abs(m.mueller_linear(ETA, ti, tr, phi) - F[..., :3, :3]) <= 1e-13 * scale)
    # general DOLP / AOP path (first column only) against the full matrix
    dolp = np.hypot(F[..., 1, 0], F[..., 2, 0]) / F[..., 0, 0]
    np.testing.assert_allclose(m.dolp(ETA, ti, tr, phi), dolp, rtol=0, atol=1e-13)
    np.testing.assert_allclose(m.aop(ETA, ti, tr, phi), polarization.aop(F[..., :, 0]), atol=1e-12)
    # in-plane DOLP (Eq. 203) against the full matrix's F10/F00
    ti, tr = np.radians([30, 45, 60]), np.radians([30, 50, 20])
    F = m.mueller(ETA, np.r_[ti, 0.3], np.r_[tr, 0.3], np.r_[np.full(ti.size, np.pi), 1.0])[:-1]
    np.testing.assert_allclose(m.dolp(ETA, ti, tr), F[..., 1, 0] / F[..., 0, 0], rtol=1e-12)
    assert np.all(m.aop(ETA, ti, tr, np.pi) == 0)


def test_inplane_dolp_is_eq203():
    sigma = 0.3
    m = Model(sigma)
    ti, tr = np.radians([30, 45, 60, 50]), np.radians([30, 45, 60, 35])
    beta, alpha = (ti + tr) / 2, (ti - tr) / 2
    Rs, Rp = fresnel.reflectances(ETA, beta)
    G = np.minimum(
        1, np.minimum(2 * np.cos(alpha) * np.cos(tr), 2 * np.cos(alpha) * np.cos(ti)) / np.cos(beta)
    )
    gamma = (
        G
        * np.exp(-(np.tan(alpha) ** 2) / (2 * sigma**2))
        / (8 * np.pi * sigma**2 * np.cos(ti) * np.cos(tr) * np.cos(alpha) ** 4)
    )
    rho = m.dhr_pec(ti)
    expected = (Rs - Rp) / (Rs + Rp) * gamma / (gamma + (1 - rho) / np.pi)
    np.testing.assert_allclose(m.dolp(ETA, ti, tr), expected, rtol=1e-12)
    # the diffuse term lowers the DOLP below Thilak et al.'s smooth-facet value (Eq. 115)
    assert np.all(m.dolp(ETA, ti, tr) < dolp_thilak(ETA, ti, tr))
    np.testing.assert_allclose(
        Model(sigma, diffuse="none").dolp(ETA, ti, tr), dolp_thilak(ETA, ti, tr), rtol=1e-13
    )


def test_dolp_special_indices():
    m = Model(0.2)
    th = np.radians([10, 40, 70])
    assert np.all(m.dolp(PEC, th, th) == 0)  # a perfect conductor does not polarize
    near_one = m.dolp(1 + 1e-9, th, th)
    # eta = 1: no interface, no reflected light, F = 0: the DOLP of zero light is NaN (issue 20;
    # it used to return the continuous extension, 0.63). Next to it the DOLP is well defined and
    # tends to that extension, the smooth-facet formula's value at eta = 1.
    assert np.all(m.mueller(1.0, th, th, np.pi) == 0)
    assert np.all(np.isnan(m.dolp(1.0, th, th)))
    assert np.all(np.isnan(Model(0.2, diffuse="none").dolp(1.0, th, th, 2.0)))
    ratio = m.specular_fraction(th, th)
    np.testing.assert_allclose(near_one, dolp_thilak(1.0, th, th) * ratio, rtol=1e-6)
    assert np.all((near_one >= 0) & (near_one <= 1))
    big_kappa = m.dolp(0.5 - 1000j, th, th)
    assert np.all((big_kappa >= 0) & (big_kappa < 1e-3))  # kappa >> n: nearly a perfect conductor


def test_extreme_inputs_no_nan_overflow_or_negative_diffuse():
    th = np.r_[0, np.radians([1, 30, 60, 85, 89, 89.99]), np.pi / 2]
    TI, TR, PH = np.meshgrid(th, th, [0.0, 1.0, np.pi], indexing="ij")
    etas = [0.01 - 0j, 20 + 0j, 1.5 - 1e3j, 0.01 - 1e3j, 1 + 1e-12, PEC]
    grazing_incidence = TI == np.pi / 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for sigma in [1e-3, 0.05, 0.6, 1.5]:
            for shadowing in ["torrance-sparrow", "smith"]:
                m = Model(sigma, shadowing=shadowing)
                assert np.all(m._diffuse_factor(TI, TR) >= 0)
                for eta in etas:
                    F = m.mueller(eta, TI, TR, PH)
                    assert np.all(np.isfinite(F)) and np.all(F[..., 0, 0] >= 0)
                    d = m.dolp(eta, TI, TR, PH)
                    # the DOLP of zero light is NaN, and only there. No light at exactly grazing
                    # incidence (rho = 1 there, so the diffuse term vanishes, and the lobe is 0 by
                    # convention) and, at sigma = 1e-3, where the lobe underflows while rho is 1;
                    # except where the lobe diverges (both directions grazing and opposite): F holds
                    # 0 for it, the DOLP is its limit, the facet's (0 at a facet angle of 90 deg)
                    dark = (F[..., 0, 0] == 0) & ~m.diverges(TI, TR, PH)
                    if sigma >= 0.05:
                        assert np.all(dark <= grazing_incidence)
                    assert np.all(np.isnan(d[dark])) and np.all(np.isfinite(d[~dark]))
                    assert np.all((d[~dark] >= 0) & (d[~dark] <= 1))
            rho = Model(sigma).dhr_pec(th)
            assert np.all((rho >= 0) & (rho <= 1))


def test_dolp_far_from_a_smooth_lobe_does_not_depend_on_how_sigma_is_given():
    # Far from the lobe of a smooth surface both terms of F underflow. Model.dolp is then NaN (the DOLP
    # of no light) whether sigma is a scalar or an array; it was 0 for the scalar, where the DHR's
    # rounding (1 - rho = 5.6e-16) made a diffuse term out of nothing, and NaN for the array. The
    # inversion's forward model, a formula, gives the facet's DOLP there (Gamma >> D).
    from scatterlab.inversion.forward import DolpForward

    ti, tr, ph = 0.02985028, 1.15450591, -2.69686975
    for sigma in (0.01304252, np.array([0.01304252])):
        m = Model(sigma)
        assert np.all(m.mueller(1.5, ti, tr, ph)[..., 0, 0] == 0)
        assert np.all(np.isnan(m.dolp(1.5, ti, tr, ph)))
    fwd = DolpForward(np.atleast_1d(ti), np.atleast_1d(tr), ph, sigma=0.01304252)
    assert 0.49 < float(np.squeeze(fwd([1.5, 0.0]))) < 0.51


def test_array_sigma_broadcasts():
    m = Model(np.array([0.1, 0.3, 0.6])[:, None])
    d = m.dolp(ETA, np.radians([30, 45]), np.radians([30, 45]))
    assert d.shape == (3, 2)
    np.testing.assert_allclose(
        d[1], Model(0.3).dolp(ETA, np.radians([30, 45]), np.radians([30, 45]))
    )


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: Model(-0.1), "sigma"),
        (lambda: Model(0.3, shadowing="blinn"), "shadowing"),
        (lambda: Model(0.3, diffuse="lambert"), "diffuse"),
        (lambda: Model(0.3).mueller(1.5 + 0.1j, 0.3, 0.3, np.pi), "eta"),
        (lambda: Model(0.3).mueller("metal", 0.3, 0.3, np.pi), "eta"),
        (lambda: Model(0.3).dolp(1.5, 1.7, 0.3), "theta_i"),
        (lambda: Model(0.3).dolp(1.5, 0.3, np.nan), "theta_r"),
        (lambda: Model(0.3).dolp(np.ones(3), np.ones(2) * 0.3, 0.3), "shape"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_smith_dhr_quadrature_equals_independent_hemisphere_integral(hemisphere_integral):
    m = Model(0.3, shadowing="smith", diffuse="none")
    ti = np.radians(50)
    spec = hemisphere_integral(
        lambda tr, ph: m.mueller(PEC, np.full_like(tr, ti), tr, ph)[..., 0, 0]
    )
    assert m.dhr_pec(ti) == pytest.approx(spec, abs=1e-6)
    assert m.dhr_pec(ti) <= 1


def test_generalised_cauchy_distribution_in_the_model():
    """The distribution interface is real: a HyperCauchy model evaluates, its DHR (adaptive cubature)
    is <= 1 with shadowing, and for large nu with b^2 = 2 nu sigma^2 it tends to the Beckmann model."""
    from scatterlab.pbrdf import HyperCauchy

    sigma, nu = 0.3, 400.0
    hc = Model(distribution=HyperCauchy(np.sqrt(2 * nu) * sigma, nu), diffuse="none")
    bk = Model(sigma, diffuse="none")
    ti, tr = np.radians(40), np.radians([20, 40, 60])
    np.testing.assert_allclose(
        hc.mueller(ETA, ti, tr, np.pi), bk.mueller(ETA, ti, tr, np.pi), rtol=0.02
    )
    cauchy = Model(distribution=HyperCauchy(0.3, 2.0))
    rho = cauchy.dhr_pec(np.radians(30))
    assert 0 < rho <= 1
    assert np.all(np.isfinite(cauchy.dolp(ETA, ti, tr, 1.0)))


def test_array_sigma_larger_than_one_chunk_matches_scalar_models():
    """A per-pixel roughness array is sliced with the angles when evaluation is chunked.

    Scalar sigma reads rho from the 1-D cache (documented to add < 1e-8), array sigma from the 2-D table."""
    from scatterlab.pbrdf import Model
    from scatterlab.pbrdf.model import _CHUNK

    rng = np.random.default_rng(3)
    sig = rng.choice([0.1, 0.3, 0.6], size=(6000, 1))
    ti = np.radians(np.r_[20, 35, 50, 65])
    assert sig.size * ti.size > _CHUNK
    eta = 1.5 - 0.02j
    got = Model(sig).dolp(eta, ti, ti)
    F = Model(sig).mueller_linear(eta, ti, ti + 0.1, 2.0)
    for s in (0.1, 0.3, 0.6):
        sel = sig[:, 0] == s
        np.testing.assert_allclose(
            got[sel], np.broadcast_to(Model(s).dolp(eta, ti, ti), got[sel].shape), rtol=1e-8
        )
        want = Model(s).mueller_linear(eta, ti, ti + 0.1, 2.0)
        np.testing.assert_allclose(
            F[sel], np.broadcast_to(want, F[sel].shape), rtol=1e-5, atol=1e-12
        )
