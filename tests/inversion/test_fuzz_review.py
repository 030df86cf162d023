"""Defects of a fuzz review and of a new-user trial of ``fit-dolp``: every bad input is a ValueError
naming the argument and its range, no numpy warning leaks (warnings are errors here), and what the
posterior says about its least-squares minima agrees with its table."""

import warnings

import numpy as np
import pytest

from scatterlab.inversion import (
    ConvergenceWarning,
    DolpForward,
    IdentifiabilityWarning,
    dolp_model_error,
    dolp_model_error_covariance,
    effective_sample_size,
    ensemble_rhat,
    fit_dolp,
    inverse_information,
    local_minima,
    model_dolp,
    sample_posterior,
    thilak_crlb,
    thilak_two_step,
)

TI = np.radians(np.r_[30.0, 40, 50, 60])
PAINT = (1.39, 0.34, 0.3)
Y = model_dolp(*PAINT, TI, TI)


@pytest.fixture(autouse=True)
def _strict():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        warnings.simplefilter("ignore", ConvergenceWarning)
        yield


def quick(*a, **kw):
    return sample_posterior(*a, n_steps=20, n_walkers=8, n_ensembles=1, **kw)


# -- 1 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [np.nan, -1.0, 0.0, np.inf, "4", [1.0, 2.0]])
def test_local_minima_refuses_a_bad_delta_chi2(bad):
    with pytest.raises(ValueError, match=r"delta_chi2 must be a single finite number > 0"):
        local_minima(Y, TI, TI, delta_chi2=bad)
    assert len(local_minima(Y, TI, TI, delta_chi2=4.0)) >= 1


def test_sampler_options_refuse_a_bad_mode_delta_chi2():
    with pytest.raises(ValueError, match="mode_delta_chi2"):
        quick(Y, TI, TI, 0.01, 0, sigma=0.3, mode_delta_chi2=np.nan)


# -- 2 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [1e-200, 1e200, np.array([0.1, 0.2]), "a", np.nan, 0.0, 30.0])
def test_model_error_covariance_refuses_a_bad_correlation(bad):
    with pytest.raises(ValueError, match=r"correlation must be .*\[1e-06, 6.28319\] \[rad\]"):
        dolp_model_error_covariance(TI, TI, correlation=bad)


@pytest.mark.parametrize("c", [1e-6, np.radians(20), 2 * np.pi])
def test_model_error_covariance_is_finite_across_the_correlation_range(c):
    C = dolp_model_error_covariance(TI, TI, correlation=c)
    assert np.all(np.isfinite(C)) and np.allclose(np.diag(C), dolp_model_error(TI, TI) ** 2)


def test_model_error_names_arguments_whose_shapes_do_not_broadcast():
    with pytest.raises(ValueError, match=r"theta_i\(4,\), theta_r\(3,\)"):
        dolp_model_error(TI, TI[:3])


# -- 3, 4 ------------------------------------------------------------------------------------------
def test_noise_bounds_must_lie_in_the_range_of_a_dolp_noise():
    with pytest.raises(ValueError, match=r"noise_bounds .*1e-12 <= low < high <= 1"):
        quick(Y, TI, TI, None, 0, sigma=0.3, noise_bounds=(1e-300, 1e-299))
    quick(Y, TI, TI, None, 0, sigma=0.3, noise_bounds=(1e-12, 1e-11))  # the edge works, no warning


