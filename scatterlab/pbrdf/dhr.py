r"""Directional-hemispherical reflectance of the specular term of a PEC surface (Eq. 174).

.. math::

   \rho^{s,\mathrm{PEC}}(\theta_i;\sigma)
   = \int_{2\pi} F^{s,\mathrm{PEC}}_{00}\cos\theta_r\,d\omega_r .

Quadrature. Reflection maps the facet normal :math:`\hat h` to the outgoing
direction with :math:`d\omega_r = 4\cos\beta\,d\omega_h`, and
:math:`P(\alpha)\,d\omega_h = p(\mathbf s)\,d^2 s` in facet slopes, so

.. math::

   \rho = \int G(\mathbf s)\,\frac{\cos\theta_i - s_x\sin\theta_i}{\cos\theta_i}\,
          p(\mathbf s)\; \mathbb 1[\theta_r(\mathbf s) < \pi/2]\; d^2 s ,

a Gaussian-weighted integral over the slope plane (facet normal
:math:`\propto(-s_x, -s_y, 1)`). For each :math:`s_y` the visible region is an
interval in :math:`s_x` between the roots of
:math:`\cos\theta_i(s_x^2+s_y^2) + 2 s_x\sin\theta_i - \cos\theta_i = 0` (the
horizon), and the Torrance-Sparrow :math:`G` is smooth except where
:math:`G_c = 1` (:math:`s_x = -\cot\theta_i`), :math:`G_b = 1` (a cubic in
:math:`s_x`) and :math:`G_b = G_c` (a quadratic). The integral is split at all of
them and each piece integrated by Gauss-Legendre; the outer :math:`s_y` integral
uses :math:`s_y = \sin t/\cos\theta_i`, which removes the square-root endpoint of
the visible region. Both are truncated at ``window`` standard deviations. The
accuracy knobs are the node counts (studies/performance/perf_dhr_quadrature.py);
the defaults give about 1e-12.

:func:`dhr_sphere_unshadowed` is the closed form of the unshadowed (Priest-Germer)
model integrated over the whole sphere, as the reference's Fig. 27 does:
:math:`\Phi(\cot\theta_i/\sigma) + \sigma\tan\theta_i\,\varphi(\cot\theta_i/\sigma)`.

:class:`DHRTable` tabulates :math:`\rho` over :math:`(z, \ln\sigma)` with
:math:`z = (2/\pi)\arctan(\cot\theta_i/\sigma)`, the variable in which the
grazing boundary layer of smooth surfaces is resolved uniformly, and interpolates
it with a bicubic spline. Its maximum error is stated in
:attr:`DHRTable.max_error` and tested; tables are built once per process and
cached on disk (``$SCATTERLAB_CACHE`` or ``~/.cache/scatterlab``).
"""

from __future__ import annotations

import functools
import hashlib
import io
import os
from pathlib import Path

import numpy as np
from scipy import interpolate, special

from scatterlab._checks import as_angle, as_count, as_positive
from scatterlab.pbrdf.shadowing import SHADOWING, shadowing_strategy

__all__ = [
    "dhr_beckmann",
    "dhr_sphere_unshadowed",
    "dhr_slope_quadrature",
    "DHRTable",
    "dhr_table",
    "SpecularDHR",
]

_GL_CACHE: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _gauss_legendre(n: int):
    if n not in _GL_CACHE:
        _GL_CACHE[n] = np.polynomial.legendre.leggauss(n)
    return _GL_CACHE[n]


def _real_roots_in(coeffs_monic: np.ndarray) -> np.ndarray:
    """Real roots of monic cubics ``x^3 + a2 x^2 + a1 x + a0`` (coeffs ``(..., 3)`` = a2, a1, a0).

    NaN for complex roots.
    """
    shape = coeffs_monic.shape[:-1]
    C = np.zeros(shape + (3, 3))
    C[..., 0, :] = -coeffs_monic
    C[..., 1, 0] = 1.0
    C[..., 2, 1] = 1.0
    r = np.linalg.eigvals(C)
    real = np.abs(r.imag) <= 1e-9 * (1 + np.abs(r.real))
    return np.where(real, r.real, np.nan)


