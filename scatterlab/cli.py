"""The ``scatterlab`` command.

::

    scatterlab study list
    scatterlab study run ID [--quick] [--out DIR] [--seed N] [--force]
    scatterlab study run all [--quick] [--out DIR]
    scatterlab characterize [SCENE.toml] [--out DIR] [--force] [--quick]

Sweeps inside studies use ``--workers N`` local processes or a Dask cluster
given by ``--scheduler ADDRESS``.
"""

from __future__ import annotations

import argparse
import sys

__all__ = ["main"]


def _executor(args):
    from scatterlab.runtime import get_executor

    if args.scheduler:
        return get_executor("dask", scheduler=args.scheduler)
    if args.workers and args.workers > 1:
        return get_executor("processes", workers=args.workers)
    return get_executor("serial")


def _study(args) -> int:
    from scatterlab import study_runner as studies

    if args.action == "list":
        for sid, st in studies.discover().items():
            print(f"{sid:24s} {st.title}  [{st.reproduces}]")
        return 0
    if not args.id:
        print("scatterlab study run: give a study ID or 'all'", file=sys.stderr)
        return 2
    ex = _executor(args)
    try:
        if args.id == "all":
            index, status = studies.run_all(args.out, quick=args.quick, seed=args.seed, force=True,
                                            executor=ex)
            failed = {k: v for k, v in status.items() if v != "ok"}
            print(f"index: {index}")
            for k, v in failed.items():
                print(f"FAILED {k}: {v}", file=sys.stderr)
            return 1 if failed else 0
        report = studies.run_study(args.id, args.out, quick=args.quick, seed=args.seed, force=args.force,
                                   executor=ex)
        print(f"report: {report}")
        return 0
    except (ValueError, FileExistsError) as exc:
        print(f"scatterlab: {exc}", file=sys.stderr)
        return 2
    finally:
        ex.close()


def _characterize(args) -> int:
    from scatterlab.characterization import characterize, default_scene, load_scene

    try:
        cfg = load_scene(args.scene) if args.scene else default_scene()
        if args.quick:  # a small, fast version of the same scene (tests, smoke runs)
            cfg.image_size, cfg.geometry_deg, cfg.d_over_r0 = 64, cfg.geometry_deg[::3], cfg.d_over_r0[:1]
            cfg.iterations, cfg.posterior_steps = 15, 400
        ex = _executor(args)
        try:
            report = characterize(cfg, args.out, overwrite=args.force, executor=ex)
        finally:
            ex.close()
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        print(f"scatterlab: {exc}", file=sys.stderr)
        return 2
    print(f"report: {report}")
    return 0


def main(argv=None) -> int:
    """Entry point of the ``scatterlab`` command; returns the exit status."""
    parser = argparse.ArgumentParser(prog="scatterlab", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    st = sub.add_parser("study", help="list or run the studies that reproduce the reference figures")
    st.add_argument("action", choices=["list", "run"])
    st.add_argument("id", nargs="?", help="study id, or 'all'")
    st.add_argument("--quick", action="store_true", help="small sizes (under a minute per study)")
    st.add_argument("--out", default=None, help="output folder (default results/[quick/]ID)")
    st.add_argument("--seed", type=int, default=20101210, help="random seed recorded in metrics.json")
    st.add_argument("--force", action="store_true", help="replace an existing report")
    st.add_argument("--workers", type=int, default=None, help="local worker processes for sweeps")
    st.add_argument("--scheduler", default=None, help="Dask scheduler address for sweeps")
    ch = sub.add_parser("characterize", help="simulate, deconvolve, classify and characterize a scene (main job)")
    ch.add_argument("scene", nargs="?", help="scene description (TOML); default: the bundled painted plates")
    ch.add_argument("--out", default="results/characterize", help="output folder")
    ch.add_argument("--force", action="store_true", help="replace an existing report")
    ch.add_argument("--quick", action="store_true", help="smaller images, fewer geometries and iterations")
    ch.add_argument("--workers", type=int, default=None, help="local worker processes")
    ch.add_argument("--scheduler", default=None, help="Dask scheduler address")
    args = parser.parse_args(argv)
    if args.command == "study":
        return _study(args)
    if args.command == "characterize":
        return _characterize(args)
    return 2  # pragma: no cover


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
