"""Makes em_reference.npz: seeded blind_deconvolve runs on a small scene, computed with the code of main
at commit ac7196c (before the EM was split into state / E-step / M-step / PSF update). test_em_reference.py
checks that the split code reproduces these arrays to float rounding.

Run from a checkout of that commit: ``python tests/deconvolution/data/make_em_reference.py OUT.npz``.
The inputs are channel stacks (K, H, W) built here without the imaging module (its Stokes layout changed).
"""

import sys

import numpy as np

from scatterlab.deconvolution import PRIOR_SETS, blind_deconvolve, initial_psf
from scatterlab.imaging import circular_pupil


def gaussian_psf(shape, sd):
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    g = np.exp(-((yy - shape[0] // 2) ** 2 + (xx - shape[1] // 2) ** 2) / (2 * sd * sd))
    return g / g.sum()


def channels(n=24, aop=0.0, seed=0):
    """Poisson channel images (4, n, n) at 0/45/90/135 deg of a two-material object blurred periodically."""
    rng = np.random.default_rng(seed)
    lab = np.zeros((n, n), int)
    lab[5:11, 4:20] = 1
    lab[14:20, 10:15] = 1
    s0 = np.where(lab == 1, 2.0, 1.0)
    P = np.where(lab == 1, 0.05, 0.6)
    th = np.radians([0.0, 45.0, 90.0, 135.0])
    o = 0.5 * s0 * (1 + P * np.cos(2 * (aop - th[:, None, None])))
    h = gaussian_psf((n, n), 1.2)
    blur = np.fft.irfft2(np.fft.rfft2(o) * np.fft.rfft2(np.fft.ifftshift(h)), s=(n, n))
    return rng.poisson(2000 * np.clip(blur, 0, None) / blur.max()).astype(float), th


CASES = {
    "em_shared": dict(iterations=8),
    "em_shared_aop": dict(iterations=8, aop=0.4, boundary="periodic"),
    "em_per_channel": dict(iterations=6, shared_psf=False),
    "estimate_aop": dict(iterations=6, estimate_aop=True, aop_true=0.5),
    "priors": dict(iterations=6, priors=PRIOR_SETS["ch5"], prior_weight=1.0),
    "fixed_text_start": dict(iterations=6, psf_mode="fixed", s0_start=1.0, dolp_start=0.5),
    "pupil": dict(iterations=4, psf_mode="pupil", tol=1e-12, masked=True),
    "saturation": dict(iterations=5, saturation=None),
}


def run(name, kw):
    kw = dict(kw)
    d, th = channels(aop=kw.pop("aop_true", 0.0))
    if kw.pop("masked", False):
        m = np.ones(d.shape[1:], bool)
        m[3:5, 3:5] = False
        kw["mask"] = m
        kw["pupil"] = circular_pupil(8, 3.0)
    if kw.get("psf_mode") == "fixed":
        kw["psf0"] = initial_psf(circular_pupil(8, 3.0), (d.shape[1] + 2 * 6, d.shape[2] + 2 * 6), rng=3)
    if name == "saturation":
        kw["saturation"] = float(np.quantile(d, 0.97))
    r = blind_deconvolve(d, th, **kw)
    return {
        f"{name}/s0": r.s0,
        f"{name}/dolp": r.dolp,
        f"{name}/aop": r.aop,
        f"{name}/psfs": r.psfs,
        f"{name}/loglik": r.loglik,
        f"{name}/objective": r.objective,
        f"{name}/classes": np.array([]) if r.classes is None else r.classes,
        f"{name}/iterations": np.array(r.iterations),
    }


if __name__ == "__main__":
    out = {}
    for name, kw in CASES.items():
        out.update(run(name, kw))
    np.savez_compressed(sys.argv[1], **out)