def _outer_split_points(c: np.ndarray, s: np.ndarray) -> list[np.ndarray]:
    """s_y >= 0 where the Torrance-Sparrow kink curves fold or meet the horizon (NaN where absent).

    * folds of G_b = 1: zeros of the discriminant of the cubic
      ``s x^3 - 3c x^2 + s(q - 4) x + c(4 - 3q)`` (q = 1 + s_y^2), a cubic in q;
    * fold of G_b = G_c: ``s_y = tan(theta_i)/2``;
    * G_c = 1 (``s_x = -cot``) meets the horizon: ``s_y^2 = 3 - cot^2``;
    * the triple point G_b = G_c = 1: ``s_y^2 = 1 - cot^2``.
    """
    pts = []
    # discriminant 18abcd - 4b^3 d + b^2 c^2 - 4 a c^3 - 27 a^2 d^2 with c_ = s(q-4), d = c(4-3q)
    a, b = s, -3 * c
    q = np.polynomial.Polynomial([0.0, 1.0])
    roots_q = []
    for ci, si, ai, bi in zip(c, s, a, b):
        C = si * (q - 4)
        D = ci * (4 - 3 * q)
        disc = (
            18 * ai * bi * C * D - 4 * bi**3 * D + bi**2 * C**2 - 4 * ai * C**3 - 27 * ai**2 * D**2
        )
        r = disc.roots()
        r = r[(np.abs(r.imag) < 1e-9) & (r.real >= 1)].real
        roots_q.append(np.pad(np.sort(r), (0, 3 - r.size), constant_values=np.nan))
    roots_q = np.array(roots_q)
    for k in range(3):
        pts.append(np.sqrt(roots_q[:, k] - 1))
    pts.append(s / (2 * c))
    cot2 = (c / s) ** 2
    with np.errstate(invalid="ignore"):
        pts.append(np.where(3 - cot2 > 0, np.sqrt(np.abs(3 - cot2)), np.nan))
        pts.append(np.where(1 - cot2 > 0, np.sqrt(np.abs(1 - cot2)), np.nan))
    return pts


def dhr_beckmann(
    theta_i,
    sigma: float,
    shadowing="torrance-sparrow",
    *,
    n_outer: int | None = None,
    n_inner: int | None = None,
    window: float = 9.0,
) -> np.ndarray:
    """Specular DHR of a PEC Beckmann surface over the upper hemisphere (Eq. 174), by quadrature.

    Parameters
    ----------
    theta_i : array_like
        Incidence angles [rad] in ``[0, pi/2]`` (1-D or scalar).
    sigma : float
        Per-axis rms facet slope.
    shadowing : {"torrance-sparrow", "none", "smith"} or Shadowing
    n_outer, n_inner : int
        Gauss-Legendre nodes of each outer (s_y) piece and of each inner (s_x) piece.
        Defaults (measured to give <= 1e-9 absolute, see the performance study):
        16 for "torrance-sparrow", 24 for "none", 32 for "smith".
    window : float
        Truncation of the slope plane in standard deviations.

    Returns
    -------
    rho : ndarray, shape of ``theta_i``. ``<= 1`` for the shadowed models (clipped at
        rounding); may exceed 1 for ``"none"`` (the Priest-Germer model does not
        conserve energy, Figs. 27-28).
    """
    from scatterlab.pbrdf.distributions import Beckmann

    strategy = shadowing_strategy(shadowing)
    n_outer = _nodes(n_outer or strategy.quadrature_nodes, "n_outer")
    n_inner = _nodes(n_inner or strategy.quadrature_nodes, "n_inner")
    window = float(as_positive(window, "window"))
    sigma = float(Beckmann(float(as_positive(sigma, "sigma"))).sigma)  # [1e-4, 5]
    theta = np.atleast_1d(as_angle(theta_i, "theta_i"))
    c = np.cos(theta)[:, None]
    s = np.maximum(np.sin(theta), 1e-9)[:, None]
    K = window * sigma
    sy, wy, cos_t = _outer_nodes(c, s, sigma, K, strategy, n_outer)
    sx, wx = _inner_nodes(c, s, sy, cos_t, sigma, K, strategy, n_inner)
    syb, cb, sb = sy[..., None, None], c[..., None, None], s[..., None, None]
    n2 = 1 + sx * sx + syb * syb
    m = cb - sx * sb  # N cos(beta) > 0 inside
    rz = np.maximum(2 * m / n2 - cb, 0.0)  # cos(theta_r)
    dist = Beckmann(sigma)
    f = strategy.slope_integrand(m, rz, cb, sb, dist) * dist.slope_pdf(sx * sx + syb * syb)
    inner = np.sum(f * wx, axis=(-1, -2))  # (T, No)
    rho = np.sum(inner * wy, axis=-1)
    if strategy.conserves_energy:
        rho = np.minimum(rho, 1.0)
    return rho.reshape(np.shape(theta_i))


