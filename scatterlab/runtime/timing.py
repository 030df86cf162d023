"""Wall-time measurement helpers for studies and benchmarks (never used in test assertions)."""

from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import contextmanager

__all__ = ["Stopwatch", "best_time", "throughput"]


class Stopwatch:
    """Accumulates named wall-time intervals: ``with sw("fill"): ...``; ``sw.times`` [s]."""

    def __init__(self):
        self.times: dict[str, float] = {}

    @contextmanager
    def __call__(self, name: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.times[name] = self.times.get(name, 0.0) + time.perf_counter() - t0


def best_time(
    fn: Callable[[], object], *, repeat: int = 5, number: int = 1, budget: float = 10.0
) -> float:
    """Best-of-``repeat`` wall time [s] of ``number`` calls of ``fn``, divided by ``number``.

    Stops early once ``budget`` seconds have been spent (at least one repeat runs).

    Parameters
    ----------
    fn : callable
        The work, called without arguments.
    repeat : int
        Number of timed repeats (at most).
    number : int
        Calls per repeat.
    budget : float
        Time budget [s].

    Returns
    -------
    float
        Best time per call [s].
    """
    if repeat < 1 or number < 1:
        raise ValueError("repeat and number must be >= 1")
    best = float("inf")
    spent = 0.0
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        dt = time.perf_counter() - t0
        best = min(best, dt / number)
        spent += dt
        if spent > budget:
            break
    return best


def throughput(fn: Callable[[], object], n_evaluations: int, **kw) -> float:
    """Evaluations per second of ``fn`` that performs ``n_evaluations`` evaluations per call.

    Parameters
    ----------
    fn : callable
        The work, called without arguments.
    n_evaluations : int
        Evaluations one call performs.
    **kw
        Passed to :func:`best_time`.

    Returns
    -------
    float
        Evaluations per second [1/s].
    """
    return n_evaluations / best_time(fn, **kw)
