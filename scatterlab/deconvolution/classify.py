"""Material classification of polarimetric images and its scoring against a reference (Table 4's columns).

* :func:`classify_dolp` -- the DOLP thresholds of Ch. V: each pixel to the prior of largest density;
* :func:`classify_unmixing` -- a classification refined by linear unmixing of the Stokes images, which
  places the edges of a blurred image where they are;
* :func:`classification_errors` -- Table 4's error columns.
"""

from __future__ import annotations

import numpy as np

from scatterlab.deconvolution.priors import _prior_set

__all__ = ["classification_errors", "classify_dolp", "classify_unmixing"]


def classification_errors(estimate, truth, *, metal_classes=(1,), mask=None) -> dict:
    """Classification errors of a label map against a reference map (Table 4).

    Parameters
    ----------
    estimate, truth : array_like of int, shape (H, W)
        Label maps; ``metal_classes`` are the metal labels, all others dielectric.
    metal_classes : tuple of int
    mask : bool array (H, W), optional
        Pixels to score.

    Returns
    -------
    dict
        ``false_metal`` and ``false_dielectric`` (fractions of all pixels), ``false_metal_rate`` (per true
        dielectric pixel) and ``false_dielectric_rate`` (per true metal pixel) -- Table 4's columns --,
        ``metal_share``, ``total_error`` (fraction of all pixels), ``correlation`` and ``rmse`` of the binary
        maps, and ``pixels`` (the number scored).
    """
    e = np.isin(np.asarray(estimate), metal_classes)
    t = np.isin(np.asarray(truth), metal_classes)
    if e.shape != t.shape:
        raise ValueError(f"estimate {e.shape} and truth {t.shape} must have the same shape")
    sel = np.ones(e.shape, bool) if mask is None else np.asarray(mask, bool)
    if sel.shape != e.shape or not sel.any():
        raise ValueError(
            f"mask must be a boolean array of shape {e.shape} selecting at least one pixel, got "
            f"shape {sel.shape} with {int(sel.sum())} selected"
        )
    e, t = e[sel], t[sel]
    n = e.size
    ef, tf = e.astype(float), t.astype(float)
    corr = float(np.corrcoef(ef, tf)[0, 1]) if ef.std() > 0 and tf.std() > 0 else float("nan")
    n_metal, n_diel = int(t.sum()), int((~t).sum())
    return {
        "false_metal": float(np.sum(e & ~t) / n),
        "false_dielectric": float(np.sum(~e & t) / n),
        # Table 4's columns: wrongly metal per true dielectric pixel, wrongly dielectric per true metal
        # pixel (its rows imply these class-size normalisations); the total is over all pixels
        "false_metal_rate": float(np.sum(e & ~t) / n_diel) if n_diel else float("nan"),
        "false_dielectric_rate": float(np.sum(~e & t) / n_metal) if n_metal else float("nan"),
        "metal_share": float(n_metal / n),
        "total_error": float(np.sum(e != t) / n),
        "correlation": corr,
        "rmse": float(np.sqrt(np.mean((ef - tf) ** 2))),
        "pixels": int(n),
    }


def classify_dolp(dolp, priors) -> np.ndarray:
    """Label each pixel with the prior of largest density at its DOLP (argmax_k ln Pi_k(P)): the DOLP
    thresholding of the no-turbulence and degraded images in Ch. V, whose thresholds are the DOLPs of equal
    prior probability (0.30 for the Ch. V priors).

    Parameters
    ----------
    dolp : array_like or numpy masked array, any shape
        Degree of linear polarization per pixel (dimensionless, nominally in [0, 1]). A pixel without light
        has no class: pass it masked, as :func:`scatterlab.imaging.dolp_aop_from_stokes` returns DOLP images
        (masked pixels get class -1 whatever value lies under the mask); the unmasked values, and all the
        values of a plain array, must be finite.
    priors : str or sequence of SuperGaussianPrior
        The DOLP priors (at least one), or the key of a set in ``PRIOR_SETS`` (``"ch5"``, ``"ch6"``, ``"ch7"``).

    Returns
    -------
    ndarray of int, shape of ``dolp``
        Index into ``priors`` of the prior with the largest density at each pixel; -1 where ``dolp`` is
        masked (no class, as in :func:`classify_unmixing`).

    Raises
    ------
    ValueError
        ``priors`` empty, an unknown key or not priors; an unmasked ``dolp`` value NaN or infinite.
    """
    priors = _prior_set(priors, "priors")
    if not priors:
        raise ValueError(
            "priors must list at least one SuperGaussianPrior (or name a set of PRIOR_SETS)"
        )
    masked = np.ma.getmaskarray(dolp) if np.ma.isMaskedArray(dolp) else None
    P = np.asarray(np.ma.getdata(dolp), float)
    if masked is not None:
        P = np.where(masked, 0.0, P)  # any finite value: the label is replaced below
    bad = ~np.isfinite(P)
    if bad.any():  # NaN is a pixel without light: no class, not the first prior's
        raise ValueError(
            f"dolp must be finite: {int(bad.sum())} pixel(s) are NaN or inf (no light, or bad "
            "values). Pass dolp as a numpy masked array with them masked "
            "(numpy.ma.masked_invalid(dolp); imaging.dolp_aop_from_stokes returns one) and they get "
            "class -1, or give them a DOLP with numpy.nan_to_num"
        )
    with np.errstate(over="ignore"):
        logs = np.stack(
            [np.nan_to_num(pr.log_pdf(P), nan=-np.inf, neginf=-np.inf) for pr in priors]
        )
    labels = np.argmax(logs, axis=0)
    if masked is not None:
        labels = np.where(masked, -1, labels)
    return labels


