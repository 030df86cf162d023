"""Issue 20 reproducers in the pBRDF (each kept as a test) and the shadowing strategies (issue 18)."""

import numpy as np
import pytest

from scatterlab.pbrdf import (
    PEC,
    SMITH,
    TORRANCE_SPARROW,
    Model,
    Shadowing,
    dhr_beckmann,
    dhr_table,
    shadowing_strategy,
)

ETA = 3.23 - 4.35j
HALF_PI = np.pi / 2


# ---------------------------------------------------------------- grazing directions
@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith", "none"])
def test_double_grazing_is_finite_and_batch_independent(shadowing):
    """theta_i = theta_r = 90 deg gave F00 = 1.18e32 in plane and 1.82e30 in a mixed batch. No facet
    joins two opposite horizon directions: the specular term is 0 there, on every path."""
    m = Model(0.3, shadowing=shadowing)
    alone = m.mueller(PEC, HALF_PI, HALF_PI, np.pi)
    mixed = m.mueller(PEC, [HALF_PI, 0.3], [HALF_PI, 0.4], [np.pi, 1.0])[0]
    assert np.all(np.isfinite(alone))
    np.testing.assert_array_equal(alone, mixed)
    spec = Model(0.3, shadowing=shadowing, diffuse="none").mueller(
        ETA, HALF_PI, HALF_PI, [np.pi, 0.0, 1.0]
    )
    assert np.all(spec == 0)


@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith"])
def test_single_grazing_direction_is_the_continuous_limit(shadowing):
    """With the other direction above the horizon the shadowed models have a finite limit at exactly
    90 deg: the value there continues the values at 90 deg - 1e-10 rad."""
    m = Model(0.3, shadowing=shadowing, diffuse="none")
    for ti, phi in [(0.6, np.pi), (0.6, 2.0), (1.2, 0.5)]:
        at = m.mueller(ETA, ti, HALF_PI, phi)
        near = m.mueller(ETA, ti, HALF_PI - 1e-10, phi)
        assert np.all(np.isfinite(at)) and at[0, 0] > 0
        np.testing.assert_allclose(at, near, rtol=1e-6, atol=1e-12 * near[0, 0])
        # reciprocity of the specular term also holds at grazing: F(r -> i) = Q F^T Q
        Q = np.diag([1.0, 1, 1, -1])
        np.testing.assert_allclose(
            m.mueller(ETA, HALF_PI, ti, phi), Q @ at.T @ Q, rtol=1e-12, atol=1e-14 * at[0, 0]
        )


def test_unshadowed_grazing_divergence_is_defined_as_zero():
    """Priest-Germer diverges like 1/cos(theta) at a grazing direction; the value there is 0."""
    m = Model(0.3, shadowing="none", diffuse="none")
    assert m.mueller(ETA, 0.5, HALF_PI, np.pi)[0, 0] == 0
    assert np.isfinite(m.mueller(ETA, 0.5, HALF_PI - 1e-7, np.pi)[0, 0])


def test_unshadowed_grazing_dolp_is_the_limit():
    """shadowing="none" at exactly 90 deg: F's specular term is 0 there (it diverges like 1/cos), and
    the DOLP was NaN (no diffuse term, or rho > 1 clips it) or 0 (the diffuse term's) where its limit
    is 0.627 (eta 1.5, 1 rad to 90 deg). It is the limit now, the facet's DOLP; AOP and specular
    fraction too."""
    for diffuse in ("hyde", "none"):
        m = Model(0.3, shadowing="none", diffuse=diffuse)
        for ti, tr, phi in [(1.0, HALF_PI, np.pi), (HALF_PI, 1.0, np.pi), (0.6, HALF_PI, 2.0)]:
            ti_n, tr_n = min(ti, HALF_PI - 1e-9), min(tr, HALF_PI - 1e-9)
            assert m.diverges(ti, tr, phi) and not m.diverges(ti_n, tr_n, phi)
            assert m.mueller(ETA, ti, tr, phi)[0, 0] < 1  # the convention: no specular term
            for eta in (1.5, ETA):
                at = m.dolp(eta, ti, tr, phi)
                assert np.isfinite(at) and at == pytest.approx(
                    m.dolp(eta, ti_n, tr_n, phi), abs=1e-8
                )
                assert m.aop(eta, ti, tr, phi) == pytest.approx(
                    m.aop(eta, ti_n, tr_n, phi), abs=1e-8
                )
            assert m.specular_fraction(ti, tr, phi) == 1.0
        assert m.dolp(1.5, 1.0, HALF_PI, np.pi) == pytest.approx(0.62714, abs=1e-5)
        # eta = 1: no interface, no light, NaN as everywhere (Model.dolp is the DOLP of the light)
        assert np.isnan(m.dolp(1.0, 1.0, HALF_PI, np.pi))


