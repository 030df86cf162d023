r"""Exact series solutions for a plane wave on a circular cylinder: perfect conductor or penetrable, s and p.

Incident :math:`e^{-jkx} = \sum_n j^{-n}J_n(k\rho)e^{jn\phi}` (exp(+j w t)), :math:`\psi = E_z` (s) or
:math:`H_z` (p); outside :math:`\psi_1 = \sum_n j^{-n}[J_n(k\rho) - a_nH^{(2)}_n(k\rho)]e^{jn\phi}`, inside
(index :math:`m = \eta = n - j\kappa`) :math:`\psi_2 = \sum_n j^{-n}b_nJ_n(mk\rho)e^{jn\phi}`. Continuity of
:math:`\psi` and of :math:`\partial_\rho\psi` (s) or :math:`\epsilon^{-1}\partial_\rho\psi` (p) at
:math:`\rho = a` (x = ka) give (Bohren and Huffman, Absorption and Scattering of Light by Small Particles,
Sec. 8.4; Balanis, Advanced Engineering Electromagnetics, Sec. 11.5)

.. math:: a_n = \frac{J_n'(x) - qL_nJ_n(x)}{H_n'(x) - qL_nH_n(x)},\quad L_n = \frac{J_n'(mx)}{J_n(mx)},\quad
          q = m\ \text{(s)},\ 1/m\ \text{(p)}

and the perfect conductor is the limit :math:`a_n = J_n(x)/H_n(x)` (s, :math:`q\to\infty`) or
:math:`J_n'(x)/H_n'(x)` (p, :math:`q\to0`). The bistatic echo width (2-D radar cross-section) is

.. math:: \sigma_{2D}(\phi) = \frac{4}{k}\left|\sum_{n=-\infty}^{\infty}a_ne^{jn\phi}\right|^2

with phi measured from the direction of propagation (phi = pi is backscatter). :math:`L_n` is formed from
exponentially scaled Bessel functions (``jve``), so strongly absorbing cylinders do not overflow. The series
is truncated at :math:`|n| \le x\max(1, \mathrm{Re}\,m) + 4x^{1/3} + 15`.
"""

from __future__ import annotations

import numpy as np
from scipy import special

from scatterlab._checks import as_finite, as_index, as_scalar

__all__ = ["cylinder_echo_width", "cylinder_surface_field", "cylinder_coefficients"]

KA_MIN = 1e-300  # smallest electrical radius: 2/(pi ka) and H_1(ka) ~ 2j/(pi ka) stay finite
KA_MAX = 2e4  # largest electrical radius: the series' 2 ka + 4 (ka)^(1/3) orders cost O(ka) (PEC:
# 0.25 s at 2e4, 12 s at 1e6) and, for |eta| < 1, the continued fraction of the ratio J_(m+1)/J_m
# O(ka^2) (eta = 0.5: 1.2 s at 2e4, 28 s at 1e5); ka = 1e7 took 206 s


def _orders(ka, m=None):
    # beyond |n| ~ ka the fields outside and on the surface fall off as J_n(ka) / H_n(ka) ~ (ka/2n)^(2n)
    # whatever the index: orders up to ka Re(m) (counted before) changed no echo width by a bit, for
    # m from 0.5 to 1e3 - 1e3j, and made |m| = 1e5 take 2e6 orders (30 s)
    N = int(np.ceil(ka + 4 * ka ** (1 / 3) + (15 if m is not None else 10)))
    return np.arange(-N, N + 1)


def _checked_ka(ka):
    """``ka`` as one float in [KA_MIN, KA_MAX]; a ValueError naming ``ka`` otherwise."""
    if isinstance(ka, (str, bytes, bool, np.bool_)) or np.ndim(ka) != 0:
        raise ValueError(
            f"ka must be a single finite number in [{KA_MIN:g}, {KA_MAX:g}] (the electrical "
            f"radius of one cylinder), got {ka!r}"
        )
    ka = as_scalar(ka, "ka", 0.0, open_lo=True)
    if ka < KA_MIN:
        raise ValueError(
            f"ka must be >= {KA_MIN:g} (below it the Wronskian 2/(pi ka) overflows), got {ka:g}"
        )
    if ka > KA_MAX:
        raise ValueError(
            f"ka must be <= {KA_MAX:g}: the series has 2 ka orders and its cost grows as ka "
            f"(as ka^2 for |eta| < 1; seconds at ka = {KA_MAX:g}, minutes beyond 1e5), got {ka:g}"
        )
    return ka


