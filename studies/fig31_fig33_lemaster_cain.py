"""Figs. 31-33: LeMaster and Cain's polarimetric blind deconvolution with the AOP estimated.

The reference text (Sec. 3.3.2) shows LeMaster and Cain's measurement: two fully polarized, back-illuminated bars,
the top one polarized at 2 deg and the bottom one at -83 deg, imaged through linear polarizers at 0, 60 and
-60 deg, with a phase screen at the aperture for the 60 and -60 deg images only (Fig. 31). Their EM estimates
the unpolarized and polarized images lambda_u = (1 - P) S0 and lambda_p = P S0 (Fig. 32: the start, and the
estimate after 500 iterations, with lambda_u "nearly all dark") and the AOP (Fig. 33: -8 deg for the top bar
and -72 deg for the bottom bar).

Here the experiment is simulated (the text gives no photon count, aperture or screen strength; the values
chosen are listed in the metrics): the bars on a dark field, a diffraction-limited 0-deg channel and one
Kolmogorov screen (piston and tilt removed) shared by the 60 and -60 deg channels, Poisson noise. The EM
(:func:`scatterlab.deconvolution.blind_deconvolve`) runs with ``estimate_aop=True`` (the geometry does not fix
the AOP: LeMaster and Cain's per-pixel AOP M-step) and one PSF per channel. Each bar's AOP is the circular mean
of the per-pixel AOP weighted by the polarized light lambda_p; its uncertainty is the weighted circular spread
over the bar divided by sqrt(pixels). The baseline is the AOP of the least-squares Stokes images of the data.
A control run knows the true PSFs (``psf_mode="fixed"``); both runs record the bars' AOP at every iteration
(``callback``), which shows whether the blind run's AOP error comes from the PSF estimate.

Quick mode: 32 x 32 pixels, 100 iterations per run (about 15-25 s). Full mode: 64 x 64 pixels and the text's
500 iterations per run (about 3-4 min on one core).
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.deconvolution import blind_deconvolve, object_grid, resample_psf
from scatterlab.imaging import (
    channel_images,
    circular_pupil,
    convolve,
    detect,
    phase_screen,
    psf,
    remove_piston_tilt,
    stokes_from_channels,
)
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.polarization import aop as stokes_aop
from scatterlab.polarization import dolp as stokes_dolp
from scatterlab.polarization import stokes_vector

STUDY = {
    "id": "fig31_fig33",
    "title": "LeMaster-Cain blind deconvolution of two polarized bars, AOP estimated",
    "reproduces": "Figs. 31-33 (Sec. 3.3.2)",
}

TRUE_AOP_DEG = {"top": 2.0, "bottom": -83.0}
PUBLISHED_AOP_DEG = {"top": -8.0, "bottom": -72.0}  # Fig. 33, text below Fig. 31
ANGLES_DEG = (0.0, 60.0, -60.0)
PHOTONS = 1e4  # expected photo-electrons in the brightest pixel of a channel
D_OVER_R0 = 5.0


def bars(n):
    """Labels (n, n): 0 dark field, 1 top bar, 2 bottom bar; and the linear Stokes image (n, n, 3)."""
    lab = np.zeros((n, n), int)
    h = max(n // 8, 2)
    rows = {1: n // 2 - 3 * h // 2, 2: n // 2 + 3 * h // 2}
    for k, r in rows.items():
        lab[r - h // 2 : r - h // 2 + h, n // 4 : 3 * n // 4] = k
    S = np.zeros((n, n, 3))
    for k, name in ((1, "top"), (2, "bottom")):
        S[lab == k] = stokes_vector(1.0, 1.0, np.radians(TRUE_AOP_DEG[name]))[:3]
    return lab, S


def measure(n, rng):
    """Channel counts (3, n, n) at 0/60/-60 deg: the 0-deg channel diffraction limited, the others through
    one shared phase screen; returns counts, angles [rad], true PSFs (3, n, n), pupil."""
    lab, S = bars(n)
    th = np.radians(ANGLES_DEG)
    m = n // 2  # pupil grid; PSFs are 2m x 2m = n x n (Nyquist)
    pupil = circular_pupil(m, m / 4)
    diameter = m / 2
    screen = remove_piston_tilt(phase_screen(m, 1.0, diameter / D_OVER_R0, rng), pupil > 0)
    h_dl, h_tu = psf(pupil, pad=2), psf(pupil, screen, pad=2)
    psfs = np.stack([h_dl, h_tu, h_tu])
    clean = np.clip(convolve(channel_images(S, th), psfs), 0.0, None)  # FFT round-off below zero
    counts = detect(clean, rng, photons=PHOTONS)
    return lab, S, counts, th, psfs, pupil


def bar_aop(aop, weight, sel):
    """Weighted circular mean of an AOP map over ``sel`` [deg] and its standard error [deg]."""
    w = np.where(np.isfinite(aop[sel]), weight[sel], 0.0)
    z = np.exp(2j * np.nan_to_num(aop[sel]))
    mean = np.sum(w * z) / np.sum(w)
    spread = np.sqrt(-2 * np.log(max(abs(mean), 1e-12))) / 2  # circular sd of alpha [rad]
    n_eff = np.sum(w) ** 2 / np.sum(w**2)
    return float(np.degrees(0.5 * np.angle(mean))), float(np.degrees(spread / np.sqrt(n_eff)))


def wrap_deg(d):
    """An AOP difference wrapped into (-90, 90] deg."""
    return float((d + 90.0) % 180.0 - 90.0)


def deconvolve(counts, th, lab, iterations, radius, psf0=None):
    """EM with the AOP estimated; returns the result and the bars' AOP [deg] after every iteration."""
    track = []

    def record(r):
        lam_p = r.dolp * r.s0
        track.append([bar_aop(r.aop, lam_p, lab == k)[0] for k in (1, 2)])

    kw = dict(psf0=psf0, psf_mode="fixed") if psf0 is not None else {}
    res = blind_deconvolve(
        counts,
        th,
        estimate_aop=True,
        shared_psf=False,
        iterations=iterations,
        psf_radius=radius,
        callback=record,
        **kw,
    )
    return res, np.array(track)


