import os

import pytest

from scatterlab import runtime


def square(x):
    return x * x


def fail_on_three(x):
    if x == 3:
        raise ValueError("three")
    return x


@pytest.mark.parametrize("kind", ["serial", "processes"])
def test_executor_returns_in_order_and_propagates(kind):
    with runtime.get_executor(kind, workers=2) as ex:
        assert ex.map(square, range(20)) == [i * i for i in range(20)]
        with pytest.raises(runtime.TaskError, match="task 3 failed: ValueError: three") as info:
            ex.map(fail_on_three, range(6))
        assert info.value.index == 3


@pytest.mark.slow
def test_dask_local_cluster_executor():
    pytest.importorskip("dask.distributed")
    with runtime.get_executor("dask", workers=2) as ex:
        assert ex.map(square, range(10)) == [i * i for i in range(10)]
        with pytest.raises(runtime.TaskError) as info:
            ex.map(fail_on_three, range(6))
        assert info.value.index == 3


def test_executor_bad_kind():
    with pytest.raises(ValueError, match="kind"):
        runtime.get_executor("threads")


def test_chunks():
    assert [list(c) for c in runtime.chunks(list(range(7)), 3)] == [[0, 1, 2], [3, 4], [5, 6]]


def test_atomic_write_refuses_overwrite_and_leaves_no_temp(tmp_path):
    p = tmp_path / "a" / "x.json"
    runtime.write_json(p, {"a": 1.5, "z": 1 - 2j})
    assert runtime.read_json(p) == {"a": 1.5, "z": {"re": 1.0, "im": -2.0}}
    with pytest.raises(FileExistsError):
        runtime.write_json(p, {"a": 2})
    runtime.write_json(p, {"a": 2}, overwrite=True)
    assert runtime.read_json(p) == {"a": 2}
    assert os.listdir(p.parent) == ["x.json"]


def test_failed_write_keeps_old_file(tmp_path, monkeypatch):
    p = tmp_path / "r.txt"
    runtime.write_text(p, "old")

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError):
        runtime.write_text(p, "new", overwrite=True)
    monkeypatch.undo()
    assert p.read_text() == "old"
    assert os.listdir(tmp_path) == ["r.txt"]


def test_progress_is_silent_when_disabled(monkeypatch, capsys):
    monkeypatch.setenv("SCATTERLAB_PROGRESS", "0")
    assert list(runtime.progress(range(3), desc="x")) == [0, 1, 2]
    assert capsys.readouterr().err == ""


def test_stopwatch_and_best_time():
    sw = runtime.Stopwatch()
    with sw("a"):
        sum(range(1000))
    assert sw.times["a"] > 0
    assert runtime.best_time(lambda: sum(range(100)), repeat=2) > 0


def test_deprecated_runner_alias_is_lazy():
    # importing runtime and the deprecated alias scatterlab.runtime.studies loads no upper layer:
    # the study runner moved to scatterlab.study_runner
    import subprocess
    import sys

    code = (
        "import sys, scatterlab; before = set(sys.modules); "
        "import scatterlab.runtime, scatterlab.runtime.studies; "
        "print(sorted(m for m in set(sys.modules) - before if m.startswith('scatterlab')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "['scatterlab.runtime.studies']"
