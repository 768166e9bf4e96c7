"""``rollball bench`` in miniature: the report's shape, sane errors, and the C yardstick."""

import json
import time

import numpy as np
import pytest

from rollball import Scene, Simulation
from rollball.bench import Config, report, run, targets
from rollball.bench.cstep import CStep
from rollball.cli import main
from rollball.comparison import default_runs
from rollball.examples import EXAMPLES_DIR


def test_small_work_precision_report(tmp_path):
    text = run(tmp_path, Config(("bowl",), 0.5, quick=True, targets=False), log=lambda _: None)
    assert (tmp_path / "bench.md").read_text() == text
    bowl = json.loads((tmp_path / "bench.json").read_text())["scenes"]["bowl"]
    assert bowl["format"] == "rollball-compare" and bowl["t_end"] == 0.5  # rollball compare's own
    assert {(r["method"], r["munthe_kaas"]) for r in bowl["runs"]} == {(s.method, s.munthe_kaas)
                                                                        for s in default_runs()}
    scipy = [p["contact"] for p in bowl["scipy_dop853"]]
    assert len(scipy) == 2 and scipy[0] > scipy[-1] and scipy[0] < 1e-3
    # classic and Munthe-Kaas share the motion, and differ in R
    mk, classic = ([r["error"] for r in bowl["runs"] if r["method"] == "rk4" and r["munthe_kaas"] is k]
                   for k in (True, False))
    # (same steps, same contact errors; a ladder goes on until both its errors are at the floor, so
    # classic's, whose R is worse, may take a step more)
    n = min(len(mk), len(classic))
    assert n >= 2 and [e["contact"] for e in mk[:n]] == [e["contact"] for e in classic[:n]]
    assert mk[0]["orientation"] < classic[0]["orientation"]
    assert "### bowl" in text and "#### scipy DOP853 on the same equations" in text
    assert (tmp_path / "bench.png").read_bytes()[:4] == b"\x89PNG" and "![work-precision](bench.png)" in text


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


def test_a_measurements_child_process_is_stopped_after_its_timeout():
    started = time.monotonic()
    with pytest.raises(RuntimeError, match="took more than 0.5 s"):
        targets._python("import time; time.sleep(60)", timeout=0.5)
    assert time.monotonic() - started < 30


def test_the_row_limits_memory_is_measured_in_a_separate_process():
    """(Its own row limit, small: the child asserts the run stopped there, rows kept.)"""
    assert 10 * 2**20 < targets.row_limit_memory(5000) < 1 << 30


def test_bench_command_line_usage(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["bench", "--help"])
    assert stop.value.code == 0 and "--quick" in capsys.readouterr().out


def _targets(**changes):
    cold = {"import": 0.4, "first_simulate_cold_cache": 20.0, "new_formula_cold_cache": 0.1,
            "process_cold_cache": 21.0, "first_simulate_disk_cache": 0.3, "known_formula_disk_cache": 0.09,
            "process_disk_cache": 1.0, "all_methods_cold_cache": 8.0}
    results = {"c": {"ratio": 1.1, "ns_ours": 270.0, "ns_c": 245.0, "same_step": 1e-15},
               "costs": {"rk4 MK": 270.0}, "real_time": 400.0, "latency": 0.02, "latency_cpu": 0.015,
               "memory": 100 * 2**20,
               "app": {"longest_gap_ms": 90.0, "median_gap_ms": 20.0}, "cold": cold}
    for key, value in changes.items():
        if key in cold:
            cold[key] = value
        else:
            results[key] = value
    return "\n".join(report._targets(results))


def test_the_report_marks_each_figure_that_misses_its_goal():
    assert "missed" not in _targets()
    for change, row in [({"all_methods_cold_cache": 36.0}, "compiling every method"),
                        ({"c": {"ratio": 1.3, "ns_ours": 300.0, "ns_c": 230.0, "same_step": 1e-15}}, "against C"),
                        ({"latency": 0.045}, "never seen before"), ({"memory": 400 * 2**20}, "peak memory, 10"),
                        ({"row_limit_memory": 3.1e9}, "row limit"),
                        ({"hybrid": {"liftoff": {"hybrid_ms": 30.0, "glued_ms": 0.4, "ratio": 75.0},
                                     "cylinder": {"hybrid_ms": 3.0, "glued_ms": 1.0, "ratio": 3.0}}}, "| liftoff |"),
                        ({"sweep": {"runs": 400, "one_s": 1.3, "two_s": 1.0, "ratio": 1.3}}, "| 1.30 s | 1.00 s |")]:
        missed = [line for line in _targets(**change).splitlines() if "missed" in line]
        assert len(missed) == 1 and row in missed[0], (change, missed)


