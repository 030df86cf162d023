"""Shared helpers for study scripts (not a study: the runner skips files starting with '_')."""

import numpy as np


def plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot

    return pyplot


def rms_slope_from_degrees(deg):
    """The reference's "n deg rms slope roughness" read as a per-axis rms slope sigma = tan(n deg)."""
    return np.tan(np.radians(deg))
