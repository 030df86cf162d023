"""Fig. 42: Mueller elements of flame-sprayed aluminium (1.226 - j10.413, roughness 0.43) at 1.064 um,
synthetic measurements through an ECM-calibrated imperfect ellipsometer, against the pBRDF; best-fit index.

Full-mode run time (measured 24 Nov 2026, serial, load average 1.1-1.2 on the shared 2-core
machine): 4 s wall.
"""

from scatterlab.studies._common import mueller_figure_study

STUDY = {
    "id": "fig42",
    "title": "Mueller elements of flame-sprayed aluminium: synthetic ECM measurement and fit",
    "reproduces": "Fig. 42 (Sec. 4.4)",
}


def run(ctx):
    mueller_figure_study(
        ctx, 1.226 - 10.413j, 0.43, "fig42", "0.8886 - j3.4602", "flame-sprayed aluminium"
    )
