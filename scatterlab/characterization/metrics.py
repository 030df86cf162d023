"""Scoring stage: every image of a plate against the truth (simulation) and against the no-turbulence image.

Per image key (``no_turbulence`` -- the restored reference --, ``no_turbulence_unrestored``,
``D_r0_<x>_degraded``, ``D_r0_<x>_corrected``):

* DOLP RMSE and S0 relative RMSE (the flux matched per geometry, each being exposed for itself) against
  the object and against the reference, and against the object away from the paint/metal edges (the
  region masks below);
* for a blind restoration, the PSF estimate's L1 distance from the true PSF (``psf_l1_error``);
* classification at the geometry nearest 50 deg (Table 4) against the reference classification (the
  priors' DOLP thresholds applied to the restored no-turbulence image) and against the true labels;
* per-pixel n and kappa (Table 5: mean and standard deviation over each eroded region, median |eta error|);
* region posteriors of n and kappa with the truth beside them.

Statistics exclude a border of 1/16 of the image and the pixels the registration brought in from beyond the
camera's field (``Registered.measured``; shifts of 10-25 pixels are ordinary at D/r0 12.9).
"""

from __future__ import annotations

import numpy as np

from scatterlab.characterization.estimation import (
    default_margin,
    pixel_maps,
    region_data,
    region_masks,
    region_posteriors,
)

__all__ = ["score_plate", "rmse", "reference_classes", "pixel_scatter", "at_fit_bound"]


def rmse(a, b, sel) -> float:
    """Root-mean-square difference of ``a`` and ``b`` over the finite entries selected by ``sel``.

    Parameters
    ----------
    a, b : ndarray
        Images of the same shape.
    sel : ndarray of bool
        Entries compared (broadcast to the images).

    Returns
    -------
    float
        The RMS difference (NaN when nothing is selected).
    """
    d = (np.asarray(a) - np.asarray(b))[sel]
    d = d[np.isfinite(d)]
    return float(np.sqrt(np.mean(d**2))) if d.size else float("nan")


def _stack(obs, case, kind, attr):
    return np.stack([getattr(o.images[(case, kind)], attr) for o in obs])


def _image_errors(obs, case, kind, sel, away=None):
    """DOLP RMSE and flux-normalised S0 relative RMSE over ``sel`` against the truth and the reference;
    with ``away`` (the eroded region masks) also against the truth away from the paint/metal edges
    (``*_truth_away_from_edges``), where neither the camera's resolution nor the keystone interpolation
    of the edge's step in brightness enters."""
    truth_dolp = np.stack([o.truth_dolp for o in obs])
    truth_s0 = np.stack([o.truth_s0 for o in obs])
    ref_dolp = _stack(obs, "no_turbulence", "restored", "dolp")
    ref_s0 = _stack(obs, "no_turbulence", "restored", "s0")
    dolp, s0 = _stack(obs, case, kind, "dolp"), _stack(obs, case, kind, "s0")
    # pixels the registration brought in from beyond the camera's field are not scored
    sel3 = np.broadcast_to(sel, dolp.shape) & _measured(obs, case, kind)
    out = {
        "dolp_rmse_truth": rmse(dolp, truth_dolp, sel3),
        "dolp_rmse_no_turbulence": rmse(dolp, ref_dolp, sel3),
    }
    scale = {}
    for name, target in (("truth", truth_s0), ("no_turbulence", ref_s0)):
        # each geometry is exposed for itself (its brightest pixel sets the photon budget) and the
        # truth's radiance changes threefold over the geometries: the flux is matched per geometry, or
        # the exposures' ratios would be scored as an S0 error
        flux = np.sum(np.where(sel3, s0, 0.0), axis=(-2, -1))
        scale[name] = (
            np.sum(np.where(sel3, target, 0.0), axis=(-2, -1)) / np.maximum(flux, 1e-300)
        )[:, None, None]
        out[f"s0_relative_rmse_{name}"] = rmse(s0 * scale[name], target, sel3) / float(
            target[:, sel].mean()
        )
    if away is not None and away.any():
        away3 = np.broadcast_to(away, dolp.shape) & _measured(obs, case, kind)
        out["dolp_rmse_truth_away_from_edges"] = rmse(dolp, truth_dolp, away3)
        # same flux scale and normaliser as over the whole field: the two numbers compare
        out["s0_relative_rmse_truth_away_from_edges"] = rmse(
            s0 * scale["truth"], truth_s0, away3
        ) / float(truth_s0[:, sel].mean())
    return out


