"""``rollball compare`` and ``rollball.compare``: run specs, orders, errors checked against an
independent reference, the compare.json of docs/design.md §6, progress, cancelling and Ctrl-C."""

import json
import math
import threading
import time

import numpy as np
import pytest
from conftest import make_scene

import rollball
from rollball import METHODS, RunSpec, Scene, compare, comparison_report, parse_runs, simulate
from rollball.cli import main
from rollball.comparison import Cancelled, error_series, reference_run
from rollball.examples import EXAMPLES_DIR
from rollball.reference import reference_solution

# not one of the examples: a tilted bowl of waves, started moving and spinning
WAVES = dict(landscape="0.4*cos(0.9*x + 0.3)*sin(1.1*y) + 0.05*x^2", x=0.2, y=0.4, vx=0.6, vy=-0.3,
             spin=2.0, duration=3.0)
STATUSES = {"ok", "does_not_fit", "nonfinite", "aborted"}
ERROR_KEYS = {"contact", "velocity", "omega", "orientation", "energy"}


@pytest.fixture(scope="module")
def waves():
    scene = make_scene(**WAVES)
    return scene, compare(scene, runs="euler,rk4,lawson5", quick=True)


def test_orders_of_the_munthe_kaas_methods_on_a_new_scene(waves):
    _, cmp = waves
    orders = {o.spec.method: o for o in cmp.orders}
    assert set(orders) == {"euler", "rk4", "lawson5"}
    for name, expected in (("euler", 1), ("rk4", 4), ("lawson5", 5)):
        assert orders[name].expected == expected == METHODS[name].order
        assert abs(orders[name].contact - expected) <= 0.4, orders[name]
        assert abs(orders[name].orientation - expected) <= 0.4, orders[name]
    for name in ("rk4", "lawson5"):  # each ladder went down to the reference's floor
        assert [r.below_reference_floor for r in cmp.runs if r.spec.method == name][-1]


def test_reported_errors_agree_with_an_independent_computation(waves):
    scene, cmp = waves
    run = next(r for r in cmp.runs if r.spec == RunSpec("rk4") and 1e-9 < r.error["contact"] < 1e-6)
    traj = simulate(scene, method="rk4", munthe_kaas=True, dt=run.dt, t_end=cmp.t_end)
    # scipy's DOP853 on the plain equations of rollball/reference.py at the common times
    times = np.linspace(0.0, cmp.t_end, round(cmp.t_end / cmp.record_dt) + 1)
    rows = [int(np.argmin(np.abs(traj.t - t))) for t in times]
    assert len(times) >= 50 and np.allclose(traj.t[rows], times, rtol=0, atol=1e-12)
    alpha, _, R = reference_solution(scene, times, rtol=1e-13, atol=1e-13)
    contact = np.linalg.norm(traj.contact[rows] - alpha, axis=1).max()
    orientation = np.sqrt(((traj.R[rows] - R) ** 2).sum(axis=(1, 2))).max()
    energy = np.abs(traj.energy[rows] - traj.energy[0]).max() / traj.energy_scale  # E is conserved
    assert contact == pytest.approx(run.error["contact"], rel=1e-3)
    assert orientation == pytest.approx(run.error["orientation"], rel=1e-3)
    assert energy == pytest.approx(run.error["energy"], rel=1e-3)


