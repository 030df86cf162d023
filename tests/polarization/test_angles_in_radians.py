"""Orientation angles are radians within a full turn either way: one beyond 2 pi (45, 90, 180) is almost
always degrees, which were read silently as radians (``linear_polarizer(45.0)`` is a polarizer at 58 deg).
Each is a ValueError naming the argument and suggesting numpy.radians, as blind_deconvolve's ``angles``."""

import numpy as np
import pytest

from scatterlab import polarization as P

S = np.array([1.0, 0.5, 0.0, 0.0])

CASES = [
    (lambda a: P.linear_polarizer(a), "angle"),
    (lambda a: P.diattenuator(1.0, 0.1, a), "angle"),
    (lambda a: P.linear_retarder(np.pi / 2, a), "fast_axis"),
    (lambda a: P.rotator(a), "rotation_angle"),
    (lambda a: P.rotate_mueller(np.eye(4), a), "angle"),
    (lambda a: P.rotation(a), "angle"),
    (lambda a: P.rotate_jones(np.eye(2), a), "angle"),
    (lambda a: P.linear_polarizer_jones(a), "angle"),
    (lambda a: P.linear_retarder_jones(np.pi / 2, a), "fast_axis"),
    (lambda a: P.rotator_jones(a), "rotation_angle"),
    (lambda a: P.linear_jones_vector(a), "angle"),
    (lambda a: P.stokes_vector(1.0, 0.5, a), "aop"),
    (lambda a: P.signed_dolp(S, a), "aop"),
]


@pytest.mark.parametrize("case, name", CASES)
@pytest.mark.parametrize("degrees", [45.0, 180.0, -90.0, np.array([0.0, 45.0, 90.0, 135.0])])
def test_angles_in_degrees_are_refused(case, name, degrees):
    with pytest.raises(ValueError, match=rf"^{name} must be .* in radians .*numpy\.radians"):
        case(degrees)


@pytest.mark.parametrize("case, name", CASES)
def test_angles_in_radians_within_a_turn_are_accepted(case, name):
    for a in (0.0, np.pi / 4, -np.pi, 2 * np.pi, np.radians([0.0, 45.0, 90.0, 135.0])):
        assert np.all(np.isfinite(case(a)))


def test_a_full_turn_either_way_is_the_same_element():
    np.testing.assert_allclose(P.linear_polarizer(2 * np.pi), P.linear_polarizer(0.0), atol=1e-15)
    np.testing.assert_allclose(P.rotation(-2 * np.pi), np.eye(2), atol=1e-15)
    assert P.signed_dolp(S, np.pi) == pytest.approx(0.5)


def test_retardance_is_not_an_orientation():
    """A multi-order wave plate has a retardance of many turns: not refused."""
    M = P.linear_retarder(2 * np.pi * 10 + np.pi / 2, 0.0)
    np.testing.assert_allclose(M, P.linear_retarder(np.pi / 2, 0.0), atol=1e-12)
