import numpy as np
import pytest

from scatterlab.pbrdf import facet_geometry


def test_specular_plane_angles_eq112():
    ti, tr = np.radians([10, 30, 60, 80]), np.radians([50, 30, 20, 85])
    g = facet_geometry(ti, tr, np.pi)
    np.testing.assert_allclose(g.beta, (ti + tr) / 2, atol=1e-12)
    np.testing.assert_allclose(g.alpha, np.abs(ti - tr) / 2, atol=1e-12)
    np.testing.assert_allclose(g.gamma_i, 0, atol=1e-12)
    np.testing.assert_allclose(g.gamma_r, 0, atol=1e-12)


def test_rotation_cosines_eq170(rng):
    ti, tr = rng.uniform(0.1, 1.4, 50), rng.uniform(0.1, 1.4, 50)
    phi = rng.uniform(0, 2 * np.pi, 50)
    g = facet_geometry(ti, tr, phi)
    sb = np.sin(g.beta)
    np.testing.assert_allclose(
        g.cos_gi, (g.cos_alpha - np.cos(ti) * g.cos_beta) / (np.sin(ti) * sb), atol=1e-10
    )
    np.testing.assert_allclose(
        g.cos_gr, (g.cos_alpha - np.cos(tr) * g.cos_beta) / (np.sin(tr) * sb), atol=1e-10
    )
    # Eq. 167
    np.testing.assert_allclose(
        np.cos(2 * g.beta),
        np.cos(ti) * np.cos(tr) + np.sin(ti) * np.sin(tr) * np.cos(phi),
        atol=1e-12,
    )
    np.testing.assert_allclose(
        g.cos_alpha, (np.cos(ti) + np.cos(tr)) / (2 * g.cos_beta), atol=1e-12
    )


def test_limits_normal_incidence_and_backscatter_are_continuous():
    from scatterlab.pbrdf import Model

    m = Model(0.3, diffuse="none")
    eta = 1.5 - 0.2j
    for ti, tr, phi in [(0.0, 0.6, 1.0), (0.6, 0.0, 1.0), (0.5, 0.5, 0.0), (0.0, 0.0, 0.3)]:
        F0 = m.mueller(eta, ti, tr, phi)
        F1 = m.mueller(eta, ti + 1e-7, tr + 2e-7, phi + 1e-7)
        assert np.all(np.isfinite(F0))
        np.testing.assert_allclose(F0, F1, atol=1e-5 * F0[0, 0])


def test_bad_angles():
    with pytest.raises(ValueError, match="theta_i"):
        facet_geometry(-0.1, 0.2, 0.0)
    with pytest.raises(ValueError, match="theta_r"):
        facet_geometry(0.1, 1.6, 0.0)
    with pytest.raises(ValueError, match="phi"):
        facet_geometry(0.1, 0.2, np.nan)


def test_cos_and_sin_from_tangents_are_accurate_and_exact_at_quarter_turns(rng):
    """The half-angle forms behind the geometry agree with np.cos and np.sin to rounding (1e-15
    relative, also next to their zeros); the grazing snap and the multiples of pi/2 are exact."""
    from scatterlab.pbrdf.geometry import azimuth_cos_sin, polar_cos, polar_cos_sin

    near_ends = 10.0 ** -rng.uniform(1, 15, 500)
    theta = np.r_[rng.uniform(0, np.pi / 2, 2000), np.pi / 2 - near_ends, near_ends]
    c, s = polar_cos_sin(theta)
    np.testing.assert_allclose(c, np.cos(theta), rtol=1e-15, atol=0)
    np.testing.assert_allclose(s, np.sin(theta), rtol=1e-15, atol=0)
    np.testing.assert_array_equal(polar_cos(theta), c)
    assert polar_cos(np.pi / 2) == 0.0 and polar_cos_sin(0.0) == (1.0, 0.0)
    assert polar_cos_sin(np.pi / 2) == (0.0, 1.0)
    zeros = np.r_[-3, -1, 1, 3] * (np.pi / 2)
    phi = np.r_[
        rng.uniform(-2 * np.pi, 2 * np.pi, 2000),
        (zeros[:, None] + 1e-9 * rng.normal(size=50)).ravel(),
    ]
    cp, sp = azimuth_cos_sin(phi)
    np.testing.assert_allclose(cp, np.cos(phi), rtol=1e-15, atol=0)
    np.testing.assert_allclose(sp, np.sin(phi), rtol=1e-15, atol=0)
    k = np.arange(-4, 5)
    cp, sp = azimuth_cos_sin(k * (np.pi / 2))
    assert np.all(cp == [1, 0, -1, 0, 1, 0, -1, 0, 1]) and np.all(
        sp == [0, 1, 0, -1, 0, 1, 0, -1, 0]
    )
    cp, sp = azimuth_cos_sin(np.r_[20 * np.pi, 100.0])  # beyond two turns: np.cos and np.sin
    assert cp[0] == 1 and sp[0] == 0 and cp[1] == np.cos(100.0) and sp[1] == np.sin(100.0)
