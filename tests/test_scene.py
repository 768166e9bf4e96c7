"""Scene files: round trips, defaults, and refusals that name their key."""

import json

import pytest

from rollball.examples import EXAMPLES_DIR, example_scenes
from rollball.scene import VERSION, Ball, Scene, SceneError

MINIMAL = {"format": "rollball-scene", "version": 2, "landscape": "x*y"}


def test_design_example_is_the_default():
    scene = Scene.from_dict(MINIMAL)
    assert scene.gravity == 9.81 and scene.ball.radius == 0.1 and scene.ball.mass == 1.0
    assert (scene.start.x, scene.start.y) == (0.3, -0.2)
    assert scene.integrator.method == "rk4" and scene.integrator.munthe_kaas is True
    assert scene.integrator.dt == 0.001 and scene.duration == 10.0
    assert (scene.view.min, scene.view.max, scene.view.step) == (-3.0, 3.0, 0.1)


def test_round_trip(tmp_path):
    scene = Scene.load(EXAMPLES_DIR / "bump.json")
    path = tmp_path / "copy.json"
    scene.save(path)
    assert Scene.load(path) == scene
    assert json.loads(path.read_text(encoding="utf-8"))["format"] == "rollball-scene"


def test_integers_are_numbers():
    scene = Scene.from_dict({**MINIMAL, "ball": {"radius": 1, "mass": 2}, "duration": 3})
    assert scene.ball.radius == 1.0 and isinstance(scene.ball.radius, float)


def test_numpy_numbers_are_numbers():
    import numpy as np

    scene = Scene(landscape="x", ball=Ball(np.float64(0.25), np.int64(2)))
    assert (scene.ball.radius, scene.ball.mass) == (0.25, 2.0)
    assert type(scene.ball.radius) is float and type(scene.ball.mass) is float
    with pytest.raises(SceneError, match="^ball.radius: must be a number"):
        Scene(landscape="x", ball=Ball(np.bool_(True)))


def test_every_example_loads_and_has_a_description():
    examples = example_scenes()
    names = {path.stem for path, _ in examples}
    assert {"hills", "bowl", "incline", "saddle", "bump", "liftoff", "valley", "too_big"} <= names
    for path, scene in examples:
        assert scene.description, path


# Refused scene texts and files, with the keys named, are the corpus in tests/hostile_corpus.py.


def test_constructed_scenes_are_validated_too():
    with pytest.raises(SceneError, match="^ball.radius:"):
        Scene(landscape="x", ball=Ball(radius=-1.0))
    with pytest.raises(SceneError, match="^landscape:"):
        Scene(landscape="import os")


def test_version_1_files_are_migrated_and_saved_as_the_newest_version(tmp_path):
    old = {"format": "rollball-scene", "version": 1, "landscape": "x*y",
           "integrator": {"method": "adaptive", "munthe_kaas": True, "rtol": 1e-8}}
    scene = Scene.from_dict(old)
    assert scene.integrator.method == "dopri5" and scene.integrator.rtol == 1e-8
    assert Scene.from_dict({**old, "integrator": {"method": "lawson5"}}).integrator.method == "lawson5"
    path = tmp_path / "new.json"
    scene.save(path)
    saved = json.loads(path.read_text(encoding="utf-8"))
    assert saved["version"] == VERSION and saved["integrator"]["method"] == "dopri5" and "parameters" not in saved
    assert old["integrator"]["method"] == "adaptive"  # the migration does not change its input


