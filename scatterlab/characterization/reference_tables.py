"""The reference text's published Tables 4 and 5 (painted aluminium and steel, 1550 nm; measured data).

Keys follow the pipeline's image names: ``no_turbulence``, ``D_r0_7.9_degraded``, ``D_r0_7.9_corrected``, ...
Table 4 rows: (fraction wrongly metal, wrongly dielectric, total, correlation coefficient, RMSE) at
theta_i = theta_r = 50 deg against the no-turbulence classification. Table 5 rows: (E[n], sd n, E[kappa],
sd kappa) per region (``paint`` and the bare ``metal``).
"""

TABLE4 = {
    "aluminium": {
        "D_r0_7.9_degraded": (0.0322, 0.0709, 0.0476, 0.9005, 0.2183),
        "D_r0_7.9_corrected": (0.0244, 0.0835, 0.0480, 0.8999, 0.2190),
        "D_r0_10.5_degraded": (0.0332, 0.0898, 0.0558, 0.8834, 0.2362),
        "D_r0_10.5_corrected": (0.0264, 0.0992, 0.0555, 0.8843, 0.2355),
        "D_r0_12.9_degraded": (0.0339, 0.0950, 0.0583, 0.8782, 0.2414),
        "D_r0_12.9_corrected": (0.0293, 0.0971, 0.0564, 0.8823, 0.2374),
    },
    "steel": {
        "D_r0_7.9_degraded": (0.0236, 0.0571, 0.0402, 0.9200, 0.2005),
        "D_r0_7.9_corrected": (0.0147, 0.0708, 0.0424, 0.9165, 0.2060),
        "D_r0_10.5_degraded": (0.0227, 0.0776, 0.0498, 0.9015, 0.2233),
        "D_r0_10.5_corrected": (0.0164, 0.0724, 0.0441, 0.9131, 0.2100),
        "D_r0_12.9_degraded": (0.0236, 0.0911, 0.0570, 0.8879, 0.2387),
        "D_r0_12.9_corrected": (0.0209, 0.0847, 0.0524, 0.8968, 0.2290),
    },
}

TABLE5 = {
    "aluminium": {
        "metal": {"no_turbulence": (3.8614, 1.487, 11.1757, 3.7652),
                  "D_r0_7.9_degraded": (4.1437, 1.1708, 11.9855, 2.8092),
                  "D_r0_12.9_degraded": (4.2454, 1.0718, 12.2713, 2.7750),
                  "D_r0_7.9_corrected": (3.9451, 1.2605, 11.3748, 3.1434),
                  "D_r0_12.9_corrected": (3.9762, 1.0008, 11.9791, 2.2400)},
        "paint": {"no_turbulence": (2.2467, 1.2717, 1.4073, 1.4859),
                  "D_r0_7.9_degraded": (2.2420, 1.2777, 1.5772, 1.9564),
                  "D_r0_12.9_degraded": (2.3074, 1.3033, 1.8434, 2.5221),
                  "D_r0_7.9_corrected": (1.2832, 0.30757, 0.68629, 0.14007),
                  "D_r0_12.9_corrected": (1.3586, 0.49623, 0.77617, 0.34729)},
    },
    "steel": {
        "metal": {"no_turbulence": (3.8649, 1.6921, 5.7123, 1.6088),
                  "D_r0_7.9_degraded": (4.4741, 1.1529, 6.3506, 1.0067),
                  "D_r0_12.9_degraded": (4.8632, 0.52165, 6.7198, 0.59269),
                  "D_r0_7.9_corrected": (4.6241, 1.2863, 4.6493, 1.3366),
                  "D_r0_12.9_corrected": (4.8465, 0.84901, 5.0693, 1.0472)},
        "paint": {"no_turbulence": (2.1424, 1.1946, 1.1951, 1.0491),
                  "D_r0_7.9_degraded": (2.3459, 1.2942, 1.4020, 1.6017),
                  "D_r0_12.9_degraded": (2.3819, 1.3459, 1.7714, 2.207),
                  "D_r0_7.9_corrected": (1.3290, 0.40899, 0.63531, 0.22920),
                  "D_r0_12.9_corrected": (1.3874, 0.67263, 0.74994, 0.65207)},
    },
}
