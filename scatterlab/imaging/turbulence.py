r"""Atmospheric turbulence: refractive-index spectra, Fried parameter, Rytov variance, phase screens.

* Refractive-index spectra: Kolmogorov (Eq. 70), :math:`\Phi_n = 0.033 C_n^2\kappa^{-11/3}`, and the
  modified von Karman spectrum with outer scale :math:`L_0` and inner scale :math:`\ell_0`,
  :math:`\Phi_n = 0.033 C_n^2 e^{-\kappa^2/\kappa_m^2}/(\kappa^2 + \kappa_0^2)^{11/6}`,
  :math:`\kappa_0 = 2\pi/L_0`, :math:`\kappa_m = 5.92/\ell_0` [rad/m].
* Fried parameter (Eqs. 74-75) and plane-wave Rytov variance (Eqs. 80-81); a warning when the
  weak-turbulence assumption (:math:`\sigma_R^2 < 0.2`) of the phase-screen model fails.
* Phase screens (Eqs. 71-79): a complex Gaussian field with variance set by the phase spectrum
  :math:`\Phi_\varphi(f) = 0.023\,r_0^{-5/3}(f^2 + L_0^{-2})^{-11/6}e^{-(f/f_m)^2}` (cycles/m;
  :math:`f_m = 5.92/(2\pi\ell_0)`), transformed by FFT -- Eq. 79 is this variance for an N x N grid of
  side D. The FFT grid misses the lowest frequencies, so plain screens fall short of the structure
  function at large separations (errata to Eq. 79); ``subharmonics=True`` adds three levels of
  subharmonics (after Lane et al. 1992) on 3x3 grids of 1/3, 1/9 and 1/27 of the frequency spacing.
  Lane's point-sampled subharmonics still fall 14-35 % short for Kolmogorov turbulence, because the
  spectrum is singular at the origin; here every near-origin mode (the FFT cells with |i|, |j| <= 2, the
  subharmonic cells, and the last level's central cell as four quadrant modes) gets the variance
  :math:`\int_{cell}\Phi|f|^2 d^2f / |f_c|^2`, which makes each cell's share of the structure function
  exact at small separations. Measured: within 5 % of 6.88 (r/r0)^(5/3) from 2 px to D/2 (tests).

Units: lengths in metres, phases in radians, frequencies in cycles per metre unless stated. Every
random routine takes ``rng``.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
from scipy import integrate, special

from scatterlab._checks import as_positive

__all__ = [
    "STRUCTURE_CONSTANT",
    "PSD_CONSTANT",
    "kolmogorov_psd",
    "von_karman_psd",
    "phase_psd",
    "fried_parameter",
    "rytov_variance",
    "rytov_variance_from_r0",
    "phase_screen",
    "SlidingScreen",
    "remove_piston_tilt",
    "structure_function",
    "structure_function_theory",
    "phase_variance_theory",
]


def kolmogorov_psd(kappa, cn2):
    """Kolmogorov refractive-index spectrum (Eq. 70) [m^3] at spatial frequency ``kappa`` [rad/m].

    Parameters
    ----------
    kappa : array_like
        Spatial frequency [rad/m], > 0.
    cn2 : float
        Refractive-index structure constant C_n^2 [m^(-2/3)], >= 0.

    Returns
    -------
    ndarray, shape of ``kappa``
        ``0.033 C_n^2 kappa^(-11/3)`` [m^3].
    """
    kappa = as_positive(kappa, "kappa")
    return 0.033 * float(as_positive(cn2, "cn2", allow_zero=True)) * kappa ** (-11 / 3)


def von_karman_psd(kappa, cn2, L0=np.inf, l0=0.0):
    """Modified von Karman refractive-index spectrum [m^3] with outer scale ``L0`` and inner scale
    ``l0`` [m].

    Parameters
    ----------
    kappa : array_like
        Spatial frequency [rad/m], >= 0.
    cn2 : float
        Refractive-index structure constant C_n^2 [m^(-2/3)].
    L0 : float
        Outer scale [m] (``inf``: none).
    l0 : float
        Inner scale [m] (0: none).

    Returns
    -------
    ndarray, shape of ``kappa``
        The spectrum [m^3].
    """
    kappa = as_positive(kappa, "kappa", allow_zero=True)
    k0 = 0.0 if np.isinf(L0) else 2 * np.pi / float(as_positive(L0, "L0"))
    km = np.inf if l0 == 0 else 5.92 / float(as_positive(l0, "l0"))
    with np.errstate(divide="ignore"):
        return 0.033 * cn2 * np.exp(-((kappa / km) ** 2)) * (kappa**2 + k0**2) ** (-11 / 6)


# 2 [(24/5) Gamma(6/5)]^(5/6) = 6.8839: the Kolmogorov structure-function constant
STRUCTURE_CONSTANT = 2 * (24 / 5 * special.gamma(6 / 5)) ** (5 / 6)
# the phase-spectrum constant that reproduces it exactly (0.02290, the 0.0229 of Eq. 79), from
# D(r) = 4 pi A r0^(-5/3) (2 pi r)^(5/3) int u^(-8/3) (1 - J0(u)) du, int = -Gamma(-5/6) / (2^(8/3) Gamma(11/6))
PSD_CONSTANT = STRUCTURE_CONSTANT / (
    4
    * np.pi
    * (2 * np.pi) ** (5 / 3)
    * (-special.gamma(-5 / 6) / (2 ** (8 / 3) * special.gamma(11 / 6)))
)


def phase_psd(f, r0, L0=np.inf, l0=0.0):
    """Phase spectrum [rad^2 m^2] at ``f`` [cycles/m]: 0.0229 r0^(-5/3) (f^2 + 1/L0^2)^(-11/6) exp(-(f/fm)^2).

    The constant is :data:`PSD_CONSTANT` = 0.022896 (Eq. 79's 0.0229), exact for D(r) = 6.8839 (r/r0)^(5/3).

    Parameters
    ----------
    f : array_like
        Spatial frequency [cycles/m].
    r0 : float
        Fried parameter [m].
    L0 : float
        Outer scale [m] (``inf``: none).
    l0 : float
        Inner scale [m] (0: none).

    Returns
    -------
    ndarray, shape of ``f``
        Phase power spectral density [rad^2 m^2].
    """
    f = np.asarray(f, float)
    f0 = 0.0 if np.isinf(L0) else 1.0 / L0
    fm = np.inf if l0 == 0 else 5.92 / (2 * np.pi * l0)
    with np.errstate(divide="ignore"):
        return (
            PSD_CONSTANT
            * r0 ** (-5 / 3)
            * np.exp(-((f / fm) ** 2))
            * (f * f + f0 * f0) ** (-11 / 6)
        )


def fried_parameter(cn2, path_length, wavelength):
    """Fried parameter r0 [m] (Eqs. 74-75), plane wave.

    Parameters
    ----------
    cn2 : float or callable
        Constant C_n^2 [m^(-2/3)], or a profile ``cn2(z)`` integrated over ``[0, path_length]``.
    path_length : float
        Propagation path length [m].
    wavelength : float
        Wavelength [m].

    Returns
    -------
    float
        Fried parameter r0 [m].
    """
    L = float(as_positive(path_length, "path_length"))
    lam = float(as_positive(wavelength, "wavelength"))
    integral = integrate.quad(cn2, 0, L)[0] if callable(cn2) else float(as_positive(cn2, "cn2")) * L
    if integral <= 0:
        raise ValueError("cn2 must integrate to a positive value over the path")
    k = 2 * np.pi / lam
    return (0.423 * k * k * integral) ** (-3 / 5)


def _weak_check(s2):
    if s2 >= 0.2:
        warnings.warn(
            f"Rytov variance {s2:.3g} >= 0.2: turbulence is not weak and the phase-screen model "
            "(Eqs. 82-83) neglects scintillation",
            RuntimeWarning,
            stacklevel=3,
        )
    return s2


def rytov_variance(cn2, path_length, wavelength):
    """Plane-wave Rytov variance (Eq. 80); warns when >= 0.2 (strong turbulence).

    Parameters
    ----------
    cn2 : float or callable
        Constant C_n^2 [m^(-2/3)], or a profile ``cn2(z)`` [m^(-2/3)] of the distance ``z`` [m].
    path_length : float
        Propagation path length [m].
    wavelength : float
        Wavelength [m].

    Returns
    -------
    float
        Rytov variance [dimensionless].
    """
    L = float(as_positive(path_length, "path_length"))
    k = 2 * np.pi / float(as_positive(wavelength, "wavelength"))
    if callable(cn2):
        integral = integrate.quad(lambda z: cn2(z) * (1 - z / L) ** (5 / 6), 0, L)[0]
    else:
        integral = float(as_positive(cn2, "cn2")) * L * 6 / 11
    return _weak_check(2.25 * k ** (7 / 6) * L ** (5 / 6) * integral)


def rytov_variance_from_r0(r0, path_length, wavelength):
    """Eq. 81: 2.91 [L / (k r0^2)]^(5/6) for constant C_n^2; warns when >= 0.2.

    Parameters
    ----------
    r0 : float
        Fried parameter [m].
    path_length : float
        Propagation path length [m].
    wavelength : float
        Wavelength [m].

    Returns
    -------
    float
        Rytov variance [dimensionless].
    """
    r0 = float(as_positive(r0, "r0"))
    L = float(as_positive(path_length, "path_length"))
    k = 2 * np.pi / float(as_positive(wavelength, "wavelength"))
    return _weak_check(2.91 * (L / (k * r0 * r0)) ** (5 / 6))


MAX_D_OVER_R0 = 1e6  # a screen width over r0 beyond this has phase differences no grid samples
MIN_D_OVER_R0 = 1e-6  # below, the rms phase is under 1e-5 rad


def _check_screen_args(n, dx, r0, L0, l0):
    if not (isinstance(n, (int, np.integer)) and n >= 4):
        raise ValueError("n (screen size in pixels) must be an integer >= 4")
    dx = float(as_positive(dx, "dx"))
    r0 = float(as_positive(r0, "r0"))
    if not (L0 == np.inf or (np.isfinite(L0) and L0 > 0)):
        raise ValueError(f"L0 (outer scale) must be > 0 or +inf, got {L0!r}")
    if not (np.isfinite(l0) and l0 >= 0):
        raise ValueError(f"l0 (inner scale) must be a finite length >= 0, got {l0!r}")
    if n * dx / r0 < MIN_D_OVER_R0:
        raise ValueError(
            f"r0 = {r0:g} m is too large for a screen {n * dx:g} m wide: D/r0 = {n * dx / r0:.3g} must "
            f"be >= {MIN_D_OVER_R0:g} (the phase would be below 1e-5 rad: no turbulence to simulate)"
        )
    if n * dx / r0 > MAX_D_OVER_R0:
        raise ValueError(
            f"r0 = {r0:g} m is too small for a screen {n * dx:g} m wide: D/r0 = {n * dx / r0:.3g} "
            f"must be <= {MAX_D_OVER_R0:g} (the phase is then not sampled by any grid)"
        )
    return dx, r0


def _cell_variance(x0, x1, y0, y1, fcx, fcy, L0, l0):
    """Variance of the mode at (fcx, fcy) standing for the frequency cell [x0, x1] x [y0, y1] (r0 = 1):
    int_cell Phi |f|^2 d^2f / |fc|^2, which makes the cell's contribution to the structure function exact
    at small separations (point sampling the singular spectrum underestimates it)."""

    def g(y, x):
        f2 = x * x + y * y
        return phase_psd(np.sqrt(f2), 1.0, L0, l0) * f2 if f2 > 0 else 0.0

    val = integrate.dblquad(g, x0, x1, y0, y1, epsrel=1e-7, epsabs=0)[0]
    return val / (fcx * fcx + fcy * fcy)


@functools.lru_cache(maxsize=64)
def _low_frequency_modes(ny, nx, dx, L0, l0, levels):
    """Near-origin modes for r0 = 1: the FFT cells with |i|, |j| <= 2 (replacing their point samples),
    ``levels`` 3x3 subharmonic rings, and the last level's central cell as four quadrant modes."""
    dfx, dfy = 1 / (nx * dx), 1 / (ny * dx)
    grid = []
    for i in range(-2, 3):
        for j in range(-2, 3):
            if i == 0 and j == 0:
                continue
            fcx, fcy = i * dfx, j * dfy
            grid.append(
                (
                    i,
                    j,
                    _cell_variance(
                        fcx - dfx / 2, fcx + dfx / 2, fcy - dfy / 2, fcy + dfy / 2, fcx, fcy, L0, l0
                    ),
                )
            )
    modes = []
    if levels:
        for p in range(1, levels + 1):
            hx, hy = dfx / 3**p, dfy / 3**p
            for i in (-1, 0, 1):
                for j in (-1, 0, 1):
                    if i == 0 and j == 0:
                        continue
                    fcx, fcy = i * hx, j * hy
                    modes.append(
                        (
                            fcx,
                            fcy,
                            _cell_variance(
                                fcx - hx / 2,
                                fcx + hx / 2,
                                fcy - hy / 2,
                                fcy + hy / 2,
                                fcx,
                                fcy,
                                L0,
                                l0,
                            ),
                        )
                    )
        hx, hy = dfx / 3**levels, dfy / 3**levels
        for sx in (-1, 1):
            for sy in (-1, 1):
                fcx, fcy = sx * hx / 4, sy * hy / 4
                x0, x1 = sorted((0.0, sx * hx / 2))
                y0, y1 = sorted((0.0, sy * hy / 2))
                modes.append((fcx, fcy, _cell_variance(x0, x1, y0, y1, fcx, fcy, L0, l0)))
    return tuple(grid), tuple(modes)


def _fft_field(shape, dx, r0, L0, l0, rng, levels):
    ny, nx = shape
    fx = np.fft.fftfreq(nx, dx)
    fy = np.fft.fftfreq(ny, dx)
    f = np.hypot(fx[None, :], fy[:, None])
    dfx, dfy = 1 / (nx * dx), 1 / (ny * dx)
    var = phase_psd(np.where(f > 0, f, 1.0), r0, L0, l0) * dfx * dfy
    var[0, 0] = 0.0  # no piston
    grid, modes = _low_frequency_modes(ny, nx, dx, L0, l0, levels)
    scale = r0 ** (-5 / 3)
    if levels:  # plain FFT screens (no subharmonics) keep the point-sampled spectrum of Eq. 79
        for i, j, v in grid:
            var[j % ny, i % nx] = v * scale
    cn = (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) * np.sqrt(var)
    phase = np.fft.ifft2(cn).real * (nx * ny)
    if levels:
        x = (np.arange(nx) - nx / 2) * dx
        y = (np.arange(ny) - ny / 2) * dx
        m = np.array(modes)
        c = (rng.standard_normal(len(m)) + 1j * rng.standard_normal(len(m))) * np.sqrt(
            m[:, 2] * scale
        )
        ex = np.exp(2j * np.pi * m[:, 0, None] * x[None, :])
        ey = np.exp(2j * np.pi * m[:, 1, None] * y[None, :])
        low = np.einsum("k,ky,kx->yx", c, ey, ex).real
        phase = phase + low - low.mean()
    return phase


SUBHARMONIC_LEVELS = 3


def phase_screen(n, dx, r0, rng=None, L0=np.inf, subharmonics=True, l0=0.0):
    """Random turbulent phase screen [rad], shape ``(n, n)`` (Eqs. 71-79).

    Parameters
    ----------
    n : int
        Screen size [pixels].
    dx : float
        Grid spacing [m].
    r0 : float
        Fried parameter [m] (> 0).
    rng : seed or Generator
    L0 : float
        Outer scale [m] (``inf``: Kolmogorov).
    subharmonics : bool
        Add low-frequency subharmonics (recommended: without them the structure function falls short at
        separations above ~ n dx / 10).
    l0 : float
        Inner scale [m] (0: none).

    Returns
    -------
    ndarray (n, n) of phase [rad]; statistically homogeneous with structure function
    ``6.88 (r/r0)^(5/3)`` for Kolmogorov turbulence.
    """
    dx, r0 = _check_screen_args(n, dx, r0, L0, l0)
    rng = np.random.default_rng(rng)
    # in units of r0 (the screen depends on dx / r0, L0 / r0 and l0 / r0 only): no overflow for lengths
    # given in any unit, 1e-200 or 1e300
    return _fft_field(
        (n, n),
        dx / r0,
        1.0,
        float(L0) / r0,
        float(l0) / r0,
        rng,
        SUBHARMONIC_LEVELS if subharmonics else 0,
    )


class SlidingScreen:
    """A long periodic screen (a "phase wheel") that slides across the pupil to give a time sequence.

    Parameters
    ----------
    n : int
        Window size [pixels].
    dx, r0, L0, l0 : as in :func:`phase_screen`.
    length : int
        Strip length [pixels] (>= n); the strip is periodic, so windows wrap around like a wheel.
    rng : seed or Generator
    """

    def __init__(self, n, dx, r0, rng=None, *, length=None, L0=np.inf, l0=0.0, subharmonics=True):
        dx, r0 = _check_screen_args(n, dx, r0, L0, l0)
        length = 4 * n if length is None else int(length)
        if length < n:
            raise ValueError("length must be >= n")
        rng = np.random.default_rng(rng)
        self.n, self.dx = n, dx
        self.strip = _fft_field(
            (n, length),
            dx / r0,  # in units of r0, as phase_screen
            1.0,
            float(L0) / r0,
            float(l0) / r0,
            rng,
            SUBHARMONIC_LEVELS if subharmonics else 0,
        )

    def window(self, shift) -> np.ndarray:
        """The (n, n) window starting ``shift`` pixels (float: Fourier-interpolated) along the strip."""
        length = self.strip.shape[1]
        if not np.isfinite(shift):
            raise ValueError(f"shift must be a finite number of pixels, got {shift!r}")
        if float(shift).is_integer():
            idx = (int(shift) + np.arange(self.n)) % length
            return self.strip[:, idx]
        f = np.fft.fftfreq(length)
        shifted = np.fft.ifft(
            np.fft.fft(self.strip, axis=1) * np.exp(2j * np.pi * f * shift), axis=1
        ).real
        return shifted[:, : self.n]

    def frames(self, count: int, step: float = 1.0) -> np.ndarray:
        """``count`` windows ``step`` pixels apart (frozen flow), shape ``(count, n, n)``."""
        return np.stack([self.window(k * step) for k in range(count)])


def remove_piston_tilt(phase, mask=None) -> np.ndarray:
    """Subtract the least-squares piston and tilt over ``mask`` (default: the whole screen) [rad].

    Parameters
    ----------
    phase : array_like, shape (..., ny, nx)
        Phase screen(s) [rad].
    mask : array_like of bool, shape (ny, nx), optional
        Pixels where the fit is made (default: all).

    Returns
    -------
    ndarray, shape (..., ny, nx)
        Phase with piston and tilt removed [rad]; 0 outside ``mask``.
    """
    phase = np.asarray(phase, float)
    ny, nx = phase.shape[-2:]
    y, x = np.mgrid[0:ny, 0:nx]
    m = np.ones((ny, nx), bool) if mask is None else np.asarray(mask, bool)
    if m.shape != (ny, nx) or m.sum() < 3:
        raise ValueError(
            f"mask must be a boolean ({ny}, {nx}) array with at least 3 pixels (piston and two "
            f"tilts), got shape {m.shape} with {int(m.sum())}"
        )
    G = np.stack([np.ones(m.sum()), x[m], y[m]], 1)
    coef, *_ = np.linalg.lstsq(G, phase[..., m].reshape(-1, m.sum()).T, rcond=None)
    plane = coef[0][:, None, None] + coef[1][:, None, None] * x + coef[2][:, None, None] * y
    out = phase - plane.reshape(phase.shape)
    return np.where(m, out, 0.0)


def structure_function(screens, max_separation: int) -> tuple[np.ndarray, np.ndarray]:
    """Empirical phase structure function <[phi(x + r) - phi(x)]^2> along both axes.

    Parameters
    ----------
    screens : array (..., n, n)
    max_separation : int [pixels]

    Returns
    -------
    r : ndarray of separations [pixels] 1..max_separation;  D : ndarray [rad^2].
    """
    s = np.asarray(screens, float)
    seps = np.arange(1, max_separation + 1)
    D = np.array(
        [
            0.5
            * (
                np.mean((s[..., :, k:] - s[..., :, :-k]) ** 2)
                + np.mean((s[..., k:, :] - s[..., :-k, :]) ** 2)
            )
            for k in seps
        ]
    )
    return seps, D


def structure_function_theory(r, r0, L0=np.inf, l0=0.0) -> np.ndarray:
    """Phase structure function from the spectrum by quadrature: D(r) = 4 pi int Phi(f) (1 - J0(2 pi f r)) f df.

    Independent of the screen generator; for ``L0 = inf, l0 = 0`` it equals 6.88 (r/r0)^(5/3).

    Parameters
    ----------
    r : array_like
        Separations [m].
    r0 : float
        Fried parameter [m].
    L0 : float
        Outer scale [m] (``inf``: none).
    l0 : float
        Inner scale [m] (0: none).

    Returns
    -------
    ndarray, shape (N,)
        D(r) [rad^2] at the ``N`` separations (``r`` flattened to at least 1-D).
    """
    r = np.atleast_1d(np.asarray(r, float))
    out = np.empty(r.shape)
    for i, ri in enumerate(r):
        # in u = 2 pi f r: D = 4 pi (2 pi r)^-2 int Phi(u / 2 pi r) (1 - J0(u)) u du; [0, 200] in segments,
        # the tail without J0 (there |J0| Phi u ~ u^(-19/6): < 1e-7 of the total)
        c = 2 * np.pi * ri

        def g(u, c=c):
            u2 = u * u
            one_minus_j0 = u2 / 4 - u2 * u2 / 64 + u2**3 / 2304 if u < 0.1 else 1 - special.j0(u)
            return phase_psd(u / c, r0, L0, l0) * one_minus_j0 * u

        # [0, 1] with u = t^3 (the integrand ~ u^(-2/3) at 0 for Kolmogorov), then segments of 10
        head = integrate.quad(lambda t: g(t**3) * 3 * t * t, 0.0, 1.0, limit=200)[0]
        edges = np.r_[1.0, np.arange(10.0, 201.0, 10.0)]
        body = head + sum(
            integrate.quad(g, a, b, limit=200)[0] for a, b in zip(edges[:-1], edges[1:])
        )
        tail = integrate.quad(
            lambda u, c=c: phase_psd(u / c, r0, L0, l0) * u, 200.0, np.inf, limit=200
        )[0]
        out[i] = 4 * np.pi * (body + tail) / c**2
    return out


def phase_variance_theory(r0, L0, l0=0.0) -> float:
    """Total phase variance [rad^2] of von Karman turbulence: 2 pi int Phi(f) f df (finite for
    finite L0).

    Parameters
    ----------
    r0 : float
        Fried parameter [m].
    L0 : float
        Outer scale [m], finite.
    l0 : float
        Inner scale [m] (0: none).

    Returns
    -------
    float
        Phase variance [rad^2].
    """
    if np.isinf(L0):
        raise ValueError("the phase variance of Kolmogorov turbulence (L0 = inf) is infinite")
    return (
        2 * np.pi * integrate.quad(lambda f: phase_psd(f, r0, L0, l0) * f, 0, np.inf, limit=400)[0]
    )
