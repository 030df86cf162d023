"""Fast path (banded matrix + FFT far interactions) against dense LU, quadrature and energy."""

import warnings

import numpy as np
import pytest
from scipy import special

from scatterlab.mom import (
    TaperedWave,
    contour,
    correlation_length_for_slope,
    impedance_matrix,
    rough_surface,
    solve_tm,
)
from scatterlab.mom.efie import impedance_diagonals
from scatterlab.mom.fast import FastOperator, FastOptions, scattered_power

K = 2 * np.pi


def profile(length, seed=3, sigma_h=0.3):
    return rough_surface(
        length,
        0.1,
        sigma_h,
        correlation_length_for_slope(sigma_h, 0.3),
        np.random.default_rng(seed),
    )


def test_diagonals_are_the_dense_matrix_elements():
    c = contour(*profile(40))
    A = impedance_matrix(c, K)
    nb = 45
    D = impedance_diagonals(c, K, nb)
    for o in range(-nb, nb + 1):
        m = np.arange(max(0, -o), c.size - max(0, o))
        assert np.allclose(D[nb + o, m], np.diagonal(A, o), rtol=1e-8, atol=0)


@pytest.mark.parametrize("offset", [35, 60, 120])
def test_far_elements_match_a_32_point_pulse_integral(offset):
    """Flat pulse of 0.1 wavelength: the far rule (phase and amplitude of the pulse integral) is
    within 2e-5 of 32-point Gauss-Legendre (the phase factor alone was off by 7e-4 at 3.5 wl)."""
    x = np.arange(300) * 0.1
    A = impedance_matrix(contour(x, np.zeros_like(x)), K)
    xg, wg = np.polynomial.legendre.leggauss(32)
    ref = -0.25j * 0.1 * np.sum(wg / 2 * special.hankel2(0, K * np.abs(offset * 0.1 + xg * 0.05)))
    assert abs(A[100, 100 + offset] - ref) < 2e-5 * abs(ref)


def test_fast_operator_reproduces_the_dense_product():
    """Band 3 wavelengths, order 8: measured 1.9e-6 (a random vector, rough surface)."""
    c = contour(*profile(100))
    rng = np.random.default_rng(0)
    U = rng.standard_normal(c.size) + 1j * rng.standard_normal(c.size)
    ref = impedance_matrix(c, K) @ U
    errs = []
    for order in (0, 4, 8):
        op = FastOperator(c, K, FastOptions(band=3.0, order=order))
        errs.append(np.linalg.norm(op.matvec(U) - ref) / np.linalg.norm(ref))
    assert errs[2] < 1e-5
    assert errs[0] > errs[1] > errs[2]  # the Taylor series converges


def test_fast_solve_matches_lu_and_conserves_energy():
    """2000 unknowns, two incidences: measured 8e-7 in the current and the coefficient; the
    reflected power by FFT agrees with a 40001-angle trapezoid of the dense solution."""
    x, y = profile(200)
    incs = [TaperedWave(np.radians(t), 50.0, x0=0.5 * (x[0] + x[-1])) for t in (20, 60)]
    ref = solve_tm(x, y, 1.0, incs)
    sol = solve_tm(x, y, 1.0, incs, solver="fast", fast=FastOptions(dense_below=0))
    assert sol.solver == "fast"
    cur = np.linalg.norm(sol.current - ref.current, axis=0) / np.linalg.norm(ref.current, axis=0)
    assert np.all(cur < 1e-5)
    th = np.radians(np.linspace(-89, 89, 357))
    a, b = ref.scattering_coefficient(th), sol.scattering_coefficient(th)
    assert np.all(np.linalg.norm(b - a, axis=0) / np.linalg.norm(a, axis=0) < 1e-5)
    thq = np.linspace(-np.pi / 2, np.pi / 2, 40001)
    trap = np.trapezoid(ref.scattering_coefficient(thq), thq, axis=0)
    power = scattered_power(sol)
    assert np.all(np.abs(power - 1) < 2e-3)  # PEC: R = 1 (discretisation ~1e-4)
    assert np.all(np.abs(power - trap) < 3e-4)


def test_small_problems_use_lu_and_failures_fall_back():
    x, y = profile(60)
    inc = TaperedWave(np.radians(30), 15.0, x0=0.5 * (x[0] + x[-1]))
    ref = solve_tm(x, y, 1.0, inc)
    small = solve_tm(x, y, 1.0, inc, solver="fast")  # 600 < dense_below
    assert small.solver == "lu"
    np.testing.assert_allclose(small.current, ref.current)
    with pytest.warns(UserWarning, match="falling back to LU"):
        fb = solve_tm(
            x,
            y,
            1.0,
            inc,
            solver="fast",
            fast=FastOptions(dense_below=0, tol=1e-14, max_iter=1, restart=1),
        )
    assert fb.solver == "lu"


def test_fast_path_refuses_what_it_cannot_do():
    x, y = profile(60)
    x = x + 0.01 * np.sin(np.arange(x.size))  # not a uniform grid
    with pytest.raises(ValueError, match="uniform grid"):
        solve_tm(
            x,
            y,
            1.0,
            TaperedWave(0.3, 10.0, x0=float(np.mean(x))),
            solver="fast",
            fast=FastOptions(dense_below=0),
        )
    for bad in ({"band": 0.0}, {"order": -1}, {"tol": 2.0}, {"max_iter": 0}):
        with pytest.raises(ValueError):
            FastOptions(**bad)
    with pytest.raises(ValueError, match="FastOptions"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            solve_tm(*profile(60), 1.0, TaperedWave(0.3, 10.0, x0=3.0), solver="fast", fast={})
