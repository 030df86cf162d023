"""Fig. 48: simulated short-exposure MTFs for D/r0 = 7.9, 10.5, 12.9 against Fried's theory, with
D/r0 fitted from each simulated MTF and the fit's RMSE (the text's check of its turbulence simulator).

As in the text, the *short-exposure* (tilt-removed) theoretical MTF (alpha = 1, near field) is fitted
to the measured one: each simulated frame's phase screen has its least-squares tilt over the pupil
removed, and the MTF is the modulus of the frames' mean OTF. The fit is least squares in log MTF down
to the 0.02 floor, and the RMSE of the fit (in MTF, as the caption annotates) is reported. The fit's
standard error is a delete-a-group jackknife over the phase screens (10 groups; the MTF refitted
with each group left out), which carries the Monte-Carlo scatter of the mean OTF, combined in
quadrature with the Jacobian error of the averaged profile. The Jacobian error alone treats the
profile points as independent and was about 5x smaller than the seed-to-seed scatter of the fit;
the jackknife error matches that scatter (40-seed quick survey: sd / jackknife s.e. = 1.28, 1.16,
0.86 at D/r0 = 7.9, 10.5, 12.9). Over those seeds the fit is biased by -0.27 +/- 0.06 at 7.9 and
+0.24 +/- 0.05 at 12.9 (none at 10.5), a systematic of the simulation/fit that only the 5 %
tolerance covers. The text's own RMSE values are printed only on its figure, not
in the text, so they are not compared. The long-exposure fit of the same frames (tilt kept) is shown
for contrast. Run time on the shared 2-core machine: quick 3.2 s, full 6.6 s (29 Nov 2026, load ~1;
10 s and 61 s at load ~14 before).
"""

import numpy as np
from scatterlab.studies._common import compare, jackknife_se, set_verdict
from scipy import optimize

from scatterlab.imaging import (
    circular_pupil,
    diffraction_mtf,
    fit_r0,
    phase_screen,
    psf,
    radial_profile,
    short_exposure_mtf,
)
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "fig48",
    "title": "Short-exposure MTFs against Fried's theory, with fitted D/r0 and fit RMSE",
    "reproduces": "Fig. 48 (Sec. 5.3)",
}
D_R0 = (7.9, 10.5, 12.9)
GROUPS = 10  # groups of screens for the jackknife standard error of the fit


def _fit_short(nu, prof, floor=0.02):
    """D/r0 of Fried's short-exposure MTF fitted to ``prof`` in log MTF; (value, standard error,
    RMSE of the fit in MTF, fitted mask)."""
    stop = nu[np.nonzero((prof <= floor) & (nu > 0))[0][0]] if np.any(prof <= floor) else 1.0
    sel = (prof > floor) & (nu > 0) & (nu < min(stop, 1.0))

    def resid(p):
        return np.log(short_exposure_mtf(nu[sel], np.exp(p[0]))) - np.log(prof[sel])

    res = optimize.least_squares(resid, [np.log(8.0)])
    dof = max(sel.sum() - 1, 1)
    s2 = np.sum(res.fun**2) / dof
    se_log = np.sqrt(s2 / float(res.jac[:, 0] @ res.jac[:, 0]))
    value = float(np.exp(res.x[0]))
    rmse = float(np.sqrt(np.mean((short_exposure_mtf(nu[sel], value) - prof[sel]) ** 2)))
    return value, value * se_log, rmse, sel


def _frames(ctx, pupil, n, R, r0, frames, groups=GROUPS):
    """Tilt-removed frames' summed OTF per group of screens (``groups`` consecutive, equal groups),
    and the mean PSF of the raw frames."""
    yy, xx = np.mgrid[:n, :n] - (n - 1) / 2
    inside = pupil > 0
    basis = np.stack([xx[inside], yy[inside], np.ones(inside.sum())], 1)
    group_of = np.arange(frames) * groups // frames
    otf, raw = None, 0.0
    for i in range(frames):
        screen = phase_screen(n, 1.0 / (2 * R), r0, ctx.rng)
        coef = np.linalg.lstsq(basis, screen[inside], rcond=None)[0]
        flat = screen - (coef[0] * xx + coef[1] * yy)
        f = np.fft.fft2(psf(pupil, flat, pad=2))
        if otf is None:
            otf = np.zeros((groups,) + f.shape, complex)
        otf[group_of[i]] += f
        raw = raw + psf(pupil, screen, pad=2)
    return otf, raw / frames


def _mtf_profile(otf_sum, R):
    """Radial profile of the MTF (modulus of the mean OTF, normalised to 1 at zero frequency) out
    to the cut-off; (nu, profile)."""
    otf = np.abs(np.fft.fftshift(otf_sum))
    r, prof = radial_profile(otf / otf.max())
    return r[: 2 * R] / (2 * R), prof[: 2 * R]


