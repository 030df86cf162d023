"""Input checks of the readers found by a new-user trial and a fuzz review: wavelengths in the wrong unit
(one shared range check, naming the likely unit), strongly negative and too small dataset images, standard
deviations of 0, unknown keys of a ``columns`` mapping. Each error names the file (and line and column, or
key) and the allowed range."""

from pathlib import Path

import numpy as np
import pytest

from scatterlab.imaging import ANGLES_0_45_90_135, channel_images
from scatterlab.io import (
    Optics,
    PolarimetricDataset,
    read_dataset,
    read_dolp_table,
    read_ellipsometry,
    read_mueller_brdf,
    write_dataset,
)
from scatterlab.io.table import likely_wavelength_unit, wavelength_range_problem

EXAMPLES = Path(__file__).resolve().parents[2] / "data" / "examples"
needs_examples = pytest.mark.skipif(not EXAMPLES.is_dir(), reason="data/examples not present")


def _edited(tmp_path, name, edit):
    """A copy of an example table with ``edit(header cells, data rows as cell lists)`` applied."""
    lines = (EXAMPLES / name).read_text().splitlines()
    comments = [x for x in lines if x.startswith("#")]
    rows = [x.split(",") for x in lines if x and not x.startswith("#")]
    edit(rows[0], rows[1:])
    out = tmp_path / name
    out.write_text("\n".join(comments + [",".join(r) for r in rows]) + "\n")
    return out, len(comments) + 2  # the file and the line of its first data row


# ------------------------------------------------------------------------------------ wavelengths
def test_the_shared_wavelength_range_names_the_likely_unit():
    assert wavelength_range_problem(0.6328) is None and wavelength_range_problem(1064, "nm") is None
    problem = wavelength_range_problem(633)
    assert "wavelength 633 um is outside [0.01, 100] um" in problem
    assert "a wavelength in nm read as um? (633 nm = 0.633 um)" in problem
    assert likely_wavelength_unit(633) == "nm" and likely_wavelength_unit(1.55e-6, "um") == "m"
    assert likely_wavelength_unit(1.55) is None  # in range: nothing to suggest
    assert "outside" in wavelength_range_problem(1e9) and likely_wavelength_unit(1e9) is None


@needs_examples
def test_a_mueller_table_in_nm_read_as_um_is_refused(tmp_path):
    def edit(head, rows):
        i = head.index("lambda")
        for r in rows:
            r[i] = f"{float(r[i]) * 1000:g}"

    path, line = _edited(tmp_path, "mueller_brdf_two_wavelengths.csv", edit)
    with pytest.raises(ValueError) as err:
        read_mueller_brdf(path)
    message = str(err.value)
    assert f"{path}, line {line}, column 'lambda': wavelength" in message
    assert "is outside [0.01, 100] um: a wavelength in nm read as um?" in message
    assert "wavelength_unit='nm'" in message
    assert np.all(read_mueller_brdf(path, wavelength_unit="nm").wavelength < 1e-5)


@needs_examples
def test_an_ellipsometry_file_in_nm_read_as_um_is_refused(tmp_path):
    def edit(head, rows):
        for r in rows:
            r[head.index("lambda")] = "1064"

    path, line = _edited(tmp_path, "ellipsometry_in_plane.csv", edit)
    with pytest.raises(ValueError, match=r"wavelength 1064 um is outside \[0.01, 100\] um") as err:
        read_ellipsometry(path)
    assert f"line {line}, column 'lambda'" in str(err.value)
    assert "wavelength_unit='nm'" in str(err.value)
    assert read_ellipsometry(path, wavelength_unit="nm").wavelength == pytest.approx(1.064e-6)


def _dataset(H=64, W=64, scale=100.0, read_noise=10.0, **kw):
    rng = np.random.default_rng(1)
    S = np.stack(
        [np.full((H, W), 100.0), rng.uniform(-30, 30, (H, W)), rng.uniform(-30, 30, (H, W))], -1
    )
    counts = np.stack([channel_images(S * scale * (g + 1), ANGLES_0_45_90_135) for g in range(2)])
    return dict(
        counts=counts,
        polarizer_angles=ANGLES_0_45_90_135,
        theta=np.radians([40.0, 55.0]),
        wavelength=1.55e-6,
        optics=Optics(pixels_per_lambda_over_d=2.0),
        read_noise=read_noise,
        **kw,
    )


def _npz(tmp_path, **changes):
    path = write_dataset(tmp_path / "d.npz", PolarimetricDataset(**_dataset()), overwrite=True)
    with np.load(path) as z:
        flat = {k: z[k] for k in z.files} | changes
    np.savez(tmp_path / "bad.npz", **flat)
    return tmp_path / "bad.npz"


def test_a_dataset_wavelength_in_nm_says_what_to_write(tmp_path):
    with pytest.raises(ValueError) as err:
        read_dataset(_npz(tmp_path, wavelength_um=np.array(1550.0)))
    message = str(err.value)
    assert (
        "bad.npz: 'wavelength_um' = 1550: wavelength 1550 um is outside [0.01, 100] um" in message
    )
    assert "a wavelength in nm read as um?" in message and "write 1.55" in message


