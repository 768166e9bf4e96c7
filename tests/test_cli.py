"""The command line: summaries, CSV output and exit codes, never a traceback."""

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rollball import read_csv
from rollball.cli import main
from rollball.examples import EXAMPLES_DIR, example_scenes
from rollball.text import shown

HILLS = str(EXAMPLES_DIR / "hills.json")


def test_simulate_prints_a_summary_and_writes_csv(tmp_path, capsys):
    out = tmp_path / "hills.csv"
    assert main(["simulate", HILLS, "--t-end", "1", "--every", "10", "--csv", str(out)]) == 0
    line = capsys.readouterr().out.strip()
    assert "\n" not in line
    assert "1000 steps" in line and "status ok" in line and "energy drift" in line and "no lift-off" in line
    data = read_csv(out)
    assert data.shape == (101, 23) and data[-1, 0] == 1.0


def test_options_override_the_scene(tmp_path, capsys):
    out = tmp_path / "o.csv"
    assert main(["simulate", HILLS, "--method", "lawson5", "--classic", "--dt", "0.01", "--t-end", "0.5",
                 "--csv", str(out)]) == 0
    assert "50 steps" in capsys.readouterr().out
    assert "lawson5, classic" in out.read_text()


def test_the_summary_warns_about_accuracy_as_the_app_does(capsys):
    assert main(["simulate", HILLS, "--method", "euler", "--classic", "--dt", "0.01", "--t-end", "3"]) == 0
    line = capsys.readouterr().out.strip()
    assert "\n" not in line
    assert "WARNING: energy changed by" in line and "WARNING: ‖RᵀR − I‖ = " in line
    assert "R is no longer a rotation" in line


def test_liftoff_is_a_warning_not_a_failure(capsys):
    assert main(["simulate", str(EXAMPLES_DIR / "liftoff.json")]) == 0
    assert "lift-off at t = " in capsys.readouterr().out


def test_stopped_by_the_physics_exits_1_and_still_writes(tmp_path, capsys):
    out = tmp_path / "big.csv"
    assert main(["simulate", str(EXAMPLES_DIR / "too_big.json"), "--csv", str(out)]) == 1
    assert "does_not_fit" in capsys.readouterr().out
    assert len(read_csv(out)) > 10


@pytest.mark.parametrize("args", [
    ["simulate", "missing.json"],
    ["simulate", HILLS, "--dt", "-1"],
    ["simulate", HILLS, "--dt", "nan"],
    ["simulate", HILLS, "--method", "rk45"],
    ["simulate", HILLS, "--every", "0"],
    ["simulate", HILLS, "--classic", "--munthe-kaas"],
    ["simulate", HILLS, "--dt", "1e-9"],
    ["simulate", HILLS, "--t-end", "0.1", "--csv", "/nonexistent-folder/x.csv"],
    ["frobnicate"],
    [],
])
def test_bad_input_exits_2_with_one_line(args, capsys):
    with pytest.raises(SystemExit) as info:
        sys.exit(main(args))
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    if args:
        assert err and "Traceback" not in err


def test_bad_scene_file_names_the_key(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "rollball-scene", "version": 1, "landscape": "x",
                               "ball": {"radius": -1}}))
    assert main(["simulate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "ball.radius" in err and len(err.strip().splitlines()) == 1


def test_examples_lists_descriptions(capsys):
    assert main(["examples"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^hills +Sine-cosine hills", out, re.MULTILINE) and len(out.splitlines()) >= 8
    for path, scene in example_scenes():   # each example's description as its scene has it
        assert re.search(rf"^{path.stem} +{re.escape(shown(scene.description))}$", out, re.MULTILINE)


def test_an_example_runs_by_name_from_any_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "hills", "--t-end", "0.1"]) == 0
    assert capsys.readouterr().out.startswith("hills: 100 steps")
    assert main(["simulate", "hillz"]) == 2
    err = capsys.readouterr().err
    assert "no such scene file or example" in err and "hills" in err and len(err.strip().splitlines()) == 1


def test_installed_entry_point_runs(tmp_path):
    entry_point = str(Path(sys.executable).parent / "rollball")
    result = subprocess.run([entry_point, "simulate", HILLS, "--t-end", "0.2"], capture_output=True,
                            text=True, timeout=120, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "200 steps" in result.stdout
    result = subprocess.run([sys.executable, "-m", "rollball", "--help"], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 0 and "simulate" in result.stdout and "examples" in result.stdout


def test_adaptive_from_the_command_line(tmp_path, capsys):
    out = tmp_path / "a.csv"
    assert main(["simulate", HILLS, "--method", "dopri5", "--rtol", "1e-8", "--atol", "1e-11",
                 "--t-end", "1", "--record-dt", "0.25", "--csv", str(out)]) == 0
    summary = capsys.readouterr().out
    assert "status ok" in summary and " rejected, " in summary and " evaluations)" in summary
    assert np.array_equal(read_csv(out)[:, 0], [0, 0.25, 0.5, 0.75, 1.0])
    assert "dopri5, Munthe-Kaas, rtol 1e-08" in out.read_text()
    assert main(["simulate", HILLS, "--method", "adaptive", "--t-end", "0.1"]) == 0  # the old name
    with pytest.raises(SystemExit) as stop:
        main(["simulate", HILLS, "--method", "rk45"])
    assert stop.value.code == 2 and "valid methods: euler, rk4" in capsys.readouterr().err
    assert main(["simulate", HILLS, "--method", "dopri5", "--classic"]) == 2
    assert "Munthe-Kaas" in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:
        main(["simulate", HILLS, "--rtol", "0"])
    assert stop.value.code == 2


def test_simulate_prints_the_transitions(capsys):
    assert main(["simulate", "ridge_jump", "--t-end", "1.3"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert "first lift-off at t = 0.6738" in out[0] and "J dissipated" in out[0] and "WARNING" not in out[0]
    assert out[1].startswith("  lift-off at t = 0.6738") and out[2].startswith("  landing at t = 1.2116")
    assert "along the normal" in out[2] and "J lost" in out[2]
