"""What one pixel of a region can tell: the region's pixel scatter and the Cramer-Rao bound of a single pixel
of its true material (``metrics.pixel_scatter``, ``metrics._pixel_stats``), and the report's note."""

import warnings
from types import SimpleNamespace

import numpy as np

from scatterlab.characterization.metrics import _pixel_stats, pixel_scatter
from scatterlab.characterization.report_text import _failure_notes
from scatterlab.inversion import fit_dolp
from scatterlab.inversion.least_squares import model_dolp

THETAS = np.radians([30, 35, 40, 45, 50, 55, 60.0])  # the default scene's geometries
SIGMA = 0.3


def _region(n, kappa, noise, shape=(40, 40), seed=0):
    """A region of one material: its model DOLP at every pixel plus white noise of ``noise``."""
    rng = np.random.default_rng(seed)
    truth = model_dolp(n, kappa, SIGMA, THETAS, THETAS)
    stack = truth[:, None, None] + noise * rng.standard_normal((THETAS.size,) + shape)
    return stack, np.ones(shape, bool)


def test_pixel_scatter_is_the_noise_of_a_uniform_region_and_ignores_outliers():
    stack, mask = _region(3.6, 5.88, 0.002)
    assert abs(pixel_scatter(stack, mask) / 0.002 - 1) < 0.05
    stack[:, :2, :] = 0.9  # a few bright paint pixels left in the region (5 %)
    assert abs(pixel_scatter(stack, mask) / 0.002 - 1) < 0.12
    stack[:] = np.nan
    assert np.isnan(pixel_scatter(stack, mask))


def _fitted(n, kappa, noise, shape):
    """The least-squares fits of a uniform region's pixels and the region's pixel statistics."""
    stack, mask = _region(n, kappa, noise, shape)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_dolp(np.moveaxis(stack, 0, -1), THETAS, THETAS, sigma=SIGMA)
    maps = SimpleNamespace(n=fit.n, kappa=fit.kappa)
    stats = _pixel_stats(maps, {"metal": mask}, {"metal": (n, kappa)}, stack, THETAS, SIGMA)
    return fit, stats["metal"]


def test_a_steel_pixels_bound_is_the_spread_of_its_fits_and_aluminiums_exceeds_the_box():
    """Steel at small noise: the least-squares fits of independent pixels scatter as the Cramer-Rao bound
    says (an efficient estimator; Monte Carlo, 1600 pixels). Aluminium at the default scene's no-turbulence
    pixel noise (0.002): the bound of kappa is many times the fit's box of 25, and the fits of its pixels
    spread over the box."""
    fit, stats = _fitted(3.6, 5.88, 0.0005, (40, 40))
    assert abs(stats["pixel_dolp_scatter"] / 0.0005 - 1) < 0.05
    # the standard deviation of 1600 fits is known to ~2 %; the bound is first order in the noise
    assert abs(np.std(fit.n) / stats["pixel_crlb_n"] - 1) < 0.1
    assert abs(np.std(fit.kappa) / stats["pixel_crlb_kappa"] - 1) < 0.1

    fit, stats = _fitted(1.44, 16.0, 0.002, (20, 20))
    assert stats["pixel_crlb_kappa"] > 4 * 25 and stats["pixel_crlb_n"] > 5
    assert np.percentile(fit.kappa, 25) < 8 and np.percentile(fit.kappa, 75) > 20


def test_the_failure_note_gives_each_images_pixel_bound_for_the_failed_metal():
    def stats(scatter, bn, bk):
        return {"aluminium": dict(pixel_dolp_scatter=scatter, pixel_crlb_n=bn, pixel_crlb_kappa=bk)}

    res = SimpleNamespace(
        plate=SimpleNamespace(metal="aluminium"),
        metrics={
            "no_turbulence": stats(0.0019, 31.0, 170.0),
            "D_r0_7.9_degraded": stats(0.0061, 98.0, 540.0),
            "D_r0_7.9_corrected": {**stats(0.0083, 130.0, 730.0), "psf_l1_error": 1.1},
        },
    )
    eta = (
        "aluminium, D/r0 = 7.9: deconvolution does not worsen the aluminium's median |eta error|",
        "13.3 vs 9.5",
        False,
    )
    text = "\n".join(_failure_notes([res], [eta], SimpleNamespace(psf=False)))
    assert "What one pixel can tell" in text
    assert "no turbulence 0.0019: n +-31, kappa +-170" in text
    assert "D/r0 = 7.9 degraded 0.0061" in text and "D/r0 = 7.9 corrected 0.0083" in text
    assert "kappa 0-25" in text
    cls = (
        "aluminium, D/r0 = 7.9: corrected vs no-turbulence classification error <= 0.06",
        "",
        False,
    )
    assert "What one pixel can tell" not in "\n".join(
        _failure_notes([res], [cls], SimpleNamespace(psf=False))
    )


def test_fits_that_stop_on_the_box_edge_are_told_from_estimates():
    """A pixel whose DOLP no material in the fit's box gives (below a perfect conductor's, above the
    dielectric's maximum) is fitted on the box's edge and flagged; noise-free steel and paint pixels are
    fitted inside the box and not flagged; unfitted (NaN) pixels are not flagged."""
    from scatterlab.characterization.metrics import at_fit_bound
    from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

    steel = model_dolp(3.6, 5.88, SIGMA, THETAS, THETAS)
    paint = model_dolp(1.39, 0.34, SIGMA, THETAS, THETAS)
    beyond_metal = np.zeros_like(steel)  # no polarization at all: |eta| beyond the box
    y = np.stack([steel, paint, beyond_metal, np.full_like(steel, np.nan)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_dolp(y, THETAS, THETAS, sigma=SIGMA)
    flagged = at_fit_bound(fit.n, fit.kappa)
    np.testing.assert_array_equal(flagged, [False, False, True, False])
    assert fit.kappa[2] == DEFAULT_BOUNDS["kappa"][1] or fit.n[2] in DEFAULT_BOUNDS["n"]
    np.testing.assert_allclose([fit.n[0], fit.kappa[0]], [3.6, 5.88], rtol=1e-3)
