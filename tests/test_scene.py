"""Scene files: round trips, defaults, and refusals that name their key."""

import json
import os

import pytest

from rollball.examples import EXAMPLES_DIR, example_scenes
from rollball.scene import Ball, Scene, SceneError

MINIMAL = {"format": "rollball-scene", "version": 1, "landscape": "x*y"}


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


def _bad(**changes):
    data = json.loads(json.dumps(MINIMAL))
    for dotted, value in changes.items():
        keys = dotted.split("__")
        target = data
        for key in keys[:-1]:
            target = target.setdefault(key, {})
        if value is KeyError:
            del target[keys[-1]]
        else:
            target[keys[-1]] = value
    return data


@pytest.mark.parametrize("data, key", [
    (_bad(format="something-else"), "format"),
    (_bad(format=KeyError), "format"),
    (_bad(version=KeyError), "version"),
    (_bad(version=2), "version"),
    (_bad(version=0), "version"),
    (_bad(version=1.0), "version"),
    (_bad(version=True), "version"),
    (_bad(landscape=KeyError), "landscape"),
    (_bad(landscape="z + 1"), "landscape"),
    (_bad(landscape=5), "landscape"),
    (_bad(colour="red"), "colour"),
    (_bad(ball__colour="red"), "ball.colour"),
    (_bad(ball__radius=-0.1), "ball.radius"),
    (_bad(ball__radius=0), "ball.radius"),
    (_bad(ball__radius="0.1"), "ball.radius"),
    (_bad(ball__radius=True), "ball.radius"),
    (_bad(ball__radius=None), "ball.radius"),
    (_bad(ball__mass=0), "ball.mass"),
    (_bad(ball=[0.1, 1.0]), "ball"),
    (_bad(gravity=-9.81), "gravity"),
    (_bad(integrator__dt=0), "integrator.dt"),
    (_bad(integrator__method="rk45"), "integrator.method"),
    (_bad(integrator__munthe_kaas=1), "integrator.munthe_kaas"),
    (_bad(duration=-1), "duration"),
    (_bad(view__min=3.0), "view.min"),
    (_bad(view__step=0), "view.step"),
    (_bad(start__x=10**400), "start.x"),
    (_bad(description=["a"]), "description"),
    ([MINIMAL], "scene"),
])
def test_refusal_names_the_key(data, key):
    with pytest.raises(SceneError) as info:
        Scene.from_dict(data)
    assert str(info.value).startswith(f"{key}:"), str(info.value)


@pytest.mark.parametrize("text, key", [
    ('{"format": "rollball-scene", "version": 1, "landscape": "x", "gravity": NaN}', "scene"),
    ('{"format": "rollball-scene", "version": 1, "landscape": "x", "gravity": Infinity}', "scene"),
    ('{"format": "rollball-scene", "version": 1, "landscape": "x", "gravity": 1e999}', "gravity"),
    ('{"format": "rollball-scene", "version": 1, "landscape": "x", "landscape": "y"}', "landscape"),
    ('{"format": "rollball-scene", "version": 1, "landscape": "x"', "scene"),
    ("", "scene"),
    ("[]", "scene"),
    ("null", "scene"),
    ("[" * 100000, "scene"),
])
def test_refused_text(text, key):
    with pytest.raises(SceneError) as info:
        Scene.loads(text)
    assert str(info.value).startswith(f"{key}:"), str(info.value)


def test_refused_files(tmp_path):
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe")
    with pytest.raises(SceneError, match="UTF-8"):
        Scene.load(binary)
    huge = tmp_path / "huge.json"
    huge.write_bytes(b" " * (2 << 20))
    with pytest.raises(SceneError, match="larger"):
        Scene.load(huge)


def test_constructed_scenes_are_validated_too():
    with pytest.raises(SceneError, match="^ball.radius:"):
        Scene(landscape="x", ball=Ball(radius=-1.0))
    with pytest.raises(SceneError, match="^landscape:"):
        Scene(landscape="import os")


def test_save_is_atomic_and_keeps_the_old_file_on_failure(tmp_path, monkeypatch):
    path = tmp_path / "scene.json"
    Scene.from_dict(MINIMAL).save(path)
    before = path.read_bytes()

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError):
        Scene(landscape="x + y").save(path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["scene.json"]  # no temporary left behind


def test_save_into_a_missing_folder_fails_cleanly(tmp_path):
    with pytest.raises(OSError):
        Scene.from_dict(MINIMAL).save(tmp_path / "missing" / "scene.json")