@pytest.mark.parametrize("shadowing", ["torrance-sparrow", "smith", "none"])
@pytest.mark.parametrize("diffuse", ["hyde", "none"])
def test_double_grazing_dolp_is_the_limit(shadowing, diffuse):
    """theta_i = theta_r = 90 deg in the specular plane: F00 grows like 1/cos^2 towards it (4.4e23 at
    90 deg - 1e-12 rad, Torrance-Sparrow) and is defined there as the diffuse term alone (2.5e-11 with
    "hyde", 0 without): the grazing convention, kept. The DOLP, NaN without a diffuse term, is its
    limit 0 (facet angle 90 deg: R_s = R_p)."""
    m = Model(0.3, shadowing=shadowing, diffuse=diffuse)
    assert m.diverges(HALF_PI, HALF_PI, np.pi)
    assert not m.diverges([HALF_PI - 1e-9, 0.3], [HALF_PI - 1e-9, 0.4], np.pi).any()
    F = m.mueller(ETA, HALF_PI, HALF_PI, np.pi)
    assert np.all(np.isfinite(F)) and (diffuse == "hyde" or F[0, 0] == 0)
    for eta in (1.5, ETA, PEC):
        assert m.dolp(eta, HALF_PI, HALF_PI, np.pi) == 0
        assert m.dolp(eta, HALF_PI - 1e-9, HALF_PI - 1e-9, np.pi) < 1e-7
    assert m.specular_fraction(HALF_PI, HALF_PI) == 1.0
    # in a batch: the same values, and no NaN
    batch = m.dolp(1.5, [HALF_PI, 1.0, HALF_PI, 0.3], [HALF_PI, HALF_PI, 1.0, 0.4], np.pi)
    assert np.all(np.isfinite(batch))
    alone = [m.dolp(1.5, a, b) for a, b in [(HALF_PI, HALF_PI), (1.0, HALF_PI), (HALF_PI, 1.0)]]
    np.testing.assert_array_equal(batch[:3], alone)


# ---------------------------------------------------------------- the unshadowed DHR table
def test_unshadowed_table_reproducer_and_energy():
    """The table for shadowing="none" was off by 3e-3 at small sigma (0.99692, quadrature: 1),
    so the Hyde diffuse term created energy (PEC total 1.0031)."""
    m = Model(1e-3, shadowing="none")
    th = np.radians(73.38)
    ref = float(dhr_beckmann(th, 1e-3, "none", n_outer=40, n_inner=40))
    assert ref == pytest.approx(1.0, abs=1e-8)
    assert m.dhr_pec(th) == pytest.approx(ref, abs=1e-6)
    total = m.dhr_pec(th) + np.pi * m.diffuse_factor(th, 0.0)  # Hyde: int D cos = (1 - rho)
    assert total <= 1 + 1e-6


@pytest.mark.parametrize("shadowing", ["none", "smith"])
def test_table_error_against_quadrature_at_random_points(shadowing):
    """Stated table error (<= 1e-6 absolute, relative where the unshadowed rho > 1) at 150 random
    points, against the quadrature with 1.5x its default nodes (an independent convergence)."""
    table = dhr_table(shadowing)
    assert table.max_error <= 2e-6
    rng = np.random.default_rng(20)
    th = rng.uniform(0, np.radians(89.5), 150)
    sg = np.exp(rng.uniform(np.log(1e-3), np.log(1.5), 150))
    nodes = int(1.5 * shadowing_strategy(shadowing).quadrature_nodes)
    ref = np.array(
        [dhr_beckmann(t, s, shadowing, n_outer=nodes, n_inner=nodes) for t, s in zip(th, sg)]
    )
    assert np.max(np.abs(table(th, sg) - ref) / np.maximum(1, ref)) <= 1e-6


def test_small_sigma_unshadowed_table_dense_sweep():
    """The failure was at small sigma between 45 and 87 deg: sweep that band densely."""
    th = np.radians(np.linspace(45, 87, 43))
    for sigma in (1e-3, 3e-3, 0.02):
        ref = dhr_beckmann(th, sigma, "none")
        np.testing.assert_allclose(dhr_table("none")(th, sigma), ref, atol=1e-6)


