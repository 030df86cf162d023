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
  exact at small separations. Measured: the structure function averaged over many screens is within 5 % of
  6.88 (r/r0)^(5/3) from 2 px to D/2 (tests; 0.93 at 1 px); a single screen scatters widely about it
  (256 px: 5-95 % of screens at 0.77-1.40 of it at 2 px, 0.54-1.92 at 20 px).
  An outer scale must span at least 10 pixels (:data:`MIN_OUTER_SCALE_PIXELS`): below, a growing share
  of the phase variance (over 5 %, half at 2 px) lies beyond the grid's Nyquist frequency.
* Extreme values: the spectra are evaluated without overflow (0 where they are below the smallest
  double, inf only where they are infinite, a ValueError where a finite value exceeds the largest);
  :func:`structure_function_theory` works in ``u = 2 pi f r``, so D(0) = 0 and r from 1e-300 m to 1e300 m.

Units: lengths in metres, phases in radians, frequencies in cycles per metre unless stated. Every
random routine takes ``rng``.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from scipy import integrate, special

from scatterlab._checks import as_count, as_finite, as_positive, as_rng, as_scalar

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


_LOG_MAX = float(np.log(np.finfo(float).max))  # 709.78: exp of more overflows double precision


def _positive_scalar(value, name: str) -> float:
    """A single finite number > 0 (a length, r0)."""
    if np.ndim(value) != 0:
        raise ValueError(
            f"{name} must be a single number > 0, got an array of shape {np.shape(value)}"
        )
    return float(as_positive(value, name))


def _finite_scalar(value, name: str) -> float:
    """A single finite number (a shift in pixels)."""
    if np.ndim(value) != 0:
        raise ValueError(
            f"{name} must be a single finite number of pixels, got an array of shape "
            f"{np.shape(value)}"
        )
    return float(as_finite(value, name))


def _outer_scale(L0) -> float:
    """The outer scale [m]: > 0 or +inf (none)."""
    if np.ndim(L0) != 0 or not (L0 == np.inf or (np.isfinite(L0) and L0 > 0)):
        raise ValueError(f"L0 (outer scale) must be > 0 or +inf [m], got {L0!r}")
    return float(L0)


def _inner_scale(l0) -> float:
    """The inner scale [m]: finite and >= 0 (0: none)."""
    if np.ndim(l0) != 0 or not (np.isfinite(l0) and l0 >= 0):
        raise ValueError(f"l0 (inner scale) must be a finite length >= 0 [m], got {l0!r}")
    return float(l0)


def _scales(L0, l0) -> tuple[float, float]:
    """The outer and inner scales [m], checked one by one and together: ``l0 <= L0``."""
    L0, l0 = _outer_scale(L0), _inner_scale(l0)
    if l0 > L0:
        raise ValueError(
            f"l0 (inner scale) must not exceed L0 (outer scale): 0 <= l0 <= L0, got l0 = {l0:g} m "
            f"> L0 = {L0:g} m (the inertial range between them would be empty)"
        )
    return L0, l0


def _power_law(h, hscale, log_c, k, xscale, too_small):
    """``c h^(-11/3) exp(-x^2)``, ``c = hscale^(11/3) = exp(log_c)``, ``x = k xscale``, without overflow.

    ``h >= 0`` and ``k >= 0`` have one shape, ``xscale >= 0`` may be inf. ``h = 0`` (then ``k = 0``) gives
    inf, the spectrum's true value there; a finite value beyond the double range raises
    ``ValueError(too_small(h_min))``, where ``h_min = hscale * max^(-3/11)`` is the smallest ``h`` whose
    power law is representable.
    """
    h, k = np.asarray(h, float), np.asarray(k, float)
    with np.errstate(
        over="ignore", invalid="ignore"
    ):  # inf where x overflows: exp(-x^2) is 0 there
        x = np.where(k == 0, 0.0, k * xscale)
    gauss = np.exp(
        -(np.minimum(x, 30.0) ** 2)
    )  # exp(-900) is 0 in double precision: no overflow of x^2
    # h / hscale overflows to inf only where the value is below the smallest double (then 0 is right);
    # its -11/3 power overflows only where the power law does, handled below
    with np.errstate(divide="ignore", over="ignore"):
        p = (h / hscale) ** (-11 / 3)
    big = np.isinf(p) & (h > 0)
    out = np.where(big, 0.0, p) * gauss
    if np.any(big):
        logv = log_c - 11 / 3 * np.log(h[big]) - np.minimum(x[big], 1e150) ** 2
        if np.any(logv > _LOG_MAX):
            raise ValueError(too_small(hscale * np.exp(-3 / 11 * _LOG_MAX)))
        out[big] = np.exp(logv)
    return out


