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


BATCHES = 10  # independent batches of screens for the statistical error of the structure function


def _error(screens, dx, r0):
    """Largest relative error of the structure function, 1 px to half the screen, and the statistical
    standard error at that separation (spread of BATCHES independent batches of screens)."""
    n = screens.shape[-1]
    r, D = T.structure_function(screens, n // 2)
    theory = T.STRUCTURE_CONSTANT * (r[1:] * dx / r0) ** (5 / 3)
    rel = D[1:] / theory - 1
    batch = np.array(
        [T.structure_function(b, n // 2)[1][1:] for b in np.array_split(screens, BATCHES)]
    )
    se = batch.std(0, ddof=1) / np.sqrt(BATCHES) / theory
    j = int(np.argmax(np.abs(rel)))
    return float(abs(rel[j])), float(se[j])


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
                err, se = _error(s, dx, r0)
            finally:
                T.SUBHARMONIC_LEVELS = old
            rows.append(
                {
                    "levels": levels,
                    "max_rel_error_2px_to_half": err,
                    "statistical_se": se,
                    "time_s": t,
                }
            )
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
            err, se = _error(s, dx, r0)
            sizes.append(
                {"n": n, "max_rel_error_2px_to_half": err, "statistical_se": se, "time_s": t}
            )
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
            f"{r['levels']} levels: max error {r['max_rel_error_2px_to_half']:.3f} "
            f"(+- {r['statistical_se']:.3f}) in {r['time_s'] * 1e3:.1f} ms"
            for r in rows
        )
        + " (the largest |D / theory - 1| over the separations, with the statistical standard error of the "
        f"estimate at that separation, from {BATCHES} independent batches of the screens: an error within "
        "two or three of them is the estimate's, not the generator's). Screen sizes (default levels): "
        + ", ".join(
            f"{s['n']} px: {s['max_rel_error_2px_to_half']:.3f} (+- {s['statistical_se']:.3f}) in "
            f"{s['time_s'] * 1e3:.1f} ms"
            for s in sizes
        )
        + "."
    )
    beyond = [r["levels"] for r in rows if r["max_rel_error_2px_to_half"] > 3 * r["statistical_se"]]
    ctx.say(
        "Beyond three standard errors (a real deficit of the large scales): "
        + (", ".join(f"{x} levels" for x in beyond) if beyond else "none")
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
