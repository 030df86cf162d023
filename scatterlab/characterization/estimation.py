r"""Inversion stage: n and kappa per pixel and per region from the registered DOLP over the geometries.

Per pixel, :func:`scatterlab.inversion.fit_dolp` (sigma known, as in the reference text) gives maps of n and
kappa with their Laplace errors (Table 5, Figs. 59-61).

Per region (paint, bare metal) the posterior of (n, kappa) is sampled from the region's mean DOLP at each
geometry. The region is the label map eroded by ``margin`` object pixels, so that pixels where the two
materials mix through the PSF (edge mixing) stay out. Each geometry's region mean carries an error estimate
built from what the data themselves show:

* statistical: the pixel scatter over :math:`\sqrt{N_{eff}}`, with :math:`N_{eff}` the number of
  resolution elements in the region (pixels are correlated over a PSF width, about
  :math:`(2/\cos\theta)` object pixels along the plane of incidence and 2 across, at 2 pixels per
  :math:`\lambda/D`);
* edge sensitivity: the change of the region mean when the margin is doubled, a direct measure of the halo
  and edge mixing that remain after restoration;

added in quadrature; on top of these a common DOLP noise is inferred from the scatter of the region means
about the model (log-uniform prior), which absorbs what neither estimate sees (deconvolution artefacts, model
error). The error budget (``studies/characterization_error_budget.py``) and the calibration study
(``studies/characterization_coverage.py``) measure how well these intervals cover the truth.
"""

from __future__ import annotations

import inspect
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

__all__ = [
    "RegionData",
    "RegionEstimate",
    "PixelMaps",
    "region_masks",
    "region_data",
    "pixel_maps",
    "region_posteriors",
    "default_margin",
]

PARAMS = ("n", "kappa")
PIXEL_DOLP_MARGIN = 0.05  # per-pixel DOLP beyond [-0.05, 1.05] is treated as undefined
# a self-calibration correction this large (DOLP) is flagged beside the posterior: on the coverage scene the
# bootstrap with an estimated plate recovered a third to a half of such losses (with the true plate, all)
LARGE_CORRECTION = 0.1
NOISE_FLOOR = 1e-4  # DOLP noise below which a region posterior never goes (fixed, or the inferred one's bound)
# posterior contraction (1 - var_post / var_prior) below which a parameter is reported as weakly determined:
# on the coverage scene the paints' are above 0.999, the metals' n 0.4-0.8 (their DOLP at 30-60 deg fixes
# about Re(1/eta), not n and kappa apart)
DETERMINED_CONTRACTION = 0.9


@dataclass
class RegionData:
    r"""Region-mean DOLP over the geometries and its error estimate.

    Attributes
    ----------
    name : str
    mean : ndarray, shape (M,)
        Region-mean DOLP per geometry.
    error : ndarray, shape (M,)
        Its standard error: statistical and edge sensitivity in quadrature.
    statistical, edge : ndarray, shape (M,)
        The two parts.
    pixels : int
        Pixels in the (eroded) region.
    truth : tuple of float or None
        (n, kappa) of the material when known (simulation).
    bias : ndarray, shape (M,), or None
        Re-simulated restoration bias already subtracted from ``mean``
        (:mod:`~scatterlab.characterization.self_calibration`).
    bias_spread : ndarray, shape (M,), or None
        Bootstrap spread of that bias (one replicate's standard deviation; 0 when deterministic).
    edge_shift : ndarray, shape (M,), or None
        Signed edge sensitivity: the mean of the doubly eroded region minus ``mean`` (``edge`` is its
        magnitude).
    calibrated : bool
        ``error`` was measured in full by noisy re-simulations (known-PSF self-calibration): the
        posterior then infers no further noise.
    correlated : ndarray, shape (M,), or None
        The part of ``error`` that is one error of the whole geometry series (signed, [DOLP]): a
        fraction of the subtracted bias, which the scene mismatch scales as a whole (for a paint's ratio
        correction on a reference plate, with the part of its :attr:`trend` that goes with it, so that it
        grows toward the small angles). The posterior of
        a calibrated region uses the covariance
        :math:`\mathrm{diag}(e^2 - c^2) + c\,c^\mathsf{T}`; any other region the same with an
        inferred noise added to the diagonal.
    trend : ndarray, shape (M,), or None
        A second error of the whole series, one that changes sign across it (signed, [DOLP]; also part of
        ``error``): a fraction of a ratio correction times each geometry's place in the series
        (:func:`~scatterlab.characterization.self_calibration.series_position`), for the restoration's
        dilution of a paint mis-estimated more at one end of the angles than at the other (the part of it
        independent of :attr:`correlated`). A calibrated
        region's covariance is then :math:`\mathrm{diag}(e^2 - c^2 - t^2) + c\,c^\mathsf{T} +
        t\,t^\mathsf{T}`.
    """

    name: str
    mean: np.ndarray
    error: np.ndarray
    statistical: np.ndarray
    edge: np.ndarray
    pixels: int
    truth: tuple | None = None
    bias: np.ndarray | None = None
    bias_spread: np.ndarray | None = None
    edge_shift: np.ndarray | None = None
    calibrated: bool = False
    correlated: np.ndarray | None = None
    trend: np.ndarray | None = None


