r"""Electric-field integral equation for TM (E_z) scattering by a perfect conductor (Eqs. 178-181).

With time dependence exp(+j w t) and
:math:`G(\mathbf r, \mathbf r') = -\frac{j}{4}H_0^{(2)}(k|\mathbf r - \mathbf r'|)`,
the total field vanishes on the conductor and the unknown is :math:`U = \partial\psi/\partial n`
(n out of the conductor), proportional to the surface current :math:`J_z = U/(j\omega\mu_0)`:

.. math:: \psi_{inc}(\mathbf r) = \int_C G(\mathbf r, \mathbf r')\,U(\mathbf r')\,ds', \quad \mathbf r\in C
   \qquad\text{(Eq. 178, up to the constant } \pi Z_0/2\lambda\text{)}

Pulse basis and point matching (Eqs. 179-180): ``N`` pulses centred at the given points, of lengths
:math:`\Delta s_n`. Matrix elements :math:`A_{mn} = -\frac j4\int_{C_n}H_0^{(2)}(kR_m(s))ds`:

* diagonal: the exact integral over the straight pulse,
  :math:`-\frac j4\frac2k\left[\int_0^{k\Delta s_n/2}J_0 - j\int_0^{k\Delta s_n/2}Y_0\right]`
  (``scipy.special.itj0y0``);
  its small-argument expansion :math:`-\frac j4\Delta s_n[1 - \frac{2j}{\pi}\ln\frac{\gamma k\Delta s_n}{4e}]`
  (:func:`self_term_small_argument`) is off by O((k ds)^2) -- 0.9 % excess energy at 10 points per wavelength;
* neighbours (|m - n| = 1): 8-point Gauss-Legendre along the pulse's tangent;
* near band (2 <= |m - n| <= 3 wavelengths): the corrected midpoint rule :math:`\Delta s[f + \Delta s^2 f''/24]`
  with the exact second derivative of :math:`H_0^{(2)}(kR(s))` along the pulse;
* others: the corrected midpoint rule
  :math:`-\frac j4\Delta s_n H_0^{(2)}(kR_{mn})\,\frac{\sinh w}{w}
  \big(1 - \frac{jk\Delta s_n^2\sin^2\alpha_{mn}}{24R_{mn}}\big)`,
  :math:`w = -(jk + \frac1{2R_{mn}})\cos\alpha_{mn}\Delta s_n/2`, with
  :math:`\alpha_{mn}` the angle between the source pulse and :math:`\mathbf r_m - \mathbf r_n`: the
  pulse integral of the outgoing phase and of the :math:`R^{-1/2}` amplitude
  (:func:`_pulse_factor`). The plain midpoint rule is off by 1.7 % in every far element at 10 points
  per wavelength (measured against 16-point Gauss-Legendre), which shows up as 1.4 % excess energy;
  the phase factor alone (sinc) by :math:`k\Delta s^2/(24R)`, 7e-4 at 3.5 wavelengths.
  :math:`H_0^{(2)} = J_0 - jY_0` is evaluated on one triangle (R is symmetric), in tiles of 32768
  elements that stay in cache, by Hankel's asymptotic expansion with an exact phase reduction from
  kR = 30 (:mod:`scatterlab.mom.hankel`; Cephes below, whose rounding of kR - pi/4 costs up to
  kR 2^-53 of the phase).

Far field (Eq. 181): :math:`\psi_s \to \frac{j}{4}\sqrt{\frac{2}{\pi k\rho}}e^{-j(k\rho - \pi/4)}F(\theta_s)`,
:math:`F(\theta_s) = \sum_n U_n\Delta s_n e^{jk(x_n\sin\theta_s + y_n\cos\theta_s)}` for direction
:math:`(\sin\theta_s, \cos\theta_s)`; so :math:`2\pi\rho|\psi_s|^2 = |F|^2/(4k)` (the echo width of a unit
plane wave) and :math:`\rho|\psi_s|^2 = |F|^2/(8\pi k)` per unit scattering angle, which divided by the
incident power of a tapered wave is the scattering coefficient (integrates to 1 for a PEC).
Physical optics (Kirchhoff): :math:`U = 2\,\partial\psi_{inc}/\partial n` on the lit side.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from scipy import linalg, special

from scatterlab._checks import as_finite, as_positive, as_scalar
from scatterlab.mom.hankel import hankel2_real

__all__ = [
    "Contour",
    "contour",
    "impedance_diagonals",
    "impedance_matrix",
    "solve_tm",
    "Solution",
    "physical_optics_current",
]

EULER_GAMMA = np.exp(np.euler_gamma)
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_NEAR_OFFSETS = (1, -1)
_BAND_WAVELENGTHS = (
    3.0  # corrected-midpoint band half-width (energy error < 5e-4 at 10 points per wavelength)
)


@dataclass
class Contour:
    """Pulse centres (x, y) [m], lengths ds [m], unit tangents (tx, ty) and normals (nx, ny) out of the conductor."""

    x: np.ndarray
    y: np.ndarray
    ds: np.ndarray
    tx: np.ndarray
    ty: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    closed: bool

    @property
    def size(self) -> int:
        return self.x.size


def contour(x, y, closed: bool = False) -> Contour:
    """Pulses centred at the points: an open profile (x increasing, conductor below) or a closed body
    (counter-clockwise points). Lengths and tangents from central differences (periodic when
    closed).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Pulse centres [m], N >= 4 (x increasing for an open profile, counter-clockwise when closed).
    closed : bool
        Closed body instead of an open profile.

    Returns
    -------
    Contour
        Points, pulse lengths ``ds`` [m], unit tangents and normals, each of shape (N,).
    """
    x = as_finite(x, "x").astype(float).ravel()
    y = as_finite(y, "y").astype(float).ravel()
    if x.shape != y.shape or x.size < 4:
        raise ValueError("x and y must be 1-D arrays of equal length (at least 4 points)")
    if closed:
        dx = (np.roll(x, -1) - np.roll(x, 1)) / 2
        dy = (np.roll(y, -1) - np.roll(y, 1)) / 2
        area2 = np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
        if area2 <= 0:
            raise ValueError("closed contour points must run counter-clockwise")
    else:
        if np.any(np.diff(x) <= 0):
            raise ValueError("an open profile needs increasing x (a height function y(x))")
        dx = np.gradient(x)
        dy = np.gradient(y)
    ds = np.hypot(dx, dy)
    if closed:
        step = np.hypot(np.roll(x, -1) - x, np.roll(y, -1) - y)
        if np.any(step <= 1e-12 * np.max(step)) or np.any(ds <= 0):
            bad = int(np.argmin(step))
            raise ValueError(
                f"closed contour has coincident consecutive points (x, y) at index {bad}: "
                "points must be distinct (do not repeat the first point at the end)"
            )
    tx, ty = dx / ds, dy / ds
    # open profile: conductor below, normal up = (-ty, tx); closed ccw body: outward = (ty, -tx)
    nx, ny = (ty, -tx) if closed else (-ty, tx)
    return Contour(x, y, ds, tx, ty, nx, ny, closed)


def self_term_small_argument(k, ds):
    """The textbook diagonal element (small-argument expansion of H0^(2)); kept to test the exact
    one against.

    Parameters
    ----------
    k : float
        Wavenumber [rad/m].
    ds : array_like
        Pulse lengths [m].

    Returns
    -------
    ndarray, shape of ``ds``, complex
        Diagonal elements of the MoM matrix [m].
    """
    return -0.25j * ds * (1 - 2j / np.pi * np.log(EULER_GAMMA * k * ds / (4 * np.e)))


def _hankel2_0(z):
    """H0^(2)(z) = J0 - jY0 for real z: Hankel's asymptotic expansion from z = 30, scipy's Cephes
    j0/y0 below (:func:`scatterlab.mom.hankel.hankel2_real`; within 5e-16 of |H| where Cephes
    loses up to z 2^-53, and 3.5-4x faster in cache-sized chunks)."""
    return hankel2_real(0, z)


def _hankel2_0_scipy(z):
    """H0^(2)(z) = J0 - jY0 by Cephes alone: the previous fill's kernel, kept to measure against."""
    return special.j0(z) - 1j * special.y0(z)