def test_the_report_states_the_apps_latency_against_its_goal():
    def figure(ms):
        return {"median_ms": ms, "longest_ms": 2 * ms}
    latency = {"slider": figure(40.0), "slider_compiles": 0, "formula_seen": figure(90.0),
               "formula_new": figure(120.0), "debounce_ms": 250, "goal_ms": 150, "repeats": 9}
    app = {"longest_gap_ms": 90.0, "median_gap_ms": 20.0, "latency": latency}
    text = _targets(app=app)
    assert "slider moved" in text and "**40 ms**" in text and "missed" not in text
    latency["formula_seen"] = figure(200.0)
    missed = [line for line in _targets(app=app).splitlines() if "missed" in line]
    assert len(missed) == 1 and "seen before" in missed[0]
    latency.update(preview=figure(110.0), keystroke_previewing=figure(14.0))   # reported, no goal
    text = _targets(app=app)
    assert "preview drawn (median of 9) | 110 ms" in text and "back to back (median of 9) | 14 ms" in text
    latency.update(keystroke_typing=figure(30.0), typing_keys=24, typing_interval_ms=100, typing_applied=9)
    assert "9 landscapes drawn meanwhile) (median of 24) | 30 ms (longest 60 ms) | ≤ 50 ms |" in _targets(app=app)
    latency["keystroke_typing"] = figure(70.0)   # typing lags
    missed = [line for line in _targets(app=app).splitlines() if "missed" in line]
    assert len(missed) == 2 and "typing on" in missed[1]


def test_a_run_that_changes_mode_is_timed_against_the_same_scene_glued(monkeypatch):
    from rollball.bench import targets
    monkeypatch.setattr(targets, "HYBRID", ("cylinder",))
    costs = targets.hybrid_costs(1)
    assert set(costs) == {"cylinder", "bowl, slip and grip"}
    for figures in costs.values():
        assert figures["hybrid_ms"] > 0.0 and figures["glued_ms"] > 0.0 and figures["ratio"] > 0.0


def test_a_sweep_is_timed_on_one_worker_against_two(monkeypatch):
    monkeypatch.setattr(targets.os, "cpu_count", lambda: 2)
    figures = targets.sweep_speedup(1, runs=16)
    assert figures["runs"] == 16 and figures["one_s"] > 0.0 and figures["two_s"] > 0.0
    assert figures["ratio"] == figures["one_s"] / figures["two_s"]
    assert "**" in _targets(sweep=figures) and "two workers" in _targets(sweep=figures)
    monkeypatch.setattr(targets.os, "cpu_count", lambda: 1)
    assert targets.sweep_speedup(1) is None and "two workers" not in _targets(sweep=None)


def test_a_run_with_the_three_dissipations_is_timed_against_the_same_run_without(monkeypatch):
    """``dissipation_cost``: both runs really differ (the one with rolling resistance, spin friction
    and air takes more evaluations), and the report marks a ratio above its goal."""
    from rollball.simulation import Simulation
    evaluations = []

    class Counted(Simulation):
        def advance(self, max_steps=None, **options):
            rows = super().advance(max_steps, **options)
            evaluations.append(self.evaluations)
            return rows

    monkeypatch.setattr(targets, "Simulation", Counted)
    figures = targets.dissipation_cost(1)
    assert figures["with_ms"] > 0.0 and figures["without_ms"] > 0.0 and figures["ratio"] > 0.0
    assert evaluations[0] > evaluations[1] * 1.1, evaluations   # (with the three, then without: 37 275, 32 101)
    assert figures["fastest_with_ms"] <= figures["with_ms"] and figures["fastest_without_ms"] <= figures["without_ms"]
    assert figures["fastest_ratio"] == figures["fastest_with_ms"] / figures["fastest_without_ms"]
    met = {**figures, "ratio": 1.4, "fastest_ratio": 1.45}
    assert "missed" not in _targets(dissipation=met)
    assert "with the three" in _targets(dissipation=figures)
    for key in ("ratio", "fastest_ratio"):   # (either statistic above the goal is marked)
        missed = [line for line in _targets(dissipation={**met, key: 1.6}).splitlines() if "missed" in line]
        assert len(missed) == 1 and "1.60×" in missed[0], key
    old = {key: figures[key] for key in ("with_ms", "without_ms", "ratio")}   # (a bench.json of before)
    assert "with the three" in _targets(dissipation=old)


