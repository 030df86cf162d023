r"""Self-calibration of the region-mean DOLP by re-simulation (a parametric bootstrap of the restoration bias).

A restoration cannot give back what the optics removed: the object's frequencies beyond :math:`D/\lambda`
are gone, and Richardson-Lucy-type EM pulls the last per cent of a bright neighbour's light out of a dim
region only slowly. For the painted plates this leaves the paint's region-mean DOLP 0.004-0.009 low after the
known-PSF restoration (noise-free, converged; the metal's halo is 20-30x brighter than the paint), and
0.2-0.5 low after a *blind* restoration of a small scene through D/r0 = 7.9 (the blind PSF misses most of the
turbulent halo) -- biases that no noise term can cover.

The bias depends on the scene's layout and contrast, which the data show, so it is measured on a copy of the
scene as estimated: the classification gives the layout (metal vs dielectric), a least-squares fit to the
uncorrected region means gives each region's material, and that synthetic plate is imaged and restored as the
data were, then registered like the data:

* **known PSF** (the no-turbulence image): one noise-free re-simulation through the same PSF, restored with
  it. The bias is deterministic; half of it is kept as a systematic error (the re-simulated scene is not the
  true one).
* **blind** (a turbulent image): ``replicates`` re-simulations per geometry, each through a *new* Kolmogorov
  screen of the image's D/r0 and with the data's noise, restored blindly from a new random start PSF and
  aligned with the synthetic object -- a bootstrap over turbulence, noise and the blind estimate.
  Re-simulating through the data's own PSF *estimate* instead (the first version) sees only the part of the
  blur the estimate caught: on the coverage scene it found biases of 0.01-0.05 where the data's were
  0.2-0.5. The paint's bias is a ratio (restored over true DOLP: its polarization diluted by the metal's
  unpolarized halo), the metal's a difference. A paint whose DOLP the restoration halved is first estimated
  as a lossier, brighter paint than it is, which a re-simulation dilutes less; a second pass re-estimates the
  plate from the first pass's correction. The data's own bias is one more draw from the replicates' spread,
  so the systematic error is their standard deviation (pooled over the geometries) times
  :math:`\sqrt{1 + 1/R}`, in quadrature with half the correction (scene mismatch).

What it does not see (the scene's own details) is left to the inferred noise term of the posterior;
``studies/characterization_coverage.py`` measures whether the intervals then cover the truth.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from scatterlab.characterization.acquisition import Ideal, acquire
from scatterlab.characterization.estimation import RegionData, region_data
from scatterlab.characterization.registration import register_restoration
from scatterlab.characterization.restoration import RestoreSettings, restore
from scatterlab.characterization.scene_config import Plate

__all__ = ["BiasEstimate", "estimated_plate", "restoration_bias", "bias_corrected"]

# of the re-simulated bias, kept as a systematic error after subtracting it (the re-simulated scene is an
# estimate of the true one)
SYSTEMATIC_FRACTION = 0.5
BOOTSTRAP_REPLICATES = 2  # re-simulations per geometry of a blindly restored image
CALIBRATION_PASSES = (
    2  # bootstrap passes (each re-estimates the plate from the previous pass's correction)
)
RATIO_MIN_DOLP = (
    0.1  # a region this polarized (synthetic truth) is corrected by a ratio, not a difference
)


@dataclass(frozen=True)
class BiasEstimate:
    """Re-simulated restoration bias of one region's mean DOLP.

    Attributes
    ----------
    mean : ndarray, shape (M,)
        Bias per geometry [DOLP]: the re-simulated region mean minus the synthetic truth (mean over the
        replicates).
    spread : ndarray, shape (M,)
        Standard deviation of one replicate's bias [DOLP], pooled over the geometries (0 for the
        deterministic known-PSF re-simulation).
    replicates : int
        Re-simulations per geometry.
    ratio : ndarray, shape (M,), or None
        Restored over true region-mean DOLP (mean over replicates), for a polarized region diluted by a
        bright neighbour's halo: the data are then divided by it instead of having ``mean`` subtracted.
    """

    mean: np.ndarray
    spread: np.ndarray
    replicates: int = 1
    ratio: np.ndarray | None = None

    def systematic(self) -> np.ndarray:
        """Error left after subtracting :attr:`mean` [DOLP], shape (M,): the scene-mismatch fraction of the
        bias and, for a bootstrap, the data's own draw from the replicates' spread (:math:`\\sqrt{1 + 1/R}`)."""
        draw = self.spread * np.sqrt(1.0 + 1.0 / self.replicates) if self.replicates > 1 else 0.0
        return np.hypot(SYSTEMATIC_FRACTION * np.abs(self.mean), draw)


def estimated_plate(regions, thetas, sigma) -> Plate:
    """A plate whose paint and metal are the least-squares fits to the regions' (uncorrected) mean DOLP.

    Parameters
    ----------
    regions : list of RegionData
    thetas : ndarray, shape (M,)
        Specular angles [rad].
    sigma : float
        Known roughness.

    Returns
    -------
    Plate
    """
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
    plate, labels, theta, psf, blind, d_over_r0, cfg, seed = task
    rng = np.random.default_rng(seed)
    bootstrap = blind and d_over_r0 is not None
    # known PSF: noise-free through the same PSF; bootstrap: a new screen of the same D/r0, with noise;
    # blind without a D/r0: noise-free through the data's estimated PSF (sees only the blur it caught)
    acq = acquire(
        plate,
        labels,
        theta,
        "resimulation",
        d_over_r0 if bootstrap else (float("nan") if blind else None),
        cfg,
        rng,
        Ideal(noise=not bootstrap),
        psf=None if bootstrap else psf,
    )
    settings = RestoreSettings(cfg.iterations, cfg.psf_model, None, True, None)
    rest = restore(acq, settings, seed, Ideal(psf=not blind))
    # a blind restoration through a new screen is shifted by its tilt: aligned with the synthetic object, as
    # the data are aligned with the restored no-turbulence image
    reference = acq.truth_s0 if bootstrap else None
    reg = register_restoration(rest, theta, reference, foreshortened=acq.foreshortened)
    return reg.dolp, acq.truth_dolp


def restoration_bias(
    regions,
    class_map,
    thetas,
    psfs,
    cfg,
    rng,
    interior,
    margin,
    *,
    blind=False,
    d_over_r0=None,
    replicates=None,
    executor=None,
) -> dict:
    """Re-simulated bias of each region's mean DOLP per geometry (module docstring).

    Parameters
    ----------
    regions : list of RegionData
        The data's region means (uncorrected), ``name`` "paint" and "metal".
    class_map : ndarray of int, shape (H, W)
        Estimated layout in object coordinates (0 dielectric, > 0 metal).
    thetas : ndarray, shape (M,)
        Specular angles [rad].
    psfs : list of ndarray (H, W) or None
        Per geometry, the PSF the image was restored with (None: the diffraction-limited one); used by the
        known-PSF re-simulation.
    cfg : SceneConfig
    rng : numpy.random.Generator
    interior : bool ndarray (H, W)
        Pixels scored.
    margin : int
        Region erosion [pixels].
    blind : bool
        The data were restored blindly: bootstrap over new screens of ``d_over_r0``, restored blindly.
    d_over_r0 : float, optional
        Turbulence strength of the blind case. Without it (measured data of unknown D/r0) the re-simulation
        goes through the data's estimated PSF, which sees only the part of the blur the estimate caught
        (biases 5-10 times too small on the coverage scene).
    replicates : int, optional
        Re-simulations per geometry of the bootstrap (default :data:`BOOTSTRAP_REPLICATES`; 1 for the
        known-PSF re-simulation).
    executor : optional

    Returns
    -------
    dict
        Region name -> :class:`BiasEstimate`.
    """
    from scatterlab.runtime import get_executor

    if d_over_r0 is not None and not (np.isfinite(d_over_r0) and d_over_r0 > 0):
        raise ValueError(f"d_over_r0 must be > 0 (or None), got {d_over_r0!r}")
    bootstrap = blind and d_over_r0 is not None
    R = int(BOOTSTRAP_REPLICATES if replicates is None else replicates) if bootstrap else 1
    if R < 1:
        raise ValueError(f"replicates must be >= 1, got {replicates!r}")
    labels = (np.asarray(class_map) > 0).astype(int)
    ex = executor if executor is not None else get_executor("serial")
    bias, current = {}, list(regions)
    for _ in range(CALIBRATION_PASSES if bootstrap else 1):
        # each pass re-estimates the plate from the data corrected by the previous pass: a paint whose
        # DOLP the blind restoration halved is first estimated as a brighter, lossier paint than it is
        plate = estimated_plate(current, thetas, cfg.sigma_known)
        tasks = [
            (plate, labels, th, psf, blind, d_over_r0, cfg, int(rng.integers(2**63)))
            for _ in range(R)
            for th, psf in zip(thetas, psfs)
        ]
        out = ex.map(_resimulate_task, tasks, desc="self-calibration")
        bias = _bias_from_replicates(regions, out, labels, interior, margin, thetas, R, bootstrap)
        current = [bias_corrected(r, bias[r.name]) for r in regions]
    return bias


def _bias_from_replicates(regions, out, labels, interior, margin, thetas, R, bootstrap) -> dict:
    """Per region, the :class:`BiasEstimate` of ``R`` replicates of the ``M`` geometries (``out`` in
    replicate-major order: (restored DOLP, true DOLP) pairs)."""
    M = len(thetas)
    stack = np.stack([d for d, _ in out]).reshape((R, M) + labels.shape)
    truth = np.stack([t for _, t in out[:M]])
    bias = {}
    for r in regions:
        lab = 0 if r.name == "paint" else 1
        true = np.array([np.nanmean(t[labels == lab]) for t in truth])
        est = np.stack(
            [region_data(r.name, st, labels, interior, margin, thetas).mean for st in stack]
        )
        b = est - true
        spread = (
            np.full(M, np.sqrt(np.nanmean(np.nanvar(b, axis=0, ddof=1)))) if R > 1 else np.zeros(M)
        )
        ratio = None
        if bootstrap and r.name == "paint" and np.all(true > RATIO_MIN_DOLP):
            # a dim polarized region is diluted by its bright neighbour's unpolarized halo: restored =
            # ratio x true, a ratio that depends on the layout and contrast far more than on the paint
            ratio = est.mean(axis=0) / true
        bias[r.name] = BiasEstimate(b.mean(axis=0), spread, R, ratio)
    return bias


def bias_corrected(region: RegionData, bias) -> RegionData:
    """``region`` with the re-simulated bias subtracted and its systematic error added.

    Parameters
    ----------
    region : RegionData
        Uncorrected region means.
    bias : BiasEstimate or array_like, shape (M,)
        From :func:`restoration_bias` (a plain array is a deterministic bias: half of it kept as error).

    Returns
    -------
    RegionData
        ``mean`` corrected and clipped to [0, 1]; ``error``, ``statistical`` and ``edge`` scaled by the
        correction's slope (``1 / ratio`` for a ratio), ``error`` with :meth:`BiasEstimate.systematic` added
        in quadrature; ``bias`` the subtracted bias, ``bias_spread`` the bootstrap spread.
    """
    if not isinstance(bias, BiasEstimate):
        b = np.asarray(bias, float)
        bias = BiasEstimate(b, np.zeros_like(b), 1)
    scale = 1.0 if bias.ratio is None else 1.0 / bias.ratio  # d(corrected mean) / d(mean)
    if bias.ratio is not None:
        corrected = region.mean / bias.ratio
        # the same error model on the equivalent difference; the spread scales with the correction
        equivalent = BiasEstimate(
            region.mean - corrected, bias.spread / bias.ratio, bias.replicates
        )
        sys_err = equivalent.systematic()
        subtracted = equivalent.mean
    else:
        sys_err = bias.systematic()
        subtracted = bias.mean
    # a DOLP is in [0, 1]: a corrected mean beyond it keeps the bound (its error still carries the bias)
    mean = np.clip(region.mean - subtracted, 0.0, 1.0)
    # dividing the mean by a ratio divides its statistical and edge errors by it too
    return replace(
        region,
        mean=mean,
        error=np.sqrt((scale * region.error) ** 2 + sys_err**2),
        statistical=scale * region.statistical,
        edge=scale * region.edge,
        bias=subtracted,
        bias_spread=bias.spread,
    )
