"""Every Python snippet of the README runs as pasted, in order, in a fresh namespace each (issue: a README a
user can trust)."""

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_snippet_runs(i, monkeypatch, tmp_path):
    # paths in the snippets are relative to the repository; what they write goes to results/, here in a
    # temporary folder beside a link to the repository's data/
    (tmp_path / "data").symlink_to(README.parent / "data")
    monkeypatch.chdir(tmp_path)
    exec(compile(BLOCKS[i], f"README.md[python block {i}]", "exec"), {})


def test_readme_links_stay_inside_the_repository():
    text = README.read_text()
    assert "../shared" not in text
    for target in re.findall(r"\]\(([^)#]+)", text):
        assert not target.startswith(("http:", "https:", "/")), target
        assert (README.parent / target).exists(), target