def test_index_bounds_beyond_what_the_model_evaluates_are_refused():
    with pytest.raises(ValueError, match=r"bounds\['kappa'\] must have high <= 1e\+06"):
        fit_dolp(Y, TI, TI, bounds={"kappa": (0, 1e300)})
    with pytest.raises(ValueError, match=r"bounds\['n'\] must have high <= 1e\+06"):
        quick(Y, TI, TI, 0.01, 0, sigma=0.3, bounds={"n": (0, 1e7)})
    # the largest box is evaluated without overflow
    fit = fit_dolp(Y, TI, TI, bounds={"n": (0, 1e6), "kappa": (0, 1e6)}, starts=((1e6, 1e6),))
    assert np.isfinite(fit.cost)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(noise=0.01, systematic=1e200), r"systematic .*in \[0, 1\]"),
        (dict(covariance=np.eye(4) * 1e-300), r"covariance must have eigenvalues >= 1e-24"),
        (dict(covariance=np.eye(4) * 1e200), r"covariance must have variances"),
    ],
)
def test_fit_dolp_refuses_error_models_that_overflow(kw, match):
    with pytest.raises(ValueError, match=match):
        fit_dolp(Y, TI, TI, **kw)


def test_fit_dolp_at_the_edge_of_the_error_range_is_finite():
    fit = fit_dolp(Y, TI, TI, covariance=np.eye(4) * 1e-24)
    assert np.all(np.isfinite(fit.covariance))
    fit = fit_dolp(Y, TI, TI, noise=1.0, systematic=1.0)
    assert np.all(np.isfinite(fit.covariance))


def test_sample_posterior_refuses_a_huge_correlated_error():
    with pytest.raises(ValueError, match=r"correlated .*\|c\| <= 1"):
        quick(Y, TI, TI, 0.01, 0, sigma=0.3, correlated=np.full(4, 1e200))


def test_a_tiny_covariance_is_named_as_the_covariance_not_the_noise():
    with pytest.raises(ValueError, match=r"^covariance must have eigenvalues"):
        sample_posterior(Y, TI, TI, None, 0, covariance=np.eye(4) * 1e-300)


# -- 5 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["sigma", "noise"])
def test_fit_dolp_checks_per_pixel_shapes_before_fitting(name, monkeypatch):
    from scatterlab.inversion import least_squares

    def no_fit(*a, **kw):  # the shape is refused before any fit runs
        raise AssertionError("the fit ran")

    monkeypatch.setattr(least_squares, "_best_of_starts", no_fit)
    kw = {name: [0.2, 0.2, 0.2]}
    with pytest.raises(
        ValueError, match=rf"{name} must .*broadcasts to dolp's leading axes \(2,\)"
    ):
        fit_dolp(np.stack([Y, Y]), TI, TI, **kw)


# -- 6 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "bad, match",
    [(5.0, "square matrices"), ([1.0, 2.0], "square matrices"), ([[1, 5], [0, 1]], "symmetric")],
)
def test_inverse_information_validates_square_symmetric_matrices(bad, match):
    with pytest.raises(ValueError, match=rf"info must be {match}"):
        inverse_information(bad)


def test_inverse_information_accepts_rounding_asymmetry():
    A = np.array([[2.0, 1.0], [1.0 + 1e-15, 3.0]])
    cov, ok = inverse_information(A)
    assert ok.all() and np.allclose(cov, np.linalg.inv((A + A.T) / 2))


# -- 7 ---------------------------------------------------------------------------------------------
def test_chain_diagnostics_refuse_2d_chains():
    chain = np.random.default_rng(0).standard_normal((100, 4))
    with pytest.raises(ValueError, match=r"chain must be a 3-D array \(steps, walkers, P\)"):
        ensemble_rhat(chain, 2)
    with pytest.raises(ValueError, match=r"chain must be a 3-D array"):
        effective_sample_size(chain)


def test_chain_diagnostics_are_scale_invariant():
    chain = np.random.default_rng(0).standard_normal((200, 8, 2))
    for scale in (1e160, 1e-160):
        np.testing.assert_allclose(
            effective_sample_size(chain * scale), effective_sample_size(chain)
        )
        np.testing.assert_allclose(ensemble_rhat(chain * scale, 2), ensemble_rhat(chain, 2))


# -- 8 ---------------------------------------------------------------------------------------------
def test_forward_names_params_of_the_wrong_length():
    with pytest.raises(ValueError, match=r"params must have shape \(\.\.\., 3\)"):
        DolpForward(TI, TI)([1.5])
    with pytest.raises(ValueError, match=r"params must have shape \(\.\.\., 2\)"):
        DolpForward(TI, TI, sigma=0.3).value_and_jacobian([1.5, 0.1, 0.3])


