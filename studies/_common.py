"""Shared helpers of the studies (not a study: the runner skips modules starting with '_').

Imported as ``scatterlab.studies._common``; the pyplot accessor ``plt`` is
:func:`scatterlab.plotting.headless_pyplot`, shared with the reports.
"""

import numpy as np

from scatterlab.plotting import headless_pyplot as plt


def rms_slope_from_degrees(deg):
    """The reference's "n deg rms slope roughness" as a per-axis rms slope sigma = tan(n deg)."""
    return np.tan(np.radians(deg))


def imperfect_1064_instrument():
    """The reference's switched wave-plate ellipsometer with fixed, realistic imperfections."""
    from scatterlab.ellipsometry import (
        Errors,
        Instrument,
        switched_wave_plate_psa,
        switched_wave_plate_psg,
    )

    psg = switched_wave_plate_psg(
        Errors(
            retardance=(0.05, -0.03, 0.04, 0.06),
            azimuth=(0.02, -0.01, 0.03, 0.0),
            extinction_ratio=1e-3,
        )
    )
    psa = switched_wave_plate_psa(
        Errors(
            retardance=(0.03, 0.02, -0.04, 0.01),
            azimuth=(-0.02, 0.01, 0.0, 0.02),
            extinction_ratio=2e-3,
        )
    )
    return Instrument(psg, psa, name="switched wave-plate, 1064 nm")


REF_TRUE_AZ = np.radians([0.0, 61.5, 118.2, 46.3])
REF_NOMINAL = np.radians([0.0, 60.0, 120.0, 45.0])


def calibrate(instrument, rng, noise, repeats=1, **kw):
    """ECM with the reference's set (polarizer at 0/60/120 deg, quarter-wave plate at 45 deg),
    slightly misaligned."""
    from scatterlab.ellipsometry import ecm_calibrate
    from scatterlab.polarization import linear_polarizer, linear_retarder

    samples = [linear_polarizer(a, 1e-4) * 0.9 for a in REF_TRUE_AZ[:3]]
    samples.append(linear_retarder(np.radians(88), REF_TRUE_AZ[3]) * 0.95)
    B0 = instrument.measure(np.eye(4), rng, noise=noise, repeats=repeats)[0]
    refs = [
        (k, instrument.measure(M, rng, noise=noise, repeats=repeats)[0], a)
        for k, M, a in zip(["polarizer"] * 3 + ["retarder"], samples, REF_NOMINAL)
    ]
    return ecm_calibrate(B0, refs, **kw)


def _chain_accuracy_text(d_eta, eta, published_fit):
    """The synthetic chain's error |d eta| against the reference's real-data shift
    |published fit - literature eta| (``published_fit`` as "n - jkappa"), both in the text."""
    n, kappa = (float(v) for v in published_fit.replace(" ", "").split("-j"))
    shift = abs(complex(n, -kappa) - eta)
    size = "smaller than" if d_eta < shift else "not smaller than"
    size = "far smaller than" if d_eta < 0.1 * shift else size
    return (
        "they show the accuracy of the measurement chain and the fit (|d eta| = "
        f"{d_eta:.1e} here), {size} the reference's shift from the literature value "
        f"(|{published_fit} - literature| = {shift:.2g})."
    )


