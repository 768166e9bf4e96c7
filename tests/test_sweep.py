"""Sweeps: each run ends exactly where ``simulate`` ends the same scene; grid, validation,
workers, cancellation, the files and the command line."""

import csv
import dataclasses
import json
import math
import os
import signal
import threading

import numpy as np
import pytest

from rollball import Scene, simulate, sweep
from rollball.cli import main
from rollball.examples import EXAMPLES_DIR
from rollball.sweeps import Grid, parse_vary
from rollball.scene import Contact, Start
from rollball.sweeps.grid import with_values
from rollball.sweeps.outcomes import OUTCOMES
from rollball.trajectory import MODES

LIFTOFF = Scene.load(EXAMPLES_DIR / "liftoff.json")
# liftoff where the ball could slip and rolling resistance could stop it: its runs go through
# ``Simulation``, which holds the GIL (processes)
SLIPPING = Scene.from_dict({**LIFTOFF.to_dict(), "contact": {"friction": 0.5, "restitution": 0.0,
                                                             "after_liftoff": "fly", "rolling_resistance": 0.001}})


def _outcomes_of(traj):
    """The sweep's outcomes, computed independently from a full recorded trajectory."""
    speed = np.linalg.norm(traj.velocity, axis=1)
    return {"t_reached": traj.t[-1], "liftoff_time": np.nan if traj.liftoff_time is None else traj.liftoff_time,
            "x_end": traj.contact[-1, 0], "y_end": traj.contact[-1, 1], "energy_drift": traj.energy_drift,
            "min_normal_force": traj.normal_force.min(), "max_speed": speed.max(),
            "path_length": np.linalg.norm(np.diff(traj.center, axis=0), axis=1).sum()}


@pytest.mark.parametrize("scene, vary", [
    (LIFTOFF, {"start.vx": [3.0, 4.5, 6.0], "start.spin": [-4.0, 2.0]}),        # with and without lift-off
    (Scene.load(EXAMPLES_DIR / "too_big.json"), {"ball.radius": [0.05, 0.2]}),   # does not fit
    (Scene.load(EXAMPLES_DIR / "hills.json"), {"integrator.dt": [0.003, 0.0021], "duration": [0.5, 1.0]}),
    # runs that fly, bounce and roll, or fly to the end (their flights' rows without contacts, ``run_one``)
    (Scene.load(EXAMPLES_DIR / "ridge_jump.json"), {"start.vx": [3.3, 3.6], "contact.restitution": [0.2, 0.5]}),
    (Scene.from_dict({**LIFTOFF.to_dict(), "landscape": "-0.5*x^2 - 0.1*y", "duration": 0.8,
                      "start": {"x": -0.2, "y": 0.1, "vx": 4.0, "vy": 0.5},
                      "contact": {"friction": None, "restitution": 0.0, "after_liftoff": "fly"}}),
     {"start.vy": [0.0, 0.5]}),
], ids=["liftoff", "too_big", "steps", "ridge_jump", "away"])
def test_every_run_ends_where_simulate_ends_it(scene, vary):
    table = sweep(scene, vary, workers=1)
    values = table.grid.values()
    for i in range(len(table)):
        traj = simulate(with_values(scene, table.keys, values[i]))
        assert table["status"][i] == str(traj.status)
        for name, expected in _outcomes_of(traj).items():
            np.testing.assert_allclose(table[name][i], expected, rtol=1e-12, atol=1e-14, err_msg=name)
    assert set(table["status"]) == {"ok"} | ({"does_not_fit"} if "ball.radius" in vary else set())


# Scenes whose ball rolls and flies in vacuum: the batch loop flies their runs itself (``kernel.batch``).
FLYING = [("liftoff", {"start.vx": [3.0, 4.5, 6.0], "start.spin": [-4.0, 2.0]}),
          ("ridge_jump", {"start.vx": [3.3, 3.6], "contact.restitution": [0.0, 0.2, 0.5]}),
          ("cylinder", {"start.x": [0.02, 0.05, 0.3], "duration": [0.9, 2.5]}),
          ("bump", {"start.vy": [0.0, 0.3], "start.vx": [2.0, 4.5]})]


