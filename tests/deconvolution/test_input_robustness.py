"""A fuzz review's reproducers in the deconvolution package: each is a ValueError naming the argument and its
range (never a crash, a numpy error, a TypeError or a silently wrong answer), and valid input still works.

* adaptive_priors: DOLP values far outside [0, 1] crashed scipy's k-means (a segfault at 1e300); slightly
  outside, the error named the prior's internal ``c3``;
* blind_deconvolve: a start DOLP of 1 never moves and a negative one was read as 0 (a fixed point too);
  an AOP in degrees, a wrongly shaped ``aop``/``s0_start``, a 1-D ``psf0`` and ``gs_steps=-1``;
* classify_unmixing: pixels without light were relabelled to the first class;
* resample_psf, object_grid, SuperGaussianPrior and dolp_update: wrong types and ranges.
"""

import re
import warnings

import numpy as np
import pytest

from scatterlab.deconvolution import (
    PRIOR_SETS,
    SuperGaussianPrior,
    adaptive_priors,
    blind_deconvolve,
    classify_unmixing,
    dolp_update,
    object_grid,
    resample_psf,
)
from scatterlab.imaging import ANGLES_0_45_90_135 as A

GOOD = np.random.default_rng(0).poisson(100, (4, 16, 16)).astype(float)


@pytest.fixture(autouse=True)
def _warnings_are_errors():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


@pytest.mark.parametrize(
    "values, shown",
    [
        (np.r_[np.full(20, 0.1), np.full(20, 1e300)], "1e+300"),  # crashed scipy's kmeans2
        (np.r_[np.full(20, 0.1), np.full(20, 1.05)], "1.05"),
        (np.r_[np.full(20, -0.05), np.full(20, 0.8)], "-0.05"),
    ],
)
def test_adaptive_priors_refuses_dolp_outside_0_1_naming_dolp(values, shown):
    with pytest.raises(ValueError, match=r"dolp must be in \[0, 1\], got " + re.escape(shown)):
        adaptive_priors(values)


def test_adaptive_priors_ignores_nan_and_masked_pixels_but_refuses_inf():
    v = np.r_[np.full(20, 0.1), np.full(20, 0.8)]
    ref = adaptive_priors(v)
    assert adaptive_priors(np.r_[v, np.nan]) == ref
    masked = np.ma.array(np.r_[v, 5.0], mask=np.r_[np.zeros(40, bool), True])
    assert adaptive_priors(masked) == ref
    assert adaptive_priors(np.r_[v, 7.0], mask=np.r_[np.ones(40, bool), False]) == ref
    with pytest.raises(ValueError, match="dolp must be finite"):
        adaptive_priors(np.r_[v, np.inf])
    with pytest.raises(ValueError, match="mask must be a boolean array"):
        adaptive_priors(v, mask=np.ones(40, int))
    with pytest.raises(ValueError, match="dolp must be a numeric"):
        adaptive_priors(["a"] * 40)


@pytest.mark.parametrize(
    "start", [1.0, -0.5, -1.0, 1.5, np.r_[0.5, 1.0].repeat(128).reshape(16, 16)]
)
def test_dolp_start_refuses_the_fixed_points_and_signed_values(start):
    """1 is a fixed point of the multiplicative update (Q = T there: the ML update is 1 again) and a negative
    start was clipped to 0, also a fixed point: DOLP 0 everywhere, every pixel read as metal."""
    with pytest.raises(ValueError, match=r"dolp_start must be finite and in \[0, 1\)"):
        blind_deconvolve(GOOD, A, dolp_start=start, iterations=2)


def test_dolp_start_zero_and_inside_the_interval_still_run():
    # 0 is the unpolarized (Richardson-Lucy) EM the studies use; 0.5 is the text's start
    for start in (0.0, 0.5, 0.999):
        res = blind_deconvolve(GOOD, A, dolp_start=start, iterations=2)
        assert np.all(np.isfinite(res.loglik))


def test_aop_in_degrees_is_refused_like_the_angles():
    with pytest.raises(
        ValueError, match=r"aop must be .* radians .* got 45 \(degrees\? use numpy.radians"
    ):
        blind_deconvolve(GOOD, A, aop=45.0, iterations=2)
    with pytest.raises(ValueError, match="aop must be .* radians"):
        blind_deconvolve(GOOD, A, aop=np.full((16, 16), 90.0), estimate_aop=True, iterations=2)
    res = blind_deconvolve(GOOD, A, aop=np.radians(45.0), iterations=2)
    np.testing.assert_allclose(res.aop, np.pi / 4)


@pytest.mark.parametrize(
    "kw, name",
    [
        (dict(aop=np.zeros((3, 3))), "aop"),
        (dict(aop=np.zeros((16, 15))), "aop"),
        (dict(s0_start=np.ones((4, 4))), "s0_start"),
        (dict(dolp_start=np.full((2, 16, 16), 0.5)), "dolp_start"),
        (dict(s0_start="bright"), "s0_start"),
        (dict(psf0=np.full(32, 1 / 32)), "psf0"),
        (dict(psf0=np.full((2, 2, 32, 32), 1.0)), "psf0"),
        (dict(gs_steps=-1), "gs_steps"),
        (dict(gs_steps=2.5), "gs_steps"),
    ],
)
def test_blind_deconvolve_shapes_and_counts_name_the_argument(kw, name):
    with pytest.raises(ValueError, match=name):
        blind_deconvolve(GOOD, A, iterations=2, **kw)


