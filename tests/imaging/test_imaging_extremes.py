"""Extreme but allowed inputs of scatterlab.imaging give finite, correct results without a RuntimeWarning, and
malformed ones a ValueError naming the argument (the defects of a fuzz run with RuntimeWarnings as errors).

Every expected value is an analytic formula: the mean of a Poisson count, the PSF of a square pupil (a
product of Dirichlet kernels), Eqs. 74-75 and 80-81 for r0 and the Rytov variance, the limits of Fried's
MTFs, the OTF of a few points and the structure function of a single spike.
"""

import math
import warnings
from contextlib import contextmanager

import numpy as np
import pytest

from scatterlab import imaging as I


@contextmanager
def no_runtime_warning():
    """Turn any RuntimeWarning (overflow, invalid value, divide by zero) into an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        yield


# --- 1. detect: the mean photo-electron count is formed without overflow -------------------------------


@pytest.mark.parametrize(
    "value, photons, scale, mean",
    [
        (1e300, 1e9, None, 1e9),  # photons * I overflowed before the division by scale
        (1e300, 1e-3, 1e290, 1e7),  # photons * I / scale = 1e-3 * 1e10
        (
            1e-320,
            100.0,
            None,
            100.0,
        ),  # subnormal intensities: the brightest pixel still gets `photons`
        (1e-300, 1e6, 1e-302, 1e8),
    ],
)
def test_detect_extreme_intensities_have_the_poisson_mean(value, photons, scale, mean):
    channels = np.full((4, 8, 8), value)
    with no_runtime_warning():
        counts = I.detect(channels, 0, photons=photons, scale=scale)
    assert np.all(np.isfinite(counts))
    # 256 Poisson draws of mean `mean`: the sample mean is within 8 standard errors
    assert abs(counts.mean() - mean) < 8 * math.sqrt(mean / counts.size)


def test_detect_refuses_a_mean_beyond_the_poisson_sampler():
    # the brightest pixel's mean would be 1e9 * 1e300 / 1 e-: refused, naming scale and photons
    with pytest.raises(
        ValueError, match=r"scale \(1.0\) is too small for photons \(1000000000.0\)"
    ):
        I.detect(np.full((4, 2, 2), 1e300), 0, photons=1e9, scale=1.0)
    with pytest.raises(ValueError, match=r"photons \* max\(channels\) / scale = 2e\+18 e-"):
        I.detect(np.full((4, 2, 2), 2.0), 0, photons=1e18, scale=1.0)


def test_detect_at_the_largest_photon_count_with_scale_the_brightest_pixel():
    # photons * peak / scale with scale = peak = 0.7 may round an ulp above photons = 1e18: still allowed
    channels = np.full((1, 4, 4), 0.7)
    with no_runtime_warning():
        counts = I.detect(channels, 0, photons=1e18, scale=0.7)
    assert abs(counts.mean() / 1e18 - 1) < 1e-6  # Poisson: relative standard error 2.5e-10


def test_detect_at_the_largest_read_noise_stays_finite():
    with no_runtime_warning():
        out = I.detect(np.ones((1, 4, 4)), 0, photons=10.0, read_noise=1e18)
    assert np.all(np.isfinite(out))
    # the difference of two reads: Gaussian with standard deviation sqrt(2) * 1e18 (Poisson negligible)
    assert 0.2 < out.std() / (math.sqrt(2) * 1e18) < 3


# --- 2. psf: any nonzero finite pupil gives a finite unit-sum PSF ---------------------------------------


def _square_pupil_psf(n, pad):
    """The PSF of a uniform n x n pupil zero-padded to m = pad n: |sum_x exp(-2 pi i k x / m)|^2 per axis,
    sin^2(pi k n / m) / sin^2(pi k / m) (n^2 at k = 0), centred at k = 0 -> pixel m / 2, unit sum."""
    m = pad * n
    k = np.arange(m) - m // 2
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(k == 0, n**2, np.sin(np.pi * k * n / m) ** 2 / np.sin(np.pi * k / m) ** 2)
    h = np.outer(f, f)
    return h / h.sum()


@pytest.mark.parametrize("amplitude", [1e-320, 1e-300, 1e-200, 1.0, 1e200, 1e300])
def test_psf_of_a_uniform_pupil_at_any_amplitude(amplitude):
    with no_runtime_warning():
        h = I.psf(np.full((8, 8), amplitude))
    assert np.all(np.isfinite(h))
    assert h.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(h, _square_pupil_psf(8, 2), rtol=0, atol=1e-12)


def test_psf_of_a_single_subnormal_pupil_pixel_is_flat():
    # one transmitting pixel: |F|^2 is the same at every frequency, the PSF is 1 / m^2 everywhere
    pupil = np.zeros((8, 8))
    pupil[3, 5] = 1e-310
    with no_runtime_warning():
        h = I.psf(pupil, phase=np.full((8, 8), 0.7))
    np.testing.assert_allclose(h, np.full((16, 16), 1 / 256), rtol=1e-12)


def test_psf_of_a_dark_pupil_is_still_refused():
    with pytest.raises(ValueError, match="pupil must transmit light"):
        I.psf(np.zeros((8, 8)))


# --- 3. r0 and the Rytov variance at extreme arguments (Eqs. 74-75, 80-81) ------------------------------


def test_fried_parameter_at_a_huge_wavelength():
    # r0 = (0.423 k^2 Cn2 L)^(-3/5) = lambda^(6/5) (0.423 (2 pi)^2 Cn2 L)^(-3/5); k^2 underflowed to 0
    cn2, L, lam = 1e-14, 1e3, 1e200
    expected = lam ** (6 / 5) * (0.423 * (2 * math.pi) ** 2 * cn2 * L) ** (-3 / 5)
    assert I.fried_parameter(cn2, L, lam) == pytest.approx(expected, rel=1e-12)
    assert I.fried_parameter(lambda z: cn2, L, lam) == pytest.approx(expected, rel=1e-10)


def test_fried_parameter_limits():
    # beyond the largest double (lambda^(6/5) alone is 1e324): refused, naming the arguments
    with pytest.raises(ValueError, match=r"r0 exceeds the largest double .*wavelength = 1e\+270 m"):
        I.fried_parameter(1e-14, 1e3, 1e270)
    # below the smallest double (log r0 = -1659): 0, the limit of extremely strong turbulence
    assert I.fried_parameter(1e300, 1e300, 1e-300) == 0.0


def test_rytov_variance_at_extreme_arguments():
    # Eq. 80, constant Cn2: 1.2273 Cn2 k^(7/6) L^(11/6) (k^(7/6) = 1e-233 is a double)
    cn2, L, lam = 1e-14, 1e3, 1e200
    k = 2 * math.pi / lam
    assert I.rytov_variance(cn2, L, lam) == pytest.approx(
        2.25 * 6 / 11 * cn2 * k ** (7 / 6) * L ** (11 / 6), rel=1e-12
    )
    # k^(7/6) of a wavelength of 1e-300 m overflowed (OverflowError): the variance is ~1e342, refused
    with pytest.raises(ValueError, match=r"Rytov variance exceeds the largest double.*1e-300 m"):
        I.rytov_variance(1e-14, 1e3, 1e-300)
    assert I.rytov_variance(1e-300, 1e-100, 1e100) == 0.0  # below the smallest double


def test_rytov_variance_from_r0_at_extreme_arguments():
    # Eq. 81: 2.91 [L / (k r0^2)]^(5/6) = 2.91 [(L / r0) / (k r0)]^(5/6); r0^2 = 1e-400 underflowed to 0
    r0, L, lam = 1e-200, 1e-200, 1e-100
    k = 2 * math.pi / lam
    with pytest.warns(RuntimeWarning, match="Rytov"):  # ~1e82: strong turbulence, as documented
        s2 = I.rytov_variance_from_r0(r0, L, lam)
    assert s2 == pytest.approx(2.91 * ((L / r0) / (k * r0)) ** (5 / 6), rel=1e-12)
    # [1 / (6e-300 * 1e-600)]^(5/6) ~ 1e750: refused (was a ZeroDivisionError)
    with pytest.raises(
        ValueError, match=r"Rytov variance exceeds the largest double.*r0 = 1e-300 m"
    ):
        I.rytov_variance_from_r0(1e-300, 1.0, 1e300)
    assert I.rytov_variance_from_r0(1e100, 1e-100, 1e-100) == 0.0  # below the smallest double


# --- 4. malformed arguments are ValueErrors naming them -------------------------------------------------

CH = np.ones((4, 2, 2))


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: I.detect(CH, 0, photons=None), "photons"),
        (lambda: I.detect(CH, 0, photons="x"), "photons"),
        (lambda: I.detect(CH, 0, photons=[1.0, 2.0]), "photons"),
        (lambda: I.detect(CH, 0, photons=1.0, read_noise=None), "read_noise"),
        (lambda: I.detect(CH, 0, photons=1.0, read_noise="x"), "read_noise"),
        (lambda: I.detect(CH, 0, photons=1.0, read_noise=1e19), r"read_noise .*\[0, 1e\+18\]"),
        (lambda: I.detect(CH, 0, photons=1.0, dark_current=None), "dark_current"),
        (lambda: I.detect(CH, 0, photons=1.0, dark_current="x"), "dark_current"),
        (lambda: I.detect(CH, 0, photons=1.0, scale="x"), "scale"),
        (lambda: I.detect(CH, 0, photons=1.0, scale=[1.0, 2.0]), "scale"),
        (lambda: I.circular_pupil(8, 4, "x"), r"obscuration .*\[0, 1\)"),
        (lambda: I.circular_pupil(8, 4, 1.0), r"obscuration .*\[0, 1\)"),
        (lambda: I.circular_pupil(8, 4, None), "obscuration"),
        (lambda: I.circular_pupil(8, "x"), "radius"),
        (lambda: I.circular_pupil(8, [2.0, 3.0]), "radius"),
        (lambda: I.circular_pupil(8.0, 4), "n must be an integer >= 4"),
        (lambda: I.painted_plate(8, zoom="x"), r"zoom .*\[0.25, 16\]"),
        (lambda: I.painted_plate(8, zoom=None), "zoom"),
        (lambda: I.painted_plate(8, center=(1,)), r"center must be \(row, column\)"),
        (lambda: I.painted_plate(8, center=(1, 2, 3)), "center"),
        (lambda: I.painted_plate(8, center="ab"), "center"),
        (lambda: I.painted_plate(8, center=None), "center"),
        (lambda: I.painted_plate(8, center=(np.nan, 8.0)), "center"),
        (lambda: I.painted_plate(8.5), "n must be an integer >= 8"),
        (lambda: I.long_exposure_mtf([0.5], "x"), "d_over_r0"),
        (lambda: I.short_exposure_mtf([0.5], [1.0, 2.0]), "d_over_r0"),
        (lambda: I.short_exposure_mtf([0.5], 2.0, alpha="x"), "alpha"),
        (lambda: I.fried_parameter(None, 1e3, 1e-6), "cn2"),
        (lambda: I.fried_parameter(1e-14, "x", 1e-6), "path_length"),
        (lambda: I.rytov_variance(1e-14, 1e3, [1e-6, 2e-6]), "wavelength"),
        (lambda: I.rytov_variance(lambda z: -1e-14, 1e3, 1e-6), "cn2 .*profile"),
        (lambda: I.rytov_variance_from_r0("x", 1e3, 1e-6), "r0"),
    ],
)
def test_malformed_arguments_are_named(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_painted_plate_accepts_a_centre_array():
    # n = 16, zoom 1: one template unit per pixel; pixel (3, 2) sits at template (3.5, 2.5), in the first
    # stroke of the "s" (rows 3-4.2, columns 2-7); pixel (0, 0) at (0.5, 0.5) is paint
    lab = I.painted_plate(16, center=np.array([8.0, 8.0]), scratches=0).labels
    assert lab.shape == (16, 16) and lab[3, 2] == 1 and lab[0, 0] == 0


# --- 5. results that are the correct limit come without a RuntimeWarning --------------------------------


@pytest.mark.parametrize("d_over_r0", [1e186, 1e300, 1.7e308])
def test_mtfs_of_a_huge_aperture_are_zero_beyond_zero_frequency(d_over_r0):
    # exp(-3.44 (nu D/r0)^(5/3) ...) is below the smallest double for every nu > 0 (and alpha nu^(1/3) < 1);
    # at nu = 0 both are the diffraction-limited MTF, 1; at nu = 1 that is 0
    nu = np.array([0.0, 1e-3, 0.5, 1.0])
    with no_runtime_warning():
        np.testing.assert_array_equal(I.long_exposure_mtf(nu, d_over_r0), [1.0, 0.0, 0.0, 0.0])
        for alpha in (0.0, 0.5, 1.0):
            np.testing.assert_array_equal(
                I.short_exposure_mtf(nu, d_over_r0, alpha), [1.0, 0.0, 0.0, 0.0]
            )


def test_mtfs_of_a_tiny_aperture_are_diffraction_limited():
    nu = np.linspace(0, 1, 11)
    with no_runtime_warning():
        long = I.long_exposure_mtf(nu, 1e-300)
        short = I.short_exposure_mtf(nu, 1e-300, 0.5)
    expected = 2 / np.pi * (np.arccos(nu) - nu * np.sqrt(1 - nu**2))
    np.testing.assert_allclose(long, expected, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(short, expected, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("a", [1e-320, 1e-300, 1.0, 1e300])
def test_otf_of_three_points_at_any_magnitude(a):
    # h = a (delta(x + 1) + 2 delta(x) + delta(x - 1)) on row c: OTF(fx) = (2 + 2 cos(2 pi fx)) / 4
    # = cos^2(pi fx) at every fy, fx = (j - c) / n cycles/pixel
    n = 8
    c = n // 2
    h = np.zeros((n, n))
    h[c, c - 1 : c + 2] = [a, 2 * a, a]
    with no_runtime_warning():
        O = I.otf(h)
    fx = (np.arange(n) - c) / n
    np.testing.assert_allclose(O, np.tile(np.cos(np.pi * fx) ** 2, (n, 1)), atol=1e-12)


def test_otf_of_a_psf_whose_sum_is_rounding_is_refused():
    # +1 and -1 cancel; the sum 1e-310 is far below the rounding of summing a PSF with |h| = 1
    h = np.zeros((8, 8))
    h[4, 4], h[4, 5], h[0, 0] = 1.0, -1.0, 1e-310
    with pytest.raises(ValueError, match="h must have a positive sum"):
        I.otf(h)


def test_structure_function_of_a_spike_beyond_the_square_root_of_the_largest_double():
    # a spike A on a zero 8 x 8 screen at (3, 3): for k <= 3, 2 of the 8 (8 - k) pairs along each axis
    # differ by A, so D(k) = A^2 / (4 (8 - k)) = (A / 2)^2 / (8 - k); A^2 = 4e308 overflowed, D does not
    A = 2e154
    s = np.zeros((8, 8))
    s[3, 3] = A
    with no_runtime_warning():
        r, D = I.structure_function(s, 3)
    np.testing.assert_array_equal(r, [1, 2, 3])
    np.testing.assert_allclose(D, (A / 2) ** 2 / (8 - r), rtol=1e-12)
    # a spike of 1e-300: D ~ 1e-600 is 0 to double precision
    with no_runtime_warning():
        assert np.all(I.structure_function(s * (1e-300 / A), 3)[1] == 0.0)


def test_structure_function_beyond_the_largest_double_is_refused():
    screens = 1e300 * np.random.default_rng(0).standard_normal((8, 8))
    with pytest.raises(ValueError, match="screens must have phase differences below"):
        I.structure_function(screens, 2)