def _nodes(n, name: str, lo: int = 1) -> int:
    """A quadrature order or grid size: an integer >= ``lo``."""
    return as_count(n, name, lo)


def _outer_nodes(c, s, sigma, K, strategy, n_outer):
    """Outer nodes ``s_y >= 0``, weights (T, No) (the factor 2 for ``s_y < 0`` included), ``cos t``.

    The integrand is even in s_y. The outer range is split where the kink curves of G fold or meet
    the horizon, so every piece is smooth up to square-root endpoints, which the map
    ``s_y = sin(t)/cos(theta_i)`` and the cosine clustering below remove.
    """
    t0 = np.arcsin(np.minimum(1.0, K * c))  # (T, 1): |s_y| <= K
    splits = [np.zeros_like(t0), t0]
    for m in (3.0, 6.0):  # sub-split the Gaussian window every 3 sigma
        splits.append(np.minimum(np.arcsin(np.minimum(1.0, m * sigma * c)), t0))
    if strategy.kinks:
        for sy_k in _outer_split_points(c[:, 0], s[:, 0]):
            tk = np.arcsin(np.clip(c[:, 0] * sy_k, 0.0, 1.0))[:, None]
            splits.append(np.where(np.isfinite(tk), np.minimum(tk, t0), 0.0))
    edges = np.sort(np.concatenate(splits, axis=1), axis=1)  # (T, P+1)
    ta, tb = edges[:, :-1], edges[:, 1:]
    xo, wo = _gauss_legendre(n_outer)
    u = (xo + 1) / 2
    wu = wo / 2
    # t = ta + (tb - ta)(1 - cos(pi u))/2 clusters nodes at both ends of each piece
    t = ta[..., None] + (tb - ta)[..., None] * (1 - np.cos(np.pi * u)) / 2
    dt = (tb - ta)[..., None] * (np.pi / 2) * np.sin(np.pi * u) * wu
    t = t.reshape(t.shape[0], -1)
    dt = dt.reshape(dt.shape[0], -1)
    cos_t = np.cos(t)
    return np.sin(t) / c, 2 * dt * cos_t / c, cos_t


def _inner_nodes(c, s, sy, cos_t, sigma, K, strategy, n_inner):
    """Inner nodes ``s_x`` and weights (T, No, P, Ni) on the visible interval, split at kinks."""
    # visible interval of s_x (horizon roots, stable forms)
    r1 = -(s + cos_t) / c
    r2 = c * (1 - sy * sy) / (s + cos_t)
    lo = np.maximum(r1, -K)
    hi = np.minimum(np.minimum(r2, K), c / s)
    hi = np.maximum(hi, lo)
    bps = _inner_kinks(c, s, sy) if strategy.kinks else [np.full_like(sy, np.nan)]
    bps += [np.full_like(sy, m * sigma) for m in (-6.0, -3.0, 0.0, 3.0, 6.0)]
    pts = np.stack([lo, hi] + [np.where(np.isfinite(b), np.clip(b, lo, hi), lo) for b in bps], -1)
    pts.sort(axis=-1)
    a, b = pts[..., :-1], pts[..., 1:]  # (T, No, P)
    xi, wi = _gauss_legendre(n_inner)
    half = (b - a) / 2
    return (a + b)[..., None] / 2 + half[..., None] * xi, half[..., None] * wi


