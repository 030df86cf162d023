"""Scoring a material classification against a reference label map (Table 4's columns)."""

from __future__ import annotations

import numpy as np

__all__ = ["classification_errors", "classify_dolp"]


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
        maps.
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
    }


def classify_dolp(dolp, priors) -> np.ndarray:
    """Label each pixel with the prior of largest density at its DOLP (argmax_k ln Pi_k(P)): the DOLP
    thresholding of the no-turbulence and degraded images in Ch. V, whose thresholds are the DOLPs of equal
    prior probability (0.30 for the Ch. V priors).

    Parameters
    ----------
    dolp : array_like, any shape
        Degree of linear polarization per pixel, in [0, 1] (finite: a pixel without light has no class).
    priors : sequence of SuperGaussianPrior
        The DOLP priors (at least one).

    Returns
    -------
    ndarray of int, shape of ``dolp``
        Index into ``priors`` of the prior with the largest density at each pixel.
    """
    P = np.asarray(dolp, float)
    if not priors:
        raise ValueError("priors must list at least one SuperGaussianPrior")
    bad = ~np.isfinite(P)
    if bad.any():  # NaN is a pixel without light: no class, not the first prior's
        raise ValueError(
            f"dolp must be finite: {int(bad.sum())} pixel(s) are NaN or inf (no light); mask them, "
            "or give them a DOLP with numpy.nan_to_num"
        )
    with np.errstate(over="ignore"):
        logs = np.stack(
            [np.nan_to_num(pr.log_pdf(P), nan=-np.inf, neginf=-np.inf) for pr in priors]
        )
    return np.argmax(logs, axis=0)
