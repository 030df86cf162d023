"""Scoring a material classification against a reference label map (Table 4's columns)."""

from __future__ import annotations

import numpy as np

__all__ = ["classification_errors", "classify_dolp"]


def classification_errors(estimate, truth, *, metal_classes=(1,), mask=None) -> dict:
    """Fractions of pixels wrongly called metal / dielectric / either, the correlation coefficient and RMSE
    between the two maps (Table 4), for integer label maps where ``metal_classes`` are the metal labels."""
    e = np.isin(np.asarray(estimate), metal_classes)
    t = np.isin(np.asarray(truth), metal_classes)
    if e.shape != t.shape:
        raise ValueError(f"estimate {e.shape} and truth {t.shape} must have the same shape")
    sel = np.ones(e.shape, bool) if mask is None else np.asarray(mask, bool)
    e, t = e[sel], t[sel]
    n = e.size
    ef, tf = e.astype(float), t.astype(float)
    corr = float(np.corrcoef(ef, tf)[0, 1]) if ef.std() > 0 and tf.std() > 0 else float("nan")
    return {"false_metal": float(np.sum(e & ~t) / n), "false_dielectric": float(np.sum(~e & t) / n),
            "total_error": float(np.sum(e != t) / n), "correlation": corr,
            "rmse": float(np.sqrt(np.mean((ef - tf) ** 2)))}


def classify_dolp(dolp, priors) -> np.ndarray:
    """Label each pixel with the prior of largest density at its DOLP (argmax_k ln Pi_k(P)): the DOLP
    thresholding of the no-turbulence and degraded images in Ch. V, whose thresholds are the DOLPs of equal
    prior probability (0.30 for the Ch. V priors). ``dolp`` any shape; returns int labels (index into priors)."""
    P = np.asarray(dolp, float)
    if not priors:
        raise ValueError("priors must list at least one SuperGaussianPrior")
    with np.errstate(over="ignore"):
        logs = np.stack([np.nan_to_num(pr.log_pdf(P), nan=-np.inf, neginf=-np.inf) for pr in priors])
    return np.argmax(logs, axis=0)