@dataclass
class RegionEstimate:
    """Posterior summary of one region.

    Attributes
    ----------
    name : str
    parameters : dict
        Per parameter (``n``, ``kappa``, ``noise``): ``{"median", "ci68": [lo, hi], "ci95": [lo, hi]}``, plus
        ``"truth"``, ``"covers68"``, ``"covers95"`` when the truth is known.
    converged : bool
    warnings : list of str
        Convergence and identifiability warnings, shown beside the numbers in the report.
    chain : ndarray, shape (S, 3)
        Posterior samples of (n, kappa, sigma).
    data : RegionData
    joint : dict or None
        When the truth is known: ``{"delta_chi2", "threshold68", "covers68", "threshold95",
        "covers95"}``, the truth's likelihood-ratio statistic, the thresholds of the joint (n, kappa)
        confidence regions and whether it lies in them
        (:meth:`scatterlab.inversion.Posterior.likelihood_ratio`).
    goodness_of_fit : dict or None
        ``{"chi2", "dof", "p_value"}`` of the best fit under the region's error model
        (:meth:`scatterlab.inversion.Posterior.goodness_of_fit`); None with an inferred noise.
    """

    name: str
    parameters: dict
    converged: bool
    warnings: list = field(default_factory=list)
    chain: np.ndarray | None = None
    data: RegionData | None = None
    joint: dict | None = None
    goodness_of_fit: dict | None = None


@dataclass
class PixelMaps:
    """Per-pixel least-squares n and kappa (maps (H, W)) with their Laplace standard errors (H, W, 2)."""

    n: np.ndarray
    kappa: np.ndarray
    errors: np.ndarray


def default_margin(theta_max: float) -> int:
    """Erosion of the region masks [object pixels]: one lambda/D (2 pixels) stretched by 1/cos(theta_max).

    Parameters
    ----------
    theta_max : float
        Largest specular angle of the scene [rad].

    Returns
    -------
    int
        Erosion [object pixels].
    """
    return int(np.ceil(2.0 / np.cos(theta_max)))


def region_masks(labels, interior, margin: int) -> dict:
    """Paint (label 0) and bare-metal (label 1) masks eroded by ``margin`` pixels, within ``interior``.

    Parameters
    ----------
    labels : ndarray of int, shape (H, W)
        Object-coordinate label map.
    interior : ndarray of bool, shape (H, W)
        Pixels scored.
    margin : int
        Erosion [pixels].

    Returns
    -------
    dict
        ``{"paint": mask, "metal": mask}``, boolean arrays (H, W).
    """
    labels = np.asarray(labels)
    out = {}
    for name, lab in (("paint", 0), ("metal", 1)):
        m = labels == lab
        if margin > 0:
            m = ndimage.binary_erosion(m, iterations=margin, border_value=1)
        out[name] = m & interior
    return out


def region_data(name, stack, labels, interior, margin, thetas, truth=None) -> RegionData:
    """Region means and their error estimate (module docstring) for a DOLP stack ``(M, H, W)``.

    Parameters
    ----------
    name : str
        ``"paint"`` or ``"metal"``.
    stack : ndarray, shape (M, H, W)
        Registered DOLP per geometry (NaN where undefined).
    labels : ndarray of int, shape (H, W)
        Layout (0 dielectric, 1 metal).
    interior : ndarray of bool, shape (H, W)
        Pixels scored.
    margin : int
        Erosion of the region [pixels].
    thetas : ndarray, shape (M,)
        Specular angles [rad].
    truth : tuple of float, optional
        (n, kappa) of the material when known.

    Returns
    -------
    RegionData
    """
    lab = {"paint": 0, "metal": 1}[name]
    masks = {}
    for k in (margin, 2 * margin):
        m = np.asarray(labels) == lab
        if k > 0:
            m = ndimage.binary_erosion(m, iterations=k, border_value=1)
        masks[k] = m & interior
    sel = masks[margin]
    if sel.sum() < 4:
        raise ValueError(
            f"the {name} region has {int(sel.sum())} pixels after an erosion of {margin} pixels: "
            "too few for a region estimate (a larger image_size or a smaller margin)"
        )
    vals = stack[:, sel]
    mean = np.nanmean(vals, axis=1)
    cells = 4.0 / np.cos(np.asarray(thetas))  # pixels per resolution element (object coordinates)
    n_eff = np.maximum(np.sum(np.isfinite(vals), axis=1) / cells, 1.0)
    stat = np.nanstd(vals, axis=1) / np.sqrt(n_eff)
    inner = masks[2 * margin]
    shift = np.nanmean(stack[:, inner], axis=1) - mean if inner.sum() >= 4 else None
    edge = np.abs(shift) if shift is not None else np.abs(stat)
    return RegionData(
        name, mean, np.hypot(stat, edge), stat, edge, int(sel.sum()), truth, edge_shift=shift
    )


