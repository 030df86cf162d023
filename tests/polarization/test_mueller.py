"""Mueller/Jones/Stokes algebra against textbook matrices, the worked example of Eq. 39,
an independent (Kronecker-product) Jones-to-Mueller derivation, Malus's law and Cloude's criterion."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from scatterlab import polarization as P

# Independent derivation: S = A (E (x) E*) with S3 = 2 Im(Es* Ep); M = A (J (x) J*) A^-1.
_A = np.array([[1, 0, 0, 1], [1, 0, 0, -1], [0, 1, 1, 0], [0, 1j, -1j, 0]])


def kron_mueller(J):
    return (_A @ np.kron(J, J.conj()) @ np.linalg.inv(_A)).real


def random_jones(rng, shape=()):
    return rng.normal(size=shape + (2, 2)) + 1j * rng.normal(size=shape + (2, 2))


def test_jones_to_mueller_matches_kronecker_derivation(rng):
    for J in random_jones(rng, (20,)):
        np.testing.assert_allclose(P.jones_to_mueller(J), kron_mueller(J), atol=1e-12)


def test_jones_to_mueller_broadcasts(rng):
    J = random_jones(rng, (3, 5))
    M = P.jones_to_mueller(J)
    assert M.shape == (3, 5, 4, 4)
    np.testing.assert_allclose(M[2, 4], P.jones_to_mueller(J[2, 4]))


def test_textbook_ideal_elements():
    np.testing.assert_allclose(
        P.linear_polarizer(0),
        0.5 * np.array([[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]),
        atol=1e-15,
    )
    np.testing.assert_allclose(
        P.linear_polarizer(np.pi / 2),
        0.5 * np.array([[1, -1, 0, 0], [-1, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]),
        atol=1e-15,
    )
    np.testing.assert_allclose(
        P.linear_polarizer(np.pi / 4),
        0.5 * np.array([[1, 0, 1, 0], [0, 0, 0, 0], [1, 0, 1, 0], [0, 0, 0, 0]]),
        atol=1e-15,
    )
    # quarter-wave plate, fast axis vertical: the matrix printed in Eq. 39
    np.testing.assert_allclose(
        P.linear_retarder(np.pi / 2, np.pi / 2),
        np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, -1], [0, 0, 1, 0]]),
        atol=1e-15,
    )
    # half-wave plate at 22.5 deg turns horizontal into +45 deg
    S = P.apply(P.linear_retarder(np.pi, np.pi / 8), [1, 1, 0, 0])
    np.testing.assert_allclose(S, [1, 0, 1, 0], atol=1e-15)
    # rotator by 30 deg turns horizontal into linear at 30 deg
    S = P.apply(P.rotator(np.pi / 6), [1, 1, 0, 0])
    np.testing.assert_allclose(S, [1, np.cos(np.pi / 3), np.sin(np.pi / 3), 0], atol=1e-15)


def test_worked_example_eq39():
    """Horizontal light through an LP at 45 deg then a QWP with vertical fast axis: (1,0,0,1)/2."""
    S = P.apply(
        P.linear_retarder(np.pi / 2, np.pi / 2) @ P.linear_polarizer(np.pi / 4), [1, 1, 0, 0]
    )
    np.testing.assert_allclose(S, [0.5, 0, 0, 0.5], atol=1e-15)
    # the same through Jones vectors and Eq. 133's Stokes convention
    E = P.linear_retarder_jones(np.pi / 2, np.pi / 2) @ P.linear_polarizer_jones(np.pi / 4) @ [1, 0]
    np.testing.assert_allclose(P.jones_to_stokes(E), [0.5, 0, 0, 0.5], atol=1e-15)
    np.testing.assert_allclose(
        P.jones_to_stokes(P.circular_jones_vector("right")), [1, 0, 0, 1], atol=1e-15
    )


@pytest.mark.parametrize("angle", [0.0, 0.4, 1.1, 2.5])
def test_element_mueller_equals_converted_jones(angle):
    np.testing.assert_allclose(
        P.jones_to_mueller(P.linear_polarizer_jones(angle, 0.01)),
        P.linear_polarizer(angle, 0.01),
        atol=1e-14,
    )
    np.testing.assert_allclose(
        P.jones_to_mueller(P.linear_retarder_jones(0.9, angle)),
        P.linear_retarder(0.9, angle),
        atol=1e-14,
    )
    np.testing.assert_allclose(
        P.jones_to_mueller(P.rotator_jones(angle)), P.rotator(angle), atol=1e-14
    )


def test_malus_law():
    a = np.linspace(0, np.pi, 37)
    S = P.apply(P.linear_polarizer(a), [1, 1, 0, 0])  # horizontal light, analyser at a
    np.testing.assert_allclose(S[..., 0], np.cos(a) ** 2, atol=1e-15)
    # two polarizers on unpolarized light: (1/2) cos^2 of the angle between them
    S = P.apply(P.linear_polarizer(a) @ P.linear_polarizer(0.0), [1, 0, 0, 0])
    np.testing.assert_allclose(S[..., 0], 0.5 * np.cos(a) ** 2, atol=1e-15)


def test_non_ideal_polarizer_extinction():
    eps = 1e-3
    crossed = P.apply(
        P.linear_polarizer(np.pi / 2, eps) @ P.linear_polarizer(0, eps), [1, 0, 0, 0]
    )[0]
    aligned = P.apply(P.linear_polarizer(0, eps) @ P.linear_polarizer(0, eps), [1, 0, 0, 0])[0]
    assert crossed == pytest.approx(eps)
    assert aligned == pytest.approx(0.5 * (1 + eps**2))


def test_retarder_conserves_intensity_and_dop(rng):
    S = P.stokes_vector(
        1.0, rng.uniform(0, 1, 50), rng.uniform(-1, 1, 50), rng.uniform(-0.7, 0.7, 50)
    )
    out = P.apply(P.linear_retarder(rng.uniform(0, 6, 50), rng.uniform(0, 3, 50)), S)
    np.testing.assert_allclose(out[..., 0], S[..., 0], atol=1e-14)
    np.testing.assert_allclose(P.dop(out), P.dop(S), atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(arrays(float, (2, 2, 2, 2), elements=st.floats(-3, 3)))
def test_property_mueller_of_product_is_product_of_muellers(x):
    J1 = x[0, 0] + 1j * x[0, 1]
    J2 = x[1, 0] + 1j * x[1, 1]
    lhs = P.jones_to_mueller(J1 @ J2)
    rhs = P.jones_to_mueller(J1) @ P.jones_to_mueller(J2)
    np.testing.assert_allclose(lhs, rhs, atol=1e-10 * (1 + np.abs(rhs).max()))
    assert P.is_physical_mueller(lhs)


def test_stokes_transport_matches_jones(rng):
    J = random_jones(rng, (10,))
    E = rng.normal(size=(10, 2)) + 1j * rng.normal(size=(10, 2))
    lhs = P.jones_to_stokes(np.einsum("...ij,...j->...i", J, E))
    rhs = P.apply(P.jones_to_mueller(J), P.jones_to_stokes(E))
    np.testing.assert_allclose(lhs, rhs, atol=1e-12)


def test_coherency_of_pure_system_is_rank_one(rng):
    J = random_jones(rng)
    M = P.jones_to_mueller(J)
    lam = np.linalg.eigvalsh(P.coherency_matrix(M))
    assert lam[-1] == pytest.approx(M[0, 0])
    np.testing.assert_allclose(lam[:3], 0, atol=1e-12)
    np.testing.assert_allclose(P.mueller_from_coherency(P.coherency_matrix(M)), M, atol=1e-13)


def test_realizability_criterion():
    assert P.is_physical_mueller(P.depolarizer(0.0))
    assert P.is_physical_mueller(P.depolarizer(-1 / 3))
    assert not P.is_physical_mueller(P.depolarizer(-0.5))
    assert not P.is_physical_mueller(np.diag([1.0, -1, -1, -1]))  # the "inverter" is not realizable
    bad = np.eye(4)
    bad[0, 1] = 1.5  # diattenuation > 1
    assert not P.is_physical_mueller(bad)
    assert P.is_physical_mueller(P.linear_polarizer(0.3) @ P.linear_retarder(1.0, 0.2))


def test_nearest_physical_mueller(rng):
    M = P.linear_retarder(0.8, 0.3) @ P.diattenuator(0.9, 0.2, 0.5)
    np.testing.assert_allclose(P.nearest_physical_mueller(M), M, atol=1e-12)
    noisy = M + 0.05 * rng.normal(size=(200, 4, 4))
    fixed = P.nearest_physical_mueller(noisy)
    assert np.all(P.is_physical_mueller(fixed))
    np.testing.assert_allclose(P.nearest_physical_mueller(fixed), fixed, atol=1e-12)
    # never farther from the truth than the noisy estimate (projection onto a convex set)
    assert np.all(
        np.linalg.norm(fixed - M, axis=(-2, -1)) <= np.linalg.norm(noisy - M, axis=(-2, -1)) + 1e-12
    )


def test_jones_kernel_blocks_and_diagonal_form_equal_the_kronecker_derivation():
    """The one Jones-to-Mueller kernel against the Kronecker-product derivation: every block the
    pBRDF asks for (full, linear 3x3, first column) and the diagonal shortcut (b = c = None)."""
    from scatterlab.polarization.mueller import mueller_from_jones_elements

    rng = np.random.default_rng(12)
    J = rng.normal(size=(50, 2, 2)) + 1j * rng.normal(size=(50, 2, 2))
    ref = np.array([kron_mueller(j) for j in J])
    a, b, c, d = J[:, 0, 0], J[:, 0, 1], J[:, 1, 0], J[:, 1, 1]
    np.testing.assert_allclose(mueller_from_jones_elements(a, b, c, d), ref, atol=1e-12)
    for shape in [(3, 3), (3, 1), (1, 1)]:
        got = mueller_from_jones_elements(a, b, c, d, shape=shape)
        np.testing.assert_allclose(got, ref[:, : shape[0], : shape[1]], atol=1e-12)
    ref_d = np.array([kron_mueller(j * np.eye(2)) for j in J])
    np.testing.assert_allclose(mueller_from_jones_elements(a, None, None, d), ref_d, atol=1e-12)


def test_rotate_mueller_linear_block():
    # Malus: a horizontal polarizer rotated by a passes cos^2 a of horizontal light. The linear block
    # (3x3) rotates like the full matrix and gives the same intensities.
    a = np.radians([0.0, 20.0, 45.0, 90.0])
    M4 = P.rotate_mueller(P.linear_polarizer(0.0), a)
    M3 = P.rotate_mueller(P.linear_polarizer(0.0)[:3, :3], a)
    assert M3.shape == (4, 3, 3)
    np.testing.assert_allclose(M3, M4[..., :3, :3], atol=1e-15)
    np.testing.assert_allclose((M3 @ [1.0, 1.0, 0.0])[:, 0], np.cos(a) ** 2, atol=1e-15)


def test_rotate_mueller_refuses_other_shapes():
    with pytest.raises(ValueError, match="M must have shape"):
        P.rotate_mueller(np.eye(2), 0.1)


def test_mueller_from_coherency_refuses_other_shapes():
    with pytest.raises(ValueError, match=r"H must have shape \(\.\.\., 4, 4\)"):
        P.mueller_from_coherency(np.eye(3))
