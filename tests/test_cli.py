from scatterlab.cli import main


def test_study_list(capsys):
    assert main(["study", "list"]) == 0
    out = capsys.readouterr().out
    assert "fig4" in out and "brewster" in out


def test_study_run_and_force(tmp_path, capsys):
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "report.md").exists() and (tmp_path / "fig4.pdf").exists()
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["study", "run", "fig4", "--quick", "--out", str(tmp_path), "--force"]) == 0


def test_study_run_all_writes_index(tmp_path, monkeypatch):
    # every study already runs in tests/test_studies.py: here a folder holding one study is enough
    import shutil

    from scatterlab.study_runner import studies_dir

    folder = tmp_path / "studies"
    folder.mkdir()
    shutil.copy(studies_dir() / "fig4_fresnel_reflectances.py", folder)
    monkeypatch.setenv("SCATTERLAB_STUDIES", str(folder))
    assert main(["study", "run", "all", "--quick", "--out", str(tmp_path / "out")]) == 0
    tmp_path = tmp_path / "out"
    index = (tmp_path / "index.md").read_text()
    assert "fig4" in index and "| ok |" in index


def test_unknown_study_exit_code(capsys):
    assert main(["study", "run", "nope", "--quick"]) == 2