@pytest.mark.parametrize("name, vary", FLYING, ids=[name for name, _ in FLYING])
def test_the_batch_loop_flies_lands_and_rolls_on_as_the_mode_machine_does(monkeypatch, name, vary):
    """Runs that roll, fly, bounce and roll on run in the compiled batch loop, on threads, none
    left to ``Simulation``, and give what their run through ``Simulation`` gives (``run_one``):
    the lift-off time, the landings and the end mode exactly, the rest to round-off (the state
    after a landing is made in the kernel; a y_end was seen one unit in the last place apart)."""
    from rollball.sweeps import batch

    scene = Scene.load(EXAMPLES_DIR / f"{name}.json")
    one, referred = batch.run_one, []
    monkeypatch.setattr(batch, "run_one", lambda varied: referred.append(varied) or one(varied))
    table = sweep(scene, vary, workers=2)
    assert not referred and not table.processes and set(table["status"]) == {"ok"}
    assert np.isfinite(table["liftoff_time"]).any() and (table["landings"] > 0).any()
    if name == "ridge_jump":   # (bounces: the restitution read per run)
        assert table["landings"].max() >= 3 and table["landings"][0] == 1
    _gives_what_simulation_gives(table, scene, one, ("liftoff_time", "end_mode", "landings"), rtol=1e-13, atol=1e-16)


def _gives_what_simulation_gives(table, scene, one, exact, *, rtol, atol):
    """Each run of ``table`` (a sweep of ``scene``) has the status and outcomes of its run through
    ``Simulation`` (``one``: ``batch.run_one``), the ``exact`` ones to the bit, the rest within rtol, atol."""
    exact = [OUTCOMES.index(name) for name in exact]
    for i, values in enumerate(table.grid.values()):
        code, expected = one(with_values(scene, table.keys, values))
        assert table.codes[i] == code
        np.testing.assert_array_equal(table.outcomes[i][exact], expected[exact], err_msg=f"run {i}")
        np.testing.assert_allclose(table.outcomes[i], expected, rtol=rtol, atol=atol, err_msg=f"run {i}")


# Scenes whose ball slips from rolling and grips in vacuum: the batch loop slides (and flies) their
# runs itself: the bench's tilted bowl thrown sideways (a slip in 3-D, a grip), the incline from rest
# over the friction (no slip, a slip at once), the cylinder with friction (slips, then flies),
# liftoff with little friction (slips, flies, lands sliding or rolling, grips)
BOWL = Scene("1.5*x^2 + 0.9*y^2 + 0.3*x*y", start=Start(x=-0.1, y=0.1, vx=1.2, vy=-0.6),
             contact=Contact(friction=0.2), duration=0.9)
INCLINE = Scene(f"{math.tan(math.radians(30.0))!r}*x", start=Start(0.0, 0.0, 0.0, 0.0, 0.0), duration=0.2,
                contact=Contact(None, 0.0, "glued"))
SLIDING = [(BOWL, {"start.vx": [1.0, 1.2, 1.4], "contact.friction": [0.15, 0.2, 0.6]}, 0),
           (INCLINE, {"contact.friction": [0.1, 0.16, 0.17, 0.3]}, 0),
           (dataclasses.replace(Scene.load(EXAMPLES_DIR / "cylinder.json"), contact=Contact(friction=0.3)),
            {"duration": [0.3, 1.5]}, 0),
           (dataclasses.replace(LIFTOFF, contact=Contact(friction=0.5, restitution=0.0, after_liftoff="fly")),
            {"start.vx": [4.5, 6.0], "contact.friction": [0.02, 0.05, 0.1]}, 0)]


@pytest.mark.parametrize("scene, vary, referrals", SLIDING, ids=["bowl", "incline", "cylinder", "liftoff"])
def test_the_batch_loop_slips_and_grips_as_the_mode_machine_does(monkeypatch, scene, vary, referrals):
    """Runs that slip from rolling, slide, grip, fly, land sliding or rolling and go on run in the
    compiled batch loop, on threads (``referred``: so many left to ``Simulation``), and give what
    their run through ``Simulation`` gives (``run_one``): the statuses, the end modes, the landings
    and the first slip's time exactly (the same kernel run up to it), the rest to round-off (the
    state at a slip or a grip is made in the kernel)."""
    from rollball.sweeps import batch

    one, referred = batch.run_one, []
    monkeypatch.setattr(batch, "run_one", lambda varied: referred.append(varied) or one(varied))
    table = sweep(scene, vary, workers=2)
    assert len(referred) == referrals and not table.processes and set(table["status"]) == {"ok"}
    assert np.isfinite(table["first_slip_time"]).any()
    if "contact.friction" in vary and "start.vx" in vary and scene is not BOWL:   # (liftoff: every run lands,
        # and at friction 0.02 the landing leaves it sliding to the end)
        assert (table["landings"] == 1).all() and (table["end_mode"][::3] == MODES.index("sliding")).all()
    if scene is BOWL:   # (at friction 0.15 the runs end sliding, at 0.2 they grip, at 0.6 they only roll)
        np.testing.assert_array_equal(table["end_mode"], [1, 0, 0] * 3)
        assert np.isfinite(table["first_grip_time"][1::3]).all() and np.isnan(table["first_slip_time"][2::3]).all()
    _gives_what_simulation_gives(table, scene, one, ("end_mode", "landings", "first_slip_time"), rtol=1e-10,
                                 atol=1e-13)


