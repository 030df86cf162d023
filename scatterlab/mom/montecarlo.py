"""Incoherent averaging of rough-surface scattering over partitions of one long surface or over realizations.

The reference (Sec. 4.3) divides a 15,000-wavelength surface into 100 partitions and adds the scattered
powers incoherently. :func:`incoherent_scattering` does that: for each partition, one matrix fill and one LU
factorisation serve every incidence angle (multiple right-hand sides, Thorsos tapered waves centred on the
partition); the scattering coefficients are averaged and their standard error per angle reported. The
coherent part :math:`|\\langle F\\rangle|^2` (phases referred to each taper's centre) is separated from the
incoherent one. Partitions run through an executor of :mod:`scatterlab.runtime`; with ``checkpoint`` the
finished partitions are saved atomically (npz) with the inputs they were computed from (angles, wavelength,
taper, partition size, polarization, eta, method, and a SHA-256 digest of each partition's profile), and a
rerun resumes after the last one saved -- or refuses with a ValueError when any of these differ.
Both polarizations and real materials go through :func:`~scatterlab.mom.solve` (``polarization``, ``eta``).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scatterlab._checks import as_count, as_finite, as_index, as_positive
from scatterlab.mom.formulations import (
    _EDGE_FIELD_WARN,
    TruncationWarning,
    _check_choices,
    edge_field_ratio,
    solve,
    truncation_message,
)
from scatterlab.mom.incidence import TaperedWave
from scatterlab.runtime.results import write_npz

__all__ = ["incoherent_scattering", "IncoherentResult", "partition_task", "surface_digest"]

_ENERGY_NODES = np.polynomial.legendre.leggauss(1024)


@dataclass
class IncoherentResult:
    """Averages over partitions: theta_i (I,), theta_s (S,) [rad]; arrays (I, S) [1/rad].

    ``energy`` (P, I) is each partition's reflected power (the coefficient integrated over theta_s);
    ``transmitted`` (P, I) the power into a lossless lower medium (NaN where undefined: PEC, absorbing or
    impedance-condition surfaces); ``per_partition`` (P, I, S) [1/rad] each partition's coefficient,
    for resampling estimates (jackknife, bootstrap) of statistics other than the mean.
    """

    theta_i: np.ndarray
    theta_s: np.ndarray
    mean: np.ndarray
    stderr: np.ndarray
    coherent: np.ndarray
    incoherent: np.ndarray
    energy: np.ndarray  # (P, I): integral of each partition's coefficient over theta_s
    partitions: int
    seconds_fill: float
    seconds_solve: float
    transmitted: np.ndarray | None = None
    polarization: str = "s"
    eta: complex | None = None
    per_partition: np.ndarray | None = None


def partition_task(task):
    """Solve one partition for all incidences.

    Parameters
    ----------
    task : tuple
        ``(x, y, wavelength, theta_i, g, theta_s, solver, polarization, eta, method)``, as in
        :func:`incoherent_scattering`, with ``x, y`` (n,) one partition [m].

    Returns
    -------
    coefficient : ndarray, shape (I, S)
        Scattering coefficient [1/rad].
    far_field : ndarray, shape (S, I), complex
        Far-field amplitudes.
    energy : ndarray, shape (I,)
        Reflected power (coefficient integrated over the scattering angle).
    fill_seconds, solve_seconds : float
        Matrix fill and solve times [s].
    transmitted : ndarray, shape (I,)
        Transmitted power (NaN where undefined).
    edge_field : ndarray, shape (I,)
        :func:`~scatterlab.mom.formulations.edge_field_ratio` in p (NaN in s): the solve's
        :class:`~scatterlab.mom.TruncationWarning` is not raised here but summarised once over the
        partitions by :func:`incoherent_scattering`.
    """
    import warnings

    x, y, wavelength, theta_i, g, theta_s, solver, polarization, eta, method = task
    k = 2 * np.pi / wavelength
    x0 = 0.5 * (x[0] + x[-1])
    incs = [TaperedWave(t, g, x0=x0) for t in theta_i]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TruncationWarning)
        sol = solve(
            x, y, wavelength, incs, solver=solver, polarization=polarization, eta=eta, method=method
        )
    edge = np.full(len(incs), np.nan)
    if polarization == "p":
        edge = edge_field_ratio(sol.contour, k, incs, sol.surface_field.reshape(x.size, -1))
    F = sol.far_field(theta_s)  # (S, I)
    P = np.array([inc.incident_power(k) for inc in incs])
    coef = (np.abs(F) ** 2 / (8 * np.pi * k * P)).T
    # energy: Gauss-Legendre over (-90, 90) deg, 1024 nodes (the lobes are smooth on this scale)
    xg, wg = _ENERGY_NODES
    Fq = sol.far_field(xg * np.pi / 2)
    energy = np.sum(wg[:, None] * np.abs(Fq) ** 2, 0) * (np.pi / 2) / (8 * np.pi * k * P)
    trans = np.full(len(incs), np.nan)
    if eta is not None and method == "exact" and np.imag(eta) == 0:
        trans = np.sum(wg[:, None] * sol.transmission_coefficient(xg * np.pi / 2), 0) * (np.pi / 2)
    return coef, F, energy, sol.timings["fill"], sol.timings["solve"], trans, edge


def surface_digest(x, y) -> str:
    """SHA-256 of a profile's float64 bytes (identifies a partition in a checkpoint).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Profile points [m].

    Returns
    -------
    str
        Hexadecimal SHA-256 digest.
    """
    h = hashlib.sha256(np.ascontiguousarray(x, float).tobytes())
    h.update(np.ascontiguousarray(y, float).tobytes())
    return h.hexdigest()


def _settings(wavelength, theta_i, theta_s, g, n, polarization, eta, method):
    """The inputs every partition shares, as arrays for the checkpoint (compared on resume)."""
    return {
        "wavelength": np.array(float(wavelength)),
        "theta_i": theta_i,
        "theta_s": theta_s,
        "g": np.array(float(g)),
        "points_per_partition": np.array(n),
        "polarization": np.array(polarization),
        "eta": np.array(complex(np.nan) if eta is None else complex(eta)),
        "method": np.array(method),
    }


def _load_checkpoint(path, settings, digests):
    """Finished partitions of a checkpoint, after checking they come from the same inputs."""
    z = np.load(path)
    if "digest" not in z.files:
        raise ValueError(
            f"checkpoint {path} carries no digest of its inputs (written by an older version): "
            "delete it or pass another checkpoint path"
        )
    for key, value in settings.items():
        old = z[key]
        same = old.shape == value.shape and (
            np.array_equal(old, value, equal_nan=True)
            if old.dtype.kind in "fc"
            else np.array_equal(old, value)
        )
        if not same:
            raise ValueError(
                f"checkpoint {path} was written for another {key} ({old!r}, now {value!r}): delete it "
                "or pass another checkpoint path"
            )
    done = {}
    for p in range(int(z["count"])):
        if p >= len(digests) or str(z["digest"][p]) != digests[p]:
            raise ValueError(
                f"checkpoint {path}: partition {p} was computed on another surface (its digest "
                "differs): delete the checkpoint or pass another path"
            )
        trans = z["transmitted"][p]
        # checkpoints written before the edge field was kept have none: NaN, no warning
        edge = z["edge"][p] if "edge" in z.files else np.full(trans.shape, np.nan)
        done[p] = (
            z["coef"][p],
            z["F"][p],
            z["energy"][p],
            float(z["fill"][p]),
            float(z["solve"][p]),
            trans,
            edge,
        )
    return done


def _check_angles(theta_i, theta_s):
    theta_i = np.atleast_1d(np.asarray(theta_i, float))
    theta_s = np.atleast_1d(np.asarray(theta_s, float))
    if theta_i.size == 0:
        raise ValueError(
            "theta_i must hold at least one incidence angle in (-pi/2, pi/2) rad, got an empty list"
        )
    if not np.all(np.isfinite(theta_i)) or np.any(np.abs(theta_i) >= np.pi / 2):
        raise ValueError("theta_i must be finite incidence angles in (-pi/2, pi/2) rad")
    if not np.all(np.isfinite(theta_s)) or np.any(np.abs(theta_s) > np.pi / 2):
        raise ValueError("theta_s must be finite scattering angles in [-pi/2, pi/2] rad")
    return theta_i, theta_s


def _check_profile(x, y, partitions):
    """``(x, y, partitions, points per partition)`` validated: 1-D finite profiles of equal length
    with increasing x, and a whole number of partitions of at least 16 points each."""
    x = as_finite(x, "x")
    y = as_finite(y, "y")
    if x.ndim != 1 or y.ndim != 1 or x.shape != y.shape:
        raise ValueError(
            f"x and y must be 1-D profiles of equal length, got shapes {x.shape} and {y.shape}"
        )
    if np.any(np.diff(x) <= 0):
        raise ValueError("x must increase (a height function y(x) of an open profile)")
    partitions = as_count(partitions, "partitions", 1)
    if x.size // partitions < 16:
        raise ValueError(
            f"partitions must leave at least 16 points per partition: at most {x.size // 16} for "
            f"{x.size} points, got {partitions}"
        )
    return x, y, partitions, x.size // partitions


def _check_partitions(tasks, polarization, method):
    """The checks each partition's solve makes that raise (sampling in each medium, taper width and
    position), made here on every partition before any is dispatched; their warnings are left to
    the solves."""
    import warnings

    from scatterlab.mom.efie import check_incidences, check_sampling, contour
    from scatterlab.mom.formulations import _check_media
    from scatterlab.mom.kernels import arclength_contour

    for x, y, wavelength, theta_i, g, _, _, _, eta, _ in tasks:
        k = 2 * np.pi / wavelength
        length = (x[-1] - x[0]) * x.size / (x.size - 1)
        # before the taper's own checks, which overflow for g ~ 1e300; with their rounding tolerance (a
        # taper of exactly a quarter of the partition, as perf_mom uses, passes)
        if length < 4 * g * (1 - 1e-9):
            raise ValueError(
                f"g (taper width) = {g:.4g} m is too wide for partitions of length {length:.4g} m: "
                f"need g <= length / 4 = {length / 4:.4g} m (fewer partitions or a narrower taper)"
            )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the partition's solve warns
            if eta is None and polarization == "s":
                c = contour(x, y)
                check_sampling(c, wavelength, 5.0)
            else:
                c = arclength_contour(contour(x, y))
                _check_media(c, wavelength, eta, method, 5.0)
        x0 = 0.5 * (x[0] + x[-1])
        check_incidences([TaperedWave(t, g, x0=x0) for t in theta_i], c, k)


def incoherent_scattering(
    x,
    y,
    wavelength,
    theta_i,
    theta_s,
    *,
    partitions: int,
    g=None,
    solver: str = "lu",
    executor=None,
    checkpoint=None,
    polarization: str = "s",
    eta=None,
    method: str = "exact",
) -> IncoherentResult:
    """Average the scattering coefficient over ``partitions`` equal pieces of the profile (x, y).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        One long surface [m] (e.g. from :func:`~scatterlab.mom.rough_surface`).
    wavelength : float
        Wavelength [m].
    theta_i : array_like, shape (I,)
        Incidence angles in (-pi/2, pi/2) [rad], at least one, all solved with one factorisation
        per partition.
    theta_s : array_like, shape (S,)
        Scattering angles in [-pi/2, pi/2] from the vertical [rad], specular at theta_i.
    partitions : int
        The profile is cut into this many pieces of ``N // partitions`` points (an integer >= 1
        leaving at least 16 points per partition).
    g : float, optional
        Taper width [m], finite and > 0; default a quarter of a partition.
    solver : {"lu", "fb", "fast"}
        Direct LU, forward-backward iteration, or ``"fast"`` (s-pol perfect conductor only), as
        :func:`~scatterlab.mom.solve`.
    executor : Executor, optional
        A :mod:`scatterlab.runtime` executor (default serial).
    checkpoint : str or os.PathLike, optional
        npz of finished partitions; an existing file is resumed. It records the shared inputs
        (wavelength, angles, taper, partition size, polarization, eta, method) and a SHA-256 digest
        of each partition's profile; any mismatch raises ValueError instead of reusing old results.
    polarization, eta, method
        As :func:`~scatterlab.mom.solve` ("s"/"p"; ``eta=None`` is a perfect conductor).

    Returns
    -------
    IncoherentResult
        Angles and the partition averages, arrays (I, S) [1/rad].

    Raises
    ------
    ValueError
        Before any partition is solved: ``x``, ``y`` not finite 1-D profiles of equal length with
        increasing x; ``partitions`` not an integer >= 1 leaving 16 points per partition; a
        wavelength, taper width ``g`` or ``eta`` out of range; angles outside their ranges; an
        unknown polarization, method or solver. Partitions' own checks (sampling, taper) raise
        from the first one solved.
    """
    from scatterlab.runtime import get_executor

    # everything a partition's solve would refuse is checked here, before any work is dispatched
    x, y, partitions, n = _check_profile(x, y, partitions)
    wavelength = float(as_positive(wavelength, "wavelength"))
    theta_i, theta_s = _check_angles(theta_i, theta_s)
    if solver not in ("lu", "fb", "fast"):
        raise ValueError(f"solver must be 'lu', 'fb' or 'fast', got {solver!r}")
    _check_choices(polarization, method, solver, eta)
    eta = None if eta is None else complex(as_index(eta, "eta"))
    dx = x[1] - x[0]
    g = n * dx / 4 if g is None else float(as_positive(g, "g (taper width)"))
    tasks = [
        (
            x[p * n : (p + 1) * n],
            y[p * n : (p + 1) * n],
            wavelength,
            theta_i,
            g,
            theta_s,
            solver,
            polarization,
            eta,
            method,
        )
        for p in range(partitions)
    ]
    digests = [surface_digest(t[0], t[1]) for t in tasks]
    settings = _settings(wavelength, theta_i, theta_s, g, n, polarization, eta, method)
    ckpt = Path(checkpoint) if checkpoint is not None else None
    done = _load_checkpoint(ckpt, settings, digests) if ckpt is not None and ckpt.exists() else {}
    _check_partitions(tasks, polarization, method)  # after a checkpoint's mismatch, before work
    ex = executor if executor is not None else get_executor("serial")
    todo = [p for p in range(partitions) if p not in done]
    # in chunks, so a checkpoint is written every few partitions
    chunk = max(1, 2 * getattr(ex, "workers", 1)) if ckpt is not None else len(todo) or 1
    for start in range(0, len(todo), chunk):
        ids = todo[start : start + chunk]
        for p, r in zip(
            ids, ex.map(partition_task, [tasks[p] for p in ids], desc="MoM partitions")
        ):
            done[p] = r
        if ckpt is not None:
            _save_checkpoint(ckpt, done, digests, settings)
    _warn_truncation(np.stack([done[p][6] for p in range(partitions)]), theta_i)
    return _average(done, partitions, theta_i, theta_s, wavelength, g, polarization, eta)


def _warn_truncation(edge, theta_i):
    """One TruncationWarning for all partitions (P, I) whose edge-field ratio exceeds the threshold."""
    import warnings

    over = edge > _EDGE_FIELD_WARN
    if not over.any():
        return
    p, i = np.unravel_index(np.nanargmax(np.where(over, edge, -np.inf)), edge.shape)
    where = f"in {int(over.any(1).sum())} of {edge.shape[0]} partitions (largest shown)"
    warnings.warn(
        truncation_message(edge[p, i], np.degrees(theta_i[i]), where),
        TruncationWarning,
        stacklevel=3,
    )


def _save_checkpoint(ckpt, done, digests, settings):
    count = 0
    while count in done:
        count += 1
    keys = range(count)
    write_npz(
        ckpt,
        overwrite=True,
        count=np.array(count),
        digest=np.array(digests[:count]),
        coef=np.stack([done[p][0] for p in keys]),
        F=np.stack([done[p][1] for p in keys]),
        energy=np.stack([done[p][2] for p in keys]),
        fill=np.array([done[p][3] for p in keys]),
        solve=np.array([done[p][4] for p in keys]),
        transmitted=np.stack([done[p][5] for p in keys]),
        edge=np.stack([done[p][6] for p in keys]),
        **settings,
    )


def _average(done, partitions, theta_i, theta_s, wavelength, g, polarization, eta):
    coef = np.stack([done[p][0] for p in range(partitions)])  # (P, I, S)
    F = np.stack([done[p][1] for p in range(partitions)])  # (P, S, I)
    k = 2 * np.pi / wavelength
    P_inc = np.array([TaperedWave(t, g).incident_power(k) for t in theta_i])
    coherent = (np.abs(F.mean(0)) ** 2 / (8 * np.pi * k * P_inc)).T
    mean = coef.mean(0)
    stderr = (
        coef.std(0, ddof=1) / np.sqrt(partitions) if partitions > 1 else np.full(mean.shape, np.nan)
    )
    return IncoherentResult(
        theta_i=theta_i,
        theta_s=theta_s,
        mean=mean,
        stderr=stderr,
        coherent=coherent,
        incoherent=mean - coherent,
        energy=np.stack([done[p][2] for p in range(partitions)]),
        partitions=partitions,
        seconds_fill=float(sum(done[p][3] for p in range(partitions))),
        seconds_solve=float(sum(done[p][4] for p in range(partitions))),
        transmitted=np.stack([done[p][5] for p in range(partitions)]),
        polarization=polarization,
        eta=eta,
        per_partition=coef,
    )
