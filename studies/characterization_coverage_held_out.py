"""Coverage of the main job's region posteriors on a scene the error model was not calibrated on.

The blind self-calibration's error fractions (``self_calibration.REFERENCE_RATIO_COMMON_FRACTION``,
``REFERENCE_RATIO_TREND_FRACTION`` and ``REFERENCE_RATIO_TREND_CORRELATION``) were measured on the trials of
``studies/characterization_coverage.py``: four specular angles 30-60 deg, D/r0 7.9 and 12.9. A user's scene
has its own angles and turbulence. This study runs the same trials (a plate drawn per seed: one of five
metals, a paint with n in [1.3, 1.7] and kappa in [0.05, 0.6], its own scratches, screens and noise) on a
scene held out from that calibration: five angles 35-75 deg, which reach past the paint's Brewster angle and
foreshorten the plate to a quarter of its height, and a D/r0 of 10.5, between the two calibrated ones. The
table and verdict read as the calibration study's. Full mode: 24 seeds, 603 s on 2 cores (28 Nov 2026); quick
mode: 2 seeds (recorded, not judged).

Runs of 28 Nov 2026 (24 seeds each), 68 % / 95 % coverage, seed 20101210 and seed 7 (pooled, 48 trials):

| family | seed 20101210 | seed 7 | pooled |
|---|---|---|---|
| corrected paint n | 0.88 / 1.00 | 0.75 / 0.92 | 0.81 / 0.96 |
| corrected paint kappa | 0.75 / 1.00 | 0.75 / 0.96 | 0.75 / 0.98 |
| corrected paint joint | 0.92 / 1.00 | 0.75 / 0.88 | 0.83 / 0.94 |
| no-turbulence paint n | 0.79 / 0.96 | 0.88 / 0.92 | 0.83 / 0.94 |
| no-turbulence paint kappa | 0.88 / 0.96 | 0.92 / 1.00 | 0.90 / 0.98 |
| no-turbulence paint joint | 0.88 / 0.92 | 0.83 / 0.92 | 0.85 / 0.92 |

No family under-covers on either seed: every family outside its band is above it (seed 20101210: 9 of 12,
seed 7: 4 of 12, the metals' among them, whose intervals follow the prior along the ridge of equal DOLP).
The corrected paint's standardised errors (truth minus median, over the 68 % half-width) have rms 0.56 (n)
and 0.73 (kappa) on seed 20101210, 1.01 and 0.87 on seed 7. On this scene the intervals are honest to
conservative. The one large miss: a no-turbulence paint n on seed 7 (gold, paint n 1.57) at 4.7
half-widths, its DOLP at 75 deg 0.0025 above the truth against a stated error of 0.0005 -- the known-PSF
calibration's error at the most foreshortened geometry, beside a bright metal, can be too small. (Seed 7 ran
through this study's functions outside the runner, two worker processes, 1300 s beside other jobs.)

The cause of that miss was the edge term: the data's edge shift minus the re-simulations', taken per geometry
as a magnitude, was near 0 at 75 deg in that trial by chance. Since session 28 it enters as its rms over the
geometries (:mod:`scatterlab.characterization.self_calibration`). Seed 7 re-run with it (the runner,
``--workers 2``, 448 s), 68 % / 95 %: no-turbulence paint n 0.83 / 1.00 (was 0.88 / 0.92), its standardised
errors rms 0.69 and at most 1.47 half-widths (was 1.18 and 4.74); kappa 0.96 / 1.00 (was 0.92 / 1.00, rms
0.45), joint 0.92 / 1.00. The corrected families are unchanged (0.75 / 0.92, 0.75 / 0.96, 0.75 / 0.88). No
family under-covers; four over-cover (the no-turbulence paint's kappa and joint region, the metals' joint
regions).
"""

from scatterlab.studies.characterization_coverage import run_coverage

STUDY = {
    "id": "characterization_coverage_held_out",
    "title": "Coverage of the characterization posteriors on a held-out scene",
    "reproduces": "ours: honest uncertainty of the main job beyond its calibration scene",
}

GEOMETRY_DEG = [35, 45, 55, 65, 75]
D_OVER_R0 = [10.5]


def run(ctx):
    run_coverage(ctx, GEOMETRY_DEG, D_OVER_R0)
