"""Blind deconvolution: Richardson-Lucy equivalence (scikit-image peer), monotone likelihood, improvement over
the degraded data, the MAP DOLP root against the companion matrix, classification, degenerate input."""

import numpy as np
import pytest

from scatterlab.deconvolution import (
    PRIOR_SETS,
    SuperGaussianPrior,
    adaptive_priors,
    blind_deconvolve,
    classification_errors,
    dolp_update,
    dolp_update_companion,
    evenly_spaced,
)
from scatterlab.imaging import ANGLES_0_45_90_135, channel_images, detect
from scatterlab.polarization import dolp


def gaussian_psf(shape, sd):
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    g = np.exp(-((yy - shape[0] // 2) ** 2 + (xx - shape[1] // 2) ** 2) / (2 * sd * sd))
    return g / g.sum()


def scene(n=48, rng=0):
    """Two-material object: DOLP 0.6 background (paint-like) and 0.05 blocks (metal-like), S0 of similar size."""
    rng = np.random.default_rng(rng)
    lab = np.zeros((n, n), int)
    lab[10:22, 8:40] = 1
    lab[28:40, 20:30] = 1
    s0 = np.where(lab == 1, 2.0, 1.0) * (1 + 0.05 * rng.standard_normal((n, n)))
    P = np.where(lab == 1, 0.05, 0.6)
    S = np.stack([s0, P * s0, np.zeros_like(s0)], axis=-1)  # (H, W, 3), Stokes axis last
    return S, lab, P


def test_known_psf_object_update_equals_richardson_lucy_of_scikit_image():
    """Unpolarized data, known PSF, periodic boundaries, object well inside the frame: our S0 / 2 after N
    iterations equals skimage.restoration.richardson_lucy(image, psf, N) (both start from 0.5)."""
    from skimage.restoration import richardson_lucy

    n = 64
    rng = np.random.default_rng(0)
    obj = np.zeros((n, n))
    obj[20:44, 20:44] = rng.uniform(1, 3, (24, 24))
    h = gaussian_psf((n, n), 1.5)
    h[np.hypot(*np.mgrid[-n // 2 : n // 2, -n // 2 : n // 2]) > 6] = 0
    h /= h.sum()
    from scatterlab.imaging import convolve

    img = convolve(obj, h) + 1e-3
    # scikit-image convolves with zero padding; wrapping the image by more than the 15 x 2 x 6 pixels the
    # iterations can carry the border makes its centre the periodic problem
    big = np.pad(img, 192, mode="wrap")
    ref = richardson_lucy(
        big,
        h[n // 2 - 6 : n // 2 + 7, n // 2 - 6 : n // 2 + 7],
        num_iter=15,
        clip=False,
        filter_epsilon=None,
    )[192:-192, 192:-192]
    # four identical unpolarized channels: i_n = h * S0/2, so S0/2 is the Richardson-Lucy estimate (start 0.5)
    res = blind_deconvolve(
        np.stack([img] * 4),
        ANGLES_0_45_90_135,
        psf0=h,
        psf_mode="fixed",
        iterations=15,
        boundary="periodic",
        s0_start=1.0,
        dolp_start=0.0,
    )
    np.testing.assert_allclose(res.s0[8:-8, 8:-8] / 2, ref[8:-8, 8:-8], rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("aop", [0.0, 0.4])
@pytest.mark.parametrize("boundary", ["periodic", "reeves"])
def test_stokes_basis_updates_equal_the_per_channel_updates(aop, boundary):
    """The shared-PSF fast path (2-3 Stokes-image transforms per convolution) against the per-channel form of
    Eq. 194 (K transforms): the same predicted images, E-step sums, S0 denominators and PSF correlation."""
    from scatterlab.deconvolution.em import _Ops, _PerChannel, _StokesBasis

    rng = np.random.default_rng(3)
    th = np.radians([0.0, 30.0, 90.0, 135.0])  # not evenly spaced on purpose
    ops = _Ops((24, 20), 5, boundary)
    Hp, Wp = ops.shape
    s0, P = rng.uniform(0.5, 2, (Hp, Wp)), rng.uniform(0, 1, (Hp, Wp))
    alpha = np.full((Hp, Wp), aop)
    h = gaussian_psf((Hp, Wp), 1.5)[None]
    d = rng.poisson(50, (4, 24, 20)).astype(float)
    one = np.zeros(4, int)
    fast, slow = _StokesBasis(ops, th, alpha, one), _PerChannel(ops, th, alpha, one)
    assert fast.J == (3 if aop else 2)
    sf, ss = fast.forward(h, s0, P), slow.forward(h, s0, P)
    np.testing.assert_allclose(sf.i, ss.i, rtol=1e-12)
    r = d / sf.i
    Tf, Qf, _, Rf = fast.estep(sf, r, s0, P)
    Ts, Qs, _, Rs = slow.estep(ss, r, s0, P)
    np.testing.assert_allclose(Tf, Ts, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(Qf, Qs, rtol=1e-10, atol=1e-12)
    w = ops.window_share(sf.Hf)
    np.testing.assert_allclose(fast.s0_denominator(w, P), slow.s0_denominator(w, P), rtol=1e-12)
    np.testing.assert_allclose(
        fast.psf_correlation(sf, Rf)[0], slow.psf_correlation(ss, Rs).sum(0), rtol=1e-10, atol=1e-12
    )


def test_multi_frame_stokes_basis_equals_channel_by_channel_convolution():
    """Two frames of four channels, each frame through its own PSF (Schulz's multi-frame data): the fast
    path's predicted images equal each channel convolved directly with its frame's PSF, and its E-step,
    S0 denominator and per-frame PSF correlations equal the per-channel form summed over each frame."""
    from scatterlab.deconvolution.em import _Ops, _PerChannel, _StokesBasis

    rng = np.random.default_rng(5)
    th = np.tile(np.radians([0.0, 45.0, 90.0, 135.0]), 2)
    group = np.repeat([0, 1], 4)
    ops = _Ops((24, 20), 5, "reeves")
    Hp, Wp = ops.shape
    s0, P = rng.uniform(0.5, 2, (Hp, Wp)), rng.uniform(0, 1, (Hp, Wp))
    alpha = np.zeros((Hp, Wp))
    h = np.stack([gaussian_psf((Hp, Wp), 1.2), gaussian_psf((Hp, Wp), 2.5)])
    fast, slow = _StokesBasis(ops, th, alpha, group), _PerChannel(ops, th, alpha, group)
    sf, ss = fast.forward(h, s0, P), slow.forward(h, s0, P)
    # independent check: each channel object convolved (FFT, periodic on the object grid) with its PSF
    o = 0.5 * s0[None] * (1 + P[None] * np.cos(2 * th)[:, None, None])
    direct = np.real(
        np.fft.ifft2(np.fft.fft2(o) * np.fft.fft2(np.fft.ifftshift(h[group], axes=(-2, -1))))
    )
    np.testing.assert_allclose(sf.i, ops.crop(direct), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ss.i, sf.i, rtol=1e-12)
    r = rng.poisson(50, (8, 24, 20)) / sf.i
    Tf, Qf, _, Rf = fast.estep(sf, r, s0, P)
    Ts, Qs, _, Rs = slow.estep(ss, r, s0, P)
    np.testing.assert_allclose(Tf, Ts, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(Qf, Qs, rtol=1e-10, atol=1e-12)
    w = ops.window_share(sf.Hf)
    assert w.shape == (2, Hp, Wp)
    np.testing.assert_allclose(fast.s0_denominator(w, P), slow.s0_denominator(w, P), rtol=1e-12)
    per_channel = slow.psf_correlation(ss, Rs)
    np.testing.assert_allclose(
        fast.psf_correlation(sf, Rf),
        np.stack([per_channel[:4].sum(0), per_channel[4:].sum(0)]),
        rtol=1e-10,
        atol=1e-12,
    )


def test_log_likelihood_never_decreases_and_deconvolution_beats_degraded_data():
    S, lab, P = scene()
    rng = np.random.default_rng(1)
    h = gaussian_psf(S.shape[:2], 2.0)
    counts = detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=5e3)
    from scatterlab.imaging import stokes_from_channels

    Sd = stokes_from_channels(counts, ANGLES_0_45_90_135)
    P_deg = np.clip(np.nan_to_num(dolp(Sd)), 0, 1)
    res = blind_deconvolve(counts, ANGLES_0_45_90_135, iterations=80, psf_radius=8)
    L = res.loglik
    assert np.all(np.diff(L) >= -1e-10 * np.abs(L[1:]))
    err_deg = np.sqrt(np.mean((P_deg - P) ** 2))
    err_dec = np.sqrt(np.mean((res.dolp - P) ** 2))
    assert err_dec < 0.9 * err_deg, (err_deg, err_dec)  # measured 0.081 against 0.099
    s0_true = S[..., 0] * counts.sum() / channel_images(S, ANGLES_0_45_90_135).sum()
    e_deg = np.sqrt(np.mean((Sd[..., 0] - s0_true) ** 2))
    e_dec = np.sqrt(np.mean((res.s0 - s0_true) ** 2))
    assert e_dec < e_deg
    # no trivial solution: the PSF keeps unit sum inside its support, the object is not a point
    assert np.isclose(res.psfs.sum(), 1.0) and res.s0.std() < 10 * S[..., 0].std() * counts.max()


def test_classification_with_chapter_v_priors_beats_the_degraded_dolp_threshold():
    S, lab, P = scene()
    rng = np.random.default_rng(2)
    h = gaussian_psf(S.shape[:2], 2.0)
    counts = detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=5e3)
    res = blind_deconvolve(
        counts, ANGLES_0_45_90_135, iterations=60, psf_radius=8, priors=PRIOR_SETS["ch5"]
    )
    ours = classification_errors(res.classes, lab)
    from scatterlab.imaging import stokes_from_channels

    Sd = stokes_from_channels(counts, ANGLES_0_45_90_135)
    naive = (np.nan_to_num(dolp(Sd)) < 0.3).astype(int)
    base = classification_errors(naive, lab)
    assert ours["total_error"] < base["total_error"]
    assert ours["total_error"] < 0.1


@pytest.mark.parametrize("prior", list(PRIOR_SETS["ch6"]) + list(PRIOR_SETS["ch5"]))
def test_map_dolp_root_matches_the_companion_matrix(prior):
    """Including the aluminium-group prior, c2^m = 35^10 ~ 2.8e15, and photon totals from 1 to 1e6."""
    rng = np.random.default_rng(3)
    T = 10 ** rng.uniform(0, 6, 40)
    Q = T * rng.uniform(0, 1, 40)
    ours = dolp_update(T, Q, prior)
    ref = np.array([dolp_update_companion(t, q, prior) for t, q in zip(T, Q)])
    np.testing.assert_allclose(ours, ref, atol=1e-9)
    assert np.all((ours >= 0) & (ours <= 1))


def test_ml_update_and_zero_photon_pixels():
    np.testing.assert_allclose(
        dolp_update(np.array([10.0, 4.0]), np.array([5.0, 1.0])), [0.5, 0.25]
    )
    out = dolp_update(np.array([0.0, 0.0]), np.array([0.0, 0.0]), PRIOR_SETS["ch5"][1])
    np.testing.assert_allclose(out, 0.15)
    S, lab, P = scene(32)
    counts = detect(channel_images(S, ANGLES_0_45_90_135), 0, photons=50)
    counts[:, :8] = 0.0  # a dark stripe: no photons at all
    res = blind_deconvolve(
        counts, ANGLES_0_45_90_135, iterations=10, psf_radius=4, priors=PRIOR_SETS["ch5"]
    )
    for a in (res.s0, res.dolp, res.psfs):
        assert np.all(np.isfinite(a))
    assert res.s0.min() >= 0  # no negative light where there were no photons
    half = np.full((4, 32, 32), 100.0)
    half[:, :, :16] = (
        0.0  # half the field dark: round-off of the FFT correlations must not go below 0
    )
    res = blind_deconvolve(half, ANGLES_0_45_90_135, psf_radius=4, iterations=5)
    assert res.s0.min() >= 0 and np.all(np.isfinite(res.s0))


def test_adaptive_priors_recentre_on_the_histogram():
    rng = np.random.default_rng(0)
    v = np.r_[
        rng.normal(0.05, 0.01, 500), rng.normal(0.25, 0.03, 500)
    ]  # near-normal: weak dielectric DOLP
    die, met = adaptive_priors(v)
    assert abs(die.c3 - 0.25) < 0.02 and abs(met.c3 - 0.05) < 0.01
    assert die.name == "dielectric" and met.name == "metal"


def test_adaptive_priors_refuse_a_dolp_image_without_contrast():
    """A constant DOLP image made scipy's two-means warn "One of the clusters is empty" and returned two
    identical priors (a near-constant one, two priors 1e-9 apart): nothing separates two classes there.
    A ValueError says so (and names dolp); a mostly constant image with a few other pixels still splits,
    without the warning."""
    import warnings

    rng = np.random.default_rng(1)
    for flat in (
        np.full((16, 16), 0.3),
        0.3 + 1e-9 * rng.standard_normal(256),
        0.3 + 1e-3 * rng.standard_normal(256),
    ):
        with pytest.raises(ValueError, match="dolp has no contrast to separate classes"):
            adaptive_priors(flat)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        die, met = adaptive_priors(np.r_[np.full(90, 0.3), np.full(10, 0.5)])
    assert die.c3 == pytest.approx(0.5) and met.c3 == pytest.approx(0.3)


def test_angles_and_bad_input():
    assert evenly_spaced(ANGLES_0_45_90_135) and evenly_spaced(np.radians([0, 60, 120]))
    assert not evenly_spaced(np.radians([0, 45, 90]))
    d = np.ones((4, 16, 16))
    with pytest.raises(ValueError, match="angles"):
        blind_deconvolve(d, ANGLES_0_45_90_135[:3])
    with pytest.raises(ValueError, match="shape"):
        blind_deconvolve(np.ones((16, 16)), ANGLES_0_45_90_135)
    with pytest.raises(ValueError, match="finite"):
        bad = d.copy()
        bad[0, 0, 0] = np.nan
        blind_deconvolve(bad, ANGLES_0_45_90_135)
    with pytest.raises(ValueError, match="psf0"):
        blind_deconvolve(d, ANGLES_0_45_90_135, psf_mode="fixed")
    with pytest.raises(ValueError, match="even"):
        SuperGaussianPrior(3.0, 0.5, m=9)


def test_prior_thresholds_and_initial_psf():
    """classify_dolp reproduces the Ch. V threshold (P < 0.30 metal, the DOLP of equal prior probability);
    the Sec. 5.3.2 start PSF has unit sum and is wider than the diffraction-limited PSF."""
    from scatterlab.deconvolution import classify_dolp, initial_psf, object_grid
    from scatterlab.imaging import circular_pupil, psf

    ch5 = PRIOR_SETS["ch5"]  # (dielectric, metal)
    np.testing.assert_array_equal(
        classify_dolp([0.0, 0.2, 0.29, 0.31, 0.6, 1.0], ch5), [1, 1, 1, 0, 0, 0]
    )
    # three classes (Ch. VI): aluminium near 0.035, iron near 0.185, dielectric above
    np.testing.assert_array_equal(classify_dolp([0.02, 0.19, 0.7], PRIOR_SETS["ch6"]), [1, 2, 0])
    pupil = circular_pupil(32, 16)
    shape = object_grid((64, 64))
    h0 = initial_psf(pupil, shape, rng=1)
    assert h0.shape == shape == (96, 96) and np.isclose(h0.sum(), 1.0) and h0.min() >= 0
    yy, xx = np.mgrid[0:96, 0:96] - 48

    def spread(h):
        return np.sqrt(np.sum(h * (yy**2 + xx**2)) / h.sum())

    from scatterlab.deconvolution.psf_update import resample_psf

    assert spread(h0) > 2 * spread(resample_psf(psf(pupil, pad=2), shape))
    with pytest.raises(ValueError, match="d_over_r0"):
        initial_psf(pupil, shape, d_over_r0=0)
    # an empty pupil was refused as "r0 must be > 0" (the screen's r0 follows from the pupil's diameter)
    for empty in (np.zeros((32, 32)), -pupil, np.full((32, 32), np.nan)):
        with pytest.raises(ValueError, match="pupil must have at least one sample > 0"):
            initial_psf(empty, shape)


def test_object_grid_and_gerchberg_saxton_refuse_bad_sizes():
    """object_grid((-4, 32)) returned (-4 + 2 pad, 32 + 2 pad); gerchberg_saxton(steps=-1) ran no step,
    silently. Each is a ValueError naming the argument and its range."""
    from scatterlab.deconvolution import gerchberg_saxton, object_grid

    for bad in ((-4, 32), (0, 32), (32.0, 32), (32,), 32, (32, 32, 3)):
        with pytest.raises(ValueError, match="data_shape must be .* integers >= 1"):
            object_grid(bad)
    for bad in (-1, 0, np.nan, np.inf):
        with pytest.raises(ValueError, match="psf_radius must be"):
            object_grid((32, 32), bad)
    for bad in (-1, 2.5):
        with pytest.raises(ValueError, match="pad must be an integer >= 0"):
            object_grid((32, 32), pad=bad)
    assert object_grid((32, 48), 4) == (40, 56) and object_grid((32, 48), pad=0) == (32, 48)
    assert object_grid((np.int64(32), 48), 4, boundary="periodic") == (32, 48)
    A = np.ones((4, 4))
    h = np.full((1, 8, 8), 1 / 64)
    for bad in (-1, 2.5, True):
        with pytest.raises(ValueError, match="steps must be an integer >= 0"):
            gerchberg_saxton(h, A, np.zeros((1, 4, 4)), (8, 8), bad)
    # 0 steps: the PSFs of the starting phases
    psfs, phases = gerchberg_saxton(h, A, np.zeros((1, 4, 4)), (8, 8), 0)
    assert np.isclose(psfs.sum(), 1) and np.all(phases == 0)


def test_saturated_pixels_are_masked_out_of_the_likelihood():
    """A glint clipped at the full well: trusting the clipped counts loses its flux; masked (saturation=...)
    the clipped pixels leave the likelihood like the Reeves border and the glint's flux is inferred from the
    light it spills into unsaturated pixels. (The price, measured: the unconstrained core adds variance, about
    1.5x the unsaturated-pixel S0 error here.) The log-likelihood stays monotone; bad masks are named."""
    S, lab, P = scene()
    S = S.copy()
    S[20:26, 20:26] *= 8.0
    rng = np.random.default_rng(4)
    h = gaussian_psf(S.shape[:2], 1.5)
    clean = detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=4e3)
    full_well = 0.4 * clean.max()
    counts = np.minimum(clean, full_well)
    sat = np.any(counts >= full_well, axis=0)
    kw = dict(psf0=_grid_psf(h, 6), psf_mode="fixed", iterations=40, psf_radius=6)
    naive = blind_deconvolve(counts, ANGLES_0_45_90_135, **kw)
    masked = blind_deconvolve(counts, ANGLES_0_45_90_135, saturation=full_well, **kw)
    assert any("masked" in n for n in masked.notes)
    assert np.all(np.diff(masked.loglik) >= -1e-10 * np.abs(masked.loglik[1:]))
    truth = S[..., 0] * clean.sum() / channel_images(S, ANGLES_0_45_90_135, h).sum()
    flux = [r.s0[sat].sum() / truth[sat].sum() for r in (naive, masked)]  # measured 0.72 and 0.85
    assert abs(flux[1] - 1) < abs(flux[0] - 1), flux
    assert np.all(np.isfinite(masked.s0)) and np.all(np.isfinite(masked.dolp))
    with pytest.raises(ValueError, match="mask"):
        blind_deconvolve(counts, ANGLES_0_45_90_135, mask=np.ones((3, 3), bool))
    with pytest.raises(ValueError, match="saturation"):
        blind_deconvolve(counts, ANGLES_0_45_90_135, saturation=-1.0)


def test_censored_mean_and_survival_match_the_poisson_law():
    """E[d | d >= c] and ln P(d >= c) of the normal approximation against scipy's exact Poisson law at
    full-well counts, and finite, ordered values far from c (independent truth: scipy.stats.poisson)."""
    from scipy import stats

    from scatterlab.deconvolution.em import censored_log_survival, censored_mean

    c = 1e5
    for lam in (99_000.0, 99_700.0, 100_000.0, 100_300.0, 101_000.0):
        k = np.arange(int(c), int(c + 60 * np.sqrt(c)))
        pk = stats.poisson.pmf(k, lam)
        exact = (k * pk).sum() / pk.sum()
        # the excess over c is what the E-step adds: right to a few per cent of it
        assert censored_mean(lam, c) - c == pytest.approx(exact - c, rel=0.05), lam
        assert censored_log_survival(lam, c) == pytest.approx(
            stats.poisson.logsf(c - 1, lam), abs=0.03
        )
    lam = np.array([0.0, 1.0, 1e3, 5e4, 1e5, 2e5, 1e12])
    m, L = censored_mean(lam, c), censored_log_survival(lam, c)
    assert np.all(np.isfinite(m)) and np.all(np.isfinite(L)) and np.all(m >= c) and np.all(L <= 0)
    assert m[-1] == lam[-1] and L[-1] == 0.0 and np.all(np.diff(L) >= 0)


def test_saturated_pixels_censored_keep_their_light():
    """A bright unpolarized disc beside polarized paint, clipped at a full well: kept as they are, the
    clipped counts lose the disc's light and leave its halo on the paint; masked, the disc's light is
    left to guesswork; censored ('at least the full well'), the restoration keeps more of both
    (independent truth: the simulated object). The log-likelihood, with the censored terms, is
    monotone."""
    from scatterlab.deconvolution import object_grid, resample_psf
    from scatterlab.imaging import circular_pupil, psf

    n = 64
    yy, xx = np.mgrid[:n, :n]
    r = np.hypot(yy - 32, xx - 24)
    disc = r < 8
    s0 = np.where(disc, 2e5, 1.2e4)
    P = np.where(disc, 0.05, 0.85)
    h = psf(circular_pupil(32, 16), pad=2)  # 2 pixels per lambda/D
    clean = channel_images(np.stack([s0, s0 * P, 0 * s0], -1), ANGLES_0_45_90_135, h)
    counts = np.random.default_rng(0).poisson(np.clip(clean, 0, None)).astype(float)
    full_well = 3e4
    clipped = np.minimum(counts, full_well)
    radius, pad = np.sqrt(2) * n / 2, n // 2
    kw = dict(
        psf0=resample_psf(h, object_grid((n, n), radius, pad=pad)),
        psf_mode="fixed",
        iterations=300,
        psf_radius=radius,
        pad=pad,
    )
    paint = ~disc & (r > 10) & (r < 16)  # the paint in the disc's halo
    runs = {
        "kept": blind_deconvolve(clipped, ANGLES_0_45_90_135, **kw),
        "masked": blind_deconvolve(clipped, ANGLES_0_45_90_135, saturation=full_well, **kw),
        "censored": blind_deconvolve(clipped, ANGLES_0_45_90_135, censor=full_well, **kw),
    }
    flux = {k: v.s0[disc].sum() / s0[disc].sum() for k, v in runs.items()}
    err = {k: np.median(np.abs(v.dolp[paint] - 0.85)) for k, v in runs.items()}
    # measured: flux 0.33 / 0.14 / 0.44, paint DOLP error 0.051 / 0.089 / 0.046
    assert flux["censored"] > max(flux["kept"], flux["masked"]), flux
    assert err["censored"] < min(err["kept"], err["masked"]), err
    cens = runs["censored"]
    assert any("censored" in note for note in cens.notes)
    assert np.all(np.diff(cens.loglik) >= -1e-10 * np.abs(cens.loglik[1:]))
    assert np.all(np.isfinite(cens.s0)) and np.all(np.isfinite(cens.dolp))
    with pytest.raises(ValueError, match="censor .* must be a number > 0"):
        blind_deconvolve(clipped, ANGLES_0_45_90_135, censor=-1.0)
    with pytest.raises(ValueError, match="not 'phase'"):
        blind_deconvolve(clipped, ANGLES_0_45_90_135, censor=full_well, psf_mode="phase")


def _grid_psf(h, pad):
    """The centred PSF h (H, W) placed on the Reeves object grid (H + 2 pad, W + 2 pad)."""
    return np.pad(h, pad)


def test_gerchberg_saxton_recovers_a_realizable_psf_and_pupil_mode_is_monotone():
    """A PSF an aperture can form, |F{A exp(j phi)}|^2, is a fixed point of the projection (Eqs. 146-150):
    Gerchberg-Saxton from a flat phase reaches it (L1 error 5e-11 after 200 steps, falling with the steps).
    In blind_deconvolve's pupil mode the projected PSF steps are kept only when the likelihood rises, so the
    log-likelihood never decreases, and the estimated PSF ends closer to the true one than its start."""
    from scatterlab.deconvolution import gerchberg_saxton, initial_psf, object_grid, resample_psf
    from scatterlab.imaging import circular_pupil, phase_screen, psf, remove_piston_tilt

    A = circular_pupil(32, 16)
    phase = remove_piston_tilt(phase_screen(32, 1.0, 8.0, np.random.default_rng(0)), A > 0)
    h = psf(A, phase, pad=2)
    errs = [
        np.abs(gerchberg_saxton(h[None], A, np.zeros((1, 32, 32)), (64, 64), k)[0][0] - h).sum()
        for k in (5, 50, 200)
    ]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-6, errs

    S, lab, P = scene(64)
    rng = np.random.default_rng(5)
    counts = detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=5e3)
    grid = object_grid((64, 64), 12)
    psf0 = initial_psf(A, grid, rng=3)
    res = blind_deconvolve(
        counts,
        ANGLES_0_45_90_135,
        psf0=psf0,
        pupil=A,
        psf_mode="pupil",
        iterations=30,
        psf_radius=12,
    )
    L = res.loglik
    assert np.all(np.diff(L) >= -1e-10 * np.abs(L[1:]))
    truth = resample_psf(h, grid)
    assert np.abs(res.psfs[0] - truth).sum() < np.abs(psf0 - truth).sum()


def test_em_recovers_a_small_dolp_exactly_with_the_aop_known():
    """A metal's DOLP of 0.005 (noise-free, no blur): EM barely moves a DOLP near 0, so its start must be
    unbiased; with the AOP known the signed Stokes projection starts it at the truth (a 0.02 floor left it at
    0.012 after 100 iterations). Independent truth: the object's own DOLP."""
    from scatterlab.deconvolution import blind_deconvolve, object_grid
    from scatterlab.imaging import ANGLES_0_45_90_135, channel_images

    S = np.zeros((32, 32, 3))
    S[..., 0], S[..., 1] = 1e5, 0.005 * 1e5
    g = object_grid((32, 32), 8)
    h = np.zeros(g)
    h[g[0] // 2, g[1] // 2] = 1
    res = blind_deconvolve(
        channel_images(S, ANGLES_0_45_90_135),
        ANGLES_0_45_90_135,
        psf0=h,
        psf_mode="fixed",
        psf_radius=8,
        iterations=100,
    )
    np.testing.assert_allclose(res.dolp, 0.005, rtol=1e-9)


def _two_bars(n=24, aops_deg=(2.0, -83.0)):
    """Two fully polarized bars on a dark field (LeMaster and Cain's object), Stokes (n, n, 3)."""
    from scatterlab.polarization import stokes_vector

    lab = np.zeros((n, n), int)
    lab[5:9, 4:20] = 1
    lab[14:18, 4:20] = 2
    S = np.zeros((n, n, 3))
    for k, a in enumerate(aops_deg, start=1):
        S[lab == k] = stokes_vector(1.0, 1.0, np.radians(a))[:3]
    S[..., 0] += 0.05  # and a faint unpolarized field
    return lab, S


@pytest.mark.parametrize("angles_deg", [(0.0, 60.0, -60.0), (0.0, 45.0, 90.0, 135.0)])
def test_estimated_aop_recovers_the_object_aop_where_the_geometry_does_not_fix_it(angles_deg):
    """Noise-free channels, known (delta) PSF: the AOP M-step returns the object's own AOP (2 and -83 deg,
    LeMaster and Cain's bars) to 0.2 deg -- the M-step's resolution: a 1-deg grid refined by a parabola
    through three points of a non-quadratic objective (measured 0.10 deg at 0/45/90/135, less at
    0/60/-60); the fixed-AOP model with its default AOP 0 cannot fit the -83 deg bar (lower likelihood)."""
    from scatterlab.deconvolution import object_grid
    from scatterlab.polarization import aop as stokes_aop

    lab, S = _two_bars()
    th = np.radians(angles_deg)
    counts = 1e4 * channel_images(S, th)
    g = object_grid((24, 24), 4)
    h = np.zeros(g)
    h[g[0] // 2, g[1] // 2] = 1
    kw = dict(psf0=h, psf_mode="fixed", psf_radius=4, iterations=30)
    est = blind_deconvolve(counts, th, estimate_aop=True, **kw)
    truth = stokes_aop(S)
    for k in (1, 2):
        err = (est.aop[lab == k] - truth[lab == k] + np.pi / 2) % np.pi - np.pi / 2
        assert np.max(np.abs(np.degrees(err))) < 0.2, (k, np.degrees(err).max())
    fixed = blind_deconvolve(counts, th, **kw)
    assert est.loglik[-1] > fixed.loglik[-1]
    np.testing.assert_array_equal(fixed.aop, 0.0)


def test_aop_start_and_callback():
    """An explicit ``aop`` is the start of the estimate (not overwritten by the data's AOP); the callback
    sees every iteration and leaves the run unchanged."""
    lab, S = _two_bars()
    th = np.radians([0.0, 60.0, -60.0])
    counts = 1e3 * channel_images(S, th)
    seen = []
    a = blind_deconvolve(counts, th, estimate_aop=True, iterations=0, aop=0.3)
    np.testing.assert_array_equal(a.aop, 0.3)
    b = blind_deconvolve(counts, th, estimate_aop=True, iterations=3, callback=seen.append)
    c = blind_deconvolve(counts, th, estimate_aop=True, iterations=3)
    assert [r.iterations for r in seen] == [1, 2, 3]
    np.testing.assert_array_equal(seen[-1].aop, c.aop)
    np.testing.assert_array_equal(b.s0, c.s0)


def test_frames_and_phase_mode_bad_input():
    d = np.ones((8, 16, 16))
    th = np.tile(ANGLES_0_45_90_135, 2)
    with pytest.raises(ValueError, match="frames"):
        blind_deconvolve(d, th, frames=3)
    with pytest.raises(ValueError, match="frames"):
        blind_deconvolve(d, th, frames=0)
    with pytest.raises(ValueError, match="frames"):
        blind_deconvolve(d, th, frames=True)
    with pytest.raises(ValueError, match="psf0 must have shape"):
        blind_deconvolve(d, th, frames=2, psf_mode="fixed", psf0=np.ones((1, 2, 24, 24)))
    with pytest.raises(ValueError, match="psf0 holds 3 PSFs"):
        blind_deconvolve(d, th, frames=2, psf_mode="fixed", psf0=np.ones((3, 24, 24)))
    with pytest.raises(ValueError, match="pupil"):
        blind_deconvolve(d, th, psf_mode="phase")
    with pytest.raises(ValueError, match="shared_psf"):
        blind_deconvolve(d, th, psf_mode="phase", pupil=np.ones((8, 8)), shared_psf=False)


def test_two_frames_with_complementary_blurs_restore_what_neither_frame_can():
    """Schulz's multi-frame diversity with known PSFs: one frame blurred along the rows by a 7-pixel box, one
    along the columns. Each box has zeros in its transfer function (frequencies 1/7, 2/7, ... along its own
    axis), so neither frame alone carries those frequencies; together they do. The joint restoration of
    both frames (one object, one PSF per frame) is much closer to the object than either frame's."""
    S, lab, P = scene(48, rng=2)
    rng = np.random.default_rng(4)
    n = 48
    row, col = np.zeros((n, n)), np.zeros((n, n))
    row[n // 2, n // 2 - 3 : n // 2 + 4] = 1 / 7
    col[n // 2 - 3 : n // 2 + 4, n // 2] = 1 / 7
    frames = [
        detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=1e5) for h in (row, col)
    ]
    th2 = np.tile(ANGLES_0_45_90_135, 2)
    kw = dict(psf_mode="fixed", boundary="periodic", iterations=300)
    joint = blind_deconvolve(np.concatenate(frames), th2, frames=2, psf0=np.stack([row, col]), **kw)
    singles = [
        blind_deconvolve(f, ANGLES_0_45_90_135, psf0=h, **kw) for f, h in zip(frames, (row, col))
    ]
    truth = S[..., 0] / S[..., 0].mean()

    def err(s0):
        return np.sqrt(np.mean((s0 / s0.mean() - truth) ** 2))

    e_joint, e_single = err(joint.s0), min(err(r.s0) for r in singles)
    assert joint.psfs.shape == (2, n, n)
    assert not any("evenly" in note for note in joint.notes)  # each frame's 0/45/90/135 deg is even
    assert e_joint < 0.5 * e_single, (e_joint, e_single)


def test_phase_mode_fits_a_pupil_phase_to_a_known_object_and_never_lowers_the_likelihood():
    """PSF-only estimation (object held at the truth): the pupil phases maximizing the likelihood by L-BFGS
    on its analytic gradient (checked against finite differences in the docstring's chain rule) bring the
    PSF closer to the true one than its start, and the log-likelihood never decreases."""
    from scatterlab.deconvolution import initial_psf, object_grid, resample_psf
    from scatterlab.imaging import circular_pupil, phase_screen, psf, remove_piston_tilt

    A = circular_pupil(16, 8)
    phase = remove_piston_tilt(phase_screen(16, 1.0, 4.0, np.random.default_rng(1)), A > 0)
    h = psf(A, phase, pad=2)
    S, lab, P = scene(48, rng=3)
    rng = np.random.default_rng(6)
    counts = detect(
        channel_images(S, ANGLES_0_45_90_135, resample_psf(h, (48, 48))), rng, photons=1e5
    )
    grid = object_grid((48, 48), 12, boundary="periodic")
    psf0 = initial_psf(A, grid, rng=8)
    # counts per unit S0: the four channels sum to 2 S0
    scale = counts.sum() / (2 * S[..., 0].sum())
    res = blind_deconvolve(
        counts,
        ANGLES_0_45_90_135,
        psf0=psf0,
        pupil=A,
        psf_mode="phase",
        psf_radius=12,
        iterations=20,
        gs_steps=10,
        boundary="periodic",
        update_object=False,
        s0_start=S[..., 0] * scale,
        dolp_start=P,
    )
    L = res.loglik
    assert np.all(np.diff(L) >= -1e-10 * np.abs(L[1:]))
    truth = resample_psf(h, grid)
    e_end, e_start = np.abs(res.psfs[0] - truth).sum(), np.abs(psf0 - truth).sum()
    assert e_end < 0.5 * e_start, (e_start, e_end)


@pytest.mark.parametrize("boundary,masked,aop", [("periodic", False, 0.0), ("reeves", True, 0.3)])
def test_phase_gradient_matches_finite_differences(boundary, masked, aop):
    """The L-BFGS gradient of psf_mode="phase": dL/dh of one frame's Poisson log-likelihood
    (``frame_loglik``, with Reeves padding and masked pixels) composed with dL/dphi of the pupil model
    (``PupilPhasePSF.gradient``, with the unit-sum normalisation over the support) against central
    differences of the log-likelihood itself; and that log-likelihood against the whole model's
    prediction for that frame."""
    from scatterlab.deconvolution.em import _Ops, _StokesBasis
    from scatterlab.deconvolution.psf_update import PupilPhasePSF
    from scatterlab.imaging import circular_pupil

    rng = np.random.default_rng(0)
    H, W = 24, 20
    valid = np.ones((H, W), bool)
    if masked:
        valid[3:7, 5:9] = False
    ops = _Ops((H, W), 5 if boundary == "reeves" else 0, boundary, valid if masked else None)
    Hp, Wp = ops.shape
    yy, xx = np.mgrid[0:Hp, 0:Wp]
    support = np.hypot(yy - Hp // 2, xx - Wp // 2) <= 6
    th = np.tile(ANGLES_0_45_90_135, 2)
    model = _StokesBasis(ops, th, np.full((Hp, Wp), aop), np.repeat([0, 1], 4))
    A = circular_pupil(12, 5)
    pp = PupilPhasePSF(A, (Hp, Wp), support)
    s0, P = rng.uniform(50, 200, (Hp, Wp)), rng.uniform(0, 1, (Hp, Wp))
    Bf = model.object_spectra(s0, P)
    h_true = pp.psf(rng.normal(0, 1, A.shape) * (A > 0))
    d = rng.poisson(model.forward(np.stack([h_true, h_true]), s0, P).i).astype(float) * valid
    ph = rng.normal(0, 1, A.shape) * (A > 0)

    def loglik(phase):
        return model.frame_loglik(1, ops.otf(pp.psf(phase)), Bf, d[4:], valid)

    L0, G = loglik(ph)
    grad = pp.gradient(ph, G)
    inside = np.argwhere(A > 0)
    for a, b in inside[rng.choice(len(inside), 8, replace=False)]:
        step = np.zeros_like(ph)
        step[a, b] = 1e-5
        fd = (loglik(ph + step)[0] - loglik(ph - step)[0]) / 2e-5
        assert fd == pytest.approx(grad[a, b], rel=1e-4, abs=1e-6 * np.abs(grad).max())
    i = model.forward(np.stack([h_true, pp.psf(ph)]), s0, P).i[4:]
    assert L0 == pytest.approx(float(np.vdot(d[4:], np.log(i)) - np.sum(i * valid)), rel=1e-12)


@pytest.mark.parametrize("mode", ["em", "phase"])
def test_a_lost_exposure_keeps_its_psf_and_leaves_the_other_frame_intact(mode):
    """A frame with no photons (a lost exposure) carries no information on its PSF, which keeps its start;
    the estimate stays finite. With periodic boundaries the ML object then explains the other frame's
    photons spread over both exposures: the same DOLP as from that frame alone, and half its S0."""
    from scatterlab.imaging import circular_pupil

    S, lab, P = scene(32, rng=4)
    rng = np.random.default_rng(2)
    h = gaussian_psf((32, 32), 1.5)
    good = detect(channel_images(S, ANGLES_0_45_90_135, h), rng, photons=2e4)
    data = np.concatenate([good, np.zeros_like(good)])
    A = circular_pupil(16, 8)
    kw = dict(boundary="periodic", psf_radius=8, iterations=15, pupil=A, psf_mode=mode)
    both = blind_deconvolve(data, np.tile(ANGLES_0_45_90_135, 2), frames=2, **kw)
    alone = blind_deconvolve(good, ANGLES_0_45_90_135, **kw)
    start = blind_deconvolve(
        data, np.tile(ANGLES_0_45_90_135, 2), frames=2, **{**kw, "iterations": 0}
    )
    assert np.all(np.isfinite(both.loglik)) and np.all(np.isfinite(both.s0))
    assert any("no photons" in note for note in both.notes)
    np.testing.assert_array_equal(both.psfs[1], start.psfs[1])
    # the halved object changes the likelihood of frame 0 by a constant only (same maximiser); the phase
    # mode's L-BFGS line search still takes slightly different steps: 2.5e-8 of a PSF peaked near 0.05
    peak = alone.psfs[0].max()
    np.testing.assert_allclose(both.psfs[0], alone.psfs[0], rtol=0, atol=1e-5 * peak)
    np.testing.assert_allclose(both.dolp, alone.dolp, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(both.s0, 0.5 * alone.s0, rtol=1e-6)


def test_unmixing_puts_a_blurred_edge_where_it_is_and_the_dolp_threshold_does_not():
    """A straight paint/metal edge (metal 12 times brighter, DOLP 0.01 against 0.88) blurred by a
    symmetric Gaussian: the DOLP threshold of Ch. V (0.30) calls metal every pixel with more than 14 % of
    metal light, about sigma to the paint's side (Phi^-1(0.857) = 1.07 sigma); the nearest material's
    Stokes vector puts the edge at the mixing fraction 1/2, where the true edge is, and keeps a stroke
    too thin to have a pure interior at its width. Unclassified and
    unmeasured pixels stay unclassified, and one material alone is left as it is."""
    from scipy import ndimage

    from scatterlab.deconvolution import PRIOR_SETS, classify_dolp, classify_unmixing

    H, edge, sigma = 64, 30, 4.0
    metal = np.zeros((H, H), bool)
    metal[:, :edge] = True
    s0_true = np.where(metal, 12.0, 1.0) * 1e4
    s1_true = np.where(metal, 0.01 * 12.0, 0.88) * 1e4
    s0 = ndimage.gaussian_filter(s0_true, sigma, mode="nearest")
    dolp = ndimage.gaussian_filter(s1_true, sigma, mode="nearest") / s0
    by_dolp = classify_dolp(dolp, PRIOR_SETS["ch7"])
    unmixed = classify_unmixing(s0, dolp, by_dolp)
    # columns called metal in the middle row: the true edge is at column 30
    assert by_dolp[H // 2].sum() - edge >= round(1.07 * sigma) - 1
    assert unmixed[H // 2].sum() == edge
    np.testing.assert_array_equal(unmixed, metal.astype(int))
    # a stroke 3 pixels wide beside a metal half-plane, blurred by sigma 1.5: its centre row is 68 % metal
    # and its next rows 58 %, the rows beyond 36 % (Gaussian integrals); unmixing keeps the 3 columns,
    # the DOLP threshold (more than 14 % metal) takes 7
    stroke = metal.copy()
    stroke[:, 44:47] = True
    s0_t = np.where(stroke, 12.0, 1.0) * 1e4
    s0_b = ndimage.gaussian_filter(s0_t, 1.5, mode="nearest")
    s1_b = ndimage.gaussian_filter(np.where(stroke, 0.12, 0.88) * 1e4, 1.5, mode="nearest")
    thin_dolp = classify_dolp(s1_b / s0_b, PRIOR_SETS["ch7"])
    assert thin_dolp[H // 2, 36:56].sum() == 7
    np.testing.assert_array_equal(
        classify_unmixing(s0_b, s1_b / s0_b, thin_dolp), stroke.astype(int)
    )
    # unmeasured and unclassified pixels keep no class
    d2, c2 = dolp.copy(), by_dolp.copy()
    d2[5, 5], c2[6, 6] = np.nan, -1
    out = classify_unmixing(s0, d2, c2)
    assert out[5, 5] == -1 and out[6, 6] == -1 and out[20, 50] == 0
    np.testing.assert_array_equal(classify_unmixing(s0, dolp, np.zeros((H, H), int)), 0)
    with pytest.raises(ValueError, match="purest"):
        classify_unmixing(s0, dolp, by_dolp, purest=0.0)
    with pytest.raises(ValueError, match="one shape"):
        classify_unmixing(s0, dolp[:5], by_dolp)