def _inner_kinks(c, s, sy):
    """s_x where the Torrance-Sparrow G has kinks.

    G_c = 1, G_b = 1 (a cubic), G_b = G_c (a quadratic).
    """
    q = 1 + sy * sy
    a2 = -3 * c / s + 0 * sy
    a1 = q - 4
    a0 = c * (4 - 3 * q) / s
    cub = _real_roots_in(np.stack(np.broadcast_arrays(a2, a1, a0), -1))
    disc = s * s - 4 * c * c * sy * sy
    sq = np.sqrt(np.maximum(disc, 0))
    quad1 = np.where(disc >= 0, (-s - sq) / (2 * c), np.nan)
    quad2 = np.where(disc >= 0, -2 * c * sy * sy / (s + sq), np.nan)
    return [np.broadcast_to(-c / s, sy.shape), cub[..., 0], cub[..., 1], cub[..., 2], quad1, quad2]


def dhr_sphere_unshadowed(theta_i, sigma) -> np.ndarray:
    """Closed form of the unshadowed (Priest-Germer) DHR integrated over the whole sphere (Fig. 27).

    ``Phi(a) + sigma tan(theta_i) phi(a)``, ``a = cot(theta_i)/sigma``, with ``Phi, phi``
    the standard normal CDF and density: every facet facing the source reflects,
    including into the lower hemisphere.

    Parameters
    ----------
    theta_i : array_like
        Incidence angles [rad] in ``[0, pi/2]``.
    sigma : array_like
        Per-axis rms facet slope (dimensionless, > 0); broadcasts with ``theta_i``.

    Returns
    -------
    ndarray
        The DHR (dimensionless, >= 0), broadcast shape. It exceeds 1 where facets reflect into the
        lower hemisphere (the unshadowed model does not conserve energy, Figs. 27-28) and grows like
        ``sigma tan(theta_i) / sqrt(2 pi)`` towards grazing incidence: ``inf`` at exactly 90 deg.
    """
    theta = as_angle(theta_i, "theta_i")
    sigma = as_positive(sigma, "sigma")
    grazing = theta == np.pi / 2
    t = np.where(grazing, 0.0, theta)
    with np.errstate(divide="ignore", over="ignore"):  # a^2 = inf near normal incidence: exp -> 0
        a = np.cos(t) / (np.sin(t) * sigma)
        term = np.where(
            np.isfinite(a), np.tan(t) * sigma * np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi), 0.0
        )
    return np.where(grazing, np.inf, special.ndtr(a) + term)