# flights that end otherwise than by a landing: a ball that never comes back (the surface falls
# away faster than the parabola), one that meets a spike 0.5 mm wide (does_not_fit), a smooth drop
HARD_FLIGHTS = [("-10*x^2", 0.0, 5.0, {"ok"}), ("0.5*exp(-x^2) + 0.4*exp(-((x-1.1)/0.0005)^2)", -1.5, 3.0,
                                                {"does_not_fit"}),
                ("-5*(1+tanh(50*x))", -1.0, 3.0, {"ok"})]


@pytest.mark.parametrize("landscape, x, vx, statuses", HARD_FLIGHTS, ids=["never_lands", "spike", "drop"])
def test_the_batch_loops_flights_end_as_the_mode_machines_do(landscape, x, vx, statuses):
    """A sweep's flights that never land, meet a feature narrower than the landing search's reach,
    or fall off a steep smooth drop end with the status and outcomes of the same runs through
    ``Simulation`` (``run_one``), whichever of the two ran them."""
    from rollball.sweeps import batch

    scene = Scene.from_dict({**LIFTOFF.to_dict(), "landscape": landscape, "duration": 2.0,
                             "start": {**LIFTOFF.to_dict()["start"], "x": x, "vx": vx}})
    assert batch.compiled(scene, ("start.vx",))
    table = sweep(scene, {"start.vx": [0.95 * vx, vx, 1.05 * vx]}, workers=1)
    assert set(table["status"]) == statuses
    for i, values in enumerate(table.grid.values()):
        code, expected = batch.run_one(with_values(scene, table.keys, values))
        assert table.codes[i] == code
        np.testing.assert_allclose(table.outcomes[i], expected, rtol=1e-13, atol=1e-16, err_msg=f"run {i}")


def test_a_run_the_batch_loop_cannot_finish_is_left_to_the_mode_machine(monkeypatch):
    """A ball that reaches a ridge's kink (where the mode machine may turn it over the edge) is
    left to ``Simulation``, the run that does not reach it is the batch loop's; either gives
    what ``Simulation`` gives."""
    from rollball.sweeps import batch

    roof = Scene.from_dict({**LIFTOFF.to_dict(), "landscape": "min(0.25*x, -0.15*x)",
                            "start": {"x": -0.8, "y": 0.1, "vx": 2.5, "vy": 0.0}})
    one, referred = batch.run_one, []
    monkeypatch.setattr(batch, "run_one", lambda varied: referred.append(varied) or one(varied))
    table = sweep(roof, {"start.vx": [0.5, 2.5]}, workers=1)
    assert [scene.start.vx for scene in referred] == [2.5]
    assert np.isnan(table["liftoff_time"][0]) and table["liftoff_time"][1] > 0.0
    for i, values in enumerate(table.grid.values()):
        code, expected = one(with_values(roof, table.keys, values))
        assert table.codes[i] == code
        np.testing.assert_allclose(table.outcomes[i], expected, rtol=1e-13, atol=1e-16)


@pytest.mark.parametrize("garbage", [np.nan, np.inf, -1e300])
def test_outcomes_do_not_depend_on_what_the_scratch_memory_held(monkeypatch, garbage):
    # the batch loop's scratch comes from np.empty: whatever it held must not change a run (the
    # motion-only state never writes its orientation scratch, which once made lift-offs vanish)
    vary = {"start.vx": [4.5, 5.25, 6.0]}   # each lifts off
    clean = sweep(LIFTOFF, vary, workers=1)
    empty = np.empty

    def used(shape, dtype=float, **kwargs):
        a = empty(shape, dtype=dtype, **kwargs)
        if a.dtype == np.float64:
            a.fill(garbage)
        return a

    monkeypatch.setattr(np, "empty", used)
    dirty = sweep(LIFTOFF, vary, workers=1)
    monkeypatch.undo()
    assert np.isfinite(clean["liftoff_time"]).all()
    np.testing.assert_array_equal(dirty.outcomes, clean.outcomes)