def _measured(obs, case, kind) -> np.ndarray:
    """(M, H, W) bool: each geometry's registered pixels that come from measured camera pixels."""
    masks = [getattr(o.images[(case, kind)], "measured", None) for o in obs]
    return np.stack(
        [np.ones(o.truth_s0.shape, bool) if m is None else m for o, m in zip(obs, masks)]
    )


def _psf_errors(obs, case):
    """How far each geometry's PSF estimate is from the PSF the data were blurred with.

    L1 after the best integer shift (:func:`~scatterlab.deconvolution.psf_distance`; 0 = the true PSF,
    2 = disjoint), the first frame's estimate when there are several; beside it the diffraction-limited
    PSF's distance, the baseline of an estimate that knows nothing of the turbulence.
    """
    from scatterlab.deconvolution import psf_distance

    d, base = [], []
    for o in obs:
        h = np.asarray(o.restorations[(case, "corrected")].psf)
        truth = o.acquisitions[case].psf_true
        d.append(psf_distance(h[0] if h.ndim == 3 else h, truth)[0])
        # what knowing nothing of the turbulence gives: the diffraction-limited PSF
        base.append(psf_distance(o.acquisitions["no_turbulence"].psf_true, truth)[0])
    return {
        "psf_l1_error": float(np.mean(d)),
        "psf_l1_error_per_geometry": d,
        "psf_l1_diffraction_limited": float(np.mean(base)),
    }


def reference_classes(observation, priors) -> np.ndarray:
    """The classification the others are scored against: the restored no-turbulence image's own classes
    (the same classifier as every other image's), or its DOLP thresholds when it has none.

    Parameters
    ----------
    observation : Observation
        One geometry's registered images.
    priors : tuple of SuperGaussianPrior
        The DOLP priors.

    Returns
    -------
    ndarray of int, shape (H, W)
    """
    from scatterlab.deconvolution import classify_dolp

    im = observation.images[("no_turbulence", "restored")]
    if im.classes is not None:
        return np.asarray(im.classes)
    return classify_dolp(np.nan_to_num(im.dolp), priors)


def _classification(result, case, kind, mid, sel, priors):
    from scatterlab.deconvolution import classification_errors

    o = result.observations[mid]
    ref = reference_classes(o, priors)
    cls = ref if (case, kind) == ("no_turbulence", "restored") else o.images[(case, kind)].classes
    metal = tuple(range(1, len(priors)))
    # a pixel either image did not measure (beyond the camera's field after registration, class -1 where
    # the camera's pixel was bad) is not scored
    own = sel & _classified(o.images[(case, kind)], cls)
    scored = own & _classified(o.images[("no_turbulence", "restored")], ref)
    return {
        "classification_vs_no_turbulence": classification_errors(
            cls, ref, metal_classes=metal, mask=scored
        ),
        "classification_vs_labels": classification_errors(
            cls,
            (result.labels > 0).astype(int),
            metal_classes=(1,),
            mask=own,
        ),
    }


def _classified(image, classes):
    """Bool (H, W): the pixels ``image`` measured and gave a class (``classes`` >= 0)."""
    m = getattr(image, "measured", None)
    return (classes >= 0) & (True if m is None else m)


def _prior_bounds(plate) -> dict | None:
    """The plate's prior ranges per region, or None when it keeps the inversion's defaults."""
    given = any(
        getattr(plate, f"{r}_{q}_prior") is not None
        for r in ("metal", "paint")
        for q in ("n", "kappa")
    )
    return {r: plate.prior_bounds(r) for r in ("metal", "paint")} if given else None


def at_fit_bound(n, k) -> np.ndarray:
    """Which fitted pixels have n or kappa on a bound of the per-pixel fit's box (n 0-5, kappa 0-25): the
    bound, not an estimate (the pixel's DOLP lies beyond what the box's materials give).

    Parameters
    ----------
    n, k : ndarray, shape (...)
        Fitted n and kappa (NaN where not fitted).

    Returns
    -------
    ndarray of bool, shape (...)
        True where a fitted value sits on a bound (False where not fitted).
    """
    from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

    n, k = np.asarray(n, float), np.asarray(k, float)
    on = np.zeros(np.broadcast(n, k).shape, bool)
    for v, name in ((n, "n"), (k, "kappa")):
        lo, hi = DEFAULT_BOUNDS[name]
        on |= np.isclose(v, lo, rtol=0, atol=1e-6) | np.isclose(v, hi, rtol=0, atol=1e-6)
    return on & np.isfinite(n) & np.isfinite(k)