class DHRTable:
    """Bicubic-spline table of the specular PEC DHR of Beckmann surfaces over (theta_i, sigma).

    The DHR of the Torrance-Sparrow model has a kink in a higher derivative at
    ``theta_i = 45 deg`` (where the triple point G_b = G_c = 1 enters the visible
    region), so the table has two smooth pieces:

    * ``theta_i <= 45 deg``: grid in ``x = theta_i / (pi/4)`` and ``ln sigma``;
    * ``theta_i >= 45 deg``: grid in ``v = arctan(x/3) / arctan(x_45/3)`` and ``ln sigma``
      with ``x = cot(theta_i)/sigma`` (``x_45 = 1/sigma``): shadowing of a smooth
      surface sets in at ``x`` of a few, so ``x`` is the variable in which the grazing
      boundary layer has the same shape for every sigma.

    For the unshadowed model, whose DHR grows like ``1 + sigma tan(theta_i) g(x)``, the table holds
    ``rho / (1 + sigma tan(theta_i))``, which is smooth in ``v``. (Tabulating ``rho cos(theta_i)``,
    as version 4 did, is not: at small sigma ``v`` squeezes 45-87 deg into its last percent, where
    ``cos(theta_i)`` varies, and the table was off by 4e-3.)

    Parameters
    ----------
    shadowing : {"torrance-sparrow", "none", "smith"} or Shadowing
    n_theta, n_sigma : int
        Grid sizes per piece in the angle variable and in ``ln(sigma)``, each >= 4 (the bicubic
        spline's minimum).
    sigma_range : (float, float)
        Tabulated roughness range; outside it :meth:`__call__` falls back to quadrature.

    Attributes
    ----------
    max_error : float
        Maximum interpolation error measured against the quadrature at the cell
        centres of every fourth row when the table was built -- absolute, and
        relative where rho > 1 (unshadowed model near grazing); the tests re-check
        it at random points.
    """

    _X0 = 3.0

    def __init__(
        self,
        shadowing="torrance-sparrow",
        *,
        n_theta: int = 65,
        n_sigma: int = 121,
        sigma_range=(1e-3, 2.5),
        cache: bool = True,
    ):
        self.strategy = shadowing_strategy(shadowing)
        self.shadowing = self.strategy.name
        self.sigma_range = (float(sigma_range[0]), float(sigma_range[1]))
        self.n_theta = _nodes(n_theta, "n_theta", 4)  # a cubic spline needs 4 nodes per axis
        self.n_sigma = _nodes(n_sigma, "n_sigma", 4)
        n_theta, n_sigma = self.n_theta, self.n_sigma
        version = 4 if self.strategy.conserves_energy else 5  # 5: the weight 1 + sigma tan
        key = f"{version}-{self.shadowing}-{n_theta}-{n_sigma}-{self.sigma_range}"
        name = f"dhr-{hashlib.sha1(key.encode()).hexdigest()[:12]}.npz"
        shipped = Path(__file__).parent / "data" / name
        path = shipped if shipped.exists() else _cache_dir() / name
        self.path = path
        data = None
        if cache and path.exists():
            try:
                data = dict(np.load(path))
            except Exception:  # a corrupt cache is rebuilt
                data = None
        if data is None:
            data = self._build()
            if cache:
                _save_npz(_cache_dir() / name, data)
        self.u = data["u"]
        self.log_sigma = data["log_sigma"]
        self.max_error = float(data["max_error"])
        self._values = (data["low"], data["high"])
        self._splines = [
            interpolate.RectBivariateSpline(self.u, self.log_sigma, data[k], kx=3, ky=3)
            for k in ("low", "high")
        ]

    # piece 0: u = theta/(pi/4); piece 1: u = arctan(x/x0)/arctan(x45/x0), x = cot(theta)/sigma
    @classmethod
    def _theta(cls, piece: int, u, sigma):
        if piece == 0:
            return u * np.pi / 4
        a45 = np.arctan(1 / (sigma * cls._X0))
        x = cls._X0 * np.tan(u * a45)
        return np.arctan2(1.0, sigma * x)

    @classmethod
    def _dtheta_du(cls, piece: int, u, sigma):
        if piece == 0:
            return np.full_like(u, np.pi / 4)
        a45 = np.arctan(1 / (sigma * cls._X0))
        x = cls._X0 * np.tan(u * a45)
        dx = cls._X0 * a45 / np.cos(u * a45) ** 2
        return sigma * dx / (1 + (sigma * x) ** 2)  # |d/du arctan2(1, sigma x)|

    @classmethod
    def _u(cls, theta, sigma):
        low = theta <= np.pi / 4
        x = 1 / (np.tan(np.maximum(theta, 1e-300)) * sigma)  # cot/sigma (np.tan is vectorised)
        u_high = np.arctan(x / cls._X0) / np.arctan(1 / (sigma * cls._X0))
        return low, np.where(low, theta / (np.pi / 4), u_high)

    def _weight(self, theta, sigma):
        """rho / weight is tabulated: 1 if shadowed, ``1 + sigma tan(theta)`` unshadowed."""
        theta = np.asarray(theta, float)
        if self.strategy.conserves_energy:
            return np.ones_like(theta * sigma)
        return 1 + sigma * np.tan(theta)

    def _grid(self):
        u = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, self.n_theta))  # clustered at both ends
        ls = np.linspace(np.log(self.sigma_range[0]), np.log(self.sigma_range[1]), self.n_sigma)
        return u, ls

    def _build(self) -> dict:
        u, ls = self._grid()
        tables = {}
        for piece, name in ((0, "low"), (1, "high")):
            vals = np.empty((u.size, ls.size))
            for j, lsig in enumerate(ls):
                sig = float(np.exp(lsig))
                th = self._theta(piece, u, sig)
                vals[:, j] = dhr_beckmann(th, sig, self.strategy) / self._weight(th, sig)
            tables[name] = vals
        err = 0.0
        uc = (u[:-1] + u[1:]) / 2
        lc = (ls[:-1] + ls[1:]) / 2
        for piece, name in ((0, "low"), (1, "high")):
            spline = interpolate.RectBivariateSpline(u, ls, tables[name], kx=3, ky=3)
            for lsig in lc[::4]:
                sig = float(np.exp(lsig))
                th = self._theta(piece, uc, sig)
                ref = dhr_beckmann(th, sig, self.strategy)
                got = spline.ev(uc, np.full_like(uc, lsig)) * self._weight(th, sig)
                err = max(err, float(np.max(np.abs(got - ref) / np.maximum(1.0, ref))))
        return {
            "u": u,
            "log_sigma": ls,
            "low": tables["low"],
            "high": tables["high"],
            "max_error": np.array(err),
        }

    def __call__(self, theta_i, sigma) -> np.ndarray:
        """rho^{s,PEC}(theta_i; sigma), broadcasting ``theta_i`` [rad] and ``sigma``."""
        theta, sig = np.broadcast_arrays(np.asarray(theta_i, float), np.asarray(sigma, float))
        lo, hi = self.sigma_range
        inside = (sig >= lo) & (sig <= hi)
        out = np.empty(theta.shape)
        if np.any(inside):
            t, sg = theta[inside], sig[inside]
            low, u = self._u(t, sg)
            ls = np.log(sg)
            vals = np.empty(t.shape)
            if np.any(low):
                vals[low] = self._splines[0].ev(u[low], ls[low])
            if not np.all(low):
                vals[~low] = self._splines[1].ev(u[~low], ls[~low])
            out[inside] = vals * self._weight(t, sg)
        if not np.all(inside):  # rare: direct quadrature, one sigma at a time
            for sg in np.unique(sig[~inside]):
                sel = (~inside) & (sig == sg)
                out[sel] = dhr_beckmann(theta[sel], float(sg), self.strategy)
        if self.strategy.conserves_energy:
            out = np.minimum(out, 1.0)
        return np.maximum(out, 0.0)

    def cosine_average(self, sigma) -> np.ndarray:
        """Cosine-weighted hemispherical average ``2 int rho(theta) cos sin dtheta`` per ``sigma``.

        Gauss-Legendre (100 nodes) on each table piece, in the piece's own variable.
        """
        sig = np.atleast_1d(np.asarray(sigma, float))
        x, w = _gauss_legendre(100)
        u = (x + 1) / 2
        wu = w / 2
        out = np.empty(sig.shape)
        for k, sg in enumerate(sig.ravel()):
            total = 0.0
            for piece in (0, 1):
                th = self._theta(piece, u, sg)
                dth = self._dtheta_du(piece, u, sg)
                total += 2 * np.sum(wu * self(th, sg) * np.cos(th) * np.sin(th) * dth)
            out.flat[k] = total
        return out.reshape(np.shape(sigma))


