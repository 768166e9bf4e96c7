"""Rolling resistance, spin friction, air and rest on the command line and as sweep keys (scene
version 4): the flags override the scene, bad values are refused in one line naming the key,
and a scene that dissipates runs each point through ``Simulation`` (not the 2011 batch loop)."""

import dataclasses

import numpy as np
import pytest

import rollball.simulation
from rollball import Scene
from rollball.cli import main
from rollball.examples import EXAMPLES_DIR
from rollball.sweeps import Grid, parse_vary
from rollball.sweeps.batch import changes_mode
from rollball.sweeps.grid import value_of, with_values

HILLS = str(EXAMPLES_DIR / "hills.json")


@pytest.fixture
def ran(monkeypatch):
    """The scene ``rollball simulate`` ran (the run itself is not made)."""
    scenes = []

    def simulate(scene, **options):
        scenes.append(scene)
        raise ValueError("not run")

    monkeypatch.setattr(rollball.simulation, "simulate", simulate)
    return scenes


def test_the_flags_override_the_scene(ran, capsys):
    main(["simulate", HILLS, "--rolling-resistance", "0.02", "--spin-friction", "0.01", "--air-density", "1.2",
          "--drag-coefficient", "0.47", "--no-stop-at-rest"])
    (scene,) = ran
    assert (scene.contact.rolling_resistance, scene.contact.spin_friction) == (0.02, 0.01)
    assert (scene.air.density, scene.air.drag_coefficient, scene.stop_at_rest) == (1.2, 0.47, False)
    assert scene.dissipates


def test_without_the_flags_the_scene_is_the_files(ran, capsys):
    main(["simulate", HILLS])
    assert ran == [Scene.load(HILLS)]


@pytest.mark.parametrize("args, words", [
    (["--rolling-resistance", "-0.1"], "--rolling-resistance: contact.rolling_resistance: must not be negative"),
    (["--spin-friction", "nan"], "--spin-friction: contact.spin_friction: must be a finite number"),
    (["--rolling-resistance", "1e999"], "contact.rolling_resistance: must be a finite number"),
    (["--spin-friction", "much"], "contact.spin_friction: must be a number, not text"),
    (["--air-density", "1.2"], "--air-density: air.drag_coefficient: must be given with air.density"),
    (["--drag-coefficient", "0.47"], "--drag-coefficient: air.density: must be given with air.drag_coefficient"),
    (["--air-density", "1.2", "--drag-coefficient", "x"], "air.drag_coefficient: must be a number, not text"),
    (["--air-density", "1e300", "--drag-coefficient", "1e300"], "air.density: the drag factor ½ ρ C_d π r² overflows"),
])
def test_bad_values_are_refused_in_one_line_naming_the_key(args, words, ran, capsys):
    assert main(["simulate", HILLS, *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and not ran


def test_stop_at_rest_both_ways_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["simulate", HILLS, "--stop-at-rest", "--no-stop-at-rest"])
    assert e.value.code == 2 and "not allowed with" in capsys.readouterr().err


def test_the_sweep_keys_are_known_and_listed_in_the_help(capsys):
    for key in ("contact.rolling_resistance", "contact.spin_friction", "air.density", "air.drag_coefficient",
                "stop_at_rest"):
        assert parse_vary(f"{key}=0:1:2")[0] == key
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    for key in ("contact.rolling_resistance,", "contact.spin_friction,", "air.density,", "air.drag_coefficient,",
                "stop_at_rest"):
        assert key in help_text


def test_stop_at_rest_sweeps_as_0_and_1():
    scene = Scene.load(HILLS)
    assert Grid.of({"stop_at_rest": [True, False]}).axes[0].tolist() == [1.0, 0.0]
    assert with_values(scene, ["stop_at_rest"], [0.0]).stop_at_rest is False
    assert with_values(scene, ["stop_at_rest"], [1.0]).stop_at_rest is True
    assert value_of(scene, "stop_at_rest") == 1.0
    with pytest.raises(ValueError, match="stop_at_rest: the values must be 0 .false. or 1 .true."):
        Grid.of({"stop_at_rest": [0.0, 0.5]})
    with pytest.raises(ValueError, match="stop_at_rest: the values must be 0"):
        Grid.of(dict([parse_vary("stop_at_rest=0:2:3")]))
    with pytest.raises(ValueError, match="not true/false"):
        Grid.of({"contact.rolling_resistance": [True]})


def test_a_density_without_a_coefficient_is_a_refused_row_naming_the_key(tmp_path, capsys):
    assert main(["sweep", HILLS, "--vary", "air.density=0:1.2:2", "--vary", "duration=0.01:0.01:1",
                 "--workers", "1", "--out", str(tmp_path)]) == 0
    rows = (tmp_path / "sweep.csv").read_text().splitlines()
    assert rows[1].split(",")[2] == "ok"
    assert ",invalid," in rows[2] and "air.drag_coefficient: must be given with air.density" in rows[2]


def test_a_scene_that_dissipates_runs_through_the_simulation():
    glued = Scene.load(HILLS)   # version 2: the 2011 model, the batch loop's
    assert not changes_mode(glued)
    assert changes_mode(dataclasses.replace(glued, contact=dataclasses.replace(glued.contact,
                                                                               rolling_resistance=0.01)))
    assert changes_mode(glued, ("air.density", "air.drag_coefficient"))
    assert changes_mode(glued, ("contact.spin_friction",))
    assert not changes_mode(glued, ("start.x", "stop_at_rest"))


def test_stop_at_rest_is_not_fitted():
    from rollball.fitting import FitError, fit
    from rollball.track import Track

    track = Track(t=np.array([0.0, 0.1]), positions=np.zeros((2, 2)), axes=("x", "y"))
    with pytest.raises(FitError, match="cannot fit stop_at_rest: it is true or false"):
        fit(Scene.load(HILLS), track, ["stop_at_rest"])


def test_a_drag_that_overflows_is_a_refused_row_naming_the_key():
    from rollball import sweep

    scene = Scene.load(HILLS)
    table = sweep(dataclasses.replace(scene, duration=0.01), {"air.density": [1.2, 1e300],
                                                             "air.drag_coefficient": [1e300]}, workers=1)
    assert table["status"][0] != "invalid" and table["status"][1] == "invalid"   # (the first runs: k ≈ 2e298 kg/m)
    assert "air.density: the drag factor ½ ρ C_d π r² overflows" in table.messages[1]
