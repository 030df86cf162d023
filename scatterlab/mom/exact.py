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

from scatterlab._checks import as_finite, as_index, as_positive

__all__ = ["cylinder_echo_width", "cylinder_surface_field", "cylinder_coefficients"]


def _orders(ka, m=None):
    # beyond |n| ~ ka the fields outside and on the surface fall off as J_n(ka) / H_n(ka) ~ (ka/2n)^(2n)
    # whatever the index: orders up to ka Re(m) (counted before) changed no echo width by a bit, for
    # m from 0.5 to 1e3 - 1e3j, and made |m| = 1e5 take 2e6 orders (30 s)
    N = int(np.ceil(ka + 4 * ka ** (1 / 3) + (15 if m is not None else 10)))
    return np.arange(-N, N + 1)


def _checked(ka, polarization, eta):
    ka = float(as_positive(ka, "ka"))
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
        Electrical radius ``k a`` [dimensionless].
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
        Surface-field coefficients c_n.
    """
    ka, eta = _checked(ka, polarization, eta)
    n = _orders(ka, eta)
    x = ka
    J, H = special.jv(n, x), special.hankel2(n, x)
    Jp, Hp = special.jvp(n, x), special.h2vp(n, x)
    if eta is None:
        a = J / H if polarization == "s" else Jp / Hp
    else:
        mx = eta * x
        with np.errstate(
            over="ignore", invalid="ignore", divide="ignore"
        ):  # far orders: dropped below
            L = (special.jve(n - 1, mx) - special.jve(n + 1, mx)) / (2 * special.jve(n, mx))
            q = eta if polarization == "s" else 1 / eta
            a = (Jp - q * L * J) / (Hp - q * L * H)
    a = np.where(np.isfinite(a), a, 0.0)  # far orders whose H_n overflowed contribute nothing
    return n, a, J - a * H


def cylinder_echo_width(
    ka, phi, wavelength: float = 1.0, *, polarization: str = "s", eta=None
) -> np.ndarray:
    """sigma_2D(phi) [m] for a cylinder of electrical radius ``ka``; ``phi`` [rad] from forward.

    ``eta=None`` is the perfect conductor; ``polarization`` "s" (E_z) or "p" (H_z).

    Parameters
    ----------
    ka : float
        Electrical radius ``k a`` [dimensionless].
    phi : array_like
        Scattering angle from the forward direction [rad].
    wavelength : float
        Wavelength [m].
    polarization : {"s", "p"}
        ``"s"`` (E_z) or ``"p"`` (H_z).
    eta : complex, optional
        Refractive index of the cylinder; None is the perfect conductor.

    Returns
    -------
    ndarray, shape of ``phi``
        Echo width sigma_2D [m].
    """
    wavelength = float(as_positive(wavelength, "wavelength"))
    n, a, _ = cylinder_coefficients(ka, polarization, eta)
    k = 2 * np.pi / wavelength
    phi = as_finite(phi, "phi")
    s = np.exp(1j * np.multiply.outer(phi, n)) @ a
    return 4 / k * np.abs(s) ** 2


def cylinder_surface_field(ka, phi, wavelength: float = 1.0) -> np.ndarray:
    """Exact U = d psi / d rho on a PEC cylinder's surface (s-pol) at angles ``phi`` (checks the MoM
    current).

    Parameters
    ----------
    ka : float
        Electrical radius ``k a`` [dimensionless].
    phi : array_like
        Angles on the surface [rad].
    wavelength : float
        Wavelength [m].

    Returns
    -------
    ndarray, shape of ``phi``, complex
        U = d psi / d rho [1/m] for a unit-amplitude incident plane wave.
    """
    ka = float(as_positive(ka, "ka"))
    k = 2 * np.pi / wavelength
    n = _orders(ka)
    # d/drho [J_n - J_n(ka)/H_n(ka) H_n] at rho = a  =  k [J_n' H_n - J_n H_n'] / H_n = k * (2j/(pi ka)) / H_n
    wr = 2j / (np.pi * ka)
    coef = (1j ** (-n.astype(float))) * k * wr / special.hankel2(n, ka)
    return np.exp(1j * np.multiply.outer(np.asarray(phi, float), n)) @ coef
