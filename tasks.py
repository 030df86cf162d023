#!/usr/bin/env python3
"""The two set-up commands of the README.

    python3 tasks.py demo   # main job: create .venv, install scatterlab, run the default characterization
    python3 tasks.py test   # tests:    create .venv, install scatterlab[test], run ruff and pytest

Each creates the virtual environment ``.venv`` beside this file when missing and
(re)installs only when ``pyproject.toml`` changed since the last install, so a
second run is fast. Only the Python standard library is needed to start.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / ("python.exe" if os.name == "nt" else "python")


def _run(*cmd, **kw) -> int:
    print("+", " ".join(str(c) for c in cmd), flush=True)
    return subprocess.call([str(c) for c in cmd], cwd=ROOT, **kw)


def ensure_env(extras: str) -> None:
    if not PY.exists():
        print(f"creating virtual environment {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    digest = hashlib.sha256((ROOT / "pyproject.toml").read_bytes() + extras.encode()).hexdigest()
    stamp = VENV / f".installed-{extras or 'base'}"
    if stamp.exists() and stamp.read_text() == digest:
        return
    target = f".[{extras}]" if extras else "."
    if _run(PY, "-m", "pip", "install", "--quiet", "--upgrade", "pip") != 0:
        sys.exit("pip upgrade failed")
    if _run(PY, "-m", "pip", "install", "--quiet", "-e", target) != 0:
        sys.exit(f"installing {target} failed")
    stamp.write_text(digest)


def demo(args) -> int:
    """The main job: the default characterization (simulate -> deconvolve/classify -> n, kappa -> report)."""
    ensure_env("")
    out = ROOT / "results" / "characterize"
    workers = str(os.cpu_count() or 1)
    return _run(
        BIN / "scatterlab", "characterize", "--out", out, "--force", "--workers", workers, *args
    )


def test(args) -> int:
    """ruff (lint, then the format check) before pytest; the first failure stops."""
    ensure_env("test")
    env = dict(os.environ, MPLBACKEND="Agg", SCATTERLAB_PROGRESS="0")
    for check in (("check", "."), ("format", "--check", ".")):
        if _run(BIN / "ruff", *check) != 0:
            print(
                f"ruff {check[0]} failed: run `.venv/bin/ruff {' '.join(check)}` (format: `ruff format .`)"
            )
            return 1
    return _run(PY, "-m", "pytest", "-q", *args, env=env)


if __name__ == "__main__":
    commands = {"demo": demo, "test": test}
    if len(sys.argv) < 2 or sys.argv[1] not in commands:
        sys.exit(f"usage: python3 tasks.py {{{'|'.join(commands)}}} [extra args]")
    sys.exit(commands[sys.argv[1]](sys.argv[2:]))
