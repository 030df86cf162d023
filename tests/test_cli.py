import warnings

import pytest

from scatterlab.cli import main


def test_study_list(capsys):
    assert main(["study", "list"]) == 0
    out = capsys.readouterr().out
    assert "fig4" in out and "brewster" in out


def test_study_run_and_force(tmp_path, capsys):
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "report.md").exists() and (tmp_path / "fig4.pdf").exists()
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path), "--force"]) == 0


def test_study_run_all_writes_index(tmp_path, monkeypatch):
    # every study already runs in tests/test_studies.py: here a folder holding one study is enough
    import shutil

    from scatterlab.study_runner import studies_dir

    folder = tmp_path / "studies"
    folder.mkdir()
    shutil.copy(studies_dir() / "fig4_fresnel_reflectances.py", folder)
    monkeypatch.setenv("SCATTERLAB_STUDIES", str(folder))
    assert main(["study", "run", "all", "--quick", "--out", str(tmp_path / "out")]) == 0
    tmp_path = tmp_path / "out"
    index = (tmp_path / "index.md").read_text()
    assert "fig4" in index and "| ok |" in index


def test_unknown_study_exit_code(capsys):
    assert main(["study", "run", "nope", "--quick"]) == 2


def test_help_says_what_the_tool_does_and_lists_each_command(capsys):
    import pytest

    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "polarimetric light scattering" in out
    for command in ("study", "characterize", "fit-mueller", "fit-dolp"):
        lines = [ln for ln in out.splitlines() if ln.strip().startswith(command + " ")]
        assert len(lines) == 1, command


def test_characterize_refuses_other_kinds_of_file(tmp_path, capsys):
    import numpy as np

    np.save(tmp_path / "channels.npy", np.zeros(3))
    (tmp_path / "table.csv").write_text("a,b\n1,2\n")
    (tmp_path / "binary.toml").write_bytes(b"\x93NUMPY\x00\xff")
    for name in ("channels.npy", "table.csv", "binary.toml"):
        assert main(["characterize", str(tmp_path / name), "--out", str(tmp_path / "out")]) == 2
        assert "expected a TOML scene" in capsys.readouterr().err, name


def _scatmech_style_file(path, eta=1.39 - 0.34j, sigma=0.3):
    import numpy as np

    from scatterlab.io import MuellerBRDF, write_mueller_brdf
    from scatterlab.pbrdf import Model

    rng = np.random.default_rng(5)
    ti = np.radians(np.r_[np.full(12, 30.0), np.full(8, 50.0)])
    tr = np.radians(np.r_[np.linspace(5, 75, 12), np.linspace(15, 70, 8)])
    phi = np.r_[np.tile([0.0, np.pi], 6), np.linspace(np.pi / 3, np.pi, 8)]
    M = Model(sigma).mueller(eta, ti, tr, phi)
    M = M + 0.005 * M[:, :1, :1] * rng.standard_normal(M.shape)
    return write_mueller_brdf(
        path,
        MuellerBRDF(1.55e-6, ti, tr, phi, M),
        normalised=True,
        signed=True,
        time_convention="exp(-iwt)",
        description="simulated",
    )


