"""fig39: the curves are normalised by their level near the specular angle, not by one speckle sample."""

import numpy as np
import pytest

from scatterlab import study_runner

F39 = study_runner.discover()["fig39"].module


def test_specular_level_is_the_window_mean():
    theta_s = F39.THETA_S
    ti = np.radians(30.0)
    line = 2.0 + np.degrees(
        theta_s - ti
    )  # odd about the specular angle: the window mean is the centre value
    assert F39.specular_level(theta_s, line, ti) == pytest.approx(2.0)
    assert F39.specular_level(theta_s, np.full_like(theta_s, 3.5), ti) == pytest.approx(3.5)


def test_a_speckle_spike_at_the_specular_sample_moves_the_level_by_its_share_of_the_window():
    theta_s = F39.THETA_S  # 0.5 deg grid: +-5 deg holds 21 samples
    ti = np.radians(10.0)
    curve = np.ones_like(theta_s)
    curve[np.argmin(np.abs(theta_s - ti))] = 22.0  # a one-sample spike 21 x above its neighbours
    assert F39.specular_level(theta_s, curve, ti) == pytest.approx(1.0 + 21.0 / 21)
