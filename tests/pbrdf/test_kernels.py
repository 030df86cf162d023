"""One kernel per formula (issue 18): every facet-DOLP form of the package is a thin wrapper over
:func:`scatterlab.fresnel.smooth_dolp`, and all of them equal the textbook
``(R_s - R_p) / (R_s + R_p)`` written here from Eq. 45 directly (an independent evaluation: the
principal square root, no reduced form), to rounding."""

import numpy as np
import pytest

from scatterlab.fresnel import smooth_dolp
from scatterlab.inversion.forward import DolpForward
from scatterlab.inversion.thilak import thilak_dop
from scatterlab.pbrdf import dolp_smooth_facet, dolp_thilak, facet_dolp

ETAS = [1.5 - 0.0j, 1.39 - 0.34j, 0.314 - 3.544j, 3.6 - 5.88j, 1.44 - 16j]


def textbook_dolp(eta, theta):
    """Eq. 45 as printed: r_s, r_p from eta cos(theta_t) = sqrt(eta^2 - sin^2), Re >= 0."""
    c, s2 = np.cos(theta), np.sin(theta) ** 2
    u = np.sqrt(eta * eta - s2 + 0j)
    u = np.where(u.real < 0, -u, u)
    rs = (c - u) / (c + u)
    rp = (eta * eta * c - u) / (eta * eta * c + u)
    Rs, Rp = np.abs(rs) ** 2, np.abs(rp) ** 2
    return (Rs - Rp) / (Rs + Rp)


@pytest.mark.parametrize("eta", ETAS)
def test_every_facet_dolp_form_equals_the_kernel_and_the_textbook_formula(eta):
    ti = np.radians(np.array([10.0, 30.0, 45.0, 60.0, 75.0]))
    tr = np.radians(np.array([20.0, 40.0, 45.0, 50.0, 80.0]))
    beta = (ti + tr) / 2
    truth = textbook_dolp(eta, beta)
    kernel = smooth_dolp(eta, np.cos(beta), np.sin(beta) ** 2)[0]
    np.testing.assert_allclose(kernel, truth, rtol=1e-12, atol=1e-15)
    forms = {
        "dolp_smooth_facet": dolp_smooth_facet(eta, beta),
        "dolp_thilak": dolp_thilak(eta, ti, tr),
        "facet_dolp (in plane)": facet_dolp(eta, ti, tr),
        "thilak_dop": thilak_dop(eta.real, -eta.imag, beta),
        "DolpForward.facet": DolpForward(ti, tr).facet(eta.real, -eta.imag)[0],
    }
    for name, value in forms.items():
        np.testing.assert_allclose(value, kernel, rtol=1e-12, atol=1e-15, err_msg=name)