def run(ctx):
    n, iterations = (32, 100) if ctx.quick else (64, 500)
    with ctx.step("simulate"):
        lab, S, counts, th, psfs, pupil = measure(n, ctx.rng)
        Sd = stokes_from_channels(counts, th)
    with ctx.step("deconvolve_blind"):
        res, track = deconvolve(counts, th, lab, iterations, n / 4)
    with ctx.step("deconvolve_known_psf"):
        grid = object_grid((n, n), n / 4)
        known = np.stack([resample_psf(h, grid) for h in psfs])
        res_k, track_k = deconvolve(counts, th, lab, iterations, n / 4, psf0=known)
    lam_u, lam_p = (1 - res.dolp) * res.s0, res.dolp * res.s0
    m = ctx.metrics
    m.update(
        {
            "image_px": n,
            "iterations": iterations,
            "polarizer_deg": list(ANGLES_DEG),
            "photons_peak": PHOTONS,
            "d_over_r0": D_OVER_R0,
            "loglik_start": float(res.loglik[0]),
            "loglik_end": float(res.loglik[-1]),
        }
    )
    rows = []
    for k, name in ((1, "top"), (2, "bottom")):
        sel = lab == k
        ours, ours_se = bar_aop(res.aop, lam_p, sel)
        base, base_se = bar_aop(stokes_aop(Sd), np.clip(Sd[..., 0], 0, None), sel)
        true, pub = TRUE_AOP_DEG[name], PUBLISHED_AOP_DEG[name]
        share_u = float(lam_u[sel].sum() / res.s0[sel].sum())
        m[f"aop_true_deg_{name}"] = true
        m[f"aop_published_deg_{name}"] = pub
        m[f"aop_ours_deg_{name}"] = ours
        m[f"aop_ours_se_deg_{name}"] = ours_se
        m[f"aop_degraded_deg_{name}"] = base
        m[f"aop_error_ours_deg_{name}"] = wrap_deg(ours - true)
        m[f"aop_error_published_deg_{name}"] = wrap_deg(pub - true)
        m[f"aop_error_degraded_deg_{name}"] = wrap_deg(base - true)
        m[f"unpolarized_share_{name}"] = share_u
        col = k - 1
        m[f"aop_error_known_psf_deg_{name}"] = wrap_deg(track_k[-1, col] - true)
        best = int(np.argmin(np.abs([wrap_deg(a - true) for a in track[:, col]])))
        m[f"aop_error_blind_best_deg_{name}"] = wrap_deg(track[best, col] - true)
        m[f"aop_error_blind_best_iteration_{name}"] = best + 1
        m[f"aop_blind_track_deg_{name}"] = [
            float(a) for a in track[:: max(1, iterations // 20), col]
        ]
        rows.append((name, true, pub, ours, ours_se, base, share_u))
    figures(ctx, counts, res, Sd, lab, lam_u, lam_p)
    convergence_figure(ctx, track, track_k)
    report(ctx, rows)


def convergence_figure(ctx, track, track_k):
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6.5, 4))
    it = np.arange(1, len(track) + 1)
    for col, (name, c) in enumerate((("top", "C0"), ("bottom", "C1"))):
        true = TRUE_AOP_DEG[name]
        ax.plot(it, [wrap_deg(a - true) for a in track[:, col]], c, label=f"{name}: blind PSFs")
        ax.plot(
            it, [wrap_deg(a - true) for a in track_k[:, col]], c + "--", label=f"{name}: known PSFs"
        )
        ax.axhline(wrap_deg(PUBLISHED_AOP_DEG[name] - true), color=c, ls=":", lw=1)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("iteration")
    ax.set_ylabel("AOP error [deg] (dotted: published)")
    ax.legend(fontsize=7)
    ctx.save_figure(fig, "aop_convergence")