class _Rho1D:
    """rho(theta) for one sigma: the table's pieces resampled on 4097 nodes, linear interpolation.

    Adds < 1e-8 to the table's error; several times faster than the 2-D spline.
    """

    def __init__(self, table: DHRTable, sigma: float):
        u = np.linspace(0.0, 1.0, 4097)
        self.table, self.sigma, self.u = table, sigma, u
        self.values = np.stack(
            [
                table(th, sigma) / table._weight(th, sigma)
                for th in (table._theta(piece, u, sigma) for piece in (0, 1))
            ]
        )
        self._flat = self.values.ravel()

    def __call__(self, theta):
        theta = np.asarray(theta, float)
        low, u = self.table._u(theta, self.sigma)
        # uniform grid: index arithmetic instead of a binary search, into the flattened pieces
        n = self.u.size - 1
        x = np.clip(u, 0.0, 1.0) * n
        i = np.minimum(x.astype(np.intp), n - 1)
        f = x - i
        i = np.where(low, i, i + (n + 1))
        v = self._flat[i] * (1 - f) + self._flat[i + 1] * f
        if self.table.strategy.conserves_energy:  # weight 1
            return v
        return v * self.table._weight(theta, self.sigma)


def dhr_slope_quadrature(
    theta_i, distribution, shadowing="torrance-sparrow", *, n_w: int = 128, n_psi: int = 128
) -> np.ndarray:
    """Specular PEC DHR (Eq. 174) of any isotropic facet distribution, by quadrature in slope space.

    Polar slope coordinates ``s = r (cos psi, sin psi)`` with ``r`` from the distribution's radial
    quantile, so ``p d^2 s = dw dpsi / (2 pi)`` with ``w`` uniform. At each ``r`` the visible arc
    ends at the horizon, at an analytic azimuth; Gauss-Legendre in ``w`` and over the arc. The kinks
    of G are not
    resolved, so the convergence is algebraic (see the test for the measured accuracy against the
    Beckmann-specific :func:`dhr_beckmann`). Used for non-Beckmann distributions.

    Parameters
    ----------
    theta_i : array_like
        Incidence angles [rad] in ``[0, pi/2]``.
    distribution : FacetDistribution
        Isotropic facet slope distribution (with a radial quantile).
    shadowing : {"torrance-sparrow", "none", "smith"} or Shadowing
    n_w, n_psi : int
        Quadrature nodes in the radial variable ``w`` and over the visible arc.

    Returns
    -------
    ndarray
        The DHR (dimensionless), shape of ``theta_i``.
    """
    strategy = shadowing_strategy(shadowing)
    theta = np.atleast_1d(as_angle(theta_i, "theta_i"))
    n_w, n_psi = _nodes(n_w, "n_w"), _nodes(n_psi, "n_psi")
    xw, ww = np.polynomial.legendre.leggauss(n_w)
    w = (xw + 1) / 2
    r = distribution.radial_quantile(w)[:, None]
    xp, wp = np.polynomial.legendre.leggauss(n_psi)
    out = np.empty(theta.shape)
    for k, t in enumerate(theta):
        c, s_ = np.cos(t), max(np.sin(t), 1e-12)
        # visible arc at slope magnitude r: psi in [psi0, pi] (and its mirror), horizon at
        # cos(psi0) = c (1 - r^2) / (2 s r)
        psi0 = np.arccos(np.clip(c * (1 - r * r) / (2 * s_ * np.maximum(r, 1e-300)), -1.0, 1.0))
        psi = psi0 + (np.pi - psi0) * (xp + 1) / 2
        wpsi = (np.pi - psi0) * wp / 2
        sx = r * np.cos(psi)
        sy = r * np.sin(psi)
        n2 = 1 + sx * sx + sy * sy
        m = c - sx * s_
        rz = np.maximum(2 * m / n2 - c, 0.0)
        gq = strategy.slope_integrand(m, rz, c, s_, distribution)
        out[k] = np.sum(ww[:, None] / 2 * wpsi * gq) / np.pi  # 2 (mirror) / (2 pi)
    if strategy.conserves_energy:
        out = np.minimum(out, 1.0)
    return out.reshape(np.shape(theta_i))