# ------------------------------------------------------- Smith: tabulated, every option works
def test_smith_reciprocal_works_at_construction_and_conserves_energy(hemisphere_integral):
    """Model(0.3, shadowing="smith", diffuse="reciprocal") failed on first use; now it uses the
    Smith table. Its PEC total DHR is 1 (independent cubature)."""
    m = Model(0.3, shadowing="smith", diffuse="reciprocal")
    ti = np.radians(40)
    total = hemisphere_integral(
        lambda tr, ph: m.mueller(PEC, np.full_like(tr, ti), tr, ph)[..., 0, 0]
    )
    assert total == pytest.approx(1.0, abs=3e-6)
    a, b = m.mueller(PEC, 0.3, 1.1, 1.0)[0, 0], m.mueller(PEC, 1.1, 0.3, 1.0)[0, 0]
    assert a == pytest.approx(b, rel=1e-12)


def test_smith_dhr_reads_the_table():
    m = Model(0.3, shadowing="smith")
    th = np.radians([10, 50, 85])
    np.testing.assert_allclose(m.dhr_pec(th), dhr_beckmann(th, 0.3, "smith"), atol=1e-6)
    arr = Model(np.array([0.05, 0.3, 0.9]), shadowing="smith").dhr_pec(np.radians(60))
    np.testing.assert_allclose(
        arr, [dhr_beckmann(np.radians(60), s, "smith") for s in (0.05, 0.3, 0.9)], atol=1e-6
    )


def test_unavailable_combination_fails_at_construction():
    from scatterlab.pbrdf import HyperCauchy

    with pytest.raises(ValueError, match="Smith"):
        Model(distribution=HyperCauchy(0.3, 3.0), shadowing="smith")
    cauchy = Model(distribution=HyperCauchy(0.3, 2.0), diffuse="reciprocal")  # works now
    assert 0 < cauchy.mueller(PEC, 0.4, 0.5, 2.0)[0, 0]


# ---------------------------------------------------------------- DOLP of zero light
def test_dolp_of_zero_light_is_nan():
    """Model.dolp was 0.83 where F00 = 0 and 0.634 at eta = 1; the convention is NaN."""
    m = Model(1e-3, diffuse="none")
    F = m.mueller(1.5, 0.3, 1.2, np.pi)
    assert F[0, 0] == 0
    assert np.isnan(m.dolp(1.5, 0.3, 1.2))
    assert np.isnan(m.aop(1.5, 0.3, 1.2, 2.0))
    assert np.isnan(Model(0.3).dolp(1.0, 0.5, 0.5))
    assert Model(1e-3).dolp(1.5, 0.3, 1.2) == 0  # a diffuse term: light, unpolarized


# ---------------------------------------------------------------- strategies
def test_strategy_objects_and_names_are_interchangeable():
    ti, tr, phi = np.radians([20, 50, 80]), np.radians([30, 45, 85]), np.array([np.pi, 2.0, 0.7])
    for name, obj in [("torrance-sparrow", TORRANCE_SPARROW), ("smith", SMITH)]:
        np.testing.assert_array_equal(
            Model(0.3, shadowing=name).mueller(ETA, ti, tr, phi),
            Model(0.3, shadowing=obj).mueller(ETA, ti, tr, phi),
        )
    assert shadowing_strategy("smith") is SMITH
    with pytest.raises(ValueError, match="shadowing"):
        shadowing_strategy("blinn")


def test_a_user_shadowing_function_plugs_into_model_and_dhr():
    """A new Shadowing (G = 1/2, a toy) works in the pBRDF and the DHR quadrature alike."""
    half = Shadowing(
        "half",
        g_over_cos=lambda geo, slopes: 0.5 / (geo.cos_theta_i * geo.cos_theta_r),
        slope_integrand=lambda m, rz, c, s, slopes: 0.5 * m / c,
        conserves_energy=True,
        quadrature_nodes=24,
    )
    ti, tr = np.radians([20, 40]), np.radians([30, 60])
    F_half = Model(0.3, shadowing=half, diffuse="none").mueller(ETA, ti, tr, 2.0)
    F_none = Model(0.3, shadowing="none", diffuse="none").mueller(ETA, ti, tr, 2.0)
    np.testing.assert_allclose(F_half, 0.5 * F_none, rtol=1e-14)
    np.testing.assert_allclose(
        dhr_beckmann(ti, 0.3, half), 0.5 * dhr_beckmann(ti, 0.3, "none"), rtol=1e-12
    )


