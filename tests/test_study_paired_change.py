"""studies._common.paired_change: a paired comparison's mean, standard error and 95 % interval."""

import importlib

import numpy as np
import pytest
from scipy import stats

from scatterlab import study_runner

study_runner.discover()  # mounts this checkout's studies/ as scatterlab.studies
_common = importlib.import_module("scatterlab.studies._common")


def test_paired_change_cancels_the_shared_draw_to_draw_scatter():
    base = np.array([1.0, 5.0, 2.0, 8.0])  # large scatter shared by both methods
    other = base - np.array([0.10, 0.12, 0.08, 0.10])
    c = _common.paired_change(base, other)
    assert c["mean"] == pytest.approx(-0.10)
    assert c["se"] == pytest.approx(np.std([0.10, 0.12, 0.08, 0.10], ddof=1) / 2)
    assert c["half_width"] == pytest.approx(stats.t.ppf(0.975, 3) * c["se"])
    assert c["word"] == "lower"


def test_paired_change_says_when_the_interval_includes_zero():
    c = _common.paired_change([0.3, 0.3, 0.3], [0.31, 0.28, 0.32])
    assert c["word"] == "no change resolved"
    assert _common.paired_change([0.1, 0.2, 0.3], [0.3, 0.4, 0.5])["word"] == "higher"


def test_paired_change_of_one_draw_resolves_nothing():
    c = _common.paired_change([0.3], [0.1])
    assert c["se"] == np.inf and c["word"] == "no change resolved"


def test_paired_change_refuses_unequal_lengths():
    with pytest.raises(ValueError, match="equal-length"):
        _common.paired_change([1.0, 2.0], [1.0, 2.0, 3.0])
