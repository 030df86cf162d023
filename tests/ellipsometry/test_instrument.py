import warnings

import numpy as np
import pytest

from scatterlab.ellipsometry import (
    Instrument,
    condition_number,
    rotating_retarder_psg,
    switched_wave_plate_psa,
    switched_wave_plate_psg,
    tetrahedral_psa,
    tetrahedral_psg,
)
from scatterlab.polarization import dop, is_physical_mueller, linear_retarder


def test_tetrahedral_design_is_optimal():
    # sqrt(3) is the smallest possible condition number of a 4-state polarimeter (Tyo 2002)
    assert condition_number(tetrahedral_psg()) == pytest.approx(np.sqrt(3))
    assert condition_number(tetrahedral_psa()) == pytest.approx(np.sqrt(3))
    assert (
        condition_number(rotating_retarder_psg()) < 1.8
    )  # the 132 deg / +-15.1, +-51.7 deg design
    assert condition_number(switched_wave_plate_psg()) > np.sqrt(3)


def test_ideal_switched_psg_states():
    W = switched_wave_plate_psg()
    np.testing.assert_allclose(W[:, 0], [1, 1, 0, 0], atol=1e-15)  # H
    np.testing.assert_allclose(W[:, 1], [1, -1, 0, 0], atol=1e-15)  # V (HWP at 45 deg)
    np.testing.assert_allclose(W[:, 2], [1, 0, 1, 0], atol=1e-15)  # +45 (HWP at 22.5 deg)
    assert abs(W[3, 3]) == pytest.approx(1) and dop(W[:, 3]) == pytest.approx(
        1
    )  # circular (QWP at 45 deg)


def test_measurement_model_and_noise_statistics():
    inst = Instrument(switched_wave_plate_psg(), switched_wave_plate_psa())
    M = linear_retarder(0.6, 0.2) * 0.8
    np.testing.assert_allclose(inst.intensities(M), inst.A @ M @ inst.W)
    assert is_physical_mueller(M)
    rng = np.random.default_rng(0)
    B = inst.intensities(M)
    mean, std = inst.measure(M, rng, noise=0.01, repeats=4000, relative_to="max")
    sigma = 0.01 * np.abs(B).max()
    np.testing.assert_allclose(std, sigma, rtol=0.06)  # 4000 draws: std of the std is ~1.1 %
    assert np.all(np.abs(mean - B) < 5 * sigma / np.sqrt(4000))
    mean, std = inst.measure(M, rng, noise=0.01, repeats=4000)  # relative to each reading
    np.testing.assert_allclose(std, 0.01 * np.abs(B), rtol=0.06)


def test_bad_instrument_input():
    with pytest.raises(ValueError, match="W"):
        Instrument(np.ones((3, 3)), np.eye(4))
    inst = Instrument(switched_wave_plate_psg(), switched_wave_plate_psa())
    with pytest.raises(ValueError, match="repeats"):
        inst.measure(np.eye(4), repeats=0)


def test_unphysical_states_are_pointed_out_and_physical_ones_give_no_negative_intensity(rng):
    """The identity as PSG has columns (0, 1, 0, 0), ...: a polarized part without intensity. A
    physical instrument and sample never give a negative reading; that instrument does, and is named."""
    import warnings

    from scatterlab.polarization import diattenuator

    with pytest.warns(UserWarning, match="W column 1 is not a physical polarization state"):
        bad = Instrument(np.eye(4), switched_wave_plate_psa())
    M = diattenuator(1.0, 0.0, np.pi / 2)  # a vertical polarizer
    assert bad.intensities(M).min() < 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        good = Instrument(switched_wave_plate_psg(), switched_wave_plate_psa())
    for angle in rng.uniform(0, np.pi, 20):
        for M in (diattenuator(1.0, 0.0, angle), linear_retarder(angle, 2 * angle) * 0.9):
            assert good.intensities(M).min() >= -1e-12


def test_measure_and_intensities_check_their_arguments():
    ins = Instrument(tetrahedral_psg(), tetrahedral_psa())
    with pytest.raises(ValueError, match="M .* must be finite"):
        ins.measure(np.full((4, 4), np.nan), 0)
    with pytest.raises(ValueError, match=r"M .* must have shape \(\.\.\., 4, 4\)"):
        ins.intensities(np.eye(3))
    for bad in (2.5, 0, np.nan, True):
        with pytest.raises(ValueError, match="repeats must be an integer >= 1"):
            ins.measure(np.eye(4), 0, repeats=bad)
    with pytest.raises(ValueError, match="rng"):
        ins.measure(np.eye(4), 1.5, noise=0.01)
    B, s = ins.measure(np.eye(4), 0, repeats=np.int64(2))
    np.testing.assert_allclose(B, tetrahedral_psa() @ tetrahedral_psg(), atol=1e-12)


def test_noise_is_a_relative_level_in_0_1_and_huge_readings_stay_finite():
    """noise = 1e300 overflowed with RuntimeWarnings: noise is a relative standard deviation, refused
    above 1 (noise as large as the reading) with a ValueError naming it and the range. Readings up to
    ~1e305 with noise = 1 (whose squares overflowed the standard deviation) are finite and scale
    exactly: the noise model is linear, so measuring 2^1000 M is 2^1000 times measuring M with the
    same draws, and the std is noise |B| within its sampling error. Intensities beyond the double
    range are a ValueError naming M."""
    ins = Instrument(tetrahedral_psg(), tetrahedral_psa())
    M = linear_retarder(0.6, 0.2) * 0.8
    B = ins.intensities(M)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for bad in (1.0 + 1e-12, 2.0, 1e300):
            with pytest.raises(ValueError, match=r"noise must be in \[0, 1\]"):
                ins.measure(M, 0, noise=bad)
        with pytest.raises(ValueError, match=r"noise must be a single number in \[0, 1\]"):
            ins.measure(M, 0, noise=[0.1, 0.2])
        with pytest.raises(ValueError, match=r"noise_floor must be a single number >= 0"):
            ins.measure(M, 0, noise=0.01, noise_floor=[0.1, 0.2])  # was a TypeError from float()
        big = 2.0**1000  # ~1e301, a power of two: scaling is exact
        for relative_to in ("each", "max"):
            mean, std = ins.measure(M, 5, noise=1.0, repeats=4000, relative_to=relative_to)
            mean_big, std_big = ins.measure(
                M * big, 5, noise=1.0, repeats=4000, relative_to=relative_to
            )
            np.testing.assert_allclose(mean_big, mean * big, rtol=1e-13, atol=1e-13 * big)
            np.testing.assert_allclose(std_big, std * big, rtol=1e-13)
        # 4000 draws: the std of the std is ~1.1 %
        np.testing.assert_allclose(std_big, np.abs(B).max() * big, rtol=0.05)
        mean, std = ins.measure(M, 6, noise_floor=1e300, repeats=4000)
        np.testing.assert_allclose(std, 1e300, rtol=0.05)
        with pytest.raises(ValueError, match="M .* too large: its intensities A M W exceed"):
            ins.measure(np.eye(4) * 1e308, 0)
        for seed in range(5):  # readings near the largest double: finite, or refused; never inf
            try:
                mean, std = ins.measure(np.eye(4) * 1e307, seed, noise=1.0, repeats=3)
            except ValueError as exc:
                assert "the noisy readings exceed the largest double" in str(exc)
            else:
                assert np.all(np.isfinite(mean)) and np.all(np.isfinite(std))
