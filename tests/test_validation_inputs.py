"""Input validation of the inversion, ellipsometry and MoM entry points: a bad argument raises a
ValueError naming it (never a silently wrong answer or a numpy/scipy warning)."""

import warnings
from pathlib import Path

import numpy as np
import pytest

from scatterlab import mom
from scatterlab.ellipsometry import (
    Instrument,
    depolarization_index,
    ecm_calibrate,
    fit_mueller_elements,
    model_elements,
    normalised_elements,
    tetrahedral_psa,
    tetrahedral_psg,
)
from scatterlab.inversion import (
    FitOptions,
    fit_dolp,
    fit_dolp_per_pixel,
    model_dolp,
    thilak_crlb,
    thilak_two_step,
)
from scatterlab.inversion.thilak import thilak_dop
from scatterlab.mom.asymptotics import spm1_alpha, spm1_coefficient
from scatterlab.polarization import linear_polarizer, linear_retarder

EXAMPLES = Path(__file__).resolve().parents[1] / "data" / "examples"

TI = TR = np.deg2rad([10, 30, 45, 60, 75, 85])
TH = np.radians([10, 20, 30, 40, 50, 60, 70])


@pytest.fixture
def y():
    return model_dolp(1.5, 0.1, 0.1, TI, TR)


# -- 1. fit_dolp options -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"sigma0": -1.0}, "sigma0"),
        ({"sigma0": 0.0}, "sigma0"),
        ({"sigma0": np.nan}, "sigma0"),
        ({"tol": np.inf}, "tol"),
        ({"tol": np.nan}, "tol"),
        ({"tol": -1e-12}, "tol"),
        ({"starts": [(-1, -1)]}, "starts"),
        ({"starts": [(1.5, 0.1), (1.5, -0.1)]}, "starts"),
        ({"max_iter": True}, "max_iter"),
    ],
)
def test_fit_dolp_refuses_bad_options(y, kw, name):
    with pytest.raises(ValueError, match=name):
        fit_dolp(y, TI, TR, **kw)
    with pytest.raises(ValueError, match=name):
        fit_dolp(y, TI, TR, options=FitOptions(**kw))


def test_fit_dolp_per_pixel_refuses_bad_sigma0_and_starts(y):
    with pytest.raises(ValueError, match="sigma0"):
        fit_dolp_per_pixel(y, TI, TR, sigma0=-1.0)
    with pytest.raises(ValueError, match="starts"):
        fit_dolp_per_pixel(y, TI, TR, starts=[(-1.0, 0.0)])


# -- 2. model_dolp ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "n, kappa, name",
    [(-1.5, 0.0, "n"), (np.nan, 0.1, "n"), (1.5, -3.0, "kappa"), (1.5, np.nan, "kappa")],
)
def test_model_dolp_refuses_negative_or_nan_index(n, kappa, name):
    with pytest.raises(ValueError, match=f"{name} must"):
        model_dolp(n, kappa, 0.1, TI, TR)


def test_model_dolp_keeps_the_bound_n_zero():
    # n = 0 (the lower bound of the fit) is allowed and evaluated at n = 1e-6, as before
    np.testing.assert_array_equal(
        model_dolp(0.0, 0.5, 0.1, TI, TR), model_dolp(1e-6, 0.5, 0.1, TI, TR)
    )


# -- 3. Thilak's two-step method -------------------------------------------------------------------


@pytest.mark.parametrize(
    "dop",
    [np.full(6, 5.0), np.full(6, np.nan), np.r_[0.1, 0.1, np.inf, 0.1, 0.1, 0.1], -np.ones(6)],
)
def test_thilak_two_step_refuses_dop_outside_0_1_or_not_finite(dop):
    with pytest.raises(ValueError, match="dop"):
        thilak_two_step(dop, TI, np.radians(60), np.random.default_rng(0))


