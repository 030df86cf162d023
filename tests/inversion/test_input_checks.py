"""Issue 20 for the inversion: bad input is refused with a message naming the argument, and a design
that
cannot determine the parameters is reported as such (never a confident answer)."""

import warnings

import emcee
import numpy as np
import pytest

from scatterlab.inversion import (
    ConvergenceWarning,
    FitOptions,
    IdentifiabilityWarning,
    crlb,
    fit_dolp,
    inverse_information,
    model_dolp,
    sample_posterior,
)
from scatterlab.inversion.report import posterior_report

TI = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 45, 45, 45, 45])
TR = np.radians(np.r_[30, 35, 40, 45, 50, 55, 60, 20, 30, 60, 70])
PAINT = (1.39, 0.34, 0.3)


def quiet(*a, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return sample_posterior(*a, **kw)


def test_fit_options_and_the_old_keywords_are_the_same_fit():
    """FitOptions groups bounds, starts, sigma0, max_iter and tol; the keywords still work, giving
    one both ways or an unknown keyword is a ValueError naming it."""
    y = model_dolp(*PAINT, TI, TR)
    kw = dict(starts=((1.5, 0.05), (3.0, 4.0)), sigma0=0.2, max_iter=50, tol=1e-10)
    a = fit_dolp(y, TI, TR, **kw)
    b = fit_dolp(y, TI, TR, options=FitOptions(**kw))
    np.testing.assert_array_equal([a.n, a.kappa, a.sigma], [b.n, b.kappa, b.sigma])
    np.testing.assert_allclose([a.n, a.kappa, a.sigma], PAINT, rtol=1e-6)  # noise-free truth
    with pytest.raises(ValueError, match="starts"):
        fit_dolp(y, TI, TR, options=FitOptions(), starts=((1.5, 0.05),))
    with pytest.raises(ValueError, match="unknown keyword.*sigma_0"):
        fit_dolp(y, TI, TR, sigma_0=0.3)
    with pytest.raises(ValueError, match="max_iter"):
        fit_dolp(y, TI, TR, options=FitOptions(max_iter=0))


@pytest.mark.parametrize("bad", [1.5, -0.2, 1e300, np.inf, -np.inf])
def test_fit_dolp_refuses_dolp_outside_0_1_and_infinite_values(bad):
    y = model_dolp(*PAINT, TI, TR)
    y[3] = bad
    with pytest.raises(ValueError, match="dolp"):
        fit_dolp(y, TI, TR)


def test_fit_dolp_accepts_noise_margin_and_nan():
    y = model_dolp(*PAINT, TI, TR)
    y[0], y[1] = 1.0 + 0.04, np.nan  # within the 0.05 noise margin; NaN masks
    assert fit_dolp(y, TI, TR).valid
    y[0] = 1.08  # allowed only with a noise large enough to explain it (5 sd)
    with pytest.raises(ValueError, match="dolp"):
        fit_dolp(y, TI, TR)
    assert fit_dolp(y, TI, TR, noise=0.02).valid


@pytest.mark.parametrize("noise", [0.0, -1e-3, np.nan, np.inf, [1e-3, -1e-3], 1e-300, 1e300, 2.0])
def test_fit_dolp_refuses_bad_noise(noise):
    y = np.stack([model_dolp(*PAINT, TI, TR)] * 2)
    with pytest.raises(ValueError, match="noise"):
        fit_dolp(y, TI, TR, noise=noise)


def test_fit_dolp_refuses_empty_starts_and_misspelled_bounds():
    y = model_dolp(*PAINT, TI, TR)
    with pytest.raises(ValueError, match="starts"):
        fit_dolp(y, TI, TR, starts=())
    with pytest.raises(ValueError, match="starts"):
        fit_dolp(y, TI, TR, starts=(1.5,))
    with pytest.raises(ValueError, match=r"kapa.*allowed keys are \['kappa', 'n', 'sigma'\]"):
        fit_dolp(y, TI, TR, bounds={"kapa": (0.0, 5.0)})
    with pytest.raises(ValueError, match="geometries"):  # fewer geometries than unknowns
        fit_dolp(y[:2], TI[:2], TR[:2])


def test_seven_copies_of_one_geometry_determine_nothing():
    """Issue 20's reproducer: seven copies of the 45 deg geometry carry the information of one
    measurement,
    a rank-1 Fisher matrix, so none of the three parameters is determined (crlb inf). The fit used
    to report
    n = 0.207 +- 0.086; now every parameter is flagged and its variance is inf, with a warning."""
    ti = tr = np.full(7, np.radians(45.0))
    truth = (1.44, 16.0, 0.2)
    assert np.all(np.isinf(crlb(*truth, ti, tr, 1e-3)))
    y = model_dolp(*truth, ti, tr) + 1e-3 * np.random.default_rng(0).standard_normal(7)
    with pytest.warns(IdentifiabilityWarning, match="n, kappa, sigma"):
        fit = fit_dolp(y, ti, tr)
    assert not np.any(fit.identifiable)
    assert np.all(np.isinf(fit.errors))


def test_glass_kappa_zero_is_undetermined_but_n_and_sigma_keep_finite_errors():
    """At kappa = 0 the DOLP is stationary in kappa (zero information): kappa is flagged, while n
    and sigma
    keep the errors they would have with kappa known (the information is block-diagonal)."""
    y = model_dolp(1.5, 0.0, 0.4, TI, TR)
    with pytest.warns(IdentifiabilityWarning, match="kappa"):
        fit = fit_dolp(y, TI, TR, noise=1e-3)
    assert fit.identifiable.tolist() == [True, False, True]
    assert np.isinf(fit.errors[1]) and np.all(np.isfinite(fit.errors[[0, 2]]))
    np.testing.assert_allclose(
        fit.errors[[0, 2]], crlb(1.5, 0.0, 0.4, TI, TR, 1e-3)[[0, 2]], rtol=1e-3
    )


def test_inverse_information_against_hand_made_matrices():
    # full rank: the ordinary inverse
    A = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]])
    cov, ok = inverse_information(A)
    np.testing.assert_allclose(cov, np.linalg.inv(A), rtol=1e-12)
    assert ok.all()
    # rank 2, null direction (1, -1, 0): p0 and p1 undetermined, p2 determined with variance 1/2
    B = np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 2.0]])
    cov, ok = inverse_information(B)
    assert ok.tolist() == [False, False, True]
    assert np.isinf(cov[0, 0]) and np.isinf(cov[1, 1]) and np.isnan(cov[0, 2])
    np.testing.assert_allclose(cov[2, 2], 0.5)
    cov, ok = inverse_information(np.full((3, 3), np.nan))
    assert not ok.any() and np.all(np.isnan(cov))


