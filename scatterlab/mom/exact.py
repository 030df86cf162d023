r"""Exact series solution for a TM plane wave on a perfectly conducting circular cylinder.

Incident :math:`e^{-jkx} = \sum_n j^{-n}J_n(k\rho)e^{jn\phi}` (exp(+j w t)); on the cylinder of radius a the
total field vanishes, so :math:`\psi_s = -\sum_n j^{-n}\frac{J_n(ka)}{H^{(2)}_n(ka)}H^{(2)}_n(k\rho)e^{jn\phi}`
and the bistatic echo width (2-D radar cross-section) is

.. math:: \sigma_{2D}(\phi) = \frac{4}{k}\left|\sum_{n=-\infty}^{\infty}\frac{J_n(ka)}{H^{(2)}_n(ka)}e^{jn\phi}\right|^2

with phi measured from the direction of propagation (phi = pi is backscatter). The series is truncated at
:math:`|n| \le ka + 4(ka)^{1/3} + 10`, beyond which the terms fall below 1e-16 of the largest.
"""

from __future__ import annotations

import numpy as np
from scipy import special

from scatterlab._checks import as_positive

__all__ = ["cylinder_echo_width", "cylinder_surface_field"]


def _orders(ka):
    N = int(np.ceil(ka + 4 * ka ** (1 / 3) + 10))
    return np.arange(-N, N + 1)


def cylinder_echo_width(ka, phi, wavelength: float = 1.0) -> np.ndarray:
    """sigma_2D(phi) [m] for a PEC cylinder of electrical radius ``ka`` (TM); ``phi`` [rad] from forward."""
    ka = float(as_positive(ka, "ka"))
    k = 2 * np.pi / wavelength
    n = _orders(ka)
    coef = special.jv(n, ka) / special.hankel2(n, ka)
    phi = np.asarray(phi, float)
    s = np.exp(1j * np.multiply.outer(phi, n)) @ coef
    return 4 / k * np.abs(s) ** 2


def cylinder_surface_field(ka, phi, wavelength: float = 1.0) -> np.ndarray:
    """Exact U = d psi / d rho on the cylinder surface at angles ``phi`` (for checking the MoM current)."""
    ka = float(as_positive(ka, "ka"))
    k = 2 * np.pi / wavelength
    n = _orders(ka)
    # d/drho [J_n - J_n(ka)/H_n(ka) H_n] at rho = a  =  k [J_n' H_n - J_n H_n'] / H_n = k * (2j/(pi ka)) / H_n
    wr = 2j / (np.pi * ka)
    coef = (1j ** (-n.astype(float))) * k * wr / special.hankel2(n, ka)
    return np.exp(1j * np.multiply.outer(np.asarray(phi, float), n)) @ coef
