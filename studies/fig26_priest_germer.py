"""Fig. 26: the Priest-Germer pBRDF (Eq. 134) in-plane at the specular angle for Enhanced Martin
Black and LabSphere Infragold at 3.39 um, normalised Mueller elements against angle.

The text (Sec. 3.2.2) gives neither index nor roughness, and the measured points exist only in the
printed figure (Priest and Meier, Opt. Eng. 41, 988 (2002), their Ref. [104]), so the study
computes the model curves with parameters chosen and cited here, and cannot compare with the data.

Parameters and where they come from (deviations from the unknown published ones):

* **Roughness: not needed.** At the specular geometry (theta_i = theta_r, phi = pi) the facet
  normal is the mean normal and the facet angle is theta_i, so Eq. 134's normalised elements
  m_jk / m_00 are those of smooth Fresnel reflection at theta_i for every sigma (the slope density
  and the 1/cos factors cancel in the ratio). The study measures this (sigma 0.05-1.0).
* **Infragold (gold overcoat):** gold at 3.39 um from Ordal et al., Appl. Opt. 24, 4493 (1985)
  and 26, 744 (1987) (refractiveindex.info main/Au/Ordal, linear between 3.33 um
  (1.52 - j24.1) and 3.64 um (1.81 - j26.3)): eta = 1.576 - j24.53. Band: the other gold data at
  3.39 um in the same database, Olmon et al. 2012 (1.41 - j23.37), Babar and Weaver 2015
  (0.675 - j23.13), Rakic et al. 1998 (2.02 - j21.02). (The text's gold index 0.285 - j7.35 of
  Fig. 41 is for 1.064 um.)
* **Enhanced Martin Black:** the first surface is the anodic aluminium oxide, which reflects like
  a dielectric (the dye absorbs what enters; the text: light "leaves the surface after a single
  bounce", the rest is absorbed). Index: sapphire, ordinary ray, Malitson's Sellmeier formula at
  3.39 um (:func:`scatterlab.materials.index` ``"Al2O3"``, 1.699), kappa = 0. Band: n 1.4-1.8
  and kappa 0-0.2 for a porous, dyed anodic film (no published value found). Assumption, not
  a published parameter.
* **The dissertation's own pBRDF** (Eq. 177, shadowing and diffuse term) for Infragold with the
  rms slope sigma = 0.44 of Fig. 41 (same LabSphere Infragold product; geometric-optics slopes do
  not depend on the wavelength) is drawn beside it, to show what a diffuse term does to the
  specular Mueller elements, which the text invokes to explain the Infragold discrepancy.

Independent checks: the normalised Priest-Germer elements against the smooth Fresnel Mueller
matrix (:func:`scatterlab.fresnel.mueller_matrix`); physical realizability (Cloude coherency
matrix positive semi-definite, rank one: a pure Jones reflection, so
(M01^2 + M22^2 + M23^2) / M00^2 = 1 and depolarization index 1); Brewster's angle arctan(n) where
M01/M00 = 1 for the dielectric; the principal angle (M22 = 0) of the metal.

Run time (quick 86 angles, full 341; the rest is the same) on the shared 2-core machine: quick
2.4 s near idle, full 3.6 s at load ~7.
"""

import numpy as np
from scatterlab.studies._common import set_verdict

from scatterlab.fresnel import brewster_angle, mueller_matrix
from scatterlab.materials import index
from scatterlab.pbrdf import Model
from scatterlab.plotting import headless_pyplot as plt
from scatterlab.polarization import coherency_matrix

STUDY = {
    "id": "fig26",
    "title": "Priest-Germer pBRDF Mueller elements at the specular angle, Martin Black and Infragold",
    "reproduces": "Fig. 26 (Sec. 3.2.2)",
}

WAVELENGTH = 3.39e-6
GOLD_ORDAL = 1.576 - 24.53j
GOLD_BAND = {"Olmon 2012": 1.41 - 23.37j, "Babar 2015": 0.675 - 23.13j, "Rakic 1998": 2.02 - 21.02j}
BLACK_BAND = [n - 1j * k for n in (1.4, 1.8) for k in (0.0, 0.2)]
INFRAGOLD_SIGMA = 0.44  # Fig. 41's rms slope of LabSphere Infragold
SIGMAS = (0.05, 0.44, 1.0)
NAMES = ("M01/M00", "M11/M00", "M22/M00", "M23/M00")
ELEMENTS = ((0, 1), (1, 1), (2, 2), (2, 3))


