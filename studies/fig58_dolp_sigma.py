"""Fig. 58: DOLP vs roughness sigma for glass (1.5) and iron (3.6 - j5.9) at specular angles 30-60 deg.

The text calls the effect of sigma on the specular DOLP "small". The study measures it over the
plotted range (sigma 0.05-0.6) and over the range of the text's own samples (sigma < 1 deg of rms
slope, sigma < tan 1 deg = 0.0175), and states which holds. The text gives no numbers for the curves,
so the comparison is qualitative. Run time, measured on the shared 2-core machine at load ~14: full 3.5 s.
"""

import numpy as np
from scatterlab.studies._common import rms_slope_from_degrees, set_verdict

from scatterlab.pbrdf import Model
from scatterlab.plotting import headless_pyplot as plt

STUDY = {
    "id": "fig58",
    "title": "DOLP vs roughness at specular geometries (glass, iron)",
    "reproduces": "Fig. 58 (Sec. 7.3)",
}


def run(ctx):
    sigma = np.linspace(0.05, 0.6, 12 if ctx.quick else 111)
    angles = np.radians(np.arange(30, 61, 5))
    pyplot = plt()
    fig, axes = pyplot.subplots(1, 2, figsize=(11, 4))
    model = Model(sigma[:, None])
    for ax, (name, eta) in zip(axes, (("glass", 1.5 + 0j), ("iron", 3.6 - 5.9j))):
        with ctx.step(name):
            d = model.dolp(eta, angles[None, :], angles[None, :])  # (sigma, angle)
        for k, a in enumerate(angles):
            ax.plot(sigma, d[:, k], label=f"{np.degrees(a):.0f} deg")
        ax.set(title=name, xlabel=r"roughness $\sigma$", ylabel="DOLP")
        spread_sigma = np.max(d.max(axis=0) - d.min(axis=0))
        spread_angle = np.max(d.max(axis=1) - d.min(axis=1))
        ctx.metrics[f"max_dolp_change_over_sigma_{name}"] = float(spread_sigma)
        ctx.metrics[f"max_dolp_change_over_angle_{name}"] = float(spread_angle)
    axes[0].legend(fontsize=7)
    ctx.save_figure(fig, "fig58")
    m = ctx.metrics
    small = Model(np.array([1e-3, rms_slope_from_degrees(1.0)])[:, None])
    lines = []
    for name, eta in (("glass", 1.5 + 0j), ("iron", 3.6 - 5.9j)):
        d30 = model.dolp(eta, angles[:1], angles[:1])[[0, -1], 0]
        ds = small.dolp(eta, angles[None, :], angles[None, :])
        m[f"dolp_30deg_{name}_sigma_{sigma[0]:.2f}"] = float(d30[0])
        m[f"dolp_30deg_{name}_sigma_{sigma[-1]:.2f}"] = float(d30[1])
        m[f"max_dolp_change_sigma_below_1deg_{name}"] = float(np.max(np.abs(ds[1] - ds[0])))
        lines.append(
            f"{name}: at 30 deg the DOLP goes from {d30[0]:.3f} (sigma {sigma[0]:.2f}) to "
            f"{d30[1]:.3f} (sigma {sigma[-1]:.2f}), {abs(d30[1] / d30[0] - 1):.0%} relative; the "
            f"largest change over all angles is {m[f'max_dolp_change_over_sigma_{name}']:.3f} "
            f"against {m[f'max_dolp_change_over_angle_{name}']:.3f} across the angles 30-60 deg; "
            f"for sigma below 1 deg of slope (the text's samples) at most "
            f"{m[f'max_dolp_change_sigma_below_1deg_{name}']:.1e}"
        )
    big = max(m["max_dolp_change_over_sigma_glass"], m["max_dolp_change_over_sigma_iron"])
    tiny = max(
        m["max_dolp_change_sigma_below_1deg_glass"], m["max_dolp_change_sigma_below_1deg_iron"]
    )
    ctx.say(
        "; ".join(lines)
        + ". The text calls the effect of sigma on the specular DOLP small: "
        + (
            f"that holds for its own highly specular samples (change <= {tiny:.1e}), NOT over "
            f"the plotted range, where the DOLP changes by up to {big:.2f} -- at 30 deg the "
            "glass DOLP drops by a large fraction as the diffuse term grows with sigma. "
            if big > 0.05
            else f"it holds over the whole plotted range (change <= {big:.3f}). "
        )
        + "Either way a specular-only sweep constrains sigma weakly where sigma is small, which "
        "is why the text recommends off-specular sweeps (see the inversion's experiment design)."
    )
    set_verdict(
        ctx,
        "partly",
        f"curves computed (no published numbers); sigma 0.05-0.6 changes DOLP by up to {big:.2f} "
        f"(text: 'small'); sigma < 1 deg by <= {tiny:.1e}",
    )
