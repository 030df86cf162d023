"""``characterize --quick`` reduces any valid scene to a valid smoke test, and the report's notes speak of
the scene that ran."""

from types import SimpleNamespace

import pytest

from scatterlab.characterization import SceneConfig, default_scene, load_scene
from scatterlab.characterization.report_text import _failure_notes, _header
from scatterlab.characterization.scene_config import quick_scene


def test_the_default_scene_quick_is_as_before():
    q = quick_scene(default_scene())
    assert (q.image_size, q.geometry_deg, q.d_over_r0) == (64, [30, 45, 60], [7.9])
    assert (q.iterations, q.posterior_steps) == (15, 400) and "quick" in q.title
    assert default_scene().image_size == 128  # the scene given is left alone


@pytest.mark.parametrize(
    "geometry, kept",
    [
        ([35, 50], [35, 50]),
        ([35, 50, 65], [35, 50, 65]),
        ([35, 45, 55, 65], [35, 55, 65]),
        ([35, 41, 47, 53, 59, 65], [35, 47, 65]),  # both ends kept
    ],
)
def test_short_geometry_sets_stay_valid_and_keep_their_range(geometry, kept):
    assert quick_scene(SceneConfig(geometry_deg=geometry).validate()).geometry_deg == kept


def test_small_images_are_not_enlarged_and_margins_and_diversity_follow():
    assert quick_scene(SceneConfig(image_size=32).validate()).image_size == 32
    q = quick_scene(SceneConfig(region_margin_px=12, phase_diversity_waves=[1.0, 2.0]).validate())
    assert q.region_margin_px == 6 and q.phase_diversity_waves == [1.0]


def test_a_non_table_plate_entry_is_refused_by_name(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text("plates = [1, 2]\n")
    with pytest.raises(ValueError, match=r"plates\[0\] must be a \[\[plates\]\] table"):
        load_scene(p)


def _results(metal):
    return [
        SimpleNamespace(
            plate=SimpleNamespace(metal=metal), metrics={"D_r0_10_corrected": {"psf_l1_error": 1.1}}
        )
    ]


def test_failure_notes_cite_default_scene_measurements_only_for_the_failure_they_explain():
    ideal = SimpleNamespace(psf=False)
    cls = (
        "copper, D/r0 = 10: corrected vs no-turbulence classification error <= 0.06",
        "0.08",
        False,
    )
    text = "\n".join(_failure_notes(_results("copper"), [cls], ideal))
    assert "Neither classifies" in text and "9.60 against 9.51" not in text
    eta = (
        "copper, D/r0 = 10: deconvolution does not worsen the copper's median |eta error|",
        "",
        False,
    )
    text = "\n".join(_failure_notes(_results("copper"), [eta], ideal))
    assert "9.60 against 9.51" in text and "Neither classifies" not in text


def test_the_header_promises_published_numbers_only_for_plates_that_have_them():
    ideal = SimpleNamespace(label=lambda: "none")
    cfg = SceneConfig(plates=[SimpleNamespace(metal="copper")], d_over_r0=[])
    text = "\n".join(_header(cfg, 1.0, ideal))
    assert "Tables 4 and 5" not in text and "no turbulent case" in text
    assert "Tables 4 and 5" in "\n".join(_header(default_scene(), 1.0, ideal))


def test_a_named_metal_without_its_index_is_flagged(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text('[[plates]]\nmetal = "copper"\nmetal_kappa = 9.0\n')
    with pytest.warns(
        UserWarning, match="names metal 'copper' but not metal_n: aluminium's metal_n = 1.44"
    ):
        load_scene(p)


def test_a_wavelength_in_nanometres_is_flagged(tmp_path):
    p = tmp_path / "scene.toml"
    p.write_text("wavelength_um = 50\n")  # far infrared, or 50 nm: allowed, and said
    with pytest.warns(UserWarning, match="nanometres given as micrometres"):
        load_scene(p)
    # outside the dataset reader's [0.01, 100] um: nanometres or metres in a micrometre key
    for value in ("1550", "1.55e-6", "0", "-1.55"):
        p.write_text(f"wavelength_um = {value}\n")
        with pytest.raises(ValueError, match=r"wavelength_um must be in \[0.01, 100\] um"):
            load_scene(p)
    p.write_text("wavelength_um = 1.55e-6\n")
    with pytest.raises(ValueError, match=r"got 1.55e-06 \(metres\? nanometres\?"):
        load_scene(p)