def _hankel2_1_scipy(z):
    """H1^(2)(z) = J1 - jY1 by Cephes alone (see :func:`_hankel2_0_scipy`)."""
    return special.j1(z) - 1j * special.y1(z)


def _sinc(u):
    """sin(u)/u; a Taylor polynomial (error < 3e-9) for |u| <= 0.5, the usual 10 points per wavelength."""
    if np.max(np.abs(u), initial=0.0) <= 0.5:
        u2 = u * u
        return 1 - u2 / 6 * (1 - u2 / 20 * (1 - u2 / 42))
    return np.sinc(u / np.pi)


def _fill_far(A, c, k, block, kernels):
    """H0^(2)(kR) times the pulse's phase factor into A, one triangle of R per row block.

    Row blocks write disjoint parts of A (rows [s, e) x columns >= s and its transpose), so they run on
    threads: numpy's ufuncs release the GIL (measured 1.7x on 2 cores).
    """
    from concurrent.futures import ThreadPoolExecutor

    N = c.size
    starts = range(0, N, block)
    workers = min(len(starts), os.cpu_count() or 1)
    if workers > 1:
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(lambda s0: _fill_block(A, c, k, s0, min(N, s0 + block), kernels), starts))
    else:
        for s0 in starts:
            _fill_block(A, c, k, s0, min(N, s0 + block), kernels)