class SpecularDHR:
    """The specular PEC DHR of one pBRDF model, :math:`\\rho^{s,\\mathrm{PEC}}(\\theta_i)`.

    Eq. 174.

    Beckmann slopes read the shipped table of their shadowing (a 1-D resampling per scalar sigma);
    another distribution is tabulated once, as a shape-preserving cubic (PCHIP) over 129
    Chebyshev-clustered angles of :func:`dhr_slope_quadrature`.

    Parameters
    ----------
    shadowing : str or Shadowing
    sigma : float or ndarray, optional
        Beckmann rms slope (give this or ``distribution``).
    distribution : FacetDistribution, optional
    """

    def __init__(self, shadowing, sigma=None, distribution=None):
        self.strategy = shadowing_strategy(shadowing)
        self.sigma, self.distribution = sigma, distribution
        self._fn = None

    def _function(self):
        if self._fn is None:
            if self.distribution is not None:
                self._fn = _spline_dhr(self.distribution, self.strategy)
            else:
                table = dhr_table(self.strategy)
                lo, hi = table.sigma_range
                if np.ndim(self.sigma) == 0 and lo <= self.sigma <= hi:
                    self._fn = _Rho1D(table, float(self.sigma))
                else:
                    self._fn = functools.partial(_table_at, table, self.sigma)
        return self._fn

    def __call__(self, theta_i) -> np.ndarray:
        """rho at incidence angles ``theta_i`` [rad] (validated), broadcast against ``sigma``."""
        return self._function()(theta_i)

    def cosine_average(self) -> np.ndarray:
        """``2 int rho cos(theta) sin(theta) dtheta`` per sigma (norm of the reciprocal diffuse)."""
        if self.distribution is None:
            sig = np.asarray(self.sigma, float)
            flat = [_cosine_average_beckmann(self.strategy.name, float(s)) for s in sig.ravel()]
            return np.reshape(flat, sig.shape)
        x, w = _gauss_legendre(200)
        th = (x + 1) * np.pi / 4
        return np.sum(w * np.pi / 4 * 2 * self(th) * np.cos(th) * np.sin(th))