def test_a_sweep_that_changes_mode_is_timed_against_the_same_sweep_glued(monkeypatch):
    """``hybrid_sweeps``: the sweep of the example really flies (its runs land) where the glued one
    runs the batch path, and the report marks a ratio above its goal."""
    from rollball.sweeps import batch
    monkeypatch.setattr(targets, "_hybrid_scenes", lambda: {"cylinder": Scene.load(EXAMPLES_DIR / "cylinder.json")})
    landed = []
    run = batch.run

    def counted(task):   # (the batch loop flies these runs: their landings from each batch's outcomes)
        result = run(task)
        if task.scene.contact.after_liftoff == "fly":   # (not the glued sweep's)
            landed.extend(result.outcomes[:, batch.O_LANDINGS].tolist())
        return result

    monkeypatch.setattr(batch, "run", counted)
    figures = targets.hybrid_sweeps(1, runs=6)
    assert set(figures) == {"cylinder"} and figures["cylinder"]["runs"] == 6
    assert figures["cylinder"]["hybrid_s"] > 0.0 and figures["cylinder"]["glued_s"] > 0.0
    # (the warm-up's and the timed sweep's on one worker, the first and the timed on every core: six
    # runs are too few to go to worker processes; the Dask sweeps fly in Dask's workers, out of reach)
    from rollball.sweeps.runner import local_workers
    assert len(landed) == 24 and min(landed) >= 1, landed
    assert figures["cylinder"]["hybrid_all_s"] > 0.0 and figures["cylinder"]["glued_all_s"] > 0.0
    assert figures["cylinder"]["workers"] >= 1
    assert figures["cylinder"]["processes"] is False   # (six runs: too few to repay starting processes)
    assert "| cylinder | " in _targets(hybrid_sweeps={"cylinder": figures["cylinder"]}) and "| threads |" in _targets(
        hybrid_sweeps={"cylinder": figures["cylinder"]})
    for suffix in ("", "_all", "_dask"):   # (one sweep of each: its own fastest)
        assert figures["cylinder"]["fastest_ratio" + suffix] == pytest.approx(figures["cylinder"]["ratio" + suffix])
    met = {**figures["cylinder"], "ratio": 3.0, "ratio_all": 3.5, "ratio_dask": 3.5, "fastest_ratio": 3.1,
           "fastest_ratio_all": 3.6, "fastest_ratio_dask": 3.6}
    assert "missed" not in _targets(hybrid_sweeps={"cylinder": met})
    for key in ("fastest_ratio", "fastest_ratio_all", "fastest_ratio_dask"):   # (either statistic above: marked)
        missed = [line for line in _targets(hybrid_sweeps={"cylinder": {**met, key: 4.2}}).splitlines()
                  if "missed" in line]
        assert len(missed) == 1 and "| cylinder |" in missed[0] and "4.2×" in missed[0], key
    before = {key: value for key, value in met.items() if not key.startswith("fastest")}   # (a bench.json of before)
    assert "missed" not in _targets(hybrid_sweeps={"cylinder": before}) and "| – |" in _targets(
        hybrid_sweeps={"cylinder": before})
    missed = [line for line in _targets(hybrid_sweeps={"cylinder": {**met, "ratio": 5.0}}).splitlines()
              if "missed" in line]
    assert len(missed) == 1 and "| cylinder | 6 |" in missed[0]
    missed = [line for line in _targets(hybrid_sweeps={"cylinder": {**met, "ratio_all": 4.5}}).splitlines()
              if "missed" in line]
    assert len(missed) == 1 and "| cylinder |" in missed[0] and "4.5×" in missed[0]
    assert figures["cylinder"]["hybrid_dask_s"] > 0.0 and figures["cylinder"]["dask_workers"] == local_workers()
    missed = [line for line in _targets(hybrid_sweeps={"cylinder": {**met, "ratio_dask": 4.6}}).splitlines()
              if "missed" in line]
    assert len(missed) == 1 and "| cylinder |" in missed[0] and "4.6×" in missed[0]
