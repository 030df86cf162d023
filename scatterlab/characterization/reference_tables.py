"""The reference text's published Tables 4 and 5 (painted aluminium and steel, 1550 nm; measured).

Read from the shipped CSV files (:mod:`scatterlab.reference_data`, ``data/reference/`` in the
repository), arranged by the pipeline's image names: ``no_turbulence``, ``D_r0_7.9_degraded``,
``D_r0_7.9_corrected``, ...

``TABLE4[sample][image]``: (fraction wrongly metal, wrongly dielectric, total, correlation
coefficient, RMSE) at theta_i = theta_r = 50 deg against the no-turbulence classification. The
text's columns 1-2 are normalised by the size of the true class, not by all pixels (see
``table4_classification.csv``). ``TABLE5[sample][region][image]``: (E[n], sd n, E[kappa], sd kappa)
per region (``paint`` and the bare ``metal``).
"""

from __future__ import annotations

from scatterlab.reference_data import table

__all__ = ["TABLE4", "TABLE5", "image_key"]


def image_key(image: str, d_over_r0: float) -> str:
    """The pipeline's name of an image: ``"no_turbulence"`` or ``"D_r0_<D/r0>_<image>"``.

    Parameters
    ----------
    image : str
        ``"no_turbulence"``, ``"degraded"`` or ``"corrected"``.
    d_over_r0 : float
        Turbulence strength.

    Returns
    -------
    str
    """
    return "no_turbulence" if image == "no_turbulence" else f"D_r0_{d_over_r0:g}_{image}"


def _table4() -> dict:
    out: dict = {}
    for r in table("table4_classification").rows():
        out.setdefault(r["sample"], {})[image_key(r["image"], r["d_over_r0"])] = (
            r["frac_wrong_metal"],
            r["frac_wrong_dielectric"],
            r["frac_wrong_total"],
            r["correlation"],
            r["rmse"],
        )
    return out


def _table5() -> dict:
    out: dict = {}
    for r in table("table5_characterization").rows():
        out.setdefault(r["sample"], {}).setdefault(r["region"], {})[
            image_key(r["image"], r["d_over_r0"])
        ] = (r["n_mean"], r["n_sd"], r["kappa_mean"], r["kappa_sd"])
    return out


TABLE4 = _table4()
TABLE5 = _table5()