def _jackknife(otf_groups, R):
    """Delete-a-group jackknife standard error of the short-exposure D/r0 fit over the screens:
    the MTF is refitted with each group of screens left out, and
    se^2 = (G - 1) / G * sum_g (fit_g - mean fit)^2. It carries the Monte-Carlo scatter of the
    mean OTF, which the Jacobian error of one averaged profile (points treated as independent)
    misses."""
    total = otf_groups.sum(0)
    fits = np.array([_fit_short(*_mtf_profile(total - g, R))[0] for g in otf_groups])
    return float(jackknife_se(fits)), fits


def run(ctx):
    n, R, D = 64, 32, 1.0
    frames = 100 if ctx.quick else 1000
    pupil = circular_pupil(n, R)
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6.5, 4.2))
    nu_f = np.linspace(0, 1, 200)
    ax.semilogy(nu_f, diffraction_mtf(nu_f), "k:", label="diffraction limit")
    cmp = []
    for d_r0 in D_R0:
        with ctx.step(f"D_over_r0_{d_r0}"):
            otf_groups, h_long = _frames(ctx, pupil, n, R, D / d_r0, frames)
            nu, prof = _mtf_profile(otf_groups.sum(0), R)
            fit, se_jac, rmse, sel = _fit_short(nu, prof)
            se_mc, _ = _jackknife(otf_groups, R)
            # the band's u: the screens' Monte-Carlo scatter (jackknife) combined with the
            # Jacobian error of the averaged profile (lack of fit)
            se = float(np.hypot(se_mc, se_jac))
            r_l, prof_l = radial_profile(np.abs(np.fft.fftshift(np.fft.fft2(h_long))))
            long_fit = D / fit_r0(nu, prof_l[: 2 * R] / prof_l[0], D)
        (line,) = ax.semilogy(nu, prof, "o", ms=3, label=f"simulated, D/r0 = {d_r0}")
        ax.semilogy(
            nu_f,
            short_exposure_mtf(nu_f, fit),
            "-",
            color=line.get_color(),
            label=f"short-exposure fit D/r0 = {fit:.2f} +/- {se:.2f}, RMSE {rmse:.4f}",
        )
        ctx.metrics[f"D_over_r0_{d_r0}"] = {
            "short_exposure_fit": fit,
            "fit_standard_error": se,
            "fit_standard_error_jackknife": se_mc,
            "fit_standard_error_jacobian": se_jac,
            "fit_rmse_mtf": rmse,
            "long_exposure_fit_same_frames": long_fit,
        }
        cmp.append(compare(f"D/r0 = {d_r0}", d_r0, fit, 0.0, se, tol=0.05 * d_r0))
    ax.set(
        xlabel=r"normalised frequency $\nu = f\lambda/D$",
        ylabel="MTF",
        ylim=(1e-3, 1.1),
        xlim=(0, 0.6),
    )
    ax.legend(fontsize=6)
    ctx.save_figure(fig, "fig48")
    ctx.metrics["comparisons"] = cmp
    worst = max(abs(c["diff"]) / c["published"] for c in cmp)
    ctx.metrics["max_relative_d_over_r0_error"] = worst
    inside = all(c["inside"] for c in cmp)
    ctx.say(
        f"Short-exposure (tilt-removed) MTFs of {frames} simulated frames, fitted with Fried's "
        "short-exposure MTF as in the text (the input D/r0 plays the role of the text's fitted "
        "value; the band is 2 standard errors of our fit, from a jackknife over groups of screens "
        "combined with the Jacobian error, plus 5 % of D/r0): "
        + " ".join(c["text"] for c in cmp)
        + " Fit RMSE (in MTF): "
        + ", ".join(f"{ctx.metrics[f'D_over_r0_{d}']['fit_rmse_mtf']:.4f}" for d in D_R0)
        + "; the text annotates its RMSEs only on the figure. The long-exposure fit of the same "
        "frames gives D/r0 = "
        + ", ".join(
            f"{ctx.metrics[f'D_over_r0_{d}']['long_exposure_fit_same_frames']:.2f}" for d in D_R0
        )
        + " (tilt kept)."
    )
    # a difference beyond the fit's statistics that only the 5 % tolerance lets in is a bias of the
    # simulation and fit, not noise: said where this run shows it
    biased = [c for c in cmp if c["inside"] and abs(c["diff"]) > 2 * c["u_combined"]]
    if biased:
        ctx.say(
            "Beyond 2 standard errors but inside through the 5 % tolerance: "
            + ", ".join(
                f"{c['name']} ({c['diff']:+.3g}, {abs(c['diff']) / c['u_combined']:.1f} standard errors)"
                for c in biased
            )
            + ". That is a bias of the simulation and the fit, not noise: over 40 quick-mode seeds "
            "(29 Nov 2026) the fit came out -0.27 +- 0.06 off at D/r0 = 7.9, +0.24 +- 0.05 at 12.9 "
            "and -0.00 +- 0.06 at 10.5."
        )
    set_verdict(
        ctx,
        "reproduced" if inside else "partly",
        f"fitted short-exposure D/r0 within {worst:.1%} of 7.9/10.5/12.9; fit RMSE "
        + "/".join(f"{ctx.metrics[f'D_over_r0_{d}']['fit_rmse_mtf']:.3f}" for d in D_R0),
    )
