"""psf_distance: an estimate's L1 distance from the true PSF after the best integer shift."""

import numpy as np
import pytest

from scatterlab.deconvolution import psf_distance
from scatterlab.imaging import circular_pupil, phase_screen, psf


def _speckle_psf(seed):
    A = circular_pupil(16, 8)
    return psf(A, phase_screen(16, 1.0, 16 / 6.0, np.random.default_rng(seed)), pad=2)


def test_a_shifted_and_rescaled_copy_is_at_distance_zero():
    """The translation a blind estimate is found up to, and its scale, do not count."""
    truth = _speckle_psf(0)
    moved = 3.0 * np.roll(truth, (2, -3), (0, 1))
    d, shift = psf_distance(moved, truth)
    assert d == pytest.approx(0.0, abs=1e-12)
    assert shift == (-2, 3)


def test_disjoint_psfs_are_at_distance_two_and_others_between():
    truth = np.zeros((32, 32))
    truth[16, 16] = 1.0
    far = np.zeros((32, 32))
    far[2, 2] = 1.0  # 14 px away: beyond the reach of 8
    assert psf_distance(far, truth)[0] == pytest.approx(2.0)
    # another screen's PSF: strictly between the two
    d = psf_distance(_speckle_psf(1), _speckle_psf(2))[0]
    assert 0.1 < d < 2.0


def test_an_estimate_on_another_grid_is_compared_on_the_truths():
    truth = _speckle_psf(3)  # 32 x 32
    wide = np.pad(truth, 16)  # the same PSF on a 64 x 64 grid
    assert psf_distance(wide, truth)[0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    "h, truth, reach, name",
    [
        (np.full((4, 4), np.nan), np.ones((4, 4)), 2, "h"),
        (np.ones((4, 4)), -np.ones((4, 4)), 2, "truth"),
        (np.ones((4, 4)), np.zeros((4, 4)), 2, "truth"),
        (np.ones(4), np.ones((4, 4)), 2, "h"),
        (np.ones((4, 4)), np.ones((4, 4)), -1, "reach"),
    ],
)
def test_bad_input_names_the_argument(h, truth, reach, name):
    with pytest.raises(ValueError, match=name):
        psf_distance(h, truth, reach)


def test_an_estimate_with_all_its_light_outside_the_truths_grid_is_disjoint():
    from scatterlab.deconvolution import resample_psf

    h = np.zeros((64, 64))
    h[0, 0] = 1.0  # a corner the 16 x 16 crop does not reach
    truth = np.zeros((16, 16))
    truth[8, 8] = 1.0
    assert psf_distance(h, truth) == (2.0, (0, 0))
    with pytest.raises(ValueError, match="no light inside"):
        resample_psf(h, (16, 16))
