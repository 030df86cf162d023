r"""Self-calibration of the region-mean DOLP by re-simulation (a parametric bootstrap of the restoration bias).

A restoration cannot give back what the optics removed: the object's frequencies beyond :math:`D/\lambda`
are gone, and Richardson-Lucy-type EM pulls the last per cent of a bright neighbour's light out of a dim
region only slowly. For the painted plates this leaves the paint's region-mean DOLP 0.004-0.009 low after the
known-PSF restoration (noise-free, converged; the metal's halo is 20-30x brighter than the paint) -- a bias
that is the same for every noise realization, so no noise term can cover it.

The bias depends on the scene's layout and contrast, which the data show, so it is measured on a copy of the
scene as estimated: the classification gives the layout (metal vs dielectric), a least-squares fit to the
uncorrected region means gives each region's material, and that synthetic plate is imaged through the same
PSF (the known one, or the deconvolution's estimate for a corrected image), without noise, restored as the
data were (with the known PSF, or blindly from a new random start PSF -- a parametric bootstrap of the
whole blind restoration, PSF error included) and registered like the data. The bias of each region
and geometry is the re-simulated region mean
minus the synthetic truth; it is subtracted from the data, and half of it is kept as a systematic error
(the re-simulated scene is not the true one). What it does not see (the scene's own details, the random
start of one blind run) is left to the inferred noise term of the posterior.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from scatterlab.characterization.acquisition import Ideal, acquire
from scatterlab.characterization.estimation import RegionData, region_data
from scatterlab.characterization.registration import register_restoration
from scatterlab.characterization.restoration import RestoreSettings, restore
from scatterlab.characterization.scene_config import Plate

__all__ = ["estimated_plate", "restoration_bias", "bias_corrected"]

SYSTEMATIC_FRACTION = (
    0.5  # of the re-simulated bias, kept as a systematic error after subtracting it
)


def estimated_plate(regions, thetas, sigma) -> Plate:
    """A plate whose paint and metal are the least-squares fits to the regions' (uncorrected) mean DOLP."""
    from scatterlab.inversion import fit_dolp

    fits = {}
    for r in regions:
        f = fit_dolp(r.mean, thetas, thetas, sigma=sigma)
        fits[r.name] = (max(float(f.n), 0.05), max(float(f.kappa), 0.0))
    # a region the data lack (none of its pixels survive the erosion) keeps a typical material: it has no
    # pixels in the re-simulated layout's scored regions either
    (pn, pk), (mn, mk) = fits.get("paint", (1.5, 0.0)), fits.get("metal", (1.44, 16.0))
    return Plate("estimate", mn, mk, pn, pk, sigma, sigma)


def _resimulate_task(task):
    """Module-level (process executors): image, restore as the data were restored (known PSF, or blindly from
    a random start PSF) and register one geometry."""
    plate, labels, theta, psf, blind, cfg, seed = task
    rng = np.random.default_rng(seed)
    acq = acquire(
        plate,
        labels,
        theta,
        "resimulation",
        float("nan") if blind else None,
        cfg,
        rng,
        Ideal(noise=True),
        psf=psf,
    )
    settings = RestoreSettings(cfg.iterations, cfg.psf_model, None, True, None)
    rest = restore(acq, settings, seed, Ideal(psf=not blind))
    reg = register_restoration(rest, theta, None, foreshortened=acq.foreshortened)
    return reg.dolp, acq.truth_dolp


def restoration_bias(
    regions, class_map, thetas, psfs, cfg, rng, interior, margin, *, blind=False, executor=None
) -> dict:
    """Re-simulated bias of each region's mean DOLP per geometry.

    Parameters
    ----------
    regions : list of RegionData
        The data's region means (uncorrected), ``name`` "paint" and "metal".
    class_map : ndarray of int, shape (H, W)
        Estimated layout in object coordinates (0 dielectric, > 0 metal).
    thetas : ndarray, shape (M,)
        Specular angles [rad].
    psfs : list of ndarray (H, W) or None
        Per geometry, the PSF the image was restored with (None: the diffraction-limited one).
    cfg : SceneConfig
    rng : numpy.random.Generator
    interior : bool ndarray (H, W)
        Pixels scored.
    margin : int
        Region erosion [pixels].
    blind : bool
        Restore the re-simulated images blindly, as the data were (then the bias includes the error of the
        blind PSF estimate); otherwise with the PSF known.
    executor : optional

    Returns
    -------
    dict
        Region name -> bias array (M,) [DOLP].
    """
    from scatterlab.runtime import get_executor

    plate = estimated_plate(regions, thetas, cfg.sigma_known)
    labels = (np.asarray(class_map) > 0).astype(int)
    tasks = [
        (plate, labels, th, psf, blind, cfg, int(rng.integers(2**63)))
        for th, psf in zip(thetas, psfs)
    ]
    ex = executor if executor is not None else get_executor("serial")
    out = ex.map(_resimulate_task, tasks, desc="self-calibration")
    stack = np.stack([d for d, _ in out])
    truth = np.stack([t for _, t in out])
    bias = {}
    for r in regions:
        lab = 0 if r.name == "paint" else 1
        est = region_data(r.name, stack, labels, interior, margin, thetas)
        true = np.array([np.nanmean(t[labels == lab]) for t in truth])
        bias[r.name] = est.mean - true
    return bias


def bias_corrected(region: RegionData, bias) -> RegionData:
    """``region`` with the re-simulated ``bias`` (M,) subtracted and a fraction of it added to its error."""
    b = np.asarray(bias, float)
    sys_err = SYSTEMATIC_FRACTION * np.abs(b)
    # a DOLP is in [0, 1]: a corrected mean beyond it keeps the bound (its error still carries the bias)
    mean = np.clip(region.mean - b, 0.0, 1.0)
    return replace(region, mean=mean, error=np.sqrt(region.error**2 + sys_err**2), bias=b)