def _at_bound(n, k) -> float:
    """Share of fitted pixels whose n or kappa sits on a bound of the fit (the bound, not an estimate)."""
    fitted = np.isfinite(n) & np.isfinite(k)
    if not fitted.any():
        return 0.0
    return float(at_fit_bound(n, k)[fitted].mean())


def pixel_scatter(stack, mask) -> float:
    """A region's per-pixel DOLP error: the robust spread (1.4826 x the median absolute deviation from its
    median) of its pixels' DOLP at each geometry, RMS over the geometries.

    The pixels of a region are one material seen at one geometry, so their spread is what a per-pixel fit
    meets beyond the region's common bias: the pixel noise and the restoration's spatial errors.

    Parameters
    ----------
    stack : ndarray, shape (M, H, W)
        Registered DOLP per geometry (NaN where undefined).
    mask : ndarray of bool, shape (H, W)
        The region's pixels.

    Returns
    -------
    float
        DOLP standard deviation (NaN when no geometry has a defined pixel).
    """
    spreads = []
    for d in np.asarray(stack, float):
        v = d[mask]
        v = v[np.isfinite(v)]
        if v.size:
            spreads.append(1.4826 * np.median(np.abs(v - np.median(v))))
    return float(np.sqrt(np.mean(np.square(spreads)))) if spreads else float("nan")


def _pixel_bounds(truth, thetas, sigma, scatter) -> tuple:
    """Cramer-Rao bounds (n, kappa) of one pixel of the true material at the region's pixel scatter: how
    well any unbiased estimator could place a single pixel (inf where the design cannot)."""
    from scatterlab.inversion.design import crlb

    if not np.isfinite(scatter) or scatter <= 0:
        return float("nan"), float("nan")
    n, k = truth
    b = crlb(max(n, 1e-3), k, sigma, thetas, thetas, max(scatter, 1e-12), sigma_known=True)
    return float(b[0]), float(b[1])


def _pixel_stats(maps, masks, truths, stack=None, thetas=None, sigma=None):
    out = {}
    for region, (tn, tk) in truths.items():
        m = masks[region]
        n, k = maps.n[m], maps.kappa[m]
        out[region] = {
            "share_at_fit_bound": _at_bound(n, k),
            "n_mean": float(np.nanmean(n)),
            "n_std": float(np.nanstd(n)),
            "kappa_mean": float(np.nanmean(k)),
            "kappa_std": float(np.nanstd(k)),
            "n_truth": tn,
            "kappa_truth": tk,
            "n_median_abs_error": float(np.nanmedian(np.abs(n - tn))),
            "kappa_median_abs_error": float(np.nanmedian(np.abs(k - tk))),
            "index_median_abs_error": float(np.nanmedian(np.hypot(n - tn, k - tk))),
        }
        if stack is not None:
            scatter = pixel_scatter(stack, m)
            bn, bk = _pixel_bounds((tn, tk), thetas, sigma, scatter)
            out[region].update(pixel_dolp_scatter=scatter, pixel_crlb_n=bn, pixel_crlb_kappa=bk)
    return out


def _self_calibrated(
    result, case, kind, regions, thetas, cfg, rng, sel, margin, executor, reference=None
):
    """Regions with the re-simulated restoration bias subtracted (:mod:`self_calibration`); a turbulent
    image's bootstrap re-simulates the ``reference`` plate (the no-turbulence image's) when given."""
    from scatterlab.characterization.self_calibration import bias_corrected, restoration_bias
    from scatterlab.deconvolution import PRIOR_SETS, classify_dolp, resample_psf

    obs = result.observations
    mid = int(np.argmin(np.abs(np.degrees(thetas) - 50)))
    ref = np.nan_to_num(obs[mid].images[("no_turbulence", "restored")].dolp)
    layout = classify_dolp(ref, PRIOR_SETS["ch7"])  # metal vs dielectric, from the data
    shape = result.labels.shape
    psfs = [
        None if case == "no_turbulence" else resample_psf(o.restorations[(case, kind)].psf, shape)
        for o in obs
    ]
    from scatterlab.characterization.pipeline import cases_of

    d_over_r0 = dict(cases_of(cfg))[case]
    bias = restoration_bias(
        regions,
        layout,
        thetas,
        psfs,
        cfg,
        rng,
        sel,
        margin,
        blind=d_over_r0 is not None,
        d_over_r0=d_over_r0,
        replicates=cfg.calibration_replicates,
        plate=None if d_over_r0 is None else reference,
        executor=executor,
    )
    return [bias_corrected(r, bias[r.name]) for r in regions]


