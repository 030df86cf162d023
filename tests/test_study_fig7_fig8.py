"""Figs. 7-8 study: the turbulent PSFs shown do not wrap around their frame."""

import json
import math

import numpy as np
import pytest

from scatterlab import study_runner

FIG78 = study_runner.discover()["fig7_fig8"].module


def test_edge_energy_of_a_gaussian_matches_the_error_function():
    # independent truth: a centred Gaussian keeps erf(b / (sqrt2 s))^2 inside a square of half-width b
    N, s = 256, 20.0
    x = np.arange(N) - N / 2
    h = np.exp(-(x[:, None] ** 2 + x[None, :] ** 2) / (2 * s**2))
    half = N / 2 - round(N * FIG78.EDGE_BAND) - 0.5  # pixel centres of the kept square
    expected = 1 - math.erf((half + 0.5) / (math.sqrt(2) * s)) ** 2
    assert FIG78.edge_energy(h) == pytest.approx(expected, rel=0.02)


def test_edge_energy_flags_a_wrapped_psf():
    N = 128
    x = np.arange(N) - N / 2
    h = np.exp(-(x[:, None] ** 2 + x[None, :] ** 2) / (2 * 6.0**2))
    assert FIG78.edge_energy(h) < 1e-6
    assert FIG78.edge_energy(np.fft.fftshift(h)) > 0.99  # centre moved to the corners


def test_turbulent_psfs_do_not_wrap(tmp_path):
    study_runner.run_study("fig7_fig8", tmp_path, quick=True, seed=11)
    m = json.loads((tmp_path / "metrics.json").read_text())["metrics"]
    edges = [v for k, v in m.items() if k.startswith("edge_energy_turb_")]
    assert len(edges) == 3
    # tolerance: 2 % of the energy in the outer eighth of the frame on each side; the old 64-px
    # grid (r0 = 1.5 px, frame 1.5 seeing widths) put 25-37 % there
    assert max(edges) < 0.02
    assert m["verdict"] == "reproduced"
