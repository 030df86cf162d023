"""The inversion's forward model equals the pBRDF DOLP, and its Jacobian equals finite differences of it."""

import numpy as np
import pytest

from scatterlab.inversion.forward import DolpForward
from scatterlab.pbrdf import Model

TI = np.radians(np.r_[30, 40, 50, 60, 45, 45, 80])
TR = np.radians(np.r_[30, 40, 50, 60, 20, 70, 89.99])
PARAMS = np.array(
    [
        [1.39, 0.34, 0.3],
        [1.44, 16.0, 0.2],
        [3.6, 5.88, 0.3],
        [0.6, 0.0, 0.5],
        [1.0, 0.0, 0.3],
        [0.314, 3.544, 0.1],
        [0.52, 1e-3, 1e-3],
        [2.0, 1e3, 1.5],
    ]
)


def pbrdf_dolp(p, phi):
    """Model.dolp; at eta = 1 exactly no light is reflected and it is NaN, while the forward model
    is the continuous extension there (a function of the parameters): compare with the next float
    above 1."""
    eta = p[:, 0] - 1j * p[:, 1]
    eta = np.where(eta == 1, np.nextafter(1.0, 2.0), eta)
    return Model(p[:, 2:3]).dolp(eta[:, None], TI, TR, phi)


@pytest.mark.parametrize("phi", [np.pi, np.r_[np.pi, 3.0, 2.8, np.pi, 2.5, 2.0, 3.1]])
def test_value_equals_model_dolp_and_jacobian_equals_central_differences(phi):
    fwd = DolpForward(TI, TR, phi)
    v, J = fwd.value_and_jacobian(PARAMS)
    np.testing.assert_allclose(v, pbrdf_dolp(PARAMS, phi), atol=1e-12)
    for k in range(3):
        h = 1e-6 * np.maximum(PARAMS[:, k], 1e-3)
        up, dn = PARAMS.copy(), PARAMS.copy()
        up[:, k] += h
        dn[:, k] -= h
        dn[:, 1] = np.maximum(dn[:, 1], 0)  # kappa = 0 is a bound: one-sided there
        fd = (pbrdf_dolp(up, phi) - pbrdf_dolp(dn, phi)) / (up[:, k] - dn[:, k])[:, None]
        rows = slice(None)
        if k == 1 and np.ndim(phi):
            # at kappa = 0 the DOLP has a square-root edge in kappa (n < 1 beyond the critical angle, eta = 1):
            # one-sided differences with different steps differ there; the in-plane slope is analytic
            rows = PARAMS[:, 1] > 0
        np.testing.assert_allclose(
            J[rows, :, k], fd[rows], atol=2e-6 * max(1, np.abs(fd).max()), rtol=1e-5
        )
    assert np.all(np.isfinite(J))


def test_branch_point_n_equals_sin_beta_gives_a_finite_jacobian():
    """n = sin(beta), kappa = 0 (total reflection sets in): the slope in n is infinite there; ours stays finite."""
    v, J = DolpForward(TI[:1], TR[:1]).value_and_jacobian(np.array([[0.5, 0.0, 0.3]]))
    assert np.all(np.isfinite(v)) and np.all(np.isfinite(J))


def test_known_sigma_fixes_the_fraction_and_selects_rows():
    sig = np.array([0.1, 0.3, 0.6])
    fwd = DolpForward(TI, TR, sigma=sig)
    p = np.array([[1.5, 0.1], [3.0, 4.0], [1.2, 8.0]])
    want = Model(sig[:, None]).dolp((p[:, 0] - 1j * p[:, 1])[:, None], TI, TR)
    np.testing.assert_allclose(fwd(p), want, atol=1e-14)
    np.testing.assert_allclose(fwd(p[1:], rows=np.array([1, 2])), want[1:], atol=1e-14)


@pytest.mark.parametrize("phi", [np.pi, 2.7])
def test_tabulated_specular_fraction_matches_the_pbrdf(phi):
    """Gamma exact, D linear in log sigma on 8193 nodes: within 2e-5 of Model.specular_fraction for sigma
    over the whole table range, including grazing 89.99 deg (measured: 1.6e-6 in plane, 9.3e-6 out of plane)."""
    ti = np.radians(np.r_[10, 30, 45, 60, 45, 45, 80, 89.99, 60])
    tr = np.radians(np.r_[10, 30, 45, 60, 20, 70, 85, 89.99, 10])
    sig = np.exp(np.random.default_rng(0).uniform(np.log(1e-3), np.log(2.5), 5000))
    R, dR = DolpForward(ti, tr, phi).fraction(sig, gradient=True)
    want = Model(sig[:, None]).specular_fraction(ti, tr, phi)
    np.testing.assert_allclose(R, want, atol=2e-5)
    assert np.all(np.isfinite(dR))


def test_thilak_dop_wrapper_equals_the_printed_eq115():
    """thilak_dop is a thin wrapper over the package's smooth-facet DOLP kernel; the text's own form
    (Eq. 115 with the errata's A and B), written out here, is the independent reference, including
    the negative (n, kappa) and beta > 90 deg the unconstrained fit may visit."""
    from scatterlab.inversion.thilak import thilak_dop

    def eq115(n, kappa, beta):
        s, c = np.sin(beta), np.cos(beta)
        D = n * n - kappa * kappa - s * s
        C = 4 * n * n * kappa * kappa + D * D
        A = np.sqrt(np.maximum(np.sqrt(C) + D, 0) / 2)
        B = np.sqrt(np.maximum(np.sqrt(C) - D, 0) / 2)
        return 2 * A * s * s * c / (A * A * c * c + s**4 + B * B * c * c)

    rng = np.random.default_rng(15)
    n, kappa = rng.uniform(-3, 5, 400), rng.uniform(-2, 20, 400)
    beta = rng.uniform(0.01, 2.0, 400)
    np.testing.assert_allclose(
        thilak_dop(n, kappa, beta), eq115(n, kappa, beta), rtol=1e-10, atol=1e-13
    )
    np.testing.assert_allclose(thilak_dop(0.314, 3.544, 0.0), 0.0, atol=1e-15)


def test_facet_factor_out_of_plane_is_the_facet_dolp():
    """Out of the plane the facet factor is the facet's own DOLP, finite where the lobe vanishes."""
    from scatterlab.pbrdf import facet_dolp

    fwd = DolpForward(TI, TR, np.r_[np.pi, 3.0, 2.8, np.pi, 2.5, 2.0, 3.1])
    P, _ = fwd.facet(np.array([1.5]), np.array([0.1]))
    np.testing.assert_allclose(P[0], facet_dolp(1.5 - 0.1j, TI, TR, fwd.phi), rtol=1e-14)
    tiny = Model(
        1e-3, diffuse="none"
    )  # the lobe underflows off-specular: the pBRDF DOLP is NaN there
    assert np.isnan(tiny.dolp(1.5 - 0.1j, 0.3, 1.2, 2.0))
    assert np.isfinite(facet_dolp(1.5 - 0.1j, 0.3, 1.2, 2.0))