def score_plate(result, cfg, rng, *, executor=None, priors=None) -> None:
    """Fill ``result.estimates`` and ``result.metrics`` for every image key (module docstring).

    Parameters
    ----------
    result : PlateResult
        Observations of one plate; its ``estimates`` and ``metrics`` are filled in place.
    cfg : SceneConfig
    rng : numpy.random.Generator
        Self-calibration and posterior sampling.
    executor : optional
        Parallel re-simulations and posteriors.
    priors : tuple of SuperGaussianPrior, optional
        DOLP priors (classification scores).

    Returns
    -------
    None
    """
    from scatterlab.characterization.pipeline import image_kinds, interior
    from scatterlab.characterization.self_calibration import estimated_plate

    obs, labels, plate = result.observations, result.labels, result.plate
    thetas = np.array([o.theta for o in obs])
    shape = labels.shape
    sel = interior(shape, max(2, shape[0] // 16))
    mid = int(np.argmin(np.abs(np.degrees(thetas) - 50)))
    margin = (
        cfg.region_margin_px if cfg.region_margin_px is not None else default_margin(thetas.max())
    )
    masks = region_masks(labels, sel, margin)
    truths = {
        "paint": (plate.paint_n, plate.paint_kappa),
        "metal": (plate.metal_n, plate.metal_kappa),
    }
    reference = None  # the plate the no-turbulence image shows (first in image_kinds)
    for key, case, kind in image_kinds(cfg):
        cs = _image_errors(obs, case, kind, sel, away=masks["paint"] | masks["metal"])
        if kind == "corrected":
            cs.update(_psf_errors(obs, case))
        if priors:
            cs.update(_classification(result, case, kind, mid, sel, priors))
        est = {}
        if "n_kappa" in cfg.estimate:
            stack = _stack(obs, case, kind, "dolp")
            est["maps"] = pixel_maps(stack, thetas, cfg.sigma_known)
            # the pixels measured at every geometry (none brought in from beyond the field)
            everywhere = _measured(obs, case, kind).all(axis=0)
            scored = {r: m & everywhere for r, m in masks.items()}
            stats_of = _pixel_stats(est["maps"], scored, truths, stack, thetas, cfg.sigma_known)
            for region, stats in stats_of.items():
                cs[plate.metal if region == "metal" else region] = stats
        if "posterior" in cfg.estimate and kind != "degraded":
            stack = _stack(obs, case, kind, "dolp")
            regions = [
                region_data(r, stack, labels, sel, margin, thetas, truths[r])
                for r in ("paint", "metal")
            ]
            regions = _self_calibrated(
                result, case, kind, regions, thetas, cfg, rng, sel, margin, executor, reference
            )
            if case == "no_turbulence":
                # the turbulent images' bootstraps re-simulate this plate: their own DOLP, diluted by
                # the metal's halo, would give a brighter paint that a re-simulation dilutes less
                reference = estimated_plate(regions, thetas, cfg.sigma_known)
            est["regions"] = region_posteriors(
                regions,
                thetas,
                cfg.sigma_known,
                rng,
                n_steps=cfg.posterior_steps,
                executor=executor,
                model_error=cfg.model_error,
                bounds=_prior_bounds(plate),
            )
            for r in est["regions"]:
                name = plate.metal if r.name == "metal" else r.name
                cs[f"posterior_{name}"] = dict(
                    r.parameters,
                    converged=r.converged,
                    warnings=r.warnings,
                    dolp_mean=r.data.mean.tolist(),
                    dolp_error=r.data.error.tolist(),
                    dolp_bias_corrected=r.data.bias.tolist(),
                    dolp_bias_spread=r.data.bias_spread.tolist(),
                )
                if r.joint is not None:
                    cs[f"posterior_{name}"]["joint"] = r.joint
                if r.goodness_of_fit is not None:
                    cs[f"posterior_{name}"]["goodness_of_fit"] = r.goodness_of_fit
        result.estimates[key] = est
        result.metrics[key] = cs