def normalised(M):
    """In-plane normalised elements of Mueller matrices.

    Parameters
    ----------
    M : array (..., 4, 4)

    Returns
    -------
    ndarray (..., 4)
        ``(M01, M11, M22, M23) / M00``.
    """
    return np.stack([M[..., j, k] / M[..., 0, 0] for j, k in ELEMENTS], -1)


def priest_germer(eta, theta, sigma):
    """Eq. 134 (no shadowing, no diffuse term) at theta_i = theta_r = ``theta``, phi = pi.

    Parameters
    ----------
    eta : complex
    theta : array (N,) [rad]
    sigma : float
        Per-axis rms slope.

    Returns
    -------
    ndarray (N, 4, 4)
        Mueller BRDF [1/sr].
    """
    return Model(sigma, shadowing="none", diffuse="none").mueller(eta, theta, theta, np.pi)


def realizability(M):
    """Physical-realizability measures of Mueller matrices.

    Parameters
    ----------
    M : array (..., 4, 4)

    Returns
    -------
    dict
        ``min_eig``: the smallest coherency eigenvalue relative to the trace (>= 0 for a physical
        matrix); ``second_eig``: the second largest relative to the trace (0 for a pure Jones
        matrix); ``depolarization_index``: Gil-Bernabeu index (1: non-depolarizing), min over
        the matrices; ``pure_identity``: max |(M01^2 + M22^2 + M23^2)/M00^2 - 1|.
    """
    H = coherency_matrix(M)
    ev = np.linalg.eigvalsh(H) / np.trace(H, axis1=-2, axis2=-1).real[..., None]
    di = np.sqrt(((M**2).sum((-2, -1)) - M[..., 0, 0] ** 2) / (3 * M[..., 0, 0] ** 2))
    N = normalised(M)
    return {
        "min_eig": float(ev[..., 0].min()),
        "second_eig": float(ev[..., -2].max()),
        "depolarization_index": float(di.min()),
        "pure_identity": float(np.abs(N[..., 0] ** 2 + N[..., 2] ** 2 + N[..., 3] ** 2 - 1).max()),
    }


def _checks(ctx, materials, theta):
    """The Fresnel identity for every sigma, realizability, Brewster and principal angles."""
    fres_err, real = 0.0, {}
    for name, eta in materials.items():
        fres = normalised(mueller_matrix(eta, theta))
        for s in SIGMAS:
            fres_err = max(
                fres_err, float(np.abs(normalised(priest_germer(eta, theta, s)) - fres).max())
            )
        real[name] = realizability(priest_germer(eta, theta, INFRAGOLD_SIGMA))
    ctx.metrics["max_abs_pg_minus_fresnel"] = fres_err
    ctx.metrics["realizability"] = real
    fine = np.radians(np.linspace(0.0, 89.9, 8991))
    black = materials["Enhanced Martin Black"]
    m01 = normalised(priest_germer(black, fine, INFRAGOLD_SIGMA))[:, 0]
    ctx.metrics["brewster_deg"] = {
        "arctan_n": float(np.degrees(brewster_angle(black.real))),
        "argmax_M01": float(np.degrees(fine[np.argmax(m01)])),
        "max_M01": float(m01.max()),
    }
    m22 = normalised(priest_germer(materials["LabSphere Infragold"], fine, INFRAGOLD_SIGMA))[:, 2]
    ctx.metrics["gold_principal_angle_deg"] = float(np.degrees(fine[np.argmax(m22 > 0)]))
    gold60 = normalised(priest_germer(materials["LabSphere Infragold"], fine[fine <= np.radians(60)],
                                      INFRAGOLD_SIGMA))  # fmt: skip
    ctx.metrics["gold_max_dev_from_mirror_to_60deg"] = float(np.abs(gold60 - [0, 1, -1, 0]).max())
    return fres_err, real


def _figure(ctx, materials, theta):
    pyplot = plt()
    fig, axes = pyplot.subplots(2, 4, figsize=(15, 6.5), sharex=True)
    bands = {"Enhanced Martin Black": BLACK_BAND, "LabSphere Infragold": list(GOLD_BAND.values())}
    deg = np.degrees(theta)
    for row, (name, eta) in zip(axes, materials.items()):
        curve = normalised(priest_germer(eta, theta, INFRAGOLD_SIGMA))
        band = np.array([normalised(priest_germer(e, theta, INFRAGOLD_SIGMA)) for e in bands[name]])
        for k, ax in enumerate(row):
            ax.fill_between(deg, band[..., k].min(0), band[..., k].max(0), color="C0", alpha=0.2,
                            label="index band")  # fmt: skip
            ax.plot(deg, curve[:, k], "C0", label=f"Priest-Germer, eta = {eta:.4g}")
            if name == "LabSphere Infragold":
                hyde = normalised(Model(INFRAGOLD_SIGMA).mueller(eta, theta, theta, np.pi))
                ax.plot(deg, hyde[:, k], "C3--", label="Eq. 177 (diffuse), sigma 0.44")
            ax.set(title=f"{name}: {NAMES[k]}", ylim=(-1.05, 1.05))
            ax.axhline(0, color="k", lw=0.4)
        row[0].legend(fontsize=6)
    for ax in axes[1]:
        ax.set(xlabel=r"$\theta_i = \theta_r$ [deg]")
    fig.suptitle("Fig. 26 model curves at 3.39 um (measured points not available)")
    ctx.save_figure(fig, "fig26")


