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