def pixel_maps(stack, thetas, sigma) -> PixelMaps:
    """Per-pixel n and kappa from a DOLP stack at specular geometries.

    Parameters
    ----------
    stack : ndarray, shape (M, H, W)
        Registered DOLP per geometry (NaN where undefined; values beyond ``[-0.05, 1.05]`` are treated as
        undefined).
    thetas : ndarray, shape (M,)
        Specular angles [rad].
    sigma : float
        Known roughness.

    Returns
    -------
    PixelMaps
    """
    # a DOLP far outside [0, 1] is a dark pixel's noise, not a measurement: undefined (NaN), as the
    # convention for zero light says; fit_dolp masks NaN entries
    from scatterlab.inversion import IdentifiabilityWarning, fit_dolp

    y = np.where((stack >= -PIXEL_DOLP_MARGIN) & (stack <= 1 + PIXEL_DOLP_MARGIN), stack, np.nan)
    with warnings.catch_warnings():
        # paint pixels fitted at kappa = 0 do not determine kappa: their error is inf in the maps already
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        fit = fit_dolp(np.moveaxis(y, 0, -1), thetas, thetas, sigma=sigma)
    return PixelMaps(fit.n, fit.kappa, fit.errors)


def contraction_text(c: float) -> str:
    """A posterior contraction as the report prints it: two decimals, or ``"none"`` below 0.005.

    A chain spread as wide as the prior has an estimated contraction scattered around 0, sometimes
    slightly negative (-0.02); printed as a number, that reads as a defect of the sampler.

    Parameters
    ----------
    c : float
        ``1 - var_post / var_prior`` (:meth:`scatterlab.inversion.Posterior.contraction`).

    Returns
    -------
    str
    """
    return f"{c:.2f}" if c >= 0.005 else "none"


