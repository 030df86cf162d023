"""H0^(2), H1^(2) of a real argument (scatterlab.mom.hankel): Hankel's expansion with an exact phase
reduction from x = 30, scipy's Cephes below; references from mpmath at 40 digits."""

import mpmath as mp
import numpy as np
import pytest
from scipy import special

from scatterlab.mom import efie, kernels
from scatterlab.mom import hankel as hk

# measured: at most 4.9e-16 of |H| from x = 30 to 1e6 (2700 log-spaced points and 800 in
# [20, 40]); scipy's Cephes loses up to x 2^-53 there (5e-13 at x = 5000)
TOL = 6e-16


def _scipy(order, x):
    if order == 0:
        return special.j0(x) - 1j * special.y0(x)
    return special.j1(x) - 1j * special.y1(x)


def _errors(order, x, h):
    """|h - H| / |H| against mpmath at 40 digits, per point."""
    with mp.workdps(40):
        out = []
        for xv, hv in zip(np.ravel(x), np.ravel(h)):
            ref = mp.hankel2(order, mp.mpf(float(xv)))
            out.append(float(abs(mp.mpc(complex(hv)) - ref) / abs(ref)))
    return np.array(out)


@pytest.mark.parametrize("order", [0, 1])
def test_against_mpmath_across_the_switch_and_at_large_x(order):
    rng = np.random.default_rng(7)
    x = np.concatenate(
        [
            np.logspace(-3, 6, 271),
            np.linspace(25.0, 35.0, 101),
            [np.nextafter(hk.SWITCH, 0), hk.SWITCH, np.nextafter(hk.SWITCH, np.inf)],
            10 ** rng.uniform(3, np.log10(hk.X_MAX), 40),
        ]
    )
    h = hk.hankel2_real(order, x)
    asym = x >= hk.SWITCH
    err = _errors(order, x[asym], h[asym])
    assert err.max() <= TOL, (x[asym][np.argmax(err)], err.max())
    # scipy itself is far off at large x: the expansion is the more accurate one there
    big = x[asym] > 1e3
    assert np.all(err[big] <= _errors(order, x[asym][big], _scipy(order, x[asym][big])))
    # below the switch-over: scipy's values, bit for bit
    np.testing.assert_array_equal(h[~asym], _scipy(order, x[~asym]))


@pytest.mark.parametrize("order", [0, 1])
def test_continuous_at_the_switch_over(order):
    a, b = np.nextafter(hk.SWITCH, 0), hk.SWITCH
    ha, hb = hk.hankel2_real(order, np.array([a, b]))
    with mp.workdps(40):
        ra, rb = mp.hankel2(order, mp.mpf(a)), mp.hankel2(order, mp.mpf(b))
        jump = float(abs((mp.mpc(complex(ha)) - mp.mpc(complex(hb))) - (ra - rb)) / abs(rb))
    # measured 7.4e-16 (order 0) and 9.4e-16 (order 1): scipy's error just below x = 30
    assert jump <= 1.2e-15


@pytest.mark.parametrize("order", [0, 1])
def test_scalar_and_array_agree(order):
    rng = np.random.default_rng(3)
    x = rng.uniform(0.5, 3000.0, (3, 2 * hk._CHUNK // 3 + 5))  # spans several chunks
    h = hk.hankel2_real(order, x)
    assert h.shape == x.shape and h.dtype == complex
    for i, j in [(0, 0), (1, 17), (2, x.shape[1] - 1), (1, hk._CHUNK // 2)]:
        s = hk.hankel2_real(order, x[i, j])
        assert np.ndim(s) == 0 and isinstance(s, np.complexfloating)
        assert s == h[i, j]
    assert hk.hankel2_real(order, float(x[0, 0])) == h[0, 0]
    assert hk.hankel2_real(order, [x[0, 0]])[0] == h[0, 0]
    assert hk.hankel2_real(order, np.empty((0, 3))).shape == (0, 3)


@pytest.mark.parametrize("order", [0, 1])
def test_zero_negative_nan_inf_and_huge_behave_as_before(order):
    special_values = [0.0, -0.0, -5.0, -100.0, np.nan, np.inf, -np.inf, 2 * hk.X_MAX, 1e300]
    with np.errstate(all="ignore"):
        for v in special_values:  # alone, as scalars
            np.testing.assert_array_equal(hk.hankel2_real(order, v), _scipy(order, v))
        # mixed with values on the expansion's path (the fix-up inside a chunk)
        x = np.array(special_values + [30.0, 100.0, 1e4])
        h = hk.hankel2_real(order, x)
        old = _scipy(order, x)
    n = len(special_values)
    np.testing.assert_array_equal(h[:n], old[:n])
    assert np.all(np.isfinite(h[n:]))


def test_phase_reduction_constants_and_coefficients():
    with mp.workdps(60):
        total = mp.mpf(hk._C1) + mp.mpf(hk._C2) + mp.mpf(hk._C3)
        assert abs(total - mp.pi / 8) < mp.mpf(2) ** -110
    # (4m + 1) C1 and (4m + 1) C2 exact for 4m + 1 < 2^23 (X_MAX): at most 30 significant bits
    for c in (hk._C1, hk._C2):
        mant, _ = np.frexp(c)
        assert float(mant * 2.0**30).is_integer()
    assert 4 * hk.X_MAX / np.pi + 2 < 2.0**23
    # A&S 9.2.9-9.2.10: P = 1 - (mu-1)(mu-9)/(2! (8x)^2) + ..., Q = (mu-1)/(8x) - ...
    p0, q0 = hk.asymptotic_coefficients(0)
    p1, q1 = hk.asymptotic_coefficients(1)
    assert (p0[:2] == [1, -9 / 128]).all() and (q0[:2] == [-1 / 8, 75 / 1024]).all()
    assert (p1[:2] == [1, 15 / 128]).all() and (q1[:1] == [3 / 8]).all()
    assert p0.size + q0.size == hk.TERMS


def test_fill_paths_use_it():
    x = np.array([0.5, 31.0, 4000.0])
    np.testing.assert_array_equal(efie._hankel2_0(x), hk.hankel2_real(0, x))
    np.testing.assert_array_equal(kernels.hankel2(1, x), hk.hankel2_real(1, x))
    with pytest.raises(ValueError, match="order"):
        hk.hankel2_real(2, x)
