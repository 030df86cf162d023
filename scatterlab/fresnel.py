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

(multiply numerator and denominator by the conjugate-like factor); the factors after
:math:`(1-\eta^2)` are the reduced coefficients of :func:`reduced_coefficients`, the one kernel
every reflection formula of the package uses (the DOLP of :func:`smooth_dolp` is the ratio of
non-negative terms in :math:`u` they reduce to, Eq. 115). :math:`A, B` are computed without
cancellation from :math:`AB = n\kappa`, with :math:`D = n^2 - \kappa^2 - \sin^2\theta` formed in
whichever exact form is accurate (:math:`(n^2 - 1) - \kappa^2 + \cos^2\theta` near
:math:`\eta = 1`, the plain form for :math:`|\eta| \ll 1`).

Valid range. ``n >= 0`` (``n = 0`` with ``kappa > 0`` is a lossless plasma below its plasma
frequency: total reflection) and ``1e-50 <= |eta| <= 1e50``; outside it a :class:`ValueError`
names ``eta`` and the range (beyond it the powers up to :math:`|\eta|^4` in the formulas would
overflow or underflow). Inside it the results are finite, :math:`R_s, R_p \in [0, 1]`, and
tested against 50-digit references from :math:`|\eta| = 10^{-8}` to :math:`10^{6}`, and
against the limits (total reflection as :math:`\eta \to 0`, a perfect conductor as
:math:`|\eta| \to \infty`) at the ends; :math:`\theta` from 0 to exactly :math:`\pi/2`.

References
----------
Reference text (AFIT/DEE/ENG/10-12), Eqs. 28, 45-55, 85.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy import optimize

from scatterlab._checks import as_angle, as_finite, as_index, as_positive, broadcast
from scatterlab.polarization.mueller import mueller_from_jones_elements

