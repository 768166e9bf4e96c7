"""The run controller without a window or GL, and the Qt-free document."""

import math
from pathlib import Path

import numpy as np
import pytest

from rollball_app.controller import FINISHED, PAUSED, READY, RUNNING, STOPPED, Run, RunController
from rollball_app.document import Document
from rollball_app.worker import ROWS
from rollball import Scene, Simulation, simulate
from rollball.examples import EXAMPLES_DIR
from rollball.landscape import landscape_for


def runs_of(scene, *variants):
    landscape = landscape_for(scene.landscape)
    return [Run(Simulation(scene, **variant), landscape, label=str(variant)) for variant in variants]


@pytest.fixture
def hills():
    return Scene.load(EXAMPLES_DIR / "hills.json")


def test_several_runs_play_in_sync_to_the_end(qtbot, hills):
    controller = RunController()
    controller.speed = math.inf
    states, frames = [], []
    controller.stateChanged.connect(states.append)
    controller.frameReady.connect(lambda force: frames.append(controller.play_time))
    runs = runs_of(hills, dict(method="rk4", t_end=0.5), dict(method="euler", munthe_kaas=False, dt=0.01,
                                                                 t_end=0.5, record_every=5))
    with qtbot.waitSignal(controller.finished, timeout=30_000):
        controller.start(runs)
    assert controller.state == FINISHED and controller.computed and controller.thread is None
    assert states[:2] == [READY, RUNNING] and states[-1] == FINISHED
    assert controller.play_time == 0.5 and frames[-1] == 0.5 and frames == sorted(frames)
    assert [len(run.buffer) for run in runs] == [501, 11]
    expected = simulate(hills, method="euler", munthe_kaas=False, dt=0.01, t_end=0.5, record_every=5)
    assert np.array_equal(runs[1].buffer.rows, expected.data)   # rows arrive whole and in order


def test_pause_step_stop_and_reset(qtbot, hills):
    controller = RunController()
    controller.start(runs_of(hills, dict(method="rk4", t_end=5.0)))
    qtbot.waitUntil(lambda: controller.play_time > 0.05, timeout=30_000)
    controller.toggle_pause()
    held = controller.play_time
    qtbot.wait(100)
    assert controller.state == PAUSED and controller.play_time == held
    controller.step()
    assert controller.play_time == pytest.approx(held + 0.016)
    controller.stop()
    assert controller.state == STOPPED and controller.thread is None and len(controller.buffer) > 1
    controller.reset()
    assert controller.state == READY and controller.runs == [] and controller.play_time == 0.0


@pytest.mark.parametrize("after_liftoff", ["glued", "fly"])
def test_liftoff_is_an_event_once(qtbot, after_liftoff):
    """A glued ball's lift-off is said once; a ball that flies says its lift-off and its landing."""
    data = Scene.load(EXAMPLES_DIR / "liftoff.json").to_dict()
    data["contact"]["after_liftoff"] = after_liftoff
    scene = Scene.from_dict(data)
    controller = RunController()
    controller.speed = math.inf
    events = []
    controller.event.connect(lambda i, kind, t: events.append((i, kind, t)))
    runs = runs_of(scene, {})
    with qtbot.waitSignal(controller.finished, timeout=30_000):
        controller.start(runs)
    if after_liftoff == "glued":
        assert events == [(0, "liftoff", runs[0].simulation.liftoff_time)] and not runs[0].transitions
    else:
        assert events == [(0, change.kind, change.time) for change in runs[0].transitions]
        assert [kind for _, kind, _ in events] == ["liftoff", "landing"]
        assert events[0][2] == runs[0].simulation.liftoff_time


def test_document_title_and_dirty_flag(hills):
    doc = Document()
    assert doc.title() == "untitled[*] — RollBall" and doc.dirty(hills) and doc.stem is None
    doc.opened(EXAMPLES_DIR / "hills.json", hills, example=True)
    assert doc.name == "hills (example)" and doc.path is None and not doc.dirty(hills)
    changed = Scene.from_dict({**hills.to_dict(), "duration": 3.0})
    assert doc.dirty(changed)
    doc.saved(Path("/tmp/mine.json"), changed)
    assert doc.title() == "mine.json[*] — RollBall" and doc.stem == "mine" and not doc.dirty(changed)


def test_runs_are_measured_against_a_reference_computed_alongside(qtbot, hills):
    controller = RunController()
    controller.speed = math.inf
    runs = runs_of(hills, dict(method="euler", munthe_kaas=False, t_end=1.5), dict(method="rk4", t_end=1.5))
    with qtbot.waitSignal(controller.measured, timeout=60_000):
        controller.start(runs, reference=(hills, 1.5, 1e-3))
    trajectory, estimate = controller.reference
    assert trajectory.t[-1] == 1.5 and 0 <= estimate < 1e-9
    for run in runs:
        assert set(run.errors) >= {"contact", "energy", "orientation"} and len(run.errors["contact"]) == 1501
        assert run.seconds > 0
    assert np.nanmax(runs[0].errors["contact"]) > 1e4 * np.nanmax(runs[1].errors["contact"])
    controller.shutdown()


def test_a_kernel_being_compiled_is_a_state_of_its_own(qtbot, hills, monkeypatch):
    from contextlib import contextmanager

    import rollball_app.worker

    @contextmanager
    def compiles_at_once(say):   # as numba's compile event would, before the first rows
        say()
        yield
    monkeypatch.setattr(rollball_app.worker, "compile_notice", compiles_at_once)
    controller = RunController()
    seen = []
    controller.stateChanged.connect(lambda state: seen.append((state, controller.compiling)))
    with qtbot.waitSignal(controller.finished, timeout=30_000):
        controller.speed = math.inf
        controller.start(runs_of(hills, dict(method="rk4", t_end=0.5)))
    assert (RUNNING, True) in seen and seen[-1] == (FINISHED, False)
    assert seen.index((RUNNING, True)) < len(seen) - 1 and not controller.compiling


def test_a_run_counts_as_ended_only_once_its_last_rows_have_arrived(qtbot, hills):
    # the worker finishes a run before the GUI thread has taken its last rows: until they are
    # there, playback must not go past what that run has shown
    controller = RunController()
    runs = controller.runs = runs_of(hills, dict(method="rk4", t_end=0.5), dict(method="dopri5", t_end=0.5))
    slow, fast = runs
    worker = controller.thread = object()   # the worker whose rows these are
    controller._progress(worker, (ROWS, 0, slow.buffer.derive(slow.simulation.advance(200)), False))
    rows = fast.simulation.advance(10**6)
    assert fast.simulation.done and len(rows) > 1
    assert controller.end_time == fast.buffer.end_time < slow.buffer.end_time   # the fast run has shown nothing
    controller._progress(worker, (ROWS, 1, fast.buffer.derive(rows), True))
    assert fast.ended and controller.end_time == slow.buffer.end_time
