r"""Single- and double-layer matrices of the 2-D Helmholtz operator for any (complex) wavenumber.

With time dependence exp(+j w t) and :math:`G(\mathbf r, \mathbf r') = -\frac j4 H_0^{(2)}(kR)`,
:math:`k = k_0\eta` (:math:`\eta = n - j\kappa`, so :math:`H^{(2)}` of a complex argument decays
into a lossy medium), pulse basis and point matching at the pulse centres give

.. math:: S_{mn} = \int_{C_n} G(\mathbf r_m, \mathbf r')\,ds', \qquad
          D_{mn} = \int_{C_n} \frac{\partial G(\mathbf r_m, \mathbf r')}{\partial n'}\,ds'
          = \int_{C_n}\frac{jk}{4}H_1^{(2)}(kR)\,\frac{\hat n'\cdot(\mathbf r' - \mathbf
          r_m)}{R}\,ds'

(:math:`D` is the principal value; the :math:`\pm\frac12` jump is added by the caller). Quadrature:

* each pulse is the parabola through its centre with the contour's tangent and curvature vector
  :math:`\boldsymbol\kappa = d^2\mathbf r/ds^2` (from the points), so the double layer sees the
  curvature;
* self terms: :math:`S_{nn}` by subtracting the logarithm, :math:`H_0^{(2)}(kr) + \frac{2j}{\pi}\ln
  r` being smooth (8-point Gauss-Legendre) and :math:`\int_0^h\ln r\,dr = h\ln h - h` exact;
  :math:`D_{nn}` from the parabola, :math:`\hat n\cdot(\mathbf r(s)-\mathbf r_n) = -\frac12(\hat
  n\cdot\boldsymbol\kappa)s^2`, whose static limit is :math:`(\hat n\cdot\boldsymbol\kappa)\Delta
  s/(4\pi)` (the kernel :math:`zH_1^{(2)}(kz)` is regular, 8-point Gauss-Legendre on the half
  pulse);
* near band (``band`` wavelengths of the medium either side, 3 to 30 pulses): Gauss-Legendre on the
  curved pulse, 8 points for the two nearest neighbours and 4 beyond, against the quadratic through
  the unknowns at the pulse and its two neighbours (product integration; constant at the ends of an
  open profile);
* the midpoint rule beyond, with the Euler-Maclaurin end correction :math:`-\frac{h^2}{24}f'(a)`
  where it meets the band (:math:`f'` from the first three far pulses), so the error is
  :math:`O(h^3)`;
* far: the midpoint rule with the pulse's phase factor
  :math:`\mathrm{sinc}(k\Delta s_n\cos\alpha_{mn}/2)` (the exact pulse integral of the outgoing
  phase).
"""

from __future__ import annotations

import os

import numpy as np
from scipy import special

from scatterlab.mom.hankel import hankel2_real

__all__ = ["arclength_contour", "curvature", "hankel2", "layer_matrices"]

_GL8 = np.polynomial.legendre.leggauss(8)
_GL4 = np.polynomial.legendre.leggauss(4)
_MAX_BAND = 30  # pulses
_TILE = 32768  # elements per row block of the far part
_DECAYED = (
    -40.0
)  # Im(kR) below this: |H^(2)| < e^-40 |H^(2)| at the source; set to 0 without evaluating


def hankel2(order: int, z):
    """H_order^(2)(z), order 0 or 1, for real or complex z (Im z <= 0); 0 where Im z < -40 (decayed
    by e^-40).

    Parameters
    ----------
    order : {0, 1}
        Order of the Hankel function.
    z : array_like
        Argument, real or complex with ``Im z <= 0``.

    Returns
    -------
    ndarray, shape of ``z``, complex
        H_order^(2)(z).
    """
    z = np.asarray(z)
    if not np.iscomplexobj(z):  # Hankel's expansion from z = 30, Cephes below (mom.hankel)
        return hankel2_real(order, z)
    live = z.imag >= _DECAYED
    out = np.zeros(z.shape, complex)
    zl = z[live]
    # scaled H^(2) (times exp(-jz)) stays finite; the factor exp(-jz) applied afterwards
    out[live] = special.hankel2e(order, zl) * np.exp(-1j * zl)
    return out