# --------------------------------------------------------------------------------- dataset counts
def test_a_strongly_negative_block_is_refused_and_read_noise_is_not(tmp_path):
    """A 64 x 20 block at -500 e- with a 10 e- read noise: 35 sigma of the noise of a dark-subtracted
    count, in a bright image whose negative share of the light (under 1 %) the light-weighted check lets
    through. Gaussian read noise, a few hot pixels of a subtracted dark frame, or the block listed in
    bad_pixels are read."""
    kw = _dataset()
    kw["counts"][0, 1, :, :20] = -500.0
    with pytest.raises(ValueError) as err:
        PolarimetricDataset(**kw)
    message = str(err.value)
    assert "'counts' at geometry 0, channel 1: 1280 of 4096 pixels are below -70.71 e-" in message
    assert "5 noise sigmas below 0" in message and "sqrt(2) x read_noise_e 10 e-" in message
    assert "bad_pixels" in message
    counts = kw["counts"].copy()
    with pytest.raises(ValueError, match="bad.npz: 'counts' at geometry 0, channel 1: 1280"):
        read_dataset(_npz(tmp_path, counts=counts))
    # the block listed as bad pixels: read
    bad = np.zeros((64, 64), bool)
    bad[:, :20] = True
    PolarimetricDataset(**kw, bad_pixels=np.broadcast_to(bad, (2, 64, 64)))
    # read noise around 0 (a dark field, 14 e- rms with read_noise_e 10 e-) and four hot pixels
    rng = np.random.default_rng(2)
    kw = _dataset()
    kw["counts"][:, :, :, :20] = rng.normal(0, 14.0, (2, 4, 64, 20))
    kw["counts"][0, 0, 5, 5:9] = -300.0
    assert np.mean(PolarimetricDataset(**kw).counts < 0) > 0.1
    # without read_noise_e the scatter of neighbouring pixels stands in for it
    kw = _dataset(scale=1.0, read_noise=None)
    kw["counts"][1, 2, 10:30, 10:30] = -400.0
    kw["counts"][1, 2, 40:, :] = 1e4  # light enough that the negative share alone lets it through
    with pytest.raises(ValueError, match="read_noise_e not given: sigma from the scatter"):
        PolarimetricDataset(**kw)


def test_images_smaller_than_8_x_8_are_refused_at_reading(tmp_path):
    with pytest.raises(ValueError) as err:
        read_dataset(_npz(tmp_path, counts=np.full((2, 4, 6, 6), 100.0)))
    assert "bad.npz: 'counts' images are 6 x 6 pixels" in str(err.value)
    assert "H, W >= 8" in str(err.value)
    raw = _npz(
        tmp_path, dofp_pattern_deg=np.array([[90.0, 45], [135, 0]]), raw=np.full((2, 12, 12), 50.0)
    )
    with np.load(raw) as z:
        flat = {k: z[k] for k in z.files if k not in ("counts", "polarizer_deg")}
    np.savez(tmp_path / "raw.npz", **flat)
    with pytest.raises(
        ValueError, match=r"raw.npz: 'raw' frames 12 x 12 demosaic into 6 x 6 channel"
    ):
        read_dataset(tmp_path / "raw.npz")
    PolarimetricDataset(**_dataset(H=8, W=8))  # the smallest


# ---------------------------------------------------------------------------- standard deviations
@needs_examples
def test_a_standard_deviation_of_0_is_refused_with_its_line_and_column(tmp_path):
    def edit(head, rows):
        rows[0][head.index("std_m12")] = "0"

    path, line = _edited(tmp_path, "ellipsometry_in_plane.csv", edit)
    with pytest.raises(
        ValueError, match=rf"line {line}, column 'std_m12': standard deviation must be > 0, got 0"
    ):
        read_ellipsometry(path)

    def edit(head, rows):
        rows[1][[h.startswith("std_") for h in head].index(True) + 3] = "0"

    path, line = _edited(tmp_path, "mueller_brdf_two_wavelengths.csv", edit)
    with pytest.raises(
        ValueError, match=rf"line {line + 1}, column 'std_.*': standard deviation must be > 0"
    ):
        read_mueller_brdf(path)


# ------------------------------------------------------------------------------- columns mappings
@needs_examples
def test_unknown_keys_of_a_columns_mapping_are_refused():
    with pytest.raises(ValueError) as err:
        read_dolp_table(EXAMPLES / "dolp_paint.csv", columns={"std_dop": "sd", "dolp": "dolp"})
    message = str(err.value)
    assert "dolp_paint.csv: unknown key in columns: 'std_dop' (did you mean 'std'?)" in message
    assert "the valid keys are 'theta', 'theta_i', 'theta_r', 'phi', 'dolp', 'std'" in message
    with pytest.raises(ValueError, match=r"unknown keys in columns: 'lambda', 'aoi'.*'wavelength'"):
        read_ellipsometry(
            EXAMPLES / "ellipsometry_in_plane.csv", columns={"lambda": "x", "aoi": "y"}
        )
    with pytest.raises(
        ValueError, match=r"unknown key in columns: 'thetai' \(did you mean 'theta_i'"
    ):
        read_mueller_brdf(EXAMPLES / "mueller_brdf_two_wavelengths.csv", columns={"thetai": "x"})
    # element names are keys of the element readers
    read_ellipsometry(
        EXAMPLES / "ellipsometry_in_plane.csv", columns={"m12": "m12", "theta": "theta"}
    )
