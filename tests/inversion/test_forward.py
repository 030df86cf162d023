"""The inversion's forward model equals the pBRDF DOLP, and its Jacobian equals finite differences of it."""

import numpy as np
import pytest

from scatterlab.inversion.forward import DolpForward
from scatterlab.pbrdf import Model

TI = np.radians(np.r_[30, 40, 50, 60, 45, 45, 80])
TR = np.radians(np.r_[30, 40, 50, 60, 20, 70, 89.99])
PARAMS = np.array([[1.39, 0.34, 0.3], [1.44, 16.0, 0.2], [3.6, 5.88, 0.3], [0.6, 0.0, 0.5],
                   [1.0, 0.0, 0.3], [0.314, 3.544, 0.1], [0.52, 1e-3, 1e-3], [2.0, 1e3, 1.5]])


def pbrdf_dolp(p, phi):
    return Model(p[:, 2:3]).dolp((p[:, 0] - 1j * p[:, 1])[:, None], TI, TR, phi)


@pytest.mark.parametrize("phi", [np.pi, np.r_[np.pi, 3.0, 2.8, np.pi, 2.5, 2.0, 3.1]])
def test_value_equals_model_dolp_and_jacobian_equals_central_differences(phi):
    fwd = DolpForward(TI, TR, phi)
    v, J = fwd.value_and_jacobian(PARAMS)
    np.testing.assert_allclose(v, pbrdf_dolp(PARAMS, phi), atol=1e-14)
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
        np.testing.assert_allclose(J[rows, :, k], fd[rows], atol=2e-6 * max(1, np.abs(fd).max()), rtol=1e-5)
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
