"""The PEC matrix fill (Hankel's expansion, cache-sized tiles, the pulse factor in real arithmetic)
against the previous one (Cephes j0/y0, complex pulse factor, whole row blocks)."""

import numpy as np
import pytest

from scatterlab.mom import contour, correlation_length_for_slope, efie, rough_surface

K = 2 * np.pi


@pytest.mark.parametrize("ppw", [10, 3])  # 3 points per wavelength: the sinh branch (|w| > 0.6)
def test_times_pulse_factor_is_the_pulse_factor(ppw):
    rng = np.random.default_rng(0)
    P, Q = 50, 60
    h = rng.uniform(0.8, 1.2, (1, Q)) / ppw
    th = rng.uniform(0, 2 * np.pi, (1, Q))
    DX = rng.uniform(-20, 20, (P, Q))
    DY = rng.uniform(-2, 2, (P, Q))
    DX[0] = 0.05  # close pairs
    R = np.hypot(DX, DY)
    H = efie._hankel2_0(K * R)
    ref = H * efie._pulse_factor(K, h, (np.cos(th) * DX + np.sin(th) * DY) / R, R)
    new = efie._times_pulse_factor(H, K, h, np.cos(th), np.sin(th), DX, DY, 1 / R)
    # measured 3.1e-16 (ppw 10) and 4.2e-16 (ppw 3)
    assert np.max(np.abs(new - ref) / np.abs(ref)) <= 6e-16


@pytest.mark.parametrize("n, closed", [(400, False), (1500, False), (300, True)])
def test_fill_matches_the_previous_fill_within_its_phase_error(n, closed):
    rng = np.random.default_rng(5)
    if closed:
        t = 2 * np.pi * (np.arange(n) + 0.5) / n
        c = contour(3 * np.cos(t), 2 * np.sin(t), closed=True)
    else:
        x, y = rough_surface(n / 10, 0.1, 1.0, correlation_length_for_slope(1.0, 0.3), rng)
        c = contour(x, y)
    A = efie.impedance_matrix(c, K)
    B = efie._impedance_matrix(c, K, "scipy")
    R = np.hypot(c.x[:, None] - c.x[None], c.y[:, None] - c.y[None])
    # Cephes rounds kR - pi/4 before its phase: relative error up to kR 2^-53 in the old fill
    # (measured at most 0.89 of this bound)
    bound = 1.5 * (K * R * 2.0**-53 + 1e-15)
    assert np.all(np.abs(A - B) <= bound * np.abs(B))
    # diagonal, neighbours and the near band do not use the expansion (kR < 30 there): identical
    i = np.arange(n)
    np.testing.assert_array_equal(A[i, i], B[i, i])
    np.testing.assert_array_equal(A[i[:-1], i[1:]], B[i[:-1], i[1:]])


def test_fill_is_independent_of_the_tiling():
    rng = np.random.default_rng(9)
    x, y = rough_surface(70.0, 0.1, 1.0, correlation_length_for_slope(1.0, 0.3), rng)
    c = contour(x, y)
    A = efie.impedance_matrix(c, K)
    h0, h1, _, fill_tile = efie._KERNELS["expansion"]
    N = c.size
    B = np.empty((N, N), complex)
    efie._fill_far(B, c, K, N, (h0, h1, 1000, fill_tile))  # one row block, small tiles
    B *= (-0.25j) * c.ds[None, :]
    far = np.abs(np.subtract.outer(np.arange(N), np.arange(N))) > 40  # beyond the near band
    np.testing.assert_array_equal(A[far], B[far])
