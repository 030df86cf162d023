import numpy as np
import pytest
from scipy.integrate import cubature


def hemisphere_integral(fn, rtol=1e-7, atol=2e-9, full_circle=False):
    """int over the outgoing hemisphere of fn(theta_r, phi) cos(theta_r) d omega, by adaptive cubature
    in (mu = cos theta_r, phi) -- independent of the slope-space quadrature of scatterlab.pbrdf.dhr.
    Unless ``full_circle``, the integrand is taken symmetric in phi -> 2 pi - phi (true of F00) and phi
    runs over [0, pi] twice; Mueller elements odd under that mirror need ``full_circle``. ``fn`` may return
    (npoints,) or (npoints, k) values. Tolerances: 1e-7 relative / 2e-9 absolute per cell, two
    orders below the tolerances the tests assert."""

    def f(x):
        mu, ph = x[:, 0], x[:, 1]
        tr = np.arccos(np.clip(mu, 0.0, 1.0))
        val = fn(tr, ph) * (1 if full_circle else 2)
        return val * (mu if val.ndim == 1 else mu[:, None])

    # split mu and phi so the specular lobe sits inside small cells
    mus = np.linspace(0, 1, 9)
    phs = np.r_[0, np.pi / 2, 3 * np.pi / 4, 7 * np.pi / 8, np.pi]
    if full_circle:
        phs = np.r_[phs, 2 * np.pi - phs[::-1][1:]]
    total = 0.0
    for a, b in zip(mus[:-1], mus[1:]):
        for c, d in zip(phs[:-1], phs[1:]):
            res = cubature(f, [a, c], [b, d], rtol=rtol, atol=atol, max_subdivisions=20000)
            total += res.estimate
    return total


@pytest.fixture(name="hemisphere_integral")
def _hemisphere_integral_fixture():
    return hemisphere_integral