def test_fit_mueller_fits_a_scatmech_style_file_and_writes_its_report(tmp_path, capsys):
    import json

    import pytest

    path = _scatmech_style_file(tmp_path / "paint.csv")
    assert ",-" in path.read_text()  # signed polar angles in the file
    out = tmp_path / "fit"
    assert (
        main(["fit-mueller", str(path), "--out", str(out), "--time-convention", "exp(-iwt)"]) == 0
    )
    assert "n = 1.39" in capsys.readouterr().out
    metrics = json.loads((out / "metrics.json").read_text())["fit"]
    # 0.5 % noise of m11 on 16 elements x 20 geometries: within 4 standard errors (seed fixed)
    for name, truth in (("n", 1.39), ("kappa", 0.34), ("sigma", 0.3)):
        assert metrics[name] == pytest.approx(truth, abs=4 * metrics["errors"][name])
    report = (out / "report.md").read_text()
    assert "explains" in report and "signed observation angles" in report
    assert (out / "elements.png").stat().st_size > 0 and (out / "residuals.png").stat().st_size > 0
    assert main(["fit-mueller", str(path), "--out", str(out)]) == 2  # report exists
    assert "--force" in capsys.readouterr().err
    # read in the wrong convention, the report says so; a posterior on request
    argv = ["fit-mueller", str(path), "--out", str(out), "--force", "--posterior-steps", "60"]
    assert main(argv) == 0
    report = (out / "report.md").read_text()
    assert "Time convention?" in report and "Posterior (emcee, 24 walkers x 60 steps" in report
    # said on the console too, not only in the file
    assert "time convention" in capsys.readouterr().err
    # a known roughness is held: said on the console and in the report, with a posterior of n, kappa
    argv = ["fit-mueller", str(path), "--out", str(out), "--force", "--sigma", "0.3"]
    assert main(argv + ["--time-convention", "exp(-iwt)", "--posterior-steps", "60"]) == 0
    out_text = capsys.readouterr().out
    assert "sigma = 0.3 (known)" in out_text
    assert "posterior (24 walkers x 60 steps): n = 1.3" in out_text
    report = (out / "report.md").read_text()
    assert "| sigma (rms facet slope) | 0.3 | known, held fixed |" in report
    assert "sigma = 0.3 known (median" in report
    metrics = json.loads((out / "metrics.json").read_text())["fit"]
    assert metrics["options"]["sigma_known"] == 0.3 and metrics["errors"]["sigma"] is None
    assert metrics["n"] == pytest.approx(1.39, abs=4 * metrics["errors"]["n"])
    assert main(argv[:-1] + ["3"]) == 2
    assert "--sigma must be a known rms slope in [0.001, 1.5], got 3" in capsys.readouterr().err
    # a smooth surface's known roughness below the fitted range (0.01) is held too, as fit-ellipsometry
    # and analyze take it; these data are of a rough one (0.3), whose off-specular light a surface of
    # 0.005 cannot give, and the fit says the data then do not determine n and kappa
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # the CLI prints a warning as a line of its own
        assert main(argv[:-1] + ["0.005"]) == 0
    said = capsys.readouterr()
    assert "sigma = 0.005 (known)" in said.out
    assert "do not determine n and kappa" in said.err


def test_fit_mueller_bad_input_exit_codes(tmp_path, capsys):
    from scatterlab.io import MuellerBRDF, read_mueller_brdf, write_mueller_brdf

    path = _scatmech_style_file(tmp_path / "p.csv")
    assert main(["fit-mueller", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "o")]) == 2
    assert "no such file: " in capsys.readouterr().err  # one line, not an OS error number
    data = read_mueller_brdf(path, time_convention="exp(-iwt)")
    two = MuellerBRDF(
        list(data.wavelength) + [1.064e-6],
        list(data.theta_i) * 1 + [0.3],
        list(data.theta_r) + [0.3],
        list(data.phi) + [3.0],
        list(data.mueller) + [data.mueller[0]],
    )
    write_mueller_brdf(tmp_path / "two.csv", two)
    assert main(["fit-mueller", str(tmp_path / "two.csv"), "--out", str(tmp_path / "o")]) == 2
    assert "--wavelength-um" in capsys.readouterr().err
    # a wavelength not in the file: the message stays in the unit the user typed
    argv = ["fit-mueller", str(tmp_path / "two.csv"), "--out", str(tmp_path / "o")]
    assert main([*argv, "--wavelength-um", "1.6"]) == 2
    err = capsys.readouterr().err
    assert "--wavelength-um 1.6 is not in" in err and "[um]: 1.064, 1.55" in err


def test_subcommand_usage_and_python_dash_m():
    import subprocess
    import sys

    run = subprocess.run(
        [sys.executable, "-m", "scatterlab", "study", "--help"], capture_output=True, text=True
    )
    assert run.returncode == 0 and run.stdout.startswith("usage: scatterlab study [-h]"), run