def _pulse_factor(k, h, cos_a, R):
    """Pulse integral of H0^(2)(k R(s)) over a straight pulse of length h, over h H0^(2)(k R).

    ln H0(kR(s)) is linear in s to O(1/(kR)^2), with slope a = -(jk + 1/(2R)) cos(a) (the phase and
    the 1/sqrt(R) amplitude), whose pulse average is sinh(a h / 2) / (a h / 2); the curvature of
    R(s), s^2 sin^2(a) / (2R), adds the factor 1 - jk h^2 sin^2(a) / (24 R). The sinc of the phase
    alone (the earlier rule) left a relative error k h^2 / (24 R): 7e-4 at 3.5 wavelengths at 10
    points per wavelength, against 1e-5 now (a 32-point Gauss-Legendre reference).
    """
    w = -(1j * k + 0.5 / R) * cos_a * (h / 2)
    w2 = w * w
    if np.max(np.abs(w2), initial=0.0) <= 0.36:
        shc = 1 + w2 / 6 * (1 + w2 / 20 * (1 + w2 / 42))  # error < 3e-9 for |w| <= 0.6
    else:
        shc = np.where(w2 == 0, 1.0, np.sinh(w) / np.where(w2 == 0, 1.0, w))
    return shc * (1 - 1j * k * h * h * (1 - cos_a * cos_a) / (24 * R))


