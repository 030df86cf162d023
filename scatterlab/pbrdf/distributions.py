r"""Facet slope distributions behind one small interface.

A distribution gives the probability density :math:`p(\mathbf{s})` of the 2-D
facet slope :math:`\mathbf{s} = -\nabla h` (isotropic, normalised
:math:`\int p\, d^2s = 1`), evaluated from :math:`|\mathbf s|^2 = \tan^2\alpha`.
The density of facet normals per solid angle is then
:math:`P(\alpha) = p/\cos^3\alpha` (Eq. 127), normalised :math:`\int P\, d\omega = 1`,
and the pBRDF uses :math:`P(\alpha)/\cos\alpha` (Eq. 166).

* :class:`Beckmann` -- Gaussian slopes (Eqs. 127, 168); ``sigma`` is the per-axis
  rms slope, :math:`\sigma^2 = 2\sigma_h^2/\ell^2` (Eq. 128).
* :class:`HyperCauchy` -- a two-parameter generalised Cauchy family,
  :math:`p = \frac{\nu-1}{\pi b^2}(1 + |\mathbf s|^2/b^2)^{-\nu}`, ``nu > 1``; ``nu = 2``
  is the Cauchy (Trowbridge-Reitz) distribution discussed by Shell and Gartley,
  and ``nu -> inf`` with ``b^2 = 2 nu sigma^2`` tends to Beckmann. It is in the
  spirit of the hyper-Cauchy of Wellems et al. (Ref. 140), whose exact
  parameterisation the reference text does not give.

Each also provides Smith's masking function :math:`\Lambda` where it has a
closed form (Beckmann; HyperCauchy with ``nu = 2``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

from scatterlab._checks import as_finite, as_positive

__all__ = ["Beckmann", "HyperCauchy", "FacetDistribution"]


class FacetDistribution:
    """Interface: ``slope_pdf(tan2)`` [1/slope^2], ``facet_pdf(tan2)`` [1/sr], ``smith_lambda(tan_theta)``."""

    def slope_pdf(self, tan2: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def facet_pdf(self, tan2: np.ndarray) -> np.ndarray:
        """Density of facet normals per solid angle, ``P(alpha) = p(tan alpha) / cos^3 alpha`` (Eq. 127)."""
        tan2 = np.asarray(tan2, float)
        return self.slope_pdf(tan2) * (1 + tan2) ** 1.5

    def radial_quantile(self, w: np.ndarray) -> np.ndarray:
        """Slope magnitude r with P(|s| > r) = w, w in (0, 1] (maps the radial distribution to uniform)."""
        raise NotImplementedError

    def smith_lambda(self, tan_theta: np.ndarray) -> np.ndarray:
        raise ValueError(
            f"Smith shadowing has no closed form for {type(self).__name__}; "
            "shadowing must be 'torrance-sparrow' or 'none' for it"
        )

    def smith_lambda_cos(self, cos_theta: np.ndarray) -> np.ndarray:
        """``cos(theta) * Lambda(theta)``, finite at grazing (``cos theta = 0``), where Lambda is infinite."""
        raise ValueError(
            f"Smith shadowing has no closed form for {type(self).__name__}; "
            "shadowing must be 'torrance-sparrow' or 'none' for it"
        )

    @property
    def rms_slope(self) -> float:
        """Per-axis rms slope (inf when the variance diverges)."""
        raise NotImplementedError


@dataclass(frozen=True, eq=False)
class Beckmann(FacetDistribution):
    """Gaussian slopes with per-axis rms slope ``sigma`` (Eq. 127): ``p = exp(-tan^2/(2 sigma^2)) / (2 pi sigma^2)``.

    ``sigma`` may be an array in ``[1e-4, 5]``; it broadcasts against the slopes.
    """

    sigma: float

    def __post_init__(self):
        s = as_positive(self.sigma, "sigma")
        if not np.all((s >= 1e-4) & (s <= 5)):
            raise ValueError("sigma (per-axis rms facet slope) must be in [1e-4, 5]")
        object.__setattr__(self, "sigma", float(s) if s.ndim == 0 else s)

    @classmethod
    def from_height(cls, sigma_h: float, corr_length: float) -> "Beckmann":
        """From rms height and correlation length [same units]: ``sigma^2 = 2 sigma_h^2 / l^2`` (Eq. 128)."""
        sigma_h = float(as_positive(sigma_h, "sigma_h"))
        corr_length = float(as_positive(corr_length, "corr_length"))
        return cls(np.sqrt(2.0) * sigma_h / corr_length)

    def radial_quantile(self, w):
        return self.sigma * np.sqrt(-2 * np.log(w))

    def slope_pdf(self, tan2):
        s2 = self.sigma**2
        return np.exp(-np.asarray(tan2, float) / (2 * s2)) / (2 * np.pi * s2)

    def smith_lambda(self, tan_theta):
        r"""Smith's :math:`\Lambda(\theta) = [e^{-a^2}/(a\sqrt\pi) - \mathrm{erfc}(a)]/2`,
        :math:`a = \cot\theta/(\sqrt2\sigma)`."""
        t = np.asarray(tan_theta, float)
        with np.errstate(divide="ignore"):
            a = np.where(t > 0, 1.0 / (np.sqrt(2.0) * self.sigma * np.where(t > 0, t, 1.0)), np.inf)
        return _beckmann_lambda(a)

    def smith_lambda_cos(self, cos_theta):
        r"""Finite at grazing:
        :math:`\cos\theta\,\Lambda = \tfrac12 e^{-a^2}\sqrt2\sigma\sin\theta\,(1/\sqrt\pi - a\,\mathrm{erfcx}(a))`.
        """
        c = np.clip(np.asarray(cos_theta, float), 0.0, 1.0)
        s = np.sqrt((1 - c) * (1 + c))
        k = np.sqrt(2.0) * self.sigma * s
        with np.errstate(divide="ignore"):
            a = np.where(k > 0, c / np.where(k > 0, k, 1.0), np.inf)
        small = a < 10
        a_s = np.where(small, a, 1.0)
        near = 0.5 * np.exp(-a_s * a_s) * k * (1 / np.sqrt(np.pi) - a_s * special.erfcx(a_s))
        return np.where(
            small, np.maximum(near, 0.0), c * _beckmann_lambda(np.where(small, 10.0, a))
        )

    @property
    def rms_slope(self):
        return self.sigma


def _beckmann_lambda(a):
    """Smith's Lambda of Beckmann slopes as a function of ``a = cot(theta)/(sqrt(2) sigma)``."""
    big = a > 25  # Lambda < 1e-270: zero to double precision
    grazing = a < 1e-150  # theta -> 90 deg: fully masked (and a^2 would underflow)
    a_s = np.where(big | grazing, 1.0, a)
    # 1/(a sqrt(pi)) - erfcx(a) cancels for large a: use its asymptotic series there (a >= 10: < 1e-12 rel.)
    x = 1.0 / (2 * np.maximum(a_s, 10.0) ** 2)  # only used where a >= 10
    series = x * (1 - 3 * x * (1 - 5 * x * (1 - 7 * x * (1 - 9 * x * (1 - 11 * x)))))
    diff = np.where(
        a_s >= 10,
        series / (a_s * np.sqrt(np.pi)),
        1.0 / (a_s * np.sqrt(np.pi)) - special.erfcx(a_s),
    )
    lam = 0.5 * np.exp(-a_s * a_s) * diff
    return np.where(big, 0.0, np.where(grazing, np.inf, np.maximum(lam, 0.0)))