def test_crlb_refuses_unphysical_truth_and_a_single_geometry():
    with pytest.raises(ValueError, match="n must"):
        crlb(-1.0, 0.3, 0.3, TI, TR, 1e-3)
    with pytest.raises(ValueError, match="kappa"):
        crlb(1.5, -0.3, 0.3, TI, TR, 1e-3)
    with pytest.raises(ValueError, match="geometries"):
        crlb(1.5, 0.3, 0.3, TI[:1], TR[:1], 1e-3)
    with pytest.raises(ValueError, match="noise"):
        crlb(1.5, 0.3, 0.3, TI, TR, np.nan)


def test_sample_posterior_refuses_bad_input():
    ti, tr = TI[:4], TR[:4]
    with pytest.raises(ValueError, match="dolp"):
        sample_posterior(np.full(4, 1.5), ti, tr, 0.01, 0)
    y = model_dolp(*PAINT, TI, TR)
    with pytest.raises(ValueError, match="n_steps"):
        sample_posterior(y, TI, TR, 0.01, 0, n_steps=1)
    with pytest.raises(ValueError, match="n_ensembles"):
        sample_posterior(y, TI, TR, 0.01, 0, n_ensembles=0)
    with pytest.raises(ValueError, match="moves"):
        sample_posterior(y, TI, TR, 0.01, 0, moves="gibbs")
    with pytest.raises(ValueError, match="unknown keyword"):
        sample_posterior(y, TI, TR, 0.01, 0, n_step=100)
    with pytest.raises(ValueError, match="kapa"):
        sample_posterior(y, TI, TR, 0.01, 0, bounds={"kapa": (0.0, 5.0)})
    with pytest.raises(ValueError, match="noise or covariance"):
        sample_posterior(y, TI, TR, 0.01, 0, covariance=np.eye(TI.size) * 1e-4)
    with pytest.raises(ValueError, match="positive definite"):
        sample_posterior(y, TI, TR, None, 0, covariance=-np.eye(TI.size))
    with pytest.raises(ValueError, match="systematic"):
        sample_posterior(y, TI, TR, 0.01, 0, systematic=-1e-3)
    with pytest.raises(ValueError, match="systematic"):
        sample_posterior(y, TI, TR, 0.01, 0, systematic=np.ones(3) * 1e-3)


def test_rng_takes_what_default_rng_takes_and_moves_and_backends_as_emcee_objects(tmp_path):
    y = model_dolp(*PAINT, TI, TR) + 2e-3 * np.random.default_rng(0).standard_normal(TI.size)
    a = quiet(y, TI, TR, 2e-3, 7, n_steps=60)
    b = quiet(y, TI, TR, 2e-3, np.random.default_rng(7), n_steps=60)
    np.testing.assert_array_equal(a.chain, b.chain)  # an int seed is default_rng(seed)
    moves = [(emcee.moves.StretchMove(a=1.5), 1.0)]
    backends = [emcee.backends.Backend(), emcee.backends.Backend()]
    c = quiet(y, TI, TR, 2e-3, 7, n_steps=60, moves=moves, backend=backends)
    assert backends[0].iteration == 60 and c.n_steps == 60
    d = quiet(y, TI, TR, 2e-3, 8, n_steps=90, moves=moves, backend=backends)  # resumes the objects
    assert backends[1].iteration == 90 and d.n_steps == 90
    with pytest.raises(ValueError, match="other data"):
        quiet(y + 1e-3, TI, TR, 2e-3, 8, n_steps=120, moves=moves, backend=backends)
    # the report takes rng too: the same seed gives the same predictive figure
    posterior_report(a, tmp_path / "1", "p", rng=3)
    posterior_report(a, tmp_path / "2", "p", rng=3)
    assert (tmp_path / "1" / "p_predictive.png").read_bytes() == (
        tmp_path / "2" / "p_predictive.png"
    ).read_bytes()


@pytest.mark.parametrize("noise", [1e-300, 1e300])
def test_crlb_and_the_sampler_refuse_a_noise_no_dolp_can_have(noise):
    """1e-300 overflowed in the whitened squares (divide warnings), 1e300 in the margin ('margin must be
    a non-negative float, got inf', naming an internal argument)."""
    from scatterlab.inversion import crlb, sample_posterior

    y = model_dolp(1.5, 0.1, 0.3, TI, TR)
    with pytest.raises(
        ValueError, match=r"noise must be a DOLP standard deviation in \[1e-12, 1\]"
    ):
        crlb(1.5, 0.1, 0.3, TI, TR, noise)
    with pytest.raises(
        ValueError, match=r"noise must be a DOLP standard deviation in \[1e-12, 1\]"
    ):
        sample_posterior(y, TI, TR, noise, 0, n_steps=20)
