"""Several exposures sharing one pure few-material layout (``layout_psf(frames=F, edge_band=2)``): rounds
and exposures vs PSF error vs the paint's DOLP vs time.

The plate of ``perf_layout_psf`` (paint S0 1, DOLP 0.8; metal S0 10, DOLP 0.02 in two corners and a bar) is
seen F times, each exposure through its own Kolmogorov screen (D/r0 5) with 1e5 photo-electrons at the
brightest channel pixel. Unlike ``perf_layout_psf`` the exposures are rendered as the characterization's
acquisition renders them: on a field twice as wide (the plate is larger than the field), blurred there and
cropped, so light from outside enters and none wraps around -- which a PSF support of the whole field needs.

The baseline is the multi-frame blind EM (Schulz's pupil model, a PSF per exposure, support of radius n/4).
``layout_psf`` starts from it with the whole field as PSF support, two materials, and either pure interiors
(``edge_band`` 2: only pixels within 2 of an edge mix) or a soft layout everywhere, for R rounds, its
accuracy knob. Each row reports the mean PSF L1 distance from the truth over the exposures (after the best
integer shift; 2 = disjoint), the fitted paint's DOLP error (the layout's own material value), the DOLP
RMSE off the edges of the known-PSF restoration of all exposures with the PSFs found (whole field, 150
iterations; the pixels a region mean uses), and the time of ``layout_psf`` as a ratio to the blind EM's in
the same run.

Full mode (96 x 96, F = 1, 2, 4, R = 0, 5, 10, 20, 40, one set of screens): see the metrics and the figure;
the quick mode (48 x 48, F = 3, R = 0 and 8) runs in the tests.
"""

import time

import numpy as np
from scatterlab.studies._common import set_verdict
from scatterlab.studies.performance.perf_layout_psf import painted_plate_object
from scipy.ndimage import binary_erosion

from scatterlab.deconvolution import (
    blind_deconvolve,
    initial_psf,
    layout_psf,
    object_grid,
    psf_distance,
    resample_psf,
)
from scatterlab.imaging import (
    ANGLES_0_45_90_135,
    channel_images,
    circular_pupil,
    detect,
    phase_screen,
    psf,
)
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "perf_layout_frames",
    "title": "Exposures sharing a pure few-material layout: rounds and frames vs PSF error, paint DOLP, time",
    "reproduces": "own performance study: what identifies the blind PSFs and the dim material",
}

PAINT_DOLP = 0.8


