import warnings

import numpy as np
import pytest

from scatterlab import polarization as P


def test_dop_dolp_aop_known_values():
    S = P.stokes_vector(2.0, 0.6, 0.3, 0.2)
    assert P.dop(S) == pytest.approx(0.6)
    assert P.dolp(S) == pytest.approx(0.6 * np.cos(0.4))
    assert P.aop(S) == pytest.approx(0.3)
    assert P.aop([1, 0, -1, 0]) == pytest.approx(-np.pi / 4)
    assert P.aop([1, -1, 0, 0]) == pytest.approx(np.pi / 2)  # range (-pi/2, pi/2]
    np.testing.assert_allclose(P.dolp(np.array([[1, 0.3, 0.4], [2, 0, 0]])), [0.5, 0.0])


def test_zero_intensity_is_nan_without_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        S = np.array([[0, 0, 0, 0], [1, 0, 0, 0], [1, 0, 0, 1]], float)
        assert np.isnan(P.dop(S)[0]) and np.isnan(P.dolp(S)[0]) and np.isnan(P.aop(S)[0])
        assert P.dop(S)[1] == 0 and np.isnan(P.aop(S)[1])  # unpolarized: AOP undefined
        assert P.dop(S)[2] == 1 and np.isnan(P.aop(S)[2])  # circular: AOP undefined


def test_is_physical_stokes():
    assert P.is_physical_stokes([1, 0.6, 0.8, 0])
    assert not P.is_physical_stokes([1, 0.7, 0.8, 0])
    assert not P.is_physical_stokes([-1, 0, 0, 0])


@pytest.mark.parametrize("scale", [1e-300, 1e-13, 1.0, 1e155, 1e300])
def test_stokes_checks_are_scale_free(scale):
    # a degree of polarization of 10 is unphysical at any scale, 0.5 physical at any scale; no overflow
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not P.is_physical_stokes(scale * np.array([0.1, 1.0, 0, 0]))
        assert P.is_physical_stokes(scale * np.array([1.0, 0.3, 0.4, 0]))
        assert P.dop(scale * np.array([1.0, 0.3, 0.4, 0])) == pytest.approx(0.5)


def test_bad_input():
    with pytest.raises(ValueError, match="S"):
        P.dop([1, 0, 0])
    with pytest.raises(ValueError, match="dop"):
        P.stokes_vector(1, 1.2)
    with pytest.raises(ValueError, match="J"):
        P.jones_to_mueller(np.ones((3, 3)))
    with pytest.raises(ValueError, match="extinction_ratio"):
        P.linear_polarizer(0, 2.0)
    with pytest.raises(ValueError, match="M"):
        P.coherency_matrix(np.full((4, 4), np.nan))


def test_one_zero_light_rule_with_a_threshold_and_a_mask():
    """dolp, aop, signed_dolp and dolp_aop share one rule: NaN where S0 <= min_intensity (no warnings);
    the mask of dolp_aop is exactly the defined pixels."""
    S = np.array([[0.0, 0, 0], [0.5, 0.2, 0.1], [2.0, 1.0, 0.0], [-1.0, 0, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d, a, valid = P.dolp_aop(S, min_intensity=0.5, mask=True)
        s = P.signed_dolp(S, min_intensity=0.5)
    np.testing.assert_array_equal(valid, [False, False, True, False])
    assert (
        np.isnan(d[[0, 1, 3]]).all()
        and np.isnan(a[[0, 1, 3]]).all()
        and np.isnan(s[[0, 1, 3]]).all()
    )
    assert d[2] == 0.5 and a[2] == 0.0 and s[2] == 0.5
    assert P.dolp(S)[1] == pytest.approx(np.hypot(0.2, 0.1) / 0.5)  # default threshold 0
    for bad in (
        -1.0,
        None,
        "x",
        np.inf,
        [0.1, 0.2],
    ):  # wrong values and types alike: ValueError by name
        for f in (P.dolp, P.aop, P.signed_dolp, P.dolp_aop):
            with pytest.raises(ValueError, match="min_intensity"):
                f(S, min_intensity=bad)
    with pytest.raises(ValueError, match=r"\(\.\.\., 4\) or \(\.\.\., 3\)"):
        P.dolp(np.ones((3, 5)))


def test_signed_dolp_is_the_projection_on_a_known_aop():
    """For light polarized at the AOP a, the signed DOLP on a equals the DOLP, on a + 90 deg its negative,
    on a + 45 deg zero (Malus); for unpolarized light with Gaussian Stokes noise it is unbiased (mean within
    4 standard errors of 0), where the DOLP has the Rician bias (mean about sqrt(pi/2) sigma)."""
    a = np.radians([-83.0, 2.0, 30.0])
    S = P.stokes_vector(1.0, 0.4, a)
    np.testing.assert_allclose(P.signed_dolp(S, a), P.dolp(S), rtol=1e-14)
    np.testing.assert_allclose(P.signed_dolp(S, a + np.pi / 2), -P.dolp(S), rtol=1e-14)
    np.testing.assert_allclose(P.signed_dolp(S, a + np.pi / 4), 0.0, atol=1e-15)
    rng = np.random.default_rng(3)
    sigma, n = 0.05, 20000
    noisy = np.stack([np.ones(n), *(sigma * rng.standard_normal((2, n)))], axis=-1)
    signed = P.signed_dolp(noisy)
    assert abs(signed.mean()) < 4 * sigma / np.sqrt(n)
    assert P.dolp(noisy).mean() == pytest.approx(np.sqrt(np.pi / 2) * sigma, rel=0.03)


def test_infinite_stokes_entries_give_nan_not_a_number_that_looks_like_a_dolp():
    """sqrt(S1^2 + S2^2) / S0 with an infinite S0 gave 0, with an infinite S1 inf: undefined, NaN."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(P.dolp([np.inf, 1.0, 0.0, 0.0])) and np.isnan(
            P.dolp([1.0, np.inf, 0.0, 0.0])
        )
        assert P.dolp([2.0, 1.0, 0.0, 0.0]) == 0.5
    with pytest.raises(ValueError, match="aop"):
        P.signed_dolp(np.array([1.0, 0.5, 0.0]), np.inf)


def test_apply_needs_a_4x4_mueller_matrix_and_a_4_stokes_vector():
    with pytest.raises(ValueError, match="M must have shape"):
        P.apply(np.eye(3), [1.0, 0.0, 0.0])
    np.testing.assert_allclose(P.apply(np.eye(4), [1.0, 0.5, 0.0, 0.0]), [1.0, 0.5, 0.0, 0.0])
