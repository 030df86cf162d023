"""Time to simulate a whole 4-channel 512 x 512 polarimetric scene (render, PSF from a fresh phase screen,
channels, noise, Stokes estimate) on this machine; goal: under a second (issue 7, item 8). Both modes
time the 512 x 512 scene (quick: best of 3, full: best of 5).

Full-mode run time (measured 24 Nov 2026, serial, load average 3.8-3.7 on the shared 2-core
machine): 5 s wall.
"""

from scatterlab.studies._common import set_verdict

from scatterlab.imaging import (
    ANGLES_0_45_90_135,
    channel_images,
    circular_pupil,
    detect,
    painted_plate,
    phase_screen,
    psf,
    render_stokes,
    stokes_from_channels,
)
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.runtime import Stopwatch, best_time

STUDY = {
    "id": "perf_scene",
    "title": "Whole 4-channel 512 x 512 scene simulation time",
    "reproduces": "own performance study",
}
GOAL_SIZE, GOAL_S = 512, 1.0  # issue 7, item 8


def run(ctx):
    size = GOAL_SIZE
    repeat = 3 if ctx.quick else 5
    n = size // 2
    scene = painted_plate(size, rng=0)
    pupil = circular_pupil(n, n / 2)
    phase_screen(n, 1.0, n / 10.5, 0)  # build the screen generator's cached weights once

    def simulate(sw=None):
        sw = sw or Stopwatch()
        with sw("render"):
            S = render_stokes(scene)
        with sw("psf"):
            h = psf(pupil, phase_screen(n, 1.0, n / 10.5, ctx.rng), pad=2)
        with sw("channels"):
            I = channel_images(S, ANGLES_0_45_90_135, h)
        with sw("noise"):
            counts = detect(I, ctx.rng, photons=2e4, read_noise=10, dark_current=5)
        with sw("stokes"):
            return stokes_from_channels(counts, ANGLES_0_45_90_135)

    with ctx.step("timing"):
        total = best_time(simulate, repeat=repeat)
        sw = Stopwatch()
        simulate(sw)
    ctx.metrics.update(
        {"size": size, "total_s": total, "steps_s": sw.times, "goal_met": total < GOAL_S}
    )
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(5, 3))
    ax.bar(list(sw.times), list(sw.times.values()))
    ax.set_ylabel("time [s]")
    ax.set_title(f"{size} x {size}, 4 channels: {total:.2f} s")
    ctx.save_figure(fig, "perf_scene")
    ctx.say(
        f"A whole 4-channel {size} x {size} scene takes {total:.2f} s (best of {repeat}; goal < "
        f"{GOAL_S:g} s at {GOAL_SIZE}: {'met' if total < GOAL_S else 'NOT met'}): "
        + ", ".join(f"{k} {v * 1e3:.0f} ms" for k, v in sw.times.items())
        + "."
    )
    slowest = max(sw.times, key=sw.times.get)
    set_verdict(
        ctx,
        "own study",
        f"4-channel {size} x {size} scene in {total:.2f} s (best of {repeat}; goal < {GOAL_S:g} s: "
        f"{'met' if total < GOAL_S else 'NOT met'}); slowest step {slowest} {sw.times[slowest] * 1e3:.0f} ms",
    )