def run(ctx):
    black = complex(index("Al2O3", WAVELENGTH))
    materials = {"Enhanced Martin Black": black, "LabSphere Infragold": GOLD_ORDAL}
    theta = np.radians(np.linspace(0.0, 85.0, 86 if ctx.quick else 341))
    with ctx.step("checks"):
        fres_err, real = _checks(ctx, materials, theta)
    with ctx.step("figure"):
        _figure(ctx, materials, theta)
    with ctx.step("diffuse_term"):
        hyde = Model(INFRAGOLD_SIGMA).mueller(GOLD_ORDAL, theta, theta, np.pi)
        di = np.sqrt(((hyde**2).sum((-2, -1)) - hyde[..., 0, 0] ** 2) / (3 * hyde[..., 0, 0] ** 2))
        m22_hyde = normalised(hyde)[:, 2]
    ctx.metrics["materials"] = {k: [v.real, -v.imag] for k, v in materials.items()}
    ctx.metrics["infragold_eq177_depolarization_index_range"] = [float(di.min()), float(di.max())]
    ctx.metrics["infragold_eq177_M22_at_0deg"] = float(m22_hyde[0])
    b, pa = ctx.metrics["brewster_deg"], ctx.metrics["gold_principal_angle_deg"]
    worst = min(r["min_eig"] for r in real.values())
    second = max(r["second_eig"] for r in real.values())
    pure = max(r["pure_identity"] for r in real.values())
    ctx.say(
        "Fig. 26's measured points are only in the printed figure and the text gives no index or "
        "roughness, so this study draws the model curves with cited parameters (docstring: gold "
        f"{GOLD_ORDAL.real:.3f} - j{-GOLD_ORDAL.imag:.2f} from Ordal et al., the anodic oxide of "
        f"Martin Black as sapphire {black.real:.3f}, kappa 0, an assumption) and cannot compare "
        "them with the measurements."
    )
    ctx.say(
        "Roughness does not matter at the specular angle: for sigma "
        + ", ".join(f"{s:g}" for s in SIGMAS)
        + f" the normalised Priest-Germer elements equal the smooth Fresnel Mueller matrix's to "
        f"{fres_err:.1e} (max abs). The matrices are physical and pure: coherency eigenvalues >= "
        f"{worst:.1e} and the second largest <= {second:.1e} of the trace, (M01^2 + M22^2 + "
        f"M23^2)/M00^2 = 1 to {pure:.1e}, depolarization index 1. Martin Black's M01/M00 peaks at "
        f"{b['max_M01']:.6f} at {b['argmax_M01']:.2f} deg, Brewster's arctan(n) = "
        f"{b['arctan_n']:.2f} deg; gold's M22/M00 changes sign at the principal angle "
        f"{pa:.1f} deg; up to 60 deg gold's elements differ from a perfect mirror's (0, 1, -1, 0) "
        f"by at most {ctx.metrics['gold_max_dev_from_mirror_to_60deg']:.3f}."
    )
    ctx.say(
        "What the text says about Fig. 26 follows from the model's form: Eq. 134 has no diffuse "
        "term, so its matrices are non-depolarizing at every angle and index; it can fit a "
        "single-bounce surface (Martin Black) but not a surface whose multiple bounces "
        "depolarize (Infragold). With a diffuse term (Eq. 177, sigma 0.44 of Fig. 41) Infragold's "
        f"depolarization index falls to {di.min():.2f}-{di.max():.2f} and M22/M00 at normal "
        f"incidence to {m22_hyde[0]:.2f} instead of -1. Whether the measured points show that "
        "cannot be checked here."
    )
    set_verdict(
        ctx,
        "partly",
        f"model curves only (measured points not available); PG = Fresnel to {fres_err:.0e}, "
        f"Brewster {b['argmax_M01']:.2f} vs {b['arctan_n']:.2f} deg",
    )