def _summarise(name, post, data: RegionData) -> RegionEstimate:
    s = post.summary()
    params = {}
    for p in ("n", "kappa", "noise"):
        if p not in s["parameters"]:
            continue
        d = s["parameters"][p]
        entry = {"median": float(d["median"]), "ci68": [float(x) for x in d["ci68"]]}
        if "ci95" in d:
            entry["ci95"] = [float(x) for x in d["ci95"]]
        if data.truth is not None and p in PARAMS:
            t = float(data.truth[PARAMS.index(p)])
            entry.update(
                truth=t,
                covers68=bool(entry["ci68"][0] <= t <= entry["ci68"][1]),
                covers95=bool(entry["ci95"][0] <= t <= entry["ci95"][1]),
            )
        params[p] = entry
    contraction = dict(zip(("n", "kappa"), post.contraction()[:2].tolist()))
    for p, c in contraction.items():
        params[p]["contraction"] = float(c)
    joint = None
    if data.truth is not None and post.sigma_known is not None:
        delta = float(post.likelihood_ratio(np.asarray(data.truth[:2], float)))
        limits = {lv: post.region_threshold(lv / 100) for lv in (68, 95)}
        joint = {"delta_chi2": delta} | {
            key: value
            for lv, t in limits.items()
            for key, value in ((f"threshold{lv}", t), (f"covers{lv}", bool(delta <= t)))
        }
    notes = []
    weak = [p for p, c in contraction.items() if c < DETERMINED_CONTRACTION]
    if weak:
        notes.append(
            f"the data determine {' and '.join(weak)} only partly (posterior contraction "
            + ", ".join(contraction_text(contraction[p]) for p in weak)
            + f", below {DETERMINED_CONTRACTION:g}; 1 = fixed by the data, 0 = the prior's spread, none = "
            "below 0.005): the marginal interval follows the prior along a ridge of equal DOLP, and for a "
            "fixed material it does not cover at its nominal rate. The joint (n, kappa) likelihood-ratio "
            "region is the calibrated statement"
            + (
                ""
                if joint is None
                else f" (truth inside at 68 % / 95 %: {'yes' if joint['covers68'] else 'no'} / "
                f"{'yes' if joint['covers95'] else 'no'})"
            )
        )
    if joint is not None and np.isfinite(joint["delta_chi2"]) and not joint["covers95"]:
        notes.append(
            f"**the truth lies outside even the joint 95 % region** (Delta chi^2 "
            f"{joint['delta_chi2']:.1f}, threshold {joint['threshold95']:.1f}). A correct region misses "
            "it 1 time in 20; a miss far beyond the threshold says this region's DOLP is off by more "
            "than the error it carries (a restoration or classification error the self-calibration did "
            "not measure)"
        )
    from scatterlab.inversion.posterior import FIT_P_MIN

    fit = s.get("goodness_of_fit")
    if fit is not None and fit["p_value"] < FIT_P_MIN:
        notes.append(
            f"**this region's DOLP does not fit the model within the errors it carries** (chi-square "
            f"{fit['chi2']:.1f} for {fit['dof']} degrees of freedom, p = {fit['p_value']:.1e}): an error "
            "the error model lacks, so the interval is too narrow"
        )
    diag = s.get("diagnostics", {})
    converged = bool(diag.get("converged", True))
    if not converged:
        notes.append(
            "the chain did not converge (too short for its autocorrelation time): "
            "the interval is a rough guide only"
        )
    if diag.get("multimodal"):
        notes.append("the posterior has several modes: the median lies between them")
    if data.bias is not None and np.nanmax(np.abs(data.bias)) > LARGE_CORRECTION:
        moved = (
            f"the self-calibration moved this region's DOLP by up to "
            f"{np.nanmax(np.abs(data.bias)):.2f}: the restoration lost much of its polarization"
        )
        if data.calibrated:
            notes.append(
                moved
                + "; the error is the re-simulations' spread plus a part of the correction shared "
                "by all geometries, calibrated on simulated scenes (studies/characterization_coverage.py)"
            )
        else:
            notes.append(
                moved
                + ", and a re-simulation of a plate estimated from these data recovers only part "
                "of such a loss (studies/characterization_coverage.py), so the interval may be too narrow"
            )
    if data.bias is not None:
        held = int(np.sum((data.mean <= 0.0) | (data.mean >= 1.0)))
        if held:
            notes.append(
                f"the corrected DOLP left [0, 1] at {held} of {data.mean.size} geometries and is held at "
                "the bound there (its error still carries the correction)"
            )
    return RegionEstimate(name, params, converged, notes, post.chain, data, joint, fit)


def _covariance(region: RegionData, error) -> np.ndarray:
    """Error covariance (M, M) of a calibrated region's means [DOLP^2] whose total error per geometry is
    ``error`` (M,): independent per geometry, plus its :attr:`RegionData.correlated` and
    :attr:`RegionData.trend` parts shared by the whole series, plus the noise floor."""
    error = np.asarray(error, float)
    c = np.zeros_like(error) if region.correlated is None else np.asarray(region.correlated)
    t = np.zeros_like(error) if region.trend is None else np.asarray(region.trend, float)
    independent = np.maximum(error**2 - c**2 - t**2, 0.0) + NOISE_FLOOR**2
    return np.diag(independent) + np.outer(c, c) + np.outer(t, t)


def _common(region: RegionData) -> np.ndarray:
    """The error (M,) that ``region``'s whole geometry series shares [DOLP] (zeros when none)."""
    if region.correlated is None:
        return np.zeros_like(region.mean, dtype=float)
    return np.abs(np.asarray(region.correlated, float))


def _noise_model(errors, m, sampler):
    """(noise, keywords) of ``sampler`` (:func:`~scatterlab.inversion.sample_posteriors`) for regions with
    per-geometry errors ``errors`` (K, M) that leave a noise level to infer."""
    if m < 3:  # (n, kappa) from two geometries: no data left to infer a noise level
        return max(float(errors.max()), NOISE_FLOOR), {}
    if "systematic" in inspect.signature(sampler).parameters:
        return None, {"systematic": errors, "noise_bounds": (NOISE_FLOOR, 0.5)}
    return None, {
        "noise_bounds": (max(float(errors.max()), NOISE_FLOOR), 0.5)
    }  # the error as a floor