__all__ = [
    "complex_index",
    "index_from_permittivity",
    "refraction_term",
    "ReducedFresnel",
    "reduced_coefficients",
    "smooth_dolp",
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


def _normal_term(eta: np.ndarray, cos2: np.ndarray, sin2: np.ndarray) -> np.ndarray:
    """``A - jB = sqrt(eta^2 - sin^2)``, ``A, B >= 0``, without cancellation (unchecked).

    ``D = Re(eta^2) - sin^2 = n^2 - kappa^2 - sin^2`` is formed in whichever of two exact forms has
    the smaller rounding error: ``(n - 1)(n + 1) - kappa^2 + cos^2`` when ``eta -> 1`` near grazing
    incidence (where ``n^2 - sin^2`` cancels), ``n^2 - kappa^2 - sin^2`` otherwise, in particular
    for ``|eta| << 1``, where ``(n^2 - 1) + cos^2`` cancels (issue 20: it gave R = 1.19 at
    ``eta = -2.2e-8j``). Then ``A, B`` follow from ``AB = n kappa`` (errata to Eq. 49).
    """
    n, kappa = eta.real, -eta.imag
    kk = kappa * kappa
    near_one = np.abs((n - 1) * (n + 1)) + cos2 < n * n + sin2
    d = np.where(near_one, (n - 1) * (n + 1) - kk + cos2, n * n - kk - sin2)
    nk = n * kappa
    w = np.hypot(d, 2 * nk)
    big = np.sqrt((w + np.abs(d)) / 2)
    small = np.divide(nk, big, out=np.zeros_like(big), where=big > 0)
    a = np.where(d >= 0, big, small)
    b = np.where(d >= 0, small, big)
    return a - 1j * b


def _index_and_angle(eta, theta):
    """Validated ``eta`` (passive, ``1e-50 <= |eta| <= 1e50``) and ``theta`` in [0, pi/2] [rad],
    broadcast to one shape."""
    return broadcast(eta=as_index(eta), theta=as_angle(theta))


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
    eta, theta = _index_and_angle(eta, theta)
    return _normal_term(eta, np.cos(theta) ** 2, np.sin(theta) ** 2)


class ReducedFresnel(NamedTuple):
    """Reduced Fresnel coefficients and their eta-derivatives, see :func:`reduced_coefficients`."""

    rs: np.ndarray
    rp: np.ndarray
    scale: np.ndarray
    drs: np.ndarray | None = None
    drp: np.ndarray | None = None


def reduced_coefficients(
    eta,
    cos_theta,
    sin2_theta=None,
    *,
    derivative: bool = False,
    normalize: bool = False,
    checked: bool = False,
) -> ReducedFresnel:
    r"""Reduced Fresnel coefficients :math:`r' = r/(1-\eta^2)`, the kernel of reflection formulas.

    .. math::

       r_s' = \frac{1}{(\cos\theta + u)^2},\qquad
       r_p' = -\frac{\eta^2\cos^2\theta - \sin^2\theta}{(\eta^2\cos\theta + u)^2},\qquad
       u = \sqrt{\eta^2 - \sin^2\theta},

    exact rewritings of Eq. 45 (module docstring) with :math:`r = (1-\eta^2)\,r'`. They are
    finite at :math:`\eta = 1` (except at exact grazing incidence), so ratios such as the DOLP are
    the continuous extension there, and holomorphic in :math:`\eta`, so
    :math:`\partial|r'|^2/\partial n = 2\,\mathrm{Re}(r'^* r'_\eta)` and
    :math:`\partial|r'|^2/\partial\kappa = 2\,\mathrm{Im}(r'^* r'_\eta)`.

    Parameters
    ----------
    eta : array_like of complex, or ``"pec"``
        Complex index ``n - 1j*kappa``; ``"pec"`` gives ``rs' = -1, rp' = 1, scale = 1``.
    cos_theta : array_like
        Cosine of the angle of incidence, in ``[0, 1]``.
    sin2_theta : array_like, optional
        :math:`\sin^2\theta`; pass it when known to full relative accuracy (small angles with
        ``|eta| << 1``). Default ``(1 - cos)(1 + cos)``.
    derivative : bool
        Also return :math:`dr_s'/d\eta` and :math:`dr_p'/d\eta` (kept finite at the branch point
        :math:`u = 0`, where :math:`du/d\eta = \eta/u` is evaluated at ``|u| = 1e-12 |eta|``).
    normalize : bool
        Where a denominator is below 1e-60 (``eta -> 1`` at grazing incidence, where the reduced
        factors grow like ``1/|1 - eta^2|`` and their squares overflow), divide ``rs, rp`` (and
        ``drs, drp``) by ``m = max(|rs|, |rp|)`` and multiply ``scale`` by ``m^2``: the same
        reflectances, every factor bounded. Elsewhere the values are not touched.
    checked : bool
        Skip validation (inputs already validated and broadcast).

    Returns
    -------
    ReducedFresnel
        ``(rs, rp, scale, drs, drp)`` of the broadcast shape; ``scale = |1 - eta^2|^2`` (times
        ``m^2`` when normalized) so that ``R_s = scale |rs|^2``; ``drs, drp`` are None unless
        ``derivative``.
    """
    c = np.asarray(cos_theta, float)
    if isinstance(eta, str):
        return _reduced_pec(eta, c, derivative)
    if not checked:
        eta, c = _check_index_and_cosine(eta, c)
        if sin2_theta is not None:
            sin2_theta = _check_sin2(sin2_theta, c)
    cos2 = c * c
    s2 = (1 - c) * (1 + c) if sin2_theta is None else np.asarray(sin2_theta, float)
    u = _normal_term(eta, cos2, s2)
    eta2 = eta * eta
    ds = c + u  # denominator root of r_s'
    dp = eta2 * c + u  # denominator root of r_p'
    num_p = eta2 * cos2 - s2
    with np.errstate(divide="ignore", invalid="ignore"):  # eta = 1 at exact grazing: no interface
        rs = 1.0 / (ds * ds)
        rp = -num_p / (dp * dp)
    f = (1 - eta) * (1 + eta)
    drs, drp = _reduced_derivatives(eta, c, s2, u, ds, dp) if derivative else (None, None)
    if normalize and _tiny(ds, dp):
        return _normalized(rs, rp, f, drs, drp)
    return ReducedFresnel(rs, rp, f.real**2 + f.imag**2, drs, drp)


def _reduced_pec(eta: str, c: np.ndarray, derivative: bool) -> ReducedFresnel:
    """The perfect conductor's ``rs' = -1, rp' = 1, scale = 1`` (``eta = "pec"``)."""
    if eta.lower() != "pec":
        raise ValueError(f"eta must be a complex index n - 1j*kappa or 'pec', got {eta!r}")
    one = np.ones_like(c)
    zero = np.zeros_like(c) + 0j if derivative else None
    return ReducedFresnel(-one + 0j, one + 0j, one, zero, zero)


def _check_index_and_cosine(eta, c):
    """Validated and broadcast ``eta`` and ``cos_theta`` in ``[0, 1]``."""
    eta = as_index(eta)
    c = as_finite(c, "cos_theta")
    if np.any((c < 0) | (c > 1)):
        raise ValueError("cos_theta must be in [0, 1]")
    return broadcast(eta=eta, cos_theta=c)


def _check_sin2(sin2_theta, c):
    """``sin2_theta`` validated: in ``[0, 1]`` and equal to ``1 - cos_theta^2`` up to rounding."""
    s2 = as_finite(sin2_theta, "sin2_theta")
    if np.any((s2 < 0) | (s2 > 1) | (np.abs(c * c + s2 - 1) > 1e-9)):
        raise ValueError("sin2_theta must be in [0, 1] and equal 1 - cos_theta**2 (to 1e-9)")
    return s2


def _normalized(rs, rp, f, drs, drp) -> ReducedFresnel:
    """Divide the reduced factors by ``m = max(|rs|, |rp|)`` and put ``m^2`` into the scale."""
    m = np.maximum(np.abs(rs), np.abs(rp))
    m = np.where(np.isfinite(m) & (m > 0), m, 1.0)  # eta = 1 at exact grazing: left as is
    with np.errstate(invalid="ignore"):
        rs, rp = rs / m, rp / m
        if drs is not None:
            drs, drp = drs / m, drp / m
    f = f * m
    return ReducedFresnel(rs, rp, f.real**2 + f.imag**2, drs, drp)


def _tiny(*denominators) -> bool:
    """True if a denominator is small enough for the squared reduced factors to overflow."""
    return any(np.any(np.abs(x.real) + np.abs(x.imag) < 1e-60) for x in denominators)


# |u| below this times |eta| is the branch point u = 0 (eta = sin(theta)), where du/deta = eta/u is
# infinite: it is evaluated at |u| = BRANCH_FLOOR |eta|, so |du/deta| <= 1 / BRANCH_FLOOR
BRANCH_FLOOR = 1e-12


def _du_deta(eta, u):
    """``du/d eta = eta/u`` (``u = sqrt(eta^2 - sin^2)``), capped at ``1/BRANCH_FLOOR`` in modulus.

    The floor is relative to ``|eta|``: at normal incidence ``u = eta`` and ``du/d eta = 1`` however
    small ``|eta|`` is (an absolute floor gave ``eta/1e-12`` there).
    """
    floor = BRANCH_FLOOR * np.abs(eta)
    return eta / np.where(np.abs(u) < floor, floor, u)


def _reduced_derivatives(eta, c, s2, u, ds, dp):
    """``d rs'/d eta``, ``d rp'/d eta`` (``du/d eta`` from :func:`_du_deta`).

    ``rp' = -N/dp^2`` with ``N = eta^2 c^2 - s^2``, ``dp = eta^2 c + u``: the numerator of
    ``d rp'/d eta = -(N' dp - 2 N dp')/dp^3`` is written with ``u^2 = eta^2 - s^2`` as
    ``-2 eta (eta^2 c^3 - 2 c s^2) + 2 s^4 eta/u``, without the cancellation of its ``eta^2``
    terms as ``eta -> 0`` near normal incidence (it gave ``-2e20`` instead of ``2`` at
    ``eta = 1e-20``).
    """
    du = _du_deta(eta, u)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        drs = -2.0 * du / (ds * ds * ds)
        drp = (2 * eta * c * (eta * eta * c * c - 2 * s2) - 2 * s2 * s2 * du) / (dp * dp * dp)
    return drs, drp


def smooth_dolp(eta, cos_theta, sin2_theta=None, *, gradient: bool = False, checked: bool = False):
    r"""DOLP of unpolarized light reflected by a smooth surface, :math:`(R_s - R_p)/(R_s + R_p)`.

    The facet DOLP of the pBRDF (Eq. 114 at the facet angle :math:`\beta`). It is evaluated as
    Thilak et al.'s Eq. 115, the same function written with :math:`u = A - jB`
    (:func:`refraction_term`),

    .. math::

       P = \frac{2A\sin^2\theta\cos\theta}{|u|^2\cos^2\theta + \sin^4\theta},

    a ratio of non-negative terms, so it keeps its relative accuracy over the whole valid range
    ``1e-50 <= |eta| <= 1e50`` (the difference :math:`R_s - R_p` cancels for :math:`|\eta| \to 0`
    and :math:`|\eta| \to \infty`, and the squares of the reduced coefficients underflow beyond
    :math:`|\eta| \approx 10^{40}`). It is the continuous extension at :math:`\eta = 1`
    (:math:`u = \cos\theta`; a formula of eta: :meth:`scatterlab.pbrdf.Model.dolp`, a measurement,
    is NaN where no light is reflected), 0 at normal and at grazing incidence and where the
    reflection is total (:math:`A = 0`).
    (:func:`scatterlab.inversion.thilak.thilak_dop` is the same function continued to any real
    ``(n, kappa)``.)

    Parameters
    ----------
    eta : array_like of complex, or ``"pec"``
        Complex index ``n - 1j*kappa`` [dimensionless], ``1e-50 <= |eta| <= 1e50``; ``"pec"`` (a
        perfect conductor) gives 0.
    cos_theta, sin2_theta : array_like
        As in :func:`reduced_coefficients` (angle of incidence on the reflecting surface).
    gradient : bool
        Also return the derivatives in ``(n, kappa)``, from :math:`du/d\eta = \eta/u`
        (``u`` holomorphic): :math:`\partial A/\partial n = \mathrm{Re}(du/d\eta)`,
        :math:`\partial A/\partial\kappa = \mathrm{Im}(du/d\eta)`. At the branch point
        :math:`u = 0` (``eta = sin(theta)``, real), where the derivative in ``n`` is infinite,
        :math:`du/d\eta` is evaluated at ``|u| = 1e-12 |eta|``, as in
        :func:`reduced_coefficients`.
    checked : bool
        Skip validation (inputs already validated; they broadcast).

    Returns
    -------
    dolp : ndarray in ``[0, 1]``, broadcast shape of the inputs.
    grad : ndarray ``(..., 2)`` or None
        ``d dolp/dn`` and ``d dolp/dkappa`` [dimensionless], finite; None unless ``gradient``.
    """
    c = np.asarray(cos_theta, float)
    if isinstance(eta, str):
        zero = _reduced_pec(eta, c, False).scale * 0.0
        return zero, (np.zeros(zero.shape + (2,)) if gradient else None)
    if not checked:
        eta, c = _check_index_and_cosine(eta, c)
        if sin2_theta is not None:
            sin2_theta = _check_sin2(sin2_theta, c)
    s2 = (1 - c) * (1 + c) if sin2_theta is None else np.asarray(sin2_theta, float)
    u = _normal_term(eta, c * c, s2)
    a = u.real
    # q > 0: c^2 |u|^2 >= c^2 |eta|^2 at normal incidence, s^4 > 0 elsewhere; <= 1e100 + 1
    q = c * c * (u.real**2 + u.imag**2) + s2 * s2
    f = 2 * s2 * c / q
    # P <= 1 exactly (2 A s^2 c <= A^2 c^2 + s^4): clip the last bit; + 0.0 turns the -0.0 of
    # kappa = -0.0 into 0
    P = np.minimum(f * a, 1.0) + 0.0
    if not gradient:
        return P, None
    du = _du_deta(eta, u)
    udu = np.conj(u) * du  # (d|u|^2/dn, d|u|^2/dkappa) = 2 (Re, Im) of conj(u) du/deta
    ac = 2 * a * c * c / q
    grad = np.stack([f * (du.real - ac * udu.real), f * (du.imag - ac * udu.imag)], -1)
    return P, grad


def _coefficients(eta: np.ndarray, theta: np.ndarray):
    """Unchecked rs, rp: ``(1 - eta^2)`` times the reduced coefficients."""
    red = reduced_coefficients(eta, np.cos(theta), np.sin(theta) ** 2, checked=True)
    f = (1 - eta) * (1 + eta)
    # eta == 1 exactly at grazing incidence is 0 * inf; there is no interface: r = 0.
    rs = np.where(f == 0, 0.0, f * np.where(f == 0, 0.0, red.rs))
    rp = np.where(f == 0, 0.0, f * np.where(f == 0, 0.0, red.rp))
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
    eta, theta = _index_and_angle(eta, theta)
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
    eta, theta = _index_and_angle(eta, theta)
    c = np.cos(theta)
    u = _normal_term(eta, c * c, np.sin(theta) ** 2)
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
    eta, theta = _index_and_angle(eta, theta)
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
    eta, theta = _index_and_angle(eta, theta)
    c = np.cos(theta)
    u = _normal_term(eta, c * c, np.sin(theta) ** 2)
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
    eta, theta = _index_and_angle(eta, theta)
    rs, rp = _coefficients(eta, theta)
    return mueller_from_jones_elements(rs, None, None, rp)


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
    xtol = float(as_positive(xtol, "xtol"))
    out = np.empty(eta.shape)
    for idx, e in np.ndenumerate(eta):
        if e.imag == 0:
            out[idx] = np.arctan(e.real)
            continue
        e_arr = np.asarray(e)

        def abs_rp(t, e_arr=e_arr):
            return float(np.abs(_coefficients(e_arr, np.asarray(t))[1]))

        res = optimize.minimize_scalar(
            abs_rp, bounds=(0.0, np.pi / 2), method="bounded", options={"xatol": xtol}
        )
        out[idx] = res.x
    return out
