"""Fig. 41 study (ECM-calibrated ellipsometry of a synthetic sample): the report attributes a fit
deviation to the calibration only when the deviation exceeds the repeat noise's standard errors."""

import json

import pytest

from scatterlab import study_runner


@pytest.mark.parametrize("seed", [20101210, 1])
def test_calibration_error_is_claimed_only_beyond_the_repeat_noise(tmp_path, seed):
    # a seed survey found the claim "the rest is the calibration's own error" made at 6.0 standard
    # errors on one seed and at 1.5 on another, where nothing beyond the noise is shown
    report = study_runner.run_study("fig41", tmp_path, quick=True, seed=seed).read_text()
    m = json.loads((tmp_path / "metrics.json").read_text())["metrics"]
    z = max(m["fit_deviation_in_sigmas"])
    claimed = "the rest is the calibration's own error" in report
    assert claimed == (z > 3)
    assert claimed or "shows no error beyond the sample's repeat noise" in report
