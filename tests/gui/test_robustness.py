"""The app at the edges: many runs, scenes changed under a run, hostile text pasted or opened."""

import gc
import os
import threading
from pathlib import Path

import numpy as np
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from rollball_app.controller import PAUSED, READY, RUNNING
from rollball_app.worker import Worker

from .guitools import apply_fields, run_to_end, set_field
from hostile_corpus import FORMULAS, SCENE_BYTES, SCENE_TEXTS
from rollball import Scene
from rollball.examples import EXAMPLES_DIR
from rollball.text import shown


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


def test_a_hundred_start_stop_cycles_leave_no_threads_or_memory(qtbot, window):
    """Threads end; what Python holds does not grow with the runs (``tracemalloc``: numpy's arrays,
    a run's buffers among them, are counted). The process's resident size is a coarse check only:
    the allocator's arenas and the GL driver move it by ±25 MB from one try to the next."""
    import tracemalloc

    def cycles(n):
        for i in range(n):
            window.runs.start()
            if i % 2:
                qtbot.waitUntil(lambda: window.controller.buffer is not None and len(window.controller.buffer) > 0,
                                timeout=30_000)
            window.runs.stop() if i % 3 else window.runs.reset()
        qtbot.wait(50)  # deleteLater of the finished threads
        gc.collect()

    cycles(10)
    threads, memory = threading.active_count(), rss_mb()
    tracemalloc.start()
    try:
        cycles(100)
        qtbot.waitUntil(lambda: not Worker.running, timeout=10_000)   # every worker let go of
        gc.collect()
        held = tracemalloc.get_traced_memory()[0] / 2**20
    finally:
        tracemalloc.stop()
    print(f"\n100 start/stop cycles: threads {threads} -> {threading.active_count()}, "
          f"Python {held:+.1f} MB, resident {rss_mb() - memory:+.1f} MB")
    assert threading.active_count() <= threads
    assert held < 5, f"{held:.1f} MB more held by Python after 100 runs"
    assert rss_mb() - memory < 150, f"{rss_mb() - memory:.1f} MB more after 100 runs"
    run_to_end(qtbot, window)  # and it still works
    assert window.message.text().startswith("Finished")


def test_opening_a_scene_during_a_run_replaces_it(qtbot, window):
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.play_time > 0.02, timeout=30_000)
    assert window.files.open_scene(EXAMPLES_DIR / "bowl.json", remember=False)
    assert window.controller.state == READY and window.controller.thread is None
    assert window.scene == Scene.load(EXAMPLES_DIR / "bowl.json")
    run_to_end(qtbot, window)
    assert window.controller.simulation.scene.landscape == window.scene.landscape


@pytest.mark.parametrize("text, key", [(t, k) for group in SCENE_TEXTS.values() for t, k in group][::4])
def test_a_hostile_scene_file_opened_during_a_run_changes_nothing(qtbot, window, dialogs, tmp_path, text, key):
    window.runs.toggle_pause() if window.controller.state == RUNNING else window.runs.start()
    scene, state = window.scene, window.controller.state
    path = tmp_path / "hostile.json"
    path.write_text(text, encoding="utf-8")
    assert not window.files.open_scene(path)
    assert dialogs[-1][0] == "warning" and f"hostile.json: {shown(key)}" in dialogs[-1][2]
    assert (window.scene == scene and window.controller.state == state and window.controller.thread is not None
            or window.controller.computed)


@pytest.mark.parametrize("data", SCENE_BYTES, ids=range(len(SCENE_BYTES)))
def test_binary_scene_files_are_refused(window, dialogs, tmp_path, data):
    payload = data[0] if isinstance(data, tuple) else data
    path = tmp_path / "binary.json"
    path.write_bytes(payload)
    scene = window.scene
    assert not window.files.open_scene(path)
    assert dialogs and "binary.json" in dialogs[-1][2]
    assert window.scene == scene


def test_pasting_hostile_formulas_shows_the_refusal_and_keeps_the_landscape(qtbot, window, tmp_path):
    scene, surface = window.scene, window.view.surface
    marker = Path("/tmp/rollball-pwned")
    field = window.panel.formula
    entries = [entry for group in FORMULAS.values() for entry in group]
    for text, fragment in entries:
        QtGui.QGuiApplication.clipboard().setText(text)
        field.clear()
        field.setFocus()
        qtbot.keySequence(field, QtGui.QKeySequence.StandardKey.Paste)
        apply_fields(qtbot, window)
        if field.text() != text:  # a line edit drops what it cannot hold (newlines)
            continue
        assert fragment in window.panel.error_text, text
        assert window.scene == scene and window.view.surface is surface
    assert not marker.exists()
    assert len(entries) > 100


def test_fields_left_invalid_do_not_stop_a_start(qtbot, window):
    set_field(qtbot, window, "ball.radius", "-1")
    window.runs.start()
    assert window.controller.simulation.scene.ball.radius == 0.1      # the last valid scene runs
    assert "Radius: must be greater than 0" in window.panel.error_text


def test_a_start_point_outside_the_domain_says_so(qtbot, window):
    set_field(qtbot, window, "landscape", "log(x)")
    set_field(qtbot, window, "start.x", "-1")
    assert "cannot be evaluated at the start point" in window.message.text()
    run_to_end(qtbot, window)
    assert "Stopped early (nonfinite)" in window.message.text()


