"""Phase screens: subharmonic levels and screen size vs structure-function error vs time, and speed against
AOtools' ft_sh_phase_screen at 256 and 512 pixels (same run).

Full-mode run time (measured 24 Nov 2026, serial, load average 3.3-2.6 on the shared 2-core
machine): 60 s wall.
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.imaging import turbulence as T
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.runtime import best_time

STUDY = {
    "id": "perf_phase_screens",
    "title": "Phase screens: accuracy vs time; speed vs AOtools",
    "reproduces": "own performance study",
}


def run(ctx):
    dx, r0 = 0.01, 0.1
    count = 200 if ctx.quick else 1500
    rows = []
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6, 4))
    with ctx.step("levels"):
        for levels in (0, 1, 3, 5):
            old = T.SUBHARMONIC_LEVELS
            T.SUBHARMONIC_LEVELS = max(levels, 1)
            try:
                n = 64
                kw = {"subharmonics": levels > 0}
                T.phase_screen(n, dx, r0, 0, **kw)  # build the cached weights outside the timing
                t = best_time(lambda: T.phase_screen(n, dx, r0, ctx.rng, **kw), repeat=5)
                s = np.stack([T.phase_screen(n, dx, r0, ctx.rng, **kw) for _ in range(count)])
                r, D = T.structure_function(s, n // 2)
                err = float(
                    np.max(
                        np.abs(D[1:] / (T.STRUCTURE_CONSTANT * (r[1:] * dx / r0) ** (5 / 3)) - 1)
                    )
                )
            finally:
                T.SUBHARMONIC_LEVELS = old
            rows.append({"levels": levels, "max_rel_error_2px_to_half": err, "time_s": t})
            ax.loglog(t, err, "o")
            ax.annotate(f"{levels} levels", (t, err), fontsize=7)
    sizes = []
    with ctx.step("sizes"):
        for n in (32, 64, 128) if ctx.quick else (32, 64, 128, 256):
            T.phase_screen(n, dx, r0, 0)
            t = best_time(lambda: T.phase_screen(n, dx, r0, ctx.rng), repeat=5)
            s = np.stack(
                [T.phase_screen(n, dx, r0, ctx.rng) for _ in range(max(50, count * 64 // n))]
            )
            r, D = T.structure_function(s, n // 2)
            err = float(
                np.max(np.abs(D[1:] / (T.STRUCTURE_CONSTANT * (r[1:] * dx / r0) ** (5 / 3)) - 1))
            )
            sizes.append({"n": n, "max_rel_error_2px_to_half": err, "time_s": t})
            ax.loglog(t, err, "s", color="C3")
            ax.annotate(f"{n} px", (t, err), fontsize=7, color="C3")
    ctx.metrics["sizes"] = sizes
    ax.set(
        xlabel="time per screen [s]",
        ylabel="max |D/theory - 1|, 2 px to D/2",
        title="subharmonic levels (64 px) and screen sizes",
    )
    ctx.save_figure(fig, "perf_phase_screens")
    speed = {}
    try:
        from aotools.turbulence.phasescreen import ft_sh_phase_screen
    except ImportError:
        ft_sh_phase_screen = None
    with ctx.step("speed"):
        for n in (256, 512):
            T.phase_screen(n, dx, r0, 0)
            ours = best_time(lambda: T.phase_screen(n, dx, r0, ctx.rng), repeat=5)
            entry = {"ours_s": ours}
            if ft_sh_phase_screen is not None:
                peer = best_time(lambda: ft_sh_phase_screen(r0, n, dx, 1e6, 1e-10), repeat=5)
                entry.update(peer_s=peer, speedup=peer / ours)
            speed[n] = entry
    ctx.metrics.update({"levels": rows, "speed": speed})
    ctx.say(
        "Accuracy against time (64 px, "
        + f"{count} screens): "
        + ", ".join(
            f"{r['levels']} levels: max error {r['max_rel_error_2px_to_half']:.3f} in {r['time_s'] * 1e3:.1f} ms"
            for r in rows
        )
        + " (the error includes the statistical error of the estimate, a few per cent). "
        "Screen sizes (default levels): "
        + ", ".join(
            f"{s['n']} px: {s['max_rel_error_2px_to_half']:.3f} in {s['time_s'] * 1e3:.1f} ms"
            for s in sizes
        )
        + "."
    )
    headline = "64 px, largest relative error of D vs theory: " + ", ".join(
        f"{r['levels']} levels {r['max_rel_error_2px_to_half']:.3f}" for r in rows
    )
    if all("speedup" in v for v in speed.values()):
        headline += "; vs AOtools ft_sh_phase_screen " + ", ".join(
            f"{n} px {v['speedup']:.1f}x" for n, v in speed.items()
        )
    else:
        headline += "; AOtools not installed, no peer ratio"
    set_verdict(ctx, "own study", headline)
    if all("speedup" in v for v in speed.values()):
        ctx.say(
            "Speed against AOtools' ft_sh_phase_screen (same run): "
            + ", ".join(
                f"{n} px: {v['ours_s'] * 1e3:.1f} ms vs {v['peer_s'] * 1e3:.1f} ms (x{v['speedup']:.1f})"
                for n, v in speed.items()
            )
            + "."
        )
    else:
        ctx.say(
            "AOtools is not installed: speeds are ours only: "
            + ", ".join(f"{n} px: {v['ours_s'] * 1e3:.1f} ms" for n, v in speed.items())
            + "."
        )