def test_reference_and_error_series_at_the_runs_times():
    scene = make_scene(**WAVES)
    ref, estimate = reference_run(scene, t_end=1.0, record_dt=0.1)
    assert ref.status == "ok" and np.allclose(ref.t, np.arange(11) * 0.1, rtol=0, atol=1e-12)
    assert 0 < estimate < 1e-9
    traj = simulate(scene, method="rk4", dt=0.025, t_end=1.0)
    series = error_series(traj, ref)
    assert set(series) == ERROR_KEYS and all(len(v) == len(traj) for v in series.values())
    on_grid = np.isclose(traj.t / 0.1, np.round(traj.t / 0.1), rtol=0, atol=1e-9)
    for values in series.values():
        assert np.isnan(values[~on_grid]).all() and np.isfinite(values[on_grid]).all()
    assert series["contact"][0] == 0 and 1e-10 < np.nanmax(series["contact"]) < 1e-5


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def check_compare_json(doc: dict) -> None:
    """docs/design.md §6: compare.json's keys and the types of their values."""
    assert doc["format"] == "rollball-compare" and doc["version"] == 1
    assert doc["program"] == f"rollball {rollball.__version__}"
    Scene.from_dict(doc["scene"])  # the scene as in a scene file
    assert _number(doc["t_end"]) and doc["t_end"] > 0 and isinstance(doc["machine"], str)
    ref = doc["reference"]
    assert ref["method"] in METHODS and _number(ref["rtol"]) and _number(ref["error_estimate"])
    assert isinstance(ref["checked"], bool) and isinstance(ref["problems"], list) and len(ref["checks"]) == 2
    assert ref["checked"] == (not ref["problems"])
    assert isinstance(doc["runs"], list) and doc["runs"]
    for run in doc["runs"]:
        method = METHODS[run["method"]]
        assert isinstance(run["munthe_kaas"], bool) and (run["munthe_kaas"] or method.classic_allowed)
        if method.fixed_step:
            assert _number(run["dt"]) and run["rtol"] is None and run["atol"] is None
        else:
            assert run["dt"] is None and _number(run["rtol"]) and _number(run["atol"])
        assert run["status"] in STATUSES
        for key in ("steps", "rejected", "evaluations"):
            assert isinstance(run[key], int) and not isinstance(run[key], bool) and run[key] >= 0
        assert run["evaluations"] >= run["steps"] > 0
        assert _number(run["seconds"]) and run["seconds"] > 0
        assert set(run["error"]) == ERROR_KEYS
        assert set(run["below_reference_accuracy"]) <= ERROR_KEYS
        for key, value in run["error"].items():  # an error below the reference's accuracy is never a number
            assert ((_number(value) and value >= 0 and key not in run["below_reference_accuracy"])
                    or (value is None and (run["status"] != "ok" or key in run["below_reference_accuracy"])))
        assert isinstance(run["below_reference_floor"], bool)
    for order in doc["orders"]:
        assert METHODS[order["method"]].fixed_step and isinstance(order["munthe_kaas"], bool)
        for key in ("contact", "orientation"):
            assert order[key] is None or _number(order[key])


def test_quick_command_line_on_the_hills_writes_three_files(tmp_path, capsys):
    start = time.perf_counter()
    assert main(["compare", str(EXAMPLES_DIR / "hills.json"), "--quick", "--out", str(tmp_path)]) == 0
    assert time.perf_counter() - start < 600  # about 10 s on 2 shared cores, compiling included
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compare.json", "compare.md", "compare.png"]
    out = capsys.readouterr().out
    assert "fastest for 1e-06:" in out and ("for 1e-10:" in out or "no run reached 1e-10" in out)

    def refuse(name):
        raise ValueError(f"not JSON: {name}")

    doc = json.loads((tmp_path / "compare.json").read_text(), parse_constant=refuse)
    check_compare_json(doc)
    specs = {(r["method"], r["munthe_kaas"]) for r in doc["runs"]}
    assert specs == {(s.method, s.munthe_kaas) for s in rollball.comparison.default_runs()}
    fixed = {(n, mk) for n, m in METHODS.items() if m.fixed_step for mk in (True, False)
             if mk or m.classic_allowed}
    assert {(o["method"], o["munthe_kaas"]) for o in doc["orders"]} == fixed
    text = (tmp_path / "compare.md").read_text()
    assert "![error against compute time and against step size](compare.png)" in text
    assert all(f"`{s}`" in text for s in rollball.comparison.default_runs())
    assert (tmp_path / "compare.png").read_bytes()[:4] == b"\x89PNG"


def test_run_specs():
    assert parse_runs("euler/classic, rk4,dopri5,rk4") == [RunSpec("euler", False), RunSpec("rk4"),
                                                           RunSpec("dopri5")]
    assert [str(s) for s in parse_runs("adaptive,lawson5/classic")] == ["dopri5", "lawson5/classic"]
    for bad in ("rk5", "rk4/classical", "", "rk4,", "dopri5/classic", "rk4/classic/classic"):
        with pytest.raises(ValueError, match="valid runs: euler, euler/classic, rk4"):
            parse_runs(bad)
    every = [str(s) for s in rollball.comparison.default_runs()]
    assert every == [s for n, m in METHODS.items() for s in ([n, f"{n}/classic"] if m.classic_allowed else [n])]


