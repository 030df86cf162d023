"""The series-wide trend error of a blind paint's ratio correction (self_calibration.REFERENCE_RATIO_TREND_FRACTION).

A paint's n is set by how its DOLP changes with angle, so an error that tilts the whole series -- the
reference plate's dilution mis-estimated more at one end of the angles than at the other -- moves n much more
than independent errors of the same size. Data are drawn here with such a tilt, of a known size; an error
model that carries it gives standardised n errors of unit rms, one without it does not.
"""

import warnings

import numpy as np
import pytest

from scatterlab.characterization.estimation import RegionData, _covariance
from scatterlab.characterization.self_calibration import (
    REFERENCE_RATIO_TREND_CORRELATION,
    BiasEstimate,
    bias_corrected,
    series_position,
)
from scatterlab.inversion import fit_dolp
from scatterlab.pbrdf import Model

THETAS = np.radians([30.0, 40.0, 50.0, 60.0])
SIGMA = 0.3
PAINT = (1.5, 0.3)


def test_series_position_runs_from_minus_one_to_one_in_angle():
    np.testing.assert_allclose(series_position(THETAS), [-1, -1 / 3, 1 / 3, 1])
    # any order; unequal steps are placed by angle, not by index
    np.testing.assert_allclose(series_position(np.radians([60.0, 30.0, 35.0])), [1, -1, -2 / 3])
    np.testing.assert_allclose(series_position(np.radians([45.0])), [0.0])
    np.testing.assert_allclose(series_position(np.radians([45.0, 45.0])), [0.0, 0.0])


def _measured_paint(truth, ratio, spread, trend):
    """A paint restored at ``ratio`` x its DOLP, corrected by a measured reference-plate bootstrap."""
    observed = ratio * truth
    region = RegionData("paint", observed, np.full(4, 0.01), np.full(4, 0.01), np.zeros(4), 200)
    bias = BiasEstimate(
        observed - truth,
        np.full(4, spread),
        4,
        ratio=np.full(4, ratio),
        fraction=0.0,
        common=0.15,
        measured=True,
        trend=trend,
        position=series_position(THETAS),
        trend_correlation=REFERENCE_RATIO_TREND_CORRELATION,
    )
    return bias_corrected(region, bias)


@pytest.mark.parametrize("with_trend", [True, False])
def test_a_tilted_series_is_covered_only_when_the_trend_is_modelled(with_trend):
    """2000 data sets drawn with independent errors, a level error and a tilt of the sizes the corrected
    region states (a paint restored at 0.93 of its DOLP: errors 0.007-0.015, where the Laplace
    approximation holds): the standard errors of n from the covariance with the trend standardise the n
    errors to rms 1 (0.9-1.1; 0.97); the error model without the trend (the level alone) leaves them at
    rms > 1.3 (1.78)."""
    truth = Model(SIGMA).dolp(PAINT[0] - 1j * PAINT[1], THETAS, THETAS, np.pi)
    region = _measured_paint(truth, ratio=0.93, spread=0.004, trend=0.15)
    assert region.calibrated and region.trend is not None
    C_true = _covariance(region, region.error)
    # the model without the trend is the error model before it: the level error alone
    model = region if with_trend else _measured_paint(truth, ratio=0.93, spread=0.004, trend=0.0)
    assert with_trend or model.trend is None
    C_model = _covariance(model, model.error)
    rng = np.random.default_rng(5)
    y = truth + rng.multivariate_normal(np.zeros(4), C_true, size=2000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_dolp(y, THETAS, THETAS, sigma=SIGMA, covariance=C_model)
    ok = np.isfinite(fit.n) & np.isfinite(fit.covariance[:, 0, 0])
    z = (fit.n[ok] - PAINT[0]) / np.sqrt(fit.covariance[ok, 0, 0])
    rms = float(np.sqrt(np.mean(z**2)))
    assert ok.mean() > 0.99
    if with_trend:
        assert 0.9 < rms < 1.1, rms
    else:
        assert rms > 1.3, rms


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"trend_correlation": 1.5}, "trend_correlation"),
        ({"trend_correlation": -1.01}, "trend_correlation"),
        ({"trend_correlation": float("nan")}, "trend_correlation"),
        ({"trend": -0.1}, "trend"),
        ({"common": float("inf")}, "common"),
        ({"fraction": -0.5}, "fraction"),
        ({"replicates": 0}, "replicates"),
        ({"replicates": 2.5}, "replicates"),
        ({"position": np.zeros(3)}, "position"),
    ],
)
def test_a_bias_estimate_refuses_what_would_make_its_error_nan_or_negative(kw, name):
    """A correlation beyond [-1, 1] would make the trend's independent part sqrt(1 - rho^2) NaN inside the
    posterior; the error is named where it is set."""
    with pytest.raises(ValueError, match=name):
        BiasEstimate(np.zeros(4), np.zeros(4), **kw)


def test_a_perfectly_correlated_trend_is_all_level():
    """At rho = +-1 the trend's independent mode vanishes (no NaN): the whole trend rides on the level."""
    truth = Model(SIGMA).dolp(PAINT[0] - 1j * PAINT[1], THETAS, THETAS, np.pi)
    observed = 0.9 * truth
    region = RegionData("paint", observed, np.full(4, 0.01), np.full(4, 0.01), np.zeros(4), 200)
    for rho in (-1.0, 1.0):
        bias = BiasEstimate(
            observed - truth,
            np.full(4, 0.004),
            4,
            ratio=np.full(4, 0.9),
            fraction=0.0,
            common=0.15,
            measured=True,
            trend=0.15,
            position=series_position(THETAS),
            trend_correlation=rho,
        )
        c = bias_corrected(region, bias)
        np.testing.assert_allclose(c.trend, 0.0, atol=1e-15)
        x, b = series_position(THETAS), c.bias
        np.testing.assert_allclose(c.correlated, 0.15 * b + rho * 0.15 * b * x)
        assert np.all(np.isfinite(c.error))
