"""Fig. 44: DOLP over the hemisphere (theta_r, phi) for Al, Fe, glass and Teflon at 1550 nm, theta_i = 45 deg,
roughness 0.1 and 0.6, with the shadowed pBRDF and its diffuse term (Eq. 177); plus a pyvista 3-D lobe.

Indices as in the figure caption: Al 1.44 - j16, Fe 3.60 - j5.88, glass 1.44, Teflon 1.35.

Run time, measured on the shared 2-core machine at load ~14: quick 37 s, full 38 s.
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab import materials
from scatterlab.pbrdf import Model
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.plotting import pbrdf_lobe_png, polar_contour

STUDY = {
    "id": "fig44",
    "title": "DOLP over the hemisphere for Al, Fe, glass, Teflon at 1550 nm",
    "reproduces": "Fig. 44 (Sec. 5.2.2)",
}

MATERIALS = {
    "Al": "ref:al_1550",
    "Fe": "ref:fe_1550",
    "glass": "ref:glass_1550",
    "Teflon": "ref:teflon_1550",
}


def run(ctx):
    ti = np.radians(45)
    tr = np.radians(np.linspace(0, 89, 46 if ctx.quick else 179))
    phi = np.linspace(0, 2 * np.pi, 73 if ctx.quick else 361)
    TR, PH = np.meshgrid(tr, phi, indexing="ij")
    pyplot = plt()
    fig, axes = pyplot.subplots(2, 4, subplot_kw={"projection": "polar"}, figsize=(15, 7.5))
    for col, (name, key) in enumerate(MATERIALS.items()):
        eta = materials.index(key, 1.55e-6)
        for row, sigma in enumerate((0.1, 0.6)):
            with ctx.step(f"{name}_{sigma}"):
                d = Model(sigma).dolp(eta, ti, TR, PH)
            ax = axes[row, col]
            polar_contour(tr, phi, d, ax=ax, levels=np.linspace(0, 1, 21), vmin=0, vmax=1)
            ax.set_title(f"{name}, roughness {sigma}", fontsize=9)
            k = np.unravel_index(np.argmax(d), d.shape)
            ctx.metrics[f"max_dolp_{name}_{sigma}"] = float(d[k])
            ctx.metrics[f"theta_r_of_max_{name}_{sigma}"] = float(np.degrees(tr[k[0]]))
            ctx.metrics[f"phi_of_max_deg_{name}_{sigma}"] = float(np.degrees(phi[k[1]]))
    import matplotlib as mpl

    fig.colorbar(
        mpl.cm.ScalarMappable(norm=mpl.colors.Normalize(0, 1), cmap="viridis"),
        ax=axes,
        shrink=0.6,
        label="DOLP",
    )
    ctx.save_figure(fig, "fig44")
    with ctx.step("lobe_3d"):
        try:
            pbrdf_lobe_png(
                Model(0.3),
                materials.index("ref:glass_1550", 1.55e-6),
                ti,
                ctx.out / "lobe_3d.png",
                n_theta=45 if ctx.quick else 90,
                n_phi=90 if ctx.quick else 180,
                title="glass, roughness 0.3, theta_i = 45 deg: F00 lobe coloured by DOLP",
            )
            ctx.add_image("lobe_3d")
            ctx.metrics["lobe_3d_rendered"] = True
        except Exception as exc:  # no OpenGL context: report it instead of failing the study
            ctx.metrics["lobe_3d_rendered"] = False
            ctx.say(f"The pyvista rendering failed on this machine: {type(exc).__name__}: {exc}")
    m = ctx.metrics
    metal_max = max(m[f"max_dolp_{n}_{s}"] for n in ("Al", "Fe") for s in (0.1, 0.6))
    ctx.say(
        f"Dielectrics: the largest DOLP is {m['max_dolp_glass_0.1']:.4f} (glass) and {m['max_dolp_Teflon_0.1']:.4f} "
        f"(Teflon) at theta_r = {m['theta_r_of_max_glass_0.1']:.0f} and {m['theta_r_of_max_Teflon_0.1']:.0f} deg "
        "in the specular plane for roughness 0.1 -- the reference reports 'approximately 1 ... at an observation "
        "angle of approximately 60 deg' (Brewster: beta = (45 + 65)/2 ~ arctan(1.44) = 55 deg). Diffuse "
        f"scattering keeps it below 1. Metals stay below {metal_max:.2f} everywhere (the "
        f"reference: a metal prior extending to 0.3). "
        "For roughness 0.6 the DOLP spreads out of the specular plane and loses magnitude "
        f"(glass max {m['max_dolp_glass_0.6']:.2f}), as the reference describes."
    )
    g, t = m["max_dolp_glass_0.1"], m["theta_r_of_max_glass_0.1"]
    ok = g > 0.9 and abs(t - 60) <= 10 and metal_max <= 0.3
    set_verdict(
        ctx,
        "reproduced" if ok else "partly",
        f"glass max DOLP {g:.3f} at theta_r {t:.0f} deg (text: ~1 at ~60 deg); metals <= "
        f"{metal_max:.2f} (text: <= 0.3)",
    )
