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
    ns = {}
    exec(compile(BLOCKS[i], f"README.md[python block {i}]", "exec"), ns)
    if "(res.classes == plate.labels).mean()" in BLOCKS[i]:
        # the blind-deconvolution snippet claims 0.94 of the pixels classified right (paint 0 / metal 1
        # against the plate's labels); a demonstration that called everything metal passed the run alone
        classes, labels = ns["res"].classes, ns["plate"].labels
        assert (classes == labels).mean() == pytest.approx(0.94, abs=0.01)
        for k in (0, 1):  # each material, not only the majority one
            assert (classes[labels == k] == k).mean() > 0.9


def test_readme_has_the_checked_blind_deconvolution_snippet():
    assert sum("(res.classes == plate.labels).mean()" in b for b in BLOCKS) == 1


def test_readme_links_stay_inside_the_repository():
    text = README.read_text()
    assert "../shared" not in text
    for target in re.findall(r"\]\(([^)#]+)", text):
        assert not target.startswith(("http:", "https:", "/")), target
        assert (README.parent / target).exists(), target