def kolmogorov_psd(kappa, cn2):
    """Kolmogorov refractive-index spectrum (Eq. 70) [m^3] at spatial frequency ``kappa`` [rad/m].

    Parameters
    ----------
    kappa : array_like
        Spatial frequency [rad/m], > 0 (and large enough that the spectrum fits in double precision,
        ``kappa >= (0.033 C_n^2 / 1.8e308)^(3/11)``: 1e-84 rad/m for ``C_n^2 = 1e-14``).
    cn2 : float
        Refractive-index structure constant C_n^2 [m^(-2/3)], >= 0.

    Returns
    -------
    ndarray, shape of ``kappa``
        ``0.033 C_n^2 kappa^(-11/3)`` [m^3].

    Raises
    ------
    ValueError
        ``kappa <= 0``, ``cn2 < 0``, or a spectrum beyond the largest double.
    """
    kappa = as_positive(kappa, "kappa")
    c = 0.033 * _nonnegative_scalar(cn2, "cn2")
    if c == 0:
        return np.zeros(kappa.shape)
    return _power_law(
        kappa,
        c ** (3 / 11),
        np.log(c),
        kappa,
        0.0,
        lambda kmin: (
            f"kappa must be >= {kmin:.3g} rad/m for cn2 = {cn2:g} m^(-2/3): below, the spectrum exceeds "
            "the largest double (1.8e308 m^3)"
        ),
    )


def _nonnegative_scalar(value, name: str) -> float:
    if np.ndim(value) != 0:
        raise ValueError(
            f"{name} must be a single number >= 0, got an array of shape {np.shape(value)}"
        )
    return float(as_positive(value, name, allow_zero=True))


