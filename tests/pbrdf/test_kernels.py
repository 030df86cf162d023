"""One kernel per formula (issue 18): every facet-DOLP form of the package is a thin wrapper over
:func:`scatterlab.fresnel.smooth_dolp`, and all of them equal the textbook
``(R_s - R_p) / (R_s + R_p)`` written here from Eq. 45 directly (an independent evaluation: the
principal square root, no reduced form), to rounding."""

import numpy as np
import pytest

from scatterlab.fresnel import smooth_dolp
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.thilak import thilak_dop
from scatterlab.pbrdf import dolp_smooth_facet, dolp_thilak, facet_dolp

ETAS = [1.5 - 0.0j, 1.39 - 0.34j, 0.314 - 3.544j, 3.6 - 5.88j, 1.44 - 16j]


def textbook_dolp(eta, theta):
    """Eq. 45 as printed: r_s, r_p from eta cos(theta_t) = sqrt(eta^2 - sin^2), Re >= 0."""
    c, s2 = np.cos(theta), np.sin(theta) ** 2
    u = np.sqrt(eta * eta - s2 + 0j)
    u = np.where(u.real < 0, -u, u)
    rs = (c - u) / (c + u)
    rp = (eta * eta * c - u) / (eta * eta * c + u)
    Rs, Rp = np.abs(rs) ** 2, np.abs(rp) ** 2
    return (Rs - Rp) / (Rs + Rp)


@pytest.mark.parametrize("eta", ETAS)
def test_every_facet_dolp_form_equals_the_kernel_and_the_textbook_formula(eta):
    ti = np.radians(np.array([10.0, 30.0, 45.0, 60.0, 75.0]))
    tr = np.radians(np.array([20.0, 40.0, 45.0, 50.0, 80.0]))
    beta = (ti + tr) / 2
    truth = textbook_dolp(eta, beta)
    kernel = smooth_dolp(eta, np.cos(beta), np.sin(beta) ** 2)[0]
    np.testing.assert_allclose(kernel, truth, rtol=1e-12, atol=1e-15)
    forms = {
        "dolp_smooth_facet": dolp_smooth_facet(eta, beta),
        "dolp_thilak": dolp_thilak(eta, ti, tr),
        "facet_dolp (in plane)": facet_dolp(eta, ti, tr),
        "thilak_dop": thilak_dop(eta.real, -eta.imag, beta),
        "DolpForward.facet": DolpForward(ti, tr).facet(eta.real, -eta.imag)[0],
    }
    for name, value in forms.items():
        np.testing.assert_allclose(value, kernel, rtol=1e-12, atol=1e-15, err_msg=name)


@pytest.mark.parametrize("eta", ["pec", 1.0, 1.5 - 0.0j, 3.6 - 5.88j, 1e-8, 1e6 - 1e6j])
def test_facet_mueller_is_eq133_of_the_jones_elements(eta, rng):
    """The product form of Eq. 169's Mueller matrix equals Eq. 133 of facet_jones to rounding, in
    every block, at random and extreme geometries (normal, grazing, backscatter, specular plane),
    and 0 at eta = 1; in the facet's frame S0 and the DOLP are the same."""
    from scatterlab.pbrdf import facet_geometry, facet_jones, facet_mueller, in_plane_geometry
    from scatterlab.polarization.mueller import mueller_from_jones_elements

    edges = np.array([0, 1e-8, 0.7, np.radians(89.99), np.pi / 2])
    phis = np.array([0, 1e-9, np.pi / 2, np.pi - 1e-9, np.pi, 4.0, -2 * np.pi])
    grid = [a.ravel() for a in np.meshgrid(edges, edges, phis, indexing="ij")]
    ti, tr, phi = (np.r_[g, rng.uniform(0, s, 500)] for g, s in zip(grid, (1.57, 1.57, 6.28)))
    plane = np.r_[np.repeat(edges, edges.size), rng.uniform(0, 1.57, 100)]
    plane = (plane, np.r_[np.tile(edges, edges.size), rng.uniform(0, 1.57, 100)])
    e = eta if eta == "pec" else np.full(ti.shape, eta, complex)
    e_plane = eta if eta == "pec" else np.full(plane[0].shape, eta, complex)
    for geo, idx in ((facet_geometry(ti, tr, phi), e), (in_plane_geometry(*plane), e_plane)):
        a, b, c, d, scale = facet_jones(idx, geo)
        with np.errstate(invalid="ignore"):
            ref = mueller_from_jones_elements(a, b, c, d) * scale[..., None, None]
        ref[scale == 0] = 0.0
        size = np.abs(ref).max(axis=(-2, -1), keepdims=True)
        for rows, cols in ((4, 4), (3, 3), (3, 1), (1, 1)):
            got = facet_mueller(idx, geo, shape=(rows, cols))
            assert np.all(np.abs(got - ref[..., :rows, :cols]) <= 1e-13 * size)
        if np.isscalar(eta) and eta == 1.0:
            assert np.all(got == 0)
        col = facet_mueller(idx, geo, shape=(3, 1), facet_frame=True)[..., 0]
        assert np.all(col[..., 2] == 0)
        size = size[..., 0, 0]
        assert np.all(np.abs(col[..., 0] - ref[..., 0, 0]) <= 1e-13 * size)
        dolp = np.hypot(ref[..., 1, 0], ref[..., 2, 0])
        assert np.all(np.abs(np.abs(col[..., 1]) - dolp) <= 1e-13 * size)
