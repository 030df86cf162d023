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
