"""The DOLP and ellipsometry table readers: units, the radians-as-degrees warning and bad rows."""

import warnings

import numpy as np
import pytest

from scatterlab.io import read_dolp_table


def _write(path, theta, dolp):
    lines = ["theta,dolp"] + [f"{t},{d}" for t, d in zip(theta, dolp)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_radians_read_as_degrees_are_refused(tmp_path):
    # the same specular angles written in radians: read as degrees, every one is below pi/2 "deg", where
    # the DOLP is near 0 and the fit would report nonsense (n = 0.02): refused, as read_dataset does
    theta = np.radians([30.0, 45.0, 60.0])
    path = _write(tmp_path / "rad.csv", theta, [0.3, 0.5, 0.7])
    with pytest.raises(
        ValueError,
        match=r"column 'theta': the polar angles are read in degrees .*radians read as degrees",
    ):
        read_dolp_table(path)
    both = tmp_path / "both.csv"
    both.write_text("theta_i,theta_r,dolp\n0.5,0.6,0.3\n0.7,0.8,0.5\n")
    with pytest.raises(ValueError, match=r"column 'theta_i' and 'theta_r'.*angle_unit='rad'"):
        read_dolp_table(both)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        data = read_dolp_table(path, angle_unit="rad")
        read_dolp_table(_write(tmp_path / "deg.csv", [30, 45, 60], [0.3, 0.5, 0.7]))
    np.testing.assert_allclose(data.theta_i, theta)
    np.testing.assert_allclose(data.theta_r, theta)


def test_polar_angles_beyond_90_deg_are_refused(tmp_path):
    path = _write(tmp_path / "bad.csv", [30, -95], [0.3, 0.5])
    with pytest.raises(
        ValueError, match=r"line 3, column 'theta'.*-95.0 deg is outside \[-90, 90\] deg"
    ):
        read_dolp_table(path)


def test_degrees_read_as_radians_are_pointed_out(tmp_path):
    path = _write(tmp_path / "deg.csv", [30, 60], [0.3, 0.5])
    with pytest.raises(ValueError, match=r"30.0 rad is outside .* it looks like degrees"):
        read_dolp_table(path, angle_unit="rad")


def test_signed_in_plane_angles_are_the_other_side_of_the_normal(tmp_path):
    """docs/conventions.md: a negative polar angle is |theta| with the azimuth turned by pi. The
    independent truth is the pBRDF's DOLP of the geometry written out explicitly: (40, -40, phi 180)
    is back-scatter (40, 40, phi 0), (-30, 50, phi 90) is (30, 50, phi 270); a signed specular
    angle turns both directions and leaves phi at 180."""
    from scatterlab.inversion import model_dolp

    path = tmp_path / "signed.csv"
    path.write_text("theta_i,theta_r,phi,dolp\n40,-40,180,0.1\n-30,50,90,0.2\n-20,-60,180,0.3\n")
    data = read_dolp_table(path)
    explicit = np.radians([[40, 40, 0], [30, 50, 270], [20, 60, 180]])
    np.testing.assert_allclose(np.c_[data.theta_i, data.theta_r, data.phi], explicit, atol=1e-12)
    assert sum("signed angle" in note for note in data.notes) == 2
    eta = (1.5, 0.01)
    got = model_dolp(*eta, 0.3, data.theta_i, data.theta_r, data.phi)
    want = model_dolp(*eta, 0.3, *explicit.T)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    spec = _write(tmp_path / "spec.csv", [-40, 50], [0.3, 0.5])
    data = read_dolp_table(spec)
    np.testing.assert_allclose(np.degrees(data.theta_i), [40, 50])
    np.testing.assert_allclose(data.theta_r, data.theta_i)
    np.testing.assert_allclose(data.phi, np.pi)


def test_ellipsometry_in_radians_read_as_degrees_is_refused(tmp_path):
    from scatterlab.io import read_ellipsometry

    path = tmp_path / "e.csv"
    path.write_text("theta,m12,m22,m33,m34\n0.5,0.1,0.9,0.8,0.1\n0.7,0.1,0.9,0.8,0.1\n")
    with pytest.raises(ValueError, match="radians read as degrees"):
        read_ellipsometry(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        data = read_ellipsometry(path, angle_unit="rad")
    np.testing.assert_allclose(data.theta, [0.5, 0.7])


def test_an_azimuth_in_degrees_in_a_radian_file_is_refused(tmp_path):
    # theta in radians but phi still 180 (degrees): read as 180 rad it would be a silent wrong geometry
    path = tmp_path / "p.csv"
    path.write_text("theta_i,theta_r,phi,dolp\n0.5,0.5,180,0.3\n0.7,0.7,180,0.5\n")
    with pytest.raises(ValueError, match=r"azimuth 180.0 rad is outside \[-360, 360\] deg"):
        read_dolp_table(path, angle_unit="rad")


def test_a_header_that_states_another_unit_or_convention_is_pointed_out(tmp_path):
    """The writers state the units and the time convention in the header; read otherwise, the
    reader says so (and does as told)."""
    from scatterlab.io import (
        DolpData,
        EllipsometryData,
        read_ellipsometry,
        write_dolp_table,
        write_ellipsometry,
    )

    th = np.radians([30.0, 50.0, 70.0])
    dolp = DolpData(th, th, np.full(3, np.pi), np.array([0.3, 0.5, 0.7]))
    path = write_dolp_table(tmp_path / "d.csv", dolp, angle_unit="rad")
    with (
        pytest.warns(UserWarning) as record,
        pytest.raises(ValueError, match="radians read as degrees"),
    ):
        read_dolp_table(path)
    said = " ".join(str(w.message) for w in record)
    assert "its header states angles in rad but they are read as deg" in said
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_dolp_table(path, angle_unit="rad")
    data = EllipsometryData(th, np.tile([0.0, 0.9, -0.8, -0.1], (3, 1)))
    path = write_ellipsometry(tmp_path / "e.csv", data, time_convention="exp(-iwt)")
    with pytest.warns(UserWarning, match="time convention exp\\(-iwt\\) but it is read as"):
        read_ellipsometry(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_ellipsometry(path, time_convention="exp(-iwt)")
    np.testing.assert_allclose(back.elements, data.elements, atol=1e-12)


def test_a_dolp_in_percent_is_refused_with_the_fix(tmp_path):
    path = _write(tmp_path / "pct.csv", [30, 45, 60], [30.5, 52.0, 71.2])
    with pytest.raises(ValueError, match="looks like percent: divide it"):
        read_dolp_table(path)
    path = _write(tmp_path / "neg.csv", [30, 45, 60], [0.3, -0.5, 0.7])
    with pytest.raises(
        ValueError, match=r"outside \[0, 1\] \(by more than a noise margin of 0.05\)$"
    ):
        read_dolp_table(path)


def test_decimal_commas_and_spreadsheet_leftovers(tmp_path):
    # beside ';' (the European spreadsheet export) a decimal comma is read as the decimal mark
    semi = tmp_path / "semi.csv"
    semi.write_text("theta;dolp;std\n30;0,30;0,01\n45;0,52;1,5e-2\n")
    d = read_dolp_table(semi)
    np.testing.assert_allclose(d.dolp, [0.30, 0.52])
    np.testing.assert_allclose(d.std, [0.01, 0.015])
    # in a comma-separated table they split the numbers into too many cells: said, with the fix
    comma = tmp_path / "comma.csv"
    comma.write_text("theta,dolp\n30,0,30\n45,0,52\n")
    with pytest.raises(ValueError, match=r"line 2: 3 values for 2 columns \(decimal commas\?"):
        read_dolp_table(comma)
    # a row that is merely short gets no such guess
    short = tmp_path / "short.csv"
    short.write_text("theta,dolp,std\n30,0.3\n")
    with pytest.raises(ValueError, match=r"2 values for 3 columns$"):
        read_dolp_table(short)
    # rows of empty cells below the data are skipped; an empty cell inside a row is named
    excel = tmp_path / "excel.csv"
    excel.write_text("theta,dolp\n30,0.3\n45,0.5\n,\n,\n")
    np.testing.assert_allclose(read_dolp_table(excel).dolp, [0.3, 0.5])
    excel.write_text("theta,dolp\n30,0.3\n45,\n")
    with pytest.raises(
        ValueError, match=r"line 3, column 'dolp': '' is not a number \(an empty cell"
    ):
        read_dolp_table(excel)


def test_unused_columns_are_named_and_an_error_column_under_another_name_is_warned_of(tmp_path):
    """A column the reader does not use is named in the notes; one that looks like the DOLP's error
    (uncertainty, sd, error) while the table has no std column is warned of with the name expected, since
    the error would otherwise be inferred without a word."""
    rows = "30,0.3,0.01,20\n45,0.5,0.01,21\n60,0.7,0.01,22\n"
    for name in ("uncertainty", "sd", "error", "err", "Sigma"):
        path = tmp_path / f"{name}.csv"
        path.write_text(f"theta,dolp,{name},temperature\n{rows}")
        with pytest.warns(
            UserWarning, match=rf"columns '{name}', 'temperature' not used.*name it std_dolp"
        ):
            data = read_dolp_table(path)
        assert data.std is None and data.unused == [name, "temperature"]
    # with a std column, an extra one is only noted
    path = tmp_path / "t.csv"
    path.write_text(f"theta,dolp,std_dolp,temperature\n{rows}")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        data = read_dolp_table(path)
    assert data.unused == ["temperature"] and data.std is not None
    assert any("column 'temperature' not used" in note for note in data.notes)
    path.write_text(
        f"theta,dolp,std_dolp\n{rows.replace(',20', '').replace(',21', '').replace(',22', '')}"
    )
    data = read_dolp_table(path)
    assert data.unused == [] and not any("not used" in note for note in data.notes)


def test_the_azimuths_read_are_listed(tmp_path):
    path = tmp_path / "phi.csv"
    path.write_text("theta,phi,dolp\n30,0,0.3\n45,0,0.5\n60,90,0.7\n")
    data = read_dolp_table(path)
    (note,) = [n for n in data.notes if "azimuth" in n]
    assert "column 'phi'" in note and "[deg]: 0 (2 rows), 90 (1 row)" in note
    path.write_text("theta,phi,dolp\n30,3.14159,0.3\n45,3.14159,0.5\n")
    (note,) = [n for n in read_dolp_table(path).notes if "azimuth" in n]
    assert "3.14159 (2 rows)" in note and "pi radians read as degrees?" in note
    rad = tmp_path / "rad.csv"
    rad.write_text("theta,phi,dolp\n0.5,3.14159265,0.3\n0.8,1.5707963,0.5\n")
    (note,) = [n for n in read_dolp_table(rad, angle_unit="rad").notes if "azimuth" in n]
    assert "[deg]: 90 (1 row), 180 (1 row)" in note and "read as degrees" not in note
