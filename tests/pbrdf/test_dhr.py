import numpy as np
import pytest

from scatterlab.pbrdf import DHRTable, dhr_beckmann, dhr_sphere_unshadowed, dhr_table


def test_table_error_against_quadrature_at_random_points():
    """The shipped table's stated maximum error (<= 1e-6) holds at 300 random (theta_i, sigma)."""
    table = dhr_table("torrance-sparrow")
    assert table.max_error <= 1e-6
    rng = np.random.default_rng(11)
    th = rng.uniform(0, np.pi / 2, 300)
    sg = np.exp(rng.uniform(np.log(1e-3), np.log(1.5), 300))
    ref = np.array([dhr_beckmann(t, s) for t, s in zip(th, sg)])
    assert np.max(np.abs(table(th, sg) - ref)) <= 1e-6


def test_quadrature_converges_to_the_same_value():
    th = np.radians([0, 20, 45, 60, 80, 89.9])
    for sigma in [0.01, 0.3, 1.0]:
        a = dhr_beckmann(th, sigma)
        b = dhr_beckmann(th, sigma, n_outer=40, n_inner=40)
        np.testing.assert_allclose(a, b, atol=1e-9)


def test_unshadowed_hemisphere_vs_sphere_closed_form():
    """Fig. 27 integrates the Priest-Germer model over the whole sphere; the closed form is >= the
    hemisphere integral and equal to it when no facet reflects below the horizon."""
    th = np.radians([0, 10, 30, 50, 70, 85])
    for sigma in [0.02, 0.26]:
        hemi = dhr_beckmann(th, sigma, "none", n_outer=32, n_inner=32)
        sphere = dhr_sphere_unshadowed(th, sigma)
        assert np.all(sphere >= hemi - 1e-12)
    np.testing.assert_allclose(
        dhr_beckmann(th[:3], 0.02, "none"), dhr_sphere_unshadowed(th[:3], 0.02), atol=1e-12
    )
    assert dhr_sphere_unshadowed(0.0, 0.3) == pytest.approx(1.0)


def test_shadowed_dhr_never_exceeds_one_and_smooth_limit():
    th = np.linspace(0, np.pi / 2, 91)
    for sigma in [1e-3, 0.1, 0.3, 0.6, 1.5]:
        rho = dhr_table()(th, sigma)
        assert np.all(rho <= 1) and np.all(rho >= 0)
    np.testing.assert_allclose(
        dhr_table()(np.radians([0, 30, 60]), 1e-3), 1.0, atol=1e-6
    )  # sigma -> 0


def test_cosine_average_by_independent_quadrature():
    from scipy.integrate import quad

    table = dhr_table()
    for sigma in [0.05, 0.3, 0.8]:
        ref = (
            2
            * quad(
                lambda t: dhr_beckmann(t, sigma) * np.cos(t) * np.sin(t),
                0,
                np.pi / 2,
                limit=200,
                epsabs=1e-11,
            )[0]
        )
        assert table.cosine_average(sigma) == pytest.approx(ref, abs=2e-7)


def test_general_slope_quadrature_against_beckmann_specific_quadrature():
    """The distribution-agnostic DHR quadrature (used for non-Beckmann slopes) against the kink-resolving
    Beckmann quadrature: 2e-5 with shadowing at the default sizes (stated in its docstring)."""
    from scatterlab.pbrdf import Beckmann
    from scatterlab.pbrdf.model import dhr_slope_quadrature

    th = np.radians([0, 20, 45, 70, 85, 89.5])
    for sigma in (0.05, 0.3, 1.0):
        np.testing.assert_allclose(
            dhr_slope_quadrature(th, Beckmann(sigma)), dhr_beckmann(th, sigma), atol=2e-5
        )


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"n_theta": 0}, "n_theta"),
        ({"n_theta": 3}, "n_theta"),
        ({"n_sigma": 0}, "n_sigma"),
        ({"n_theta": 8.5}, "n_theta"),
        ({"n_sigma": True}, "n_sigma"),
    ],
)
def test_table_grid_sizes_are_checked(kw, name):
    """DHRTable(n_theta=0) failed with an IndexError deep in the build (n_sigma=0 in the spline): a
    bicubic table needs 4 nodes per axis."""
    with pytest.raises(ValueError, match=rf"{name} must be an integer >= 4"):
        DHRTable(cache=False, **kw)


def test_unshadowed_sphere_dhr_near_normal_incidence_is_one_without_warnings():
    """theta_i -> 0: no facet is cut off by the horizon, so the unshadowed DHR is exactly 1 (Phi(a) -> 1,
    the tan term -> 0), also where cot(theta_i)/sigma overflows its square."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert dhr_sphere_unshadowed(np.array([0.0, 1e-300, 1e-150]), 0.1) == pytest.approx(1.0)