@dataclass(frozen=True)
class HyperCauchy(FacetDistribution):
    """Generalised Cauchy slopes: ``p = (nu - 1)/(pi b^2) (1 + tan^2/b^2)^(-nu)``.

    ``b`` in ``[1e-4, 1e4]`` (the slope scale, like Beckmann's sigma) and ``nu`` finite and
    ``>= 1.05``. The distribution is normalisable for every ``nu > 1``, but a fraction
    ``(1 + 1e40)^(1 - nu)`` of its facets has slopes beyond ``1e20 b``: 40 % at ``nu = 1.01``, where
    the slope quadrature overflows; 1 % at ``nu = 1.05``.
    """

    b: float
    nu: float = 2.0

    def __post_init__(self):
        b = float(as_positive(self.b, "b"))
        if not 1e-4 <= b <= 1e4:
            raise ValueError(f"b (slope scale) must be in [1e-4, 1e4], got {b!r}")
        nu = float(as_finite(self.nu, "nu"))
        if not nu >= 1.05:
            raise ValueError(
                f"nu must be finite and >= 1.05 (below it over 1 % of the facets are steeper than 1e20 b), got {nu!r}"
            )

    def radial_quantile(self, w):
        return self.b * np.sqrt(np.expm1(-np.log(w) / (self.nu - 1)))

    def slope_pdf(self, tan2):
        b2 = self.b**2
        return (self.nu - 1) / (np.pi * b2) * (1 + np.asarray(tan2, float) / b2) ** (-self.nu)

    def smith_lambda(self, tan_theta):
        if self.nu != 2.0:
            return super().smith_lambda(tan_theta)
        y = np.abs(self.b * np.asarray(tan_theta, float))
        # (sqrt(1 + y^2) - 1)/2 without cancellation at small y, nor overflow of y^2 at grazing
        # (tan ~ 1e300 from the slope quadrature): y/(1 + hypot(1, y)) <= 1
        return y * (y / (1 + np.hypot(1.0, y))) / 2

    def smith_lambda_cos(self, cos_theta):
        """``cos(theta) Lambda = b^2 sin^2 / (2 (cos + sqrt(cos^2 + b^2 sin^2)))`` (nu = 2), finite at grazing."""
        if self.nu != 2.0:
            return super().smith_lambda_cos(cos_theta)
        c = np.clip(np.asarray(cos_theta, float), 0.0, 1.0)
        bs2 = self.b**2 * (1 - c) * (1 + c)
        return bs2 / (c + np.sqrt(c * c + bs2)) / 2

    @property
    def rms_slope(self):
        return self.b / np.sqrt(2 * (self.nu - 2)) if self.nu > 2 else np.inf
