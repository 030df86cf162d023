"""Mueller BRDF tables: geometry conversion checked against NIST SCATMECH (pySCATMECH) and the pBRDF
symmetries.

The SCATMECH file is built from physical directions: each row's signed (theta, phi) pairs are turned
into unit vectors (a negative polar angle then points to the other side of the normal by itself),
and SCATMECH is asked for the Mueller BRDF at the angles of those vectors in its own frame (source
at azimuth 180 deg, observer at ``phis``). The reader's conversion (signs, azimuth folding, mirror,
time convention) is therefore checked against an evaluation that never uses it.
"""

import numpy as np
import pytest

from scatterlab.ellipsometry import fit_pbrdf
from scatterlab.io import MuellerBRDF, read_mueller_brdf, write_mueller_brdf
from scatterlab.io.table import element_name
from scatterlab.pbrdf import Model

SIGMA = (
    0.212132 / np.sqrt(2) * np.sqrt(2) / np.sqrt(2)
)  # sqrt(2) sigma = 0.212132: six digits for SCATMECH
ETA = 1.44 - 7.5j


def signed_rows():
    """(thetai, phii, thetar, phir) [deg]: a goniometer's in-plane scan with signed thetar,
    SCATMECH's incidence (phii = 180), a signed incidence, and out-of-plane rows on both sides of
    the plane."""
    rows = [(30.0, 180.0, t, 0.0) for t in (-70, -45, -20, -5, 10, 25, 30, 35, 50, 75)]
    rows += [
        (-40.0, 0.0, t, 0.0) for t in (-60, -10, 20, 40, 55)
    ]  # thetai < 0: the source at azimuth 180
    rows += [(55.0, 180.0, 40.0, p) for p in (-150, -60, 20, 90, 170, 200, 300)]
    rows += [(20.0, 37.0, 65.0, 37.0 + p) for p in (100, 180, 260)]  # rotated frame
    return np.array(rows)


def unit(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)


def scatmech_file(path, rows, eta=ETA, sigma=SIGMA, normalised=True):
    brdf = pytest.importorskip("pySCATMECH.brdf", reason="pySCATMECH (test extra) is not installed")
    model = brdf.BRDF_Model(
        "Shadowed_Facet_BRDF_Model",
        substrate=complex(eta.real, -eta.imag),
        sdf="Gaussian_Slope_Distribution_Function",
        shadow="Torrance_Sparrow_Shadow_Function",
        **{"lambda": 0.6328},
    )
    model.setParameter("sdf.s", np.sqrt(2) * sigma)
    head = ["lambda", "thetai", "phii", "thetar", "phir", "f_r11"]
    head += [
        f"f_r{j}{k}/f_r11" if normalised else f"f_r{j}{k}" for j in range(1, 5) for k in range(1, 5)
    ][1:]
    lines = [
        "# simulated with pySCATMECH Shadowed_Facet_BRDF_Model (exp(-iwt), degrees, micrometres)",
        ",".join(head),
    ]
    for ti, pi_, tr, pr in rows:
        si, so = unit(ti, pi_), unit(tr, pr)  # towards the source, towards the observer
        a_src = np.arctan2(si[1], si[0]) if np.hypot(si[0], si[1]) > 0 else 0.0
        a_obs = np.arctan2(so[1], so[0])
        F = np.array(model.MuellerBRDF(np.arccos(si[2]), np.arccos(so[2]), a_obs - a_src + np.pi))
        vals = F.ravel() / np.r_[1.0, np.full(15, F[0, 0] if normalised else 1.0)]
        lines.append(",".join(repr(float(v)) for v in [0.6328, ti, pi_, tr, pr, *vals]))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.peer
@pytest.mark.parametrize("normalised", [True, False])
def test_scatmech_file_read_in_project_geometry_matches_pbrdf(tmp_path, normalised):
    rows = signed_rows()
    data = read_mueller_brdf(
        scatmech_file(tmp_path / "scatmech.csv", rows, normalised=normalised),
        time_convention="exp(-iwt)",
    )
    assert data.wavelength == pytest.approx(0.6328e-6)
    assert np.all(data.theta_i >= 0) and np.all(data.theta_r >= 0)
    assert np.all((data.phi >= 0) & (data.phi <= np.pi))
    # the in-plane scan: thetar = +30 with phir = 0 is specular; negative thetar is the backward
    # half-plane
    assert data.phi[6] == pytest.approx(np.pi) and data.theta_r[6] == pytest.approx(np.radians(30))
    assert data.phi[0] == pytest.approx(0.0) and data.theta_r[0] == pytest.approx(np.radians(70))
    F = Model(SIGMA, diffuse="none").mueller(ETA, data.theta_i, data.theta_r, data.phi)
    scale = F[:, :1, :1]
    np.testing.assert_allclose(
        data.mueller / scale, F / scale, atol=1e-9
    )  # SCATMECH vs pBRDF: 1e-9 of F00
    # the out-of-plane rows really exercise the mirror: the elements it changes are not small there
    R = np.diag([1.0, 1, -1, -1])
    assert np.max(np.abs(R @ F[-10:] @ R - F[-10:]) / scale[-10:]) > 0.05


