r"""Random rough surfaces with Gaussian heights and a Gaussian correlation function (spectral method).

The profile :math:`f(x)` of a surface of length ``L`` sampled every ``dx`` is synthesised by the FFT method of
Fung and Chen (Ref. 40; Thorsos 1988): complex Gaussian amplitudes weighted by the square root of the power
spectrum

.. math:: W(k) = \frac{\sigma_h^2 \ell}{2\sqrt\pi}\, e^{-k^2\ell^2/4}

(the transform of :math:`\sigma_h^2 e^{-x^2/\ell^2}`), made Hermitian so the profile is real. The profile is
periodic with period ``L``. Its rms slope is :math:`\sqrt2\,\sigma_h/\ell` -- the "2^(1/2) sigma_h / l" of
Fig. 39 and the per-axis facet slope ``sigma`` of the pBRDF (Eq. 128).
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_positive, as_rng

__all__ = ["rough_surface", "rms_slope", "correlation_length_for_slope", "gaussian_spectrum"]


def rms_slope(sigma_h, corr_length):
    """rms slope sqrt(2) sigma_h / l of a Gaussian-correlated surface (the pBRDF's sigma, Eq. 128).

    Parameters
    ----------
    sigma_h : array_like
        rms height [m] (>= 0).
    corr_length : array_like
        Correlation length [m] (> 0).

    Returns
    -------
    ndarray
        rms slope [dimensionless].

    Raises
    ------
    ValueError
        If ``sigma_h`` is not finite and >= 0 or ``corr_length`` not finite and > 0.
    """
    sigma_h = as_positive(sigma_h, "sigma_h", allow_zero=True)
    return np.sqrt(2) * sigma_h / as_positive(corr_length, "corr_length")


def correlation_length_for_slope(sigma_h, slope):
    """Correlation length l giving rms slope ``slope`` for rms height ``sigma_h``: l = sqrt(2)
    sigma_h / slope.

    Parameters
    ----------
    sigma_h : array_like
        rms height [m] (> 0).
    slope : array_like
        rms slope [dimensionless] (> 0).

    Returns
    -------
    ndarray
        Correlation length l [m].

    Raises
    ------
    ValueError
        If ``sigma_h`` or ``slope`` is not finite and > 0.
    """
    return np.sqrt(2) * as_positive(sigma_h, "sigma_h") / as_positive(slope, "slope")


def gaussian_spectrum(k, sigma_h, corr_length):
    """Two-sided power spectrum W(k) [m^3] of the Gaussian correlation function; integrates to
    sigma_h^2.

    Parameters
    ----------
    k : array_like
        Spatial frequency [rad/m].
    sigma_h : float
        rms height [m].
    corr_length : float
        Correlation length [m].

    Returns
    -------
    ndarray, shape of ``k``
        W(k) [m^3].
    """
    return sigma_h**2 * corr_length / (2 * np.sqrt(np.pi)) * np.exp(-((k * corr_length) ** 2) / 4)


def rough_surface(length, dx, sigma_h, corr_length, rng):
    """One realization of a Gaussian rough surface.

    Parameters
    ----------
    length : float [m] -- period of the profile; ``N = round(length / dx)`` samples.
    dx : float [m] -- sampling step; should be well below the correlation length (``dx <= l / 4``).
    sigma_h : float [m] -- rms height.
    corr_length : float [m] -- Gaussian correlation length ``l``.
    rng : numpy.random.Generator or seed

    Returns
    -------
    x, y : ndarrays (N,) [m] -- abscissae from ``-length/2`` and heights.
    """
    length = float(as_positive(length, "length"))
    dx = float(as_positive(dx, "dx"))
    sigma_h = float(as_positive(sigma_h, "sigma_h", allow_zero=True))
    corr_length = float(as_positive(corr_length, "corr_length"))
    if dx > corr_length / 4:
        raise ValueError(
            f"dx = {dx:g} must be at most corr_length / 4 = {corr_length / 4:g} to resolve the surface"
        )
    n = int(round(length / dx))
    if n < 8:
        raise ValueError("length must hold at least 8 samples of dx")
    rng = as_rng(rng)
    k = 2 * np.pi * np.fft.rfftfreq(n, dx)
    # y_j = sum over all k_m (positive and negative) of c_m exp(i k_m x_j), E|c_m|^2 = W(k_m) dk, c_-m = c_m*:
    # the variance sums W dk over the two-sided grid, i.e. sigma_h^2
    dk = 2 * np.pi / (n * dx)
    c = (rng.standard_normal(k.size) + 1j * rng.standard_normal(k.size)) / np.sqrt(2)
    c[0] = rng.standard_normal()  # the k = 0 and Nyquist terms are their own conjugates: real
    if n % 2 == 0:
        c[-1] = rng.standard_normal()
    c *= np.sqrt(gaussian_spectrum(k, sigma_h, corr_length) * dk)
    y = np.fft.irfft(c * n, n)  # irfft divides by n and adds the conjugate half
    x = (np.arange(n) - n / 2) * dx
    return x, y