def von_karman_psd(kappa, cn2, L0=np.inf, l0=0.0):
    """Modified von Karman refractive-index spectrum [m^3] with outer scale ``L0`` and inner scale
    ``l0`` [m].

    Parameters
    ----------
    kappa : array_like
        Spatial frequency [rad/m], >= 0 (``kappa = 0`` with ``L0 = inf`` gives inf, the true value).
    cn2 : float
        Refractive-index structure constant C_n^2 [m^(-2/3)], >= 0.
    L0 : float
        Outer scale [m], > 0 (``inf``: none).
    l0 : float
        Inner scale [m], finite, >= 0 (0: none) and <= ``L0``.

    Returns
    -------
    ndarray, shape of ``kappa``
        ``0.033 C_n^2 exp(-kappa^2 / kappa_m^2) (kappa^2 + kappa_0^2)^(-11/6)`` [m^3], computed without
        overflow (underflows to 0 where the spectrum is below the smallest double).

    Raises
    ------
    ValueError
        Arguments out of range, or a finite spectrum beyond the largest double (``kappa`` and
        ``2 pi / L0`` both below ``(0.033 C_n^2 / 1.8e308)^(3/11)``).
    """
    kappa = as_positive(kappa, "kappa", allow_zero=True)
    c = 0.033 * _nonnegative_scalar(cn2, "cn2")
    L0, l0 = _scales(L0, l0)
    if c == 0:
        return np.zeros(kappa.shape)
    # Python floats: 2 pi / L0 for L0 = 1e-320 is inf (spectrum 0), without a numpy warning
    k0 = 0.0 if np.isinf(L0) else 2 * np.pi / L0
    return _power_law(
        np.hypot(kappa, k0),  # (kappa^2 + k0^2)^(1/2) without overflow of the squares
        c ** (3 / 11),
        np.log(c),
        kappa,
        l0 / 5.92,  # x = kappa / kappa_m
        lambda kmin: (
            f"kappa and 2 pi / L0 must not both be below {kmin:.3g} rad/m for cn2 = {cn2:g} m^(-2/3): "
            "the spectrum then exceeds the largest double (1.8e308 m^3)"
        ),
    )


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

    The constant is :data:`PSD_CONSTANT` = 0.022896 (Eq. 79's 0.0229), exact for D(r) = 6.8839 (r/r0)^(5/3);
    ``fm = 5.92 / (2 pi l0)``.

    Parameters
    ----------
    f : array_like
        Spatial frequency [cycles/m], finite; signed frequencies (``numpy.fft.fftfreq``) are allowed, the
        spectrum is isotropic. ``f = 0`` with ``L0 = inf`` gives inf, the true value.
    r0 : float
        Fried parameter [m], > 0.
    L0 : float
        Outer scale [m], > 0 (``inf``: none).
    l0 : float
        Inner scale [m], finite, >= 0 (0: none) and <= ``L0``.

    Returns
    -------
    ndarray, shape of ``f``
        Phase power spectral density [rad^2 m^2], computed without overflow (underflows to 0 where the
        spectrum is below the smallest double).

    Raises
    ------
    ValueError
        Arguments out of range, or a finite spectrum beyond the largest double (``sqrt(f^2 + 1/L0^2)``
        below ``(0.0229 / 1.8e308)^(3/11) r0^(-5/11)``, e.g. ``f = 1``, ``r0 = 1e-200``).
    """
    f = np.abs(as_finite(f, "f"))
    r0 = _positive_scalar(r0, "r0")
    L0, l0 = _scales(L0, l0)
    f0 = 0.0 if np.isinf(L0) else 1.0 / L0  # Python floats: inf for L0 = 1e-320, without a warning
    # A r0^(-5/3) h^(-11/3) = (h / hscale)^(-11/3) with hscale = A^(3/11) r0^(-5/11): r0^(-5/3) itself may
    # overflow (r0 = 1e-200) where the spectrum does not
    return _power_law(
        np.hypot(f, f0),
        PSD_CONSTANT ** (3 / 11) * r0 ** (-5 / 11),
        np.log(PSD_CONSTANT) - 5 / 3 * np.log(r0),
        f,
        2 * np.pi * l0 / 5.92,  # x = f / fm
        lambda fmin: (
            f"f and 1 / L0 must not both be below {fmin:.3g} cycles/m for r0 = {r0:g} m: the phase "
            "spectrum then exceeds the largest double (1.8e308 rad^2 m^2)"
        ),
    )


def _log_path_integral(cn2, L: float, weight=None, mean_weight: float = 1.0) -> float:
    """``log int_0^L C_n^2(z) w(z) dz`` [log m^(1/3)], ``w = 1`` without ``weight``.

    A constant ``cn2`` gives ``log cn2 + log L + log mean_weight`` (``mean_weight`` is the mean of ``w``
    over the path), which never overflows; a profile ``cn2(z)`` is integrated by quadrature, and the
    integral must be finite and > 0.
    """
    if callable(cn2):
        integrand = cn2 if weight is None else (lambda z: cn2(z) * weight(z))
        integral = integrate.quad(integrand, 0, L)[0]
        if not (math.isfinite(integral) and integral > 0):
            raise ValueError(
                "cn2 (a profile cn2(z) [m^(-2/3)]) must integrate to a finite positive value over the "
                f"path [0, {L:g}] m, got {integral!r}"
            )
        return math.log(integral)
    c = as_scalar(cn2, "cn2", 0.0, open_lo=True, unit=" [m^(-2/3)] (or a profile cn2(z))")
    return math.log(c) + math.log(L) + math.log(mean_weight)


def _shown(cn2) -> str:
    """``cn2`` for a message: the number, or "a profile"."""
    return "a profile" if callable(cn2) else f"{float(cn2):g} m^(-2/3)"


def _exp_or_refuse(log_value: float, message: str) -> float:
    """``exp(log_value)``: 0.0 where it is below the smallest double (the correct limit), a ValueError with
    ``message`` where it exceeds the largest."""
    if log_value > _LOG_MAX:
        raise ValueError(message)
    return math.exp(log_value)  # math.exp underflows to 0.0 without an error


def fried_parameter(cn2, path_length, wavelength):
    """Fried parameter r0 [m] (Eqs. 74-75), plane wave: ``r0 = (0.423 k^2 int C_n^2 dz)^(-3/5)``.

    Evaluated in logarithms, so no intermediate overflows or underflows: ``k^2`` of a wavelength of 1e200 m
    is below the smallest double, but ``r0`` is not.

    Parameters
    ----------
    cn2 : float or callable
        Constant C_n^2 [m^(-2/3)], a single finite number > 0, or a profile ``cn2(z)`` [m^(-2/3)]
        integrated over ``[0, path_length]`` (the integral must be finite and > 0).
    path_length : float
        Propagation path length [m], a single finite number > 0.
    wavelength : float
        Wavelength [m], a single finite number > 0.

    Returns
    -------
    float
        Fried parameter r0 [m]; 0.0 where it is below the smallest double (extremely strong turbulence,
        the correct limit).

    Raises
    ------
    ValueError
        An argument out of range (``None`` and strings included), or an ``r0`` beyond the largest double
        (1.8e308 m: extremely weak turbulence or a huge wavelength, e.g. ``cn2 = 1e-14``, ``L = 1e3``,
        ``wavelength = 1e270``).
    """
    L = as_scalar(path_length, "path_length", 0.0, open_lo=True, unit=" [m]")
    lam = as_scalar(wavelength, "wavelength", 0.0, open_lo=True, unit=" [m]")
    log_c = _log_path_integral(cn2, L)
    # log r0 = -3/5 [log 0.423 + 2 log(2 pi) - 2 log(lambda) + log int C_n^2 dz]
    log_r0 = -0.6 * (math.log(0.423) + 2 * math.log(2 * math.pi) - 2 * math.log(lam) + log_c)
    return _exp_or_refuse(
        log_r0,
        f"r0 exceeds the largest double (1.8e308 m) for cn2 = {_shown(cn2)}, path_length = {L:g} m and "
        f"wavelength = {lam:g} m: the turbulence is too weak (cn2 * path_length too small) or the "
        "wavelength too long",
    )


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

    ``sigma_R^2 = 2.25 k^(7/6) L^(5/6) int_0^L C_n^2(z) (1 - z/L)^(5/6) dz``, i.e. ``1.23 C_n^2 k^(7/6)
    L^(11/6)`` for a constant C_n^2; evaluated in logarithms (``k^(7/6)`` of a wavelength of 1e-300 m
    overflows, the variance may not).

    Parameters
    ----------
    cn2 : float or callable
        Constant C_n^2 [m^(-2/3)], a single finite number > 0, or a profile ``cn2(z)`` [m^(-2/3)] of the
        distance ``z`` [m] (its weighted integral must be finite and > 0).
    path_length : float
        Propagation path length [m], a single finite number > 0.
    wavelength : float
        Wavelength [m], a single finite number > 0.

    Returns
    -------
    float
        Rytov variance [dimensionless]; 0.0 where it is below the smallest double (the correct limit).

    Raises
    ------
    ValueError
        An argument out of range (``None`` and strings included), or a variance beyond the largest double
        (1.8e308, e.g. ``wavelength = 1e-300`` m): the weak-fluctuation theory is meaningless long before.
    """
    L = as_scalar(path_length, "path_length", 0.0, open_lo=True, unit=" [m]")
    lam = as_scalar(wavelength, "wavelength", 0.0, open_lo=True, unit=" [m]")
    # the weight (1 - z/L)^(5/6) has the mean 6/11 over the path
    log_c = _log_path_integral(cn2, L, lambda z: (1 - z / L) ** (5 / 6), 6 / 11)
    log_k = math.log(2 * math.pi) - math.log(lam)
    log_s2 = math.log(2.25) + 7 / 6 * log_k + 5 / 6 * math.log(L) + log_c
    s2 = _exp_or_refuse(
        log_s2,
        f"the Rytov variance exceeds the largest double (1.8e308) for cn2 = {_shown(cn2)}, path_length = "
        f"{L:g} m and wavelength = {lam:g} m: the wavelength is too short, or cn2 or path_length too "
        "large",
    )
    return _weak_check(s2)


def rytov_variance_from_r0(r0, path_length, wavelength):
    """Eq. 81: 2.91 [L / (k r0^2)]^(5/6) for constant C_n^2; warns when >= 0.2.

    Evaluated in logarithms (``r0^2`` of r0 = 1e-300 m underflows, the variance may not).

    Parameters
    ----------
    r0 : float
        Fried parameter [m], a single finite number > 0.
    path_length : float
        Propagation path length [m], a single finite number > 0.
    wavelength : float
        Wavelength [m], a single finite number > 0.

    Returns
    -------
    float
        Rytov variance [dimensionless]; 0.0 where it is below the smallest double (the correct limit).

    Raises
    ------
    ValueError
        An argument out of range (``None`` and strings included), or a variance beyond the largest double
        (1.8e308, e.g. ``r0 = 1e-300`` m with ``wavelength = 1e-300`` m).
    """
    r0 = as_scalar(r0, "r0", 0.0, open_lo=True, unit=" [m]")
    L = as_scalar(path_length, "path_length", 0.0, open_lo=True, unit=" [m]")
    lam = as_scalar(wavelength, "wavelength", 0.0, open_lo=True, unit=" [m]")
    log_k = math.log(2 * math.pi) - math.log(lam)
    log_s2 = math.log(2.91) + 5 / 6 * (math.log(L) - log_k - 2 * math.log(r0))
    s2 = _exp_or_refuse(
        log_s2,
        f"the Rytov variance exceeds the largest double (1.8e308) for r0 = {r0:g} m, path_length = "
        f"{L:g} m and wavelength = {lam:g} m: r0 is too small, or path_length or wavelength too large",
    )
    return _weak_check(s2)


MAX_D_OVER_R0 = 1e6  # a screen width over r0 beyond this has phase differences no grid samples
MIN_D_OVER_R0 = 1e-6  # below, the rms phase is under 1e-5 rad
# the largest inner scale over the screen width: at 10 the screens' structure function matches the quadrature
# (400 screens of 32 px: 0.998 at 1-16 px); from ~100 the spectrum lives below 1/100 of the FFT's frequency
# step and the cell integrals of the subharmonics warn (IntegrationWarning), lose accuracy (0.84 at 3e5) and
# give empty screens at 1e6
MAX_L0_OVER_D = 10.0
# the smallest outer scale in pixels, L0 / dx. The phase spectrum is flat below f = 1 / L0, so for an L0 of a
# few pixels much of the phase variance lies beyond the grid's Nyquist frequency 1 / (2 dx), where an FFT screen
# has no modes. Measured (400 screens of 64 px) against phase_variance_theory: the screens carry half the
# variance at L0 = 2 dx, 0.77 at 4 dx, 0.95 at 10 dx (structure function 0.90 of the quadrature at 2 px, 0.94-0.95
# from 4 px, comparable to the 0.93 of Kolmogorov screens at 1 px), and (L0 / dx)^2 / (1.2 pi) of it for
# L0 << dx. The true variance tends to 0 as L0 -> 0 (~ L0^(5/3): below the smallest double at L0 = 1e-300 m),
# but the screen's share of it tends to 0 too: below 10 px the screens are refused, not silently short.
MIN_OUTER_SCALE_PIXELS = 10.0


def _check_screen_args(n, dx, r0, L0, l0):
    if not (isinstance(n, (int, np.integer)) and n >= 4):
        raise ValueError("n (screen size in pixels) must be an integer >= 4")
    dx = float(as_positive(dx, "dx"))
    r0 = float(as_positive(r0, "r0"))
    L0, l0 = _scales(L0, l0)
    if L0 < MIN_OUTER_SCALE_PIXELS * dx:
        raise ValueError(
            f"L0 (outer scale) must be >= {MIN_OUTER_SCALE_PIXELS:g} dx = "
            f"{MIN_OUTER_SCALE_PIXELS * dx:g} m or inf for a grid spacing dx = {dx:g} m, got L0 = "
            f"{L0:g} m: a smaller outer scale puts a growing share of the phase variance (over 5 %, "
            "half at 2 dx) beyond the grid's Nyquist frequency, where the screen has no modes (use "
            "a finer grid)"
        )
    if l0 > MAX_L0_OVER_D * n * dx:
        raise ValueError(
            f"l0 (inner scale) must be in [0, {MAX_L0_OVER_D:g} n dx] = [0, {MAX_L0_OVER_D * n * dx:g}] m "
            f"for a screen {n * dx:g} m wide, got {l0:g}: a larger inner scale leaves the turbulence at "
            "frequencies the screen's subharmonics cannot resolve"
        )
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
        Outer scale [m], ``>= 10 dx`` (:data:`MIN_OUTER_SCALE_PIXELS`; a smaller one puts over 5 % of the
        phase variance beyond the grid's Nyquist frequency) or ``inf`` (Kolmogorov).
    subharmonics : bool
        Add low-frequency subharmonics (recommended: without them the structure function falls short at
        separations above ~ n dx / 10).
    l0 : float
        Inner scale [m], in ``[0, 10 n dx]`` (0: none; :data:`MAX_L0_OVER_D`) and ``<= L0``.

    Returns
    -------
    ndarray (n, n) of phase [rad]; statistically homogeneous with structure function
    ``6.88 (r/r0)^(5/3)`` for Kolmogorov turbulence.

    Raises
    ------
    ValueError
        ``n`` < 4, ``dx`` or ``r0`` <= 0, ``n dx / r0`` outside ``[1e-6, 1e6]``, ``L0`` below
        ``10 dx``, ``l0`` outside ``[0, 10 n dx]``, or ``l0 > L0``.
    """
    dx, r0 = _check_screen_args(n, dx, r0, L0, l0)
    rng = as_rng(rng)
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
        # a strip shorter than the window, or a fractional length (int() truncated 1.5 to 1), is refused
        length = (
            4 * n if length is None else as_count(length, "length", lo=n, unit=" [pixels] (>= n)")
        )
        rng = as_rng(rng)
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
        """The (n, n) window starting ``shift`` pixels along the strip.

        Parameters
        ----------
        shift : float
            Position along the strip [pixels], any finite number: the strip is periodic, so the
            shift is taken modulo its length (exactly, ``math.fmod``), and a fractional shift is
            Fourier-interpolated.

        Returns
        -------
        ndarray (n, n)
            Phase [rad].

        Raises
        ------
        ValueError
            ``shift`` not a single finite number.
        """
        length = self.strip.shape[1]
        # modulo the period first: exact, and int(1e20) + arange overflowed C longs
        shift = math.fmod(_finite_scalar(shift, "shift"), length)
        if shift.is_integer():
            idx = (int(shift) + np.arange(self.n)) % length
            return self.strip[:, idx]
        f = np.fft.fftfreq(length)
        shifted = np.fft.ifft(
            np.fft.fft(self.strip, axis=1) * np.exp(2j * np.pi * f * shift), axis=1
        ).real
        return shifted[:, : self.n]

    def frames(self, count: int, step: float = 1.0) -> np.ndarray:
        """``count`` windows ``step`` pixels apart (frozen flow).

        Parameters
        ----------
        count : int
            Number of frames, >= 1.
        step : float
            Shift between frames [pixels], any finite number (taken modulo the strip length).

        Returns
        -------
        ndarray (count, n, n)
            Phase [rad].
        """
        count = as_count(count, "count", lo=1)
        # modulo the strip length first (exact): k step cannot overflow
        step = math.fmod(_finite_scalar(step, "step"), self.strip.shape[1])
        return np.stack([self.window(k * step) for k in range(count)])


def remove_piston_tilt(phase, mask=None) -> np.ndarray:
    """Subtract the least-squares piston and tilt over ``mask`` (default: the whole screen) [rad].

    Only what the mask's pixels determine is removed: with pixels in general position, piston and the
    two tilts; with collinear pixels (a single row, column or diagonal, or two pixels) piston and the
    tilt along their line -- the tilt across it is constant on the mask, part of the piston there;
    with one pixel, piston alone. The result on the mask is then the residual of the least-squares fit
    of a plane, which is unique even where the plane is not.

    Parameters
    ----------
    phase : array_like, shape (..., ny, nx)
        Phase screen(s) [rad], finite.
    mask : array_like of bool, shape (ny, nx), optional
        Pixels where the fit is made (default: all), at least 1.

    Returns
    -------
    ndarray, shape (..., ny, nx)
        Phase with piston and tilt removed [rad]; 0 outside ``mask`` (and everywhere for a mask of 1
        or 2 pixels, or of collinear pixels on which the phase is linear).

    Raises
    ------
    ValueError
        ``phase`` not finite or not at least 2-D, or ``mask`` of another shape or empty.
    """
    phase = as_finite(phase, "phase")
    if phase.ndim < 2:
        raise ValueError(
            f"phase must be a screen (ny, nx) or a stack (..., ny, nx), got shape {phase.shape}"
        )
    ny, nx = phase.shape[-2:]
    m = np.ones((ny, nx), bool) if mask is None else np.asarray(mask, bool)
    if m.shape != (ny, nx) or not m.any():
        raise ValueError(
            f"mask must be a boolean ({ny}, {nx}) array with at least 1 pixel, got shape {m.shape} "
            f"with {int(m.sum())}"
        )
    y, x = np.nonzero(m)
    G = np.stack([np.ones(x.size), *_tilt_coordinates(x, y)], 1)
    data = phase[..., m].reshape(-1, x.size).T  # (pixels, screens)
    coef, *_ = np.linalg.lstsq(G, data, rcond=None)
    out = np.zeros(phase.shape)
    out[..., m] = (data - G @ coef).T.reshape(phase.shape[:-2] + (x.size,))
    return out


def _tilt_coordinates(x, y) -> list[np.ndarray]:
    """The tilt regressors the pixels ``(x, y)`` determine, centred: ``[x, y]`` in general position,
    the coordinate along their line if collinear, none for a single pixel. Collinearity is decided
    exactly, in integers: ``n^2 det(cov) = (n Sxx - Sx^2)(n Syy - Sy^2) - (n Sxy - Sx Sy)^2 = 0``."""
    n = x.size
    sx, sy = int(x.sum()), int(y.sum())
    cxx = n * int((x * x).sum()) - sx * sx
    cyy = n * int((y * y).sum()) - sy * sy
    cxy = n * int((x * y).sum()) - sx * sy
    u, v = x - sx / n, y - sy / n
    if cxx * cyy - cxy * cxy != 0:
        return [u, v]
    if cxx == 0 and cyy == 0:
        return []
    # the line's direction: (cxx, cxy) or (cxy, cyy), whichever is not zero (cov is rank 1)
    dx, dy = (float(cxx), float(cxy)) if cxx else (float(cxy), float(cyy))
    return [(u * dx + v * dy) / math.hypot(dx, dy)]


def structure_function(screens, max_separation: int) -> tuple[np.ndarray, np.ndarray]:
    """Empirical phase structure function <[phi(x + r) - phi(x)]^2> along both axes.

    Parameters
    ----------
    screens : array_like, shape (..., ny, nx)
        Phase screen(s) [rad], finite.
    max_separation : int
        Largest separation [pixels], in ``[1, min(ny, nx) - 1]``.

    Returns
    -------
    r : ndarray of int, shape (max_separation,)
        Separations 1..max_separation [pixels].
    D : ndarray, shape (max_separation,)
        Structure function [rad^2], averaged over the two axes and all screens. Computed on the screens
        scaled by a power of two to ``|phase| <= 1`` (exact), so phases of any magnitude are handled; 0
        where it is below the smallest double.

    Raises
    ------
    ValueError
        ``screens`` not finite or not at least 2-D, ``max_separation`` out of range, or a structure
        function beyond the largest double (phase differences above ~1e154 rad).
    """
    s = as_finite(screens, "screens")
    if s.ndim < 2 or min(s.shape[-2:]) < 2:
        raise ValueError(
            f"screens must be a screen (ny, nx) or a stack (..., ny, nx) with ny, nx >= 2, got shape {s.shape}"
        )
    n = min(s.shape[-2:])
    k_max = as_count(max_separation, "max_separation", lo=1, unit=" [pixels]")
    if k_max > n - 1:
        raise ValueError(
            f"max_separation must be in [1, {n - 1}] pixels (the screens are {s.shape[-2]} x {s.shape[-1]}: "
            f"a separation of {k_max} has no pixel pairs), got {max_separation!r}"
        )
    seps = np.arange(1, k_max + 1)
    # scaled by a power of two to |phase| <= 1 (exact): the differences and their squares cannot overflow
    # (phases of 1e300 rad), and the result is scaled back exactly unless it leaves the double range
    exponent = math.frexp(float(np.max(np.abs(s), initial=0.0)))[1]
    s = np.ldexp(s, -exponent)
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
    with np.errstate(over="ignore", under="ignore"):
        D = np.ldexp(
            D, 2 * exponent
        )  # underflows to 0 for phases below ~1e-154 rad: the correct limit
    if not np.all(np.isfinite(D)):
        raise ValueError(
            "screens must have phase differences below ~1e154 rad: the structure function then "
            "exceeds the largest double (1.8e308 rad^2)"
        )
    return seps, D


# beyond r = 50 L0 / (2 pi) the von Karman covariance is below 1e-20 of the variance (a^(5/6) K_5/6(a),
# a = 2 pi r / L0): D(r) = 2 sigma^2 to double precision
_SATURATION = 50.0


def _structure_integral(a, um):
    """PSD_CONSTANT int_0^inf (u^2 + a^2)^(-11/6) exp(-(u/um)^2) (1 - J0(u)) u du: the structure function is
    D(r) = 4 pi (2 pi r / r0)^(5/3) times this, with a = 2 pi r / L0 (0: none), um = 5.92 r / l0 (inf: none).
    Plain floats, no overflow: near 0 the integrand is written as u^(-2/3) (1 + (a/u)^2)^(-11/6) (...)."""
    xs = 0.0 if np.isinf(um) else 1.0 / um

    def gauss(u):
        return math.exp(-(min(u * xs, 30.0) ** 2))

    def g(u):  # u >= 0.1
        return PSD_CONSTANT * math.hypot(u, a) ** (-11 / 3) * gauss(u) * (1 - special.j0(u)) * u

    def head(t):  # g(t^3) 3 t^2 on [0, 1]; below u = 0.1, 1 - J0(u) = u^2/4 - u^4/64 + u^6/2304
        u = t**3
        if u >= 0.1:
            return g(u) * 3 * t * t
        if u == 0:
            return 0.0 if a > 0 else 0.75 * PSD_CONSTANT
        series = 0.25 - u * u / 64 + u**4 / 2304
        return 3 * PSD_CONSTANT * math.hypot(1.0, a / u) ** (-11 / 3) * gauss(u) * series

    # [0, 1] with u = t^3 (the integrand ~ u^(-2/3) at 0 for Kolmogorov), split where the outer scale
    # bends the spectrum (u = a) and the inner scale cuts it off (the integrand lives below a few um);
    # then segments of 10, and the tail without J0 from where |J0| Phi u ~ u^(1/2) (u^2 + a^2)^(-11/6) is
    # below ~1e-7 of the total (~0.6 a^(-5/3) for a >> 1): u = 200 for a <= 1, further out for large a
    cuts = sorted(c ** (1 / 3) for c in (a, um, 3 * um, 6 * um) if 0 < c < 1)
    total = integrate.quad(head, 0.0, 1.0, limit=200, points=cuts or None)[0]
    end = 200.0 * max(1.0, a ** (6 / 11))
    edges = np.r_[1.0, np.arange(10.0, end + 10.0, 10.0)]
    total += sum(integrate.quad(g, lo, hi, limit=200)[0] for lo, hi in zip(edges[:-1], edges[1:]))

    # the tail int_E^inf A u (u^2 + a^2)^(-11/6) exp(-(u/um)^2) du in w = (u^2 + a^2)^(-5/6), dw = -(5/3) u
    # (u^2 + a^2)^(-11/6) du: (3/5) A int_0^w(E) exp(-(u(w)/um)^2) dw, a bounded integrand on a finite interval
    w_end = math.hypot(edges[-1], a) ** (-5 / 3)
    if np.isinf(um):
        return total + 0.6 * PSD_CONSTANT * w_end

    def tail(w):
        return gauss(math.sqrt(max(w ** (-6 / 5) - a * a, 0.0)))

    return total + 0.6 * PSD_CONSTANT * integrate.quad(tail, 0.0, w_end, limit=200)[0]


def structure_function_theory(r, r0, L0=np.inf, l0=0.0) -> np.ndarray:
    """Phase structure function from the spectrum by quadrature: D(r) = 4 pi int Phi(f) (1 - J0(2 pi f r)) f df.

    Independent of the screen generator; for ``L0 = inf, l0 = 0`` it equals 6.88 (r/r0)^(5/3), for
    ``l0 = 0`` the von Karman closed form 2 sigma^2 [1 - 2^(1/6) a^(5/6) K_5/6(a) / Gamma(5/6)],
    ``a = 2 pi r / L0``. Computed in the dimensionless ``u = 2 pi f r``, so any ``r`` from 0 to 1e300 m;
    beyond ``a = 50`` the structure function is ``2 sigma^2`` (:func:`phase_variance_theory`) to double
    precision.

    Parameters
    ----------
    r : array_like
        Separations [m], finite and >= 0 (``D(0) = 0``).
    r0 : float
        Fried parameter [m], > 0.
    L0 : float
        Outer scale [m], > 0 (``inf``: none).
    l0 : float
        Inner scale [m], finite, >= 0 (0: none) and <= ``L0``.

    Returns
    -------
    ndarray, shape (N,)
        D(r) [rad^2] at the ``N`` separations (``r`` flattened to at least 1-D).

    Raises
    ------
    ValueError
        Arguments out of range, or a structure function beyond the largest double (``r / r0`` above
        ~1e184 for Kolmogorov turbulence).
    """
    r = np.atleast_1d(as_positive(r, "r", allow_zero=True)).ravel()
    r0 = _positive_scalar(r0, "r0")
    L0, l0 = _scales(L0, l0)
    out = np.zeros(r.shape)
    saturated = None
    for i, ri in enumerate(r):
        ri = float(ri)
        if ri == 0:
            continue  # D(0) = 0
        a = (
            0.0 if np.isinf(L0) else 2 * np.pi * (ri / L0)
        )  # Python floats: inf, not a warning, if huge
        if a > _SATURATION:
            if saturated is None:
                saturated = 2 * phase_variance_theory(r0, L0, l0)
            out[i] = saturated
            continue
        um = np.inf if l0 == 0 else 5.92 * (ri / l0)
        # 4 pi (2 pi r / r0)^(5/3) J in logarithms: r / r0 may overflow (r = 1e300, r0 = 1e-10)
        J = _structure_integral(a, um)
        if J == 0:
            continue  # the inner scale leaves nothing at this r (D ~ r^2 underflows)
        log_d = np.log(4 * np.pi * J) + 5 / 3 * (np.log(2 * np.pi) + np.log(ri) - np.log(r0))
        if log_d > _LOG_MAX:
            raise ValueError(
                f"r / r0 = {ri:g} / {r0:g} is too large: D(r) exceeds the largest double (1.8e308 rad^2); "
                "r must be smaller or r0 larger"
            )
        out[i] = np.exp(log_d)
    return out


def phase_variance_theory(r0, L0, l0=0.0) -> float:
    """Total phase variance [rad^2] of von Karman turbulence: 2 pi int Phi(f) f df (finite for
    finite L0).

    Computed in ``u = f L0``: sigma^2 = 2 pi (L0/r0)^(5/3) int Phi(u; r0 = 1, L0 = 1, l0 / L0) u du, which is
    ``0.0229 pi (6/5) (L0/r0)^(5/3)`` for ``l0 = 0``.

    Parameters
    ----------
    r0 : float
        Fried parameter [m], > 0.
    L0 : float
        Outer scale [m], finite and > 0.
    l0 : float
        Inner scale [m], finite, >= 0 (0: none) and <= ``L0``.

    Returns
    -------
    float
        Phase variance [rad^2].

    Raises
    ------
    ValueError
        ``L0 = inf`` (the variance is infinite), other arguments out of range, or a variance beyond the
        largest double (``L0 / r0`` above ~1e184).
    """
    r0 = _positive_scalar(r0, "r0")
    L0, l0 = _scales(L0, l0)
    if np.isinf(L0):
        raise ValueError("the phase variance of Kolmogorov turbulence (L0 = inf) is infinite")
    lam = l0 / L0
    um = np.inf if lam == 0 else 5.92 / (2 * np.pi * lam)  # the inner-scale cut-off in u

    xs = 0.0 if np.isinf(um) else 1.0 / um

    def g(u):  # Phi(u; 1, 1, lam) u, plain floats (u^2 + 1 >= 1: no overflow)
        return PSD_CONSTANT * (u * u + 1) ** (-11 / 6) * math.exp(-(min(u * xs, 30.0) ** 2)) * u

    cuts = [c for c in (um, 3 * um, 6 * um) if c < 1]
    integral = integrate.quad(g, 0.0, 1.0, limit=400, points=cuts or None)[0]
    integral += integrate.quad(g, 1.0, np.inf, limit=400)[0]
    if integral == 0:
        return 0.0
    log_var = np.log(2 * np.pi * integral) + 5 / 3 * (np.log(L0) - np.log(r0))
    if log_var > _LOG_MAX:
        raise ValueError(
            f"L0 / r0 = {L0:g} / {r0:g} is too large: the phase variance exceeds the largest double "
            "(1.8e308 rad^2)"
        )
    return float(np.exp(log_var))
