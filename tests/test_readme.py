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


def test_readme_blind_deconvolution_snippet_classifies_as_it_says():
    # the snippet claims 0.94 of the pixels classified right (paint 0 / metal 1 against the plate's labels);
    # a demonstration that classified everything as metal passed the run-only test above
    (block,) = [b for b in BLOCKS if "(res.classes == plate.labels).mean()" in b]
    ns = {}
    exec(compile(block, "README.md[blind deconvolution]", "exec"), ns)
    right = (ns["res"].classes == ns["plate"].labels).mean()
    assert right == pytest.approx(0.94, abs=0.01)
    for k in (0, 1):  # each material, not only the majority one
        assert (ns["res"].classes[ns["plate"].labels == k] == k).mean() > 0.9