def _table_at(table, sigma, theta):
    return table(theta, sigma)


@functools.lru_cache(maxsize=256)
def _cosine_average_beckmann(shadowing: str, sigma: float) -> float:
    return float(dhr_table(shadowing).cosine_average(sigma))


def _spline_dhr(distribution, strategy):
    """rho(theta) of a non-Beckmann distribution: shape-preserving cubic (PCHIP) of rho * weight over
    129 angles. A plain cubic spline overshot between the nodes where rho * cos climbs steeply at grazing
    (heavy-tailed slopes without shadowing: rho -1.8e5 at 85 deg, hence a diffuse term 1.8e5 times
    too large); PCHIP keeps the non-negative node values non-negative, with the same accuracy elsewhere
    (relative error to the quadrature 6e-3 up to 85 deg for HyperCauchy(0.3, 1.05), 1e-5 to 4e-4 for
    smoother distributions)."""
    nodes = np.pi / 4 * (1 - np.cos(np.linspace(0, np.pi, 129)))
    weight = (lambda t: np.ones_like(t)) if strategy.conserves_energy else np.cos
    vals = dhr_slope_quadrature(nodes, distribution, strategy)
    spline = interpolate.PchipInterpolator(nodes, vals * weight(nodes))

    def rho(theta):
        theta = np.asarray(theta, float)
        with np.errstate(divide="ignore"):  # exactly 90 deg without shadowing: rho diverges
            return np.maximum(spline(theta) / weight(theta), 0.0)

    return rho


def _cache_dir() -> Path:
    d = Path(os.environ.get("SCATTERLAB_CACHE", Path.home() / ".cache" / "scatterlab"))
    return d


def _save_npz(path: Path, data: dict) -> None:
    from scatterlab.runtime.results import atomic_write_bytes

    buf = io.BytesIO()
    np.savez(buf, **data)
    try:
        atomic_write_bytes(path, buf.getvalue(), overwrite=True)
    except OSError:  # read-only home: keep the table in memory only
        pass


def dhr_table(shadowing="torrance-sparrow") -> DHRTable:
    """The process-wide table for ``shadowing`` (shipped, cached, or built once).

    Parameters
    ----------
    shadowing : {"torrance-sparrow", "none", "smith"} or Shadowing

    Returns
    -------
    DHRTable
        Interpolating table of the Beckmann PEC DHR over (theta_i, sigma).
    """
    return _dhr_table(shadowing_strategy(shadowing).name)


@functools.cache
def _dhr_table(name: str) -> DHRTable:
    return DHRTable(name)


def build_shipped_tables(names=SHADOWING) -> list[Path]:
    """Rebuild the tables shipped in ``scatterlab/pbrdf/data``.

    ``python -m scatterlab.pbrdf.dhr [NAME ...]``.

    Parameters
    ----------
    names : sequence of str
        Shadowing names to rebuild (default all of :data:`SHADOWING`).

    Returns
    -------
    list of Path
        The written ``.npz`` files.
    """
    out = []
    for shadowing in names:
        table = DHRTable(shadowing, cache=False)
        name = table.path.name
        data = {"u": table.u, "log_sigma": table.log_sigma, "max_error": np.array(table.max_error)}
        data["low"], data["high"] = table._values  # tabulated values; splines are rebuilt on load
        path = Path(__file__).parent / "data" / name
        _save_npz(path, data)
        out.append(path)
    return out


if __name__ == "__main__":  # pragma: no cover
    import sys

    for p in build_shipped_tables(tuple(sys.argv[1:]) or SHADOWING):
        print(p)
