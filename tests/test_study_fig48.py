"""Fig. 48 study: the standard error of the fitted D/r0 carries the phase screens' Monte-Carlo
scatter (delete-a-group jackknife over the screens)."""

from types import SimpleNamespace

import numpy as np

from scatterlab import study_runner
from scatterlab.imaging import circular_pupil

FIG48 = study_runner.discover()["fig48"].module


def _fit_with_errors(seed, d_r0, frames=100, n=64, R=32):
    """Short-exposure fit of one quick-mode simulation: (D/r0, jackknife s.e., Jacobian s.e.)."""
    ctx = SimpleNamespace(rng=np.random.default_rng(seed))
    otf_groups, _ = FIG48._frames(ctx, circular_pupil(n, R), n, R, 1.0 / d_r0, frames)
    fit, se_jac, _, _ = FIG48._fit_short(*FIG48._mtf_profile(otf_groups.sum(0), R))
    se_mc, _ = FIG48._jackknife(otf_groups, R)
    return fit, se_mc, se_jac


def test_jackknife_error_matches_the_seed_to_seed_scatter():
    # 16 independent simulations at the study's smallest D/r0 (quick mode's 100 screens): the
    # sample sd of the fits has a relative s.e. of 1/sqrt(2 * 15) = 18 %, so the jackknife
    # s.e. (RMS over the seeds) must match it within a factor 1.5 (about 2.3 of those s.e.)
    d_r0 = 7.9
    fits, se_mc, se_jac = np.array([_fit_with_errors(seed, d_r0) for seed in range(16)]).T
    sd = fits.std(ddof=1)
    rms_mc = np.sqrt(np.mean(se_mc**2))
    assert 1 / 1.5 < sd / rms_mc < 1.5, (sd, rms_mc)
    # the Jacobian error of one averaged profile (points taken as independent) misses most of it
    assert np.sqrt(np.mean(se_jac**2)) < sd / 2


def test_jackknife_is_zero_when_every_group_of_screens_agrees():
    # identical groups: leaving any one out leaves the mean OTF, hence the fit, unchanged
    ctx = SimpleNamespace(rng=np.random.default_rng(3))
    n, R = 64, 32
    one, _ = FIG48._frames(ctx, circular_pupil(n, R), n, R, 1.0 / 10.5, 10, groups=1)
    se, fits = FIG48._jackknife(np.repeat(one, FIG48.GROUPS, 0), R)
    assert len(fits) == FIG48.GROUPS
    assert se < 1e-9 * fits.mean()