def test_a_landscape_undefined_along_the_way_is_nonfinite():
    scene = Scene(landscape="sqrt(x)", start=LIFTOFF.start.__class__(x=0.5, y=0.0, vx=-3.0), duration=1.0)
    table = sweep(scene, {"start.x": [0.5, -1.0]}, workers=1)
    assert list(table["status"]) == ["nonfinite", "nonfinite"]
    traj = simulate(scene)
    assert table["t_reached"][0] == traj.t[-1] < 1.0 and table["x_end"][0] == traj.contact[-1, 0]
    assert np.isnan(table["t_reached"][1])  # the start itself is outside the landscape's domain


def test_a_refused_scene_gives_its_row_a_status_and_a_message(tmp_path):
    table = sweep(LIFTOFF, {"ball.radius": [0.1, -0.1, 0.0], "start.vx": [4.0, 5.0]}, workers=1)
    assert list(table["status"]) == ["ok"] * 2 + ["invalid"] * 4
    assert "ball.radius: must be greater than 0" in table.messages[2]
    assert np.isnan(table.outcomes[2:]).all()
    table.save(tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "sweep.csv", encoding="utf-8")))
    assert rows[3]["status"] == "invalid" and rows[3]["x_end"] == "" and "radius" in rows[3]["message"]


def test_grid_is_row_major_with_the_last_key_fastest():
    grid = Grid.of({"start.vx": [1.0, 2.0], "start.spin": [10.0, 20.0, 30.0]})
    assert grid.shape == (2, 3) and grid.size == 6
    np.testing.assert_array_equal(grid.values(), [[1, 10], [1, 20], [1, 30], [2, 10], [2, 20], [2, 30]])
    np.testing.assert_array_equal(grid.values(4, 6), [[2, 20], [2, 30]])


def test_parse_vary_includes_both_ends():
    key, values = parse_vary("start.vx=3:6:61")
    assert key == "start.vx" and len(values) == 61 and values[0] == 3.0 and values[-1] == 6.0
    assert parse_vary("gravity=9.81:1:1")[1].tolist() == [9.81]


@pytest.mark.parametrize("text, words", [
    ("start.z=0:1:3", "cannot vary 'start.z'"),
    ("landscape=0:1:3", "cannot vary 'landscape'"),
    ("integrator.method=0:1:3", "cannot vary"),
    ("start.vx=0:1:0", "N must be 1 or more"),
    ("start.vx=0:1", "expected KEY=START:STOP:N"),
    ("start.vx=a:1:3", "must be numbers"),
    ("start.vx=0:inf:3", "finite"),
    ("start.vx=0:1:2.5", "whole number"),
    ("start.vx", "expected KEY=START:STOP:N"),
])
def test_bad_vary_is_refused_with_a_message(text, words):
    with pytest.raises(ValueError, match=words):
        parse_vary(text)


def test_bad_grids_are_refused():
    with pytest.raises(ValueError, match="more than a sweep may run"):
        Grid.of({"start.vx": np.zeros(10_000), "start.vy": np.zeros(10_000)})
    with pytest.raises(ValueError, match="finite"):
        Grid.of({"start.vx": [1.0, np.nan]})
    with pytest.raises(ValueError, match="non-empty"):
        Grid.of({"start.vx": []})
    with pytest.raises(ValueError, match="varied twice"):
        Grid.of([("start.vx", [1.0]), ("start.vx", [2.0])])
    with pytest.raises(ValueError, match="at least one key"):
        Grid.of({})
    with pytest.raises(ValueError, match="fixed-step methods"):
        sweep(Scene(landscape="0", integrator=LIFTOFF.integrator.__class__(method="dopri5")),
              {"start.vx": [1.0]})
    with pytest.raises(ValueError, match="not both"):
        sweep(LIFTOFF, {"start.vx": [1.0]}, workers=1, scheduler="tcp://127.0.0.1:1")
    with pytest.raises(ValueError, match="workers"):
        sweep(LIFTOFF, {"start.vx": [1.0]}, workers=0)


