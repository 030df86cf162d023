"""Prior ranges of a plate's region posteriors in a scene file ([[plates]] keys ``*_prior``)."""

import pytest

from scatterlab.characterization import load_scene
from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

PLATE = """
[[plates]]
metal = "copper"
metal_n = 0.61
metal_kappa = 10.4
paint_n = 1.45
paint_kappa = 0.3
"""


def _load(tmp_path, extra):
    p = tmp_path / "scene.toml"
    p.write_text(PLATE + extra)
    return load_scene(p)


def test_prior_ranges_are_read_and_default_to_the_inversions(tmp_path):
    plate = _load(tmp_path, "paint_n_prior = [1.3, 1.8]\nmetal_kappa_prior = [4, 17]\n").plates[0]
    assert plate.prior_bounds("paint") == {"n": (1.3, 1.8), "kappa": DEFAULT_BOUNDS["kappa"]}
    assert plate.prior_bounds("metal") == {"n": DEFAULT_BOUNDS["n"], "kappa": (4.0, 17.0)}
    assert _load(tmp_path, "").plates[0].prior_bounds("metal") == {
        "n": DEFAULT_BOUNDS["n"],
        "kappa": DEFAULT_BOUNDS["kappa"],
    }


@pytest.mark.parametrize(
    "line, match",
    [
        ("paint_n_prior = [1.8, 1.3]", "paint_n_prior must be \\[low, high\\]"),
        ("paint_n_prior = [1.3]", "paint_n_prior must be \\[low, high\\]"),
        ("paint_n_prior = [-1.0, 2.0]", "paint_n_prior must be \\[low, high\\]"),
        ("metal_kappa_prior = ['a', 2.0]", "metal_kappa_prior must be a list"),
        ("metal_kappa_prior = 3.0", "metal_kappa_prior must be a list"),
        ("paint_kappa_prior = [0.5, 0.9]", "excludes the plate's paint_kappa = 0.3"),
        ("paint_n_priors = [1.3, 1.8]", "unknown key"),
    ],
)
def test_bad_prior_ranges_are_refused_by_name(tmp_path, line, match):
    with pytest.raises(ValueError, match=match):
        _load(tmp_path, line + "\n")


def test_a_region_other_than_metal_or_paint_is_refused(tmp_path):
    with pytest.raises(ValueError, match="region must be 'metal' or 'paint'"):
        _load(tmp_path, "").plates[0].prior_bounds("steel")