def mueller_figure_study(ctx, eta, sigma, label, published_fit, literature_name):
    """Figs. 41-42: synthetic Mueller measurements of a rough metal vs the pBRDF; best-fit index."""
    from scatterlab.ellipsometry import fit_mueller_elements, normalised_elements
    from scatterlab.pbrdf import Model

    pyplot = plt()
    rng = ctx.rng
    repeats = 32 if ctx.quick else 256
    noise = 5e-3
    inst = imperfect_1064_instrument()
    theta = np.radians(np.arange(10, 81, 10))
    model = Model(sigma)
    with ctx.step("calibration"):
        cal = calibrate(inst, rng, noise, repeats=repeats)
    with ctx.step("measurements"):
        F = model.mueller(eta, theta, theta, np.pi)
        scale = 1.0 / F[:, 0, 0]  # each geometry measured at a comparable signal level
        B = inst.intensities(F * scale[:, None, None])
        draws = B + noise * np.abs(B) * rng.standard_normal((repeats,) + B.shape)
        elems = normalised_elements(cal.mueller(draws))  # (repeats, angles, 4)
        mean, std = elems.mean(axis=0), elems.std(axis=0, ddof=1)
    with ctx.step("fit"):
        fit = fit_mueller_elements(theta, mean, std=std / np.sqrt(repeats))
    truth = normalised_elements(F)
    fine = np.radians(np.linspace(5, 85, 161))
    curve = normalised_elements(model.mueller(eta, fine, fine, np.pi))
    fitted = normalised_elements(Model(fit.sigma).mueller(fit.eta, fine, fine, np.pi))
    fig, grid = pyplot.subplots(
        2, 4, figsize=(15, 5.5), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    axes, raxes = grid[0], grid[1]
    names = ["M01/M00", "M11/M00", "M22/M00", "M23/M00"]
    fit_at_data = normalised_elements(Model(fit.sigma).mueller(fit.eta, theta, theta, np.pi))
    for k, rax in enumerate(raxes):
        rax.errorbar(
            np.degrees(theta),
            mean[:, k] - fit_at_data[:, k],
            yerr=std[:, k] / np.sqrt(repeats),
            fmt="o",
            ms=3,
        )
        rax.axhline(0, color="k", lw=0.5)
        rax.set(xlabel=r"$\theta_i = \theta_r$ [deg]", ylabel="data - fit" if k == 0 else None)
    for k, ax in enumerate(axes):
        ax.errorbar(
            np.degrees(theta),
            mean[:, k],
            yerr=std[:, k],
            fmt="o",
            ms=4,
            label=f"synthetic ({repeats} repeats)",
        )
        ax.plot(
            np.degrees(fine),
            curve[:, k],
            "-",
            label=f"pBRDF, eta = {eta.real:.4g} - j{-eta.imag:.4g}",
        )
        ax.plot(
            np.degrees(fine), fitted[:, k], "--", label=f"best fit {fit.n:.4f} - j{fit.kappa:.4f}"
        )
        ax.set(title=names[k])
    axes[0].legend(fontsize=7)
    ctx.save_figure(fig, label)
    err = fit.errors
    ctx.metrics.update(
        {
            "eta_true": eta,
            "sigma_true": sigma,
            "n_fit": fit.n,
            "kappa_fit": fit.kappa,
            "sigma_fit": fit.sigma,
            "n_err_1sigma": err[0],
            "kappa_err_1sigma": err[1],
            "sigma_err_1sigma": err[2],
            "published_fit_on_real_data": published_fit,
            "repeats": repeats,
            "noise_per_reading": noise,
            "ecm_quality": cal.quality,
            "cond_W": cal.cond_W,
            "cond_A": cal.cond_A,
            "max_abs_error_of_mean_elements": float(np.max(np.abs(mean - truth))),
            "azimuth_errors_deg": list(
                np.degrees(np.array([r["azimuth"] for r in cal.references]) - REF_TRUE_AZ)
            ),
        }
    )
    z = np.abs(
        np.array([fit.n - eta.real, fit.kappa + eta.imag, fit.sigma - sigma])
        / np.maximum(err, 1e-300)
    )
    ctx.metrics["fit_deviation_in_sigmas"] = list(z)
    dev = ctx.metrics["max_abs_error_of_mean_elements"]
    ctx.say(
        f"Synthetic {literature_name} (eta = {eta.real} - j{-eta.imag}, roughness {sigma}) "
        f"measured at 1.064 um through an imperfect switched wave-plate ellipsometer "
        f"(cond W = {cal.cond_W:.2f}, cond A = {cal.cond_A:.2f}) calibrated by ECM from the "
        f"reference's set, {repeats} repeats of noise {noise} per reading. The means agree with "
        f"the pBRDF to {dev:.1e}; the fit recovers eta = {fit.n:.4f} - j{fit.kappa:.4f} and "
        f"sigma = {fit.sigma:.4f}, i.e. |dn| = {abs(fit.n - eta.real):.4f}, "
        f"|dkappa| = {abs(fit.kappa + eta.imag):.4f}, |dsigma| = {abs(fit.sigma - sigma):.4f}. "
        f"Its standard errors ({err[0]:.4f}, {err[1]:.4f}, {err[2]:.1e}) count only the repeat "
        f"noise of the sample measurements, and the deviation is {max(z):.1f} of them: "
        + (
            "the rest is the calibration's own error (W and A from noisy references), common to "
            "all angles, which averaging the sample more cannot remove."
            if max(z) > 3
            else "within 3 of them, so this run shows no error beyond the sample's repeat noise "
            "(the calibration's own error, from noisy references, is below what it can resolve)."
        )
    )
    ctx.say(
        f"On its real data the reference found {published_fit} instead of the literature value: "
        "a real sample differs from the model (surface oxide or contamination, multiple "
        "scattering and depolarisation beyond the single-bounce facet model, a non-Gaussian slope "
        "distribution, the bulk index of a sprayed or plated coating). Synthetic data generated "
        "by the model itself cannot reproduce that shift; "
        + _chain_accuracy_text(abs(fit.eta - eta), eta, published_fit)
    )
    set_verdict(
        ctx,
        "partly",
        f"synthetic chain recovers eta to |d eta| {abs(fit.eta - eta):.1e}; the published real-data "
        f"fit {published_fit} is not reproducible from synthetic data",
    )


def plate_observations(ctx, theta_deg, d_over_r0, *, priors, iterations, size, reps=1, plates=None):
    """Simulated painted plates (Figs. 47-61) at one specular geometry, through turbulence,
    corrected by the EM with ``priors`` and registered: {plate name: [observation per repetition]}.

    Each observation is a dict ``{case: {kind: {"s0", "dolp", "classes", "priors"}}}`` built from
    :func:`scatterlab.characterization.pipeline.observe`: ``no_turbulence/degraded`` is the reference
    (the no-turbulence image restored with its known PSF, classified by the priors' DOLP thresholds as
    in Ch. V); per D/r0, ``degraded`` (thresholds) and ``corrected`` (EM, the priors' continuation).
    """
    from scatterlab.characterization import SceneConfig
    from scatterlab.characterization.pipeline import observe
    from scatterlab.characterization.scene_config import Plate
    from scatterlab.deconvolution import classify_dolp
    from scatterlab.imaging import painted_plate

    def as_dict(o):
        ref = o.images[("no_turbulence", "restored")]
        out = {
            "no_turbulence": {
                "degraded": _image(ref, classify_dolp(np.nan_to_num(ref.dolp), priors), priors)
            }
        }
        for case, kind in o.images:
            if case == "no_turbulence":
                continue
            img = o.images[(case, kind)]
            out.setdefault(case, {})[kind] = _image(img, img.classes, priors)
        return out

    plates = plates or [Plate(), Plate("steel", 3.60, 5.88)]
    out = {}
    for k, plate in enumerate(plates):
        dr = d_over_r0[k] if isinstance(d_over_r0[0], (list, tuple)) else d_over_r0
        cfg = SceneConfig(
            image_size=size,
            geometry_deg=[theta_deg],
            d_over_r0=list(dr),
            iterations=iterations,
            plates=[plate],
        )
        labels = painted_plate(size, theta=np.radians(theta_deg), rng=ctx.rng).labels
        out[plate.metal] = {
            "labels": labels,
            "obs": [
                as_dict(
                    observe(
                        plate,
                        labels,
                        [np.radians(theta_deg)],
                        cfg,
                        ctx.rng,
                        priors=priors,
                        executor=ctx.executor,
                    )[0]
                )
                for _ in range(reps)
            ],
        }
    return out


def _image(img, classes, priors):
    return {"s0": img.s0, "dolp": np.nan_to_num(img.dolp), "classes": classes, "priors": priors}


VERDICTS = ("reproduced", "partly", "not reproduced", "own study")


def set_verdict(ctx, verdict, headline):
    """Record the study's verdict and headline agreement number for the index page.

    Parameters
    ----------
    ctx : StudyContext
        The study's context; ``ctx.metrics["verdict"]`` and ``ctx.metrics["headline"]`` are set.
    verdict : str
        One of :data:`VERDICTS`: "reproduced" (every compared number inside its combined
        uncertainty or the stated tolerance), "partly", "not reproduced", "own study".
    headline : str
        One short line with the headline agreement number (published, ours, difference).

    Returns
    -------
    None
    """
    if verdict not in VERDICTS:
        raise ValueError(f"verdict must be one of {VERDICTS}, got {verdict!r}")
    ctx.metrics["verdict"] = verdict
    ctx.metrics["headline"] = str(headline)


def t_factor(n):
    """Two-sided 95 % coverage factor of a standard error estimated from ``n`` Monte-Carlo draws
    (realizations, partitions, groups): Student's t with n - 1 degrees of freedom (2.57 for 6, 1.98
    for 100), since with few draws the standard error is itself uncertain. inf below two draws.

    Parameters
    ----------
    n : int
        Number of draws.

    Returns
    -------
    float
    """
    from scipy.stats import t as student_t

    return float(student_t.ppf(0.975, n - 1)) if n > 1 else float("inf")


def jackknife_se(loo):
    """Jackknife standard error from the leave-one-out values ``loo`` (G, ...) of G draws or groups:
    sqrt((G - 1) / G * sum_g (loo_g - mean)^2). NaN with fewer than two.

    Parameters
    ----------
    loo : array_like, shape (G, ...)
        The statistic recomputed with each draw (or group of draws) left out.

    Returns
    -------
    ndarray, shape (...)
    """
    loo = np.asarray(loo, float)
    G = len(loo)
    if G < 2:
        return np.full(loo.shape[1:], np.nan)
    return np.sqrt((G - 1) / G * np.sum((loo - loo.mean(axis=0)) ** 2, axis=0))


def paired_change(base, other):
    """Mean change from ``base`` to ``other`` paired draw by draw, with its standard error and 95 % interval.

    For two methods applied to the same draws (acquisitions, screens, scenes): the draw-to-draw scatter
    they share cancels in the differences, which a comparison of two separate means would count twice.

    Parameters
    ----------
    base, other : array_like, shape (N,)
        One number per draw, in the same order.

    Returns
    -------
    dict
        ``mean`` (other minus base), ``se`` (standard error over the N draws; inf for one draw),
        ``half_width`` (95 % Student t half-width, :func:`t_factor`) and ``word``: "lower" or "higher"
        where the interval excludes zero, else "no change resolved".
    """
    base, other = np.asarray(base, float), np.asarray(other, float)
    if base.ndim != 1 or base.shape != other.shape or base.size == 0:
        raise ValueError(
            "base and other must be two equal-length 1-D sequences, "
            f"got shapes {base.shape} and {other.shape}"
        )
    d = other - base
    se = float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("inf")
    mean, half = float(d.mean()), t_factor(d.size) * se
    word = "lower" if mean + half < 0 else "higher" if mean - half > 0 else "no change resolved"
    return {"mean": mean, "se": se, "half_width": half, "word": word}


def compare(name, published, ours, u_published=0.0, u_ours=0.0, k=2.0, tol=0.0):
    """A like-for-like comparison of one number with its published value.

    Parameters
    ----------
    name : str
        What is compared (used in the sentence).
    published, ours : float
        The published value and ours.
    u_published, u_ours : float
        Their standard uncertainties (0 where none is known: a value read from a plot gets
        its reading error, an exact model value 0).
    k : float
        Coverage factor of the combined uncertainty (default 2, about 95 %).
    tol : float
        A stated absolute tolerance added to the allowed band (e.g. the reading error of a
        curve read off a printed figure); 0 for none.

    Returns
    -------
    dict
        ``name, published, ours, diff`` (ours - published), ``u_combined``
        (sqrt(u_p^2 + u_o^2)), ``band`` (k u_combined + tol), ``inside`` (|diff| <= band) and
        ``text``, one sentence stating all of them.
    """
    published, ours = float(published), float(ours)
    u = float(np.hypot(u_published, u_ours))
    band = k * u + tol
    diff = ours - published
    inside = bool(np.isfinite(diff) and abs(diff) <= band)
    rel = f" ({diff / published:+.1%})" if published else ""
    text = (
        f"{name}: published {published:.4g}, ours {ours:.4g}, difference {diff:+.3g}{rel}; "
        f"allowed band {band:.3g} (k = {k:g} x combined u {u:.3g}"
        + (f" + tolerance {tol:.3g}" if tol else "")
        + f"): {'inside' if inside else 'OUTSIDE'}."
    )
    return {
        "name": name,
        "published": published,
        "ours": ours,
        "diff": diff,
        "u_combined": u,
        "band": band,
        "inside": inside,
        "text": text,
    }
