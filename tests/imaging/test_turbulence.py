"""Turbulence: spectra and screens against independent truths (closed forms, quadrature of the spectrum)."""

import contextlib
import warnings

import numpy as np
import pytest

from scatterlab.imaging import turbulence as T


def test_structure_constant_and_spectrum_constant():
    assert T.STRUCTURE_CONSTANT == pytest.approx(6.88, abs=0.005)
    assert T.PSD_CONSTANT == pytest.approx(0.0229, abs=1e-4)  # Eq. 79
    r = np.array([1e-3, 0.05, 0.3, 3.0])
    np.testing.assert_allclose(
        T.structure_function_theory(r, 0.1), T.STRUCTURE_CONSTANT * (r / 0.1) ** (5 / 3), rtol=1e-5
    )


def test_von_karman_variance_closed_form():
    """2 pi int 0.0229 r0^-5/3 (f^2 + f0^2)^-11/6 f df = 0.0229 pi (6/5) (L0/r0)^(5/3)."""
    for L0 in (0.5, 2.0, 20.0):
        closed = T.PSD_CONSTANT * np.pi * 6 / 5 * (L0 / 0.1) ** (5 / 3)
        assert T.phase_variance_theory(0.1, L0) == pytest.approx(closed, rel=1e-8)
    with pytest.raises(ValueError, match="infinite"):
        T.phase_variance_theory(0.1, np.inf)


