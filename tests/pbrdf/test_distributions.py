import mpmath
import numpy as np
import pytest
from scipy import integrate

from scatterlab.pbrdf import Beckmann, HyperCauchy


@pytest.mark.parametrize(
    "dist",
    [Beckmann(0.05), Beckmann(0.3), Beckmann(1.2), HyperCauchy(0.3, 2.0), HyperCauchy(0.5, 3.5)],
)
def test_slope_density_normalised_and_facet_density_eq127(dist):
    # int p d^2 s = 1 (radial integral) and int P(alpha) d omega = 1 (Eq. 127 normalisation)
    tot = integrate.quad(lambda r: 2 * np.pi * r * dist.slope_pdf(r * r), 0, np.inf, limit=200)[0]
    assert tot == pytest.approx(1, abs=1e-9)
    tot = integrate.quad(
        lambda a: 2 * np.pi * np.sin(a) * dist.facet_pdf(np.tan(a) ** 2),
        0,
        np.pi / 2,
        limit=400,
        points=[0.01, 0.1, 0.5],
    )[0]
    assert tot == pytest.approx(1, abs=1e-8)


def test_beckmann_per_axis_variance_and_eq128():
    d = Beckmann(0.3)
    var = integrate.quad(lambda r: 2 * np.pi * r * r * r * d.slope_pdf(r * r), 0, np.inf)[0] / 2
    assert np.sqrt(var) == pytest.approx(0.3, rel=1e-9)
    assert Beckmann.from_height(2.0, 10.0).sigma == pytest.approx(np.sqrt(2) * 0.2)
    assert HyperCauchy(0.6, 4.0).rms_slope == pytest.approx(0.6 / 2)


@pytest.mark.parametrize("sigma", [0.1, 0.5])
@pytest.mark.parametrize("theta", [0.3, 0.9, 1.4])
def test_smith_lambda_matches_its_integral_definition(sigma, theta):
    """Lambda(mu) = (1/mu) int_mu^inf (q - mu) p1(q) dq with p1 the marginal slope density, mu = cot(theta)."""
    mpmath.mp.dps = 40
    mu = mpmath.mpf(1) / mpmath.tan(theta)
    s = mpmath.mpf(sigma)
    a = mu / (mpmath.sqrt(2) * s)
    # 40-digit evaluation of the closed form (free of the double-precision cancellation)
    ref = float(mpmath.exp(-a * a) / (2 * a * mpmath.sqrt(mpmath.pi)) - mpmath.erfc(a) / 2)
    assert Beckmann(sigma).smith_lambda(np.tan(theta)) == pytest.approx(ref, rel=1e-9, abs=1e-300)
    if a < 8:  # and the integral definition itself, where quadrature is reliable

        def p1(q):
            return mpmath.exp(-q * q / (2 * s**2)) / mpmath.sqrt(2 * mpmath.pi * s**2)

        width = s * s / mu
        integral = mpmath.quad(
            lambda q: (q - mu) * p1(q), [mu + k * width for k in (0, 1, 5, 20)] + [mpmath.inf]
        )
        assert float(integral / mu) == pytest.approx(ref, rel=1e-9)
    mu = float(mu)
    b = 0.4  # Cauchy (nu = 2): marginal is Student-t-like with density b^2 / (2 (b^2 + q^2)^1.5)

    def p1c(q):
        return b * b / (2 * (b * b + q * q) ** 1.5)

    refc = integrate.quad(lambda q: (q - mu) * p1c(q), mu, np.inf)[0] / mu
    assert HyperCauchy(b, 2.0).smith_lambda(np.tan(theta)) == pytest.approx(refc, rel=1e-8)


def test_bad_parameters():
    with pytest.raises(ValueError, match="sigma"):
        Beckmann(-0.1)
    with pytest.raises(ValueError, match="sigma"):
        Beckmann(10.0)
    with pytest.raises(ValueError, match="nu"):
        HyperCauchy(0.3, 1.0)
    with pytest.raises(ValueError, match="Smith"):
        HyperCauchy(0.3, 3.0).smith_lambda(np.array([0.5]))