def test_thilak_two_step_margin():
    ti = np.radians(np.linspace(35, 80, 10))
    tr = np.radians(60.0)
    y = thilak_dop(0.314, 3.544, (ti + tr) / 2)
    y[0] = -0.01  # a noisy DOP of a metal may fall below 0: accepted within the default margin
    assert thilak_two_step(y, ti, tr, np.random.default_rng(0)).n.shape == (1,)
    with pytest.raises(ValueError, match="dop"):
        thilak_two_step(y, ti, tr, np.random.default_rng(0), margin=0.0)
    with pytest.raises(ValueError, match="margin"):
        thilak_two_step(y, ti, tr, np.random.default_rng(0), margin=-1.0)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"start": (np.nan, 1.0)}, "start must be a non-empty sequence of finite"),
        ({"start": (-1.0, 1.0)}, "start must have n >= 0"),
        ({"start": "ab"}, "start must be"),
        ({"max_restarts": -1}, "max_restarts must be >= 0"),
        ({"max_restarts": 2.5}, "max_restarts must be an integer"),
    ],
)
def test_thilak_two_step_refuses_bad_start_and_restarts(kw, match):
    ti = np.radians(np.linspace(35, 80, 10))
    y = thilak_dop(0.314, 3.544, (ti + np.radians(60.0)) / 2)
    with pytest.raises(ValueError, match=match):
        thilak_two_step(y, ti, np.radians(60.0), np.random.default_rng(0), **kw)


@pytest.mark.parametrize("k", range(4))
def test_thilak_crlb_refuses_arrays_by_name(k):
    args = [1.5, 0.3, np.radians(60), TI, 1e-3]
    args[[0, 1, 2, 4][k]] = np.array([args[[0, 1, 2, 4][k]]] * 2)
    name = ("n", "kappa", "theta_r", "noise")[k]
    with pytest.raises(ValueError, match=f"{name} must be a single float"):
        thilak_crlb(*args)


# -- 4. ellipsometry -------------------------------------------------------------------------------


def test_depolarization_index_and_normalised_elements_need_4x4():
    with pytest.raises(ValueError, match=r"M must have shape \(\.\.\., 4, 4\)"):
        depolarization_index(np.eye(3))
    with pytest.raises(ValueError, match=r"M must have shape \(\.\.\., 4, 4\)"):
        normalised_elements(np.eye(3))


def test_no_light_gives_nan_elements_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.all(np.isnan(normalised_elements(np.zeros((4, 4)))))
        M = np.stack([np.zeros((4, 4)), 2 * np.eye(4)])
        out = normalised_elements(M)
        assert np.all(np.isnan(out[0]))
        np.testing.assert_array_equal(out[1], [0.0, 1.0, 1.0, 0.0])
        # eta = 1: nothing is reflected
        assert np.all(np.isnan(model_elements(TH, 1.0, 0.0, 0.2)))


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"tolerance": np.nan}, "tolerance"),
        ({"tolerance": -0.1}, "tolerance"),
        ({"sigma0": np.nan}, "sigma0"),
        ({"sigma0": -0.3}, "sigma0"),
        ({"sigma": np.nan}, "sigma"),
    ],
)
def test_fit_mueller_elements_refuses_bad_options(kw, name):
    y = model_elements(TH, 1.5, 0.1, 0.2)
    with pytest.raises(ValueError, match=name):
        fit_mueller_elements(TH, y, **kw)


@pytest.mark.parametrize(
    "starts, match",
    [
        ([], "non-empty"),
        ([(np.nan, 1.0)], "finite"),
        ([(1.5, -0.1)], "n >= 0 and kappa >= 0"),
        ([(1.5,)], "pairs"),
    ],
)
def test_fit_mueller_elements_and_fit_pbrdf_refuse_bad_starts(starts, match):
    from scatterlab.ellipsometry import fit_pbrdf
    from scatterlab.io import read_mueller_brdf

    y = model_elements(TH, 1.5, 0.1, 0.2)
    with pytest.raises(ValueError, match=f"starts must .*{match}"):
        fit_mueller_elements(TH, y, starts=starts)
    if not EXAMPLES.is_dir():
        pytest.skip("data/examples not present (installed package)")
    data = read_mueller_brdf(EXAMPLES / "mueller_brdf_scatmech_style.csv")
    with pytest.raises(ValueError, match=f"starts must .*{match}"):
        fit_pbrdf(data, starts=starts, posterior_steps=0)


