import numpy as np
import pytest

from scatterlab.imaging import ANGLES_0_45_90_135, channel_images, stokes_from_channels
from scatterlab.io import (
    Optics,
    PolarimetricDataset,
    Truth,
    demosaic,
    mosaic,
    read_dataset,
    write_dataset,
    write_dataset_tiff,
)


def small(rng=0, truth=True, G=2, H=8, W=10):
    rng = np.random.default_rng(rng)
    S = np.stack(
        [np.full((H, W), 100.0), rng.uniform(-30, 30, (H, W)), rng.uniform(-30, 30, (H, W))],
        axis=-1,
    )
    counts = np.stack([channel_images(S * (g + 1), ANGLES_0_45_90_135) for g in range(G)])
    t = None
    if truth:
        labels = rng.integers(0, 2, (H, W))
        t = Truth(
            labels,
            ["paint", "metal"],
            np.array([1.39, 1.44]),
            np.array([0.34, 16.0]),
            np.array([0.3, 0.3]),
            s0=rng.uniform(1, 2, (G, H, W)),
            dolp=rng.uniform(0, 1, (G, H, W)),
            psf=rng.uniform(0, 1, (G, H, W)),
        )
    return PolarimetricDataset(
        counts,
        ANGLES_0_45_90_135,
        np.radians([40.0, 55.0][:G]),
        1.55e-6,
        Optics(pixels_per_lambda_over_d=2.0),
        read_noise=10.0,
        truth=t,
        title="test",
        description="simulated",
        simulated=True,
    )


def assert_same(a, b):
    np.testing.assert_allclose(a.counts, b.counts, rtol=1e-6)  # images are stored as float32
    np.testing.assert_allclose(
        np.mod(a.polarizer_angles, np.pi), np.mod(b.polarizer_angles, np.pi), atol=1e-12
    )
    np.testing.assert_allclose(a.theta, b.theta, rtol=1e-14)
    assert a.wavelength == pytest.approx(b.wavelength, rel=1e-14)
    assert a.optics == b.optics and a.read_noise == b.read_noise and a.simulated == b.simulated
    assert (a.title, a.description) == (b.title, b.description)
    if a.truth is not None:
        assert b.truth.names == a.truth.names
        np.testing.assert_array_equal(b.truth.labels, a.truth.labels)
        for k in ("n", "kappa", "sigma"):
            np.testing.assert_array_equal(getattr(b.truth, k), getattr(a.truth, k))
        for k in ("s0", "dolp", "psf"):
            np.testing.assert_allclose(getattr(b.truth, k), getattr(a.truth, k), rtol=1e-6)


@pytest.mark.parametrize("suffix", [".h5", ".npz", ".tif"])
@pytest.mark.parametrize("dofp", [None, ((90, 45), (135, 0)), ((0, 45), (135, 90))])
def test_round_trip_every_format(tmp_path, suffix, dofp):
    ds = small()
    path = write_dataset(tmp_path / f"d{suffix}", ds, dofp_pattern=dofp)
    back = read_dataset(path)
    assert_same(ds, back)
    assert back.shape == (2, 4, 8, 10)
    if dofp is not None:
        assert "demosaiced" in back.notes[0]
    if suffix == ".tif":
        assert_same(ds, read_dataset(path.with_suffix(".toml")))


def test_dofp_demosaic_layout_and_stokes():
    """A raw frame of a uniform scene with known linear Stokes: each superpixel position carries the
    intensity of its polarizer (Malus, Eq. 197), whatever the layout."""
    S = np.array([1.0, 0.3, -0.2])
    raw = np.empty((4, 6))
    pattern = np.array([[90.0, 45.0], [135.0, 0.0]])
    for i in range(2):
        for j in range(2):
            a = np.radians(pattern[i, j])
            raw[i::2, j::2] = 0.5 * (S[0] + S[1] * np.cos(2 * a) + S[2] * np.sin(2 * a))
    ch, ang = demosaic(raw, pattern)
    assert ch.shape == (4, 2, 3) and np.degrees(ang) == pytest.approx([0, 45, 90, 135])
    np.testing.assert_allclose(stokes_from_channels(ch, ang)[0, 0], S, atol=1e-15)
    np.testing.assert_array_equal(mosaic(ch, ang, pattern), raw)


