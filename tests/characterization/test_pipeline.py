"""The characterization pipeline runs end to end on a tiny scene, writes atomic HDF5 results and a report,
computes only what the scene asks for, and rejects bad scene files with clear messages."""

import json

import numpy as np
import pytest

from scatterlab.characterization import SceneConfig, characterize, load_scene
from scatterlab.characterization.scene_config import Plate


def tiny(**kw):
    cfg = SceneConfig(image_size=32, geometry_deg=[35, 55], d_over_r0=[7.9], iterations=5, posterior_steps=300,
                      plates=[Plate()], **kw)
    return cfg.validate()


def test_pipeline_writes_results_and_report(tmp_path):
    import h5py

    report = characterize(tiny(), tmp_path)
    text = report.read_text()
    assert "aluminium plate" in text and "DOLP RMSE" in text
    with h5py.File(tmp_path / "results.h5") as f:
        g = f["aluminium/D_r0_7.9/theta_35"]
        assert g["dolp_corrected"].shape == (32, 32) and "classes" in g
        assert f["aluminium/no_turbulence/n_corrected"].shape == (32, 32)
        assert f["aluminium/no_turbulence/posterior_paint/chain"].shape[-1] == 3
        assert np.all(np.diff(g["loglik"][()]) >= -1e-9 * np.abs(g["loglik"][1:]))
    s = json.loads((tmp_path / "summary.json").read_text())
    assert set(s["plates"]["aluminium"]) == {"no_turbulence", "D_r0_7.9"}
    assert not (tmp_path / "results.h5.part").exists()
    with pytest.raises(FileExistsError):
        characterize(tiny(), tmp_path)


def test_only_requested_estimates_are_computed(tmp_path):
    import h5py

    characterize(tiny(estimate=["classes"]), tmp_path)
    with h5py.File(tmp_path / "results.h5") as f:
        assert "n_corrected" not in f["aluminium/no_turbulence"]
        assert "posterior_paint" not in f["aluminium/no_turbulence"]


def test_scene_files_are_validated(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text('image_size = 32\ngeometry_deg = [40, 50]\n[[plates]]\nmetal = "steel"\nmetal_n = 3.6\n')
    cfg = load_scene(p)
    assert cfg.plates[0].metal == "steel" and cfg.image_size == 32
    p.write_text("image_sise = 32\n")
    with pytest.raises(ValueError, match="image_sise"):
        load_scene(p)
    p.write_text("geometry_deg = [95]\n")
    with pytest.raises(ValueError, match="geometry_deg"):
        load_scene(p)
    p.write_text('priors = "ch9"\n')
    with pytest.raises(ValueError, match="priors"):
        load_scene(p)
