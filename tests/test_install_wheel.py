"""A normal (non-editable) install works: the wheel holds the library, its data and the studies.

The slow test builds an sdist from a clean copy of the source tree (it must hold data/, docs and tests),
then a wheel from that sdist, installs it with ``--no-deps``
into a fresh virtual environment that sees this environment's installed dependencies through a
``.pth`` file (but not the source tree), and runs the command line from a folder outside the
repository. The fast test checks
that the explicit package list of pyproject.toml names every package of the source tree.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
IGNORE = shutil.ignore_patterns(
    ".git",
    ".venv",
    "results",
    "build",
    "dist",
    "*.egg-info",
    "__pycache__",
    ".pytest_cache",
    ".hypothesis",
    "*.pyc",
)


def _source_packages() -> set[str]:
    """Dotted names of the packages in the source tree, as the wheel must hold them."""
    names = {
        ".".join(p.parent.relative_to(ROOT).parts)
        for p in (ROOT / "scatterlab").rglob("__init__.py")
    }
    names |= {
        ".".join(("scatterlab",) + p.parent.relative_to(ROOT).parts)
        for p in (ROOT / "studies").rglob("__init__.py")
    }
    return names


def test_pyproject_lists_every_package():
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert set(tool["packages"]) == _source_packages(), (
        "pyproject.toml [tool.setuptools] packages must list every package "
        "(a new subpackage needs a line)"
    )
    assert tool["package-dir"] == {"scatterlab.studies": "studies"}
    assert not (ROOT / "scatterlab" / "studies").exists(), "studies/ stays at the top level"


def _run(cmd, cwd, env):
    done = subprocess.run(
        [str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, timeout=900
    )
    assert done.returncode == 0, f"{cmd} failed:\n{done.stdout}\n{done.stderr}"
    return done.stdout


def _fresh_env_seeing_installed_dependencies(path: Path) -> Path:
    """A venv without pip whose sys.path ends with this environment's site-packages (no sources)."""
    venv.EnvBuilder(with_pip=False).create(path)
    python = path / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    site = Path(
        _run(
            [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            path,
            _clean_env(),
        ).strip()
    )
    ours = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "_scatterlab_test_deps.pth").write_text("\n".join(sorted(ours)) + "\n")
    return python


def _clean_env() -> dict:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYTHONPATH", "PYTHONHOME", "SCATTERLAB_STUDIES")
    }
    env.update(MPLBACKEND="Agg", SCATTERLAB_PROGRESS="0", OMP_NUM_THREADS="1")
    return env


def _build_sdist_then_wheel(src: Path, tmp_path: Path, env: dict) -> tuple[Path, Path]:
    """The sdist of ``src``, and the wheel built from that sdist (not from the source tree), with the
    build backend pyproject.toml asks for, installed once into a folder of its own."""
    backend = tmp_path / "backend"
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    _run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--target", backend, *requires],
        tmp_path,
        env,
    )
    env = dict(env, PYTHONPATH=str(backend))
    build = "import sys, setuptools.build_meta as b; print(getattr(b, sys.argv[1])(sys.argv[2]))"
    dist = tmp_path / "dist"
    sdist = dist / _run([sys.executable, "-c", build, "build_sdist", dist], src, env).split()[-1]
    with tarfile.open(sdist) as tar:
        tar.extractall(tmp_path / "unpacked", filter="data")
    (unpacked,) = (tmp_path / "unpacked").iterdir()
    wheel = (
        dist / _run([sys.executable, "-c", build, "build_wheel", dist], unpacked, env).split()[-1]
    )
    return sdist, wheel


def _check_sdist(sdist: Path) -> None:
    """The sdist holds the repository's data/ folder (scenes, reference numbers, examples), docs, tests."""
    with tarfile.open(sdist) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
    data = {
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "data").rglob("*")
        if p.is_file() and "__pycache__" not in p.parts
    }
    assert "data/README.md" in data and any(n.startswith("data/examples/") for n in data)
    assert data <= names, sorted(data - names)
    assert {"LICENSE", "README.md", "tests/test_install_wheel.py", "docs/conventions.md"} <= names
    assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)


@pytest.mark.slow
def test_wheel_installs_and_runs_outside_the_repository(tmp_path):
    env = _clean_env()
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=IGNORE)
    sdist, wheel = _build_sdist_then_wheel(src, tmp_path, env)
    _check_sdist(sdist)

    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/", 1)[0] for n in names}
    assert tops == {"scatterlab", next(t for t in tops if t.endswith(".dist-info"))}, tops
    assert "scatterlab/studies/fig4_fresnel_reflectances.py" in names
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names), (
        "the license ships in the wheel"
    )
    assert "scatterlab/studies/performance/perf_phase_screens.py" in names
    assert _source_packages() <= {n.rsplit("/", 1)[0].replace("/", ".") for n in names}
    npz = sorted(p.name for p in (ROOT / "scatterlab" / "pbrdf" / "data").glob("*.npz"))
    assert npz and all(f"scatterlab/pbrdf/data/{n}" in names for n in npz)
    csv = sorted(p.name for p in (ROOT / "scatterlab" / "data" / "reference").glob("*.csv"))
    assert csv and all(f"scatterlab/data/reference/{n}" in names for n in csv)

    python = _fresh_env_seeing_installed_dependencies(tmp_path / "venv")
    _run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            python,
            "install",
            "--quiet",
            "--no-deps",
            "--no-index",
            wheel,
        ],
        tmp_path,
        env,
    )
    work = tmp_path / "elsewhere"
    work.mkdir()
    where = _run(
        [
            python,
            "-c",
            "import scatterlab, scatterlab.studies as s, scatterlab.reference_data as r; "
            "print(scatterlab.__file__); print(s.__file__); "
            "print(len(r.table('table4_classification')))",
        ],
        work,
        env,
    )
    lib, studies, rows = where.split("\n")[:3]
    site = str(tmp_path / "venv")
    assert lib.startswith(site) and studies.startswith(site), where
    assert rows == "12"

    scatterlab = python.parent / ("scatterlab.exe" if os.name == "nt" else "scatterlab")
    listing = _run([scatterlab, "study", "list"], work, env)
    from scatterlab.study_runner import discover

    listed = {line.split()[0] for line in listing.splitlines() if line.strip()}
    assert listed == set(discover())
    out = tmp_path / "fig4"
    _run([scatterlab, "study", "run", "fig4", "--quick", "--out", out], work, env)
    assert (out / "report.md").is_file() and (out / "fig4.png").is_file()

    # measured data after a normal install: a Mueller BRDF fit and an analysis of a dataset, both from files
    # copied outside the repository (the examples are not in the wheel)
    examples = ROOT / "data" / "examples"
    shutil.copy(examples / "mueller_brdf_scatmech_style.csv", work)
    shutil.copy(examples / "painted_plate.h5", work)
    _run(
        [
            scatterlab,
            "fit-mueller",
            "mueller_brdf_scatmech_style.csv",
            "--time-convention",
            "exp(-iwt)",
            "--out",
            tmp_path / "fit",
        ],
        work,
        env,
    )
    assert (tmp_path / "fit" / "report.md").is_file()
    _run(
        [
            scatterlab,
            "analyze",
            "painted_plate.h5",
            "--iterations",
            "4",
            "--posterior-steps",
            "200",
            "--out",
            tmp_path / "analyze",
        ],
        work,
        env,
    )
    assert (tmp_path / "analyze" / "report.md").is_file()
