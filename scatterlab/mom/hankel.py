r"""Hankel functions :math:`H_0^{(2)}` and :math:`H_1^{(2)}` of a real argument for the MoM matrix fill.

For large :math:`x` Hankel's asymptotic expansion (Abramowitz & Stegun 9.2.5-9.2.10, DLMF 10.17.3-4)

.. math:: H_\nu^{(2)}(x) \sim \sqrt{\frac{2}{\pi x}}\,\big(P(\nu, x) - jQ(\nu, x)\big)\,
          e^{-j(x - \nu\pi/2 - \pi/4)},

.. math:: P(\nu, x) = \sum_{k\ge0} (-1)^k\frac{a_{2k}(\nu)}{x^{2k}}, \quad
          Q(\nu, x) = \sum_{k\ge0} (-1)^k\frac{a_{2k+1}(\nu)}{x^{2k+1}}, \quad
          a_k(\nu) = \frac{(4\nu^2 - 1^2)(4\nu^2 - 3^2)\cdots(4\nu^2 - (2k-1)^2)}{k!\,8^k},

is used from :data:`SWITCH` on, with :data:`TERMS` terms in all (``P`` and ``Q`` together). For
real :math:`\nu` and :math:`x > 0` the remainders of :math:`P` and :math:`Q` are bounded by their first
neglected terms (DLMF 10.17(iii)); at :math:`x = 30` the first neglected term,
:math:`a_{17}(\nu)/30^{17}`, is 3.9e-18 (order 0) and 4.1e-18 (order 1). The phase is reduced
without rounding x: :math:`x - \pi/4 = m\pi + 2u`, :math:`|u| \le \pi/4`, with :math:`\pi/8` split in
three parts (Cody-Waite), the products :math:`(4m + 1)\,C_{1,2}` being exact up to :data:`X_MAX`, so
u is accurate to about 1e-16 absolute whatever x; :math:`\cos 2u, \sin 2u` come from
:math:`t = \tan u` as :math:`(1 - t^2)/(1 + t^2)`, :math:`2t/(1 + t^2)` (numpy's float64 ``tan`` is
vectorised, ``cos`` and ``sin`` are scalar libm calls: 12 ms against 30 ms per 1.1e6 arguments).
Cephes' ``j0``/``y0`` (scipy) round :math:`x - \pi/4` before their phase and lose up to
:math:`x\,2^{-53}` relative to :math:`|H|` (5e-13 at x = 5000, 3e-11 at 1e6); this path stays
within 4.9e-16 of :math:`|H|` from x = 30 to 1e6 (against mpmath at 40 digits,
tests/mom/test_hankel.py) and is 3.5-4x faster. Below :data:`SWITCH`, above :data:`X_MAX` and for
non-finite or non-positive input the scipy expressions are used unchanged.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy import special

__all__ = ["SWITCH", "TERMS", "X_MAX", "asymptotic_coefficients", "hankel2_real"]

SWITCH = 30.0  # x from which the asymptotic expansion is used
TERMS = 17  # a_0 .. a_16 (P: 9 terms, Q: 8 terms); a_17(nu) / 30^17 < 5e-18 for nu = 0, 1
X_MAX = 2.0**22  # (4m + 1) < 2^23: the products with the 30-bit parts of pi/8 are exact
_CHUNK = 32768  # elements per pass: the ~60 array operations stay in cache (measured 3x faster
# than one pass over 1.1e6 elements; 2048-element chunks are slower from the per-call overhead)

# pi/8 = _C1 + _C2 + _C3 (30 + 30 significant bits, then the rest: |error| 1e-35)
_C1 = float.fromhex("0x1.921fb54000000p-2")
_C2 = float.fromhex("0x1.10b4611800000p-32")
_C3 = float.fromhex("0x1.313198a2e0370p-63")
_PI_4 = np.pi / 4
_INV_PI = 1 / np.pi
_TWO_OVER_PI = 2 / np.pi


def asymptotic_coefficients(order: int, terms: int = TERMS) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of P and Q as polynomials in :math:`1/x^2` (A&S 9.2.9-9.2.10, DLMF 10.17.3).

    Parameters
    ----------
    order : {0, 1}
        Order :math:`\\nu` of the Hankel function.
    terms : int
        Number of terms :math:`a_0 \\ldots a_{terms-1}` of the expansion, in P and Q together.

    Returns
    -------
    p, q : ndarray, shape ((terms + 1) // 2,) and (terms // 2,), float
        :math:`P = \\sum_i p_i x^{-2i}`, :math:`Q = x^{-1}\\sum_i q_i x^{-2i}`, with
        :math:`p_i = (-1)^i a_{2i}(\\nu)`, :math:`q_i = (-1)^i a_{2i+1}(\\nu)` (exact rationals rounded
        once).
    """
    mu = 4 * order * order
    a, ak = [], Fraction(1)
    for k in range(terms):
        a.append(ak)
        ak = ak * Fraction(mu - (2 * k + 1) ** 2, 8 * (k + 1))
    p = [float((-1) ** i * a[2 * i]) for i in range((terms + 1) // 2)]
    q = [float((-1) ** i * a[2 * i + 1]) for i in range(terms // 2)]
    return np.array(p), np.array(q)


_COEF = {nu: asymptotic_coefficients(nu) for nu in (0, 1)}


def _scipy(order, x):
    """The previous evaluation: Cephes j0/y0 (j1/y1) through scipy."""
    if order == 0:
        return special.j0(x) - 1j * special.y0(x)
    return special.j1(x) - 1j * special.y1(x)


def _horner(coef, y2, out):
    """sum_i coef[i] y2^i into ``out`` (in place, no temporaries)."""
    out[...] = coef[-1]
    for c in coef[-2::-1]:
        out *= y2
        out += c
    return out


def _asymptotic(order, x, out):
    """H_order^(2)(x) into the complex array ``out`` for SWITCH <= x <= X_MAX (x a flat float array)."""
    p, q = _COEF[order]
    y = 1 / x
    y2 = y * y
    P = _horner(p, y2, np.empty_like(x))
    Q = _horner(q, y2, np.empty_like(x))
    Q *= y
    # x - pi/4 = m pi + 2u: u = x/2 - (4m + 1) pi/8, Cody-Waite (x/2 and (4m + 1) C1, C2 exact)
    m = np.rint((x - _PI_4) * _INV_PI)
    j = 4 * m + 1
    u = 0.5 * x
    u -= j * _C1
    u -= j * _C2
    u -= j * _C3
    t = np.tan(u, out=u)
    t2 = t * t
    # amplitude sqrt(2 / (pi x)) (-1)^m / (1 + t^2): cos 2u = (1 - t^2) d, sin 2u = 2 t d
    d = np.sqrt(_TWO_OVER_PI * y)
    d *= 1 - 2 * (m - 2 * np.floor(0.5 * m))
    d /= 1 + t2
    c = np.subtract(1, t2, out=t2)  # (1 - t^2)
    t += t  # 2 t
    # (P - jQ)(c - j s) = (P c - Q s) - j (P s + Q c) [order 0]; times j [order 1]
    re = P * c
    re -= Q * t
    re *= d
    im = P * t
    im += Q * c
    im *= d
    if order == 0:
        out.real, out.imag = re, -im
    else:
        out.real, out.imag = im, re
    return out


def hankel2_real(order: int, x):
    """H_order^(2)(x) = J_order(x) - j Y_order(x) for real x, order 0 or 1.

    Hankel's asymptotic expansion (A&S 9.2.7-9.2.10, DLMF 10.17) with an exact Cody-Waite phase
    reduction for ``SWITCH <= x <= X_MAX``; scipy's Cephes ``j0``/``y0`` (``j1``/``y1``) elsewhere,
    including x <= 0, nan and inf, which therefore behave exactly as before.

    Parameters
    ----------
    order : {0, 1}
        Order of the Hankel function.
    x : array_like, float
        Argument (dimensionless, e.g. k R); any shape.

    Returns
    -------
    ndarray or complex, shape of ``x``, complex128
        H_order^(2)(x); a numpy complex scalar for a scalar ``x``.

    Raises
    ------
    ValueError
        ``order`` not 0 or 1, or ``x`` complex.
    """
    if order not in (0, 1):
        raise ValueError(f"order must be 0 or 1, got {order!r}")
    x = np.asarray(x)
    if np.iscomplexobj(x):
        raise ValueError("hankel2_real needs a real argument")
    x = x.astype(float, copy=False)
    if x.size == 0 or not np.fmax.reduce(x, axis=None) >= SWITCH:  # nothing to expand (nan ignored)
        return _scipy(order, x)
    flat = x.ravel()
    out = np.empty(flat.shape, complex)
    with np.errstate(all="ignore"):  # garbage outside [SWITCH, X_MAX], overwritten below
        for a in range(0, flat.size, _CHUNK):
            xc, oc = flat[a : a + _CHUNK], out[a : a + _CHUNK]
            _asymptotic(order, xc, oc)
            if not (xc.min() >= SWITCH and xc.max() <= X_MAX):  # also when xc holds a nan
                bad = np.flatnonzero(~((xc >= SWITCH) & (xc <= X_MAX)))
                oc[bad] = _scipy(order, xc[bad])
    out = out.reshape(x.shape)
    return out[()] if out.ndim == 0 else out
