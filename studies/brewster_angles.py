"""Brewster and pseudo-Brewster angles of the catalogue materials at 1.064 and 1.55 um (table).

Lossless materials: Brewster angle arctan(n) (Eq. 85), where R_p = 0.
Absorbing materials: the pseudo-Brewster angle, the minimum of R_p, found by
bounded Brent minimisation; its R_p minimum is reported too. Own study (the
reference text uses these angles in Sec. 3.1.1 but tabulates none).

Run time, measured on the shared 2-core machine at load ~14: full 3 s.
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab import fresnel, materials

STUDY = {
    "id": "brewster",
    "title": "Brewster and pseudo-Brewster angles of the catalogue materials",
    "reproduces": "own study (Eq. 85 and the pseudo-Brewster angle of Sec. 3.1.1)",
}

WAVELENGTHS = (1.064e-6, 1.55e-6)


def run(ctx):
    rows = []
    names = [n for n in materials.names() if not n.startswith("ref:")]
    with ctx.step("angles"):
        for name in names:
            mat = materials.material(name)
            for wl in WAVELENGTHS:
                lo, hi = mat.wavelength_range
                if not lo <= wl <= hi:
                    continue
                eta = complex(materials.index(name, wl))
                if eta.imag == 0:
                    angle = float(fresnel.brewster_angle(eta.real))
                    kind = "Brewster"
                else:
                    angle = float(fresnel.pseudo_brewster_angle(eta))
                    kind = "pseudo-Brewster"
                rp_min = float(fresnel.reflectances(eta, angle)[1])
                rows.append(
                    {
                        "material": name,
                        "wavelength_um": wl * 1e6,
                        "n": eta.real,
                        "kappa": -eta.imag,
                        "kind": kind,
                        "angle_deg": np.degrees(angle),
                        "Rp_min": rp_min,
                        "source": mat.source,
                    }
                )
    ctx.metrics["table"] = rows
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.5))
    for k, (wl, colour) in enumerate(zip(WAVELENGTHS, ("C0", "C3"))):
        sel = [r for r in rows if r["wavelength_um"] == wl * 1e6]
        x = np.arange(len(sel)) + (k - 0.5) * 0.38
        ax.bar(x, [r["angle_deg"] for r in sel], 0.38, color=colour, label=f"{wl * 1e6:.3f} um")
        ax.set_xticks(np.arange(len(sel)), [r["material"] for r in sel], rotation=45, ha="right")
    ax.set(ylabel="(pseudo-)Brewster angle [deg]", ylim=(40, 90))
    ax.legend()
    ctx.save_figure(fig, "brewster")
    ctx.metrics["max_Rp_at_brewster_lossless"] = max(
        (r["Rp_min"] for r in rows if r["kind"] == "Brewster"), default=0.0
    )
    lines = [
        "| material | lambda [um] | n | kappa | angle | angle [deg] | R_p there |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['material']} | {r['wavelength_um']:.3f} | {r['n']:.4f} | {r['kappa']:.4f} | "
            f"{r['kind']} | {r['angle_deg']:.3f} | {r['Rp_min']:.2e} |"
        )
    ctx.say("\n".join(lines))
    ctx.say(
        "For the lossless dielectrics R_p vanishes at arctan(n) to rounding "
        f"(largest R_p there: {ctx.metrics['max_Rp_at_brewster_lossless']:.1e}). For metals the "
        "pseudo-Brewster angle lies close to grazing and R_p stays large, which is why specular DOLP "
        "separates metals from dielectrics (Ch. V). Data sources are listed in metrics.json."
    )

    def span(kind, key):
        vals = [r[key] for r in rows if r["kind"] == kind]
        return (min(vals), max(vals)) if vals else (float("nan"), float("nan"))

    b_lo, b_hi = span("Brewster", "angle_deg")
    p_lo, p_hi = span("pseudo-Brewster", "angle_deg")
    r_lo, r_hi = span("pseudo-Brewster", "Rp_min")
    set_verdict(
        ctx,
        "own study",
        f"{len(rows)} material/wavelength rows: Brewster {b_lo:.1f}-{b_hi:.1f} deg (lossless, largest R_p "
        f"there {ctx.metrics['max_Rp_at_brewster_lossless']:.1e}); pseudo-Brewster {p_lo:.1f}-{p_hi:.1f} deg "
        f"(absorbing, R_p minimum {r_lo:.2g}-{r_hi:.2g})",
    )