def arclength_contour(c):
    """A copy of the contour whose pulse lengths are arcs, not chords: the central-difference chord
    c2 = |r_(n+1) - r_(n-1)| spans an arc c2 (1 + kappa^2 c2^2 / 24) (exact to O(kappa^4 c2^4) on a
    circle).

    Parameters
    ----------
    c : Contour
        The discretised contour.

    Returns
    -------
    Contour
        Copy of ``c`` with arc pulse lengths ``ds`` [m].
    """
    import dataclasses

    kx, ky = curvature(c)
    return dataclasses.replace(c, ds=c.ds * (1 + (kx * kx + ky * ky) * (2 * c.ds) ** 2 / 24))


def curvature(c):
    """Curvature vector d^2 r / ds^2 (kx, ky) [1/m] at the points of a contour (periodic when
    closed).

    Parameters
    ----------
    c : Contour
        The discretised contour (N points).

    Returns
    -------
    kx, ky : ndarray, shape (N,)
        Components of the curvature vector [1/m].
    """
    if c.closed:

        def d(f):
            return (np.roll(f, -1) - np.roll(f, 1)) / 2

        def d2(f):
            return np.roll(f, -1) - 2 * f + np.roll(f, 1)
    else:

        def d(f):
            return np.gradient(f)

        def d2(f):
            return np.gradient(np.gradient(f))

    xp, yp, xpp, ypp = d(c.x), d(c.y), d2(c.x), d2(c.y)
    s2 = xp * xp + yp * yp
    # the component of r'' normal to the tangent, per unit arclength squared
    cross = (xp * ypp - yp * xpp) / s2**1.5  # signed curvature (left of the tangent positive)
    return -yp / np.sqrt(s2) * cross, xp / np.sqrt(s2) * cross


def _sinc(u):
    u = np.asarray(u)
    small = np.abs(u) < 1e-3
    with np.errstate(all="ignore"):
        out = np.sin(u) / np.where(small, 1.0, u)
    return np.where(small, 1 - u * u / 6, out)


def _normal(c, tx, ty):
    return (ty, -tx) if c.closed else (-ty, tx)


def _far_rows(S, D, c, k, rows):
    dx = c.x[None, :] - c.x[rows, None]  # r' - r_m
    dy = c.y[None, :] - c.y[rows, None]
    with np.errstate(all="ignore"):
        R = np.maximum(np.hypot(dx, dy), 1e-300)
        z = k * R
        phase = c.ds[None, :]
        if S is not None:
            S[rows] = -0.25j * hankel2(0, z) * phase
        if D is not None:
            D[rows] = (
                0.25j * k * hankel2(1, z) * (c.nx[None, :] * dx + c.ny[None, :] * dy) / R * phase
            )


def _offset_pairs(N, o, closed):
    """(m, n) with n = m +- o (mod N when closed; each pair once)."""
    i = np.arange(N)
    if closed:
        shifts = {o % N, (-o) % N} - {0}
        return (
            np.concatenate([i for _ in shifts]) if shifts else i[:0],
            np.concatenate([(i + sh) % N for sh in shifts]) if shifts else i[:0],
        )
    if o >= N:
        return i[:0], i[:0]
    return np.concatenate([i[: N - o], i[o:]]), np.concatenate([i[o:], i[: N - o]])


