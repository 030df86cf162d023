"""The ``scatterlab`` command.

::

    scatterlab study list
    scatterlab study run ID [--quick] [--out DIR] [--seed N] [--force]
    scatterlab study run all [--quick] [--out DIR]
    scatterlab characterize [SCENE.toml] [--out DIR] [--force] [--quick] [--workers N] [--scheduler ADDR]
    scatterlab analyze DATASET [--out DIR] [--force] [--psf blind|diffraction] [--iterations N]
                     [--classes adaptive|priors] [--bias-samples N] [--model-error] [--frames F]
                     [--psf-refine none|layout] [--blind-starts K] [--bad-pixels MASK.tif|.npy]
                     [--full-well E]
    scatterlab fit-mueller FILE.csv [--out DIR] [--wavelength-um W] [--sigma S] [--time-convention exp(-iwt)]
    scatterlab fit-dolp FILE.csv [--out DIR] [--sigma S] [--noise N] [--angle-unit rad]
    scatterlab fit-ellipsometry FILE.csv [--out DIR] [--sigma S] [--time-convention exp(-iwt)]

Sweeps inside studies use ``--workers N`` local processes or a Dask cluster
given by ``--scheduler ADDRESS``.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings

__all__ = ["main"]


def _message(exc) -> str:
    """One line for the user: the file that is missing, or the input error a parallel task met."""
    from scatterlab.runtime.executors import TaskError

    if isinstance(exc, FileNotFoundError) and exc.filename:
        return f"no such file: {exc.filename}"
    if isinstance(exc, TaskError) and isinstance(exc.__cause__, ValueError):
        return str(exc.__cause__)
    return str(exc)


def _table_command(path) -> str | None:
    """The fit command whose table ``path`` looks like (by its column names), or None."""
    from scatterlab.io.table import read_table

    try:
        keys = set(read_table(path).keys)
    except (OSError, ValueError):
        return None
    if "dolp" in keys:
        return "fit-dolp"
    elements = {f"{p}{i}{j}" for p in ("m", "fr") for i in "1234" for j in "1234"}
    if "thetai" in keys and any(k.split("/")[0] in elements for k in keys):
        return "fit-mueller"
    if "theta" in keys and keys & {"m12", "m22", "m33", "m34"}:
        return "fit-ellipsometry"
    return None


def _other_command(exc, path, command: str) -> str:
    """A hint when a fit command is given another command's table (its columns are missing)."""
    if not isinstance(exc, ValueError) or "column" not in str(exc):
        return ""
    other = _table_command(path)
    if other is None or other == command:
        return ""
    return f"\n  {path} looks like a table for `scatterlab {other}`: try that command"


# the integer options' smallest values, by command (None: every command that has the option); the
# others are checked where they are used (--workers by _executor, analyze's by AnalyzeSettings,
# fit-dolp's --posterior-steps before reading)
INTEGER_MINIMA = {"seed": (None, 0), "posterior_steps": ("fit-mueller", 0)}


def _integer_option_error(args) -> str | None:
    """The one-line error for an integer option below its smallest value, naming the option, or None."""
    for name, (command, low) in INTEGER_MINIMA.items():
        value = getattr(args, name, None)
        if value is None or (command is not None and args.command != command):
            continue
        if value < low:
            what = "a non-negative integer" if low == 0 else f"an integer >= {low}"
            return f"--{name.replace('_', '-')} must be {what}, got {value}"
    return None


def _executor(args):
    from scatterlab.runtime import get_executor

    if args.scheduler:
        return get_executor("dask", scheduler=args.scheduler)
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be an integer >= 1, got {args.workers}")
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
    try:
        ex = _executor(args)
    except ValueError as exc:
        print(f"scatterlab: {_message(exc)}", file=sys.stderr)
        return 2
    try:
        if args.id == "all":
            index, status = studies.run_all(
                args.out, quick=args.quick, seed=args.seed, force=True, executor=ex
            )
            failed = {k: v for k, v in status.items() if v != "ok"}
            print(f"index: {index}")
            for k, v in failed.items():
                print(f"FAILED {k}: {v}", file=sys.stderr)
            return 1 if failed else 0
        report = studies.run_study(
            args.id, args.out, quick=args.quick, seed=args.seed, force=args.force, executor=ex
        )
        print(f"report: {report}")
        return 0
    except (ValueError, FileExistsError) as exc:
        print(f"scatterlab: {_message(exc)}", file=sys.stderr)
        return 2
    finally:
        ex.close()