@pytest.mark.parametrize(
    "pattern, message",
    [
        ([[0, 45], [90, 180]], "four different"),
        ([0, 45, 90, 135], "2x2"),
        ([[0, 45], [90, np.nan]], "finite"),
    ],
)
def test_bad_dofp_layouts(pattern, message):
    with pytest.raises(ValueError, match=message):
        demosaic(np.zeros((4, 4)), pattern)
    with pytest.raises(ValueError, match="even"):
        demosaic(np.zeros((5, 4)))


def test_optics_sampling():
    o = Optics(aperture_diameter=0.1, pixel_pitch=5e-6, focal_length=1.0)
    assert o.sampling(1e-6) == pytest.approx(2.0)  # lambda f / (D p)
    assert o.pupil_radius(128, 1e-6) == pytest.approx(32.0)
    with pytest.raises(ValueError, match="pixels_per_lambda_over_d"):
        Optics(aperture_diameter=0.1)
    with pytest.raises(ValueError, match="> 0"):
        Optics(pixels_per_lambda_over_d=-2)


def edit_npz(tmp_path, **changes):
    path = write_dataset(tmp_path / "d.npz", small())
    with np.load(path) as z:
        flat = {k: z[k] for k in z.files}
    for k, v in changes.items():
        if v is None:
            flat.pop(k)
        else:
            flat[k] = v
    bad = tmp_path / "bad.npz"
    np.savez(bad, **flat)
    return bad


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"counts": None}, "missing 'counts'"),
        ({"theta_deg": np.array([40.0])}, "1 angles for 2 geometries"),
        ({"theta_deg": np.array([40.0, 95.0])}, r"theta_deg' must be in \(0, 90\)"),
        ({"polarizer_deg": np.array([0.0, 45, 90])}, "3 angles for 4 channels"),
        ({"polarizer_deg": np.array([0.0, 180, 0, 180])}, "three different orientations"),
        ({"counts": np.zeros((2, 4, 6))}, "'counts' must have 4 dimensions"),
        ({"counts": np.full((2, 4, 8, 10), np.nan)}, "'counts' contains NaN"),
        ({"counts": np.zeros((2, 4, 0, 8))}, "'counts' is empty"),
        ({"theta_deg": np.radians([40.0, 55.0])}, "radians given as degrees"),
        ({"polarizer_deg": np.radians([0.0, 45, 90, 135])}, "span only 2.36 deg"),
        ({"counts": -np.ones((2, 4, 8, 10))}, r"no photons .* at geometries \[0, 1\]"),
        ({"wavelength_um": np.array(-1.0)}, "'wavelength_um' must be > 0"),
        ({"wavelength_um": np.array(1550.0)}, "outside"),
        ({"pixels_per_lambda_over_d": None}, "optics need"),
        ({"truth_dolp": np.zeros((2, 3, 3))}, "'truth_dolp' must have shape"),
        ({"truth_n": np.array([1.0])}, "one entry per label"),
        ({"raw": np.zeros((2, 16, 20))}, "both 'counts' and 'raw'"),
        (
            {"counts": np.broadcast_to(np.linspace(0.0, 100.0, 10) - 60.0, (2, 4, 8, 10)).copy()},
            r"'counts' at geometry 0 are negative by \d+% of their light .*too much dark",
        ),
        ({"format": np.array("another format")}, "'format' is"),
        ({"read_noise": np.array(10.0)}, r"unknown key 'read_noise' \(did you mean 'read_noise_e'"),
    ],
)
def test_bad_dataset_files_name_the_problem(tmp_path, changes, message):
    with pytest.raises(ValueError, match=message) as err:
        read_dataset(edit_npz(tmp_path, **changes))
    assert "bad.npz" in str(err.value)


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04truncated", bytes(range(256)) * 4])
def test_a_damaged_npz_is_named_as_damaged(tmp_path, content):
    """Bytes that are not a zip archive (empty, a truncated zip, noise) get a message about the file, not
    numpy's about pickles; a zip cut short is caught too."""
    bad = tmp_path / "bad.npz"
    bad.write_bytes(content)
    with pytest.raises(ValueError, match="bad.npz: not an NPZ dataset"):
        read_dataset(bad)
    good = write_dataset(tmp_path / "d.npz", small()).read_bytes()
    cut = tmp_path / "cut.npz"
    cut.write_bytes(good[: len(good) // 2])
    with pytest.raises(ValueError, match="cut.npz: not"):
        read_dataset(cut)


def test_bad_files_and_kinds(tmp_path):
    for name in ("scene.toml.csv", "x.npy", "x.json"):
        with pytest.raises(ValueError, match="expected a dataset"):
            read_dataset(tmp_path / name)
    (tmp_path / "junk.h5").write_text("not hdf5")
    with pytest.raises(ValueError, match="junk.h5: not an HDF5 file"):
        read_dataset(tmp_path / "junk.h5")
    path = write_dataset_tiff(tmp_path / "s.tif", small(truth=False))
    side = path.with_suffix(".toml")
    side.write_text(side.read_text().replace("polarizer_deg = [", "polarizer_deg = [20.0, "))
    with pytest.raises(ValueError, match="8 TIFF pages for 2 geometries .* x 5 channels"):
        read_dataset(path)
    side.unlink()
    with pytest.raises(ValueError, match="sidecar s.toml"):
        read_dataset(path)


def test_users_tiff_stack_with_one_file_per_geometry_and_a_minimal_sidecar(tmp_path):
    import tifffile

    ds = small(truth=False)
    for g in range(2):
        tifffile.imwrite(
            tmp_path / f"geom{g}.tif", ds.counts[g].astype(np.float32), photometric="minisblack"
        )
    (tmp_path / "plate.toml").write_text(
        'tiff = ["geom0.tif", "geom1.tif"]\nwavelength_um = 1.55\ntheta_deg = [40, 55]\n'
        "polarizer_deg = [0, 45, 90, 135]\npixels_per_lambda_over_d = 2.0\n"
    )
    back = read_dataset(tmp_path / "plate.toml")
    np.testing.assert_allclose(back.counts, ds.counts, rtol=1e-6)
    assert back.truth is None and not back.simulated and back.read_noise is None
    assert back.stokes().shape == (2, 8, 10, 3)


def test_a_scene_toml_is_not_a_dataset(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text("image_size = 64\ngeometry_deg = [30, 50]\n")
    with pytest.raises(ValueError, match="expected a dataset.*scene description"):
        read_dataset(scene)


def _sidecar_stack(tmp_path, dofp=False):
    """A TIFF stack (channels, or DoFP raw frames) and its sidecar."""
    from scatterlab.io import SONY_POLARSENS

    path = write_dataset_tiff(
        tmp_path / "s.tif", small(truth=False), dofp_pattern=SONY_POLARSENS if dofp else None
    )
    return path, path.with_suffix(".toml")


@pytest.mark.parametrize(
    "dofp, old, new, message",
    [
        (False, 'layout = "channels"', 'layout = "bayer"', "layout must be 'channels' or 'dofp'"),
        (
            False,
            "wavelength_um = ",
            "wavelength_nm = ",
            "unknown key 'wavelength_nm' \\(did you mean 'wavelength_um'\\?\\)",
        ),
        (False, "theta_deg = [40.0", "theta_deg = [nan", "'theta_deg' contains NaN"),
        (False, "theta_deg = [40.0", "theta_deg = [-40.0", r"'theta_deg' must be in \(0, 90\)"),
        (True, "theta_deg = [40.0, ", "theta_deg = [", "2 DoFP frames for 1 geometries"),
        (True, "dofp_pattern_deg = [[", "dofp_pattern_deg = [[0.0, ", "2x2"),
        (True, "dofp_pattern_deg = ", "pattern = ", "unknown key 'pattern'"),
        (True, "dofp_pattern_deg = ", "# dofp_pattern_deg = ", "need 'dofp_pattern_deg'"),
        (
            False,
            "read_noise_e = ",
            "read_noise = ",
            r"'read_noise' \(did you mean 'read_noise_e'\?\)",
        ),
        (False, "format_version = 1", "format_version = 7", "reads version 1 to 1"),
        # a misspelt key is named before the pages are counted (not "8 TIFF pages for 0 geometries")
        (
            False,
            "theta_deg = ",
            "theta_degs = ",
            r"unknown key 'theta_degs' \(did you mean 'theta_deg'\?\)",
        ),
        (
            True,
            "theta_deg = ",
            "theta_degs = ",
            r"unknown key 'theta_degs' \(did you mean 'theta_deg'\?\)",
        ),
        (False, 'layout = "', 'layuot = "', r"unknown key 'layuot' \(did you mean 'layout'\?\)"),
        (False, 'tiff = "', 'tif = "', r"unknown key 'tif' \(did you mean 'tiff'\?\)"),
    ],
)
def test_bad_sidecars_name_the_problem(tmp_path, dofp, old, new, message):
    """Every TIFF-sidecar field the reader needs: an unknown layout, a missing key, NaN, angles out of
    range, a frame count that does not match the geometries, a DoFP layout of the wrong shape."""
    path, side = _sidecar_stack(tmp_path, dofp)
    text = side.read_text()
    assert old in text
    side.write_text(text.replace(old, new, 1))
    with pytest.raises(ValueError, match=message) as err:
        read_dataset(path)
    assert "s.toml" in str(err.value)


def test_bad_hdf5_and_dofp_frames_name_the_problem(tmp_path):
    """The HDF5 reader validates as the others do (a missing key, NaN images), and DoFP raw frames
    of the wrong shape (2-D, odd sizes) are refused with the file named."""
    import h5py

    from scatterlab.io import SONY_POLARSENS, write_dataset_hdf5

    path = write_dataset_hdf5(tmp_path / "d.h5", small(truth=False))
    with h5py.File(path, "a") as f5:
        del f5["theta_deg"]
    with pytest.raises(ValueError, match="d.h5: missing 'theta_deg'"):
        read_dataset(path)
    path = write_dataset_hdf5(tmp_path / "n.h5", small(truth=False), overwrite=True)
    with h5py.File(path, "a") as f5:
        f5["counts"][0, 0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="n.h5: 'counts' contains NaN"):
        read_dataset(path)
    raw = write_dataset_hdf5(tmp_path / "r.h5", small(truth=False), dofp_pattern=SONY_POLARSENS)
    with h5py.File(raw, "a") as f5:
        frames = f5["raw"][()]
        del f5["raw"]
        f5["raw"] = frames[:, :-1, :]
    with pytest.raises(ValueError, match="r.h5.*even"):
        read_dataset(raw)
    with h5py.File(raw, "a") as f5:
        del f5["raw"]
        f5["raw"] = frames[0]
    with pytest.raises(ValueError, match="r.h5: 'raw' must have 3 dimensions"):
        read_dataset(raw)


def test_negative_counts_of_read_noise_are_data():
    """A dark field with read noise (14 e- rms after dark subtraction) around a small bright object:
    half its pixels are negative, a few per cent of its light, and the dataset is read."""
    rng = np.random.default_rng(5)
    counts = rng.normal(0, 14.0, (1, 4, 8, 8))
    counts[:, :, 3:5, 3:5] += 1e4
    ds = PolarimetricDataset(
        counts,
        ANGLES_0_45_90_135,
        np.radians([40.0]),
        1.55e-6,
        Optics(pixels_per_lambda_over_d=2.0),
    )
    assert np.mean(ds.counts < 0) > 0.4


# ------------------------------------------------------------------------------------ bad pixels
def test_bad_pixels_round_trip_in_every_format(tmp_path):
    """A sensor mask (H, W) applies to every geometry, a (G, H, W) one per geometry; both survive
    every file format (the TIFF's mask as its own file) and add to a dataset's own."""
    from scatterlab.io import with_pixel_mask

    ds = small()
    bad = np.zeros((8, 10), bool)
    bad[2, 3] = bad[4, 0] = True
    masked = with_pixel_mask(ds, bad)
    valid = masked.valid_pixels()
    assert valid.shape == (2, 8, 10) and np.array_equal(valid, np.broadcast_to(~bad, (2, 8, 10)))
    assert any("left out of the likelihood per geometry: [2, 2]" in n for n in masked.notes)
    full = float(ds.counts.max())
    masked = with_pixel_mask(masked, full_well=full)
    for suffix in (".h5", ".npz", ".tif"):
        back = read_dataset(write_dataset(tmp_path / f"m{suffix}", masked))
        assert np.array_equal(back.valid_pixels(), valid), suffix
        assert back.full_well == full
    assert (tmp_path / "m-bad_pixels.tif").exists()
    per_geometry = np.zeros((2, 8, 10), bool)
    per_geometry[1, 0, 0] = True
    both = with_pixel_mask(masked, per_geometry).valid_pixels()
    assert np.array_equal(both, valid & ~per_geometry)
    # no mask: every pixel measured
    assert ds.valid_pixels() is None
    assert read_dataset(write_dataset(tmp_path / "n.npz", ds)).bad_pixels is None


def test_bad_pixels_on_a_dofp_raw_frame_mark_their_superpixel(tmp_path):
    ds = small()
    path = write_dataset(tmp_path / "raw.npz", ds, dofp_pattern=((90, 45), (135, 0)))
    with np.load(path) as z:
        flat = {k: z[k] for k in z.files}
    raw_bad = np.zeros(flat["raw"].shape[1:], np.uint8)
    raw_bad[5, 2] = 1  # row 5, column 2 of the raw frame: superpixel (2, 1)
    np.savez(tmp_path / "b.npz", bad_pixels=raw_bad, **flat)
    valid = read_dataset(tmp_path / "b.npz").valid_pixels()
    assert np.array_equal(np.argwhere(~valid[0]), [[2, 1]]) and not valid[1, 2, 1]


@pytest.mark.parametrize(
    "changes, message",
    [
        (
            {"bad_pixels": np.zeros((3, 8, 10))},
            r"'bad_pixels' must have shape \(H, W\) = \(8, 10\)",
        ),
        ({"bad_pixels": np.zeros((5, 8))}, "'bad_pixels' must have shape"),
        ({"bad_pixels": np.full((8, 10), np.nan)}, "'bad_pixels' contains NaN"),
        ({"bad_pixels": np.ones((8, 10))}, r"leaves 0.0% of the pixels at geometry 0"),
        ({"bad_pixel": np.zeros((8, 10))}, r"did you mean 'bad_pixels'"),
        ({"full_well_e": np.array(-5.0)}, "'full_well_e' must be > 0"),
        ({"full_well": np.array(9e4)}, r"did you mean 'full_well_e'"),
    ],
)
def test_bad_pixel_keys_name_the_problem(tmp_path, changes, message):
    with pytest.raises(ValueError, match=message):
        read_dataset(edit_npz(tmp_path, **changes))


def test_dead_pixels_inside_light_are_pointed_out_and_a_dark_field_is_not():
    """Pixels that read <= 0 in every channel at every geometry amid light are dead (a lit pixel's
    photo-electrons never all fall to 0); dark-subtracted pixels of a dim field with read noise are not."""
    from scatterlab.io import with_pixel_mask

    ds = small(G=2, H=16, W=16)
    # light with shot noise (noise-free synthetic channels would crowd their highest count)
    counts = np.random.default_rng(2).poisson(20 * np.clip(ds.counts, 0, None)).astype(float)
    counts[:, :, 7:9, 7:10] = 0.0
    ds.counts = counts
    with pytest.warns(UserWarning, match=r"6 pixels read <= 0 .* first at row 7, column 7"):
        dead = PolarimetricDataset(
            counts, ds.polarizer_angles, ds.theta, ds.wavelength, ds.optics, read_noise=1.0
        )
    assert any("dead pixels?" in n for n in dead.notes)
    bad = np.zeros((16, 16), bool)
    bad[7:9, 7:10] = True
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # listed: no warning, and the note is replaced
        listed = with_pixel_mask(dead, bad)
    assert not any("dead pixels?" in n for n in listed.notes)
    rng = np.random.default_rng(1)
    noise = 30.0 + rng.normal(0, 10.0, (2, 4, 16, 16))  # dim light, under 20 x the read noise
    noise[:, :, :4] -= 30.0  # and no light, where a pixel may read <= 0 in all eight reads
    noise[:, :, 0, :3] = -np.abs(noise[:, :, 0, :3])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        PolarimetricDataset(
            noise, ds.polarizer_angles, ds.theta, ds.wavelength, ds.optics, read_noise=10.0
        )


def test_a_saturated_plateau_is_pointed_out_and_shot_noise_is_not():
    """Counts clipped at a full well share their highest value over many pixels; Poisson light with
    read noise never does (independent truth: the clipping applied here)."""
    rng = np.random.default_rng(3)
    ds = small(G=2, H=32, W=32)
    light = rng.poisson(np.clip(ds.counts, 0, None) * 50) + rng.normal(0, 10, ds.counts.shape)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        PolarimetricDataset(
            light, ds.polarizer_angles, ds.theta, ds.wavelength, ds.optics, read_noise=10.0
        )
    full = np.quantile(light[1, 2], 0.9)
    clipped = light.copy()
    clipped[1] = np.minimum(clipped[1], full)
    with pytest.warns(UserWarning, match=r"pixels of geometry 1, channel \d crowd the highest"):
        sat = PolarimetricDataset(
            clipped, ds.polarizer_angles, ds.theta, ds.wavelength, ds.optics, read_noise=10.0
        )
    assert any("saturated?" in n for n in sat.notes)
    # given the full well, the plateau is censored and counted, not questioned
    from scatterlab.io import with_pixel_mask

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        given = with_pixel_mask(sat, full_well=full)
    assert not any("saturated?" in n for n in given.notes)
    n_sat = int(np.any(clipped[1] >= full, axis=0).sum())
    assert any(f"per geometry: [0, {n_sat}]" in n for n in given.notes), given.notes


def test_review_cases_of_bad_pixels_and_saturation():
    """A DoFP camera's raw-frame mask through with_pixel_mask; a wrong mask named by the shape given;
    a dark-subtracted clipped plateau (spread by the dark's scatter) still pointed out."""
    import warnings

    from scatterlab.io import with_pixel_mask

    ds = small(G=2, H=8, W=8)
    raw = np.zeros((16, 16), bool)
    raw[3, 4] = True  # superpixel (1, 2)
    valid = with_pixel_mask(ds, raw).valid_pixels()
    assert np.array_equal(np.argwhere(~valid[0]), [[1, 2]])
    with pytest.raises(ValueError, match=r"got \(5, 8\)"):
        with_pixel_mask(ds, np.zeros((5, 8)))
    rng = np.random.default_rng(0)
    light = rng.poisson(np.full((2, 4, 32, 32), 5e4)).astype(float)
    dark = 100 + rng.normal(0, 3, (32, 32))
    clipped = np.minimum(light, 3e4 + 100) - dark  # raw clipped, then the dark subtracted
    with pytest.warns(UserWarning, match="crowd the highest"):
        PolarimetricDataset(
            clipped, ds.polarizer_angles, ds.theta, ds.wavelength, ds.optics, read_noise=3.0
        )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        given = with_pixel_mask(
            PolarimetricDataset(
                light, ds.polarizer_angles, ds.theta, ds.wavelength, ds.optics, read_noise=3.0
            ),
            full_well=4e4,
        )
    assert given.full_well == 4e4 and given.valid_pixels() is None


def test_write_dataset_with_its_arguments_swapped_says_which_is_which(tmp_path):
    """write_dataset(ds, "x.npz") -- the dataset first -- names the arguments, not pathlib's TypeError."""
    from scatterlab.io import write_dataset_hdf5, write_dataset_npz

    ds = small(truth=False)
    for write, name in (
        (write_dataset, "write_dataset"),
        (write_dataset_npz, "write_dataset_npz"),
        (write_dataset_hdf5, "write_dataset_hdf5"),
        (write_dataset_tiff, "write_dataset_tiff"),
    ):
        with pytest.raises(
            TypeError,
            match=rf"{name}\(path, ds\): the first argument is the file path.*"
            "other way round",
        ):
            write(ds, str(tmp_path / "x.npz"))
    with pytest.raises(TypeError, match="ds must be a PolarimetricDataset, got str"):
        write_dataset(tmp_path / "x.npz", "y.npz")
    with pytest.raises(TypeError, match="path must be a str or Path, got int"):
        write_dataset(3, ds)
    assert not list(tmp_path.iterdir())
    assert write_dataset(tmp_path / "x.npz", ds).exists()