EXTEND = (
    4  # a chain that did not converge in n_steps is run again for up to this many times n_steps
)


def region_posteriors(
    regions, thetas, sigma, rng, *, n_steps=None, executor=None, model_error=False, bounds=None
) -> list:
    """Sample the posterior of (n, kappa) for each :class:`RegionData` (one emcee problem per region).

    Parameters
    ----------
    regions : list of RegionData
    thetas : ndarray, shape (M,)
        Specular geometries [rad].
    sigma : float
        Known roughness.
    rng : numpy.random.Generator
    n_steps : int, optional
        Chain length (None: until converged, up to the sampler's ``max_steps``). A region whose
        chain of this length has not converged is sampled again until it converges, up to
        :data:`EXTEND` times as long; one that still has not is flagged in its warnings.
    executor : optional
        Runs the regions in parallel.
    model_error : bool
        Add the pBRDF's DOLP model error measured against exact (MoM) solutions
        (:func:`scatterlab.inversion.dolp_model_error` at the known ``sigma``, for the region's class
        from the classification: "metal" for the region named ``metal``, "dielectric" otherwise) to
        each geometry's error. Right for measured data; a simulation rendered with the pBRDF itself
        has none. On held-out exact solutions this form covered the truth at 69 % / 98 % (68 % / 95 %
        intervals; study ``dolp_vs_mom``).
    bounds : dict, optional
        ``{region name: {"n": (low, high), "kappa": (low, high)}}``: the uniform prior ranges of a region's
        posterior (:meth:`scatterlab.characterization.Plate.prior_bounds`); a region not named keeps the
        inversion's defaults.

    Returns
    -------
    list of RegionEstimate
    """
    from scatterlab.inversion import ConvergenceWarning, sample_posteriors

    thetas = np.asarray(thetas, float)
    means = np.stack([r.mean for r in regions])
    errors = np.stack([r.error for r in regions])
    if model_error:
        from scatterlab.inversion import dolp_model_error

        classes = ["metal" if r.name == "metal" else "dielectric" for r in regions]
        model = [dolp_model_error(thetas, thetas, sigma, material_class=c) for c in classes]
        errors = np.hypot(errors, np.stack(model))
    kw = dict(sigma=sigma, n_steps=n_steps, executor=executor)
    # a region whose error the re-simulations measured in full gets no inferred noise: with M - 2 degrees
    # of freedom it only widened intervals that were already calibrated (no-turbulence paint of the
    # coverage scene: 68 % intervals of kappa covering 92 % of the truths with it, 79 % without)
    calibrated = np.array([r.calibrated for r in regions]) & (thetas.size >= 3)
    posts = [None] * len(regions)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        for fixed in (False, True):
            idx = np.flatnonzero(calibrated == fixed)
            if idx.size == 0:
                continue
            if fixed:
                noise, extra = (
                    None,
                    {"covariance": np.stack([_covariance(regions[k], errors[k]) for k in idx])},
                )
            else:
                common = np.stack([_common(regions[k]) for k in idx])
                independent = np.sqrt(np.maximum(errors[idx] ** 2 - common**2, 0.0))
                noise, extra = _noise_model(independent, thetas.size, sample_posteriors)
                if np.any(common):
                    extra["correlated"] = common
            if bounds:
                extra["bounds"] = [bounds.get(regions[k].name) for k in idx]
            got = sample_posteriors(means[idx], thetas, thetas, noise, rng, **kw, **extra)
            redo = [j for j, p in enumerate(got) if n_steps is not None and not p.converged]
            if redo:  # a fixed length too short for this posterior: run it until it converges
                again = sample_posteriors(
                    means[idx[redo]],
                    thetas,
                    thetas,
                    noise,
                    rng,
                    **(kw | {"n_steps": None, "max_steps": EXTEND * n_steps}),
                    **_regions_of(extra, redo),
                )
                for j, p in zip(redo, again):
                    got[j] = p
            for k, p in zip(idx, got):
                posts[k] = p
    return [_summarise(r.name, p, r) for r, p in zip(regions, posts)]


def _regions_of(extra: dict, positions: list) -> dict:
    """The keywords of :func:`~scatterlab.inversion.sample_posteriors` for the regions at ``positions``
    of a call: per-region arrays (leading axis: the regions) and lists cut, the rest shared."""
    out = {}
    for key, value in extra.items():
        if key == "bounds":
            out[key] = [value[j] for j in positions]
        elif isinstance(value, np.ndarray) and value.ndim >= 2:
            out[key] = value[positions]
        else:
            out[key] = value
    return out