DESCRIPTION = """\
scatterlab: polarimetric light scattering from rough surfaces. Simulates and inverts the
polarimetric BRDF (pBRDF) of rough surfaces, turbulence-degraded polarimetric images and Mueller
ellipsometry, and fits the complex index n - j kappa and roughness of materials to measured data.

commands:
  study          list or run the studies that reproduce the reference text's figures and tables
  characterize   simulate, deconvolve, classify and invert a painted-plate scene (TOML) end to end
  analyze        restore, classify and invert measured polarimetric channel images (a dataset) end to end
  fit-mueller    fit n, kappa, sigma of the pBRDF to a measured Mueller BRDF table (CSV) and report
  fit-dolp       posterior of n, kappa (and sigma) from measured DOLP against geometry (CSV) and report
  fit-ellipsometry
                 fit n, kappa, sigma to in-plane Mueller ellipsometry (m12, m22, m33, m34 vs angle)

Run `scatterlab COMMAND --help` for a command's options. Angles are in degrees on the command line
and in files, radians in the Python API.
"""


def _load_scene_file(path):
    """The scene of a TOML file; ValueError "expected a TOML scene" for any other kind of file."""
    import tomllib
    from pathlib import Path

    from scatterlab.characterization import load_scene

    p = Path(path)
    if p.suffix.lower() != ".toml":
        raise ValueError(
            f"expected a TOML scene (.toml), got {p.name!r}"
            + (
                " (a dataset of channel images, not a scene)"
                if p.suffix.lower() in (".h5", ".hdf5", ".npz", ".tif", ".tiff")
                else ""
            )
        )
    try:
        return load_scene(p)
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"expected a TOML scene: {p.name} is not valid TOML ({exc})") from None


def _report(args, job) -> int:
    """Run ``job(executor) -> report path`` with the executor of ``args``; print the report or the error."""
    from scatterlab.runtime.executors import TaskError

    try:
        ex = _executor(args)
        try:
            report = job(ex)
        finally:
            ex.close()
    except (ValueError, FileExistsError, FileNotFoundError, TaskError) as exc:
        if isinstance(exc, TaskError) and not isinstance(exc.__cause__, ValueError):
            raise  # a defect, not an input error: keep the traceback
        print(f"scatterlab: {_message(exc)}", file=sys.stderr)
        return 2
    print(f"report: {report}")
    return 0


def _characterize(args) -> int:
    from scatterlab.characterization import characterize, default_scene

    try:
        cfg = _load_scene_file(args.scene) if args.scene else default_scene()
    except (ValueError, FileNotFoundError) as exc:
        print(f"scatterlab: {_message(exc)}", file=sys.stderr)
        return 2
    if args.quick:  # a small, fast version of the same scene (tests, smoke runs)
        from scatterlab.characterization.scene_config import quick_scene

        try:
            cfg = quick_scene(cfg)
        except ValueError as exc:
            print(f"scatterlab: {_message(exc)}", file=sys.stderr)
            return 2
    return _report(args, lambda ex: characterize(cfg, args.out, overwrite=args.force, executor=ex))


def _analyze(args) -> int:
    from scatterlab.characterization.analysis import AnalyzeSettings, analyze

    given = {
        "psf": args.psf,
        "iterations": args.iterations,
        "priors": args.priors,
        "sigma": args.sigma,
        "posterior_steps": args.posterior_steps,
        "seed": args.seed,
        "classes": args.classes,
        "bias_samples": args.bias_samples,
        "model_error": args.model_error,
        "frames": args.frames,
        "psf_refine": args.psf_refine,
        "blind_starts": args.blind_starts,
    }
    try:
        settings = AnalyzeSettings(**given).validate()
    except ValueError as exc:
        # the settings name their field ("bias_samples must be ..."); on the command line it is a flag
        name, _, rest = str(exc).partition(" ")
        flag = f"--{name.replace('_', '-')}" if name in given else name
        print(f"scatterlab: {flag} {rest}", file=sys.stderr)
        return 2

    if args.full_well is not None and not (math.isfinite(args.full_well) and args.full_well > 0):
        print(
            f"scatterlab: --full-well must be a count > 0 photo-electrons, got {args.full_well}",
            file=sys.stderr,
        )
        return 2

    def run(ex):
        dataset = args.dataset
        if args.bad_pixels is not None or args.full_well is not None:
            from scatterlab.io import read_dataset, read_pixel_mask, with_pixel_mask

            mask = None if args.bad_pixels is None else read_pixel_mask(args.bad_pixels)
            with warnings.catch_warnings():  # about pixels the mask may list: said again if not
                warnings.simplefilter("ignore", UserWarning)
                ds = read_dataset(dataset)
            dataset = with_pixel_mask(ds, mask, full_well=args.full_well)
        return analyze(dataset, args.out, settings=settings, overwrite=args.force, executor=ex)

    return _report(args, run)