def test_blind_deconvolve_accepts_start_images_of_the_data_shape():
    res = blind_deconvolve(
        GOOD, A, iterations=2, aop=np.zeros((16, 16)), s0_start=np.ones((16, 16)), dolp_start=0.3
    )
    assert res.s0.shape == (16, 16) and np.all(np.isfinite(res.dolp))


def _two_materials(n=12):
    classes = np.zeros((n, n), int)
    classes[:, n // 2 :] = 1
    s0 = np.where(classes == 1, 10.0, 1.0)
    dolp = np.where(classes == 1, 0.05, 0.8)
    return s0, dolp, classes


def test_classify_unmixing_keeps_the_class_of_pixels_without_light():
    s0, dolp, classes = _two_materials()
    # an image without light: nothing to unmix, every pixel (metal ones too) keeps its class
    np.testing.assert_array_equal(classify_unmixing(np.zeros_like(s0), dolp, classes), classes)
    np.testing.assert_array_equal(
        classify_unmixing(np.zeros_like(s0), dolp, 1 - classes), 1 - classes
    )
    # dark pixels in a lit image: kept (the Stokes vector 0 lies nearest the darker material, class 0),
    # and they do not drag the materials' Stokes vectors
    lit = classify_unmixing(s0, dolp, classes)
    s0_dark, cls_dark = s0.copy(), classes.copy()
    s0_dark[0], cls_dark[0] = 0.0, 1
    out = classify_unmixing(s0_dark, dolp, cls_dark)
    np.testing.assert_array_equal(out[0], 1)
    np.testing.assert_array_equal(out[1:], lit[1:])
    # unmeasured pixels stay -1
    s0_nan = s0_dark.copy()
    s0_nan[1, 0] = np.nan
    assert classify_unmixing(s0_nan, dolp, cls_dark)[1, 0] == -1


def test_resample_psf_refuses_what_is_not_a_psf():
    with pytest.raises(ValueError, match="h must be finite and >= 0"):
        resample_psf(np.array([[1.0, -2.0], [3.0, -1.0]]), (3, 3))
    with pytest.raises(ValueError, match="h must be finite and >= 0"):
        resample_psf(np.array([[1.0, np.nan], [3.0, 1.0]]), (3, 3))
    with pytest.raises(ValueError, match="h must be a 2-D PSF"):
        resample_psf(np.ones(5), (3, 3))
    for bad in ((3,), (3, 0), (3.0, 3), 3):
        with pytest.raises(ValueError, match="shape must be"):
            resample_psf(np.ones((3, 3)), bad)
    out = resample_psf([[0, 1, 0], [1, 4, 1], [0, 1, 0]], (5, 5))  # a list is a PSF too
    assert (
        out.shape == (5, 5) and out.sum() == pytest.approx(1.0) and out[2, 2] == pytest.approx(0.5)
    )


def test_object_grid_refuses_a_psf_radius_beyond_the_image():
    with pytest.raises(ValueError, match=r"psf_radius must be in \(0, 22.6"):
        object_grid((16, 16), psf_radius=1e300)
    assert object_grid((16, 16), psf_radius=np.hypot(16, 16)) == (16 + 46, 16 + 46)


@pytest.mark.parametrize(
    "args, kw, name",
    [
        ((3.1, 0.65), dict(m="10"), "m must be an even integer"),
        ((3.1, 0.65), dict(m=10.0), "m must be an even integer"),
        ((3.1, 0.65), dict(m=True), "m must be an even integer"),
        (("3.1", 0.65), {}, "c2 must be a real number"),
        ((3.1, "0.65"), {}, "c3 must be a real number"),
        ((np.array([3.1, 3.2]), 0.65), {}, "c2 must be a real number"),
        ((3.1, 0.65j), {}, "c3 must be a real number"),
    ],
)
def test_prior_constants_of_the_wrong_type_are_value_errors(args, kw, name):
    with pytest.raises(ValueError, match=name):
        SuperGaussianPrior(*args, **kw)


def test_prior_constants_accept_numpy_scalars():
    p = SuperGaussianPrior(np.float64(3.1), np.float32(0.5), np.int64(10))
    assert p.log_pdf(0.5) == 0.0


def test_dolp_update_weight_is_one_number():
    prior = PRIOR_SETS["ch5"][0]
    with pytest.raises(ValueError, match="weight must be a single number"):
        dolp_update(10.0, 5.0, prior, weight=np.array([1, 2]))
    with pytest.raises(ValueError, match="weight must be numeric"):
        dolp_update(10.0, 5.0, prior, weight="heavy")
    assert 0 <= float(dolp_update(10.0, 5.0, prior, weight=np.float64(2.0))) <= 1