def test_the_migration_steps_cover_every_version():
    from rollball.scene import MIGRATIONS, _v1_to_v2, _v2_to_v3, _v3_to_v4

    assert VERSION == 4 and MIGRATIONS == [_v1_to_v2, _v2_to_v3, _v3_to_v4]
    v3 = {"landscape": "x", "contact": {"friction": 0.1}}
    assert _v3_to_v4(v3) == v3
    for key, body in (("contact.rolling_resistance", {"contact": {"rolling_resistance": 0.1}}),
                      ("air", {"air": {"density": 1.2}}), ("stop_at_rest", {"stop_at_rest": False})):
        with pytest.raises(SceneError, match=f"^{key}: unknown key in a version-3 scene"):
            _v3_to_v4({"landscape": "x", **body})
    assert _v2_to_v3({"landscape": "x", "gravity": 1}) == {
        "landscape": "x", "gravity": 1, "contact": {"friction": None, "restitution": 0.0, "after_liftoff": "glued"}}
    assert _v1_to_v2({"landscape": "x"}) == {"landscape": "x"}
    assert _v1_to_v2({"integrator": "bad"}) == {"integrator": "bad"}  # refused later, by key


def test_a_newer_version_is_refused_in_words():
    with pytest.raises(SceneError, match="^version: 5 is newer than this RollBall understands"):
        Scene.from_dict({**MINIMAL, "version": 5})


def test_the_alias_is_read_in_version_2_too():
    scene = Scene.from_dict({**MINIMAL, "integrator": {"method": "adaptive"}})
    assert scene.integrator.method == "dopri5"
    with pytest.raises(SceneError, match="^integrator.munthe_kaas: dopri5 always uses Munthe-Kaas"):
        Scene.from_dict({**MINIMAL, "integrator": {"method": "dopri5", "munthe_kaas": False}})


def _scene_text(**body) -> str:
    return json.dumps({"format": "rollball-scene", "version": 3, "landscape": "0.1*x", **body})


@pytest.mark.parametrize("low, high", [(-1.7e308, 1.7e308), (-1e308, 1e308), (-1e308, 8e307)])
def test_a_parameter_range_whose_width_overflows_is_refused_in_one_line_naming_it(low, high):
    text = _scene_text(landscape="k*x", parameters={"k": {"value": 0.0, "min": low, "max": high}})
    with pytest.raises(SceneError) as refused:
        Scene.loads(text)
    assert refused.value.key == "parameters.k.max"
    assert "overflows" in str(refused.value) and "\n" not in str(refused.value)
    # the widest range that is not too wide is a scene's like any other
    scene = Scene.loads(_scene_text(landscape="k*x", parameters={"k": {"value": 0.0, "min": -8e307, "max": 8e307}}))
    assert scene.parameters[0].max == 8e307


@pytest.mark.parametrize("where, key", [
    ({"description": "a \ud800 b"}, "description"),
    ({"description": "\udfff"}, "description"),
    ({"landscape": "0.1*x + \udc00"}, "landscape"),
    ({"integrator": {"method": "rk4\ud800"}}, "integrator.method"),
    ({"contact": {"after_liftoff": "\ud83d"}}, "contact.after_liftoff"),
    ({"parameters": {"a\ud800": 1.0}}, "parameters.a\ud800"),
])
def test_a_lone_surrogate_in_any_text_is_refused_on_load_naming_the_key(where, key, tmp_path):
    # JSON may spell a lone surrogate ("\ud800"), which UTF-8 cannot hold: such a scene could
    # be loaded but not saved
    text = _scene_text(**where)
    assert "\\ud8" in text or "\\udc" in text or "\\udf" in text
    with pytest.raises(SceneError) as refused:
        Scene.loads(text)
    assert refused.value.key == key and "lone surrogate" in str(refused.value)
    assert "\n" not in str(refused.value) and str(refused.value).isprintable()
    path = tmp_path / "scene.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError):
        Scene.load(path)
    with pytest.raises(SceneError, match="description: holds a lone surrogate"):
        Scene(landscape="0.1*x", description="\ud800")
    # a pair of surrogates is one character, and a scene like any other
    scene = Scene.loads(_scene_text(description="ball \U0001f3b1"))
    assert "\\ud83c\\udfb1" in _scene_text(description="ball \U0001f3b1")
    assert scene.description == "ball \U0001f3b1"
    scene.save(path)
    assert Scene.load(path) == scene
