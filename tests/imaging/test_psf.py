"""PSFs and MTFs against the Airy pattern, the diffraction-limited MTF and Fried's long-exposure MTF."""

import numpy as np
import pytest

from scatterlab.imaging import (
    airy_pattern,
    circular_pupil,
    diffraction_mtf,
    fit_r0,
    long_exposure_mtf,
    mtf,
    phase_screen,
    psf,
    radial_profile,
)


def test_diffraction_limited_psf_is_the_airy_pattern():
    n, R, pad = 256, 64, 4
    h = psf(circular_pupil(n, R), pad=pad)
    c = h.shape[-1] // 2
    row = h[c, c : c + 60] / h[c, c]
    k = np.arange(60)
    # the pupil is centred between pixels: the PSF's centre is at pixel c; angle per pixel = lambda/(pad n px)
    v = np.pi * (2 * R) * k / (pad * n)
    np.testing.assert_allclose(row, airy_pattern(v), atol=5e-3)  # pixelated pupil edge: O(1/R)
    first_zero = 3.8317 * pad * n / (np.pi * 2 * R)  # 1.22 lambda / D in pixels
    assert abs(np.argmin(row[: int(first_zero) + 3]) - first_zero) <= 0.5
    assert h.sum() == pytest.approx(1.0)


def test_diffraction_limited_mtf():
    n, R = 128, 32
    M = mtf(psf(circular_pupil(n, R), pad=2))
    r, prof = radial_profile(M)
    nu = r / (2 * R)
    sel = nu <= 1
    np.testing.assert_allclose(prof[sel], diffraction_mtf(nu[sel]), atol=5e-3)


@pytest.mark.parametrize("d_over_r0", [7.9, 10.5, 12.9])
def test_r0_fitted_from_simulated_long_exposure_mtf_within_5_percent(d_over_r0):
    """Long exposure = the mean of 200 PSFs through independent screens (tilt included), as Fig. 48."""
    n, R, D = 64, 32, 1.0
    r0 = D / d_over_r0
    pupil = circular_pupil(n, R)
    rng = np.random.default_rng(int(10 * d_over_r0))
    H = np.mean(
        [psf(pupil, phase_screen(n, D / (2 * R), r0, rng), pad=2) for _ in range(200)], axis=0
    )
    r, prof = radial_profile(mtf(H))
    nu = r / (2 * R)
    assert fit_r0(nu[: 2 * R], prof[: 2 * R], D) == pytest.approx(r0, rel=0.05)


def test_bad_input():
    with pytest.raises(ValueError, match="radius"):
        circular_pupil(32, 20)
    # a pupil with no pixel was returned silently (all zeros): name the arguments that emptied it
    with pytest.raises(
        ValueError, match=r"radius \(0.1 px\) and obscuration \(0\) leave the pupil empty"
    ):
        circular_pupil(8, 0.1)
    with pytest.raises(ValueError, match="radius .* and obscuration .* leave the pupil empty"):
        circular_pupil(8, 2.0, 0.95)
    with pytest.raises(ValueError, match="pad"):
        psf(circular_pupil(32, 10), pad=1)
    with pytest.raises(ValueError, match="phase"):
        psf(circular_pupil(32, 10), np.full((32, 32), np.nan))
    with pytest.raises(ValueError, match="d_over_r0"):
        long_exposure_mtf(0.1, -1)
    with pytest.raises(ValueError, match="three"):
        fit_r0(np.linspace(0, 1, 10), np.zeros(10), 1.0)


def test_shape_mismatches_and_stacks_are_named():
    """psf: numpy's 'operands could not be broadcast'; fit_r0: an IndexError; radial_profile of a stack:
    numpy's 'weights and list don't have the same length'."""
    with pytest.raises(
        ValueError, match=r"phase \(shape \(16, 16\)\) must broadcast to pupil \(shape \(32, 32\)\)"
    ):
        psf(circular_pupil(32, 16), np.zeros((16, 16)), pad=2)
    with pytest.raises(ValueError, match="pad must be an integer >= 2"):
        psf(circular_pupil(8, 4), pad=2.5)
    for nu, m in (
        (np.linspace(0, 1, 10), np.full(9, 0.5)),
        (np.linspace(0, 1, 10).reshape(2, 5), np.full((2, 5), 0.5)),
    ):
        with pytest.raises(
            ValueError, match=r"nu and measured_mtf must be 1-D arrays of the same length"
        ):
            fit_r0(nu, m, 0.1)
    with pytest.raises(
        ValueError, match=r"image must be one square 2-D image \(n, n\), got shape \(2, 8, 8\)"
    ):
        radial_profile(np.ones((2, 8, 8)))
    with pytest.raises(ValueError, match="image must be finite"):
        radial_profile(np.full((8, 8), np.nan))
    with pytest.raises(ValueError, match="nbins must be an integer >= 1"):
        radial_profile(np.ones((8, 8)), 0)
    # the radial profile of a rotationally symmetric image is the function of the rounded radius
    y, x = np.indices((33, 33)) - 16
    r, prof = radial_profile(np.rint(np.hypot(x, y)) ** 2)
    np.testing.assert_array_equal(prof, r.astype(float) ** 2)
