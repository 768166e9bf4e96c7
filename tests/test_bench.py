"""``rollball bench`` in miniature: the report's shape, sane errors, and the C yardstick."""

import json

import numpy as np
import pytest

from rollball import Scene, Simulation
from rollball.bench import Config, run, targets
from rollball.bench.cstep import CStep
from rollball.cli import main


def test_small_work_precision_report(tmp_path):
    text = run(tmp_path, Config(("bowl",), 0.5, 1, quick=True, targets=False), log=lambda _: None)
    assert (tmp_path / "bench.md").read_text() == text
    points = json.loads((tmp_path / "bench.json").read_text())["points"]
    labels = {p["label"] for p in points}
    assert labels == {"euler MK", "euler classic", "rk4 MK", "rk4 classic", "lawson5 MK",
                      "lawson5 classic", "adaptive (DP5(4) MK)", "scipy DOP853"}
    for label in ("rk4 MK", "adaptive (DP5(4) MK)", "scipy DOP853"):
        line = [p for p in points if p["label"] == label]
        errors = [p["error_alpha"] for p in line]
        assert errors[0] > errors[-1] and errors[0] < 1e-3, (label, errors)
        assert all(p["seconds"] > 0 and p["steps"] > 0 for p in line)
    # classic and Munthe-Kaas share the motion, and differ in R
    mk, classic = ([p for p in points if p["label"] == f"rk4 {k}"] for k in ("MK", "classic"))
    assert [p["error_alpha"] for p in mk] == [p["error_alpha"] for p in classic]
    assert mk[0]["error_R"] < classic[0]["error_R"]
    assert "| rk4 MK | dt 2e-02 |" in text
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert "no figure" in text
    else:
        assert (tmp_path / "bench.png").read_bytes()[:4] == b"\x89PNG" and "![work-precision]" in text


def test_the_c_step_is_the_same_step():
    c = CStep.build()
    if c is None:
        pytest.skip("no gcc")
    scene = Scene.load(targets.HILLS)
    run = Simulation(scene, method="rk4", dt=1e-3, t_end=0.5, record_every=100)
    run.advance()
    ns, x, y = c.run(scene.ball.radius, scene.ball.mass, scene.gravity, scene.start.x, scene.start.y,
                     1e-3, 500)
    assert ns > 0
    assert np.abs(run.rows[-1, 1:3] - [x, y]).max() < 1e-12
    assert np.abs(run.rows[-1, 1:3] - [scene.start.x, scene.start.y]).max() > 1e-3  # it moved


def test_memory_is_measured_in_a_separate_process():
    assert 10 * 2**20 < targets.peak_memory(1000) < 1 << 30


def test_bench_command_line_usage(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["bench", "--help"])
    assert stop.value.code == 0 and "--quick" in capsys.readouterr().out