def test_the_adaptive_method_runs_with_tolerances_and_exact_row_times(qtbot, window):
    button = window.panel.findChild(QtWidgets.QRadioButton, "method.dopri5")
    qtbot.mouseClick(window.panel.munthe_kaas, QtCore.Qt.MouseButton.LeftButton)  # off: classic
    qtbot.mouseClick(button, QtCore.Qt.MouseButton.LeftButton)
    assert window.panel.munthe_kaas.isChecked() and not window.panel.munthe_kaas.isEnabled()
    assert window.panel.numbers["integrator.rtol"].isEnabled()
    set_field(qtbot, window, "integrator.rtol", "1e-9")
    set_field(qtbot, window, "duration", "2")
    assert window.scene.integrator.method == "dopri5" and window.scene.integrator.rtol == 1e-9
    run_to_end(qtbot, window)
    t = window.controller.buffer.t
    assert len(t) == 10_001 and t[-1] == 2.0
    np.testing.assert_allclose(t, np.linspace(0, 2, 10_001), rtol=0, atol=1e-14)
    assert abs(window.controller.buffer.energy_error).max() < 1e-6  # measured 6e-8: rtol sets the motion's error
    qtbot.mouseClick(window.panel.findChild(QtWidgets.QRadioButton, "method.rk4"), QtCore.Qt.MouseButton.LeftButton)
    assert window.panel.munthe_kaas.isEnabled() and not window.panel.numbers["integrator.rtol"].isEnabled()


def test_pause_survives_a_finished_computation(qtbot, window):
    window.runs.start()
    window.runs.toggle_pause()
    qtbot.waitUntil(lambda: window.controller.computed, timeout=10_000)
    assert window.controller.state == PAUSED and window.export_action.isEnabled()
    window.runs.toggle_pause()
    assert window.controller.state == RUNNING


def test_a_formula_is_checked_off_the_gui_thread(qtbot, window, monkeypatch):
    """While a slow formula is derived and compiled the field says so, the event loop keeps
    running and the last valid scene stays; then the new landscape is taken."""
    import rollball_app.inputs

    release = threading.Event()
    real = rollball_app.inputs.landscape_for

    def slow(text, names=()):
        release.wait(30)  # as long as the test wants: the check must not block the window
        return real(text, names)

    monkeypatch.setattr(rollball_app.inputs, "landscape_for", slow)
    scene = window.scene
    field = window.panel.formula
    field.selectAll()
    qtbot.keyClicks(field, "0.3*sin(x)*cos(2*y)")
    window.panel.apply()
    assert window.panel.checking and window.panel.error_text == "checking…"
    ticks = []
    timer = QtCore.QTimer(interval=10)
    timer.timeout.connect(lambda: ticks.append(1))
    timer.start()
    qtbot.waitUntil(lambda: len(ticks) >= 5, timeout=10_000)  # the GUI thread is free
    timer.stop()
    assert window.scene == scene and window.panel.checking
    release.set()
    qtbot.waitUntil(lambda: not window.panel.checking, timeout=60_000)
    assert window.scene.landscape == "0.3*sin(x)*cos(2*y)" and window.panel.error_text == ""


def test_a_formula_too_complex_is_refused_in_the_field(qtbot, window):
    scene = window.scene
    set_field(qtbot, window, "landscape", "*".join(f"sin({k}*x+y)" for k in range(1, 40)))
    assert "formula too complex to differentiate" in window.panel.error_text
    assert window.scene == scene


def test_every_refusal_on_start_is_shown(qtbot, window, dialogs):
    set_field(qtbot, window, "duration", "1e300")
    set_field(qtbot, window, "integrator.dt", "1e-10")
    window.runs.start()
    assert dialogs[-1][:2] == ("warning", "Cannot start") and "too many" in dialogs[-1][2]
    assert window.controller.state == READY


@pytest.mark.parametrize("kind", ["fifo", "grid", "folder"])
def test_opening_a_refused_file_says_why_and_changes_nothing(qtbot, window, dialogs, tmp_path, kind, capfd):
    path = tmp_path / "scene.json"
    if kind == "fifo":
        os.mkfifo(path)  # File > Open must not block on it
    elif kind == "folder":
        path.mkdir()
    else:  # 12,001 grid points per side: gigabytes to draw
        path.write_text('{"format": "rollball-scene", "version": 2, "landscape": "x", "view": {"step": 0.0005}}')
    scene = window.scene
    assert not window.files.open_scene(path)
    words = {"fifo": "is a named pipe", "grid": "view.step: 12,001 grid points", "folder": "is a folder"}[kind]
    assert dialogs[-1][:2] == ("warning", "Cannot open scene") and words in dialogs[-1][2]
    assert window.scene == scene and not window.isWindowModified()
    assert "Traceback" not in capfd.readouterr().err


def test_markup_in_a_file_is_shown_as_text(qtbot, window, dialogs, tmp_path):
    path = tmp_path / "scene.json"
    path.write_text('{"format": "rollball-scene", "version": 2, "landscape": "x", "<b>big</b>": 1}')
    assert not window.files.open_scene(path)
    assert "<b>" not in dialogs[-1][2] and "big" in dialogs[-1][2]


def test_export_never_overwrites_the_open_scene(qtbot, window, dialogs, tmp_path):
    path = tmp_path / "mine.json"
    assert window.files.save_to(path)
    text = path.read_text()
    run_to_end(qtbot, window)
    assert not window.exports.export_csv(path)
    assert "scene being run" in dialogs[-1][2] and path.read_text() == text
