"""fit_pbrdf: parameters recovered from Mueller BRDFs made by the model with noise, and from a NIST
SCATMECH (pySCATMECH) file read through scatterlab.io (an independent forward model and file path).
"""

import numpy as np
import pytest

from scatterlab.ellipsometry import depolarization_index, fit_pbrdf
from scatterlab.io import MuellerBRDF, write_mueller_brdf
from scatterlab.pbrdf import Model
from scatterlab.polarization import depolarizer, linear_retarder

ETA, SIGMA = 1.39 - 0.34j, 0.3  # green paint at 1550 nm (a depolarizing, dielectric-like sample)


def geometries(rng, n=30):
    ti = np.radians(rng.uniform(15, 65, n))
    tr = np.radians(rng.uniform(10, 75, n))
    phi = rng.uniform(np.pi / 2, np.pi, n)
    return ti, tr, phi


def noisy(rng, rel=0.01, eta=ETA, sigma=SIGMA, wavelengths=(1.55e-6,)):
    ti, tr, phi = geometries(rng)
    M = Model(sigma).mueller(eta, ti, tr, phi)
    std = rel * M[:, :1, :1] * np.ones((1, 4, 4))
    y = M + std * rng.standard_normal(M.shape)
    wl = np.resize(np.asarray(wavelengths), ti.size)
    return MuellerBRDF(wl, ti, tr, phi, y, std, source="simulated")


def test_recovers_parameters_with_calibrated_errors():
    """1 % noise of F00 on all 16 elements at 30 out-of-plane geometries: the truth lies within 4
    standard errors (seed fixed) and the reduced chi^2 is 1 within its sampling spread (sqrt(2/477)
    ~ 0.065, 4 sigma)."""
    fit = fit_pbrdf(noisy(np.random.default_rng(7)))
    truth = np.array([ETA.real, -ETA.imag, SIGMA])
    got = np.array([fit.n, fit.kappa, fit.sigma])
    assert np.all(np.abs(got - truth) < 4 * fit.errors), (got, fit.errors)
    assert np.all(fit.errors < 0.02)
    assert fit.reduced_chi2 == pytest.approx(1.0, abs=0.26)
    assert fit.weighted and fit.determined and fit.residuals.shape == (30, 4, 4)
    assert fit.element_rms.shape == (4, 4) and np.all(fit.element_rms < 1.5)
    # the diffuse term is all the model's depolarization, and the data were made by the model
    assert fit.depolarization["explained"] == pytest.approx(1.0, abs=0.1)
    assert fit.circular_flip_ratio > 3


def test_normalised_data_and_wavelength_selection():
    rng = np.random.default_rng(8)
    data = noisy(rng, rel=0.0, wavelengths=(1.064e-6, 1.55e-6))
    with pytest.raises(ValueError, match="several wavelengths"):
        fit_pbrdf(data)
    with pytest.raises(ValueError, match="not in the data"):
        fit_pbrdf(data, wavelength=0.6e-6)
    sel = data.select(1.55e-6)
    norm = MuellerBRDF(
        sel.wavelength, sel.theta_i, sel.theta_r, sel.phi, sel.normalised_mueller(), normalised=True
    )
    fit = fit_pbrdf(norm, wavelength=1.55e-6)
    assert fit.normalised and np.all(np.isnan(fit.residuals[:, 0, 0]))
    assert [fit.n, fit.kappa, fit.sigma] == pytest.approx([ETA.real, -ETA.imag, SIGMA], abs=1e-5)


def test_depolarization_index_limits_and_partial_explanation():
    assert depolarization_index(linear_retarder(0.7, 0.3)) == pytest.approx(1.0)  # Jones matrix
    assert depolarization_index(depolarizer(0.0)) == pytest.approx(0.0)  # ideal depolarizer
    # a sample depolarizing more than the model's diffuse term: Model + extra unpolarized light
    rng = np.random.default_rng(9)
    ti, tr, phi = geometries(rng, 25)
    M = Model(SIGMA).mueller(ETA, ti, tr, phi)
    extra = np.zeros_like(M)
    extra[:, 0, 0] = 0.5 * M[:, 0, 0]
    fit = fit_pbrdf(MuellerBRDF(1.55e-6, ti, tr, phi, M + extra))
    assert 0 < fit.depolarization["explained"] < 0.9
    assert fit.depolarization["measured_mean"] > fit.depolarization["model_mean"]


def test_posterior_agrees_with_the_covariance():
    """emcee (24 walkers x 600 steps, half burn-in) around the fit: posterior sd within 30 % of the
    linearised standard errors (the chain's sd is estimated to ~10 % at this length) and medians
    within one standard error of the fit."""
    fit = fit_pbrdf(noisy(np.random.default_rng(7)), posterior_steps=600, rng=3)
    s = fit.posterior["samples"]
    np.testing.assert_allclose(s.std(0), fit.errors, rtol=0.3)
    assert np.all(np.abs(np.median(s, 0) - [fit.n, fit.kappa, fit.sigma]) < fit.errors)
    assert 0.2 < fit.posterior["acceptance"] < 0.8
    assert fit.summary()["posterior"]["steps"] == 600


