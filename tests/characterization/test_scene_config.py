"""Scene files: a value of the wrong type or range is a ValueError naming the key (never a TypeError or a
numpy warning), and ``estimate = []`` is a restoration-only scene."""

import warnings

import pytest

from scatterlab.characterization import SceneConfig, load_scene
from scatterlab.characterization.scene_config import Plate


@pytest.fixture(autouse=True)
def _warnings_are_errors():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


@pytest.mark.parametrize(
    "text, message",
    [
        # TypeError: unhashable type (the duplicate-name check ran before the plates' own checks)
        ('[[plates]]\nmetal = ["a"]\n', r"plates\[0\]\.metal must be a string"),
        ("[[plates]]\nmetal = {a = 1}\n", r"plates\[0\]\.metal must be a string"),
        (
            '[[plates]]\nmetal = "a"\nmetal_n = 2.0\nmetal_kappa = 3.0\n[[plates]]\nmetal = ["b"]\n',
            r"plates\[1\]\.metal must be",
        ),
        ('[[plates]]\nmetal_n = "1.5"\n', r"plates\[0\]\.metal_n must be a number"),
        # a RuntimeWarning from numpy.mod before the finiteness check
        ("polarizer_deg = [0, 45, 90, inf]\n", r"polarizer_deg entries must be finite"),
        ("polarizer_deg = [0, 45, 90, nan]\n", r"polarizer_deg entries must be finite"),
        # accepted: 1e300 deg is no polarizer angle
        ("polarizer_deg = [0, 45, 90, 1e300]\n", r"polarizer_deg .* \[-360, 360\] deg"),
        ("polarizer_deg = [0, 45, 90, 361]\n", r"polarizer_deg .* \[-360, 360\] deg"),
        ("polarizer_deg = [0, 45, 45]\n", "polarizer_deg needs at least three distinct"),
    ],
)
def test_scene_values_of_the_wrong_type_or_range_name_the_key(tmp_path, text, message):
    p = tmp_path / "scene.toml"
    p.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_scene(p)


def test_plate_validate_names_a_key_of_the_wrong_type():
    with pytest.raises(ValueError, match=r"plates\.metal_n must be a number, got '1.5'"):
        Plate(metal_n="1.5").validate()
    with pytest.raises(ValueError, match=r"plates\[2\]\.paint_roughness must be a number"):
        Plate(paint_roughness=None).validate("plates[2]")
    with pytest.raises(ValueError, match=r"plates\[0\]\.metal must be a string"):
        SceneConfig(plates=[Plate(metal=["a"])]).validate()


def test_valid_polarizer_angles_and_a_restoration_only_scene_are_accepted(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text("polarizer_deg = [-360, -45, 0, 60, 120, 360]\nestimate = []\n")
    cfg = load_scene(p)
    assert cfg.polarizer_deg[0] == -360 and cfg.estimate == []
