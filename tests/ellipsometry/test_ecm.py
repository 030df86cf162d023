"""ECM against known truth: simulated imperfect instruments with known W and A."""

import numpy as np
import pytest
from _ecm_helpers import NOMINAL, TRUE_AZ, measure_references

from scatterlab.ellipsometry import Instrument, ecm_calibrate
from scatterlab.polarization import diattenuator, is_physical_mueller, linear_retarder

SAMPLE = linear_retarder(0.9, 0.35) @ diattenuator(0.8, 0.3, 1.1)


def test_noise_free_recovers_w_a_sample_and_azimuths(instrument):
    B0, refs = measure_references(instrument)
    cal = ecm_calibrate(B0, refs)
    k = instrument.W[0].mean()  # overall scale fixed by mean(W[0]) = 1
    np.testing.assert_allclose(cal.W * k, instrument.W, atol=1e-12)
    np.testing.assert_allclose(cal.A / k, instrument.A, atol=1e-12)
    np.testing.assert_allclose(cal.mueller(instrument.intensities(SAMPLE)), SAMPLE, atol=1e-12)
    np.testing.assert_allclose([r["azimuth"] for r in cal.references], TRUE_AZ, atol=1e-12)
    assert cal.references[3]["delta"] == pytest.approx(np.radians(88))
    assert cal.quality < 1e-12


def test_grid_search_without_nominal_azimuths(instrument):
    B0, refs = measure_references(instrument)
    cal = ecm_calibrate(B0, [(k, B) for k, B, _ in refs])
    np.testing.assert_allclose([r["azimuth"] for r in cal.references], TRUE_AZ, atol=1e-10)


def test_orientation_errors_recovered_at_1e3_noise(instrument):
    """Azimuths 1.2-1.8 deg away from nominal are fitted from single-shot data with noise 1e-3 of
    the largest intensity: RMS error < 0.05 deg over 30 calibrations x 3 fitted azimuths (the RMS is
    estimated to ~8 %)."""
    rng = np.random.default_rng(1)
    errors = []
    for _ in range(30):
        B0, refs = measure_references(instrument, rng, noise=1e-3)
        cal = ecm_calibrate(B0, refs)
        errors.extend(np.array([r["azimuth"] for r in cal.references])[1:] - TRUE_AZ[1:])
    assert np.degrees(np.sqrt(np.mean(np.square(errors)))) < 0.05
    assert np.max(np.abs(NOMINAL - TRUE_AZ)) > np.radians(1.5)  # the fit really moved them


def test_error_against_noise_is_within_1_5x_of_the_calibration_free_floor(instrument):
    """RMS Mueller error with ECM-calibrated W, A vs with the true W, A (same noisy sample data).
    60 trials at 1e-3: the ratio of RMS errors is estimated to about 10 %."""
    rng = np.random.default_rng(2)
    err_ecm, err_true = [], []
    Ainv, Winv = np.linalg.inv(instrument.A), np.linalg.inv(instrument.W)
    for _ in range(60):
        B0, refs = measure_references(instrument, rng, noise=1e-3)
        cal = ecm_calibrate(B0, refs)
        B = instrument.measure(SAMPLE, rng, noise=1e-3)[0]
        err_ecm.append(np.sum((cal.mueller(B) - SAMPLE) ** 2))
        err_true.append(np.sum((Ainv @ B @ Winv - SAMPLE) ** 2))
    ratio = np.sqrt(np.mean(err_ecm) / np.mean(err_true))
    assert 1.0 <= ratio <= 1.5


def test_quality_diagnostic_scales_as_noise_squared(instrument):
    rng = np.random.default_rng(3)
    q = {}
    for noise in (1e-5, 1e-3):
        q[noise] = np.median(
            [
                ecm_calibrate(
                    *measure_references(instrument, rng, noise=noise), refine=False
                ).quality
                for _ in range(15)
            ]
        )
    slope = np.log10(q[1e-3] / q[1e-5]) / 2
    assert slope == pytest.approx(2.0, abs=0.25)


def test_vectorised_images_and_physical_projection(instrument):
    B0, refs = measure_references(instrument)
    cal = ecm_calibrate(B0, refs)
    rng = np.random.default_rng(4)
    B = instrument.intensities(SAMPLE) + 1e-2 * rng.standard_normal((50, 60, 4, 4))
    M = cal.mueller(B)
    assert M.shape == (50, 60, 4, 4)
    np.testing.assert_allclose(M[7, 9], cal.mueller(B[7, 9]))
    assert np.all(is_physical_mueller(cal.mueller(B, physical=True), atol=1e-9))


