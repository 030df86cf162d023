"""Fig. 27: DHR of the (unshadowed) Priest-Germer pBRDF for PEC surfaces of 1, 5 and 15 deg rms slope.

The reference integrates the unshadowed model over the whole sphere (its DHR then counts light "scattered
below the surface"). We show that closed form, Phi(cot/sigma) + sigma tan(theta) phi(cot/sigma), and the
upper-hemisphere integral (Eq. 174 with G = 1) by quadrature. Roughness "n deg rms slope" is read as the
per-axis rms slope sigma = tan(n deg).

Run time, measured on the shared 2-core machine at load ~14: quick 12 s, full 6 s.
"""

import numpy as np
from scatterlab.studies._common import rms_slope_from_degrees, set_verdict

from scatterlab.pbrdf import dhr_beckmann, dhr_sphere_unshadowed
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "fig27",
    "title": "DHR of the unshadowed Priest-Germer pBRDF (PEC)",
    "reproduces": "Fig. 27 (Sec. 3.2.3)",
}


def run(ctx):
    theta = np.radians(np.linspace(0, 89.5, 60 if ctx.quick else 360))
    degs = (1, 5, 15)
    pyplot = plt()
    fig, ax = pyplot.subplots(figsize=(6, 4))
    for deg in degs:
        sigma = rms_slope_from_degrees(deg)
        with ctx.step(f"sphere_{deg}deg"):
            sphere = dhr_sphere_unshadowed(theta, sigma)
        with ctx.step(f"hemisphere_{deg}deg"):
            hemi = dhr_beckmann(theta, sigma, "none")
        (line,) = ax.plot(np.degrees(theta), sphere, label=f"{deg} deg, whole sphere")
        ax.plot(
            np.degrees(theta),
            hemi,
            "--",
            color=line.get_color(),
            label=f"{deg} deg, upper hemisphere",
        )
        above = theta[sphere > 1.01]
        ctx.metrics[f"sigma_{deg}deg"] = sigma
        ctx.metrics[f"dhr_sphere_at_60deg_{deg}deg"] = float(
            dhr_sphere_unshadowed(np.radians(60), sigma)
        )
        ctx.metrics[f"dhr_sphere_at_85deg_{deg}deg"] = float(
            dhr_sphere_unshadowed(np.radians(85), sigma)
        )
        ctx.metrics[f"angle_dhr_exceeds_1.01_{deg}deg"] = (
            float(np.degrees(above[0])) if above.size else None
        )
        ctx.metrics[f"max_hemisphere_minus_sphere_{deg}deg"] = float(np.max(hemi - sphere))
    ax.axhline(1, color="k", lw=0.5)
    ax.set(
        xlabel=r"$\theta_i$ [deg]",
        ylabel="DHR",
        ylim=(0.8, 3),
        xlim=(0, 90),
        title="Unshadowed Priest-Germer pBRDF, PEC (Fig. 27)",
    )
    ax.legend(fontsize=7)
    ctx.save_figure(fig, "fig27")
    ctx.say(
        "As in Fig. 27, the DHR of the unshadowed model is 1 at small angles and grows without bound towards "
        f"grazing incidence: it exceeds 1.01 beyond {ctx.metrics['angle_dhr_exceeds_1.01_15deg']:.1f} deg for "
        f"15 deg roughness and {ctx.metrics['angle_dhr_exceeds_1.01_1deg']:.1f} deg for 1 deg roughness, the "
        "rougher surface diverging earlier. The whole-sphere closed form is never below the upper-hemisphere "
        "integral (the difference is the light the model sends below the horizon). The model does not "
        "conserve energy, which motivates the shadowing function of Sec. 3.2.3."
    )
    m = ctx.metrics
    a15, a1 = m["angle_dhr_exceeds_1.01_15deg"], m["angle_dhr_exceeds_1.01_1deg"]
    ok = a15 is not None and (a1 is None or a15 < a1)
    set_verdict(
        ctx,
        "reproduced" if ok else "not reproduced",
        "unshadowed DHR > 1.01 beyond "
        + " and ".join("never" if a is None else f"{a:.1f} deg" for a in (a15, a1))
        + " (15 deg, 1 deg roughness); "
        "qualitative (no published numbers)",
    )