def test_a_known_roughness_is_held_and_narrows_n_and_kappa():
    """sigma given (as from profilometry): n and kappa recovered within 4 standard errors, and their
    errors, at the same point, no larger than with sigma fitted (the inverse of a sub-block of J^T J
    never exceeds the sub-block of its inverse: fixing a parameter cannot widen the others); a wrong sigma
    shows in the fit's quality; the posterior samples only n and kappa."""
    data = noisy(np.random.default_rng(7))
    free = fit_pbrdf(data)
    fit = fit_pbrdf(data, sigma=SIGMA, posterior_steps=400, rng=4)
    assert fit.sigma == SIGMA and fit.errors[2] == 0 and fit.options["sigma_known"] == SIGMA
    got, truth = np.array([fit.n, fit.kappa]), np.array([ETA.real, -ETA.imag])
    assert np.all(np.abs(got - truth) < 4 * fit.errors[:2]), (got, fit.errors)
    assert fit.dof == free.dof + 1
    # at the free fit's own sigma the optimum, and so J, is the same point: only the inversion differs
    held = fit_pbrdf(data, sigma=free.sigma)
    assert [held.n, held.kappa] == pytest.approx([free.n, free.kappa], rel=1e-6)
    assert np.all(held.errors[:2] <= free.errors[:2] * (1 + 1e-6))
    s = fit.posterior["samples"]
    assert s.shape[1] == 3 and np.all(s[:, 2] == SIGMA)
    np.testing.assert_allclose(s[:, :2].std(0), fit.errors[:2], rtol=0.3)
    # the truth's 0.3 held at 0.2: 1 % noise on 480 elements cannot hide it
    wrong = fit_pbrdf(data, sigma=0.2)
    assert wrong.reduced_chi2 > 5 * free.reduced_chi2
    for bad in (0.0, 2.0, float("nan")):
        with pytest.raises(ValueError, match=r"sigma \(the known roughness\) must be within"):
            fit_pbrdf(data, sigma=bad)


def test_bad_arguments(tmp_path):
    data = noisy(np.random.default_rng(1))
    with pytest.raises(ValueError, match="starts"):
        fit_pbrdf(data, starts=())
    with pytest.raises(ValueError, match="bounds"):
        fit_pbrdf(data, bounds=((1, 0.5), (0, 30), (0.01, 1.5)))
    with pytest.raises(ValueError, match="posterior_steps"):
        fit_pbrdf(data, posterior_steps=-5)
    zero = MuellerBRDF(
        data.wavelength, data.theta_i, data.theta_r, data.phi, data.mueller, 0 * data.std
    )
    with pytest.raises(ValueError, match="std"):
        fit_pbrdf(zero)
    # normalised elements in the specular direction without a diffuse term do not depend on sigma at
    # all
    th = np.radians([30.0, 50.0])
    M = Model(SIGMA, diffuse="none").mueller(ETA, th, th, np.pi)
    with pytest.warns(RuntimeWarning, match="do not determine"):
        fit = fit_pbrdf(
            MuellerBRDF(1.55e-6, th, th, np.pi, M / M[:, :1, :1], normalised=True),
            diffuse="none",
            starts=((1.5, 0.3),),
        )
    assert not fit.determined and np.all(np.isinf(fit.errors))
    write_mueller_brdf(tmp_path / "d.csv", data)  # the writer accepts what the fit takes


GEOMETRIES = np.array(
    [
        [0.3, 0.3, np.pi],
        [0.5, 0.5, np.pi],
        [0.7, 0.7, np.pi],
        [0.5, 0.3, np.pi / 2],
        [1.0, 0.8, 2.5],
        [0.2, 1.2, np.pi],
    ]
)


@pytest.mark.parametrize("dark", [0, 3, 5])
def test_a_dark_geometry_is_dropped_and_the_others_recover_the_truth(dark):
    """A zero-photon geometry (F = 0) has no normalised Mueller information: weighted by its F00 it
    used to outweigh the others a million times and pull the fit to vacuum (n = 1). It is dropped with
    a warning, and the noise-free model data at the other five geometries give the truth back."""
    truth = (1.5, 0.1, 0.2)
    F = Model(truth[2]).mueller(truth[0] - 1j * truth[1], *GEOMETRIES.T)
    F[dark] = 0.0
    with pytest.warns(UserWarning, match=rf"dropped 1 of 6 geometries.*\[{dark}\]"):
        fit = fit_pbrdf(MuellerBRDF(1e-6, *GEOMETRIES.T, F))
    assert [fit.n, fit.kappa, fit.sigma] == pytest.approx(truth, abs=1e-6)
    assert fit.options["dropped"] == [dark] and fit.residuals.shape == (5, 4, 4)
    # normalised data: a dark row (F00 = 0 instead of 1) is dropped as well
    N = F / np.where(F[:, :1, :1] > 0, F[:, :1, :1], 1.0)
    with pytest.warns(UserWarning, match="dropped 1 of 6"):
        fit = fit_pbrdf(MuellerBRDF(1e-6, *GEOMETRIES.T, N, normalised=True))
    assert [fit.n, fit.kappa, fit.sigma] == pytest.approx(truth, abs=1e-5)


def test_dark_data_are_refused():
    F = np.zeros((len(GEOMETRIES), 4, 4))
    with pytest.raises(ValueError, match=r"data \(the Mueller BRDF\) are dark at all 6 geometries"):
        fit_pbrdf(MuellerBRDF(1e-6, *GEOMETRIES.T, F))
    with pytest.raises(ValueError, match="dark"):
        fit_pbrdf(MuellerBRDF(1e-6, *GEOMETRIES.T, F, np.ones_like(F)))
    with pytest.raises(ValueError, match="dark"):
        fit_pbrdf(MuellerBRDF(1e-6, *GEOMETRIES.T, F, normalised=True))


def test_walkers_and_rng_are_checked_before_the_fit():
    data = MuellerBRDF(1e-6, *GEOMETRIES.T, Model(0.2).mueller(1.5 - 0.1j, *GEOMETRIES.T))
    with pytest.raises(ValueError, match="walkers must be an integer >= 8"):
        fit_pbrdf(data, posterior_steps=10, walkers=2)
    with pytest.raises(ValueError, match="rng"):
        fit_pbrdf(data, posterior_steps=10, rng=1.5)