def test_instrument_refuses_bad_noise_and_singular_matrices():
    inst = Instrument(tetrahedral_psg(), tetrahedral_psa())
    with pytest.raises(ValueError, match="noise must be finite"):
        inst.measure(np.eye(4), 0, noise=np.nan)
    with pytest.raises(ValueError, match="noise must be >= 0"):
        inst.measure(np.eye(4), 0, noise=-0.1)
    with pytest.raises(ValueError, match="noise_floor"):
        inst.measure(np.eye(4), 0, noise_floor=np.inf)
    with pytest.raises(ValueError, match="W must be a non-singular"):
        Instrument(np.zeros((4, 4)), tetrahedral_psa())
    with pytest.raises(ValueError, match="A must be a non-singular"):
        Instrument(tetrahedral_psg(), np.ones((4, 4)))


@pytest.mark.parametrize("tol", [-1.0, 0.0, 1e-20, np.nan])
def test_ecm_calibrate_refuses_bad_fit_tolerance(tol):
    inst = Instrument(tetrahedral_psg(), tetrahedral_psa())
    az = np.radians([0.0, 60.0, 120.0, 45.0])
    refs = [("polarizer", inst.intensities(linear_polarizer(a, 1e-4)), a) for a in az[:3]]
    refs.append(("retarder", inst.intensities(linear_retarder(np.radians(88), az[3])), az[3]))
    with pytest.raises(ValueError, match="fit_tolerance"):
        ecm_calibrate(inst.intensities(np.eye(4)), refs, fit_tolerance=tol)


# -- 5. method of moments --------------------------------------------------------------------------


def test_rms_slope_and_correlation_length_refuse_bad_lengths():
    with pytest.raises(ValueError, match="corr_length must be > 0"):
        mom.rms_slope(1.0, 0.0)
    with pytest.raises(ValueError, match="sigma_h must be >= 0"):
        mom.rms_slope(-1.0, 1.0)
    with pytest.raises(ValueError, match="sigma_h must be finite"):
        mom.rms_slope(np.nan, 1.0)
    with pytest.raises(ValueError, match="slope must be > 0"):
        mom.correlation_length_for_slope(1.0, 0.0)
    with pytest.raises(ValueError, match="sigma_h must be > 0"):
        mom.correlation_length_for_slope(0.0, 0.3)
    assert mom.rms_slope(0.5, 1.0) == pytest.approx(np.sqrt(2) / 2, rel=1e-15)
    assert mom.correlation_length_for_slope(0.5, 0.3) == pytest.approx(np.sqrt(2) * 0.5 / 0.3)


def test_spm1_coefficient_checks_k_and_eta():
    with pytest.raises(ValueError, match="k must be > 0"):
        spm1_coefficient(0.5, 0.3, -1.0, (0.01, 1.0), "s")
    with pytest.raises(ValueError, match="eta"):
        spm1_coefficient(0.5, 0.3, 2 * np.pi, (0.01, 1.0), "s", eta=1.5 + 1j)
    with pytest.raises(ValueError, match="eta"):
        spm1_alpha(0.5, 0.3, "s", -1.5)


@pytest.mark.parametrize("pol", ["s", "p"])
@pytest.mark.parametrize("n", [0.2, 0.5, 0.9])
def test_spm1_alpha_is_continuous_as_kappa_goes_to_zero(pol, n):
    # eta^2 < sin^2 theta (the principal square root's cut): kappa = 0 must be the kappa -> 0+ limit
    ti, ts = 0.8, np.array([-1.2, -0.5, 0.0, 0.5, 1.2])
    np.testing.assert_allclose(
        spm1_alpha(ti, ts, pol, n), spm1_alpha(ti, ts, pol, n - 1e-9j), rtol=1e-6
    )


def test_spm1_alpha_reported_value_on_the_cut():
    np.testing.assert_allclose(
        spm1_alpha(0.8, 0.5, "s", 0.2), -0.32421598413148967 - 0.9459830842217263j, rtol=1e-12
    )


def test_incident_waves_refuse_strings_by_name():
    with pytest.raises(ValueError, match="theta must be a real number"):
        mom.TaperedWave("0.3", 10.0)
    with pytest.raises(ValueError, match="g must be a real number"):
        mom.TaperedWave(0.3, "10")
    with pytest.raises(ValueError, match="x0 must be a real number"):
        mom.TaperedWave(0.3, 10.0, x0="0")
    with pytest.raises(ValueError, match="theta must be a real number"):
        mom.PlaneWave("0.3")
    assert mom.TaperedWave(np.float64(0.3), 10).g == 10