def _checked(ka, polarization, eta):
    ka = _checked_ka(ka)
    if polarization not in ("s", "p"):
        raise ValueError(f"polarization must be 's' or 'p', got {polarization!r}")
    return ka, (None if eta is None else complex(as_index(eta, "eta")))


def cylinder_coefficients(ka, polarization: str = "s", eta=None):
    """Orders n (2N+1,), scattering coefficients a_n and surface-field coefficients c_n.

    The total field on the surface is :math:`\\sum_n j^{-n}c_ne^{jn\\phi}`, :math:`c_n = J_n(x) - a_nH_n(x)`
    (zero for the s-pol PEC); inside, :math:`\\psi_2 = \\sum_n j^{-n}c_n\\,J_n(mk\\rho)/J_n(mka)\\,e^{jn\\phi}`.

    Parameters
    ----------
    ka : float
        Electrical radius ``k a`` [dimensionless], one number in ``[1e-300, 2e4]`` (:data:`KA_MIN`,
        :data:`KA_MAX`: beyond 2e4 the series' cost, O(ka), and O(ka^2) for ``|eta| < 1``, passes
        seconds).
    polarization : {"s", "p"}
        ``"s"`` (E_z) or ``"p"`` (H_z).
    eta : complex, optional
        Refractive index of the cylinder; None is the perfect conductor.

    Returns
    -------
    n : ndarray of int, shape (2N+1,)
        Orders ``-N ... N``.
    a : ndarray, shape (2N+1,), complex
        Scattering coefficients a_n.
    c : ndarray, shape (2N+1,), complex
        Surface-field coefficients c_n, computed as :math:`-2j/(\\pi x D_n)` from the Wronskian
        (no cancellation); orders whose :math:`H_n(x)` overflows (:math:`|n| \\gg x`) have
        :math:`a_n = c_n = 0`, their small-argument limits below the smallest double.

    Raises
    ------
    ValueError
        ``ka`` not one finite number in [1e-300, 2e4], an unknown ``polarization``, ``eta`` out
        of range.
    """
    ka, eta = _checked(ka, polarization, eta)
    n = _orders(ka, eta)
    x = ka
    # With m = |n| (J_(-m) = (-1)^m J_m, the same for H; a_(-m) = a_m, c_(-m) = (-1)^m c_m):
    # a_n = N/D and, by the Wronskian J H' - J' H = -2j/(pi x), c_n = J - a_n H = -2j/(pi x D), with
    # D = H (s PEC: c = 0), H' (p PEC) or H' - q L H, all divided through by H: H'/H = H_(m-1)/H_m
    # - m/x (H' overflows first at small x), and L = m/(eta x) - r, r = J_(m+1)/J_m(eta x), so
    # that the m/x of J' and of q L cancel analytically in N (s-pol: N = -J_(m+1) + eta r J_m, not
    # a difference of two numbers 1e16 times larger). Where H_m overflows (m >> x: scipy gives
    # NaN) a_n ~ (x/2)^(2m)/(m!(m-1)!) and |c_n| < 2/(pi m |H_m|) are below the smallest double:
    # both are 0 there, not NaN.
    m = np.abs(n)
    sign = np.where((n < 0) & (m % 2 == 1), -1.0, 1.0)
    Jm, Jm1, H = special.jv(m, x), special.jv(m + 1, x), special.hankel2(m, x)
    far = ~np.isfinite(H)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # non-finite: set to 0
        H = np.where(far, 1.0, H)
        LH = np.where(m == 0, -special.hankel2(1, x) / H, special.hankel2(m - 1, x) / H - m / x)
        if eta is None:
            num, X = (Jm, 1.0) if polarization == "s" else (m / x * Jm - Jm1, LH)
        else:
            r = _bessel_ratio(m, eta * x)
            if polarization == "s":
                num, X = eta * r * Jm - Jm1, LH - m / x + eta * r
            else:
                num = m / x * (1 - 1 / eta**2) * Jm - Jm1 + r / eta * Jm
                X = LH - m / (eta**2 * x) + r / eta
        a = num / H / X  # in this order: H X overflows at small x where a and c do not
        c = -2j / (np.pi * x) / H / X * sign
    if eta is None and polarization == "s":
        c = np.zeros(n.shape, complex)  # psi = 0 on a perfect conductor
    ok = ~far & np.isfinite(a) & np.isfinite(c)
    return n, np.where(ok, a, 0.0), np.where(ok, c, 0.0)