def exposures(n, frames, d_over_r0, rng, photons=1e5):
    """``frames`` exposures of the plate, each through its own screen, with no wrap-around.

    Parameters
    ----------
    n : int
        Image side [pixels] (the pupil grid is n / 2, 2 pixels per lambda/D).
    frames : int
        Number of exposures.
    d_over_r0 : float
        Turbulence strength.
    rng : numpy.random.Generator
        Draws the screens and the noise.
    photons : float
        Photo-electrons at the brightest channel pixel of each exposure.

    Returns
    -------
    pupil : ndarray, shape (n/2, n/2)
    psfs : list of ndarray, shape (n, n)
        The true PSFs (centred, unit sum) on twice the pupil grid's sampling.
    counts : ndarray, shape (4 frames, n, n) [photo-electrons]
        The channels, frame by frame.
    angles : ndarray, shape (4 frames,) [rad]
    """
    A = circular_pupil(n // 2, n // 4)
    S, _ = painted_plate_object(n)
    m = n // 2
    wide = np.pad(S, ((m, m), (m, m), (0, 0)), mode="edge")
    hs, counts = [], []
    for _ in range(frames):
        h = psf(A, phase_screen(n // 2, 1.0, (n // 2) / d_over_r0, rng), pad=2)
        img = channel_images(wide, ANGLES_0_45_90_135, resample_psf(h, wide.shape[:2]))
        counts.append(detect(np.clip(img[:, m : m + n, m : m + n], 0, None), rng, photons=photons))
        hs.append(h)
    return A, hs, np.concatenate(counts), np.tile(ANGLES_0_45_90_135, frames)


def run(ctx):
    rng = ctx.rng
    n = 48 if ctx.quick else 96
    frame_counts = (3,) if ctx.quick else (1, 2, 4)
    knob = (0, 8) if ctx.quick else (0, 5, 10, 20, 40)
    iterations = 60 if ctx.quick else 150
    _, P = painted_plate_object(n)
    metal = P < 0.5
    off_edges = binary_erosion(metal, iterations=3) | binary_erosion(~metal, iterations=3)
    whole = (np.sqrt(2) * n / 2, n // 2)
    wgrid = object_grid((n, n), whole[0], pad=whole[1])
    rows = []
    with ctx.step("exposures and layouts"):
        for F in frame_counts:
            A, hs, counts, angles = exposures(n, F, 5.0, rng)
            grid = object_grid((n, n), n / 4, pad=n // 4)
            truths = [resample_psf(h, wgrid) for h in hs]
            t0 = time.perf_counter()
            start = blind_deconvolve(
                counts,
                angles,
                psf0=np.stack([initial_psf(A, grid, rng=int(rng.integers(2**31))) for _ in hs]),
                psf_mode="pupil",
                iterations=iterations,
                pupil=A,
                psf_radius=n / 4,
                pad=n // 4,
                frames=F,
            )
            base = time.perf_counter() - t0
            runs = [("pure", R) for R in knob] + [("soft", knob[-1])]
            for layout, R in runs:
                t0 = time.perf_counter()
                if R == 0:
                    found, paint_dolp = [resample_psf(h, wgrid) for h in start.psfs], np.nan
                else:
                    res = layout_psf(
                        counts,
                        angles,
                        start,
                        pupil=A,
                        psf_radius=whole[0],
                        pad=whole[1],
                        frames=F,
                        materials=2,
                        edge_band=2 if layout == "pure" else None,
                        rounds=R,
                        rng=0,
                    )
                    found = list(res.psf) if F > 1 else [res.psf]
                    paint_dolp = float(res.dolp[np.argmin(res.s0)])
                secs = time.perf_counter() - t0
                dist = [psf_distance(h, t)[0] for h, t in zip(found, truths)]
                fixed = blind_deconvolve(
                    counts,
                    angles,
                    psf0=np.stack(found),
                    psf_mode="fixed",
                    iterations=150,
                    pupil=A,
                    psf_radius=whole[0],
                    pad=whole[1],
                    frames=F,
                )
                # the object is found up to a translation: compare it at the best integer shift
                err = min(
                    float(
                        np.sqrt(
                            np.nanmean((np.roll(fixed.dolp, (a, b), (0, 1)) - P)[off_edges] ** 2)
                        )
                    )
                    for a in range(-6, 7)
                    for b in range(-6, 7)
                )
                rows.append(
                    {
                        "frames": F,
                        "layout": "blind EM" if R == 0 else layout,
                        "rounds": R,
                        "psf_l1_error": float(np.mean(dist)),
                        "paint_dolp_error": paint_dolp - PAINT_DOLP,
                        "dolp_rmse_off_edges": err,
                        "seconds": secs,
                        "time_ratio_to_blind_em": secs / base,
                    }
                )
    ctx.metrics["rows"] = rows
    ctx.metrics["scene"] = {"size": n, "d_over_r0": 5.0, "iterations": iterations}

    pyplot = plt()
    fig, ax = pyplot.subplots(1, 2, figsize=(10, 4), layout="constrained")
    for F in frame_counts:
        sel = [r for r in rows if r["frames"] == F and r["layout"] != "soft"]
        ax[0].plot(
            [r["rounds"] for r in sel],
            [r["psf_l1_error"] for r in sel],
            "o-",
            label=f"F = {F}, pure",
        )
        ax[1].plot(
            [r["seconds"] for r in sel[1:]],
            [abs(r["paint_dolp_error"]) for r in sel[1:]],
            "o-",
            label=f"F = {F}, pure",
        )
        soft = next(r for r in rows if r["frames"] == F and r["layout"] == "soft")
        ax[0].plot(soft["rounds"], soft["psf_l1_error"], "x", ms=9, label=f"F = {F}, soft")
        ax[1].plot(
            soft["seconds"], abs(soft["paint_dolp_error"]), "x", ms=9, label=f"F = {F}, soft"
        )
    ax[0].set(
        xlabel="rounds", ylabel="mean PSF L1 error (2 = disjoint)", title=f"{n} x {n}, D/r0 = 5"
    )
    ax[0].legend()
    ax[1].set(xlabel="layout_psf time [s]", ylabel="|paint DOLP error|", yscale="log")
    ax[1].legend(fontsize=8)
    ctx.save_figure(fig, "perf_layout_frames")
    top = knob[-1]
    lines = []
    for F in frame_counts:
        r0 = next(r for r in rows if r["frames"] == F and r["rounds"] == 0)
        rp = next(
            r for r in rows if r["frames"] == F and r["layout"] == "pure" and r["rounds"] == top
        )
        rs = next(r for r in rows if r["frames"] == F and r["layout"] == "soft")
        lines.append(
            f"F = {F}: PSF L1 {r0['psf_l1_error']:.2f} (blind EM) -> {rp['psf_l1_error']:.2f} "
            f"(pure, {top} rounds; soft {rs['psf_l1_error']:.2f}); paint DOLP error "
            f"{rp['paint_dolp_error']:+.3f} (soft {rs['paint_dolp_error']:+.3f}); DOLP RMSE off the edges "
            f"{r0['dolp_rmse_off_edges']:.3f} -> {rp['dolp_rmse_off_edges']:.3f}; "
            f"{rp['time_ratio_to_blind_em']:.0f}x the blind EM's time."
        )
    ctx.say(" ".join(lines))

    def pick(F, layout, R):
        return next(
            r for r in rows if r["frames"] == F and r["layout"] == layout and r["rounds"] == R
        )

    Fm = max(frame_counts)
    r0, rp = pick(Fm, "blind EM", 0), pick(Fm, "pure", top)
    set_verdict(
        ctx,
        "own study",
        f"PSF L1 blind EM -> pure layout ({top} rounds): "
        + ", ".join(
            f"F = {F}: {pick(F, 'blind EM', 0)['psf_l1_error']:.2f} -> "
            f"{pick(F, 'pure', top)['psf_l1_error']:.2f}"
            for F in frame_counts
        )
        + f"; with F = {Fm}: paint DOLP error {rp['paint_dolp_error']:+.3f}, DOLP RMSE off the edges "
        f"{r0['dolp_rmse_off_edges']:.3f} -> {rp['dolp_rmse_off_edges']:.3f}, "
        f"{rp['time_ratio_to_blind_em']:.0f}x the blind EM's time",
    )