def classify_unmixing(
    s0, dolp, classes, *, purest: float = 0.2, iterations: int = 20
) -> np.ndarray:
    r"""Refine a classification by linear unmixing of the Stokes images: each pixel goes to the material
    whose Stokes vector :math:`(S_0, S_1)` is nearest its own.

    Blur mixes the Stokes images linearly (every channel sees the same PSF), so a pixel near an edge is a
    mixture :math:`a\,\mathbf{s}_m + (1-a)\,\mathbf{s}_d` of the two materials' Stokes vectors, and the
    nearest material is the one with :math:`a > 1/2`: for a PSF with a centre of symmetry the edge stays
    where it is. The DOLP is a ratio, so a DOLP threshold does not: under a metal :math:`r` times brighter
    than the paint, a pixel with DOLP :math:`P_m a r + P_d(1-a)` over :math:`a r + 1 - a` falls below the
    Ch. V threshold of 0.30 once :math:`a` exceeds 0.14 (:math:`r = 12`, :math:`P_d = 0.88`,
    :math:`P_m = 0.01`), and the metal grows into the paint by the width of the blur's tail. On the default
    scene's blind restorations at 50 deg this cut the classification error by half or more (measured 27
    Nov 2026; ``docs/characterization_accuracy.md``).

    Each material's Stokes vector is the median over its purest pixels: the ``purest`` fraction of its
    class whose DOLP lies farthest toward that material's side (lowest for the class of lowest median
    DOLP, highest for the highest, nearest the class median for one in between). Between two materials the
    DOLP is monotone in the mixing fraction, so these are the least mixed pixels even where blur leaves no
    pure interior (thin strokes; eroding the regions instead did worse there). The assignment and the
    medians are repeated until the classes stop changing. It assumes, as the plate scenes do, that each
    material is uniform over the field at one geometry.

    A pixel without light (``s0 <= 0``) has the Stokes vector 0, as near to one material as to another:
    it keeps its class from ``classes`` and takes no part in the materials' Stokes vectors; an image
    without light comes back as ``classes`` (-1 where unmeasured).

    Parameters
    ----------
    s0 : array_like, shape (H, W)
        Irradiance [photo-electrons]; NaN or masked (numpy masked array) where unmeasured; ``<= 0`` is no
        light (the pixel keeps its class).
    dolp : array_like, shape (H, W)
        Signed DOLP :math:`S_1/S_0` (the geometry fixes the angle of polarization); NaN or masked where
        unmeasured.
    classes : array_like of int, shape (H, W)
        The classification to refine (for instance :func:`classify_dolp`'s); -1 (or masked) = unclassified,
        kept.
    purest : float
        Fraction of each class whose median is its material's Stokes vector, in (0, 1].
    iterations : int
        Most rounds of assignment and medians (at least 1).

    Returns
    -------
    ndarray of int, shape (H, W)
        The refined classes (the labels of ``classes``; -1 where ``classes`` is -1 or the pixel unmeasured;
        the class of ``classes`` where there is no light).
    """
    # masked pixels of numpy masked arrays (imaging's DOLP images) are unmeasured, as NaN ones are
    s0 = np.ma.filled(np.ma.asarray(s0, float), np.nan)
    P = np.ma.filled(np.ma.asarray(dolp, float), np.nan)
    lab = np.ma.filled(np.ma.asarray(classes), -1)
    if s0.shape != P.shape or s0.shape != lab.shape or s0.ndim != 2:
        raise ValueError(
            f"s0 {s0.shape}, dolp {P.shape} and classes {lab.shape} must be 2-D images of one shape"
        )
    if not 0 < purest <= 1:
        raise ValueError(f"purest must be in (0, 1], got {purest!r}")
    if int(iterations) != iterations or iterations < 1:
        raise ValueError(f"iterations must be an integer >= 1, got {iterations!r}")
    measured = np.isfinite(s0) & np.isfinite(P) & (lab >= 0)
    lab = np.where(measured, lab, -1).astype(int)
    # no light: a Stokes vector 0, equidistant from every material -- the pixel keeps its class
    lit = measured & (s0 > 0)
    dark = np.where(measured & ~lit, lab, -1)
    lab = np.where(lit, lab, -1)
    X = np.stack([np.where(lit, s0, 0.0), np.where(lit, s0 * P, 0.0)], axis=-1)
    for _ in range(int(iterations)):
        names = np.unique(lab[lab >= 0])
        if len(names) < 2:  # one material: nothing to unmix
            break
        medians = np.array([np.median(P[lab == k]) for k in names])
        lowest, highest = names[np.argmin(medians)], names[np.argmax(medians)]
        ends = []
        for k, med in zip(names, medians):
            v = P[lab == k]
            # how far each pixel's DOLP lies toward this material's side
            toward = -v if k == lowest else v if k == highest else -np.abs(v - med)
            keep = toward >= np.quantile(toward, 1 - purest)
            ends.append(np.median(X[lab == k][keep], axis=0))
        d2 = np.stack([np.sum((X - e) ** 2, axis=-1) for e in ends])
        new = np.where(lit, names[np.argmin(d2, axis=0)], -1)
        if np.array_equal(new, lab):
            break
        lab = new
    return np.where(lit, lab, dark)