def _sweep_processes() -> list:
    """This process's worker processes that run sweeps (loky's)."""
    import psutil

    return [p for p in psutil.Process().children(recursive=True)
            if "loky" in " ".join(p.cmdline()) and "resource_tracker" not in " ".join(p.cmdline())]


def test_processes_give_the_same_table_bit_for_bit_and_report_progress():
    """A ball that can slip runs through ``Simulation``, which holds the GIL: on two workers its
    batches run in worker processes; the table is that of one worker (in this process) bit for bit."""
    vary = {"start.vx": np.linspace(3, 6, 26), "start.spin": np.linspace(-4, 4, 5)}
    calls = []
    one = sweep(SLIPPING, vary, workers=1)
    two = sweep(SLIPPING, vary, workers=2, progress=lambda done, total, text: calls.append((done, total)))
    np.testing.assert_array_equal(one.codes, two.codes)
    np.testing.assert_array_equal(one.outcomes, two.outcomes)   # NaN in the same places too
    assert calls[-1] == (130, 130) and [d for d, _ in calls] == sorted(d for d, _ in calls)
    assert not two.partial and two.workers == 2 and two.error is None and two.processes and not one.processes
    assert len(_sweep_processes()) == 2


def test_a_sweep_too_small_to_repay_starting_processes_runs_on_threads():
    from rollball.sweeps.runner import PROCESS_EVALUATIONS, run_evaluations

    vary = {"start.vx": np.linspace(3, 6, 12)}   # (liftoff: 4 000 evaluations a run, 48 000 in all)
    assert 12 * run_evaluations(SLIPPING, Grid.of(vary)) < PROCESS_EVALUATIONS
    small = sweep(SLIPPING, vary, workers=2)
    assert not small.processes and small.done.all()


def test_without_processes_the_runs_go_on_threads(monkeypatch):
    from rollball.sweeps import processes

    def refused(workers):
        raise OSError("no semaphores here")

    vary = {"start.vx": np.linspace(3, 6, 200)}
    monkeypatch.setattr(processes, "pool", refused)
    threads = sweep(SLIPPING, vary, workers=2)
    monkeypatch.undo()
    np.testing.assert_array_equal(threads.outcomes, sweep(SLIPPING, vary, workers=1).outcomes)
    assert threads.error is None and threads.done.all() and not threads.processes


def test_a_worker_process_that_dies_stops_the_sweep_keeping_the_finished_runs():
    killed = []

    def progress(done, total, text):   # after the first batch: one of the workers is killed
        if not killed:
            victim = _sweep_processes()[0]
            victim.kill()
            killed.append(victim.pid)

    table = sweep(SLIPPING, {"start.vx": np.linspace(3, 6, 4000)}, workers=2, progress=progress)
    assert killed and table.partial and "worker process ended unexpectedly" in table.error
    assert 0 < table.done.sum() < len(table) and set(table["status"][table.done]) == {"ok"}
    again = sweep(SLIPPING, {"start.vx": np.linspace(3, 6, 200)}, workers=2)   # a new pool
    assert again.done.all() and again.error is None and again.processes


def test_cancel_stops_early_and_keeps_the_finished_runs(tmp_path):
    cancel = threading.Event()
    table = sweep(LIFTOFF, {"start.vx": np.linspace(3, 6, 400)}, workers=1, cancel=cancel,
                  progress=lambda done, total, text: cancel.set())
    done = table.done
    assert table.partial and 0 < done.sum() < len(table)
    assert set(table["status"][~done]) == {"not_run"} and set(table["status"][done]) == {"ok"}
    table.save(tmp_path)
    info = json.loads((tmp_path / "sweep.json").read_text())
    assert info["partial"] is True and info["finished"] == done.sum() and info["runs"] == 400
    assert len((tmp_path / "sweep.csv").read_text().splitlines()) == 1 + done.sum()


