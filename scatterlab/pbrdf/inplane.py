r"""The facet model in its 1-D (in-plane) form: the like-for-like partner of a 1-D MoM surface.

A 1-D rough profile :math:`y = h(x)` (the method of moments, :mod:`scatterlab.mom`) scatters only
in the plane of incidence, and s and p never mix. Its facets have a 1-D slope
:math:`s = \tan\alpha` with the Gaussian density

.. math:: p_1(s) = \frac{1}{\sqrt{2\pi}\,\sigma}\,e^{-s^2/(2\sigma^2)},\qquad
          \sigma = \sqrt2\,\sigma_h/\ell

(the same per-axis rms slope as the 2-D Beckmann density of Eq. 127, and as
:func:`scatterlab.mom.rms_slope`). Geometric optics of such a profile (the derivation of
Eqs. 166-173 with one slope instead of two): a plane wave from ``theta_i`` is reflected into the
signed scattering angle ``theta_s`` (MoM convention: positive on the forward side, specular at
``theta_s = theta_i``) by the facets tilted by :math:`\alpha = (\theta_s - \theta_i)/2`, seen at
the local incidence angle :math:`\beta = (\theta_i + \theta_s)/2`. They intercept
:math:`p_1(s)\,ds\,\cos\beta/\cos\alpha` of the power :math:`\cos\theta_i` falling on a unit length
of the mean line, and :math:`d\theta_s = 2\cos^2\alpha\,ds`, so the scattering coefficient per
radian (the MoM's ``scattering_coefficient``) of the specular term is

.. math:: \sigma^{spec}_{s,p}(\theta_s) = R_{s,p}(\beta)\,\Gamma_1,\qquad
          \Gamma_1 = \frac{G\,p_1(\tan\alpha)\cos\beta}{2\cos\theta_i\cos^3\alpha}.

The shadowing functions carry over unchanged: the Torrance-Sparrow V-groove function (Eq. 172) is
the exact masking of in-plane V-grooves, and Smith's :math:`\Lambda` of Gaussian slopes depends
only on the slope component in the plane of incidence, i.e. on the 1-D density above.

The diffuse term of Eqs. 176-177 in 1-D: the PEC's missing power
:math:`1 - \rho_1(\theta_i)`, :math:`\rho_1 = \int\Gamma_1\,d\theta_s` (:func:`dhr_pec_1d`), sent
out as a 2-D Lambertian, :math:`\cos\theta_s/2` per radian, times :math:`M_{00}(\beta) =
(R_s + R_p)/2`, unpolarized: it adds the same amount to both polarizations.

The specular term's DOLP is the facet's, :math:`(R_s - R_p)/(R_s + R_p)` at :math:`\beta`, in 1-D
exactly as in the 2-D pBRDF in the specular plane (Eq. 203); the 1-D and 2-D models differ only in
the specular fraction :math:`\Gamma/(\Gamma + D)`, i.e. only with the diffuse term.

:math:`\rho_1 = \int G\,p_1(s)(1 - s\tan\theta_i)\,ds` over the facets that send light above
the horizon. With shadowing it is at most 1; without it (the Priest-Germer form) it exceeds 1
towards grazing incidence, as in 2-D (the slopes that would face away from the source, which
carry the negative part of :math:`1 - s\tan\theta_i`, are left out), and the diffuse term is
then clipped at 0.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_angle, as_index, as_positive, broadcast
from scatterlab.fresnel import reflectances
from scatterlab.pbrdf.distributions import Beckmann

__all__ = [
    "slope_pdf_1d",
    "shadowing_1d",
    "specular_lobe_1d",
    "dhr_pec_1d",
    "inplane_coefficients",
    "dolp_1d",
]

SHADOWING_1D = ("torrance-sparrow", "smith", "none")
_NODES = np.polynomial.legendre.leggauss(1024)
_TAILS = 12.0  # slopes beyond 12 sigma carry < 1e-32 of the density


def _sigma(sigma):
    s = as_positive(sigma, "sigma")
    if not np.all((s >= 1e-4) & (s <= 5)):
        raise ValueError("sigma (rms facet slope) must be in [1e-4, 5]")
    return s


def _check_shadowing(shadowing):
    if shadowing not in SHADOWING_1D:
        raise ValueError(f"shadowing must be one of {SHADOWING_1D}, got {shadowing!r}")


def slope_pdf_1d(s, sigma) -> np.ndarray:
    """Gaussian density of the 1-D facet slope ``s = tan(alpha)``.

    Parameters
    ----------
    s : array_like -- slopes (dimensionless).
    sigma : array_like -- rms slope in ``[1e-4, 5]``, ``sqrt(2) sigma_h / l``.

    Returns
    -------
    ndarray [1/slope], broadcast shape; integrates to 1 over s.
    """
    sig = _sigma(sigma)
    s = np.asarray(s, float)
    return np.exp(-(s * s) / (2 * sig * sig)) / (np.sqrt(2 * np.pi) * sig)


def _angles(theta_i, theta_s):
    ti = as_angle(theta_i, "theta_i", 0.0, np.pi / 2)
    ts = as_angle(theta_s, "theta_s", -np.pi / 2, np.pi / 2)
    return ti, ts


def _shadow(ti, ts, sig, shadowing):
    """G for incidence ti >= 0 and signed ts (validated), facet tilt (ts - ti)/2."""
    alpha = (ts - ti) / 2
    cb = np.cos((ti + ts) / 2)
    if shadowing == "none":
        return np.ones(np.broadcast_shapes(np.shape(ti), np.shape(ts), np.shape(sig)))
    if shadowing == "torrance-sparrow":
        with np.errstate(divide="ignore", invalid="ignore"):
            k = np.where(cb > 0, 2 * np.cos(alpha) / np.where(cb > 0, cb, 1.0), 0.0)
        return np.clip(np.minimum(k * np.cos(ts), k * np.cos(ti)), 0.0, 1.0) + 0.0 * sig
    slopes = Beckmann(np.asarray(sig, float))
    with np.errstate(divide="ignore"):
        lam_i = slopes.smith_lambda(np.abs(np.tan(ti)))
        lam_s = slopes.smith_lambda(np.abs(np.tan(ts)))
    return 1.0 / (1.0 + lam_i + lam_s)


def shadowing_1d(theta_i, theta_s, sigma, shadowing: str = "torrance-sparrow") -> np.ndarray:
    """Shadowing/masking G of the in-plane facet joining ``theta_i`` to ``theta_s``.

    Parameters
    ----------
    theta_i : array_like [rad] in ``[0, pi/2]``
    theta_s : array_like [rad] in ``[-pi/2, pi/2]``, signed (specular at ``theta_s = theta_i``).
    sigma : array_like -- rms slope (used by Smith's function only).
    shadowing : {"torrance-sparrow", "smith", "none"}

    Returns
    -------
    ndarray in ``[0, 1]``, broadcast shape.
    """
    _check_shadowing(shadowing)
    ti, ts = _angles(theta_i, theta_s)
    return _shadow(ti, ts, _sigma(sigma), shadowing)


def _lobe(ti, ts, sig, shadowing):
    alpha = (ts - ti) / 2
    ca = np.cos(alpha)
    cb = np.cos((ti + ts) / 2)
    p = np.exp(-(np.tan(alpha) ** 2) / (2 * sig * sig)) / (np.sqrt(2 * np.pi) * sig)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = _shadow(ti, ts, sig, shadowing) * p * cb / (2 * np.cos(ti) * ca**3)
    return np.where(np.isfinite(out) & (cb > 0), out, 0.0)


def specular_lobe_1d(theta_i, theta_s, sigma, shadowing: str = "torrance-sparrow") -> np.ndarray:
    r"""The PEC specular term :math:`\Gamma_1` per radian (module docstring).

    Parameters
    ----------
    theta_i : array_like [rad] in ``[0, pi/2]``
    theta_s : array_like [rad] in ``[-pi/2, pi/2]``, signed.
    sigma : array_like -- rms slope in ``[1e-4, 5]``.
    shadowing : {"torrance-sparrow", "smith", "none"}

    Returns
    -------
    ndarray [1/rad], broadcast shape, ``>= 0``, finite. At ``theta_i = numpy.pi/2`` with shadowing it
    is the grazing limit (``G/cos(theta_i)`` is finite on the lit facets; :func:`dhr_pec_1d`), which
    integrates to 1 over ``theta_s``; without shadowing it follows the model's divergence.
    """
    _check_shadowing(shadowing)
    ti, ts = _angles(theta_i, theta_s)
    return _lobe(ti, ts, _sigma(sigma), shadowing)


def dhr_pec_1d(theta_i, sigma, shadowing: str = "torrance-sparrow") -> np.ndarray:
    r"""Specular DHR :math:`\rho_1(\theta_i) = \int\Gamma_1\,d\theta_s` of a 1-D PEC profile.

    Gauss-Legendre (1024 nodes) in the slope over the facets that reflect above the horizon,
    cut at 12 sigma; :math:`\rho_1 = \int G\,p_1(s)\,(1 - s\tan\theta_i)\,ds`.

    At grazing incidence, ``theta_i = pi/2`` exactly, the limit: only the facets facing the source
    (``s < 0``) are lit and :math:`G\tan\theta_i` tends to a finite limit while :math:`G \to 0`,
    so :math:`\rho_1 \to \int_{-\infty}^0 \lim G\tan\theta_i\,(-s)\,p_1(s)\,ds`. For
    Torrance-Sparrow :math:`G \to 2\cos\alpha\cos\theta_i/\cos\beta` with :math:`\cos\beta
    \to \sin|\alpha|`, so :math:`G\tan\theta_i\,|s| \to 2` and :math:`\rho_1 \to 2\int_{-\infty}^0
    p_1 = 1`; for Smith :math:`\Lambda(\tan\theta_i) \to \sigma\tan\theta_i/\sqrt{2\pi}`, so
    :math:`G\tan\theta_i \to \sqrt{2\pi}/\sigma` and :math:`\rho_1 \to (\sqrt{2\pi}/\sigma)
    \,\sigma/\sqrt{2\pi} = 1`. Both approach 1 linearly in :math:`\pi/2 - \theta_i`. Without
    shadowing it diverges, :math:`\rho_1 \approx 1/2 + \sigma\tan\theta_i/\sqrt{2\pi}`, which is
    what is returned at ``theta_i = numpy.pi/2``: that double lies 6e-17 below the true pi/2, so
    :math:`\tan\theta_i = 1.6\times10^{16}` and the result is finite (as from
    :func:`scatterlab.pbrdf.dhr_beckmann`).

    Parameters
    ----------
    theta_i : array_like [rad] in ``[0, pi/2]``
    sigma : array_like -- rms slope in ``[1e-4, 5]``.
    shadowing : {"torrance-sparrow", "smith", "none"}

    Returns
    -------
    ndarray ``>= 0``, broadcast shape of ``theta_i`` and ``sigma``; at most 1 with shadowing
    (module docstring), exactly 1 at ``theta_i = pi/2``; finite everywhere (about ``2.6e15
    sigma`` at ``pi/2`` without shadowing).
    """
    _check_shadowing(shadowing)
    ti = as_angle(theta_i, "theta_i", 0.0, np.pi / 2)
    sig = _sigma(sigma)
    ti, sig = np.broadcast_arrays(ti, sig)
    grazing = ti >= np.pi / 2
    if grazing.any():  # the limit (docstring); the quadrature below is for the other angles
        if shadowing == "none":
            rho = 0.5 + sig * np.tan(np.minimum(ti, np.pi / 2)) / np.sqrt(2 * np.pi)
        else:
            rho = np.ones(ti.shape)
        rest = ~grazing
        if rest.any():
            rho[rest] = dhr_pec_1d(ti[rest], sig[rest], shadowing)
        return rho[()]
    lo = np.maximum(np.tan((-np.pi / 2 - ti) / 2), -_TAILS * sig)[..., None]
    hi = np.minimum(np.tan((np.pi / 2 - ti) / 2), _TAILS * sig)[..., None]
    x, w = _NODES
    s = lo + (hi - lo) * (x + 1) / 2
    alpha = np.arctan(s)
    t, sg = ti[..., None], sig[..., None]
    g = _shadow(t, np.clip(t + 2 * alpha, -np.pi / 2, np.pi / 2), sg, shadowing)
    f = g * np.exp(-s * s / (2 * sg * sg)) / (np.sqrt(2 * np.pi) * sg) * (1 - s * np.tan(t))
    rho = np.maximum(np.sum(w * f, -1) * (hi[..., 0] - lo[..., 0]) / 2, 0.0)
    return rho if shadowing == "none" else np.minimum(rho, 1.0)


def inplane_coefficients(
    eta,
    theta_i,
    theta_s,
    sigma,
    *,
    shadowing: str = "torrance-sparrow",
    diffuse: str = "hyde",
):
    r"""Scattering coefficients per radian of the 1-D facet model, s- and p-polarized.

    :math:`\sigma_{s,p} = R_{s,p}(\beta)\Gamma_1 + D_1 M_{00}(\beta)`, with
    :math:`D_1 = \max(1 - \rho_1(\theta_i), 0)\cos\theta_s/2` for ``diffuse="hyde"`` (Eqs. 176-177 in
    1-D) and 0 for ``"none"``; the module docstring derives it.

    Parameters
    ----------
    eta : complex array_like (``n - 1j*kappa``) or ``"pec"``
    theta_i : array_like [rad] in ``[0, pi/2]``; exactly ``pi/2`` (grazing) with shadowing only, where
        the lobe is its limit (:func:`dhr_pec_1d`: a PEC's integrates to 1) and the diffuse term 0.
        Without shadowing the model diverges there (``rho_1 ~ sigma tan(theta_i)``), so
        ``shadowing="none"`` needs ``theta_i < pi/2``.
    theta_s : array_like [rad] in ``[-pi/2, pi/2]``, signed (specular at ``theta_s = theta_i``).
    sigma : array_like -- rms slope ``sqrt(2) sigma_h / l`` in ``[1e-4, 5]``.
    shadowing : {"torrance-sparrow", "smith", "none"}
    diffuse : {"hyde", "none"}

    Returns
    -------
    (coef_s, coef_p) : ndarrays [1/rad], broadcast shape, ``>= 0``; with shadowing each
    integrates over ``theta_s`` to at most 1.
    """
    _check_shadowing(shadowing)
    if diffuse not in ("hyde", "none"):
        raise ValueError(f"diffuse must be 'hyde' or 'none', got {diffuse!r}")
    ti, ts = _angles(theta_i, theta_s)
    if shadowing == "none" and np.any(ti >= np.pi / 2):
        raise ValueError(
            "theta_i must be below pi/2 rad with shadowing='none' (the unshadowed facet model "
            "diverges at grazing incidence); use 'torrance-sparrow' or 'smith' for theta_i = pi/2"
        )
    sig = _sigma(sigma)
    beta = np.abs(ti + ts) / 2
    if isinstance(eta, str):
        if eta.lower() != "pec":
            raise ValueError(f"eta must be a complex index n - 1j*kappa or 'pec', got {eta!r}")
        rs = rp = np.ones_like(beta)
    else:
        eta, beta = broadcast(eta=as_index(eta), beta=beta)
        rs, rp = reflectances(eta, beta)
    lobe = _lobe(ti, ts, sig, shadowing)
    cs, cp = rs * lobe, rp * lobe
    if diffuse == "hyde":
        d = np.maximum(1 - dhr_pec_1d(ti, sig, shadowing), 0.0) * np.cos(ts) / 2 * (rs + rp) / 2
        cs, cp = cs + d, cp + d
    return cs, cp


def dolp_1d(
    eta,
    theta_i,
    theta_s,
    sigma,
    *,
    shadowing: str = "torrance-sparrow",
    diffuse: str = "hyde",
) -> np.ndarray:
    r"""Signed DOLP :math:`(\sigma_s - \sigma_p)/(\sigma_s + \sigma_p)` of the 1-D facet model.

    For unpolarized illumination of a 1-D profile (no s-p mixing) the DOLP is this ratio of the
    s- and p-polarized coefficients; its sign says which dominates (the model's is >= 0 for
    passive media, the exact solution's may be negative). Without the diffuse term it is the
    facet's DOLP at ``beta = (theta_i + theta_s)/2``, as in Eq. 203.

    Parameters
    ----------
    eta, theta_i, theta_s, sigma, shadowing, diffuse : as :func:`inplane_coefficients`.

    Returns
    -------
    ndarray in ``[-1, 1]``, broadcast shape; NaN where no light is scattered.
    """
    cs, cp = inplane_coefficients(
        eta, theta_i, theta_s, sigma, shadowing=shadowing, diffuse=diffuse
    )
    tot = cs + cp
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(tot > 0, (cs - cp) / np.where(tot > 0, tot, 1.0), np.nan)
