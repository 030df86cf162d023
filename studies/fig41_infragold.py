"""Fig. 41: Mueller elements of LabSphere Infragold (gold, 0.285 - j7.3523, roughness 0.44) at 1.064 um,
synthetic measurements through an ECM-calibrated imperfect ellipsometer, against the pBRDF; best-fit index.

Full-mode run time (measured 24 Nov 2026, serial, load average 1.2-1.1 on the shared 2-core
machine): 4 s wall.
"""

from scatterlab.studies._common import mueller_figure_study

STUDY = {
    "id": "fig41",
    "title": "Mueller elements of Infragold: synthetic ECM measurement and pBRDF fit",
    "reproduces": "Fig. 41 (Sec. 4.4)",
}


def run(ctx):
    mueller_figure_study(
        ctx, 0.285 - 7.3523j, 0.44, "fig41", "0.4364 - j5.2526", "LabSphere Infragold"
    )
