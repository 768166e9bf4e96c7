"""Scene version 3's contact model and initial angular velocity: defaults, the migration of
version 2 to the 2011 behaviour, writing, and refusals that name their key."""

import json

import numpy as np
import pytest

from rollball.scene import VERSION, Contact, Scene, SceneError, Start

V3 = {"format": "rollball-scene", "version": 3, "landscape": "0.1*x*y"}
V2 = {**V3, "version": 2}


def test_version_3_defaults_to_flying_with_always_enough_friction():
    contact = Scene.from_dict(V3).contact
    assert contact == Contact(friction=None, restitution=0.0, after_liftoff="fly")
    assert Scene(landscape="x").contact == contact   # the same defaults in Python as in a file
    assert Scene.from_dict(V3).start.omega is None


def test_version_2_means_the_2011_ball():
    contact = Scene.from_dict(V2).contact
    assert (contact.friction, contact.restitution, contact.after_liftoff) == (None, 0.0, "glued")


@pytest.mark.parametrize("key, value", [("contact", {}), ("start", {"omega": [0, 0, 0]}), ("parameters", {"a": 1})])
def test_version_2_files_cannot_hold_version_3_keys(key, value):
    with pytest.raises(SceneError) as refusal:
        Scene.from_dict({**V2, key: value})
    assert refusal.value.key == (f"{key}.omega" if key == "start" else key)
    assert "came with version 3" in refusal.value.reason


def test_contact_and_omega_round_trip(tmp_path):
    scene = Scene.from_dict({**V3, "landscape": "0*x", "contact": {"friction": 0.25, "restitution": 0.5},
                             "start": {"x": 0, "y": 0, "vx": 1, "omega": [1, 2, 3]}})
    assert scene.contact == Contact(0.25, 0.5, "fly")
    assert scene.start.omega == (1.0, 2.0, 3.0) and all(type(w) is float for w in scene.start.omega)
    path = tmp_path / "s.json"
    scene.save(path)
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["contact"] == {"friction": 0.25, "restitution": 0.5, "after_liftoff": "fly",
                               "rolling_resistance": 0.0, "spin_friction": 0.0}
    assert data["start"]["omega"] == [1.0, 2.0, 3.0]
    assert Scene.load(path) == scene


def test_a_migrated_scene_is_written_as_glued_and_read_back_so(tmp_path):
    path = tmp_path / "s.json"
    Scene.from_dict(V2).save(path)
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["version"] == VERSION
    assert data["contact"]["after_liftoff"] == "glued" and data["contact"]["friction"] is None
    assert "omega" not in data["start"]   # a default left out
    assert Scene.load(path) == Scene.from_dict(V2)


REFUSED = [
    ({"contact": {"friction": True}}, "contact.friction", "must be a number"),
    ({"contact": {"friction": "0.2"}}, "contact.friction", "must be a number"),
    ({"contact": {"friction": -0.1}}, "contact.friction", "must not be negative"),
    ({"contact": {"friction": 1e999}}, "contact.friction", "finite"),
    ({"contact": {"restitution": None}}, "contact.restitution", "must be a number"),
    ({"contact": {"restitution": 1.5}}, "contact.restitution", "from 0 to 1"),
    ({"contact": {"restitution": -0.0001}}, "contact.restitution", "from 0 to 1"),
    ({"contact": {"restitution": False}}, "contact.restitution", "must be a number"),
    ({"contact": {"after_liftoff": "bounce"}}, "contact.after_liftoff", "'fly', 'glued'"),
    ({"contact": {"after_liftoff": None}}, "contact.after_liftoff", "must be text"),
    ({"contact": {"grip": 1}}, "contact.grip", "unknown key"),
    ({"contact": [0.2]}, "contact", "must be an object"),
    ({"start": {"omega": 3}}, "start.omega", "array of 3 numbers"),
    ({"start": {"omega": [1, 2]}}, "start.omega", "not of 2"),
    ({"start": {"omega": [0, True, 0]}}, "start.omega[1]", "must be a number"),
    ({"start": {"omega": [0, 0, 1e999]}}, "start.omega[2]", "finite"),
    ({"start": {"omega": [0, 0, 1e200]}}, "start.omega", "overflows"),
    ({"start": {"omega": [0, 0, 1], "spin": 2}}, "start.spin", "must be 0 when start.omega is given"),
]


@pytest.mark.parametrize("extra, key, fragment", REFUSED)
def test_refusals_name_the_key(extra, key, fragment):
    with pytest.raises(SceneError) as refusal:
        Scene.from_dict({**V3, **extra})
    assert refusal.value.key == key and fragment in refusal.value.reason


def test_a_start_omega_that_does_not_roll_needs_friction():
    # on the tilted plane z = 0.5 x the rolling omega is N x c' / r (+ spin N)
    start = {"x": 0.0, "y": 0.0, "vx": 1.0, "vy": 0.0}
    n = np.array([-0.5, 0.0, 1.0]) / np.sqrt(1.25)
    velocity = np.array([1.0, 0.0, 0.5])
    rolling = np.cross(n, velocity) / 0.1 + 3.0 * n
    scene = Scene.from_dict({**V3, "landscape": "0.5*x", "start": {**start, "omega": list(rolling)}})
    assert scene.start.omega == pytest.approx(tuple(rolling))
    skidding = {**V3, "landscape": "0.5*x", "start": {**start, "omega": [0.0, 0.0, 0.0]}}
    with pytest.raises(SceneError) as refusal:
        Scene.from_dict(skidding)
    assert refusal.value.key == "start.omega" and "does not roll" in refusal.value.reason
    assert "1.12 m/s" in refusal.value.reason   # |c'| = sqrt(1.25): the contact point's slip
    assert Scene.from_dict({**skidding, "contact": {"friction": 0.3}}).start.omega == (0.0, 0.0, 0.0)
    with pytest.raises(SceneError, match="^start.omega: the ball does not roll"):
        Scene(landscape="0.5*x", start=Start(0.0, 0.0, 1.0, 0.0, omega=(0.0, 0.0, 0.0)))


def test_a_rolling_start_omega_runs_as_the_start_velocity_and_spin_it_equals():
    from rollball import simulate

    landscape, start = "0.3*sin(x)*cos(y)", {"x": 0.4, "y": -0.3, "vx": 0.7, "vy": -0.2}
    plain = Scene.from_dict({**V3, "landscape": landscape, "start": {**start, "spin": 2.0}})
    d = np.array([0.3 * np.sin(0.4) * np.cos(-0.3), 0.3 * np.cos(0.4) * np.cos(-0.3),
                  -0.3 * np.sin(0.4) * np.sin(-0.3)])
    n = np.array([-d[1], -d[2], 1.0]) / np.sqrt(1 + d[1] ** 2 + d[2] ** 2)
    velocity = np.array([0.7, -0.2, d[1] * 0.7 - d[2] * 0.2])
    omega = np.cross(n, velocity) / 0.1 + 2.0 * n
    given = Scene.from_dict({**V3, "landscape": landscape, "start": {**start, "omega": list(omega)}})
    a, b = simulate(plain, t_end=0.2), simulate(given, t_end=0.2)
    assert np.allclose(a.omega[0], omega, rtol=0, atol=1e-13)
    assert np.abs(a.data - b.data).max() < 1e-12