# the quantities whose column a user can name (--column KEY=NAME), as the readers' ``columns``
MUELLER_COLUMNS = ("wavelength", "theta_i", "phi_i", "theta_r", "phi_r", "phi")
DOLP_COLUMNS = ("theta", "theta_i", "theta_r", "phi", "dolp", "std")
ELLIPSOMETRY_COLUMNS = ("theta", "wavelength")


def _columns(pairs, keys, elements: bool = False) -> dict | None:
    """``--column KEY=NAME`` options as a reader's ``columns`` mapping (ValueError naming the option);
    with ``elements`` KEY may also be a Mueller element name (m12, f_r12, std_m12, m12/m11)."""
    from scatterlab.io.table import normalise_name, parse_element

    if not pairs:
        return None
    out = {}
    for pair in pairs:
        key, eq, name = pair.partition("=")
        key, name = key.strip(), name.strip()
        try:
            element = elements and parse_element(normalise_name(key)[0]) is not None
        except ValueError:  # m12/m22: normalised by another element than the first
            element = False
        if not eq or not name or (key not in keys and not element):
            raise ValueError(
                f"--column must be KEY=NAME with KEY one of {', '.join(keys)}"
                + (" or a Mueller element (m12, std_m12, ...)" if elements else "")
                + f" and NAME a column of the file, got {pair!r}"
            )
        out[key] = name
    return out