def test_save_writes_csv_json_and_a_map(tmp_path):
    vary = {"start.vx": [3.0, 5.0, 7.0], "start.spin": [-1.0, 1.0]}
    table = sweep(LIFTOFF, vary, workers=1)
    files = table.save(tmp_path, color="x_end")
    assert [f.name for f in files] == ["sweep.csv", "sweep.json", "sweep.png"]
    rows = list(csv.reader(open(tmp_path / "sweep.csv", encoding="utf-8")))
    assert rows[0] == ["start.vx", "start.spin", "status", "t_reached", "liftoff_time", "x_end", "y_end",
                       "energy_drift", "min_normal_force", "max_speed", "path_length", "end_mode", "landings",
                       "first_slip_time", "first_grip_time", "rest_x", "rest_y", "rest_time", "basin", "message"]
    assert len(rows) == 7 and rows[1][:3] == ["3.0", "-1.0", "ok"] and rows[1][4] == ""   # no lift-off
    assert float(rows[5][4]) == table["liftoff_time"][4]                                  # full precision
    info = json.loads((tmp_path / "sweep.json").read_text())
    assert info["format"] == "rollball-sweep" and info["grid"][0] == {"key": "start.vx", "n": 3,
                                                                       "values": [3.0, 5.0, 7.0]}
    assert info["scene"]["landscape"] == LIFTOFF.landscape and info["status"] == {"ok": 6}
    assert (tmp_path / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_sweep_writes_the_files(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sweep", str(EXAMPLES_DIR / "liftoff.json"), "--vary", "start.vx=3:6:4",
                 "--workers", "2", "--out", str(out)]) == 0
    line = capsys.readouterr().out
    assert "4 of 4 runs" in line and "runs/s" in line
    assert sorted(p.name for p in out.iterdir()) == ["sweep.csv", "sweep.json", "sweep.png"]


@pytest.mark.parametrize("args, words", [
    (["--vary", "start.z=0:1:2"], "cannot vary"),
    (["--vary", "start.vx=0:1:0"], "N must be 1 or more"),
    (["--vary", "start.vx=0:1:5000", "--vary", "start.vy=0:1:5000"], "more than a sweep may run"),
    (["--vary", "start.vx=0:1:2", "--vary", "start.vx=0:1:2"], "varied twice"),
    (["--vary", "start.vx=0:1:2", "--color", "speed"], "not an outcome"),
    (["--vary", "start.vx=0:1:2", "--workers", "0"], "must be 1 or more"),
    (["--vary", "start.vx=0:1:2", "--workers", "1", "--scheduler", "tcp://x:1"], "not allowed with"),
    ([], "--vary"),
])
def test_cli_bad_input_exits_2_with_one_line(args, words, tmp_path, capsys):
    code = None
    try:
        code = main(["sweep", str(EXAMPLES_DIR / "liftoff.json"), "--out", str(tmp_path)] + args)
    except SystemExit as e:  # argparse usage errors
        code = e.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err and "Traceback" not in err


def test_cli_refuses_an_adaptive_scene(tmp_path, capsys):
    path = tmp_path / "a.json"
    Scene(landscape="0", integrator=LIFTOFF.integrator.__class__(method="dopri5")).save(path)
    assert main(["sweep", str(path), "--vary", "start.vx=0:1:2", "--out", str(tmp_path)]) == 2
    assert "fixed-step methods" in capsys.readouterr().err


def test_ctrl_c_writes_the_finished_runs_marked_partial(tmp_path, capsys):
    out = tmp_path / "out"
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        code = main(["sweep", str(EXAMPLES_DIR / "liftoff.json"), "--vary", "start.vx=3:6:20000",
                     "--workers", "1", "--out", str(out)])
    finally:
        timer.cancel()
    assert code == 130
    info = json.loads((out / "sweep.json").read_text())
    assert info["partial"] is True and 0 < info["finished"] < 20000
    assert len((out / "sweep.csv").read_text().splitlines()) == 1 + info["finished"]
    assert "stopped early" in capsys.readouterr().err