def test_bad_specs_on_the_command_line(tmp_path, capsys):
    hills = str(EXAMPLES_DIR / "hills.json")
    assert main(["compare", hills, "--runs", "rk4,euler/magic", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "'euler/magic'" in err and "valid runs:" in err and "lawson5/classic" in err
    assert main(["compare", str(tmp_path / "missing.json"), "--out", str(tmp_path)]) == 2
    assert list(tmp_path.iterdir()) == []


def test_runs_are_timed_without_the_energy_check(monkeypatch):
    # The check of whose an energy error is takes a poor run's worst interval again at shorter
    # steps (up to a tenth of a second). Timed as the method's cost, it made Euler's first try on
    # the hills (dt 1 s, 10 steps) look like 40 ms, so the search judged the next try over budget
    # and the ladder never started. A comparison measures the true error and asks no verdict.
    def no_check(run):
        raise AssertionError("a comparison's run judged its energy error")

    monkeypatch.setattr("rollball.simulation.energy_check", no_check)
    result = compare(make_scene(**{**WAVES, "duration": 1.0}), runs="euler", quick=True)
    assert len(result.runs) >= 2 and all(run.status.value == "ok" for run in result.runs)


def test_progress_and_cancel():
    scene = make_scene(**{**WAVES, "duration": 1.0})
    cancel, seen = threading.Event(), []

    def progress(done, total, text):
        seen.append((done, total, text))
        if len(seen) == 4:
            cancel.set()

    with pytest.raises(Cancelled):
        compare(scene, runs=["rk4", "euler/classic"], progress=progress, cancel=cancel)
    assert seen[0][:2] == (0, seen[0][1]) and all(0 <= d <= t for d, t, _ in seen)
    assert [d for d, _, _ in seen] == sorted(d for d, _, _ in seen)


def test_a_reference_run_is_cancelled_within_a_chunk():
    scene = make_scene(**{**WAVES, "duration": 1000.0})   # minutes of steps if it were not cancelled
    cancel = threading.Event()
    threading.Timer(0.2, cancel.set).start()
    started = time.perf_counter()
    with pytest.raises(Cancelled):
        reference_run(scene, record_dt=1.0, cancel=cancel)
    assert time.perf_counter() - started < 10


def test_ctrl_c_exits_130_and_writes_nothing(tmp_path, monkeypatch, capsys):
    from rollball import comparison

    calls = []
    advance = comparison._advance

    def interrupted(run, cancel):
        calls.append(1)
        if len(calls) == 5:
            raise KeyboardInterrupt
        return advance(run, cancel)

    monkeypatch.setattr(comparison, "_advance", interrupted)
    assert main(["compare", str(EXAMPLES_DIR / "bowl.json"), "--runs", "rk4", "--out", str(tmp_path)]) == 130
    assert "interrupted" in capsys.readouterr().err and list(tmp_path.iterdir()) == []


def test_a_scene_that_stops_is_compared_up_to_where_it_stops(tmp_path):
    scene = Scene.load(EXAMPLES_DIR / "too_big.json")  # the ball stops fitting after about half a second
    cmp = compare(scene, runs="rk4,dopri5", quick=True)
    assert cmp.reference.status != "ok" and 0 < cmp.t_end < scene.duration
    assert cmp.runs and all(r.ok for r in cmp.runs)  # each run to the last common time before
    comparison_report.save(cmp, tmp_path)
    doc = json.loads((tmp_path / "compare.json").read_text())
    check_compare_json(doc)
    assert doc["reference"]["status"] != "ok" and doc["t_end"] == cmp.t_end


def test_a_flying_scene_is_compared_over_the_whole_run():
    """The cylinder example leaves the surface, flies and lands, then rolls on: every kernel run and
    flight records on the run's one grid, so the reference and a fixed-step run share every
    recorded time after the landing too (not only those before the lift-off), and the order fitted
    over those errors is the method's (the transitions located to its accuracy)."""
    scene = Scene.load(EXAMPLES_DIR / "cylinder.json")
    result = compare(scene, runs="rk4", quick=True)
    ref = result.reference_trajectory
    assert [c.kind for c in ref.transitions] == ["liftoff", "landing"]
    landing = ref.transitions[-1].time
    grid = ref.t[np.abs(ref.t / result.record_dt - np.round(ref.t / result.record_dt)) < 1e-9]
    assert len(grid) == round(scene.duration / result.record_dt) + 1 and np.sum(grid > landing) >= 10
    dt, every = result.record_dt / 4, 4
    traj = simulate(scene, method="rk4", dt=dt, record_every=every)
    errors = error_series(traj, ref)["contact"]
    measured = traj.t[~np.isnan(errors)]
    assert set(grid) <= set(measured)   # every common time, after the landing too
    assert np.nanmax(errors[traj.t > landing]) < 1e-5
    (order,) = result.orders
    assert abs(order.contact - 4) < 0.3 and abs(order.orientation - 4) < 0.3


def test_a_reference_that_stops_after_a_transition_is_compared_up_to_its_stop():
    """sqrt(x) ends at x = 0: the ball lifts off before it and flies on over nothing, where the
    reference stops. The comparison goes up to the last common time it reached, in the flight,
    not only to the lift-off (whose row is not a common time)."""
    scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "sqrt(x)",
                             "start": {"x": 0.5, "y": 0.0, "vx": -3.0}, "duration": 1.0})
    result = compare(scene, runs="rk4", quick=True)
    ref = result.reference_trajectory
    assert ref.status == "nonfinite" and [c.kind for c in ref.transitions] == ["liftoff"]
    assert result.t_end > ref.transitions[0].time and ref.mode[-1] == "flying"
    assert result.t_end == pytest.approx(result.record_dt * round(result.t_end / result.record_dt), abs=1e-12)