def _read_noting(reader, *args, **kwargs):
    """``reader(*args, **kwargs)``, its warnings printed as usual and kept in the data's ``notes``, so
    that the report says what the screen said (radians read as degrees, a header stating another unit)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        data = reader(*args, **kwargs)
    for w in caught:
        _show_warning(w.message, w.category, w.filename, w.lineno)
        data.notes.append(f"warning: {w.message}")
    return data


def _fit_mueller(args) -> int:
    import time

    import numpy as np

    from scatterlab.ellipsometry import fit_pbrdf
    from scatterlab.ellipsometry.pbrdf_fit import BOUNDS
    from scatterlab.ellipsometry.report import write_fit_report
    from scatterlab.io import read_mueller_brdf

    try:
        data = _read_noting(
            read_mueller_brdf,
            args.file,
            _columns(args.column, MUELLER_COLUMNS, elements=True),
            angle_unit=args.angle_unit,
            wavelength_unit=args.wavelength_unit,
            time_convention=args.time_convention,
        )
        if args.wavelength_um is not None:
            try:
                data = data.select(args.wavelength_um * 1e-6)
            except ValueError:  # no row at that wavelength: say so in the option's unit
                have = ", ".join(f"{w * 1e6:g}" for w in data.wavelengths)
                raise ValueError(
                    f"--wavelength-um {args.wavelength_um:g} is not in {args.file} "
                    f"(its wavelengths [um]: {have})"
                ) from None
        elif data.wavelengths.size > 1:
            have = ", ".join(f"{w * 1e6:g}" for w in data.wavelengths)
            raise ValueError(
                f"{args.file} holds several wavelengths ({have} um): choose one with "
                "--wavelength-um"
            )
        t0 = time.perf_counter()
        if args.sigma is not None and not 1e-3 <= args.sigma <= 1.5:
            raise ValueError(f"--sigma must be a known rms slope in [0.001, 1.5], got {args.sigma}")
        # a known roughness below the fitted range's lower edge (0.01) is held, not fitted: the range
        # reaches down to it (fit-ellipsometry and analyze take the same [0.001, 1.5])
        bounds = (
            BOUNDS
            if args.sigma is None
            else BOUNDS[:2] + ((min(BOUNDS[2][0], args.sigma), BOUNDS[2][1]),)
        )
        fit = fit_pbrdf(
            data,
            shadowing=args.shadowing,
            diffuse=args.diffuse,
            posterior_steps=args.posterior_steps,
            rng=args.seed,
            sigma=args.sigma,
            bounds=bounds,
        )
        report = write_fit_report(
            data,
            fit,
            args.out,
            source=args.file,
            convention=args.time_convention,
            seconds=time.perf_counter() - t0,
            overwrite=args.force,
        )
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        print(
            f"scatterlab: {_message(exc)}{_other_command(exc, args.file, 'fit-mueller')}",
            file=sys.stderr,
        )
        return 2
    e = fit.errors
    quality = (
        f"reduced chi^2 {fit.reduced_chi2:.3g}"
        if fit.weighted
        else f"rms residual {np.sqrt(fit.reduced_chi2):.3g}" + ("" if fit.normalised else " of m11")
    )
    sigma = f"{fit.sigma:.4g} +- {e[2]:.2g}" if args.sigma is None else f"{fit.sigma:.4g} (known)"
    print(
        f"n = {fit.n:.5g} +- {e[0]:.2g}, kappa = {fit.kappa:.5g} +- {e[1]:.2g}, "
        f"sigma = {sigma} ({quality})"
    )
    if fit.posterior is not None:
        med, sd = np.median(fit.posterior["samples"], 0), fit.posterior["samples"].std(0)
        print(
            f"posterior ({fit.posterior['walkers']} walkers x {fit.posterior['steps']} steps): "
            f"n = {med[0]:.5g} +- {sd[0]:.2g}, kappa = {med[1]:.5g} +- {sd[1]:.2g}"
            + ("" if args.sigma is not None else f", sigma = {med[2]:.4g} +- {sd[2]:.2g}")
        )
    if not fit.success:
        print(
            "scatterlab: warning: the fit did not converge: these numbers are not an estimate (report.md says "
            "why; check the angle unit, --angle-unit, and the time convention)",
            file=sys.stderr,
        )
    if fit.circular_flip_ratio < 0.25:
        print(
            f"scatterlab: warning: the data fit {1 / fit.circular_flip_ratio:.3g} times better with their circular "
            "elements sign-flipped: the file is probably in the other time convention "
            "(--time-convention)",
            file=sys.stderr,
        )
    print(f"report: {report}")
    return 0


def _fit_dolp(args) -> int:
    import numpy as np

    from scatterlab.inversion import ConvergenceWarning, MisfitWarning, sample_posterior
    from scatterlab.inversion.report import posterior_report, prior_line
    from scatterlab.io.dolp_table import UNUSED_NOTE, read_dolp_table

    try:
        if args.sigma is not None and not 1e-3 <= args.sigma <= 2.5:
            raise ValueError(f"--sigma must be a known rms slope in [0.001, 2.5], got {args.sigma}")
        if args.noise is not None and not (np.isfinite(args.noise) and args.noise > 0):
            raise ValueError(f"--noise must be a DOLP standard deviation > 0, got {args.noise}")
        if args.posterior_steps is not None and args.posterior_steps < 20:
            raise ValueError(
                "--posterior-steps must be an integer >= 20 (or left out: run until converged), "
                f"got {args.posterior_steps}"
            )
        from pathlib import Path

        data = _read_noting(
            read_dolp_table,
            args.file,
            _columns(args.column, DOLP_COLUMNS),
            angle_unit=args.angle_unit,
        )
        # a column the reader left out (one that looks like the DOLP error has been warned of already)
        for note in data.notes:
            if UNUSED_NOTE in note and not note.startswith("warning:"):
                print(f"scatterlab: note: {args.file}: {note}", file=sys.stderr)
        # report.md like the other commands' reports; refused before the sampling, in the command
        # line's words
        if (Path(args.out) / "report.md").exists() and not args.force:
            raise FileExistsError(
                f"{Path(args.out) / 'report.md'} exists; pass --force to replace it"
            )
        # the error: --noise, else the file's per-row std (a diagonal covariance), else inferred
        noise = args.noise
        cov = np.diag(data.std**2) if noise is None and data.std is not None else None
        with warnings.catch_warnings():
            # kept in post.messages: said beside the estimates below, on screen and in the report
            warnings.simplefilter("ignore", ConvergenceWarning)
            warnings.simplefilter("ignore", MisfitWarning)
            post = sample_posterior(
                data.dolp,
                data.theta_i,
                data.theta_r,
                noise,
                args.seed,
                phi=data.phi,
                sigma=args.sigma,
                covariance=cov,
                n_steps=args.posterior_steps,
            )
        error = (
            f"--noise {args.noise:g} for every row"
            if args.noise is not None
            else "the file's std column (one standard deviation per row)"
            if cov is not None
            else "inferred from the scatter about the model (no std column, no --noise"
            + (f"; not used: {', '.join(map(repr, data.unused))})" if data.unused else ")")
        )
        fit_lines = _fit_check_lines(post, inferred=noise is None and cov is None)
        report = posterior_report(
            post,
            args.out,
            "report",
            rng=args.seed,
            overwrite=args.force,
            title=f"Posterior of n - j kappa from {Path(args.file).name}",
            notes=[
                f"{data.dolp.size} rows of DOLP from {args.file}; DOLP error: {error}",
                "roughness "
                + (f"sigma = {args.sigma:g} known" if args.sigma is not None else "sampled"),
                *data.notes,
            ],
        )
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        print(
            f"scatterlab: {_message(exc)}{_other_command(exc, args.file, 'fit-dolp')}",
            file=sys.stderr,
        )
        return 2
    s = post.summary()["parameters"]
    names = ("n", "kappa") if args.sigma is not None else ("n", "kappa", "sigma")
    print(
        ", ".join(
            f"{k} = {s[k]['median']:.4g} [68 %: {s[k]['ci68'][0]:.4g}, {s[k]['ci68'][1]:.4g}]"
            for k in names
        )
        + (f" (sigma {args.sigma:g} known)" if args.sigma is not None else "")
        + (
            ""
            if noise is not None or cov is not None
            else f"; DOLP noise inferred: {s['noise']['median']:.2g}"
            if "noise" in s
            else ""
        )
    )
    for line in fit_lines:
        print(line)
    print(prior_line(post))
    if not post.converged:  # the lines above say why; say how in the command line's words
        reason = post.convergence_reason
        rows, free = data.dolp.size, len(names) + (noise is None and cov is None)
        advice = []
        if "shorter than" in reason or "R-hat" in reason:
            advice.append(
                "a longer chain with --posterior-steps N (this run: "
                f"{args.posterior_steps or 'until converged, up to the sampler limit'})"
            )
        if "acceptance" in reason or rows <= free + 1:
            advice.append(
                f"{rows} rows for {free} free parameters"
                + (" (the DOLP noise is one)" if noise is None and cov is None else "")
                + ": the data barely constrain them; add geometries, fix the roughness with "
                "--sigma, or give the DOLP error with --noise or a std column"
            )
        print(
            "scatterlab: not converged (the warning above says why): " + "; or ".join(advice),
            file=sys.stderr,
        )
    print(f"report: {report}")
    return 0


def _fit_check_lines(post, inferred: bool) -> list:
    """The goodness of fit and every message of a posterior, one line each, for the fit-dolp summary on
    screen, under the estimates they qualify (the report has them under its table).

    Parameters
    ----------
    post : scatterlab.inversion.Posterior
        The sampled posterior (its ``fit_check`` and ``messages``).
    inferred : bool
        The DOLP noise was inferred (no error given): there is no fit to test.

    Returns
    -------
    list of str
        ``"goodness of fit: ..."`` (when tested) and ``"warning: ..."`` lines.
    """
    from scatterlab.inversion.posterior import FIT_P_MIN

    lines = []
    g = post.fit_check
    if g is not None:
        lines.append(
            f"goodness of fit under the stated DOLP errors: chi-square {g['chi2']:.4g} for {g['dof']} "
            f"degrees of freedom, p = {g['p_value']:.2g}"
            + (
                f" < {FIT_P_MIN:g}: the data do not fit the model within their errors, the intervals "
                "are too narrow (errors understated? a wrong angle unit or azimuth?)"
                if g["p_value"] < FIT_P_MIN
                else ""
            )
        )
    elif inferred:
        lines.append(
            "goodness of fit: not tested (the DOLP noise is inferred from the scatter and absorbs any "
            "misfit; give the error with --noise or a std_dolp column to test it)"
        )
    lines += [f"warning: {m}" for m in post.messages]
    return lines


def _add_fit_dolp(sub):
    fd = sub.add_parser(
        "fit-dolp",
        help="n, kappa (and sigma) with their posterior from measured DOLP against geometry (CSV)",
        description="Posterior of the complex index n - j kappa and the roughness sigma from a table "
        "of DOLP against geometry: columns theta (specular) or theta_i and theta_r, optionally phi "
        "(relative azimuth, default 180), dolp, optionally std_dolp; angles in degrees. Writes a "
        "Markdown report with the posterior table, a corner plot and the posterior predictive.",
    )
    fd.add_argument("file", help="CSV table of DOLP against geometry")
    fd.add_argument("--out", default="results/fit-dolp", help="output folder")
    fd.add_argument("--force", action="store_true", help="replace an existing report")
    fd.add_argument(
        "--angle-unit", default="deg", choices=["deg", "rad"], help="unit of the angle columns"
    )
    fd.add_argument(
        "--sigma", type=float, default=None, help="known roughness (rms slope); default: sampled"
    )
    fd.add_argument(
        "--noise",
        type=float,
        default=None,
        help="DOLP standard deviation of every row (default: the file's std column, else inferred)",
    )
    fd.add_argument(
        "--posterior-steps",
        type=int,
        default=None,
        help="MCMC chain length, >= 20 (default: run until converged)",
    )
    fd.add_argument("--seed", type=int, default=20101210, help="random seed (default 20101210)")
    fd.add_argument(
        "--column",
        action="append",
        default=[],
        metavar="KEY=NAME",
        help="the file's column NAME holds quantity KEY (theta, theta_i, theta_r, phi, dolp, std); repeatable",
    )


def _time_convention(text: str) -> str:
    """``--time-convention``: any spelling the readers accept (``exp(-jwt)``, ``exp(- i omega t)``)."""
    from scatterlab.io.table import time_convention_flip

    try:
        time_convention_flip(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a time convention: exp(+jwt) (= exp(+iwt), engineering, the reference "
            "text) or exp(-iwt) (= exp(-jwt), physics, SCATMECH)"
        ) from None
    return text


def _add_file_and_model_options(parser, flip: str, wavelength: str) -> None:
    """The fit commands' file units and time convention, and the pBRDF's model options."""
    parser.add_argument(
        "--angle-unit", default="deg", choices=["deg", "rad"], help="unit of the angle columns"
    )
    parser.add_argument(
        "--wavelength-unit", default="um", choices=["um", "nm", "mm", "m"], help=wavelength
    )
    parser.add_argument(
        "--time-convention",
        default="exp(+jwt)",
        type=_time_convention,
        metavar="{exp(+jwt),exp(-iwt)}",
        help=f"the file's time convention ({flip}; also exp(-jwt), exp(+iwt), with spaces or omega)",
    )
    parser.add_argument(
        "--shadowing",
        default="torrance-sparrow",
        choices=["torrance-sparrow", "smith", "none"],  # scatterlab.pbrdf.shadowing.SHADOWING
        help="pBRDF shadowing",
    )
    parser.add_argument(
        "--diffuse",
        default="hyde",
        choices=["hyde", "reciprocal", "none"],
        help="pBRDF diffuse term",
    )


def _add_fit_mueller(sub):
    fm = sub.add_parser(
        "fit-mueller",
        help="fit n, kappa, sigma of the pBRDF to a measured Mueller BRDF table",
        description="Fit n, kappa and sigma of the pBRDF to all 16 elements of a Mueller BRDF "
        "table (long CSV, e.g. NIST SCATMECH's lambda,thetai,phii,thetar,phir,f_r11,"
        "f_r12/f_r11,...); writes figures, report.md and metrics.json.",
    )
    fm.add_argument("file", help="Mueller BRDF table (CSV), one row per geometry")
    fm.add_argument("--out", default="results/fit-mueller", help="output folder")
    fm.add_argument(
        "--wavelength-um",
        type=float,
        default=None,
        help="wavelength to fit when the file has several",
    )
    _add_file_and_model_options(
        fm, "exp(-iwt): NIST SCATMECH; flips the circular elements", "unit of the wavelength column"
    )
    fm.add_argument(
        "--posterior-steps", type=int, default=0, help="emcee steps per walker (0: no posterior)"
    )
    fm.add_argument("--seed", type=int, default=20101210, help="seed of the posterior sampler")
    fm.add_argument(
        "--sigma",
        type=float,
        default=None,
        help="known roughness (rms facet slope, 0.001-1.5), held fixed; default: fitted",
    )
    fm.add_argument(
        "--column",
        action="append",
        default=[],
        metavar="KEY=NAME",
        help="the file's column NAME holds quantity KEY (wavelength, theta_i, phi_i, theta_r, phi_r, phi, "
        "or an element: f_r12, m12, std_m12, m12/m11); repeatable",
    )
    fm.add_argument("--force", action="store_true", help="replace an existing report")


def _add_fit_ellipsometry(sub):
    fe = sub.add_parser(
        "fit-ellipsometry",
        help="fit n, kappa, sigma of the pBRDF to in-plane Mueller ellipsometry (CSV) and report",
        description="Fit n, kappa and sigma of the pBRDF to in-plane Mueller ellipsometry: one row "
        "per specular angle (theta_i = theta_r) with the normalised elements m12, m22, m33, m34 "
        "(1-based names; M01, M11, M22, M23 over M00) and optionally their std_ columns; angles in "
        "degrees. Writes elements_vs_angle.png, metrics.json and report.md.",
    )
    fe.add_argument("file", help="CSV table of normalised elements against the specular angle")
    fe.add_argument("--out", default="results/fit-ellipsometry", help="output folder")
    fe.add_argument("--force", action="store_true", help="replace an existing report")
    _add_file_and_model_options(
        fe, "exp(-iwt) flips the sign of m34", "unit of the wavelength column, if any"
    )
    fe.add_argument(
        "--sigma", type=float, default=None, help="known roughness (rms slope); default: fitted"
    )
    fe.add_argument(
        "--column",
        action="append",
        default=[],
        metavar="KEY=NAME",
        help="the file's column NAME holds quantity KEY (theta, wavelength, or an element: m12, "
        "std_m12); repeatable",
    )


def _fit_ellipsometry(args) -> int:
    import time

    from scatterlab.ellipsometry import fit_mueller_elements
    from scatterlab.ellipsometry.in_plane_report import write_in_plane_report
    from scatterlab.io import read_ellipsometry

    try:
        if args.sigma is not None and not 1e-3 <= args.sigma <= 1.5:
            raise ValueError(f"--sigma must be a known rms slope in [0.001, 1.5], got {args.sigma}")
        data = _read_noting(
            read_ellipsometry,
            args.file,
            _columns(args.column, ELLIPSOMETRY_COLUMNS, elements=True),
            angle_unit=args.angle_unit,
            wavelength_unit=args.wavelength_unit,
            time_convention=args.time_convention,
        )
        t0 = time.perf_counter()
        fit = fit_mueller_elements(
            data.theta,
            data.elements,
            std=data.std,
            sigma=args.sigma,
            fit_sigma=args.sigma is None,
            shadowing=args.shadowing,
            diffuse=args.diffuse,
        )
        report = write_in_plane_report(
            data,
            fit,
            args.out,
            source=args.file,
            convention=args.time_convention,
            seconds=time.perf_counter() - t0,
            shadowing=args.shadowing,
            diffuse=args.diffuse,
            overwrite=args.force,
        )
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        print(
            f"scatterlab: {_message(exc)}{_other_command(exc, args.file, 'fit-ellipsometry')}",
            file=sys.stderr,
        )
        return 2
    e = fit.errors
    sigma = f"{fit.sigma:.4g} +- {e[2]:.2g}" if args.sigma is None else f"{fit.sigma:.4g} (known)"
    print(f"n = {fit.n:.5g} +- {e[0]:.2g}, kappa = {fit.kappa:.5g} +- {e[1]:.2g}, sigma = {sigma}")
    for line in _ellipsometry_warnings(data, fit, args):
        print(f"scatterlab: warning: {line}", file=sys.stderr)
    print(f"report: {report}")
    return 0


def _ellipsometry_warnings(data, fit, args) -> list:
    """What a user must know about an in-plane fit before using its numbers (bounds, misfit, convention)."""
    import numpy as np

    from scatterlab.ellipsometry import fit_mueller_elements
    from scatterlab.ellipsometry.fit import FIT_BOUNDS
    from scatterlab.ellipsometry.in_plane_report import goodness

    out = []
    if not fit.success:
        out.append(
            "the fit did not converge: these numbers are not an estimate (check the angle unit, "
            "--angle-unit, and the time convention)"
        )
    # kappa = 0 (a dielectric) is a physical value, not flagged
    (n_lo, n_hi), (_, k_hi), _ = FIT_BOUNDS
    for name, v, bounds in (("n", fit.n, (n_lo, n_hi)), ("kappa", fit.kappa, (k_hi,))):
        if any(np.isclose(v, b, rtol=1e-6, atol=0) for b in bounds):
            out.append(f"{name} = {v:.4g} is a bound of the fit, not an estimate")
    stat, _, _ = goodness(data, fit)
    if data.std is not None and stat > 4:
        out.append(
            f"the model does not fit within the stated errors (reduced chi^2 {stat:.3g}): the "
            "errors are too small to trust (report.md says why)"
        )
    flipped = fit_mueller_elements(
        data.theta,
        data.elements * np.array([1, 1, 1, -1]),
        std=data.std,
        sigma=args.sigma,
        fit_sigma=args.sigma is None,
        shadowing=args.shadowing,
        diffuse=args.diffuse,
    )
    if flipped.cost < 0.25 * fit.cost:
        out.append(
            f"the data fit {fit.cost / max(flipped.cost, 1e-300):.3g} times better with m34's sign "
            "flipped: the file is probably in the other time convention (--time-convention)"
        )
    return out


def main(argv=None) -> int:
    """Entry point of the ``scatterlab`` command; returns the exit status.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status (0 on success).
    """
    parser = argparse.ArgumentParser(
        prog="scatterlab",
        description=DESCRIPTION,
        usage="scatterlab [-h] COMMAND ...",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(
        dest="command",
        required=True,
        metavar="COMMAND",
        help=argparse.SUPPRESS,
        prog="scatterlab",  # subcommand usage reads "scatterlab study ...", not the top usage line
    )
    st = sub.add_parser(
        "study", help="list or run the studies that reproduce the reference figures"
    )
    st.add_argument("action", choices=["list", "run"])
    st.add_argument("id", nargs="?", help="study id, or 'all'")
    st.add_argument("--quick", action="store_true", help="small sizes (under a minute per study)")
    st.add_argument("--out", default=None, help="output folder (default results/[quick/]ID)")
    st.add_argument(
        "--seed", type=int, default=20101210, help="random seed recorded in metrics.json"
    )
    st.add_argument("--force", action="store_true", help="replace an existing report")
    st.add_argument("--workers", type=int, default=None, help="local worker processes for sweeps")
    st.add_argument("--scheduler", default=None, help="Dask scheduler address for sweeps")
    ch = sub.add_parser(
        "characterize", help="simulate, deconvolve, classify and characterize a scene (main job)"
    )
    ch.add_argument(
        "scene", nargs="?", help="scene description (TOML); default: the bundled painted plates"
    )
    ch.add_argument(
        "--out", default="results/characterize", help="output folder (default results/characterize)"
    )
    ch.add_argument("--force", action="store_true", help="replace an existing report")
    ch.add_argument(
        "--quick",
        action="store_true",
        help="a smoke test: at most 64 px, 3 geometries spread over the scene's range, the first D/r0, "
        "15 EM iterations, 400 posterior steps",
    )
    ch.add_argument("--workers", type=int, default=None, help="local worker processes")
    ch.add_argument("--scheduler", default=None, help="Dask scheduler address")
    _add_fit_mueller(sub)
    _add_fit_dolp(sub)
    _add_fit_ellipsometry(sub)
    an = sub.add_parser(
        "analyze", help="restore, classify and invert measured channel images (no simulation)"
    )
    an.add_argument(
        "dataset", help="polarimetric dataset: .h5, .npz, or a TIFF stack with its sidecar .toml"
    )
    an.add_argument("--out", default="results/analyze", help="output folder")
    an.add_argument("--force", action="store_true", help="replace an existing report")
    an.add_argument(
        "--psf",
        choices=["blind", "diffraction"],
        default="blind",
        help="blind deconvolution (through turbulence) or the optics' known diffraction PSF",
    )
    an.add_argument("--iterations", type=int, default=150, help="EM iterations (default 150)")
    an.add_argument(
        "--priors",
        choices=["ch5", "ch6", "ch7"],
        default="ch7",
        help="DOLP prior set; with the default adaptive classes it only seeds their re-centring, so it "
        "changes little: give --classes priors to classify with the set as published (ch6's three "
        "classes are then reported as paint and metal; its EM continuation is slower)",
    )
    an.add_argument(
        "--classes",
        choices=["adaptive", "priors"],
        default="adaptive",
        help="regions from priors re-centred on the data's DOLP histogram (default) or the fixed priors",
    )
    an.add_argument(
        "--bias-samples",
        type=int,
        default=3,
        help="blind re-simulations averaged by the self-calibration (default 3, >= 1)",
    )
    an.add_argument(
        "--model-error",
        action="store_true",
        help="add the pBRDF's MoM-measured DOLP model error to the region errors (real data)",
    )
    an.add_argument(
        "--frames",
        type=int,
        default=1,
        help="exposures per geometry: the channels are F consecutive groups, each through its own "
        "turbulence (default 1)",
    )
    an.add_argument(
        "--psf-refine",
        choices=["none", "layout"],
        default="none",
        help="refine each blind PSF with a few-material object (with --frames F > 1: one layout "
        "shared by the frames, whole-field PSFs; tens of times the restoration's cost)",
    )
    an.add_argument(
        "--blind-starts",
        type=int,
        default=3,
        help="random start PSFs per blind restoration, aligned and averaged: the ghosts of a wrong "
        "PSF estimate average down (default 3; 1 is the text's single start)",
    )
    an.add_argument(
        "--bad-pixels",
        default=None,
        metavar="MASK",
        help="TIFF or .npy mask, non-zero at dead, hot or defective pixels (H x W, or one page per "
        "geometry): left out of the restoration's likelihood and unclassified; added to the "
        "dataset's own bad_pixels",
    )
    an.add_argument(
        "--full-well",
        type=float,
        default=None,
        metavar="E",
        help="dark-subtracted count [e-] at which a pixel saturates: values at or above it are "
        "censored ('at least this many') and their pixels left unclassified (replaces the "
        "dataset's full_well_e)",
    )
    an.add_argument(
        "--sigma",
        type=float,
        default=None,
        help="known roughness (rms facet slope); without it 0.3 is assumed, and the report says so",
    )
    an.add_argument(
        "--posterior-steps", type=int, default=1500, help="MCMC chain length (default 1500)"
    )
    an.add_argument("--seed", type=int, default=20101210, help="random seed (default 20101210)")
    an.add_argument("--workers", type=int, default=None, help="local worker processes")
    an.add_argument("--scheduler", default=None, help="Dask scheduler address")
    args = parser.parse_args(argv)
    commands = {
        "analyze": _analyze,
        "study": _study,
        "characterize": _characterize,
        "fit-mueller": _fit_mueller,
        "fit-dolp": _fit_dolp,
        "fit-ellipsometry": _fit_ellipsometry,
    }
    problem = _integer_option_error(args)
    if problem is not None:
        print(f"scatterlab: {problem}", file=sys.stderr)
        return 2
    with warnings.catch_warnings():  # a warning is a line for the user, not a source listing
        warnings.showwarning = _show_warning
        return commands[args.command](args)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"scatterlab: warning: {message}", file=sys.stderr if file is None else file)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
