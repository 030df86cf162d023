r"""Complex index of refraction and Fresnel reflection at a smooth interface.

Conventions (stated once, tested in ``tests/test_fresnel.py``):

* Time dependence :math:`e^{+j\omega t}`; complex index :math:`\eta = n - j\kappa`
  with :math:`\kappa \ge 0` (reference text Sec. 2.4.5, Eq. 28). A positive
  imaginary part raises :class:`ValueError`.
* Angles in radians, :math:`\theta \in [0, \pi/2]` measured from the surface normal.
* Field coefficients follow Eq. 45 of the reference text,

  .. math::

     r_s = \frac{\cos\theta - \eta\cos\theta_t}{\cos\theta + \eta\cos\theta_t},\qquad
     r_p = \frac{\eta\cos\theta - \cos\theta_t}{\eta\cos\theta + \cos\theta_t},

  so that :math:`r_p = -r_s` at normal incidence and a perfect conductor has
  :math:`r_s = -1, r_p = +1`. Its smooth-surface Mueller matrix (Eq. 55) is then
  ``diag(1, 1, -1, -1)`` for a perfect mirror.
* The square root :math:`u = \eta\cos\theta_t = \sqrt{\eta^2 - \sin^2\theta} = A - jB`
  is the principal branch with :math:`A, B \ge 0` (errata to Eqs. 49 and 115,
  consistent with Eq. 84): the transmitted wave decays into the medium,
  including beyond the critical angle when :math:`n < 1`.

Numerics. Written naively, Eqs. 45 and 49 lose all relative accuracy when
:math:`\eta \to 1` (the numerator is a difference of nearly equal numbers) and
divide zero by zero at grazing incidence. Here they are rewritten exactly as

.. math::

   r_s = \frac{(1-\eta)(1+\eta)}{(\cos\theta + u)^2},\qquad
   r_p = \frac{(\eta-1)(\eta+1)\,(\eta^2\cos^2\theta - \sin^2\theta)}{(\eta^2\cos\theta + u)^2},

(multiply numerator and denominator by the conjugate-like factor) and
:math:`A, B` are computed without cancellation from :math:`AB = n\kappa`. The
results are finite for every physical input: :math:`\kappa` from 0 to 1e3,
:math:`n` from 0.01 to 20, :math:`\eta \to 1`, :math:`\theta` from 0 to exactly
:math:`\pi/2`.

References
----------
Reference text (AFIT/DEE/ENG/10-12), Eqs. 28, 45-55, 85.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from scatterlab._checks import as_angle, as_finite, as_index, as_positive, broadcast

__all__ = [
    "complex_index",
    "index_from_permittivity",
    "refraction_term",
    "coefficients",
    "transmission_coefficients",
    "reflectances",
    "transmittances",
    "mueller_matrix",
    "brewster_angle",
    "pseudo_brewster_angle",
]

EPSILON_0 = 8.8541878128e-12  # vacuum permittivity [F/m]
SPEED_OF_LIGHT = 299_792_458.0  # [m/s]


def complex_index(n, kappa) -> np.ndarray:
    """Complex index of refraction ``eta = n - 1j*kappa`` (Sec. 2.4.5).

    Parameters
    ----------
    n : array_like
        Real part, ``n >= 0`` [dimensionless].
    kappa : array_like
        Extinction coefficient, ``kappa >= 0`` [dimensionless].

    Returns
    -------
    eta : ndarray of complex, broadcast shape of ``n`` and ``kappa``.
    """
    n = as_positive(n, "n", allow_zero=True)
    kappa = as_positive(kappa, "kappa", allow_zero=True)
    n, kappa = broadcast(n=n, kappa=kappa)
    return as_index(n - 1j * kappa)


def index_from_permittivity(eps_r, conductivity=0.0, wavelength=None) -> np.ndarray:
    r"""Complex index from relative permittivity and conductivity (Eq. 28).

    :math:`\eta = \sqrt{\varepsilon'_r - j\sigma/(\omega\varepsilon_0)}` for a
    non-magnetic medium, principal root (so :math:`n > 0, \kappa \ge 0`).

    Parameters
    ----------
    eps_r : array_like
        Real relative permittivity :math:`\varepsilon'_r` (may be negative for metals).
    conductivity : array_like, optional
        Conductivity :math:`\sigma` [S/m], ``>= 0``.
    wavelength : array_like, optional
        Vacuum wavelength [m], required when ``conductivity`` is non-zero.

    Returns
    -------
    eta : ndarray of complex.
    """
    eps_r = as_finite(eps_r, "eps_r")
    conductivity = as_positive(conductivity, "conductivity", allow_zero=True)
    if np.any(conductivity > 0):
        if wavelength is None:
            raise ValueError("wavelength [m] is required when conductivity > 0")
        wavelength = as_positive(wavelength, "wavelength")
        omega = 2 * np.pi * SPEED_OF_LIGHT / wavelength
        loss = conductivity / (omega * EPSILON_0)
    else:
        loss = np.zeros_like(conductivity)
    eps_r, loss = broadcast(eps_r=eps_r, conductivity=loss)
    # Eq. 28 written without cancellation: n = sqrt((|eps| + eps')/2), kappa = loss/(2n).
    mag = np.hypot(eps_r, loss)
    big = np.sqrt((mag + np.abs(eps_r)) / 2)
    small = np.divide(loss, 2 * big, out=np.zeros_like(big), where=big > 0)
    n = np.where(eps_r >= 0, big, small)
    kappa = np.where(eps_r >= 0, small, big)
    return as_index(n - 1j * kappa, "eta (from eps_r, conductivity)")


def _refraction_term(eta: np.ndarray, cos2: np.ndarray) -> np.ndarray:
    """``A - jB = sqrt(eta^2 - sin^2) = sqrt((eta^2 - 1) + cos^2)``, ``A, B >= 0``, without cancellation.

    ``D = (n - 1)(n + 1) - kappa^2 + cos^2`` keeps full relative accuracy as eta -> 1
    at grazing incidence, where ``n^2 - sin^2`` would cancel.
    """
    n, kappa = eta.real, -eta.imag
    d = (n - 1) * (n + 1) - kappa * kappa + cos2
    nk = n * kappa
    w = np.hypot(d, 2 * nk)
    big = np.sqrt((w + np.abs(d)) / 2)
    small = np.divide(nk, big, out=np.zeros_like(big), where=big > 0)
    a = np.where(d >= 0, big, small)
    b = np.where(d >= 0, small, big)
    return a - 1j * b


def refraction_term(eta, theta) -> np.ndarray:
    r"""Normal component of the refracted wave vector, :math:`u = \eta\cos\theta_t`.

    :math:`u = \sqrt{\eta^2 - \sin^2\theta} = A - jB` with :math:`A, B \ge 0`
    (Eqs. 48-49 with the errata correction :math:`A = \sqrt{(\sqrt{C}+D)/2}`,
    :math:`B = \sqrt{(\sqrt{C}-D)/2}`, :math:`AB = n\kappa`).

    Parameters
    ----------
    eta : array_like of complex
        Complex index ``n - 1j*kappa``.
    theta : array_like
        Angle of incidence [rad] in ``[0, pi/2]``.

    Returns
    -------
    u : ndarray of complex, broadcast shape.
    """
    eta = as_index(eta)
    theta = as_angle(theta)
    eta, theta = broadcast(eta=eta, theta=theta)
    return _refraction_term(eta, np.cos(theta) ** 2)


def _coefficients(eta: np.ndarray, theta: np.ndarray):
    """Unchecked rs, rp (stable forms, see module docstring)."""
    c = np.cos(theta)
    s2 = np.sin(theta) ** 2
    u = _refraction_term(eta, c * c)
    one_minus_eta2 = (1 - eta) * (1 + eta)
    eta2 = eta * eta
    num_s = one_minus_eta2
    den_s = (c + u) ** 2
    num_p = -one_minus_eta2 * (eta2 * c * c - s2)
    den_p = (eta2 * c + u) ** 2
    # eta == 1 exactly at grazing incidence is 0/0; there is no interface: r = 0.
    rs = np.divide(num_s, den_s, out=np.zeros_like(num_s), where=num_s != 0)
    rp = np.divide(num_p, den_p, out=np.zeros_like(num_p), where=num_p != 0)
    return rs, rp


def coefficients(eta, theta):
    r"""Complex Fresnel reflection coefficients :math:`r_s, r_p` (Eqs. 45, 47, 52).

    Parameters
    ----------
    eta : array_like of complex
        Complex index ``n - 1j*kappa`` of the reflecting medium (incident medium vacuum).
    theta : array_like
        Angle of incidence [rad] in ``[0, pi/2]``.

    Returns
    -------
    rs, rp : ndarray of complex
        Field reflection coefficients, broadcast shape of ``eta`` and ``theta``.
        Sign convention of Eq. 45: ``rp = -rs`` at normal incidence.

    Notes
    -----
    Evaluated in the cancellation-free form given in the module docstring;
    ``|rs|, |rp| <= 1`` for every passive medium.
    """
    eta = as_index(eta)
    theta = as_angle(theta)
    eta, theta = broadcast(eta=eta, theta=theta)
    return _coefficients(eta, theta)


def transmission_coefficients(eta, theta):
    r"""Complex Fresnel transmission coefficients :math:`t_s, t_p` (Eq. 46).

    :math:`t_s = 2\cos\theta/(\cos\theta + u)`,
    :math:`t_p = 2\eta\cos\theta/(\eta^2\cos\theta + u)` with
    :math:`u = \eta\cos\theta_t`. They satisfy :math:`t_s = 1 + r_s` and
    :math:`\eta t_p = 1 + r_p` (continuity of the tangential fields, Eq. 44).

    Parameters
    ----------
    eta : array_like of complex
        Complex index.
    theta : array_like
        Angle of incidence [rad] in ``[0, pi/2]``.

    Returns
    -------
    ts, tp : ndarray of complex.
    """
    eta = as_index(eta)
    theta = as_angle(theta)
    eta, theta = broadcast(eta=eta, theta=theta)
    c = np.cos(theta)
    u = _refraction_term(eta, c * c)
    return 2 * c / (c + u), 2 * eta * c / (eta * eta * c + u)


def _reflectances(eta: np.ndarray, theta: np.ndarray):
    rs, rp = _coefficients(eta, theta)
    rs_r, rs_i, rp_r, rp_i = rs.real, rs.imag, rp.real, rp.imag
    # |r|^2 <= 1 holds exactly; clip only the last-bit rounding above 1.
    return (np.minimum(rs_r * rs_r + rs_i * rs_i, 1.0), np.minimum(rp_r * rp_r + rp_i * rp_i, 1.0))


def reflectances(eta, theta):
    r"""Fresnel reflectances :math:`R_s = |r_s|^2, R_p = |r_p|^2` (Eqs. 50, 53).

    Parameters
    ----------
    eta : array_like of complex
        Complex index ``n - 1j*kappa``.
    theta : array_like
        Angle of incidence [rad] in ``[0, pi/2]``.

    Returns
    -------
    Rs, Rp : ndarray of float in ``[0, 1]``, broadcast shape.
    """
    eta = as_index(eta)
    theta = as_angle(theta)
    eta, theta = broadcast(eta=eta, theta=theta)
    return _reflectances(eta, theta)


def transmittances(eta, theta):
    r"""Power transmittances :math:`T_s, T_p` into the medium, just below the interface.

    :math:`T_s = \mathrm{Re}(u)|t_s|^2/\cos\theta` and
    :math:`T_p = \mathrm{Re}(u\,\eta^*/\eta)|t_p|^2/\cos\theta`: the ratio of the
    normal Poynting flux just inside the medium to the incident one. Because the
    tangential fields are continuous, :math:`R + T = 1` for every passive medium
    (lossless or absorbing). At exactly grazing incidence ``T = 0``.

    Parameters
    ----------
    eta : array_like of complex
        Complex index.
    theta : array_like
        Angle of incidence [rad] in ``[0, pi/2]``.

    Returns
    -------
    Ts, Tp : ndarray of float in ``[0, 1]``.
    """
    eta = as_index(eta)
    theta = as_angle(theta)
    eta, theta = broadcast(eta=eta, theta=theta)
    c = np.cos(theta)
    u = _refraction_term(eta, c * c)
    ts = 2 / (c + u)  # t_s / cos(theta)
    tp = 2 * eta / (eta * eta * c + u)  # t_p / cos(theta)
    ts2 = ts.real**2 + ts.imag**2
    tp2 = tp.real**2 + tp.imag**2
    Ts = u.real * ts2 * c
    Tp = (u * np.conj(eta) / eta).real * tp2 * c
    return np.clip(Ts, 0.0, 1.0), np.clip(Tp, 0.0, 1.0)


def mueller_matrix(eta, theta) -> np.ndarray:
    r"""Mueller matrix of reflection from a smooth surface (Eq. 55).

    .. math::

       \mathbf{M} = \frac12\begin{bmatrix}
       R_s+R_p & R_s-R_p & 0 & 0\\ R_s-R_p & R_s+R_p & 0 & 0\\
       0 & 0 & 2\mathrm{Re}(r_s r_p^*) & 2\mathrm{Im}(r_s r_p^*)\\
       0 & 0 & -2\mathrm{Im}(r_s r_p^*) & 2\mathrm{Re}(r_s r_p^*)\end{bmatrix}

    in the (s, p) basis with :math:`S_1 = I_s - I_p`; it equals
    :func:`scatterlab.polarization.jones_to_mueller` of ``diag(rs, rp)``.

    Parameters
    ----------
    eta : array_like of complex
        Complex index.
    theta : array_like
        Angle of incidence [rad] in ``[0, pi/2]``.

    Returns
    -------
    M : ndarray, shape ``(..., 4, 4)``, dimensionless.
    """
    eta = as_index(eta)
    theta = as_angle(theta)
    eta, theta = broadcast(eta=eta, theta=theta)
    rs, rp = _coefficients(eta, theta)
    Rs, Rp = np.abs(rs) ** 2, np.abs(rp) ** 2
    x = rs * np.conj(rp)
    M = np.zeros(eta.shape + (4, 4))
    M[..., 0, 0] = M[..., 1, 1] = (Rs + Rp) / 2
    M[..., 0, 1] = M[..., 1, 0] = (Rs - Rp) / 2
    M[..., 2, 2] = M[..., 3, 3] = x.real
    M[..., 2, 3] = x.imag
    M[..., 3, 2] = -x.imag
    return M


def brewster_angle(n) -> np.ndarray:
    r"""Brewster angle :math:`\theta_B = \arctan n` of a lossless medium (Eq. 85).

    Parameters
    ----------
    n : array_like
        Real index ``n > 0``; a complex value must have zero imaginary part
        (use :func:`pseudo_brewster_angle` for absorbing media).

    Returns
    -------
    theta_B : ndarray [rad]; ``R_p(theta_B) = 0``.
    """
    arr = np.asarray(n)
    if np.iscomplexobj(arr):
        arr = as_index(arr, "n")
        if np.any(arr.imag != 0):
            raise ValueError(
                "n must be lossless (kappa = 0) for the Brewster angle; "
                "use pseudo_brewster_angle for absorbing media"
            )
        arr = arr.real
    n = as_positive(arr, "n")
    return np.arctan(n)


def pseudo_brewster_angle(eta, *, xtol: float = 1e-12) -> np.ndarray:
    r"""Pseudo-Brewster angle: the angle of incidence minimising :math:`R_p`.

    For a lossless medium it is :func:`brewster_angle` (returned exactly); for an
    absorbing one :math:`R_p` has a non-zero minimum there, found per element by
    bounded Brent minimisation (``scipy.optimize.minimize_scalar``) of
    :math:`|r_p|` on ``[0, pi/2]``, where it is unimodal for a passive medium.
    A smooth minimum locates the angle to about ``sqrt(machine epsilon)``:
    the accuracy is ~1e-8 rad.

    Parameters
    ----------
    eta : array_like of complex
        Complex index.
    xtol : float, optional
        Absolute tolerance requested from the minimiser [rad].

    Returns
    -------
    theta_pB : ndarray [rad], shape of ``eta``.
    """
    eta = as_index(eta)
    out = np.empty(eta.shape)
    for idx, e in np.ndenumerate(eta):
        if e.imag == 0:
            out[idx] = np.arctan(e.real)
            continue
        e_arr = np.asarray(e)

        def abs_rp(t, e_arr=e_arr):
            return float(np.abs(_coefficients(e_arr, np.asarray(t))[1]))

        res = optimize.minimize_scalar(abs_rp, bounds=(0.0, np.pi / 2), method="bounded",
                                       options={"xatol": xtol})
        out[idx] = res.x
    return out
