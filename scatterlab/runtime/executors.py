"""One executor interface for embarrassingly parallel sweeps.

``get_executor(kind)`` returns an object with ``map(fn, tasks, desc=None)``
that returns the results **in task order** and re-raises the first exception a
task raised (with the task index in the message). Kinds:

* ``"serial"`` (default): a plain loop in this process;
* ``"processes"``: a local :class:`concurrent.futures.ProcessPoolExecutor`;
* ``"dask"``: a Dask distributed client, connected to ``scheduler`` (an address
  such as ``tcp://host:8786``) or, without one, to a local cluster started for
  the purpose.

``fn`` and the tasks must be picklable for the parallel kinds (module-level
functions, plain data). Every map shows a progress bar when output is a terminal.
"""

from __future__ import annotations

import concurrent.futures as cf
import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from scatterlab.runtime.progress import progress

__all__ = [
    "Executor",
    "SerialExecutor",
    "ProcessExecutor",
    "DaskExecutor",
    "get_executor",
    "TaskError",
]


class TaskError(RuntimeError):
    """A task of a sweep failed; ``index`` is its position in the task list."""

    def __init__(self, index: int, exc: BaseException):
        super().__init__(f"task {index} failed: {type(exc).__name__}: {exc}")
        self.index = index


class Executor:
    """Base class: ``map(fn, tasks) -> list`` in task order."""

    kind = "base"

    def map(self, fn: Callable[[Any], Any], tasks: Iterable[Any], desc: str | None = None) -> list:
        raise NotImplementedError

    def close(self) -> None:
        """Release workers (no-op for serial)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class SerialExecutor(Executor):
    """Run tasks one after another in this process."""

    kind = "serial"

    def map(self, fn, tasks, desc=None):
        tasks = list(tasks)
        out = []
        for i, t in enumerate(progress(tasks, desc=desc, total=len(tasks))):
            try:
                out.append(fn(t))
            except Exception as exc:  # propagate with the task index
                raise TaskError(i, exc) from exc
        return out


def _single_blas_thread() -> None:
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)


class ProcessExecutor(Executor):
    """A local process pool with ``workers`` processes (default: CPU count)."""

    kind = "processes"

    def __init__(self, workers: int | None = None):
        if workers is not None and workers < 1:
            raise ValueError("workers must be >= 1")
        self.workers = workers or os.cpu_count() or 1
        # one BLAS/OpenMP thread per worker: workers x BLAS threads oversubscribe the cores (measured 14x
        # slower for the small linear algebra of an MCMC KDE move, 2 workers on 2 cores)
        self._pool = cf.ProcessPoolExecutor(
            max_workers=self.workers, initializer=_single_blas_thread
        )

    def map(self, fn, tasks, desc=None):
        tasks = list(tasks)
        futures = {self._pool.submit(fn, t): i for i, t in enumerate(tasks)}

        def cancel():
            for f in futures:
                f.cancel()

        return _gather(
            cf.as_completed(futures),
            futures.__getitem__,
            lambda f: f.exception(),
            cancel,
            len(tasks),
            desc,
        )

    def close(self):
        self._pool.shutdown(wait=True, cancel_futures=True)


def _gather(completed, index_of, error_of, cancel, n: int, desc):
    """Results of futures in task order, as they complete, with a progress bar; the first failure
    cancels the rest and is raised as :class:`TaskError` naming its task."""
    out: list = [None] * n
    bar = progress(None, desc=desc, total=n)
    try:
        for fut in completed:
            i, exc = index_of(fut), error_of(fut)
            if exc is not None:
                cancel()
                raise TaskError(i, exc) from exc
            out[i] = fut.result()
            bar.update(1)
    finally:
        bar.close()
    return out


class DaskExecutor(Executor):
    """A Dask distributed client (``pip install scatterlab[dask]``)."""

    kind = "dask"

    def __init__(self, scheduler: str | None = None, workers: int | None = None):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError as exc:  # pragma: no cover - depends on the extra
            raise ImportError("the dask executor needs `pip install scatterlab[dask]`") from exc
        self._cluster = None
        if scheduler:
            self.client = Client(scheduler)
        else:
            self._cluster = LocalCluster(
                n_workers=workers or os.cpu_count() or 1,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
            )
            self.client = Client(self._cluster)

    def map(self, fn, tasks, desc=None):
        from dask.distributed import as_completed

        tasks = list(tasks)
        futures = self.client.map(fn, tasks, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}

        def error(fut):
            return fut.exception() if fut.status == "error" else None

        return _gather(
            as_completed(futures),
            lambda f: index[f.key],
            error,
            lambda: self.client.cancel(futures),
            len(tasks),
            desc,
        )

    def close(self):
        self.client.close()
        if self._cluster is not None:
            self._cluster.close()


def get_executor(
    kind: str = "serial", *, workers: int | None = None, scheduler: str | None = None
) -> Executor:
    """Executor of the given kind: ``"serial"``, ``"processes"`` or ``"dask"``.

    A ``scheduler`` address implies ``"dask"``.

    Parameters
    ----------
    kind : {"serial", "processes", "dask"}
        The executor.
    workers : int, optional
        Worker processes (default: the machine's cores).
    scheduler : str, optional
        Address of a running dask scheduler.

    Returns
    -------
    Executor
        An object with ``map(fn, tasks, desc=...)`` returning the results in task order.
    """
    if scheduler:
        kind = "dask"
    if kind == "serial":
        return SerialExecutor()
    if kind == "processes":
        return ProcessExecutor(workers)
    if kind == "dask":
        return DaskExecutor(scheduler, workers)
    raise ValueError(f"kind must be 'serial', 'processes' or 'dask', got {kind!r}")


def chunks(seq: Sequence, n: int) -> list[Sequence]:
    """Split ``seq`` into ``n`` nearly equal consecutive chunks (for batching small tasks).

    Parameters
    ----------
    seq : sequence
        The items.
    n : int
        Number of chunks (>= 1).

    Returns
    -------
    list of sequence
        ``min(n, len(seq))`` consecutive slices of ``seq``, sizes differing by at most one.
    """
    if n < 1:
        raise ValueError("n must be >= 1")
    k, r = divmod(len(seq), n)
    out, start = [], 0
    for i in range(n):
        stop = start + k + (i < r)
        if stop > start:
            out.append(seq[start:stop])
        start = stop
    return out
