"""Thilak's two-step baseline, Cramer-Rao bounds and the uncertainty report."""

import warnings

import numpy as np
import pytest

from scatterlab.inversion import (
    ConvergenceWarning,
    crlb,
    fit_dolp,
    model_dolp,
    sample_posterior,
    thilak_two_step,
)
from scatterlab.inversion.thilak import thilak_dop
from scatterlab.pbrdf.dolp import dolp_smooth_facet

COPPER = (0.314, 3.544)


def test_eq115_equals_the_fresnel_dop_of_smooth_facets():
    beta = np.radians(np.linspace(1, 89, 50))
    np.testing.assert_allclose(
        thilak_dop(*COPPER, beta),
        dolp_smooth_facet(COPPER[0] - 1j * COPPER[1], beta),
        rtol=1e-12,
        atol=1e-15,
    )  # Eq. 115 rounds at 1e-16 absolute near beta = 0


def test_two_step_recovers_copper_and_theta_r_from_clean_data():
    ti = np.radians(np.linspace(35, 80, 10))
    tr = np.radians(60.0)
    y = thilak_dop(*COPPER, (ti + tr) / 2)
    fit = thilak_two_step(y, ti, tr, np.random.default_rng(0))
    np.testing.assert_allclose([fit.n[0], fit.kappa[0], fit.theta_r[0]], [*COPPER, tr], rtol=1e-6)
    assert fit.ok.all()


def test_crlb_matches_the_scatter_of_least_squares_in_the_gaussian_regime():
    ti = np.radians(np.r_[30, 40, 50, 60, 45, 45, 45])
    tr = np.radians(np.r_[30, 40, 50, 60, 20, 60, 70])
    bound = crlb(1.39, 0.34, 0.3, ti, tr, 1e-4)
    rng = np.random.default_rng(1)
    y = model_dolp(1.39, 0.34, 0.3, ti, tr) + 1e-4 * rng.standard_normal((300, ti.size))
    f = fit_dolp(y, ti, tr, starts=((1.5, 0.3),))
    scatter = np.std(np.stack([f.n, f.kappa, f.sigma], -1), 0, ddof=1)
    np.testing.assert_allclose(scatter, bound, rtol=0.15)  # 300 draws: sd known to ~4 %


def test_specular_only_sweeps_cannot_fix_sigma_but_off_specular_ones_can():
    """Fig. 58's remark, for highly specular samples (sigma = 0.02-0.1, the reference's were below 1
    deg): the
    bound on sigma from specular angles 30-60 deg is far larger than from theta_r = 20-80 deg at
    theta_i = 45.
    """
    spec = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60])
    off_r = np.radians(np.r_[20, 30, 40, 50, 60, 70, 80])
    for n, k in ((3.6, 5.9), (1.39, 0.34)):
        for s in (0.02, 0.1):
            b_spec = crlb(n, k, s, spec, spec, 1e-3)
            b_off = crlb(n, k, s, np.full(7, np.radians(45)), off_r, 1e-3)
            assert b_spec[2] > 5 * b_off[2]
    # glass: kappa = 0 is a stationary point of the DOLP, so kappa's bound is infinite, the others
    # finite
    b = crlb(1.5, 0.0, 0.3, np.full(7, np.radians(45)), off_r, 1e-3)
    assert np.isinf(b[1]) and np.all(np.isfinite(b[[0, 2]]))
    with pytest.raises(ValueError, match="noise"):
        crlb(1.5, 0.0, 0.3, spec, spec, 0.0)


def test_report_writes_figures_and_tables(tmp_path):
    from scatterlab.inversion.report import posterior_report, report_index

    ti = np.radians(np.r_[30, 40, 50, 60, 45, 45])
    tr = np.radians(np.r_[30, 40, 50, 60, 20, 70])
    rng = np.random.default_rng(0)
    y = model_dolp(1.5, 0.1, 0.3, ti, tr) + 2e-3 * rng.standard_normal(ti.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        post = sample_posterior(y, ti, tr, 2e-3, rng, n_steps=400)
    md = posterior_report(post, tmp_path, "glass", truth=(1.5, 0.1, 0.3))
    for suffix in ("_corner.png", "_trace.png", "_predictive.png"):
        assert (tmp_path / f"glass{suffix}").stat().st_size > 1000
    text = md.read_text()
    assert "| n |" in text and "68 %" in text and "tau" in text
    # the summary as JSON: the same quantiles as the table, the truth inside the 95 % interval
    import json

    summary = json.loads((tmp_path / "glass.json").read_text())["parameters"]
    lo, hi = summary["n"]["ci95"]
    assert lo <= 1.5 <= hi and f"{summary['n']['median']:.4g}" in text
    titled = posterior_report(
        post, tmp_path / "t", "g", title="Posterior of n - j kappa from x.csv", notes=["6 rows"]
    )
    assert titled.read_text().startswith("# Posterior of n - j kappa from x.csv\n\n- 6 rows\n")
    report_index(tmp_path, {"glass": post})
    assert "glass.md" in (tmp_path / "index.md").read_text()
    with pytest.raises(FileExistsError):
        posterior_report(post, tmp_path, "glass")