@pytest.mark.peer
def test_wrong_time_convention_is_visible_in_the_circular_elements(tmp_path):
    data = read_mueller_brdf(
        scatmech_file(tmp_path / "s.csv", signed_rows())
    )  # default exp(+jwt): wrong here
    F = Model(SIGMA, diffuse="none").mueller(ETA, data.theta_i, data.theta_r, data.phi)
    err = np.abs(data.mueller - F) / F[:, :1, :1]
    assert np.max(err[:, :3, :3]) < 1e-9  # linear block unaffected
    assert np.max(err[:, 2, 3]) > 0.1  # M23 (m34) has the opposite sign


def test_mirror_fold_is_the_pbrdf_symmetry():
    """Folding phi -> 2 pi - phi with R M R is exact for the (isotropic) pBRDF."""
    m = Model(0.3)
    ti, tr, phi = np.radians(35.0), np.radians(60.0), np.radians([20.0, 95.0, 170.0])
    R = np.diag([1.0, 1, -1, -1])
    np.testing.assert_allclose(
        m.mueller(ETA, ti, tr, 2 * np.pi - phi),
        R @ m.mueller(ETA, ti, tr, phi) @ R,
        rtol=1e-12,
        atol=1e-15,
    )


def model_data(n=12, rng=0, sigma=0.25, normalised=False):
    rng = np.random.default_rng(rng)
    ti, tr = np.radians(rng.uniform(5, 80, n)), np.radians(rng.uniform(0, 85, n))
    phi = np.r_[np.pi, 0.0, rng.uniform(0, np.pi, n - 2)]
    M = Model(sigma).mueller(ETA, ti, tr, phi)
    std = 1e-3 * M[:, :1, :1] * np.ones((1, 4, 4))
    return MuellerBRDF(
        np.r_[np.full(n // 2, 633e-9), np.full(n - n // 2, 1064e-9)],
        ti,
        tr,
        phi,
        M / (M[:, :1, :1] if normalised else 1),
        std,
        normalised,
        "model",
    )


@pytest.mark.parametrize("normalised", [False, True])
@pytest.mark.parametrize("signed", [False, True])
@pytest.mark.parametrize("convention", ["exp(+jwt)", "exp(-iwt)"])
def test_write_read_round_trip(tmp_path, normalised, signed, convention):
    data = model_data()
    path = write_mueller_brdf(
        tmp_path / "t.csv",
        data,
        normalised=normalised,
        signed=signed,
        time_convention=convention,
        description="simulated",
    )
    back = read_mueller_brdf(path, time_convention=convention)
    for name in ("wavelength", "theta_i", "theta_r", "phi"):
        np.testing.assert_allclose(getattr(back, name), getattr(data, name), rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(back.mueller, data.mueller, rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(back.std, data.std, rtol=1e-13)
    assert back.normalised is False
    sel = back.select(1064e-9)
    assert len(sel) == 6 and np.all(sel.wavelength == 1064e-9)


def test_units_and_normalised_only(tmp_path):
    data = model_data(normalised=True)
    path = write_mueller_brdf(tmp_path / "n.csv", data, angle_unit="rad", wavelength_unit="nm")
    text = path.read_text()
    assert "m12/m11" in text and "f_r11" not in text
    back = read_mueller_brdf(path, angle_unit="rad", wavelength_unit="nm")
    assert back.normalised and np.all(back.mueller[:, 0, 0] == 1)
    np.testing.assert_allclose(back.mueller, data.mueller, atol=1e-14)
    np.testing.assert_allclose(back.theta_r, data.theta_r, atol=1e-14)
    # read in the wrong unit, the nanometres are micrometres out of any optical range: refused, naming
    # the unit they are in
    with pytest.raises(
        ValueError, match=r"n.csv, line \d+, column 'lambda': wavelength .* um is outside"
    ):
        read_mueller_brdf(path, wavelength_unit="um", angle_unit="rad")


def test_radians_read_as_degrees_are_pointed_out(tmp_path):
    """A file in radians without a stated unit, read as degrees: every polar angle is then below
    pi / 2 "degrees", which no goniometric measurement is -- refused, naming the option."""
    path = write_mueller_brdf(tmp_path / "r.csv", model_data(normalised=True), angle_unit="rad")
    lines = [x for x in path.read_text().splitlines() if "angles in rad" not in x]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match="radians read as degrees.*angle_unit='rad'"):
        read_mueller_brdf(path)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # stated correctly: no warning
        read_mueller_brdf(path, angle_unit="rad")


def test_other_header_names_and_columns_mapping(tmp_path):
    M = Model(0.3).mueller(ETA, np.radians(20), np.radians(40), np.radians(150))
    names = ["Wavelength [nm]", "AOI", "az_in", "theta_s", "phi_s"] + [
        f"m{j}{k}" for j in range(4) for k in range(4)
    ]
    row = [633, 20, 10, 40, 160] + list(M.ravel())
    path = tmp_path / "h.tsv"
    path.write_text("\t".join(names) + "\n" + "\t".join(repr(float(v)) for v in row) + "\n")
    unmapped = read_mueller_brdf(
        path, wavelength_unit="nm"
    )  # az_in is not a known incident-azimuth name
    assert any("phii = 180" in note for note in unmapped.notes)
    assert unmapped.phi[0] == pytest.approx(np.radians(20))
    data = read_mueller_brdf(path, {"phi_i": "az_in"}, wavelength_unit="nm")
    assert data.phi[0] == pytest.approx(np.radians(150)) and data.wavelength[0] == pytest.approx(
        633e-9
    )
    np.testing.assert_allclose(data.mueller[0], M)  # 0-based m00..m33 names
    with pytest.raises(ValueError, match="in nm but wavelength_unit='um'"):
        read_mueller_brdf(path, {"phi_i": "az_in"})


def write_rows(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return path


HEADER = ["lambda", "thetai", "phii", "thetar", "phir"] + [
    f"m{j}{k}" for j in range(1, 5) for k in range(1, 5)
]
GOOD = [0.6328, 30, 180, 30, 0, 1.0] + [0.0] * 15


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda h, r: (h[:3] + h[4:], [x[:3] + x[4:] for x in r]), "missing column for theta_r"),
        (lambda h, r: (h[:-1], [x[:-1] for x in r]), r"missing Mueller element columns \['m44'\]"),
        (
            lambda h, r: (h, [r[0], r[1][:6] + ["nan"] + r[1][7:]]),
            "line 3, column 'm12'.*not a finite number",
        ),
        (lambda h, r: (h, [r[0], r[1][:3] + [95] + r[1][4:]]), "line 3, column 'thetar'.*outside"),
        (lambda h, r: (h, [r[0], [0] + r[1][1:]]), "line 3, column 'lambda'.*> 0"),
        (lambda h, r: (h, [r[0], r[1][:6] + [1.5] + r[1][7:]]), r"line 3: \|m12\| = 1.5 exceeds"),
        (lambda h, r: (h, [r[0], r[1][:5] + [-1.0] + r[1][6:]]), "line 3.*< 0"),
        (lambda h, r: (h, [r[0], r[1][:-1]]), "line 3: 20 values for 21 columns"),
        (lambda h, r: (h[:5] + ["m00"] + h[6:], r), "mix 0-based"),
        (
            lambda h, r: (h + ["std_m12"], [x + [0.01] for x in r]),
            "standard deviations given for some",
        ),
    ],
)
def test_bad_files_name_the_problem(tmp_path, change, message):
    header, rows = change(list(HEADER), [list(GOOD), list(GOOD)])
    path = write_rows(tmp_path / "bad.csv", header, rows)
    with pytest.raises(ValueError, match=message):
        read_mueller_brdf(path)
    with pytest.raises(ValueError, match="bad.csv"):
        read_mueller_brdf(path)


def test_bad_arguments_and_binary_file(tmp_path):
    good = write_rows(tmp_path / "g.csv", HEADER, [GOOD])
    with pytest.raises(ValueError, match="time_convention"):
        read_mueller_brdf(good, time_convention="exp(iwt)?")
    with pytest.raises(ValueError, match="angle_unit"):
        read_mueller_brdf(good, angle_unit="grad")
    npy = tmp_path / "x.npy"
    np.save(npy, np.zeros(3))
    with pytest.raises(ValueError, match="x.npy: not a text table"):
        read_mueller_brdf(npy)
    assert element_name(2, 3, prefix="f_r", normalised=True) == "f_r34/f_r11"


@pytest.mark.peer
def test_scatmech_file_fitted_through_the_reader(tmp_path):
    """A SCATMECH Shadowed_Facet_BRDF_Model file (exp(-iwt), signed angles, out of plane) is fitted
    by the specular pBRDF (diffuse='none', the same physics): the parameters agree to the 6 digits
    SCATMECH uses."""
    data = read_mueller_brdf(
        scatmech_file(tmp_path / "s.csv", signed_rows()), time_convention="exp(-iwt)"
    )
    fit = fit_pbrdf(data, diffuse="none", starts=((1.5, 5.0),))
    assert [fit.n, fit.kappa, fit.sigma] == pytest.approx([ETA.real, -ETA.imag, SIGMA], rel=1e-5)
    assert fit.circular_flip_ratio > 10
