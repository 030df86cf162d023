"""Small example files of every input format, simulated by the package and labelled as simulated.

``python -m scatterlab.io.examples [OUT] [--force]`` (default OUT: ``data/examples``) writes:

* ``mueller_brdf_scatmech_style.csv`` -- Mueller BRDF of green paint on aluminium (1.39 - 0.34j,
  sigma 0.3, pBRDF with Hyde's diffuse term) at 1.55 um, SCATMECH's long format:
  ``lambda,thetai,phii,thetar,phir,f_r11, f_r12/f_r11,...``, degrees and micrometres, signed
  in-plane polar angles, out-of-plane rows, the exp(-iwt) time convention, 1 % noise;
* ``mueller_brdf_two_wavelengths.csv`` -- all 16 absolute elements with standard deviations,
  aluminium at 1.064 and 1.55 um, exp(+jwt);
* ``ellipsometry_in_plane.csv`` -- in-plane normalised elements of aluminium at 1.064 um with
  standard deviations;
* ``dolp_paint.csv`` -- the specular DOLP of the green paint (1.39 - 0.34j, sigma 0.3) at 1.55 um,
  20-70 deg, with noise 0.01 and its standard deviation (``scatterlab fit-dolp``);
* ``painted_plate.h5`` / ``.npz`` / ``.tif`` + ``.toml`` -- a painted aluminium plate with
  bare-metal letters (:func:`scatterlab.imaging.painted_plate`), 64x64 pixels, 2 specular geometries
  (40 and 55 deg), 4 channels (0/45/90/135 deg) through one Kolmogorov phase screen each (D/r0 =
  7.9), shot and read noise, with the truth (labels, indices, roughness, object S0 and DOLP, PSFs);
* ``painted_plate_dofp.tif`` + ``.toml`` -- the same as division-of-focal-plane raw frames (128x128,
  Sony layout).

TIFF stacks keep their truth beside them in ``NAME-truth.npz``.

The image stacks are simulated by the main job's acquisition stage, :func:`scatterlab.characterization.acquire`
(the camera sees the plate foreshortened by cos theta; the pupil is half the image, 2 pixels per
lambda/D).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from scatterlab._checks import as_rng

__all__ = ["write_examples", "simulate_painted_plate", "SEED"]

SEED = 20101210
PAINT, ALUMINIUM = 1.39 - 0.34j, 1.44 - 16.0j  # at 1550 nm (the reference text's plates)
ALUMINIUM_1064 = 1.226 - 10.413j
LABEL = "simulated by scatterlab (scatterlab.io.examples, seed {seed}); not a measurement"


def simulate_painted_plate(
    n: int = 64,
    theta_deg=(40.0, 55.0),
    d_over_r0: float = 7.9,
    photons: float = 1e5,
    read_noise: float = 10.0,
    rng=SEED,
):
    """A simulated :class:`~scatterlab.io.PolarimetricDataset` of a painted aluminium plate.

    Parameters
    ----------
    n : int
        Image size [pixels] (even; the pupil grid is n/2, so 2 pixels per lambda/D).
    theta_deg : sequence of float
        Specular geometries [deg].
    d_over_r0 : float
        Turbulence strength (one Kolmogorov screen per acquisition).
    photons : float
        Expected photo-electrons at the brightest channel pixel.
    read_noise : float
        Read noise [e- rms].
    rng : None, int >= 0, SeedSequence, BitGenerator or Generator

    Returns
    -------
    PolarimetricDataset
        With ``truth`` in object coordinates and ``simulated=True``.
    """
    from scatterlab.characterization import Plate, SceneConfig, acquire
    from scatterlab.characterization.scene_config import plate_labels
    from scatterlab.imaging import ANGLES_0_45_90_135
    from scatterlab.io.dataset import Optics, PolarimetricDataset, Truth

    seed = rng if isinstance(rng, (int, np.integer)) else "given"
    rng = as_rng(rng)
    # simulated exactly as the main job's acquisition stage does (one code path)
    cfg = SceneConfig(image_size=n, photons=photons, read_noise=read_noise).validate()
    plate = Plate("aluminium", ALUMINIUM.real, -ALUMINIUM.imag, PAINT.real, -PAINT.imag, 0.3, 0.3)
    labels = plate_labels(cfg, rng)
    materials, rough = [PAINT, ALUMINIUM, ALUMINIUM], [0.3, 0.3, 0.3]
    counts, s0, dolp, psfs = [], [], [], []
    for th in np.radians(theta_deg):
        acq = acquire(plate, labels, th, f"D_r0_{d_over_r0:g}", d_over_r0, cfg, rng)
        counts.append(acq.counts)
        s0.append(acq.truth_s0)
        dolp.append(acq.truth_dolp)
        psfs.append(acq.psf_true)
    truth = Truth(
        labels,
        ["paint", "metal", "scratch"],
        np.array([m.real for m in materials]),
        np.array([-m.imag for m in materials]),
        np.array(rough),
        s0=np.array(s0),
        dolp=np.array(dolp),
        psf=np.array(psfs),
    )
    return PolarimetricDataset(
        np.array(counts),
        ANGLES_0_45_90_135,
        np.radians(theta_deg),
        1.55e-6,
        Optics(pixels_per_lambda_over_d=2.0),
        read_noise=read_noise,
        truth=truth,
        title="painted aluminium plate (simulated)",
        description=LABEL.format(seed=seed)
        + f"; D/r0 = {d_over_r0}, {photons:g} photo-electrons at the brightest pixel",
        simulated=True,
    )


def _mueller_scatmech_style(rng):
    from scatterlab.io.mueller_brdf import MuellerBRDF
    from scatterlab.pbrdf import Model

    rows = [(30.0, t, 180.0) for t in range(-80, 81, 10) if t != 0]  # in plane: theta_r >= 0 after
    rows += [(30.0, 0.0, 180.0)]  # normal observation
    rows += [(50.0, t, p) for t in (20.0, 45.0, 70.0) for p in (30.0, 60.0, 90.0, 120.0, 150.0)]
    ti, tr, phi = (np.radians([r[i] for r in rows]) for i in range(3))
    backward = tr < 0  # an in-plane theta_r < 0 is the backward half-plane, phi = 0
    tr, phi = np.abs(tr), np.where(backward, 0.0, phi)
    M = Model(0.3).mueller(PAINT, ti, tr, phi)
    M = M + 0.01 * M[:, :1, :1] * rng.standard_normal(M.shape)
    return MuellerBRDF(1.55e-6, ti, tr, phi, M, source="simulated")


def _mueller_two_wavelengths(rng):
    from scatterlab.io.mueller_brdf import MuellerBRDF
    from scatterlab.pbrdf import Model

    ti = np.radians(np.repeat([20.0, 45.0, 60.0], 6))
    tr = np.radians(np.tile([10.0, 25.0, 45.0, 60.0, 30.0, 50.0], 3))
    phi = np.radians(np.tile([180.0, 180.0, 180.0, 180.0, 135.0, 160.0], 3))
    out = []
    for wl, eta in ((1.064e-6, ALUMINIUM_1064), (1.55e-6, ALUMINIUM)):
        M = Model(0.2).mueller(eta, ti, tr, phi)
        std = 0.005 * M[:, :1, :1] * np.ones((1, 4, 4))
        out.append((wl, M + std * rng.standard_normal(M.shape), std))
    return MuellerBRDF(
        np.repeat([w for w, _, _ in out], ti.size),
        np.tile(ti, 2),
        np.tile(tr, 2),
        np.tile(phi, 2),
        np.concatenate([m for _, m, _ in out]),
        np.concatenate([s for _, _, s in out]),
        source="simulated",
    )


def _ellipsometry(rng):
    from scatterlab.ellipsometry.fit import model_elements
    from scatterlab.io.ellipsometry import EllipsometryData

    theta = np.radians(np.arange(10.0, 81.0, 5.0))
    y = model_elements(theta, ALUMINIUM_1064.real, -ALUMINIUM_1064.imag, 0.43)
    std = np.full_like(y, 2e-3)
    return EllipsometryData(
        theta, np.clip(y + std * rng.standard_normal(y.shape), -1, 1), std, 1.064e-6
    )


def write_examples(out="data/examples", *, overwrite: bool = False) -> list[Path]:
    """Write every example file (module docstring).

    Parameters
    ----------
    out : str or Path
        Output folder.
    overwrite : bool
        Replace existing files (otherwise FileExistsError).

    Returns
    -------
    list of Path
        The files written (the sidecars and truth files beside the TIFFs are not listed).
    """
    from scatterlab.io.dofp import SONY_POLARSENS
    from scatterlab.io.ellipsometry import write_ellipsometry
    from scatterlab.io.mueller_brdf import write_mueller_brdf
    from scatterlab.io.stacks import write_dataset_hdf5, write_dataset_npz, write_dataset_tiff

    out = Path(out)
    rng = np.random.default_rng(SEED)
    label = LABEL.format(seed=SEED)
    paths = [
        write_mueller_brdf(
            out / "mueller_brdf_scatmech_style.csv",
            _mueller_scatmech_style(rng),
            normalised=True,
            signed=True,
            time_convention="exp(-iwt)",
            overwrite=overwrite,
            description=label + "; pBRDF of green paint (1.39 - 0.34j, sigma 0.3), 1 % noise",
        ),
        write_mueller_brdf(
            out / "mueller_brdf_two_wavelengths.csv",
            _mueller_two_wavelengths(rng),
            overwrite=overwrite,
            description=label + "; pBRDF of aluminium (sigma 0.2), 0.5 % noise",
        ),
        write_ellipsometry(
            out / "ellipsometry_in_plane.csv",
            _ellipsometry(rng),
            overwrite=overwrite,
            description=label + "; aluminium at 1.064 um (1.226 - 10.413j, sigma 0.43)",
        ),
        _dolp_paint(rng, out / "dolp_paint.csv", label, overwrite),
    ]
    ds = simulate_painted_plate(rng=SEED)
    paths += [
        write_dataset_hdf5(out / "painted_plate.h5", ds, overwrite=overwrite),
        write_dataset_npz(out / "painted_plate.npz", ds, overwrite=overwrite),
        write_dataset_tiff(out / "painted_plate.tif", ds, overwrite=overwrite),
        write_dataset_tiff(
            out / "painted_plate_dofp.tif", ds, dofp_pattern=SONY_POLARSENS, overwrite=overwrite
        ),
    ]
    return paths


def _dolp_paint(rng, path, label, overwrite):
    from scatterlab.inversion import model_dolp
    from scatterlab.io.dolp_table import DolpData, write_dolp_table

    th = np.radians(np.arange(20.0, 71.0, 5.0))
    noise = 0.01
    dolp = model_dolp(PAINT.real, -PAINT.imag, 0.3, th, th) + noise * rng.standard_normal(th.size)
    data = DolpData(th, th, np.full(th.size, np.pi), np.round(dolp, 6), np.full(th.size, noise))
    return write_dolp_table(
        path,
        data,
        overwrite=overwrite,
        description=label + "; specular DOLP of green paint (1.39 - 0.34j, sigma 0.3), noise 0.01",
    )


def main(argv=None) -> int:
    """``python -m scatterlab.io.examples [OUT] [--force]``.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0 on success, 2 when a file exists and ``--force`` is not given.
    """
    parser = argparse.ArgumentParser(
        prog="python -m scatterlab.io.examples", description=__doc__.split("\n")[0]
    )
    parser.add_argument("out", nargs="?", default="data/examples", help="output folder")
    parser.add_argument("--force", action="store_true", help="replace existing files")
    args = parser.parse_args(argv)
    try:
        for p in write_examples(args.out, overwrite=args.force):
            print(p)
    except FileExistsError as exc:
        print(f"scatterlab: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