def figures(ctx, counts, res, Sd, lab, lam_u, lam_p):
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 3, figsize=(10, 3.4))
    for ax, img, a in zip(axes, counts, ANGLES_DEG):
        ax.imshow(img, cmap="gray")
        ax.set_title(f"polarizer {a:+.0f} deg" + (" (turbulence)" if a else ""), fontsize=9)
        ax.axis("off")
    fig.suptitle("Fig. 31 (simulated): channel images")
    ctx.save_figure(fig, "fig31_channels")

    s0_start = np.clip(Sd[..., 0], 0, None)
    P_start = np.clip(np.nan_to_num(stokes_dolp(Sd)), 0, 1)  # the EM's start (no light: 0)
    fig, axes = pyplot.subplots(2, 2, figsize=(7, 6.4))
    vmax = max(float(lam_p.max()), float(s0_start.max()))
    panels = [
        ((1 - P_start) * s0_start, "lambda_u start"),
        (P_start * s0_start, "lambda_p start"),
        (lam_u, f"lambda_u after {res.iterations} iterations"),
        (lam_p, f"lambda_p after {res.iterations} iterations"),
    ]
    for ax, (img, title) in zip(axes.ravel(), panels):
        ax.imshow(img, cmap="gray", vmin=0, vmax=vmax)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.suptitle("Fig. 32 (simulated): unpolarized and polarized images")
    ctx.save_figure(fig, "fig32_lambda")

    lit = lam_p > 0.2 * lam_p.max()
    fig, axes = pyplot.subplots(1, 2, figsize=(8, 3.6))
    for ax, a, title in (
        (axes[0], stokes_aop(Sd), "AOP of the data (least squares)"),
        (axes[1], res.aop, "AOP estimate (EM)"),
    ):
        im = ax.imshow(np.where(lit, np.degrees(a), np.nan), cmap="twilight", vmin=-90, vmax=90)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.colorbar(im, ax=axes, label="AOP [deg]", shrink=0.8)
    fig.suptitle("Fig. 33 (simulated): AOP where lambda_p > 20 % of its peak")
    ctx.save_figure(fig, "fig33_aop")


