import numpy as np
import pytest

from scatterlab.ellipsometry import fit_mueller_elements, normalised_elements
from scatterlab.io import EllipsometryData, read_ellipsometry, write_ellipsometry
from scatterlab.pbrdf import Model

THETA = np.radians(np.arange(10.0, 81.0, 10.0))
ETA, SIGMA = 1.226 - 10.413j, 0.43


def simulated(rng=None, noise=0.0):
    y = normalised_elements(Model(SIGMA).mueller(ETA, THETA, THETA, np.pi))
    std = None
    if noise:
        std = np.full_like(y, noise)
        y = y + std * np.random.default_rng(rng).standard_normal(y.shape)
    return EllipsometryData(THETA, y, std, 1.064e-6)


@pytest.mark.parametrize("convention", ["exp(+jwt)", "exp(-iwt)"])
def test_round_trip_feeds_the_fit(tmp_path, convention):
    """Write, read and fit: the fit recovers the truth within 5 sigma of its own error (seed fixed;
    2e-3 noise on 8 angles x 4 elements)."""
    data = simulated(rng=3, noise=2e-3)
    path = write_ellipsometry(
        tmp_path / "e.csv", data, time_convention=convention, description="simulated"
    )
    if convention == "exp(-iwt)":
        assert (
            "-0." not in path.read_text().splitlines()[3].split(",")[4]
        )  # M23 < 0 is written positive
    back = read_ellipsometry(path, time_convention=convention)
    np.testing.assert_allclose(back.theta, data.theta, rtol=1e-14)
    np.testing.assert_allclose(back.elements, data.elements, rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(back.std, data.std)
    assert back.wavelength == pytest.approx(1.064e-6)
    fit = fit_mueller_elements(back.theta, back.elements, std=back.std)
    truth = np.array([ETA.real, -ETA.imag, SIGMA])
    assert np.all(np.abs(np.array([fit.n, fit.kappa, fit.sigma]) - truth) < 5 * fit.errors)


def test_zero_based_names_absolute_first_element_and_radians(tmp_path):
    data = simulated()
    M = Model(SIGMA).mueller(ETA, THETA, THETA, np.pi)
    rows = np.column_stack(
        [THETA, 2 * M[:, 0, 0], 2 * M[:, 0, 1], 2 * M[:, 1, 1], 2 * M[:, 2, 2], 2 * M[:, 2, 3]]
    )
    path = tmp_path / "z.csv"
    path.write_text(
        "AOI [rad],m00,m01,m11,m22,m23\n" + "\n".join(",".join(map(repr, r.tolist())) for r in rows)
    )
    back = read_ellipsometry(path, angle_unit="rad")
    np.testing.assert_allclose(back.elements, data.elements, rtol=1e-13)
    assert back.wavelength is None
    with pytest.raises(ValueError, match="in rad but angle_unit='deg'"):
        read_ellipsometry(path)


@pytest.mark.parametrize(
    "header, row, message",
    [
        ("theta,m12,m22,m33", "10,0,1,1", r"missing element columns \['m34'\]"),
        ("theta,m12,m22,m33,m34", "95,0,1,1,0", "line 2, column 'theta'.*outside"),
        ("theta,m12,m22,m33,m34", "10,0,1,1.5,0", "line 2, column 'm33'.*outside \\[-1, 1\\]"),
        ("theta,m12,m22,m33,m34", "10,0,1,inf,0", "line 2, column 'm33'.*not a finite"),
        ("theta,m12,m22,m33,m34", "10,0,nan,1,0", "line 2, column 'm22'.*not a finite"),
        ("theta,m12,m22,m33,m34", "10,0,1,1", "line 2: 4 values for 5 columns"),
        ("theta,m12,m22,m33,m34", "-95,0,1,1,0", "line 2, column 'theta'.*outside"),
        (
            "theta,m12,m22,m33,m34,std_m12,std_m22,std_m33,std_m34",
            "10,0,1,1,0,0.1,-0.1,0.1,0.1",
            "line 2, column 'std_m22': standard deviation must be > 0",
        ),
        ("theta,m12,m22,m33,m34,lambda", "10,0,1,1,0,1.0\n20,0,1,1,0,1.5", "several wavelengths"),
        ("angle_of_something,m12,m22,m33,m34", "10,0,1,1,0", "missing column for theta"),
    ],
)
def test_bad_files(tmp_path, header, row, message):
    path = tmp_path / "bad.csv"
    path.write_text(header + "\n" + row + "\n")
    with pytest.raises(ValueError, match=message):
        read_ellipsometry(path)


def test_bad_options_name_the_argument(tmp_path):
    path = tmp_path / "e.csv"
    path.write_text("theta,m12,m22,m33,m34\n10,0,1,1,0\n")
    for kw, name in (
        ({"angle_unit": "grad"}, "angle_unit"),
        ({"wavelength_unit": "inch"}, "wavelength_unit"),
        ({"time_convention": "exp(iwt)?"}, "time_convention"),
    ):
        with pytest.raises(ValueError, match=name):
            read_ellipsometry(path, **kw)


def test_columns_mapping(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("angle_of_something,m12,m22,m33,m34\n10,0,1,1,0\n")
    assert read_ellipsometry(path, {"theta": "angle_of_something"}).theta[0] == pytest.approx(
        np.radians(10)
    )


def test_element_columns_of_any_name_are_mapped(tmp_path):
    # an instrument's own names for the in-plane elements and one standard deviation
    path = tmp_path / "own.csv"
    path.write_text(
        "aoi,N,C,S,Psi34,u_m12,std_m22,std_m33,std_m34\n40,0.2,0.9,0.8,0.3,0.01,0.01,0.01,0.01\n"
    )
    with pytest.raises(ValueError, match=r"missing element columns.*--column m12=NAME"):
        read_ellipsometry(path)
    names = {"m12": "N", "m22": "C", "m33": "S", "m34": "Psi34", "std_m12": "u_m12"}
    d = read_ellipsometry(path, names)
    np.testing.assert_allclose(d.elements, [[0.2, 0.9, 0.8, 0.3]])
    np.testing.assert_allclose(d.std, 0.01)
    # a mapped column stands for the element in place of one the file names so
    path.write_text("aoi,m12,m22,m33,m34,m34_corrected\n40,0.2,0.9,0.8,0.3,0.25\n")
    assert read_ellipsometry(path, {"m34": "m34_corrected"}).elements[0, 3] == 0.25
    with pytest.raises(ValueError, match=r"columns\['m34'\] = 'nope' is not a column"):
        read_ellipsometry(path, {"m34": "nope"})
    # its standard deviation under the same name is not guessed; the error says how to map it
    path.write_text(
        "aoi,m12,m22,m33,circ,std_m12,std_m22,std_m33,std_circ\n40,0.2,0.9,0.8,0.3,.01,.01,.01,.02\n"
    )
    with pytest.raises(ValueError, match=r"not for \['m34'\].*--column std_m34=NAME"):
        read_ellipsometry(path, {"m34": "circ"})
    d = read_ellipsometry(path, {"m34": "circ", "std_m34": "std_circ"})
    assert d.std[0, 3] == 0.02
    assert "'circ' as m34, 'std_circ' as std_m34" in " ".join(d.notes)  # the report records it


def test_mueller_brdf_element_columns_of_any_name_are_mapped(tmp_path):
    from scatterlab.io import read_mueller_brdf

    lines = [
        "lambda,thetai,phii,thetar,phir,"
        + ",".join(f"f_r{j}{k}" for j in range(1, 5) for k in range(1, 5))
    ]
    lines.append("1.55,30,0,30,180," + ",".join("1" if jk == 0 else "0.1" for jk in range(16)))
    path = tmp_path / "b.csv"
    path.write_text("\n".join(lines).replace("f_r12,", "BRDF_ps,") + "\n")
    with pytest.raises(
        ValueError, match=r"missing Mueller element columns \['m12'\].*--column m12=NAME"
    ):
        read_mueller_brdf(path)
    data = read_mueller_brdf(path, {"f_r12": "BRDF_ps"})
    assert data.mueller[0, 0, 1] == pytest.approx(0.1) and data.mueller[0, 0, 0] == 1


def test_m12_is_never_negative_in_the_specular_geometry():
    """The premise of the reader's sign check: R_s >= R_p (Abeles' relation) makes the pBRDF's
    in-plane m12 >= 0 for any passive index, roughness and angle, n below 1 and kappa up to 1e3
    included (and the Fresnel coefficients themselves obey |r_p| <= |r_s|)."""
    from scatterlab.ellipsometry import model_elements

    theta = np.radians([0.5, 10, 30, 50, 70, 85, 89.99])
    c = np.cos(theta)
    for n, kappa in ((1.39, 0.34), (0.2, 3.0), (0.05, 1e3), (3.6, 5.88), (1.5, 0.0), (0.9, 0.0)):
        e2 = (n - 1j * kappa) ** 2  # textbook Fresnel coefficients, principal root (passive)
        root = np.sqrt(e2 - np.sin(theta) ** 2)
        rs, rp = (c - root) / (c + root), (e2 * c - root) / (e2 * c + root)
        assert np.all(np.abs(rp) <= np.abs(rs) * (1 + 1e-12))
        for sigma in (1e-3, 0.3, 1.5):
            m12 = model_elements(theta, n, kappa, sigma)[:, 0]
            assert np.all(m12 >= -1e-12), (n, kappa, sigma, m12)


def test_a_negated_m12_column_is_pointed_out(tmp_path):
    import warnings

    data = simulated(rng=3, noise=0.002)
    path = write_ellipsometry(tmp_path / "e.csv", data)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_ellipsometry(path)  # as written: no warning
    flipped = EllipsometryData(data.theta, data.elements * [-1, 1, 1, 1], data.std, 1.064e-6)
    path = write_ellipsometry(tmp_path / "f.csv", flipped)
    with pytest.warns(UserWarning, match=r"m12 < 0 at \d+ of 8 angles.*negate its m12 column"):
        read_ellipsometry(path)
    # noise-level negatives near normal incidence are not a convention
    small = EllipsometryData(data.theta, data.elements * [0, 1, 1, 1] - [0.003, 0, 0, 0], None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_ellipsometry(write_ellipsometry(tmp_path / "s.csv", small))


def test_a_signed_angle_of_incidence_is_the_mirror_geometry(tmp_path):
    """A negative angle of incidence is the mirror image of the geometry; the mirror R M R (R = diag(1,
    1, -1, -1)) leaves m12, m22, m33 and m34, so the elements read are those of |theta|."""
    from scatterlab.io import read_ellipsometry

    signed, plain = tmp_path / "s.csv", tmp_path / "p.csv"
    signed.write_text("theta,m12,m22,m33,m34\n-50,-0.2,1,0.9,0.3\n60,-0.3,1,0.8,0.5\n")
    plain.write_text("theta,m12,m22,m33,m34\n50,-0.2,1,0.9,0.3\n60,-0.3,1,0.8,0.5\n")
    a, b = read_ellipsometry(signed), read_ellipsometry(plain)
    np.testing.assert_array_equal(a.theta, b.theta)
    np.testing.assert_array_equal(a.elements, b.elements)
    assert any("1 signed angle(s)" in note for note in a.notes)