def _bessel_ratio(m, z):
    """``J_(m+1)(z) / J_m(z)`` for orders ``m >= 0`` and complex ``z`` without overflow.

    From exponentially scaled Bessel functions (``jve``) where ``J_m(z)`` is representable; where
    it underflows (``|z| < m``), from the continued fraction ``r_m = 1 / (2(m+1)/z - r_(m+1))`` run
    down from ``m + |z| + 60``; NaN where scipy's ``jve`` fails (``|z|`` beyond ~1e17).
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        r = special.jve(m + 1, z) / special.jve(m, z)
        small = ~np.isfinite(r) & (m > abs(z))
        if small.any():
            k = m[small].astype(float)
            rs = np.zeros(k.shape, complex)
            for j in range(int(abs(z)) + 60, -1, -1):
                rs = 1 / (2 * (k + j + 1) / z - rs)
            r[small] = rs
    return r


def cylinder_echo_width(
    ka, phi, wavelength: float = 1.0, *, polarization: str = "s", eta=None
) -> np.ndarray:
    """sigma_2D(phi) [m] for a cylinder of electrical radius ``ka``; ``phi`` [rad] from forward.

    ``eta=None`` is the perfect conductor; ``polarization`` "s" (E_z) or "p" (H_z).

    Parameters
    ----------
    ka : float
        Electrical radius ``k a`` [dimensionless], one number in ``[1e-300, 2e4]`` (as
        :func:`cylinder_coefficients`).
    phi : array_like
        Scattering angle from the forward direction [rad], finite.
    wavelength : float
        Wavelength [m], finite and > 0.
    polarization : {"s", "p"}
        ``"s"`` (E_z) or ``"p"`` (H_z).
    eta : complex, optional
        Refractive index of the cylinder; None is the perfect conductor.

    Returns
    -------
    ndarray, shape of ``phi``
        Echo width sigma_2D [m].

    Raises
    ------
    ValueError
        ``ka`` not one finite number in [1e-300, 2e4], ``phi`` not finite, ``wavelength`` not one
        finite number > 0, an unknown ``polarization``, ``eta`` out of range.
    """
    wavelength = as_scalar(wavelength, "wavelength", 0.0, open_lo=True, unit=" [m]")
    phi = as_finite(phi, "phi")
    n, a, _ = cylinder_coefficients(ka, polarization, eta)
    k = 2 * np.pi / wavelength
    s = np.exp(1j * np.multiply.outer(phi, n)) @ a
    return 4 / k * np.abs(s) ** 2


def cylinder_surface_field(ka, phi, wavelength: float = 1.0) -> np.ndarray:
    """Exact U = d psi / d rho on a PEC cylinder's surface (s-pol) at angles ``phi`` (checks the MoM
    current).

    Parameters
    ----------
    ka : float
        Electrical radius ``k a`` [dimensionless], one number in ``[1e-300, 2e4]`` (as
        :func:`cylinder_coefficients`).
    phi : array_like
        Angles on the surface [rad], finite.
    wavelength : float
        Wavelength [m], finite and > 0.

    Returns
    -------
    ndarray, shape of ``phi``, complex
        U = d psi / d rho [1/m] for a unit-amplitude incident plane wave.

    Raises
    ------
    ValueError
        ``ka`` not one finite number in [1e-300, 2e4], ``phi`` not finite, ``wavelength`` not one
        finite number > 0 (the checks of :func:`cylinder_echo_width`).
    """
    ka = _checked_ka(ka)
    wavelength = as_scalar(wavelength, "wavelength", 0.0, open_lo=True, unit=" [m]")
    phi = as_finite(phi, "phi")
    k = 2 * np.pi / wavelength
    n = _orders(ka)
    # d/drho [J_n - J_n(ka)/H_n(ka) H_n] at rho = a  =  k [J_n' H_n - J_n H_n'] / H_n = k * (2j/(pi ka)) / H_n
    wr = 2j / (np.pi * ka)
    H = special.hankel2(n, ka)
    far = ~np.isfinite(H)  # overflowed (|n| >> ka): 1/H_n is below the smallest double there
    coef = np.where(far, 0.0, (1j ** (-n.astype(float))) * k * wr / np.where(far, 1.0, H))
    return np.exp(1j * np.multiply.outer(phi, n)) @ coef