def test_ctrl_c_in_a_terminal_stops_a_sweep_on_worker_processes_keeping_the_finished_runs(tmp_path):
    """Ctrl-C in a terminal interrupts the whole process group, the sweep's worker processes
    too, here while they start: they never see it, finish their batches, and the command
    writes the finished runs."""
    import subprocess
    import sys
    import time

    import psutil

    out = tmp_path / "out"
    command = [sys.executable, "-m", "rollball", "sweep", str(EXAMPLES_DIR / "liftoff.json"),   # (one that can rest)
               "--vary", "start.vx=3:6:100000", "--vary", "contact.rolling_resistance=0.001:0.001:1", "--workers", "2",
               "--out", str(out)]
    process = subprocess.Popen(command, start_new_session=True, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and process.poll() is None:   # the workers started
            workers = [p for p in psutil.Process(process.pid).children(recursive=True)
                       if "popen_loky" in " ".join(p.cmdline())]
            if len(workers) == 2:
                break
            time.sleep(0.01)
        assert process.poll() is None, process.communicate()
        os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 130, err
    info = json.loads((out / "sweep.json").read_text())
    assert info["partial"] is True and 0 < info["finished"] < 100000 and info["error"] is None
    assert len((out / "sweep.csv").read_text().splitlines()) == 1 + info["finished"]
    assert "stopped early" in err and "Traceback" not in err


def test_the_batch_loop_reads_the_columns_the_trajectory_names():
    from rollball import kernel, trajectory

    assert (kernel.ROW_CENTER, kernel.ROW_VELOCITY, kernel.ROW_ENERGY, kernel.ROW_FORCE) == (
        trajectory.CENTER.start, trajectory.VELOCITY.start, trajectory.ENERGY, trajectory.NORMAL_FORCE)
    assert trajectory.CENTER.stop - trajectory.CENTER.start == trajectory.VELOCITY.stop - trajectory.VELOCITY.start == 3


def test_a_contact_scenes_runs_report_their_modes():
    """The liftoff example flies (version 3): each run goes through Simulation, and the sweep
    says how it ended, how often it landed and when it first slipped, as the run itself does."""
    table = sweep(LIFTOFF, {"start.vx": [3.0, 5.0]}, workers=1)
    assert list(table["landings"]) == [0.0, 1.0] and list(table["end_mode"]) == [0.0, 0.0]   # rolling
    assert np.isnan(table["first_slip_time"]).all()
    fast = simulate(with_values(LIFTOFF, ("start.vx",), (5.0,)))
    assert table["liftoff_time"][1] == fast.liftoff_time and table["x_end"][1] == fast.contact[-1, 0]
    cylinder = dataclasses.replace(Scene.load(EXAMPLES_DIR / "cylinder.json"), contact=Contact(friction=0.3))
    slipping = sweep(cylinder, {"duration": [1.5]}, workers=1)
    run = simulate(dataclasses.replace(cylinder, duration=1.5))
    slip = next(change for change in run.transitions if change.kind == "slip")
    assert slipping["first_slip_time"][0] == slip.time and slipping["end_mode"][0] == MODES.index(run.mode[-1])


def test_a_billiard_sweep_slips_from_the_start_and_grips_at_the_exact_time():
    """Struck without spin on the plane with friction μ, every run slides from t = 0 (first slip
    0, no landing) and grips at t* = 2v₀/(7μg), then rolls at 5v₀/7. The duration falls between
    the runs' t*: those that grip before it end rolling, the others sliding, each where the
    closed form puts it (decelerating at μg while it slides)."""
    scene = dataclasses.replace(Scene.load(EXAMPLES_DIR / "billiard.json"), duration=0.3)
    v0 = np.array([0.5, 1.25, 2.0, 2.5, 3.5])
    table = sweep(scene, {"start.vx": v0}, workers=1)
    mu, g, T = scene.contact.friction, scene.gravity, scene.duration
    grip = 2 * v0 / (7 * mu * g)
    rolls = grip < T
    assert rolls.any() and not rolls.all() and set(table["status"]) == {"ok"}
    np.testing.assert_array_equal(table["first_slip_time"], 0.0)
    np.testing.assert_array_equal(table["landings"], 0.0)
    np.testing.assert_array_equal(table["end_mode"], np.where(rolls, MODES.index("rolling"), MODES.index("sliding")))
    np.testing.assert_allclose(table["first_grip_time"][rolls], grip[rolls], rtol=0, atol=1e-12)
    assert np.isnan(table["first_grip_time"][~rolls]).all()
    slid = np.minimum(grip, T)
    x_end = scene.start.x + v0 * slid - 0.5 * mu * g * slid ** 2 + np.where(rolls, 5 * v0 / 7 * (T - grip), 0.0)
    np.testing.assert_allclose(table["x_end"], x_end, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(table["max_speed"], v0)


def test_the_2011_models_runs_roll_to_the_end():
    table = sweep(Scene.load(EXAMPLES_DIR / "hills.json"), {"start.vx": [0.0, 0.5]}, workers=1)
    assert list(table["end_mode"]) == [0.0, 0.0] and list(table["landings"]) == [0.0, 0.0]
    assert np.isnan(table["first_slip_time"]).all()


def test_a_sweep_over_friction_finds_the_incline_threshold_and_over_restitution_the_bounces():
    """On an incline of 30° from rest the ball rolls iff μ ≥ (2/7) tan 30° (0.165), else it slips at
    once; a glued scene (friction null) given a friction by the sweep slides where it must. A
    restitution of 0 lands once and stays; 0.6 bounces again."""
    incline = Scene(f"{math.tan(math.radians(30.0))!r}*x", start=Start(0.0, 0.0, 0.0, 0.0, 0.0), duration=0.2,
                    contact=Contact(None, 0.0, "glued"))
    mu = np.array([0.1, 0.15, 0.16, 0.17, 0.2, 0.3])
    table = sweep(incline, {"contact.friction": mu}, workers=1)
    rolls = mu >= 2.0 / 7.0 * math.tan(math.radians(30.0))
    assert set(table["status"]) == {"ok"}
    np.testing.assert_array_equal(np.isnan(table["first_slip_time"]), rolls)
    np.testing.assert_array_equal(table["end_mode"], np.where(rolls, MODES.index("rolling"), MODES.index("sliding")))
    bounce = dataclasses.replace(Scene.load(EXAMPLES_DIR / "liftoff.json"), duration=1.5)
    table = sweep(bounce, {"contact.restitution": [0.0, 0.6]}, workers=1)
    assert set(table["status"]) == {"ok"}
    assert table["landings"][0] == 1.0 and table["landings"][1] > 1.0
    refused = sweep(bounce, {"contact.restitution": [1.5]}, workers=1)
    assert list(refused["status"]) == ["invalid"] and "restitution" in refused.messages[0]


def test_the_contacts_outcomes_are_drawn_where_the_contact_changes_and_named_in_the_help(capsys):
    """A sweep whose runs slip and grip draws the contact's outcomes against the varied key too
    (the grip at 2v₀/(7μg) falls as 1/μ), a glued one only the kernel's; sweep --help names them."""
    from rollball.sweeps.outcomes import CONTACT_OUTCOMES
    from rollball.sweeps.plot import _contact_changes

    billiard = sweep(Scene.load(EXAMPLES_DIR / "billiard.json"), {"contact.friction": [0.1, 0.2]}, workers=1)
    np.testing.assert_allclose(billiard["first_grip_time"], 4.0 / (7 * np.array([0.1, 0.2]) * 9.81), rtol=0, atol=1e-12)
    glued = sweep(Scene.load(EXAMPLES_DIR / "hills.json"), {"start.vx": [0.0, 0.5]}, workers=1)
    assert _contact_changes(billiard) and not _contact_changes(glued)
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert all(name in text for name in OUTCOMES) and all(name in text for name in CONTACT_OUTCOMES)


def test_a_process_that_ends_during_a_sweep_on_worker_processes_waits_only_for_the_batches_in_flight():
    """The batches sent to worker processes are run even when the sweep's process exits (loky
    finishes them): a sweep sends a few at a time, so a program that ends (the app closed in
    mid-sweep) waits seconds, not for the whole sweep (here some 200 s of batches)."""
    import subprocess
    import sys
    import time

    code = """if True:
        import threading, time
        import numpy as np
        from rollball import Scene, sweep
        from rollball.examples import EXAMPLES_DIR
        scene = Scene.load(EXAMPLES_DIR / "liftoff.json")
        started = threading.Event()
        run = lambda: sweep(scene, {"start.vx": np.linspace(3, 6, 400000), "contact.friction": [0.5]}, workers=2,
                            progress=lambda done, total, text: started.set())   # (a ball that can slip)
        threading.Thread(target=run, daemon=True).start()
        started.wait(120)
        print("exiting", flush=True)
    """
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout.readline().strip() == "exiting"   # (a batch has finished)
        exiting = time.monotonic()
        process.wait(timeout=60)
        assert time.monotonic() - exiting < 60 and process.returncode == 0
    finally:
        process.kill()
        process.wait()


def test_a_glued_sweep_on_every_core_starts_no_process():
    """The 2011 model's runs release the GIL in the compiled batch loop: their sweep runs on
    threads and starts nothing (no worker, no resource tracker)."""
    import subprocess
    import sys

    code = """if True:
        import numpy as np, psutil
        from rollball import Scene, sweep
        from rollball.examples import EXAMPLES_DIR
        table = sweep(Scene.load(EXAMPLES_DIR / "hills.json"), {"start.x": np.linspace(-1, 1, 400)}, workers=2)
        print(table.processes, len(psutil.Process().children(recursive=True)))
    """
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert result.stdout.split() == ["False", "0"], result.stderr