def _fill_block(A, c, k, start, stop, kernels):
    """Rows [start, stop) x columns >= start of A and its transpose, in tiles of about ``tile``
    elements (``kernels[2]``; None: whole rows): the ~80 array operations per element then run
    in cache (measured 1.4x faster than whole row blocks at N = 1500 with the Hankel expansion)."""
    _, _, tile, fill_tile = kernels
    step = c.size if tile is None else max(16, tile // max(stop - start, 1))
    for c0 in range(start, c.size, step):
        fill_tile(A, c, k, start, stop, c0, min(c.size, c0 + step))


def _fill_tile_scipy(A, c, k, r0, r1, c0, c1):
    """The previous fill of one tile: Cephes H0^(2), :func:`_pulse_factor` in complex arithmetic."""
    with np.errstate(all="ignore"):  # the diagonal (R = 0) is garbage here and overwritten later
        rows, cols = slice(r0, r1), slice(c0, c1)
        DX = c.x[rows, None] - c.x[None, cols]
        DY = c.y[rows, None] - c.y[None, cols]
        R = np.maximum(np.hypot(DX, DY), 1e-300)
        H = _hankel2_0_scipy(k * R)
        # the integral of H0(kR) over the straight source pulse (observer m in the rows):
        # _pulse_factor with cos(a) between the source pulse and R
        A[rows, cols] = H * _pulse_factor(
            k, c.ds[None, cols], (c.tx[None, cols] * DX + c.ty[None, cols] * DY) / R, R
        )
        A[cols, rows] = (
            H
            * _pulse_factor(
                k, c.ds[rows, None], (c.tx[rows, None] * DX + c.ty[rows, None] * DY) / R, R
            )
        ).T


def _fill_tile(A, c, k, r0, r1, c0, c1):
    """A[rows, cols] and A[cols, rows] of one tile: H0^(2)(kR) (Hankel's expansion) times
    :func:`_pulse_factor` for either pulse as the source (:func:`_times_pulse_factor`)."""
    with np.errstate(all="ignore"):  # the diagonal (R = 0) is garbage here and overwritten later
        rows, cols = slice(r0, r1), slice(c0, c1)
        DX = c.x[rows, None] - c.x[None, cols]
        DY = c.y[rows, None] - c.y[None, cols]
        R = np.maximum(np.hypot(DX, DY), 1e-300)
        H = _hankel2_0(k * R)
        inv = np.divide(1.0, R, out=R)
        A[rows, cols] = _times_pulse_factor(
            H, k, c.ds[None, cols], c.tx[None, cols], c.ty[None, cols], DX, DY, inv
        )
        A[cols, rows] = _times_pulse_factor(
            H, k, c.ds[rows, None], c.tx[rows, None], c.ty[rows, None], DX, DY, inv
        ).T


def _times_pulse_factor(H, k, h, tx, ty, DX, DY, inv):
    """H times :func:`_pulse_factor` (the same expression, within 1e-15) with the source pulse's
    length ``h`` and tangent (tx, ty) and ``inv`` = 1/R: real arithmetic wherever possible and no
    complex abs (210 us against 550 us for ``H * _pulse_factor`` on a 32768-element tile).

    Parameters
    ----------
    H : ndarray, shape (P, Q), complex
        H0^(2)(kR) of the tile.
    k : float
        Wavenumber [rad/m].
    h, tx, ty : ndarray, broadcastable to (P, Q)
        Source pulse lengths [m] and unit tangents.
    DX, DY, inv : ndarray, shape (P, Q)
        Observer minus source (or its negative: the factor is even in cos(a)) [m], and 1/R [1/m].

    Returns
    -------
    ndarray, shape (P, Q), complex
        H times the pulse factor.
    """
    cos_a = tx * DX
    cos_a += ty * DY
    cos_a *= inv
    # w = -(jk + 1/(2R)) g, g = cos(a) h / 2: w^2 = (ag^2 - kg^2) + 2j ag kg with ag = g / (2R),
    # kg = k g (ag is 0, not nan, on the diagonal, where cos(a) = 0)
    g = cos_a * (h / 2)
    ag = g * inv
    ag *= 0.5
    kg = np.multiply(g, k, out=g)
    w2 = np.empty(H.shape, complex)
    w2.imag = ag * kg
    w2.imag *= 2
    ag *= ag
    kg *= kg
    w2.real = ag - kg
    if np.max(np.add(ag, kg, out=ag), initial=0.0) <= 0.36:  # |w|^2
        # 1 + w2/6 (1 + w2/20 (1 + w2/42)), error < 3e-9 for |w| <= 0.6
        shc = w2 * (1 / 5040)
        shc += 1 / 120
        shc *= w2
        shc += 1 / 6
        shc *= w2
        shc += 1
    else:
        w = -(1j * k + 0.5 * inv) * cos_a * (h / 2)
        shc = np.where(w2 == 0, 1.0, np.sinh(w) / np.where(w2 == 0, 1.0, w))
    shc *= H
    # times 1 - jk h^2 sin^2(a) / (24 R)
    f = np.empty(H.shape, complex)
    f.real = 1.0
    beta = np.multiply(cos_a, cos_a, out=kg)
    np.subtract(1.0, beta, out=beta)
    beta *= inv
    beta *= (-k / 24) * h * h
    f.imag = beta
    shc *= f
    return shc


# (H0, H1, elements per far-field tile, tile fill): the fill, and the previous one (Cephes,
# complex pulse factor, whole row blocks) kept to measure against
_KERNELS = {
    "expansion": (_hankel2_0, partial(hankel2_real, 1), 32768, _fill_tile),
    "scipy": (_hankel2_0_scipy, _hankel2_1_scipy, None, _fill_tile_scipy),
}


def impedance_matrix(c: Contour, k: float, *, min_points_per_wavelength: float = 5.0) -> np.ndarray:
    """The N x N MoM matrix A (module docstring), complex128.

    Parameters
    ----------
    c : Contour
        The discretised contour (N pulses).
    k : float
        Wavenumber [rad/m]: one finite number > 0 that samples the contour with at least
        ``min_points_per_wavelength`` pulses per wavelength ``2 pi / k`` (the check of
        :func:`solve_tm`, :func:`check_sampling`).
    min_points_per_wavelength : float
        Sampling below this (longest pulse) raises ValueError; a median pulse longer than 1/8 of
        the wavelength warns (default 5, as :func:`solve_tm`).

    Returns
    -------
    ndarray, shape (N, N), complex
        The matrix A.

    Raises
    ------
    ValueError
        ``k`` not one finite number > 0, or too large for the sampling of ``c``.

    Warns
    -----
    UserWarning
        Fewer than 8 points per wavelength (median pulse).
    """
    k = as_scalar(k, "k", 0.0, open_lo=True, unit=" [rad/m]")
    mppw = as_scalar(min_points_per_wavelength, "min_points_per_wavelength", 0.0, open_lo=True)
    check_sampling(c, 2 * np.pi / k, mppw, f"(k = {k:g} rad/m)")
    return _impedance_matrix(c, k)


def _impedance_matrix(c, k, kernel="expansion"):
    """:func:`impedance_matrix`; ``kernel="scipy"`` is the previous fill (Cephes j0/y0, j1/y1 for
    every pair, whole row blocks), kept to measure the fill against (studies/performance/perf_mom)."""
    k = float(as_positive(k, "k"))
    h0_, h1_, _, _ = kernels = _KERNELS[kernel]
    N = c.size
    A = np.empty((N, N), complex)
    # one triangle of kR (symmetric), in row blocks to bound the temporaries
    block = max(
        16, int(-(-N // (4 * (os.cpu_count() or 1)))) if N * N < 4e7 else max(1, int(1e6 // N))
    )
    _fill_far(A, c, k, block, kernels)
    A *= (-0.25j) * c.ds[None, :]
    i = np.arange(N)
    # self term: the exact integral over the straight pulse, 2/k [int_0^{k ds/2} J0 - j int_0^{k ds/2} Y0]
    ij, iy = special.itj0y0(k * c.ds / 2)
    A[i, i] = -0.25j * (2 / k) * (ij - 1j * iy)
    # near band 2 <= |m - n| <= 3 wavelengths: the corrected midpoint rule h [f + h^2/24 f''], f(s) = H0(k R(s)),
    # f'' = k^2 H0''(kR) R'^2 + k H0'(kR) R'' with H0' = -H1, H0'' = -H0 + H1/(kR), R' = cos(a), R'' = sin^2(a)/R
    # (the 1/sqrt(R) amplitude times the phase leaves an error ~ k h^2 / (12 R) that sinc alone misses)
    band = int(np.ceil(_BAND_WAVELENGTHS * 2 * np.pi / k / np.median(c.ds)))
    for off in range(2, min(band, N - 1) + 1):
        for sgn in (1, -1):
            m = i if c.closed else i[max(0, -sgn * off) : N - max(0, sgn * off)]
            n = (m + sgn * off) % N
            dx, dy = c.x[m] - c.x[n], c.y[m] - c.y[n]
            R = np.hypot(dx, dy)
            cos_a = -(c.tx[n] * dx + c.ty[n] * dy) / R  # dR/ds moving along the source pulse
            z = k * R
            h0 = h0_(z)
            h1 = h1_(z)
            f2 = k * k * (-h0 + h1 / z) * cos_a**2 + k * (-h1) * (1 - cos_a**2) / R
            A[m, n] = -0.25j * c.ds[n] * (h0 + c.ds[n] ** 2 / 24 * f2)
    # neighbours: Gauss-Legendre over the source pulse along its tangent
    for off in _NEAR_OFFSETS:
        m = i[max(0, -off) : N - max(0, off)] if not c.closed else i
        n = (m + off) % N
        s = 0.5 * c.ds[n][:, None] * _GL_X[None, :]
        px = c.x[n][:, None] + c.tx[n][:, None] * s
        py = c.y[n][:, None] + c.ty[n][:, None] * s
        R = np.hypot(c.x[m][:, None] - px, c.y[m][:, None] - py)
        A[m, n] = -0.25j * 0.5 * c.ds[n] * np.sum(_GL_W * h0_(k * R), axis=1)
    return A


def impedance_diagonals(c: Contour, k: float, nb: int) -> np.ndarray:
    """Diagonals -nb..nb of :func:`impedance_matrix` for an open profile, without the N x N matrix.

    The same quadrature rules per element (exact self term, Gauss-Legendre neighbours, corrected
    midpoint in the 3-wavelength band, phase-corrected midpoint beyond), evaluated pair by pair.

    Parameters
    ----------
    c : Contour -- an open profile (``c.closed`` False).
    k : float [rad/m] -- wavenumber.
    nb : int -- half band width in pulses (>= 1).

    Returns
    -------
    ndarray (2 nb + 1, N) complex -- row ``nb + o`` holds A[m, m + o] at column m (zero where
    m + o is off the profile).
    """
    if c.closed:
        raise ValueError("impedance_diagonals needs an open profile (closed=False)")
    N = c.size
    out = np.zeros((2 * nb + 1, N), complex)
    band = int(np.ceil(_BAND_WAVELENGTHS * 2 * np.pi / k / np.median(c.ds)))
    ij, iy = special.itj0y0(k * c.ds / 2)
    out[nb] = -0.25j * (2 / k) * (ij - 1j * iy)
    for o in range(-nb, nb + 1):
        if o == 0 or abs(o) >= N:
            continue
        m = np.arange(max(0, -o), N - max(0, o))
        n = m + o
        out[nb + o, m] = _pair_elements(c, k, m, n, abs(o), band)
    return out


def _pair_elements(c, k, m, n, off, band):
    """A[m, n] for pairs at index distance ``off`` >= 1 (the rules of :func:`impedance_matrix`)."""
    if off == 1:
        s = 0.5 * c.ds[n][:, None] * _GL_X[None, :]
        px = c.x[n][:, None] + c.tx[n][:, None] * s
        py = c.y[n][:, None] + c.ty[n][:, None] * s
        R = np.hypot(c.x[m][:, None] - px, c.y[m][:, None] - py)
        return -0.25j * 0.5 * c.ds[n] * np.sum(_GL_W * _hankel2_0(k * R), axis=1)
    dx, dy = c.x[m] - c.x[n], c.y[m] - c.y[n]
    R = np.hypot(dx, dy)
    h0 = _hankel2_0(k * R)
    if off <= band:
        cos_a = -(c.tx[n] * dx + c.ty[n] * dy) / R
        z = k * R
        h1 = hankel2_real(1, z)
        f2 = k * k * (-h0 + h1 / z) * cos_a**2 + k * (-h1) * (1 - cos_a**2) / R
        return -0.25j * c.ds[n] * (h0 + c.ds[n] ** 2 / 24 * f2)
    cos_a = (c.tx[n] * dx + c.ty[n] * dy) / R
    return -0.25j * c.ds[n] * h0 * _pulse_factor(k, c.ds[n], cos_a, R)


def physical_optics_current(c: Contour, incidence, k: float) -> np.ndarray:
    """Kirchhoff current U = 2 d(psi_inc)/dn (lit side; zero where the incident wave grazes away).

    Parameters
    ----------
    c : Contour
        The discretised contour (N pulses).
    incidence : incident wave
        Object with ``normal_derivative(x, y, nx, ny, k)`` (and optionally ``direction()``).
    k : float
        Wavenumber [rad/m].

    Returns
    -------
    ndarray, shape (N,), complex
        The current U at the pulse centres.
    """
    U = 2 * incidence.normal_derivative(c.x, c.y, c.nx, c.ny, k)
    if hasattr(incidence, "direction"):
        d = incidence.direction()
        U = np.where(d[0] * c.nx + d[1] * c.ny < 0, U, 0.0)
    return U


@dataclass
class Solution:
    """Surface unknowns for one or several incidences.

    Attributes
    ----------
    contour : Contour
    k : float [rad/m] -- wavenumber above the surface (outside the body).
    current : ndarray (N,) or (N, K) -- U = d psi / dn at the pulse centres (per incidence in columns), n out of
        the lower medium; psi = E_z (s-pol) or H_z (p-pol). Zero for the p-pol perfect conductor.
    incidences : list
    residual : ndarray (K,) -- relative residual of the solve.
    timings : dict -- seconds for "fill" and "solve".
    surface_field : ndarray like ``current`` or None -- psi on the surface (None: zero, the s-pol PEC).
    polarization : "s" or "p"
    eta : complex or None -- index of the lower medium (None: perfect conductor).
    method : "exact" (two-medium) or "impedance" (Leontovich) for penetrable surfaces.
    quadrature : "pulse" (staircase unknowns, Eq. 179: the far field integrates each pulse exactly) or
        "smooth" (point values of a smooth field: the midpoint rule, as in :mod:`scatterlab.mom.kernels`).
    info : dict -- solver details (the fast path: iterations, Taylor order, band in pulses).
    """

    contour: Contour
    k: float
    current: np.ndarray
    incidences: list
    residual: np.ndarray
    timings: dict = field(default_factory=dict)
    solver: str = "lu"
    surface_field: np.ndarray | None = None
    polarization: str = "s"
    eta: complex | None = None
    method: str = "exact"
    quadrature: str = "pulse"
    info: dict = field(default_factory=dict)

    def _radiated(self, k, sx, sy, U, psi):
        """sum_n [U_n - jk (n_n . r) psi_n] ds_n exp(jk r . r_n) sinc(...) for directions (sx, sy) (S, 1)."""
        c = self.contour
        step = max(1, int(4e6 // c.size))  # bound the (angles, N) temporaries of long profiles
        if sx.shape[0] > step:
            parts = [
                self._radiated(k, sx[a : a + step], sy[a : a + step], U, psi)
                for a in range(0, sx.shape[0], step)
            ]
            return np.concatenate(parts, axis=0)
        phase = np.exp(1j * k * (sx * c.x[None, :] + sy * c.y[None, :]))
        if self.quadrature == "pulse":
            # exact integral of the plane-wave factor over each straight pulse (Eq. 181's integral over C'_n)
            phase = phase * _sinc(k / 2 * (sx * c.tx[None, :] + sy * c.ty[None, :]) * c.ds[None, :])
        U2 = U if U.ndim == 2 else U[:, None]
        F = phase @ (U2 * c.ds[:, None])
        if psi is not None:
            P2 = psi if psi.ndim == 2 else psi[:, None]
            F = F - (1j * k * (sx * c.nx[None, :] + sy * c.ny[None, :]) * phase) @ (
                P2 * c.ds[:, None]
            )
        return F if U.ndim == 2 else F[:, 0]

    def far_field(self, theta_s) -> np.ndarray:
        """F(theta_s) (S,) or (S, K): sum_n [U_n - jk (n_n . r) psi_n] ds_n exp(jk(x_n sin + y_n cos));
        theta_s [rad] from the vertical (direction r = (sin, cos)); psi = 0 for the s-pol PEC (Eq. 181)."""
        th = _angles(theta_s, "theta_s")
        F = self._radiated(
            self.k, np.sin(th)[:, None], np.cos(th)[:, None], self.current, self.surface_field
        )
        return F if np.ndim(theta_s) else F[0]

    def echo_width(self, theta_s) -> np.ndarray:
        """2-D bistatic cross-section |F|^2 / (4k) [m] (closed bodies under a unit plane wave)."""
        return np.abs(self.far_field(theta_s)) ** 2 / (4 * self.k)

    def _powers(self):
        P = np.array([inc.incident_power(self.k) for inc in self.incidences])
        return P if self.current.ndim == 2 else P[0]

    def scattering_coefficient(self, theta_s) -> np.ndarray:
        """|F|^2 / (8 pi k P_inc) [1/rad]: integrates to 1 over theta_s in (-90, 90) deg for a lossless surface.

        Needs tapered incidences (they carry a finite power).
        """
        if not self.contour.closed:
            _angles(theta_s, "theta_s", np.pi / 2)
        return np.abs(self.far_field(theta_s)) ** 2 / (8 * np.pi * self.k * self._powers())

    def transmission_coefficient(self, theta_t) -> np.ndarray:
        r"""Power per radian transmitted into a lossless lower medium, over the incident power [1/rad].

        ``theta_t`` [rad] from the downward vertical, positive forward (direction (sin, -cos)). With
        :math:`F_2 = \sum_n[\rho U_n - jk_2(\hat n_n\cdot\hat r)\psi_n]\Delta s_n e^{jk_2\hat r\cdot\mathbf r_n}`
        (rho = 1 for s, eta^2 for p) the field below is
        :math:`-\frac j4\sqrt{2/(\pi k_2\rho)}e^{-j(k_2\rho-\pi/4)}F_2`, and the power per angle is
        :math:`|F_2|^2/(8\pi k_0)` (s) or :math:`|F_2|^2/(8\pi k_0 n^2)` (p, H_z carries Z_0/n) per unit
        :math:`|\psi_{inc}|^2` flux. Scattering plus transmission integrates to 1 for a lossless interface.
        Needs a penetrable open surface, a real index (no far field inside an absorber) and tapered incidences.
        """
        if self.eta is None or self.contour.closed or self.method != "exact":
            raise ValueError(
                "transmission_coefficient needs a penetrable open surface solved with "
                "method='exact' (eta given, closed=False)"
            )
        if np.imag(self.eta) != 0:
            raise ValueError(
                f"transmission_coefficient needs a lossless lower medium (kappa = 0), got eta = "
                f"{self.eta}: the field decays inside an absorber and has no far field"
            )
        th = _angles(theta_t, "theta_t", np.pi / 2)
        n2 = float(np.real(self.eta))
        k2 = self.k * n2
        rho = 1.0 if self.polarization == "s" else n2 * n2
        F2 = self._radiated(
            k2, np.sin(th)[:, None], -np.cos(th)[:, None], rho * self.current, self.surface_field
        )
        T = np.abs(F2) ** 2 / (8 * np.pi * self.k * (1.0 if self.polarization == "s" else n2 * n2))
        T = T / self._powers()
        return T if np.ndim(theta_t) else T[0]


def _angles(theta, name, limit=np.pi):
    """Angles [rad] as a 1-D array, finite and within [-limit, limit]."""
    th = np.atleast_1d(np.asarray(theta, float))
    if not np.all(np.isfinite(th)) or np.any(np.abs(th) > limit):
        raise ValueError(
            f"{name} must be finite angles in [-{limit:.4g}, {limit:.4g}] rad (angles are in "
            "radians)"
        )
    return th


def check_sampling(c: Contour, wavelength: float, min_ppw: float, where: str = "") -> None:
    """Raise ValueError below ``min_ppw`` points per ``wavelength`` (longest pulse); warn below 8 (median).
    ``where`` names the medium in the messages.

    Parameters
    ----------
    c : Contour
        The discretised contour.
    wavelength : float
        Wavelength in the medium [m].
    min_ppw : float
        Minimum number of points per wavelength.
    where : str
        Name of the medium, for the messages.

    Returns
    -------
    None
    """
    import warnings

    where = f" {where}" if where else ""
    ppw = wavelength / np.max(c.ds)
    if ppw < min_ppw:
        raise ValueError(
            f"sampling of {ppw:.2f} points per wavelength{where} (longest pulse) is below "
            f"{min_ppw:g}: use a finer dx (at least 10 per wavelength recommended)"
        )
    typical = wavelength / np.median(c.ds)
    if typical < 8:
        warnings.warn(
            f"only {typical:.1f} points per wavelength{where} (median pulse): expect errors of "
            "several percent",
            stacklevel=3,
        )


def check_incidence_list(incidence) -> list:
    """``incidence`` as a list: one incident wave, or a non-empty list or tuple of them.

    Parameters
    ----------
    incidence : PlaneWave, TaperedWave or a non-empty list or tuple of them
        The incidences of a solve.

    Returns
    -------
    list
        The incidences.
    """
    incs = list(incidence) if isinstance(incidence, (list, tuple)) else [incidence]
    if not incs:
        raise ValueError(
            "incidence must be a PlaneWave, a TaperedWave or a non-empty list of them, got an "
            "empty list"
        )
    return incs


def check_incidences(incs, c: Contour, k: float) -> None:
    """Validate each incidence against the contour (taper width and position, angle from above).

    Parameters
    ----------
    incs : sequence of incident waves
        The incidences; those with a ``check(k, length, extent)`` method are checked.
    c : Contour
        The discretised contour.
    k : float
        Wavenumber [rad/m].

    Returns
    -------
    None
    """
    length = (c.x[-1] - c.x[0]) * c.size / (c.size - 1) if not c.closed else None  # N pulses of dx
    extent = None if c.closed else (c.x[0], c.x[-1], c.size)
    for inc in incs:
        if hasattr(inc, "check"):
            inc.check(k, length, extent)


def solve_tm(
    x,
    y,
    wavelength,
    incidence,
    closed: bool = False,
    *,
    solver: str = "lu",
    tol: float = 1e-6,
    max_iter: int = 50,
    block: int = 256,
    min_points_per_wavelength: float = 5.0,
    fast=None,
) -> Solution:
    """Solve the TM EFIE on a PEC contour for one incidence or a list (one factorisation for all).

    Parameters
    ----------
    x, y : array (N,) [m] -- contour points (open profile with increasing x, or closed counter-clockwise).
    wavelength : float [m]
    incidence : PlaneWave, TaperedWave or a non-empty list of them (multiple right-hand sides).
    closed : bool
    solver : "lu" (LAPACK through scipy, factorised once), "fb" (block forward-backward, Holliday et al.,
        with fallback to LU when it diverges or stalls; see :func:`scatterlab.mom.solvers.forward_backward`)
        or "fast" (banded matrix + FFT far interactions, :mod:`scatterlab.mom.fast`: open profiles on a
        uniform x grid, O(N log N) per iteration, no N x N matrix; dense LU below
        ``fast.dense_below`` unknowns or when it does not converge on a size LU can take).
    tol, max_iter, block : forward-backward controls.
    fast : FastOptions, optional -- knobs of ``solver="fast"`` (band, Taylor order, GMRES tolerance).
    min_points_per_wavelength : sampling below this (longest pulse) raises ValueError; a median pulse longer
        than 1/8 wavelength warns.

    Returns
    -------
    Solution
    """
    import time
    import warnings

    from scatterlab.mom.solvers import forward_backward

    wavelength = float(as_positive(wavelength, "wavelength"))
    k = 2 * np.pi / wavelength
    c = contour(x, y, closed)
    check_sampling(c, wavelength, min_points_per_wavelength)
    incs = check_incidence_list(incidence)
    check_incidences(incs, c, k)
    V = np.stack([inc.field(c.x, c.y, k) for inc in incs], axis=1)
    single = not isinstance(incidence, (list, tuple))
    if solver == "fast":
        sol = _solve_fast(c, k, V, incs, fast)
        if sol is not None:
            if single:
                sol.current = sol.current[:, 0]
            return sol
        solver = "lu"
    t0 = time.perf_counter()
    A = _impedance_matrix(c, k)  # sampling checked above, with the caller's floor
    t_fill = time.perf_counter() - t0
    t0 = time.perf_counter()
    used = solver
    if solver == "lu":
        U = linalg.lu_solve(
            linalg.lu_factor(A, overwrite_a=False, check_finite=False), V, check_finite=False
        )
    elif solver == "fb":
        U, info = forward_backward(A, V, tol=tol, max_iter=max_iter, block=block)
        if not info["converged"]:
            warnings.warn(
                f"forward-backward did not converge ({info['reason']}); falling back to LU",
                stacklevel=2,
            )
            U = linalg.lu_solve(linalg.lu_factor(A, check_finite=False), V, check_finite=False)
            used = "lu (fallback)"
    else:
        raise ValueError(f"solver must be 'lu', 'fb' or 'fast', got {solver!r}")
    t_solve = time.perf_counter() - t0
    res = np.linalg.norm(A @ U - V, axis=0) / np.linalg.norm(V, axis=0)
    return Solution(
        contour=c,
        k=k,
        current=U[:, 0] if single else U,
        incidences=incs,
        residual=res,
        timings={"fill": t_fill, "solve": t_solve},
        solver=used,
    )


_DENSE_LIMIT = 12000  # unknowns: a dense complex matrix of 2.3 GB, the largest LU fallback


def _solve_fast(c, k, V, incs, options):
    """The fast path of :func:`solve_tm`; None when dense LU should run instead (small N, or no
    convergence at a size LU can take -- with a warning)."""
    import time
    import warnings

    from scatterlab.mom.fast import FastOptions, fast_solve

    options = FastOptions() if options is None else options
    if not isinstance(options, FastOptions):
        raise ValueError(f"fast must be a FastOptions, got {type(options).__name__}")
    if c.size < options.dense_below:
        return None
    t0 = time.perf_counter()
    U, info = fast_solve(c, k, V, options)
    t_total = time.perf_counter() - t0
    if not info["converged"]:
        msg = (
            f"fast path did not converge (residual {np.max(info['residual']):.3g} after "
            f"{info['iterations']} iterations)"
        )
        if c.size <= _DENSE_LIMIT:
            warnings.warn(msg + "; falling back to LU", stacklevel=3)
            return None
        warnings.warn(msg + f"; N = {c.size} is too large for dense LU", stacklevel=3)
    return Solution(
        contour=c,
        k=k,
        current=U,
        incidences=incs,
        residual=info["residual"],
        timings={"fill": info["seconds_setup"], "solve": t_total - info["seconds_setup"]},
        solver="fast" if info["converged"] else "fast (not converged)",
        info=info,
    )
