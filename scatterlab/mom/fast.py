r"""Fast path for long PEC profiles (s-pol EFIE): banded matrix, canonical grid, FFT far interactions.

The banded-matrix iterative approach with the canonical grid (BMIA/CAG: Tsang, Chan and Pak 1993;
Tsang, Kong, Ding and Ao, *Scattering of Electromagnetic Waves: Numerical Simulations*, 2001,
Ch. 4) splits the EFIE matrix of :func:`scatterlab.mom.efie.impedance_matrix` at a horizontal
distance :math:`r_d` (``band`` wavelengths):

* strong interactions, :math:`|x_m - x_n| \le r_d`: the exact elements
  (:func:`~scatterlab.mom.efie.impedance_diagonals`), a banded matrix B of half width
  :math:`n_b = r_d/\Delta x` pulses, factorised once by banded LU (LAPACK ``zgbtrf``,
  :math:`O(N n_b^2)`);
* weak interactions, beyond :math:`r_d`: with :math:`z = f(x_m) - f(x_n)` small against
  :math:`|x| = |x_m - x_n|`, the Taylor series in :math:`t = z^2/x^2` of
  :math:`H_0^{(2)}(k|x|\sqrt{1 + t})` is, from :math:`(z^{-1}d/dz)^l H_0(z) = (-1)^l z^{-l} H_l(z)`,

  .. math:: H_0^{(2)}(k\sqrt{x^2 + z^2}) = \sum_{l\ge0}\frac{(-1)^l}{l!}
            \Big(\frac{kz^2}{2|x|}\Big)^l H_l^{(2)}(k|x|),

  and :math:`z^{2l} = \sum_p\binom{2l}{p} f_m^p(-f_n)^{2l-p}`: every term is a Toeplitz
  (flat-surface, canonical-grid) convolution, done by FFT. The source pulse is integrated by
  4-point Gauss-Legendre along its tangent (node g at :math:`x_n + \xi_g\Delta x/2`, height
  :math:`f_n + f'_n\xi_g\Delta x/2`, times :math:`\Delta s_n`), so a kernel and a set of
  height powers per node. Cost per product :math:`O(M^2 N\log N)` for
  ``order`` M (about 10 M FFTs), memory :math:`O(N n_b)`; no N x N matrix is built.

The system :math:`(B + W)U = V` is solved by GMRES (restarted) with B as the preconditioner
(B alone is the plain BMIA iteration, :math:`U \leftarrow B^{-1}(V - WU)`; GMRES makes it robust
where that stalls). Convergence: the relative residual of the fast operator below ``tol``; the
caller (:func:`scatterlab.mom.solve_tm`, ``solver="fast"``) falls back to dense LU below
``dense_below`` unknowns and when the iteration fails on a size LU can still take.

Validity: an open profile sampled on a uniform grid in x (as :func:`rough_surface` gives);
the series converges fast when :math:`k z_{max}^2/(2 r_d)` is of order 1 or less (heights of a
few wavelengths need a wider band). The order is chosen so that the first omitted term at the
band edge for the largest height difference is below ``far_tol`` of the leading one.

:func:`scattered_power` integrates the scattering coefficient over all angles without an angle
loop: the far field on a uniform grid of :math:`u = \sin\theta_s` by FFT (heights by a Taylor
series of :math:`e^{jkvy}`, pulses by 4-point Gauss-Legendre), then each sample of :math:`|F(u)|^2`
times the exact integral of :math:`d\theta = du/\sqrt{1-u^2}` over its cell of u.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb, factorial

import numpy as np
from scipy import fft as sfft
from scipy import special
from scipy.linalg.lapack import zgbtrf, zgbtrs
from scipy.sparse.linalg import LinearOperator, gmres

from scatterlab.mom.efie import Contour, impedance_diagonals

__all__ = ["FastOptions", "FastOperator", "fast_solve", "scattered_power"]

_GL4 = np.polynomial.legendre.leggauss(4)


@dataclass(frozen=True)
class FastOptions:
    """Accuracy and iteration knobs of the fast path.

    Attributes
    ----------
    band : float -- strong-interaction half width r_d [wavelengths] (exact elements inside).
    order : int or None -- Taylor order M of the weak kernel in z^2; None chooses it from ``far_tol``.
    far_tol : float -- target relative size of the first omitted Taylor term (automatic order).
    tol : float -- GMRES relative residual.
    max_iter : int -- maximum GMRES iterations (inner steps in total).
    restart : int -- GMRES restart length.
    dense_below : int -- below this many unknowns ``solver="fast"`` uses dense LU.
    """

    band: float = 5.0
    order: int | None = None
    far_tol: float = 1e-5
    tol: float = 1e-6
    max_iter: int = 300
    restart: int = 40
    dense_below: int = 2000

    def __post_init__(self):
        if not (np.isfinite(self.band) and self.band > 0):
            raise ValueError(f"band must be > 0 wavelengths, got {self.band!r}")
        if self.order is not None and not 0 <= int(self.order) <= 40:
            raise ValueError(f"order must be None or an integer in [0, 40], got {self.order!r}")
        for name in ("far_tol", "tol"):
            v = getattr(self, name)
            if not (np.isfinite(v) and 0 < v < 1):
                raise ValueError(f"{name} must be in (0, 1), got {v!r}")
        if int(self.max_iter) < 1 or int(self.restart) < 1:
            raise ValueError("max_iter and restart must be >= 1")


def uniform_step(c: Contour) -> float:
    """The grid step dx [m] of an open profile on a uniform x grid; ValueError otherwise.

    Parameters
    ----------
    c : Contour
        An open profile.

    Returns
    -------
    float
        Grid step dx [m].
    """
    if c.closed:
        raise ValueError("the fast path needs an open profile (closed=False)")
    d = np.diff(c.x)
    dx = float(np.mean(d))
    if np.max(np.abs(d - dx)) > 1e-6 * dx:
        raise ValueError(
            "the fast path needs x on a uniform grid (max deviation of diff(x) "
            f"{np.max(np.abs(d - dx)):.3g} m from dx = {dx:.6g} m); use solver='lu'"
        )
    return dx


def _auto_order(k, zmax, rd, far_tol):
    """Smallest M whose first omitted term (k z^2/(2 r_d))^(M+1)/(M+1)! |H_(M+1)|/|H_0| < far_tol."""
    q = k * zmax * zmax / (2 * rd)
    h0 = abs(special.hankel2(0, k * rd))
    for m in range(0, 41):
        term = q ** (m + 1) / factorial(m + 1) * abs(special.hankel2(m + 1, k * rd)) / h0
        if term < far_tol:
            return m
    return 40


class FastOperator:
    """The EFIE operator B + W of the module docstring for one profile (products and B^-1).

    Parameters
    ----------
    c : Contour -- open profile on a uniform x grid.
    k : float [rad/m]
    options : FastOptions
    """

    def __init__(self, c: Contour, k: float, options: FastOptions):
        self.c, self.k, self.options = c, k, options
        N = c.size
        self.dx = uniform_step(c)
        self.nb = nb = int(min(N - 1, max(1, np.ceil(options.band * 2 * np.pi / k / self.dx))))
        self.diags = impedance_diagonals(c, k, nb)  # (2 nb + 1, N): A[m, m + o] in row nb + o
        ab = np.zeros((3 * nb + 1, N), complex)
        for o in range(-nb, nb + 1):  # LAPACK band storage ab[kl + ku + i - j, j] = A[i, j]
            m = np.arange(max(0, -o), N - max(0, o))
            ab[2 * nb - o, m + o] = self.diags[nb + o, m]
        self.lu, self.piv, info = zgbtrf(ab, nb, nb)
        if info != 0:
            raise np.linalg.LinAlgError(f"banded LU failed (info {info})")
        self.f = c.y - np.mean(c.y)
        # the source pulse's heights at its Gauss-Legendre nodes, along its tangent
        slope = c.ds * c.ty / self.dx
        self.fg = [self.f + slope * xi * self.dx / 2 for xi in _GL4[0]]
        zmax = float(max(np.max(fg) for fg in self.fg) - min(np.min(fg) for fg in self.fg))
        self.scale = max(float(max(np.max(np.abs(fg)) for fg in self.fg)), 1e-300)
        rd = (nb + 1) * self.dx
        self.order = (
            int(options.order)
            if options.order is not None
            else _auto_order(k, zmax, rd, options.far_tol)
        )
        self._kernels(N)

    def _kernels(self, N):
        """FFTs of the Toeplitz kernels K_l(x) (zero inside the band) at each Gauss-Legendre node
        of the source pulse, circulant length L: kern_hat (4, M + 1, L)."""
        k, nb, M = self.k, self.nb, self.order
        self.L = L = sfft.next_fast_len(2 * N - 1)
        j = np.arange(L)
        off = np.where(j < N, j, j - L).astype(float)  # signed offsets m - n
        far = (np.abs(off) > nb) & (np.abs(off) <= N - 1)
        xg, wg = _GL4
        kern = np.zeros((xg.size, M + 1, L), complex)
        for g, (xi, w) in enumerate(zip(xg, wg)):
            ax = np.abs(off[far] * self.dx - xi * self.dx / 2)  # x_m - (x_n + xi dx / 2)
            z = k * ax
            h_prev, h = special.hankel2(0, z), special.hankel2(1, z)
            for lo in range(M + 1):
                if lo >= 1:  # upward recurrence H_(l+1) = (2l/z) H_l - H_(l-1), stable for H^(2)
                    h_prev, h = h, 2 * lo / z * h - h_prev
                hl = h_prev  # H_lo
                kern[g, lo, far] = (
                    w / 2 * (-1) ** lo / factorial(lo) * (k * self.scale**2 / (2 * ax)) ** lo * hl
                )
        self.kern_hat = sfft.fft(kern, axis=2)
        self.weight = -0.25j * self.c.ds  # times the pulse-averaged kernel: int_pulse G ds
        self.phi = self.f / self.scale
        self.phig = [fg / self.scale for fg in self.fg]

    def far(self, U: np.ndarray) -> np.ndarray:
        """W U (N,) complex: the weak interactions by FFT."""
        N, L, M = self.c.size, self.L, self.order
        g = self.weight * U
        acc = np.zeros((2 * M + 1, L), complex)
        for gi, phig in enumerate(self.phig):
            G = [sfft.fft((-phig) ** q * g, L) for q in range(2 * M + 1)]
            for p in range(2 * M + 1):
                for lo in range((p + 1) // 2, M + 1):
                    acc[p] += comb(2 * lo, p) * self.kern_hat[gi, lo] * G[2 * lo - p]
        out = np.zeros(N, complex)
        for p in range(2 * M + 1):
            out += self.phi**p * sfft.ifft(acc[p])[:N]
        return out

    def band(self, U: np.ndarray) -> np.ndarray:
        """B U (N,) complex: the strong interactions."""
        N, nb = self.c.size, self.nb
        out = self.diags[nb] * U
        for o in range(1, nb + 1):
            out[: N - o] += self.diags[nb + o, : N - o] * U[o:]
            out[o:] += self.diags[nb - o, o:] * U[: N - o]
        return out

    def matvec(self, U: np.ndarray) -> np.ndarray:
        """(B + W) U."""
        U = np.asarray(U, complex).ravel()
        return self.band(U) + self.far(U)

    def precondition(self, V: np.ndarray) -> np.ndarray:
        """B^-1 V by the banded LU."""
        x, info = zgbtrs(self.lu, self.nb, self.nb, np.asarray(V, complex).ravel(), self.piv)
        return x


def fast_solve(c: Contour, k: float, V: np.ndarray, options: FastOptions | None = None):
    """Solve the s-pol PEC EFIE (B + W) U = V by preconditioned GMRES, one column of V at a time.

    Parameters
    ----------
    c : Contour -- open profile on a uniform x grid.
    k : float [rad/m]
    V : ndarray (N,) or (N, K) complex -- incident field at the pulse centres.
    options : FastOptions, optional

    Returns
    -------
    U : ndarray like V -- surface unknowns d psi / dn.
    info : dict -- converged (bool), iterations (per column), residual (per column, of the fast
        operator), order, band_pulses, seconds_setup.
    """
    import time

    options = options or FastOptions()
    t0 = time.perf_counter()
    op = FastOperator(c, k, options)
    t_setup = time.perf_counter() - t0
    N = c.size
    A = LinearOperator((N, N), matvec=op.matvec, dtype=complex)
    P = LinearOperator((N, N), matvec=op.precondition, dtype=complex)
    V2 = V if V.ndim == 2 else V[:, None]
    U = np.empty(V2.shape, complex)
    iters, res = [], []
    for j in range(V2.shape[1]):
        count = [0]

        def cb(_r, count=count):
            count[0] += 1

        x0 = op.precondition(V2[:, j])  # the first BMIA step
        u, _ = gmres(
            A,
            V2[:, j],
            x0=x0,
            M=P,
            rtol=options.tol,
            atol=0.0,
            restart=options.restart,
            maxiter=max(1, options.max_iter // options.restart + 1),
            callback=cb,
            callback_type="pr_norm",
        )
        U[:, j] = u
        iters.append(count[0])
        res.append(float(np.linalg.norm(op.matvec(u) - V2[:, j]) / np.linalg.norm(V2[:, j])))
    info = {
        "converged": bool(max(res) < 10 * options.tol),
        "iterations": iters,
        "residual": np.array(res),
        "order": op.order,
        "band_pulses": op.nb,
        "seconds_setup": t_setup,
    }
    return (U if V.ndim == 2 else U[:, 0]), info


def _uniform_far_field(c: Contour, k: float, g: np.ndarray, n_fft: int):
    """F(u) = sum_n g_n (1/ds_n) int_pulse exp(jk(u x + v y)) ds on the FFT grid of u, |u| < 1.

    ``g`` (N,) is U_n ds_n. Returns (u (M,), F (M,)).
    """
    dx = uniform_step(c)
    xg, wg = np.polynomial.legendre.leggauss(4)
    dy = c.ds * c.ty  # the pulse's rise (tx ds = dx on a uniform grid)
    j = np.fft.fftfreq(n_fft, 1.0 / n_fft)
    u = j * 2 * np.pi / (k * dx * n_fft)
    keep = np.abs(u) <= 1
    u = u[keep]
    v = np.sqrt(np.maximum(1 - u * u, 0.0))
    ybar = float(np.mean(c.y))
    F = np.zeros(u.size, complex)
    for xi, w in zip(xg, wg):
        eta = c.y + xi * dy / 2 - ybar
        Y = max(float(np.max(np.abs(eta))), 1e-300)
        Q = int(np.e * k * Y + 12)
        part = np.zeros(u.size, complex)
        term = np.ones(u.size, complex)
        for q in range(Q + 1):
            if q:
                term = term * (1j * k * v * Y) / q
            s = sfft.ifft((eta / Y) ** q * g, n_fft)[keep] * n_fft
            part += term * s
        # x_n = x_0 + n dx + xi dx / 2
        F += w / 2 * np.exp(1j * k * u * (c.x[0] + xi * dx / 2)) * part
    return u, F


def scattered_power(sol, oversample: float = 3.0) -> np.ndarray:
    """Scattering coefficient of an s-pol PEC open profile integrated over theta_s in (-90, 90) deg.

    Parameters
    ----------
    sol : Solution -- s-pol PEC (``surface_field`` None), open profile on a uniform x grid,
        tapered incidences.
    oversample : float -- FFT length over N (>= 2.5: |F|^2 is sampled above its Nyquist rate).

    Returns
    -------
    ndarray (K,) or float -- reflected power over incident power (1 for a PEC up to the error).
    """
    if sol.surface_field is not None:
        raise ValueError("scattered_power handles the s-pol PEC (no surface field) only")
    c, k = sol.contour, sol.k
    n_fft = sfft.next_fast_len(int(np.ceil(oversample * c.size)))
    U = sol.current if sol.current.ndim == 2 else sol.current[:, None]
    P = np.array([inc.incident_power(k) for inc in sol.incidences])
    out = []
    for j in range(U.shape[1]):
        u, F = _uniform_far_field(c, k, U[:, j] * c.ds, n_fft)
        du = 2 * np.pi / (k * uniform_step(c) * n_fft)
        # each sample stands for its cell of u, weighted by the exact integral of d(theta) =
        # du / sqrt(1 - u^2) over the cell (the weight is singular at grazing, |u| = 1)
        lo, hi = np.maximum(u - du / 2, -1.0), np.minimum(u + du / 2, 1.0)
        w = np.arcsin(hi) - np.arcsin(lo)
        out.append(np.sum(np.abs(F) ** 2 * w) / (8 * np.pi * k * P[j]))
    out = np.array(out)
    return out if sol.current.ndim == 2 else float(out[0])