def test_workers_below_one_are_refused(tmp_path, capsys):
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path), "--workers", "0"]) == 2
    assert "--workers" in capsys.readouterr().err
    argv = ["characterize", "--quick", "--out", str(tmp_path / "c"), "--workers", "-1"]
    assert main(argv) == 2
    assert "--workers" in capsys.readouterr().err


def test_an_input_error_inside_a_parallel_task_is_one_line(tmp_path, capsys):
    """A ValueError met inside a task of the executor is the user's input, not a defect: one line and
    exit code 2, as outside it. Anything else keeps its traceback."""
    import pytest

    from scatterlab.cli import _report
    from scatterlab.runtime.executors import TaskError

    class Args:
        workers, scheduler = 1, None

    def job(ex):
        return ex.map(lambda t: (_ for _ in ()).throw(ValueError(f"bad input {t}")), [3])

    assert _report(Args, job) == 2
    assert capsys.readouterr().err.strip() == "scatterlab: bad input 3"

    def bug(ex):
        return ex.map(lambda t: 1 / 0, [0])

    with pytest.raises(TaskError):
        _report(Args, bug)


def _dolp_table(path, header, rows):
    import numpy as np

    np.savetxt(path, rows, delimiter=",", header=header, comments="")
    return str(path)


def test_fit_dolp_recovers_the_index_from_a_table_of_dolp(tmp_path, capsys):
    """A user's DOLP table (made here from the pBRDF with noise 0.01): the command's 95 % intervals hold
    the index the data were made from, and its report is written."""
    import re

    import numpy as np

    from scatterlab.inversion import model_dolp

    th = np.arange(20.0, 71.0, 10.0)
    rng = np.random.default_rng(3)
    d = model_dolp(1.5, 0.1, 0.3, np.radians(th), np.radians(th)) + 0.01 * rng.standard_normal(6)
    path = _dolp_table(tmp_path / "d.csv", "theta,dolp,std_dolp", np.c_[th, d, np.full(6, 0.01)])
    argv = ["fit-dolp", path, "--out", str(tmp_path / "o"), "--sigma", "0.3"]
    assert main([*argv, "--posterior-steps", "400"]) == 0
    out = capsys.readouterr().out
    assert "n = " in out and "(sigma 0.3 known)" in out
    text = (tmp_path / "o" / "report.md").read_text()
    for name, truth in (("n", 1.5), ("kappa", 0.1)):
        lo, hi = map(
            float, re.search(rf"\| {name} \| [^|]+\| [^|]+\| \[([^,]+), ([^\]]+)\]", text).groups()
        )
        assert lo <= truth <= hi, (name, lo, hi)