@pytest.mark.parametrize("sigma", [1e-4, 5.0])
def test_forward_jacobian_at_the_models_sigma_range_is_one_sided(sigma):
    fwd = DolpForward(TI, TI)
    _, J = fwd.value_and_jacobian([1.5, 0.1, sigma])
    h = 1e-6 * sigma * (1 if sigma < 1 else -1)
    one_sided = (fwd([1.5, 0.1, sigma + h]) - fwd([1.5, 0.1, sigma])) / h
    np.testing.assert_allclose(J[:, 2], one_sided, rtol=1e-3, atol=1e-12)


# -- 9 ---------------------------------------------------------------------------------------------
def test_thilak_and_prior_inputs_of_the_wrong_type_are_value_errors():
    with pytest.raises(ValueError, match="n must be a single float"):
        thilak_crlb("a", 0.1, 0.5, TI, 0.01)
    with pytest.raises(ValueError, match="noise_bounds must be"):
        quick(Y, TI, TI, None, 0, sigma=0.3, noise_bounds="ab")
    with pytest.raises(
        ValueError, match=r"bounds must be \(\(n_lo, n_hi\), \(kappa_lo, kappa_hi\)\)"
    ):
        thilak_two_step(Y, TI, 0.5, 0, solver="trf", bounds=((0, 5), (0, 5), (0, 1)))


# -- 10, 11 ----------------------------------------------------------------------------------------
def glass_two_minima():
    """Glass (kappa = 0) at 8 specular angles with noise 0.005: two least-squares minima, the best
    at kappa 0.07 +/- 1 (information small, not singular), the other at kappa = 0 (singular)."""
    t = np.radians(np.linspace(20, 70, 8))
    y = model_dolp(1.5, 0.0, 0.2, t, t) + 0.005 * np.random.default_rng(4).standard_normal(8)
    return y, t


def test_messages_name_the_minimum_they_are_about():
    y, t = glass_two_minima()
    post = sample_posterior(y, t, t, 0.005, 1, n_steps=100)
    best = post.least_squares[0]
    assert len(post.least_squares) == 2 and np.all(np.isfinite(best.errors))
    undetermined = [m for m in post.messages if "do not determine" in m]
    # the statement about kappa's infinite variance is about the other minimum, and says so
    assert len(undetermined) == 1 and "minimum 2 of 2" in undetermined[0]
    assert "not the table's" in undetermined[0] and "on its bound 0" in undetermined[0]
    # the table's kappa is within its Laplace error of 0: said too, of the best minimum
    near = [m for m in post.messages if "within one error of the prior bound" in m]
    assert len(near) == 1 and "minimum 1 of 2" in near[0] and "kappa = 0" in near[0]
    if not post.multimodal:
        assert any(m.startswith("the posterior has one mode") for m in post.messages)


def test_report_states_the_priors_and_the_modes_beside_the_minima(tmp_path):
    from scatterlab.inversion.report import posterior_report

    y, t = glass_two_minima()
    post = sample_posterior(y, t, t, 0.005, 1, n_steps=100, bounds={"sigma": (0.02, 1.0)})
    text = posterior_report(post, tmp_path, rng=0).read_text()
    assert (
        "Priors: n uniform on [0, 5]; kappa uniform on [0, 25]; sigma uniform on [0.02, 1]; "
        "DOLP error known" in text
    )
    modes = "**multimodal** posterior" if post.multimodal else "one posterior mode"
    assert f"{modes} (from 2 least-squares minima, see the warnings)" in text
    post = sample_posterior(y, t, t, None, 1, n_steps=60, sigma=0.2, kappa_prior="log-uniform")
    text = posterior_report(post, tmp_path / "b", rng=0).read_text()
    assert "kappa log-uniform on [0.001, 25]; sigma known (0.2, not sampled); DOLP noise " in text