def report(ctx, rows):
    m = ctx.metrics
    lines = [
        "| bar | true AOP [deg] | published [deg] (error) | ours [deg] (error, s.e.) | data's LS AOP [deg] "
        "(error) | lambda_u share |",
        "|---|---|---|---|---|---|",
    ]
    for name, true, pub, ours, se, base, share in rows:
        lines.append(
            f"| {name} | {true:.0f} | {pub:.0f} ({wrap_deg(pub - true):+.0f}) | {ours:.1f} "
            f"({wrap_deg(ours - true):+.1f}, {se:.1f}) | {base:.1f} ({wrap_deg(base - true):+.1f}) | "
            f"{share:.3f} |"
        )
    ctx.say("\n".join(lines))
    err_ours = [abs(m[f"aop_error_ours_deg_{b}"]) for b in ("top", "bottom")]
    err_pub = [abs(m[f"aop_error_published_deg_{b}"]) for b in ("top", "bottom")]
    err_base = [abs(m[f"aop_error_degraded_deg_{b}"]) for b in ("top", "bottom")]
    m["aop_max_error_ours_deg"] = max(err_ours)
    m["aop_max_error_published_deg"] = max(err_pub)
    se = [m[f"aop_ours_se_deg_{b}"] for b in ("top", "bottom")]
    verdict, text = aop_verdict(err_ours, se, err_pub, err_base)
    # simulated, not the laboratory data: the method is judged, not the published errors
    set_verdict(
        ctx,
        verdict,
        f"AOP of the two bars recovered blind to {err_ours[0]:.1f} and {err_ours[1]:.1f} deg "
        f"({err_ours[0] / se[0]:.1f} and {err_ours[1] / se[1]:.1f} s.e.; raw-data LS "
        f"{err_base[0]:.1f} and {err_base[1]:.1f}; published {err_pub[0]:.0f} and "
        f"{err_pub[1]:.0f} deg off, laboratory data not simulable)",
    )
    ctx.say(text)
    known = [abs(m[f"aop_error_known_psf_deg_{b}"]) for b in ("top", "bottom")]
    best = [abs(m[f"aop_error_blind_best_deg_{b}"]) for b in ("top", "bottom")]
    drift = max(err_ours) > 2 * max(known) and max(err_ours) > max(best) + 1.0
    ctx.say(
        f"Cause, measured: with the true PSFs the same EM ends {known[0]:.1f} and {known[1]:.1f} deg off; "
        f"the blind run came within {best[0]:.1f} and {best[1]:.1f} deg at its best iteration "
        f"({m['aop_error_blind_best_iteration_top']} and {m['aop_error_blind_best_iteration_bottom']}) "
        f"and ended {err_ours[0]:.1f} and {err_ours[1]:.1f} deg off. "
        + (
            "The blind run's AOP drifts as the iterations go on: with three channels and one PSF per "
            "channel, (S0, P, AOP) per pixel can already explain the three channel values, so the data "
            "hardly constrain how the blur is split between object and PSFs, and the AOP moves along that "
            "ridge -- a plausible source of the text's 10-11 deg errors after 500 iterations."
            if drift
            else "The blind PSF estimate costs little AOP accuracy here."
        )
    )
    shares = [m[f"unpolarized_share_{b}"] for b in ("top", "bottom")]
    ctx.say(
        f"lambda_u: {100 * max(shares):.1f} % or less of each bar's light is estimated unpolarized "
        + (
            "-- nearly all dark, as in Fig. 32."
            if max(shares) < 0.1
            else "-- not the nearly dark lambda_u of Fig. 32."
        )
    )
    ctx.say(
        "Not like for like: the published numbers come from a laboratory measurement whose photon count, "
        "aperture and screen strength the text does not give (ours: "
        f"{m['photons_peak']:.0f} photo-electrons peak, D/r0 = {m['d_over_r0']}, {m['image_px']} px, "
        f"{m['iterations']} iterations); the text attributes its 10-11 deg errors to sources discussed in "
        "LeMaster and Cain's paper (Ref. 74), which a noise-and-turbulence-only simulation does not contain. "
        "So the comparison checks the method (the AOP is recovered where the geometry does not fix it), "
        "not the published error sizes."
    )


def aop_verdict(err_ours, se, err_pub, err_base, bars=("top", "bottom")):
    """Verdict and text for the bars' AOP, generated from the errors.

    Parameters
    ----------
    err_ours, se, err_pub, err_base : sequence of float
        Per bar [deg]: |error| of the blind EM's AOP, its standard error, |error| of the published
        estimate, |error| of the raw data's least-squares AOP.
    bars : tuple of str
        Bar names.

    Returns
    -------
    verdict : str
        "reproduced" when every bar's EM error is within the text's (the method recovers the AOP at
        least as well), inside 2 s.e., and no worse than the raw-data AOP; "partly" when within the
        text's errors only; "not reproduced" otherwise.
    text : str
    """
    closer = all(o <= p for o, p in zip(err_ours, err_pub))
    covered = [o <= 2 * s for o, s in zip(err_ours, se)]
    worse = [b for b, o, r in zip(bars, err_ours, err_base) if o > r]
    text = (
        "AOP: our estimates miss the true angles by "
        + " and ".join(
            f"{o:.1f} deg ({b}, {o / s:.1f} s.e.)" for b, o, s in zip(bars, err_ours, se)
        )
        + "; LeMaster and Cain's published estimates miss them by "
        + " and ".join(f"{p:.0f}" for p in err_pub)
        + " deg, so ours are "
        + ("within" if closer else "NOT within")
        + " the published errors. "
        + (
            "The stated standard errors cover the errors (<= 2 s.e.). "
            if all(covered)
            else f"The stated standard error does NOT cover the error of "
            f"{sum(not c for c in covered)} of {len(covered)} bars (> 2 s.e.): it is the spread "
            "over the bar's pixels, which does not measure the estimate's bias. "
        )
        + "The least-squares AOP of the raw data misses by "
        + " and ".join(f"{r:.1f}" for r in err_base)
        + " deg; "
        + (
            "the EM improves on it for every bar."
            if not worse
            else f"the EM makes the {' and '.join(worse)} bar{'s' if len(worse) > 1 else ''} "
            "WORSE than the raw data."
        )
    )
    if closer and all(covered) and not worse:
        verdict = "reproduced"
    elif closer:
        verdict = "partly"
    else:
        verdict = "not reproduced"
    return verdict, text
