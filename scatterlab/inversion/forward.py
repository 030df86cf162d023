r"""The DOLP forward model of the inversion and its Jacobian (Eqs. 114, 203).

For unpolarized illumination the pBRDF's DOLP factorises into two parts that share no parameter:

.. math:: \mathcal P(n, \kappa, \sigma) = \mathcal P_f(\eta; \text{facet geometry})
          \cdot \frac{\Gamma(\sigma)}{\Gamma(\sigma) + D(\sigma)},

the DOLP of the reflecting facet, :math:`(R_s - R_p)/(R_s + R_p)` at the facet angle :math:`\beta` in the
specular plane (Eq. 114), and the specular fraction of :math:`F_{00}` (Eq. 203,
:meth:`scatterlab.pbrdf.Model.specular_fraction`). :class:`DolpForward` evaluates both once per geometry set
and differentiates them separately:

* :math:`\partial\mathcal P_f/\partial n` and :math:`\partial/\partial\kappa` analytically in the specular
  plane: the reduced coefficients :math:`r_s' = 1/(c + u)^2`, :math:`r_p' = -(\eta^2c^2 - s^2)/(\eta^2 c + u)^2`
  (:math:`u = \sqrt{\eta^2 - s^2}`) are holomorphic in :math:`\eta = n - j\kappa`, so
  :math:`\partial|r|^2/\partial n = 2\,\mathrm{Re}(r^* r')` and
  :math:`\partial|r|^2/\partial\kappa = 2\,\mathrm{Im}(r^* r')`; out of the plane by central differences of the
  facet DOLP of :class:`~scatterlab.pbrdf.Model`;
* :math:`\partial/\partial\sigma` of the specular fraction by a central difference (step 1e-6 sigma), which
  involves the DHR table only, never the Fresnel part.

With sigma known the fraction is computed once for the whole fit.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from scatterlab._checks import as_angle, as_azimuth
from scatterlab.fresnel import smooth_dolp
from scatterlab.pbrdf import Model, facet_dolp, shadowing_strategy
from scatterlab.pbrdf.geometry import facet_geometry, polar_cos

__all__ = ["DolpForward"]

_SIGMA_TABLE = (1e-3, 2.5)
_MODEL_SIGMA = (1e-4, 5.0)  # the rms slopes scatterlab.pbrdf.Model takes (Beckmann)
_SIGMA_NODES = 4097


def _eta(n, kappa):
    """eta from parameters the fit may push to the bounds (n >= 1e-9, kappa >= 0)."""
    return np.maximum(n, 1e-9) - 1j * np.maximum(kappa, 0.0)


class DolpForward:
    """DOLP of (n, kappa, sigma) at M fixed geometries, with its Jacobian.

    Parameters
    ----------
    theta_i, theta_r : array (M,) [rad]
    phi : float or array (M,) [rad], default pi (specular plane)
    sigma : float or array (...), optional
        Known roughness: then the parameters are (n, kappa) and the specular fraction is computed once.
    **model_kw
        Passed to :class:`scatterlab.pbrdf.Model` (``shadowing``, ``diffuse``).
    """

    def __init__(self, theta_i, theta_r, phi=np.pi, *, sigma=None, **model_kw):
        ti = as_angle(theta_i, "theta_i").ravel()
        tr = as_angle(theta_r, "theta_r").ravel()
        ph = np.broadcast_to(as_azimuth(phi, "phi"), ti.shape).astype(float)
        if ti.shape != tr.shape:
            raise ValueError("theta_i and theta_r must have one entry per measured geometry")
        self.theta_i, self.theta_r, self.phi = ti, tr, ph
        self.model_kw = model_kw
        self.inplane = bool(np.all(ph == np.pi))
        self.cos_beta = polar_cos((ti + tr) / 2)  # exactly 0 where both directions are grazing
        self.sin2_beta = np.sin((ti + tr) / 2) ** 2
        self.sigma_known = None if sigma is None else np.asarray(sigma, float)
        self._fixed_fraction = None if sigma is None else self.fraction(self.sigma_known)[0]
        self.n_params = 3 if sigma is None else 2

    @property
    def size(self) -> int:
        return self.theta_i.size

    # -- the two factors ---------------------------------------------------------------------------------
    def facet(self, n, kappa, *, gradient: bool = False):
        """Facet DOLP (..., M) and, with ``gradient``, d/d(n, kappa) as (..., M, 2)."""
        n, kappa = np.asarray(n, float), np.asarray(kappa, float)
        if self.inplane:
            eta = _eta(n, kappa)[..., None]
            return smooth_dolp(eta, self.cos_beta, self.sin2_beta, gradient=gradient, checked=True)

        def f(nn, kk):
            return facet_dolp(_eta(nn, kk)[..., None], self.theta_i, self.theta_r, self.phi)

        P = f(n, kappa)
        if not gradient:
            return P, None
        grad = np.empty(P.shape + (2,))
        for k in range(2):
            h = 1e-6 * np.maximum(1.0, np.abs(n if k == 0 else kappa))
            lo_n, lo_k = (
                (np.maximum(n - h, 0.0), kappa) if k == 0 else (n, np.maximum(kappa - h, 0.0))
            )
            hi_n, hi_k = (n + h, kappa) if k == 0 else (n, kappa + h)
            step = (hi_n - lo_n) if k == 0 else (hi_k - lo_k)
            grad[..., k] = (f(hi_n, hi_k) - f(lo_n, lo_k)) / step[..., None]
        return P, grad

    def _build_fraction_table(self):
        """Per geometry: log(Gamma/p) (sigma-free for Torrance-Sparrow and no shadowing) and D on a log-sigma grid."""
        strategy = shadowing_strategy(self.model_kw.get("shadowing", "torrance-sparrow"))
        if (
            not strategy.sigma_free
            or self.model_kw.get("diffuse", "hyde") != "hyde"
            or self.model_kw.get("distribution") is not None
        ):
            return (
                None  # Smith's G depends on sigma; the reciprocal D has kinks a linear table smears
            )
        ti, tr, ph = self.theta_i, self.theta_r, self.phi
        # where the lobe diverges at exact grazing (log Gamma = -inf there) the fraction is its limit, 1
        unit = Model(1.0, **self.model_kw)
        self._diverges = unit.diverges(ti, tr, ph)
        lg1, _ = unit.log_lobe_terms(ti, tr, ph)
        t2 = facet_geometry(ti, tr, ph, checked=True).tan2_alpha
        self._t2 = np.where(np.isfinite(t2), t2, 0.0)
        self._log_gop = lg1 + self._t2 / 2 + np.log(2 * np.pi)  # -inf where facets are hidden
        grid = np.linspace(np.log(_SIGMA_TABLE[0]), np.log(_SIGMA_TABLE[1]), _SIGMA_NODES)
        _, log_d = Model(np.exp(grid)[:, None], **self.model_kw).log_lobe_terms(ti, tr, ph)
        D = np.exp(log_d)
        self._dD = CubicSpline(grid, D, axis=0)(grid, 1)  # node slopes dD/dlog(sigma)
        return grid, D

    def _fraction_tabulated(self, sigma, gradient):
        grid, D_tab = self._table
        h = grid[1] - grid[0]
        x = (np.log(sigma) - grid[0]) / h
        k = np.clip(x.astype(np.intp), 0, grid.size - 2)
        f = (x - k)[..., None]
        D0, D1 = D_tab[k], D_tab[k + 1]
        # cubic Hermite with the spline's node slopes (h^4 accurate where D is smooth); D = 0 where rho is
        # clamped at 1 (the model's own discontinuity, Gamma/(Gamma + 0) = 1): a cell next to a zero node is
        # linear, and a cell touching one is taken as zero rather than a spurious tiny D
        m0, m1 = self._dD[k] * h, self._dD[k + 1] * h
        f2, f3 = f * f, f * f * f
        cubic = (
            (2 * f3 - 3 * f2 + 1) * D0
            + (f3 - 2 * f2 + f) * m0
            + (-2 * f3 + 3 * f2) * D1
            + (f3 - f2) * m1
        )
        near_zero = (D_tab[np.maximum(k - 1, 0)] <= 0) | (
            D_tab[np.minimum(k + 2, grid.size - 1)] <= 0
        )
        D = np.where((D0 > 0) & (D1 > 0), np.where(near_zero, D0 * (1 - f) + D1 * f, cubic), 0.0)
        s = sigma[..., None]
        with np.errstate(under="ignore", divide="ignore"):
            G = np.exp(self._log_gop - self._t2 / (2 * s * s) - np.log(2 * np.pi * s * s))
        tot = G + D
        safe = np.where(tot > 0, tot, 1.0)
        R = np.where(tot > 0, G / safe, np.where(D > 0, 0.0, 1.0))
        R = np.where(self._diverges, 1.0, R)
        if not gradient:
            return R, None
        dG = G * (self._t2 / s**3 - 2 / s)
        dcubic = (
            (6 * f2 - 6 * f) * D0
            + (3 * f2 - 4 * f + 1) * m0
            + (6 * f - 6 * f2) * D1
            + (3 * f2 - 2 * f) * m1
        )
        dD = np.where((D0 > 0) & (D1 > 0), np.where(near_zero, D1 - D0, dcubic), 0.0) / (h * s)
        dR = np.where(tot > 0, (dG * D - G * dD) / (safe * safe), 0.0)
        return R, np.where(self._diverges, 0.0, dR)

    def fraction(self, sigma, *, gradient: bool = False):
        """Specular fraction Gamma/(Gamma + D) (..., M) and, with ``gradient``, its sigma derivative (..., M).

        For Beckmann slopes, Torrance-Sparrow (or no) shadowing and the "hyde" diffuse term: Gamma
        exactly (analytic in sigma) and D
        interpolated (cubic Hermite) in log sigma on 4097 nodes over [1e-3, 2.5] (measured error in the tests);
        otherwise Model.specular_fraction with a central difference. 1 where both terms vanish and where the
        lobe diverges at an exactly grazing direction (:meth:`scatterlab.pbrdf.Model.diverges`), as
        Model.specular_fraction.
        """
        sigma = np.asarray(sigma, float)
        if not hasattr(self, "_table"):
            self._table = self._build_fraction_table()
        if (
            self._table is not None
            and np.all(sigma >= _SIGMA_TABLE[0])
            and np.all(sigma <= _SIGMA_TABLE[1])
        ):
            return self._fraction_tabulated(sigma, gradient)

        def f(s):
            return Model(s[..., None], **self.model_kw).specular_fraction(
                self.theta_i, self.theta_r, self.phi
            )

        R = f(sigma)
        if not gradient:
            return R, None
        # central where it can be, one-sided at the model's range of sigma (1e-4 itself is allowed:
        # a step below it was refused by the model)
        h = 1e-6 * sigma
        lo = np.maximum(sigma - h, _MODEL_SIGMA[0])
        hi = np.minimum(sigma + h, _MODEL_SIGMA[1])
        return R, (f(hi) - f(lo)) / (hi - lo)[..., None]

    # -- the model --------------------------------------------------------------------------------------
    def _known(self, rows):
        R = self._fixed_fraction
        return R if rows is None or R.ndim == 1 else R[rows]

    def _params(self, params) -> np.ndarray:
        """``params`` as a float array (..., P), P = :attr:`n_params`; else a ValueError naming it."""
        names = "(n, kappa, sigma)" if self.n_params == 3 else "(n, kappa) (sigma is known)"
        try:
            p = np.asarray(params, float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"params must be numeric {names}, got {params!r}") from exc
        if p.ndim == 0 or p.shape[-1] != self.n_params:
            raise ValueError(
                f"params must have shape (..., {self.n_params}): {names} along the last axis, got "
                f"shape {p.shape}"
            )
        return p

    def __call__(self, params, rows=None) -> np.ndarray:
        """DOLP (..., M) for parameters (..., P), P = 3 (n, kappa, sigma) or 2 (n, kappa) with sigma known.

        ``params`` must have exactly P values on its last axis (a ValueError otherwise)."""
        p = self._params(params)
        Pf, _ = self.facet(p[..., 0], p[..., 1])
        R = self._known(rows) if self.n_params == 2 else self.fraction(p[..., 2])[0]
        return Pf * R

    def value_and_jacobian(self, params, rows=None):
        """DOLP (..., M) and its Jacobian (..., M, P).

        ``rows`` selects the entries of a known per-pixel ``sigma`` (flattened) that ``params`` (N, P) belong to.
        ``params`` must have exactly P values on its last axis (a ValueError otherwise). At a bound
        of the model's sigma range (1e-4, 5) the sigma derivative is one-sided.
        """
        p = self._params(params)
        Pf, gf = self.facet(p[..., 0], p[..., 1], gradient=True)
        J = np.empty(Pf.shape + (self.n_params,))
        if self.n_params == 2:
            R = self._known(rows)
            J[..., :2] = gf * R[..., None]
        else:
            R, dR = self.fraction(p[..., 2], gradient=True)
            J[..., :2] = gf * R[..., None]
            J[..., 2] = Pf * dR
        return Pf * R, J
