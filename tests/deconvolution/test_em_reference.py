"""The EM split into state / E-step / M-step / PSF update changes no result: seeded runs reproduce the arrays
main's undivided ``blind_deconvolve`` (commit ac7196c) gave, to float rounding.

The reference (data/em_reference.npz) and the script that made it (data/make_em_reference.py, run with that
commit's code) cover the shared-PSF Stokes fast path with AOP 0 and 0.4, one PSF per channel, the AOP M-step,
two-prior classification, a fixed PSF with the text's start, the pupil model with a mask, and saturation.
Tolerance: relative 1e-9 -- the same operations in the same order, up to the summation order of the Stokes
least-squares einsum (a few ulps, amplified by at most a few iterations).
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).parent / "data"
_spec = importlib.util.spec_from_file_location("make_em_reference", DATA / "make_em_reference.py")
ref_maker = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ref_maker)


@pytest.mark.parametrize("name", sorted(ref_maker.CASES))
def test_split_em_reproduces_the_undivided_em(name):
    ref = np.load(DATA / "em_reference.npz")
    got = ref_maker.run(name, ref_maker.CASES[name])
    for key, value in got.items():
        expected = ref[key]
        assert value.shape == expected.shape, key
        if key.endswith(("classes", "iterations")):
            np.testing.assert_array_equal(value, expected, err_msg=key)
        else:
            scale = np.max(np.abs(expected)) if expected.size else 1.0
            np.testing.assert_allclose(value, expected, rtol=1e-9, atol=1e-12 * scale, err_msg=key)


def test_grouped_options_equal_the_flat_keywords():
    """``options=EMOptions(...)`` and the flat keywords of earlier versions give the same run."""
    from scatterlab.deconvolution import (
        EMOptions,
        PolarizationOptions,
        PSFOptions,
        StopOptions,
        blind_deconvolve,
    )

    d, th = ref_maker.channels()
    flat = blind_deconvolve(d, th, shared_psf=False, aop=0.2, iterations=3)
    grouped = blind_deconvolve(
        d,
        th,
        options=EMOptions(
            psf=PSFOptions(shared=False),
            polarization=PolarizationOptions(aop=0.2),
            stop=StopOptions(iterations=3),
        ),
    )
    np.testing.assert_array_equal(flat.s0, grouped.s0)
    np.testing.assert_array_equal(flat.psfs, grouped.psfs)
    with pytest.raises(TypeError, match="psf_mod"):
        blind_deconvolve(d, th, psf_mod="em")
