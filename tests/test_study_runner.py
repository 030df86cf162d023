"""The study runner's report: its key-number table says what it leaves to metrics.json."""

from scatterlab.study_runner import _markdown_table


def test_key_numbers_put_the_verdict_first_and_say_how_many_are_left_out():
    metrics = {f"m{i}": float(i) for i in range(50)}
    metrics["table"] = {"a": 1}
    metrics["verdict"] = "own study"
    metrics["headline"] = "error 0.03 | rms"
    table = _markdown_table(metrics, limit=40)
    lines = table.splitlines()
    assert lines[2] == "| verdict | own study |" and lines[3] == "| headline | error 0.03 / rms |"
    assert sum(line.startswith("| m") and line[3].isdigit() for line in lines) == 40
    assert "10 more numbers and 1 tables in `metrics.json`" in table
    short = _markdown_table({"a": 1.0, "b": 2})
    assert "metrics.json" not in short and short.count("\n| ") == 2