def test_fit_dolp_bad_tables_are_one_line_errors(tmp_path, capsys):
    import numpy as np

    rows = np.c_[[30.0, 40, 50], [0.4, 0.6, 0.8]]
    cases = [
        (_dolp_table(tmp_path / "a.csv", "theta,p_measured", rows), "missing column for dolp"),
        (
            _dolp_table(tmp_path / "b.csv", "theta,dolp", np.c_[rows[:, 0], [0.4, 1.5, 0.8]]),
            "outside [0, 1]",
        ),
        (_dolp_table(tmp_path / "c.csv", "theta_i,dolp", rows), "give both theta_i and theta_r"),
        (
            _dolp_table(tmp_path / "d.csv", "theta,dolp", np.c_[[30.0, 95, 50], rows[:, 1]]),
            "outside [-90, 90]",
        ),
        (str(tmp_path / "missing.csv"), "no such file"),
    ]
    for path, message in cases:
        assert main(["fit-dolp", path, "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, err
    assert main(["fit-dolp", cases[0][0], "--sigma", "-1", "--out", str(tmp_path / "o")]) == 2
    assert "--sigma must be" in capsys.readouterr().err
    argv = ["fit-dolp", cases[0][0], "--posterior-steps", "-5", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert "--posterior-steps must be an integer >= 20" in capsys.readouterr().err


def test_fit_dolp_column_names_a_users_column(tmp_path, capsys):
    """A column the reader does not recognise: the error names --column, and with it the fit runs."""
    import numpy as np

    from scatterlab.inversion import model_dolp

    th = np.arange(20.0, 71.0, 10.0)
    d = model_dolp(1.5, 0.1, 0.3, np.radians(th), np.radians(th))
    path = _dolp_table(tmp_path / "p.csv", "aoi,p_measured", np.c_[th, d])
    argv = ["fit-dolp", path, "--out", str(tmp_path / "o"), "--sigma", "0.3", "--noise", "0.01"]
    assert main(argv) == 2
    assert "--column dolp=NAME" in capsys.readouterr().err
    assert main([*argv, "--column", "dolp = p_measured", "--posterior-steps", "200"]) == 0
    assert "n = " in capsys.readouterr().out
    assert main([*argv, "--column", "dolp:p_measured"]) == 2
    err = capsys.readouterr().err
    assert "--column must be KEY=NAME" in err and "Traceback" not in err
    assert main([*argv, "--column", "dolp=p_measured"]) == 2  # the report exists: no sampling
    assert "exists; pass --force to replace it" in capsys.readouterr().err


def test_fit_ellipsometry_recovers_the_example_and_reports(tmp_path, capsys):
    """The bundled in-plane example (simulated aluminium, 1.226 - j10.413, sigma 0.43, element noise
    0.002): the fit's 2-sigma intervals hold the truth; the wrong time convention is told in the report."""
    import json
    from pathlib import Path

    example = Path(__file__).parents[1] / "data" / "examples" / "ellipsometry_in_plane.csv"
    out = tmp_path / "o"
    assert main(["fit-ellipsometry", str(example), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    assert "n = " in printed.out and "warning" not in printed.err, printed.err
    m = json.loads((out / "metrics.json").read_text())
    for name, truth, err in zip(("n", "kappa", "sigma"), (1.226, 10.413, 0.43), m["errors_1sigma"]):
        assert abs(m[name] - truth) <= 2 * err, (name, m[name], err)
    assert m["goodness"] < 2 and m["success"]
    assert (out / "elements_vs_angle.png").stat().st_size > 0
    assert "does not fit" not in (out / "report.md").read_text()
    # the other time convention flips m34: no fit within the errors, and the report says so
    argv = ["fit-ellipsometry", str(example), "--out", str(out), "--force"]
    assert main([*argv, "--time-convention", "exp(-iwt)"]) == 0
    assert "does not fit these data within their errors" in (out / "report.md").read_text()
    err = capsys.readouterr().err
    assert "other time convention (--time-convention)" in err, err
    assert "does not fit within the stated errors" in err
    assert main(argv[:-1]) == 2  # without --force the report is kept
    assert "exists" in capsys.readouterr().err
    # known roughness: sigma held, no error stated for it
    assert main([*argv, "--sigma", "0.43"]) == 0
    assert "sigma = 0.43 (known)" in capsys.readouterr().out
    m = json.loads((out / "metrics.json").read_text())
    assert m["sigma"] == 0.43 and m["errors_1sigma"][2] == 0
    assert abs(m["n"] - 1.226) <= 2 * m["errors_1sigma"][0]
    assert main([*argv, "--sigma", "3"]) == 2
    assert "--sigma must be" in capsys.readouterr().err
    # every spelling the readers take: exp(-jwt) is exp(-iwt), the misfit is told as above
    assert main([*argv, "--time-convention", "exp(-j omega t)"]) == 0
    assert "other time convention (--time-convention)" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([*argv, "--time-convention", "exp(jwt"])
    assert "is not a time convention: exp(+jwt)" in capsys.readouterr().err


def test_fit_ellipsometry_warns_of_a_parameter_on_the_fit_bound(tmp_path, capsys):
    """A metal beyond the fit's box (kappa 40 > 30): kappa ends on the bound, which is said on screen."""
    import numpy as np

    from scatterlab.ellipsometry import model_elements
    from scatterlab.ellipsometry.fit import FIT_BOUNDS

    theta = np.arange(20.0, 75.0, 5.0)
    el = model_elements(np.radians(theta), 2.0, 40.0, 0.3)
    rows = [",".join(f"{v:.12g}" for v in (t, *e)) for t, e in zip(theta, el)]
    (tmp_path / "e.csv").write_text("theta,m12,m22,m33,m34\n" + "\n".join(rows) + "\n")
    assert main(["fit-ellipsometry", str(tmp_path / "e.csv"), "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert f"kappa = {FIT_BOUNDS[1][1]:.4g} is a bound of the fit" in err, err
    assert "kappa in [0, 30]" in (tmp_path / "o" / "report.md").read_text()


@pytest.mark.parametrize(
    "command, example, other",
    [
        ("fit-ellipsometry", "dolp_paint.csv", "fit-dolp"),
        ("fit-dolp", "ellipsometry_in_plane.csv", "fit-ellipsometry"),
        ("fit-mueller", "ellipsometry_in_plane.csv", "fit-ellipsometry"),
        ("fit-dolp", "mueller_brdf_two_wavelengths.csv", "fit-mueller"),
    ],
)
def test_fit_commands_name_the_command_for_another_commands_table(
    command, example, other, tmp_path, capsys
):
    from pathlib import Path

    path = Path(__file__).parents[1] / "data" / "examples" / example
    assert main([command, str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"looks like a table for `scatterlab {other}`" in err and "Traceback" not in err, err
    assert not (tmp_path / "o").exists()


def test_fit_dolp_with_as_many_parameters_as_rows_says_so(tmp_path, capsys):
    """Four rows for n, kappa, sigma and an inferred noise: the advice names that, not only a longer
    chain."""
    path = tmp_path / "four.csv"
    path.write_text("theta,dolp\n30,0.30\n45,0.55\n60,0.80\n70,0.7\n")
    argv = ["fit-dolp", str(path), "--out", str(tmp_path / "o"), "--posterior-steps", "300"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "not converged (the warning above says why)" in err
    assert "4 rows for 4 free parameters (the DOLP noise is one)" in err
    assert "--posterior-steps N (this run: 300)" in err


def test_fit_ellipsometry_column_and_bad_file(tmp_path, capsys):
    from pathlib import Path

    example = Path(__file__).parents[1] / "data" / "examples" / "ellipsometry_in_plane.csv"
    text = example.read_text().replace("theta,m12", "incidence_angle,m12")
    (tmp_path / "e.csv").write_text(text)
    argv = ["fit-ellipsometry", str(tmp_path / "e.csv"), "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--column theta=NAME" in err and "Traceback" not in err
    assert main([*argv, "--column", "theta=incidence_angle"]) == 0
    # an element under the instrument's own name
    (tmp_path / "m.csv").write_text(text.replace(",m34", ",circ"))
    argv = ["fit-ellipsometry", str(tmp_path / "m.csv"), "--out", str(tmp_path / "m")]
    argv += ["--column", "theta=incidence_angle"]
    assert main(argv) == 2
    assert "--column m34=NAME" in capsys.readouterr().err
    assert main([*argv, "--column", "m34=circ"]) == 0
    assert "kappa = 10.4" in capsys.readouterr().out
    assert main([*argv, "--column", "m34=circ", "--column", "m5=x", "--force"]) == 2
    assert "or a Mueller element" in capsys.readouterr().err
    assert main(["fit-ellipsometry", str(tmp_path / "none.csv")]) == 2
    assert "no such file" in capsys.readouterr().err
    # radians read as degrees: refused on screen, naming the option, and no report written
    lines = [x for x in example.read_text().splitlines() if x and not x.startswith("#")]
    rows = [x.split(",") for x in lines[1:]]
    rad = "\n".join(
        [lines[0]] + [",".join([f"{float(r[0]) * 3.14159265 / 180:.6f}", *r[1:]]) for r in rows]
    )
    (tmp_path / "rad.csv").write_text(rad + "\n")
    argv = ["fit-ellipsometry", str(tmp_path / "rad.csv"), "--out", str(tmp_path / "r")]
    assert main(argv) == 2
    assert "--angle-unit rad" in capsys.readouterr().err
    assert not (tmp_path / "r" / "report.md").exists()


def test_shadowing_choices_are_the_models_and_are_checked_before_reading(tmp_path, capsys):
    """--shadowing offers exactly the pBRDF's shadowing models, and a wrong one stops the command
    before the file is read (argparse), not after."""
    from scatterlab.pbrdf.shadowing import SHADOWING

    with pytest.raises(SystemExit):
        main(["fit-mueller", str(tmp_path / "missing.csv"), "--shadowing", "foo"])
    err = capsys.readouterr().err
    assert "invalid choice: 'foo'" in err and "no such file" not in err
    for name in SHADOWING:
        assert f"'{name}'" in err


def _paint_rows(std, scatter=0.0, theta=None):
    """Specular DOLP of a paint (1.39 - 0.34j, sigma 0.3) at ``theta`` [deg], with Gaussian ``scatter``, and
    a std column ``std``."""
    import numpy as np

    from scatterlab.inversion import model_dolp

    th = np.arange(20.0, 71.0, 5.0) if theta is None else np.asarray(theta, float)
    d = model_dolp(1.39, 0.34, 0.3, np.radians(th), np.radians(th))
    d = d + scatter * np.random.default_rng(0).standard_normal(th.size)
    return np.c_[th, d, np.full(th.size, std)]


def test_fit_dolp_refuses_radians_read_as_degrees(tmp_path, capsys):
    """Radians in a file read in degrees: a one-line error naming the column and the unit (read_dataset and
    the scene loader refuse the same), not a report of n = 0.02 with a zero-width interval."""
    import numpy as np

    rows = _paint_rows(0.005)
    path = _dolp_table(
        tmp_path / "rad.csv", "theta,dolp,std_dolp", np.c_[np.radians(rows[:, 0]), rows[:, 1:]]
    )
    assert main(["fit-dolp", path, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "column 'theta'" in err and "read in degrees" in err and "--angle-unit rad" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_fit_dolp_names_columns_it_does_not_use_and_lists_the_azimuths(tmp_path, capsys):
    import numpy as np

    rows = _paint_rows(0.01)
    fast = ["--sigma", "0.3", "--posterior-steps", "200"]
    # an error column under a name the reader does not take: said on screen and in the report
    path = _dolp_table(tmp_path / "u.csv", "theta,dolp,uncertainty", rows)
    assert main(["fit-dolp", path, "--out", str(tmp_path / "u"), *fast]) == 0
    err = capsys.readouterr().err
    assert "column 'uncertainty' not used" in err and "name it std_dolp" in err
    assert "--column std=uncertainty" in err
    report = (tmp_path / "u" / "report.md").read_text()
    assert "not used: 'uncertainty'" in report and "name it std_dolp" in report
    # any other column: named too; and the azimuths of a phi column are listed
    table = np.c_[rows[:, 0], np.zeros(len(rows)), rows[:, 1:], np.full(len(rows), 21.0)]
    path = _dolp_table(tmp_path / "t.csv", "theta,phi,dolp,std_dolp,temperature", table)
    assert main(["fit-dolp", path, "--out", str(tmp_path / "t"), *fast]) == 0
    err = capsys.readouterr().err
    assert "note:" in err and "column 'temperature' not used" in err
    report = (tmp_path / "t" / "report.md").read_text()
    assert "column 'temperature' not used" in report
    assert (
        f"column 'phi': relative azimuths phi = phi_r - phi_i used [deg]: 0 ({len(rows)} rows)"
        in report
    )


def test_fit_dolp_shows_the_misfit_and_the_goodness_of_fit_beside_the_estimates(tmp_path, capsys):
    """A std column 10 times smaller than the scatter: the posterior's misfit message and its chi-square are
    on screen under the estimates and in the report right under the table, once."""
    rows = _paint_rows(0.005, scatter=0.05)
    path = _dolp_table(tmp_path / "s.csv", "theta,dolp,std_dolp", rows)
    argv = [
        "fit-dolp",
        path,
        "--out",
        str(tmp_path / "o"),
        "--sigma",
        "0.3",
        "--posterior-steps",
        "200",
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].startswith("n = ")
    assert lines[1].startswith("goodness of fit under the stated DOLP errors: chi-square")
    assert "the data do not fit the model within their errors" in lines[1]
    assert any(
        ln.startswith("warning: the data do not fit the model within their stated errors")
        for ln in lines
    )
    report = (tmp_path / "o" / "report.md").read_text()
    under = report.split("| parameter |")[1].split("Diagnostics:")[
        0
    ]  # the table and what follows it
    assert "Goodness of fit under the stated errors: chi-square" in under
    assert "**the data do not fit the model within these errors**" in under
    assert "- the data do not fit the model within their stated errors" in under
    assert report.count("do not fit the model within their stated errors") == 1  # said once


def test_every_seed_and_integer_option_is_named_in_its_error(tmp_path, capsys):
    path = _dolp_table(tmp_path / "d.csv", "theta,dolp", _paint_rows(0.01)[:, :2])
    cases = [
        (["fit-dolp", path, "--seed", "-3"], "--seed must be a non-negative integer, got -3"),
        (["fit-mueller", path, "--seed", "-3"], "--seed must be a non-negative integer, got -3"),
        (
            ["fit-mueller", path, "--posterior-steps", "-1"],
            "--posterior-steps must be a non-negative integer",
        ),
        (["analyze", "x.h5", "--seed", "-1"], "--seed must be a non-negative integer, got -1"),
        (["study", "run", "fig4", "--seed", "-1"], "--seed must be a non-negative integer, got -1"),
        (
            ["fit-dolp", path, "--posterior-steps", "5"],
            "--posterior-steps must be an integer >= 20",
        ),
        (["analyze", "x.h5", "--iterations", "0"], "--iterations"),
        (["characterize", "--workers", "0"], "--workers"),
    ]
    for argv, message in cases:
        assert main([*argv, "--out", str(tmp_path / "o")]) == 2, argv
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, (argv, err)
    assert not (tmp_path / "o").exists()
    with pytest.raises(SystemExit):  # not an integer: argparse names the option
        main(["fit-dolp", path, "--seed", "x"])
    assert "argument --seed: invalid int value" in capsys.readouterr().err


def test_fit_dolp_of_glass_states_the_priors_and_says_one_thing_about_kappa(tmp_path, capsys):
    """A new user's glass table (n 1.5, kappa 0, sigma 0.2; columns aoi, DOP, std_dolp): the report
    and the screen state the prior ranges, and each statement about kappa names the least-squares
    minimum it is about, so an infinite variance is never said beside the table's finite one."""
    import numpy as np

    from scatterlab.inversion import model_dolp

    deg = np.linspace(20, 70, 8)
    t = np.radians(deg)
    y = model_dolp(1.5, 0.0, 0.2, t, t) + 0.005 * np.random.default_rng(4).standard_normal(8)
    path = _dolp_table(tmp_path / "glass.csv", "aoi,DOP,std_dolp", np.c_[deg, y, np.full(8, 0.005)])
    argv = ["fit-dolp", path, "--out", str(tmp_path / "o"), "--posterior-steps", "200"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    priors = "Priors: n uniform on [0, 5]; kappa uniform on [0, 25]; sigma uniform on [0.01, 1.5]"
    report = (tmp_path / "o" / "report.md").read_text()
    assert priors in out and priors in report
    for text in (out, report):
        inf = [line for line in text.splitlines() if "Laplace error is inf" in line]
        assert inf and all("not the table's" in line for line in inf)
        near = [line for line in text.splitlines() if "within one error of the prior bound" in line]
        assert len(near) == 1 and "kappa = 0.06779 +/- 0.97" in near[0] and "1 of 2" in near[0]
    assert "one posterior mode (from 2 least-squares minima" in report or "**multimodal**" in report