def test_bad_inputs(instrument):
    B0, refs = measure_references(instrument)
    with pytest.raises(ValueError, match="retarder"):
        ecm_calibrate(B0, [r for r in refs if r[0] == "polarizer"])
    with pytest.raises(ValueError, match="singular"):
        ecm_calibrate(np.ones((4, 4)), refs)
    bad = B0.copy()
    bad[1, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        ecm_calibrate(bad, refs)
    with pytest.raises(ValueError, match="4x4"):
        ecm_calibrate(B0[:3], refs)
    with pytest.raises(ValueError, match="kind"):
        ecm_calibrate(B0, [("mirror", refs[0][1])] + refs[1:])
    with pytest.raises(ValueError, match="shape"):
        ecm_calibrate(B0, refs).mueller(np.ones((3, 4)))


def test_ill_conditioned_instrument_warns():
    W = np.diag([1.0, 1, 1, 0.001]) + 0.0
    W[0] = 1.0
    with pytest.warns(UserWarning, match="not a physical polarization state"):
        inst = Instrument(W, np.eye(4) + 0.1)  # an ill-conditioned, unphysical PSA
    B0 = inst.intensities(np.eye(4))
    refs = [
        ("polarizer", inst.intensities(m), a)
        for m, a in zip([diattenuator(1, 1e-4, a) for a in NOMINAL[:3]], NOMINAL[:3])
    ]
    refs.append(
        ("retarder", inst.intensities(linear_retarder(np.radians(88), NOMINAL[3])), NOMINAL[3])
    )
    with pytest.warns(RuntimeWarning, match="ill-conditioned"):
        ecm_calibrate(B0, refs)


def test_mueller_of_nan_intensities_is_a_clear_error(instrument):
    cal = ecm_calibrate(*measure_references(instrument))
    B = instrument.intensities(SAMPLE)
    B[1, 1] = np.nan
    with pytest.raises(ValueError, match="B .*finite"):
        cal.mueller(B)
    with pytest.raises(ValueError, match="B .*finite"):
        cal.mueller(np.full((4, 4), np.inf))


def test_reference_mueller_and_parameters_check_their_arguments():
    from scatterlab.ellipsometry import reference_mueller, reference_parameters

    with pytest.raises(ValueError, match=r"tau \(transmission\) must be >= 0"):
        reference_mueller(-1, 0.5, 0.5, 0)
    for k, bad in enumerate(([np.nan, 0.5, 0.5, 0], [1, np.nan, 0.5, 0], [1, 0.5, 0.5, np.inf])):
        with pytest.raises(ValueError, match=("tau", "psi", "azimuth")[k]):
            reference_mueller(*bad)
    with pytest.raises(ValueError, match=r"kind must be one of \('polarizer', 'retarder'\)"):
        reference_parameters(np.eye(4), "foo")
    with pytest.raises(ValueError, match="C .*NaN"):
        reference_parameters(np.full((4, 4), np.nan), "retarder")
    # a retarder's eigenvalues give its parameters back (tau = 0.8, Psi = 40 deg, Delta = 1 rad)
    M = reference_mueller(0.8, np.radians(40), 1.0, 0.3)
    assert reference_parameters(M, "retarder") == pytest.approx((0.8, np.radians(40), 1.0))


@pytest.mark.parametrize("scale", [1e-300, 1.0, 1e300])
@pytest.mark.parametrize("kind", ["polarizer", "retarder"])
def test_reference_parameters_are_scale_invariant_to_the_float_limits(scale, kind):
    """C is known up to the light level: Psi and Delta do not depend on it and tau scales with it,
    also for matrices near the float range's ends (no overflow in the eigenvalue products)."""
    import warnings

    from scatterlab.ellipsometry import reference_mueller, reference_parameters

    M = reference_mueller(0.7, 0.3, 1.1, 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tau, psi, delta = reference_parameters(scale * M, kind)
    assert tau == pytest.approx(0.7 * scale, rel=1e-12)
    assert psi == pytest.approx(0.3, abs=1e-12)
    assert delta == pytest.approx(1.1, abs=1e-12)