@pytest.mark.parametrize("eta", [-2.207e-8j, 1e-6 - 1e-6j, 5e-5 + 0j])
def test_tiny_index_reciprocity_at_exact_backscatter(eta):
    """|eta| < 1e-4 broke reciprocity at exact backscatter (sin^2(beta) from 1 - cos^2 was 2e-16,
    comparable to eta^2): F = Q F^T Q there, and r_p = -r_s makes F00 = F11 = -F22 = -F33."""
    m = Model(0.3, diffuse="none")
    th = np.radians([0.0, 20.0, 60.0, 89.0])
    F = m.mueller(eta, th, th, 0.0)
    Q = np.diag([1.0, 1, 1, -1])
    np.testing.assert_allclose(F, Q @ np.swapaxes(F, -1, -2) @ Q, rtol=1e-12, atol=0)
    np.testing.assert_allclose(
        np.diagonal(F, axis1=-2, axis2=-1), F[:, :1, 0] * np.array([1.0, 1, -1, -1]), rtol=1e-12
    )


def test_heavy_tailed_slopes_without_shadowing_keep_a_non_negative_dhr():
    """HyperCauchy(0.3, 1.05) without shadowing: rho * cos climbs steeply at grazing, and a cubic spline
    through the quadrature overshot to rho = -1.8e5 at 85 deg, which made the diffuse term 1.8e5 times too
    large. Independent truths: the slope-space quadrature itself, and rho >= 0 (so the diffuse factor
    (1 - rho) / pi stays within [0, 1 / pi])."""
    from scatterlab.pbrdf import HyperCauchy, Model
    from scatterlab.pbrdf.dhr import dhr_slope_quadrature

    dist = HyperCauchy(0.3, 1.05)
    m = Model(distribution=dist, shadowing="none")
    t = np.radians(np.r_[np.linspace(1, 85, 43), 88, 89, 89.5, 89.9, 89.99, 90.0])
    rho = m.dhr_pec(t)
    assert np.all(rho >= 0)
    ref = dhr_slope_quadrature(t[t <= np.radians(85)], dist, "none")
    np.testing.assert_allclose(
        rho[t <= np.radians(85)], ref, rtol=1e-2
    )  # measured: 6.3e-3 at 85 deg
    d = m.diffuse_factor(t, np.radians(30))
    assert np.all((d >= 0) & (d <= 1 / np.pi))
    # specular at 85 deg, where rho > 1 leaves no diffuse light: the facets seen are the mean surface, so
    # the DOLP is Fresnel's (Rs - Rp) / (Rs + Rp)
    from scatterlab.fresnel import reflectances

    rs, rp = reflectances(1.5, np.radians(85))
    assert m.dolp(1.5, np.radians(85), np.radians(85)) == pytest.approx(
        (rs - rp) / (rs + rp), rel=1e-9
    )


def test_hypercauchy_smith_is_finite_at_grazing():
    """HyperCauchy(nu = 2) has Smith's closed form Lambda = (sqrt(1 + b^2 tan^2) - 1)/2; (b tan)^2
    overflowed at the slope quadrature's tan ~ 1e300, and the Model with Smith shadowing failed for every
    b. Independent truths: the closed form where it is computable, and 0 <= rho <= 1."""
    import warnings

    from scatterlab.pbrdf import HyperCauchy, Model

    h = HyperCauchy(0.3)
    t = np.array([0.0, 1e-3, 1.0, 30.0])
    exact = np.expm1(np.log1p((0.3 * t) ** 2) / 2) / 2  # sqrt(1 + y^2) - 1 without cancellation
    np.testing.assert_allclose(h.smith_lambda(t), exact, rtol=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert h.smith_lambda(np.array([1e300]))[0] == pytest.approx(0.15e300)
        for b in (0.01, 0.3, 3.0):
            m = Model(distribution=HyperCauchy(b), shadowing="smith")
            F = m.mueller(1.5, 0.5, 0.5, np.pi)
            rho = m.dhr_pec(np.radians([0.0, 60.0, 89.99, 90.0]))
            assert np.all(np.isfinite(F)) and F[0, 0] > 0
            assert np.all((rho >= 0) & (rho <= 1))
