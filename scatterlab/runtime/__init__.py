"""Runtime services: executors for sweeps, progress bars, atomic results I/O, timing.

The bottom layer: it imports nothing else from scatterlab. The study runner is
:mod:`scatterlab.study_runner`.
"""

from scatterlab.runtime.executors import (
    DaskExecutor,
    Executor,
    ProcessExecutor,
    SerialExecutor,
    TaskError,
    chunks,
    get_executor,
)
from scatterlab.runtime.progress import progress, progress_enabled
from scatterlab.runtime.results import (
    atomic_write_bytes,
    read_json,
    to_jsonable,
    write_json,
    write_npz,
    write_text,
)
from scatterlab.runtime.timing import Stopwatch, best_time, throughput

__all__ = [
    "Executor",
    "SerialExecutor",
    "ProcessExecutor",
    "DaskExecutor",
    "TaskError",
    "get_executor",
    "chunks",
    "progress",
    "progress_enabled",
    "atomic_write_bytes",
    "write_text",
    "write_json",
    "read_json",
    "write_npz",
    "to_jsonable",
    "Stopwatch",
    "best_time",
    "throughput",
]