def _pairs(N, nb, closed):
    """(m, n, |offset|) of all pairs with 1 <= |m - n| <= nb (circular distance when closed)."""
    nb = min(nb, N // 2 if closed else N - 1)
    parts = [_offset_pairs(N, o, closed) for o in range(1, nb + 1)]
    if not parts:
        return np.zeros(0, int), np.zeros(0, int), np.zeros(0, int)
    offs = [np.full(p[0].size, o) for o, p in zip(range(1, nb + 1), parts)]
    return (
        np.concatenate([p[0] for p in parts]),
        np.concatenate([p[1] for p in parts]),
        np.concatenate(offs),
    )


def _lagrange(c, n, s):
    """Weights (3, P, Q) of psi_{n-1}, psi_n, psi_{n+1} in the quadratic through them, at arclengths
    s (P, Q) from the centre of pulse n; constant (pulse) interpolation at the ends of an open
    profile."""
    N = c.size
    lo, hi = (n - 1) % N, (n + 1) % N
    sm = -(0.5 * (c.ds[n] + c.ds[lo]))[:, None]
    sp = (0.5 * (c.ds[n] + c.ds[hi]))[:, None]
    w = np.stack(
        [
            s * (s - sp) / (sm * (sm - sp)),
            (s - sm) * (s - sp) / (sm * sp),
            s * (s - sm) / (sp * (sp - sm)),
        ]
    )
    if not c.closed:
        end = (n == 0) | (n == N - 1)
        w[:, end] = np.array([0.0, 1.0, 0.0])[:, None, None]
    return w, (lo, n, hi)


def _scatter(A, m, cols, w, values):
    """A[m, col_j] += sum_q w_j values (the product-integration weights of each neighbour)."""
    for wj, col in zip(w, cols):  # for one neighbour j the pairs (m, col) are distinct: += is safe
        A[m, col] += np.sum(wj * values, axis=1)


def _near(S, D, c, k, kx, ky, m, n, gl):
    """Gauss-Legendre over the curved source pulses n seen from the centres m, psi interpolated
    quadratically."""
    xg, wg = gl
    h = 0.5 * c.ds[n][:, None]
    s = h * xg[None, :]
    px = c.x[n][:, None] + c.tx[n][:, None] * s + 0.5 * kx[n][:, None] * s * s
    py = c.y[n][:, None] + c.ty[n][:, None] * s + 0.5 * ky[n][:, None] * s * s
    tx = c.tx[n][:, None] + kx[n][:, None] * s
    ty = c.ty[n][:, None] + ky[n][:, None] * s
    jac = np.hypot(tx, ty)
    nx, ny = _normal(c, tx / jac, ty / jac)
    dx, dy = px - c.x[m][:, None], py - c.y[m][:, None]
    R = np.hypot(dx, dy)
    w = h * wg[None, :]  # s is the arclength to O(kappa^2 s^2)
    lag, cols = _lagrange(c, n, s)
    if S is not None:
        _scatter(S, m, cols, lag, w * (-0.25j) * hankel2(0, k * R))
    if D is not None:
        _scatter(D, m, cols, lag, w * 0.25j * k * hankel2(1, k * R) * (nx * dx + ny * dy) / R)


def _self(S, D, c, k, kx, ky):
    """Self pulses: log singularity of S subtracted with exact moments, D's regular parabola
    kernel."""
    xg, wg = _GL8
    i = np.arange(c.size)
    h = 0.5 * c.ds[:, None]
    r = h * 0.5 * (xg[None, :] + 1)  # nodes on (0, h), mirrored to (-h, 0)
    w = h * 0.5 * wg[None, :]
    s = np.concatenate([-r, r], axis=1)
    ww = np.concatenate([w, w], axis=1)
    rr = np.concatenate([r, r], axis=1)
    lag, cols = _lagrange(c, i, s)
    if S is not None:
        smooth = -0.25j * (hankel2(0, k * rr) + 2j / np.pi * np.log(rr))
        _scatter(S, i, cols, lag, ww * smooth)
        # -(j/4)(-2j/pi) ln|s| = -(1/(2 pi)) ln|s| against the quadratic: moments of ln|s| on (-h,
        # h)
        hh = h[:, 0]
        mom0 = 2 * (hh * np.log(hh) - hh)
        mom2 = 2 * (hh**3 * np.log(hh) / 3 - hh**3 / 9)
        sm = -(0.5 * (c.ds + c.ds[cols[0]]))
        sp = 0.5 * (c.ds + c.ds[cols[2]])
        # quadratic weights: l(s) = a + b s + c s^2; the odd moment vanishes
        coef = [(0.0, 1 / (sm * (sm - sp))), (1.0, 1 / (sm * sp)), (0.0, 1 / (sp * (sp - sm)))]
        if not c.closed:
            end = (i == 0) | (i == c.size - 1)
        for j, (a0, c2) in enumerate(coef):
            a0 = np.full(c.size, a0) if j != 1 else sm * sp / (sm * sp)
            c2 = np.asarray(c2)
            val = -(1 / (2 * np.pi)) * (a0 * mom0 + c2 * mom2)
            if not c.closed:
                val = np.where(end, -(1 / (2 * np.pi)) * mom0 if j == 1 else 0.0, val)
            np.add.at(S, (i, cols[j]), val)
    if D is not None:
        nk = c.nx * kx + c.ny * ky
        # (jk/4) H1(k|s|) * (-(n.kappa) |s| / 2) on both halves of the pulse
        _scatter(D, i, cols, lag, ww * 0.25j * k * hankel2(1, k * rr) * rr * (-0.5 * nk[:, None]))


def layer_matrices(c, k, *, single: bool = True, double: bool = True, band: float = 2.0):
    """S and D (N x N complex; None where not asked) of the module docstring for wavenumber ``k``.

    Parameters
    ----------
    c : Contour
    k : float or complex [rad/m] -- wavenumber of the medium (Im k <= 0).
    single, double : which matrices to build.
    band : half-width of the Gauss-Legendre near band, in wavelengths 2 pi / |k| of the medium.

    Returns
    -------
    S, D : ndarrays (N, N) complex128 or None
    """
    from concurrent.futures import ThreadPoolExecutor

    N = c.size
    k = complex(k) if np.iscomplexobj(k) and np.imag(k) != 0 else float(np.real(k))
    S = np.empty((N, N), complex) if single else None
    D = np.empty((N, N), complex) if double else None
    # row blocks of about _TILE elements: the Hankel expansion's ~60 array operations run in cache
    block = max(4, min(N, _TILE // max(N, 1)))
    starts = list(range(0, N, block))
    workers = min(len(starts), os.cpu_count() or 1)
    jobs = [slice(s0, min(N, s0 + block)) for s0 in starts]
    if workers > 1:
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(lambda rows: _far_rows(S, D, c, k, rows), jobs))
    else:
        for rows in jobs:
            _far_rows(S, D, c, k, rows)
    kx, ky = curvature(c)
    # beyond ~30 pulses the midpoint rule with the end correction is accurate whatever the
    # wavelength
    nb = int(np.clip(np.ceil(band * 2 * np.pi / abs(k) / np.median(c.ds)), 3, _MAX_BAND))
    m, n, off = _pairs(N, nb, c.closed)
    i = np.arange(N)
    # Euler-Maclaurin end correction of the midpoint rule where the far part meets the band: the far
    # integral from the band edge a outwards misses -(h^2/24) f'(a) ~ (h/24) (f_1 - f_2) (first two
    # pulses) (f'(a) from the quadratic through the first three far pulses: (-2 f_1 + 3 f_2 - f_3) /
    # h)
    for o, factor in ((nb + 1, 1 + 2 / 24), (nb + 2, 1 - 3 / 24), (nb + 3, 1 + 1 / 24)):
        if (c.closed and 2 * (nb + 3) >= N) or o >= N:
            break
        mo, no = _offset_pairs(N, o, c.closed)
        for A in (S, D):
            if A is not None:
                A[mo, no] *= factor
    for A in (S, D):
        if A is not None:  # the band and the diagonal are rebuilt by product integration
            A[m, n] = 0.0
            A[i, i] = 0.0
    close = off <= 2
    for sel, gl in ((close, _GL8), (~close, _GL4)):
        idx = np.flatnonzero(sel)
        for a in range(0, idx.size, 200000):
            part = idx[a : a + 200000]
            _near(S, D, c, k, kx, ky, m[part], n[part], gl)
    _self(S, D, c, k, kx, ky)
    return S, D
