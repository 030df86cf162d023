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

from scatterlab._checks import as_angle
from scatterlab.pbrdf import Model

__all__ = ["DolpForward"]


def _facet_dolp_inplane(n, kappa, cos_beta, *, gradient: bool):
    """Facet DOLP (..., M) at facet-angle cosines (M,) and, optionally, its gradient (..., M, 2) in (n, kappa)."""
    eta = (np.maximum(n, 1e-9) - 1j * np.maximum(kappa, 0.0))[..., None]
    c = cos_beta
    c2 = c * c
    s2 = 1 - c2
    d = (eta.real - 1) * (eta.real + 1) - eta.imag**2 + c2  # Re(eta^2 - s^2), cancellation-free
    u = np.sqrt(d + 2j * eta.real * eta.imag)
    u = np.abs(u.real) - 1j * np.abs(u.imag)  # the branch A - jB with A, B >= 0 (AB = n kappa), also on the cut
    u = np.where(np.abs(u) < 1e-12, 1e-12, u)  # n = sin(beta), kappa = 0: branch point, keep the slope finite
    eta2 = eta * eta
    ds = c + u
    dp = eta2 * c + u
    num_p = eta2 * c2 - s2
    rs = 1.0 / (ds * ds)
    rp = -num_p / (dp * dp)
    a = rs.real**2 + rs.imag**2
    b = rp.real**2 + rp.imag**2
    tot = a + b
    P = (a - b) / tot
    if not gradient:
        return P, None
    du = eta / u
    drs = -2.0 * du / (ds * ds * ds)
    drp = -(2 * eta * c2 * dp - 2 * num_p * (2 * eta * c + du)) / (dp * dp * dp)
    grad = np.empty(P.shape + (2,))
    tot2 = tot * tot
    for k, (ga, gb) in enumerate(((2 * (rs.conj() * drs).real, 2 * (rp.conj() * drp).real),
                                  (2 * (rs.conj() * drs).imag, 2 * (rp.conj() * drp).imag))):
        grad[..., k] = 2 * (b * ga - a * gb) / tot2
    return P, grad


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
        ph = np.broadcast_to(np.asarray(phi, float), ti.shape).astype(float)
        if ti.shape != tr.shape:
            raise ValueError("theta_i and theta_r must have one entry per measured geometry")
        self.theta_i, self.theta_r, self.phi = ti, tr, ph
        self.model_kw = model_kw
        self.inplane = bool(np.all(ph == np.pi))
        self.cos_beta = np.cos((ti + tr) / 2)
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
            return _facet_dolp_inplane(n, kappa, self.cos_beta, gradient=gradient)
        smooth = Model(0.3, diffuse="none", **{k: v for k, v in self.model_kw.items() if k == "shadowing"})

        def f(nn, kk):
            eta = (np.maximum(nn, 1e-9) - 1j * np.maximum(kk, 0.0))[..., None]
            return smooth.dolp(eta, self.theta_i, self.theta_r, self.phi)

        P = f(n, kappa)
        if not gradient:
            return P, None
        grad = np.empty(P.shape + (2,))
        for k in range(2):
            h = 1e-6 * np.maximum(1.0, np.abs(n if k == 0 else kappa))
            lo_n, lo_k = (n - h, kappa) if k == 0 else (n, np.maximum(kappa - h, 0.0))
            hi_n, hi_k = (n + h, kappa) if k == 0 else (n, kappa + h)
            step = (hi_n - lo_n) if k == 0 else (hi_k - lo_k)
            grad[..., k] = (f(hi_n, hi_k) - f(lo_n, lo_k)) / step[..., None]
        return P, grad

    def fraction(self, sigma, *, gradient: bool = False):
        """Specular fraction Gamma/(Gamma + D) (..., M) and, with ``gradient``, its sigma derivative (..., M)."""
        sigma = np.asarray(sigma, float)

        def f(s):
            return Model(s[..., None], **self.model_kw).specular_fraction(self.theta_i, self.theta_r, self.phi)

        R = f(sigma)
        if not gradient:
            return R, None
        h = 1e-6 * sigma
        return R, (f(sigma + h) - f(sigma - h)) / (2 * h)[..., None]

    # -- the model --------------------------------------------------------------------------------------
    def _known(self, rows):
        R = self._fixed_fraction
        return R if rows is None or R.ndim == 1 else R[rows]

    def __call__(self, params, rows=None) -> np.ndarray:
        """DOLP (..., M) for parameters (..., P), P = 3 (n, kappa, sigma) or 2 (n, kappa) with sigma known."""
        p = np.asarray(params, float)
        Pf, _ = self.facet(p[..., 0], p[..., 1])
        R = self._known(rows) if self.n_params == 2 else self.fraction(p[..., 2])[0]
        return Pf * R

    def value_and_jacobian(self, params, rows=None):
        """DOLP (..., M) and its Jacobian (..., M, P).

        ``rows`` selects the entries of a known per-pixel ``sigma`` (flattened) that ``params`` (N, P) belong to.
        """
        p = np.asarray(params, float)
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