@pytest.mark.parametrize("scale", [1e-300, 1e-177, 1e-160, 1.0, 1e160, 1e300])
def test_depolarization_index_is_the_same_at_any_scale(scale):
    """diag(1, a, a, a) has P_Delta = a (closed form) whatever its scale: a smooth surface far off
    specular has M00 ~ 1e-177, whose squares underflowed to 'an ideal depolarizer'."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert depolarization_index(scale * np.diag([1.0, 0.5, 0.5, 0.5])) == pytest.approx(0.5)
        assert depolarization_index(scale * np.eye(4)) == pytest.approx(1.0)


@pytest.mark.parametrize("phi", [180.0, -7.0, [np.pi, 180.0]])
def test_an_azimuth_in_degrees_is_refused_everywhere_it_is_taken(phi):
    """phi = 180 (the specular plane in degrees) used to be read as 180 rad: a wrong fit, no error."""
    from scatterlab.inversion import DolpForward
    from scatterlab.pbrdf import Model

    th = np.radians([30.0, 40.0])
    for call in (
        lambda: fit_dolp(model_dolp(1.39, 0.34, 0.3, th, th), th, th, phi=phi),
        lambda: model_dolp(1.39, 0.34, 0.3, th, th, phi=phi),
        lambda: DolpForward(th, th, phi),
        lambda: Model(0.3).mueller(1.5, th, th, phi),
    ):
        with pytest.raises(
            ValueError,
            match=r"phi must be azimuths in radians in \[-2 pi, 2 pi\].*degrees.*phi = pi",
        ):
            call()


def test_an_azimuth_within_a_turn_either_way_is_the_same_geometry():
    """-2 pi, 0 and 2 pi (and pi and -pi) are accepted and give the same Mueller matrix."""
    from scatterlab.pbrdf import Model

    m = Model(0.3)
    np.testing.assert_allclose(
        m.mueller(1.5, 0.5, 0.6, -2 * np.pi), m.mueller(1.5, 0.5, 0.6, 2 * np.pi), atol=1e-15
    )
    np.testing.assert_allclose(
        m.mueller(1.5, 0.5, 0.6, -np.pi), m.mueller(1.5, 0.5, 0.6, np.pi), atol=1e-15
    )


@pytest.mark.parametrize("bad", [1.5, "abc", -1, True, [1, -2], [], [1.5]])
def test_an_rng_given_wrongly_is_refused_by_name(bad):
    from scatterlab._checks import as_rng

    with pytest.raises(ValueError, match="rng must be None, a non-negative integer"):
        as_rng(bad)


def test_every_accepted_rng_form_gives_a_reproducible_generator():
    from scatterlab._checks import as_rng

    g = np.random.default_rng(7)
    assert as_rng(g) is g  # shared state, not a copy
    for form in (7, np.int64(7), [7], np.random.SeedSequence(7), np.random.PCG64(7)):
        assert as_rng(form).integers(1 << 30) == np.random.default_rng(7).integers(1 << 30)
    assert isinstance(as_rng(None), np.random.Generator)


def test_thilak_two_step_refuses_a_float_rng():
    th = np.radians([30.0, 40.0, 50.0, 60.0])
    with pytest.raises(ValueError, match="rng must be None"):
        thilak_two_step(np.full(4, 0.5), th, th, 1.5)


@pytest.mark.parametrize("bad", [1.5, "abc", -1, True])
def test_public_random_functions_refuse_an_rng_given_wrongly_by_name(bad):
    from scatterlab import imaging
    from scatterlab.inversion import sample_posterior

    th = np.radians([30.0, 40.0, 50.0, 60.0])
    for call in (
        lambda: imaging.detect(np.ones((4, 4, 4)), rng=bad, photons=10),
        lambda: imaging.phase_screen(8, 0.01, 0.1, rng=bad),
        lambda: imaging.painted_plate(64, rng=bad),
        lambda: sample_posterior(np.full(4, 0.5), th, th, 0.01, rng=bad, sigma=0.3),
        lambda: mom.rough_surface(64.0, 0.1, 0.2, 1.0, bad),
        lambda: Instrument(tetrahedral_psg(), tetrahedral_psa()).measure(
            np.eye(4), bad, noise=0.01
        ),
    ):
        with pytest.raises(ValueError, match="rng must be None"):
            call()
