"""The example files in data/examples: the generator reproduces them, and each reads back to what it
claims.
"""

from pathlib import Path

import numpy as np
import pytest

from scatterlab.io import read_dataset, read_ellipsometry, read_mueller_brdf
from scatterlab.io.examples import write_examples

EXAMPLES = Path(__file__).parents[2] / "data" / "examples"
pytestmark = pytest.mark.skipif(
    not EXAMPLES.is_dir(), reason="data/examples is not in this checkout"
)


def test_generator_reproduces_the_committed_examples_and_every_file_is_listed(tmp_path):
    written = write_examples(tmp_path)
    listed = (EXAMPLES.parent / "README.md").read_text()
    for p in sorted(tmp_path.iterdir()):
        assert f"examples/{p.name}" in listed, p.name
        committed = EXAMPLES / p.name
        if p.suffix == ".toml":
            assert p.read_text() == committed.read_text(), p.name
        elif p.suffix == ".csv":
            _assert_same_table(p.read_text(), committed.read_text(), p.name)
    for p in written:
        if p.suffix in (".h5", ".npz", ".tif"):
            a, b = read_dataset(p), read_dataset(EXAMPLES / p.name)
            np.testing.assert_array_equal(a.counts, b.counts)
            np.testing.assert_array_equal(a.truth.dolp, b.truth.dolp)
    assert sum(f.stat().st_size for f in EXAMPLES.iterdir()) < 1_000_000


def _assert_same_table(text, committed, name):
    """The same comments, header and numbers: the numbers to 1e-12 relative, since the 15th digit a table
    is written with can change with the floating-point path of the machine (BLAS threads, SIMD)."""
    lines, want = text.splitlines(), committed.splitlines()
    assert len(lines) == len(want), name
    for a, b in zip(lines, want):
        try:
            x = np.array(a.split(","), float)
            y = np.array(b.split(","), float)
        except ValueError:  # a comment or the column names
            assert a == b, name
            continue
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=0, err_msg=name)


def test_examples_read_as_described():
    m = read_mueller_brdf(EXAMPLES / "mueller_brdf_scatmech_style.csv", time_convention="exp(-iwt)")
    assert any("signed" in n for n in m.notes) and np.all(m.theta_r >= 0)
    assert m.wavelength[0] == pytest.approx(1.55e-6) and m.std is None
    two = read_mueller_brdf(EXAMPLES / "mueller_brdf_two_wavelengths.csv")
    assert two.wavelengths == pytest.approx([1.064e-6, 1.55e-6]) and two.std is not None
    from scatterlab.io import read_dolp_table

    dolp = read_dolp_table(EXAMPLES / "dolp_paint.csv")
    assert dolp.specular and dolp.dolp.size == 11 and np.all(dolp.std == 0.01)
    e = read_ellipsometry(EXAMPLES / "ellipsometry_in_plane.csv")
    assert e.wavelength == pytest.approx(1.064e-6) and e.std.shape == e.elements.shape
    sets = {
        name: read_dataset(EXAMPLES / name)
        for name in (
            "painted_plate.h5",
            "painted_plate.npz",
            "painted_plate.tif",
            "painted_plate_dofp.toml",
        )
    }
    for name, ds in sets.items():
        assert ds.shape == (2, 4, 64, 64) and ds.simulated and "simulated" in ds.description, name
        np.testing.assert_array_equal(ds.counts, sets["painted_plate.h5"].counts)
        assert ds.truth.names == ["paint", "metal", "scratch"]
    ds = sets["painted_plate.h5"]
    # the truth DOLP of paint and bare metal at 55 deg is the pBRDF's (stored as float32: 1e-6)
    from scatterlab.pbrdf import Model

    t = ds.truth
    for label in (0, 1):
        eta = t.n[label] - 1j * t.kappa[label]
        expected = Model(t.sigma[label]).dolp(eta, ds.theta[1], ds.theta[1])
        assert np.median(t.dolp[1][t.labels == label]) == pytest.approx(expected, rel=1e-6)
    assert ds.optics.pupil_radius(48, ds.wavelength) == pytest.approx(12.0)