def test_von_karman_screens_match_theory_within_5_percent():
    """L0 = 1 m on a 2.56 m screen: structure function (2 px to D/2) and variance within 5 % of the
    quadrature of the spectrum; 150 screens give ~2 % statistical error at D/2."""
    rng = np.random.default_rng(7)
    n, dx, r0, L0 = 256, 0.01, 0.1, 1.0
    screens = np.stack([T.phase_screen(n, dx, r0, rng, L0=L0) for _ in range(150)])
    r, D = T.structure_function(screens, n // 2)
    theory = T.structure_function_theory(r[1:] * dx, r0, L0)
    np.testing.assert_allclose(D[1:], theory, rtol=0.05)
    assert np.var(screens) == pytest.approx(T.phase_variance_theory(r0, L0), rel=0.05)


@pytest.mark.slow
def test_kolmogorov_screens_match_6_88_within_5_percent_from_2px_to_half_width():
    """3000 screens of 64 px: the structure function is within 5 % of 6.88 (r/r0)^(5/3) for 2 px <= r <= D/2,
    up to three standard errors of the mean, estimated from 30 batch means of the screens themselves."""
    rng = np.random.default_rng(9)
    n, dx, r0 = 64, 0.01, 0.1
    screens = np.stack([T.phase_screen(n, dx, r0, rng) for _ in range(3000)])
    batches = np.array([T.structure_function(b, n // 2)[1] for b in np.split(screens, 30)])
    r = np.arange(1, n // 2 + 1)
    theory = T.STRUCTURE_CONSTANT * (r * dx / r0) ** (5 / 3)
    ratio = batches.mean(0) / theory
    se = batches.std(0, ddof=1) / np.sqrt(len(batches)) / theory
    sel = r >= 2
    assert np.all(np.abs(ratio[sel] - 1) <= 0.05 + 3 * se[sel]), (
        ratio[sel].min(),
        ratio[sel].max(),
    )
    assert np.all(se[sel] < 0.02)  # the test has the power to see a 5 % error


def test_subharmonics_remove_the_low_frequency_deficit():
    rng = np.random.default_rng(8)
    n, dx, r0 = 128, 0.01, 0.1
    ratio = {}
    for sh in (False, True):
        s = np.stack([T.phase_screen(n, dx, r0, rng, subharmonics=sh) for _ in range(300)])
        r, D = T.structure_function(s, n // 4)
        ratio[sh] = D[-1] / (T.STRUCTURE_CONSTANT * (r[-1] * dx / r0) ** (5 / 3))
    assert ratio[False] < 0.45 and ratio[True] > 0.85  # at D/4: about 0.33 without, 0.98 with


def test_fried_parameter_and_rytov_variance():
    lam, L, cn2 = 1.55e-6, 2000.0, 1e-15
    k = 2 * np.pi / lam
    r0 = T.fried_parameter(cn2, L, lam)
    assert r0 == pytest.approx((0.423 * k**2 * cn2 * L) ** (-3 / 5))  # Eq. 75
    assert T.fried_parameter(lambda z: cn2, L, lam) == pytest.approx(
        r0, rel=1e-10
    )  # Eq. 74, profile
    # Eq. 80 for constant Cn2 (1.23 Cn2 k^7/6 L^11/6) and Eq. 81 from r0 are the same number
    s2 = T.rytov_variance(cn2, L, lam)
    assert s2 == pytest.approx(1.2272727 * cn2 * k ** (7 / 6) * L ** (11 / 6), rel=1e-6)
    # Eq. 81's 2.91 is 1.2273 / 0.423 = 2.9014 rounded: the two agree to 0.3 %
    assert T.rytov_variance_from_r0(r0, L, lam) == pytest.approx(
        s2 * 2.91 / (1.2272727 / 0.423), rel=1e-6
    )
    with pytest.warns(RuntimeWarning, match="Rytov"):
        T.rytov_variance(1e-13, 5000.0, 0.5e-6)


def test_reproducible_and_sliding_screen():
    a = T.phase_screen(64, 0.01, 0.1, rng=3)
    b = T.phase_screen(64, 0.01, 0.1, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    wheel = T.SlidingScreen(32, 0.01, 0.1, rng=4, length=128)
    np.testing.assert_allclose(
        wheel.window(6)[:, :-1], wheel.window(5)[:, 1:], atol=1e-12
    )  # frozen flow
    np.testing.assert_allclose(wheel.window(130), wheel.window(2), atol=1e-12)  # periodic wheel
    np.testing.assert_allclose(wheel.window(5.0), wheel.window(5.5 - 0.5), atol=1e-12)
    half = wheel.window(5.5)
    assert np.all(np.isfinite(half)) and half.shape == (32, 32)


def test_piston_tilt_removal():
    y, x = np.mgrid[0:16, 0:16]
    plane = 0.3 + 0.1 * x - 0.05 * y
    bump = np.exp(-((x - 8) ** 2 + (y - 8) ** 2) / 8.0)
    out = T.remove_piston_tilt(plane + bump)
    expected = T.remove_piston_tilt(bump)
    np.testing.assert_allclose(out, expected, atol=1e-12)
    np.testing.assert_allclose(T.remove_piston_tilt(plane), 0, atol=1e-12)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"r0": 0.0}, "r0"),
        ({"r0": -1.0}, "r0"),
        ({"n": 2}, "n"),
        ({"dx": 0.0}, "dx"),
        ({"L0": -1.0}, "L0"),
    ],
)
def test_bad_input(kw, match):
    args = {"n": 32, "dx": 0.01, "r0": 0.1}
    args.update(kw)
    L0 = args.pop("L0", np.inf)
    with pytest.raises(ValueError, match=match):
        T.phase_screen(args["n"], args["dx"], args["r0"], rng=0, L0=L0)


@contextlib.contextmanager
def _strict():
    """Every warning an error (RuntimeWarning, ComplexWarning, scipy's IntegrationWarning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def test_structure_function_theory_at_zero_tiny_and_huge_separations():
    """D(0) = 0 (was NaN with a divide-by-zero warning); against closed forms: Kolmogorov 6.88 (r/r0)^(5/3)
    down to r = 1e-100 m, the von Karman 2 sigma^2 [1 - 2^(1/6) a^(5/6) K_5/6(a) / Gamma(5/6)],
    a = 2 pi r / L0, out to r = 1e300 m (sigma^2 = 0.0229 pi (6/5) (L0/r0)^(5/3)), and for an inner scale
    at r << l0, D = 4 pi^3 A r0^(-5/3) r^2 int f^(-2/3) exp(-(f/fm)^2) df = 2 pi^3 A r0^(-5/3) r^2 fm^(1/3)
    Gamma(1/6), fm = 5.92 / (2 pi l0)."""
    from scipy import special

    A, r0 = T.PSD_CONSTANT, 0.1  # the spectrum constant, checked against Eq. 79 above
    kolmogorov = 2 * (24 / 5 * special.gamma(6 / 5)) ** (5 / 6)  # Fried's 6.88
    with _strict():
        r = np.array([0.0, 1e-100, 1e-12, 0.01])
        np.testing.assert_array_equal(
            T.structure_function_theory([0.0, 0.0], r0, L0=10.0, l0=1e-3), 0
        )
        np.testing.assert_allclose(
            T.structure_function_theory(r, r0), kolmogorov * (r / r0) ** (5 / 3), rtol=1e-6
        )
        # von Karman: the quadrature against the closed form (cancellation spoils it below a ~ 1e-2)
        L0 = 10.0
        a = np.array([0.05, 0.3, 1.0, 3.0, 10.0, 30.0, 49.0, 51.0, 1e3, 1e100])
        rr = a * L0 / (2 * np.pi)
        sigma2 = A * np.pi * 6 / 5 * (L0 / r0) ** (5 / 3)
        closed = (
            2
            * sigma2
            * (1 - 2 ** (1 / 6) / special.gamma(5 / 6) * a ** (5 / 6) * special.kv(5 / 6, a))
        )
        np.testing.assert_allclose(T.structure_function_theory(rr, r0, L0), closed, rtol=1e-6)
        assert T.structure_function_theory(1e300, r0, L0)[0] == pytest.approx(2 * sigma2, rel=1e-12)
        # the inner-scale limit, r = 1e-3 l0 (next term ~ (pi fm r)^2: 1e-6)
        for l0 in (1e-3, 1.0, 1e4):
            fm = 5.92 / (2 * np.pi * l0)
            r = np.array([1e-5, 1e-3]) * l0
            small = 2 * np.pi**3 * A * r0 ** (-5 / 3) * r**2 * fm ** (1 / 3) * special.gamma(1 / 6)
            np.testing.assert_allclose(T.structure_function_theory(r, r0, l0=l0), small, rtol=1e-5)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: T.structure_function_theory([0.01], -0.1), "r0 must be > 0"),
        (lambda: T.structure_function_theory([0.01], 0.0), "r0 must be > 0"),
        (lambda: T.structure_function_theory([-0.01], 0.1), "r must be >= 0"),
        (lambda: T.structure_function_theory([np.nan], 0.1), "r must be finite"),
        (lambda: T.structure_function_theory([0.01], 0.1, L0=0.0), "L0"),
        (lambda: T.structure_function_theory([0.01], 0.1, l0=-1.0), "l0"),
        (lambda: T.structure_function_theory([1e300], 1e-10), "r / r0 .* too large"),
        (lambda: T.phase_variance_theory(0.1, 1e300), "L0 / r0 .* too large"),
        (lambda: T.phase_variance_theory(-0.1, 1.0), "r0 must be > 0"),
        (lambda: T.phase_psd(1.0, 1e-200), "f and 1 / L0 must not both be below .* r0 = 1e-200"),
        (lambda: T.phase_psd(1.0, -0.1), "r0 must be > 0"),
        (lambda: T.phase_psd(1.0, 0.1, l0=np.nan), "l0"),
        (lambda: T.kolmogorov_psd(1e-90, 1e-14), "kappa must be >= 5.1.e-89 rad/m"),
        (lambda: T.kolmogorov_psd(0.0, 1e-14), "kappa must be > 0"),
        (
            lambda: T.von_karman_psd(1e-90, 1e-14, L0=1e100),
            "kappa and 2 pi / L0 must not both be below",
        ),
        (lambda: T.von_karman_psd(1.0, -1e-14), "cn2 must be >= 0"),
        (
            lambda: T.phase_screen(8, 0.01, 0.1, rng=0, l0=1e160),
            r"l0 \(inner scale\) must be in \[0, 10 n dx\]",
        ),
        (lambda: T.SlidingScreen(8, 0.01, 0.1, rng=0, l0=1e3), r"l0 \(inner scale\) must be in"),
        (
            lambda: T.structure_function(np.ones((2, 8, 8)), 8),
            r"max_separation must be in \[1, 7\] pixels",
        ),
        (
            lambda: T.structure_function(np.ones((2, 8, 8)), 0),
            "max_separation must be an integer >= 1",
        ),
        (
            lambda: T.structure_function(np.ones((2, 8, 8)), -1),
            "max_separation must be an integer >= 1",
        ),
        (
            lambda: T.structure_function(np.ones((2, 8, 8)), 2.5),
            "max_separation must be an integer >= 1",
        ),
        (lambda: T.structure_function(np.full((2, 8, 8), np.nan), 3), "screens must be finite"),
        (lambda: T.remove_piston_tilt(np.full((8, 8), np.nan)), "phase must be finite"),
        (lambda: T.remove_piston_tilt(np.full((8, 8), np.inf)), "phase must be finite"),
        (lambda: T.remove_piston_tilt(np.ones(8)), r"phase must be a screen \(ny, nx\)"),
    ],
)
def test_theory_and_estimators_refuse_bad_input(call, match):
    with _strict():
        with pytest.raises(ValueError, match=match):
            call()


def test_spectra_at_extreme_frequencies_without_overflow():
    """kappa = 1e200 with an inner scale overflowed (the true value is 0); kappa near the double range is
    finite and exact; zero frequency without an outer scale is the true inf. Truths: the power laws in
    Python floats, log-space where the power would overflow an intermediate."""
    with _strict():
        assert T.von_karman_psd(1e200, 1e-14, l0=1e-3)[()] == 0.0
        assert (
            T.von_karman_psd(1e200, 1e-14, L0=10.0)[()] == 0.0
        )  # 1e-733: below the smallest double
        k = np.array([1e-83, 1e-40, 1.0, 1e50])
        truth = np.exp(np.log(0.033e-14) - 11 / 3 * np.log(k))
        np.testing.assert_allclose(T.kolmogorov_psd(k, 1e-14), truth, rtol=1e-12)
        np.testing.assert_allclose(T.von_karman_psd(k, 1e-14), truth, rtol=1e-12)
        assert T.von_karman_psd(0.0, 1e-14)[()] == np.inf and T.phase_psd(0.0, 0.1)[()] == np.inf
        # the spectrum is isotropic: a signed frequency (numpy.fft.fftfreq) is its magnitude
        assert T.phase_psd(-3.0, 0.1)[()] == T.phase_psd(3.0, 0.1)[()]
        # r0 = 1e-100 overflowed r0^(-5/3) alone; the spectrum at f = 1e20 is 0.0229e(500/3 - 220/3)
        f, r0 = 1e20, 1e-100
        assert T.phase_psd(f, r0)[()] == pytest.approx(
            0.022896 * 10 ** (500 / 3 - 220 / 3), rel=1e-4
        )
        # the inner scale at its limit, 10 n dx, is a clean screen
        s = T.phase_screen(8, 0.01, 0.1, rng=0, l0=10 * 0.08)
        assert np.all(np.isfinite(s))


def test_structure_function_of_a_ramp_up_to_the_largest_separation():
    """phi = c x: D(k) = 0.5 (c^2 k^2 + 0) along the two axes, up to max_separation = n - 1."""
    x = np.arange(8.0)
    D = T.structure_function(np.tile(0.3 * x, (8, 1)), 7)[1]
    np.testing.assert_allclose(D, 0.5 * (0.3 * np.arange(1, 8)) ** 2, rtol=1e-12)


def test_sliding_screen_takes_any_finite_shift_modulo_its_length():
    """window(1e20) raised OverflowError (int(1e20) + arange). The strip is periodic: a shift is the
    same window as the shift modulo the length, also for a fractional shift far along the strip (whose
    Fourier phase lost precision before the reduction)."""
    wheel = T.SlidingScreen(16, 0.01, 0.1, rng=4, length=96, subharmonics=False)
    with _strict():
        np.testing.assert_array_equal(wheel.window(1e20), wheel.window(10**20 % 96))  # 64
        np.testing.assert_array_equal(wheel.window(-1e20), wheel.window(-(10**20) % 96))
        np.testing.assert_allclose(wheel.window(96 * 2.0**40 + 5.5), wheel.window(5.5), atol=1e-12)
        np.testing.assert_allclose(wheel.window(5.5)[:, 1:], wheel.window(6.5)[:, :-1], atol=1e-12)
        frames = wheel.frames(3, step=1.5e308)  # 2 step overflowed to inf: a ValueError
        np.testing.assert_array_equal(frames[2], wheel.window(2 * int(1.5e308) % 96))
        for call, match in (
            (lambda: wheel.window(np.inf), "shift must be finite"),
            (lambda: wheel.window([1.0, 2.0]), "shift must be a single finite number"),
            (lambda: wheel.frames(0), "count must be an integer >= 1"),
            (lambda: wheel.frames(2, np.nan), "step must be finite"),
            # int() truncated a fractional length (1.5 -> 1, then "length must be >= n" or worse)
            (
                lambda: T.SlidingScreen(16, 0.01, 0.1, rng=0, length=40.5),
                "length must be an integer",
            ),
            (
                lambda: T.SlidingScreen(16, 0.01, 0.1, rng=0, length=8),
                r"length must be an integer >= 16",
            ),
        ):
            with pytest.raises(ValueError, match=match):
                call()


def test_outer_scale_below_10_pixels_is_refused_and_10_pixels_carries_the_variance():
    """L0 = 1e-300 m gave all-zero screens. The truth tends to 0 too (sigma^2 = 0.0229 pi (6/5)
    (L0/r0)^(5/3): below the smallest double, and so is the structure function), but the screens
    carry only (L0/dx)^2 / (1.2 pi) of the variance for L0 << dx, half at 2 px: an outer scale
    below 10 px is refused, naming L0 and the range. At 10 px, 200 screens of 64 px have 0.95 of
    the variance of the quadrature (2 % statistical error) and its structure function within 12 %
    from 2 px (0.90 there)."""
    with _strict():
        assert T.phase_variance_theory(0.1, 1e-300) == 0.0
        np.testing.assert_array_equal(T.structure_function_theory([1e-3, 1.0], 0.1, 1e-300), 0)
        for L0 in (1e-300, 0.01, 0.0999):
            with pytest.raises(ValueError, match=r"L0 \(outer scale\) must be >= 10 dx = 0.1 m"):
                T.phase_screen(16, 0.01, 0.1, rng=0, L0=L0)
            with pytest.raises(ValueError, match=r"L0 \(outer scale\) must be >= 10 dx"):
                T.SlidingScreen(16, 0.01, 0.1, rng=0, L0=L0)
        rng = np.random.default_rng(11)
        n, dx, r0, L0 = 64, 0.01, 0.1, 0.1
        screens = np.stack([T.phase_screen(n, dx, r0, rng, L0=L0) for _ in range(200)])
    ratio = np.var(screens) / T.phase_variance_theory(r0, L0)
    assert 0.9 <= ratio <= 1.02, ratio
    r, D = T.structure_function(screens, n // 2)
    np.testing.assert_allclose(D[1:], T.structure_function_theory(r[1:] * dx, r0, L0), rtol=0.12)


def test_inner_scale_above_the_outer_scale_is_refused_naming_both():
    """l0 > L0 was accepted silently: the inertial range between them is empty. l0 = L0 is allowed."""
    calls = (
        lambda l0: T.phase_screen(16, 0.01, 0.1, rng=0, L0=0.5, l0=l0),
        lambda l0: T.SlidingScreen(16, 0.01, 0.1, rng=0, L0=0.5, l0=l0),
        lambda l0: T.phase_psd(1.0, 0.1, L0=0.5, l0=l0),
        lambda l0: T.von_karman_psd(1.0, 1e-14, L0=0.5, l0=l0),
        lambda l0: T.structure_function_theory([0.01], 0.1, L0=0.5, l0=l0),
        lambda l0: T.phase_variance_theory(0.1, 0.5, l0=l0),
    )
    with _strict():
        for call in calls:
            with pytest.raises(ValueError, match=r"l0 \(inner scale\) must not exceed L0 \(outer"):
                call(0.6)
            assert np.all(np.isfinite(call(0.5) if call is not calls[1] else call(0.5).strip))


def test_piston_tilt_over_collinear_masks_removes_the_tilt_along_the_line():
    """Collinear pixels determine piston and the tilt along their line only (the tilt across is constant
    there). phi = 0.3 + 0.2 x - 0.7 y + c x y: on a row y = 3 it is linear (residual 0), on the
    diagonal x = y = t it is linear + c t^2, whose least-squares residual over t = 0..7 is
    c (t^2 - 7 t + 7) (orthogonal to 1 and t: sums 140 - 196 + 56 and 784 - 980 + 196); one or two
    pixels are fitted exactly (were refused); an empty mask is refused naming it."""
    y, x = np.mgrid[0:8, 0:8]
    c = 0.01
    phase = 0.3 + 0.2 * x - 0.7 * y + c * x * y
    t = np.arange(8)
    with _strict():
        row = np.zeros((8, 8), bool)
        row[3] = True
        np.testing.assert_allclose(T.remove_piston_tilt(phase, row), 0, atol=1e-13)
        np.testing.assert_allclose(T.remove_piston_tilt(phase, row.T), 0, atol=1e-13)
        diag = np.eye(8, dtype=bool)
        out = T.remove_piston_tilt(np.stack([phase, 2 * phase]), diag)  # a stack of screens
        np.testing.assert_allclose(out[0][diag], c * (t * t - 7 * t + 7), atol=1e-13)
        np.testing.assert_allclose(out[1], 2 * out[0], atol=1e-13)
        assert np.all(out[:, ~diag] == 0)
        anti = np.fliplr(
            diag
        )  # x = 7 - t, y = t: c x y = c (7 t - t^2), residual -c (t^2 - 7 t + 7)
        np.testing.assert_allclose(
            T.remove_piston_tilt(phase, anti)[t, 7 - t], -c * (t * t - 7 * t + 7), atol=1e-13
        )
        for k in (1, 2):
            few = np.zeros((8, 8), bool)
            few[2, 1] = few[5, 6] = True
            if k == 1:
                few[5, 6] = False
            np.testing.assert_allclose(T.remove_piston_tilt(phase, few), 0, atol=1e-13)
        with pytest.raises(
            ValueError, match=r"mask must be a boolean \(8, 8\) array with at least 1"
        ):
            T.remove_piston_tilt(phase, np.zeros((8, 8), bool))
