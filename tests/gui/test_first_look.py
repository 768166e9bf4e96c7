"""What a user sees on opening each example, and the headless picture of it."""

import os
import subprocess
import sys

import numpy as np
import pytest
from PySide6 import QtCore, QtGui

from rollball_app.main import screenshot
from rollball import Scene
from rollball.examples import example_names, scene_path

from .guitools import run_to_end, set_field

SIZE = (1024, 700)   # a projector's screen, less the taskbar


def _projected(view, point) -> np.ndarray:
    """Where pyqtgraph's own camera matrices put a point, in view coordinates (-1 to 1)."""
    w, h = view.width(), view.height()
    matrix = view.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * view.viewMatrix()
    p = matrix.map(QtGui.QVector4D(*map(float, point), 1.0))
    return np.array([p.x() / p.w(), p.y() / p.w()])


def _view_image(view) -> np.ndarray:
    return view.image()[..., :3].astype(int)


@pytest.mark.parametrize("name", example_names())
def test_every_example_opens_in_a_picture_with_the_ball_in_view_and_in_sight(window, tmp_path, name):
    out = tmp_path / f"{name}.png"
    assert screenshot(window, scene_path(name), out, None, SIZE) is None
    image = QtGui.QImage(str(out))
    assert (image.width(), image.height()) == SIZE
    view = window.view
    corner = view.mapTo(window, view.rect().topLeft())
    pixels = {image.pixel(corner.x() + i, corner.y() + j)
              for i in range(0, view.width(), 7) for j in range(0, view.height(), 7)}
    assert len(pixels) > 50, name   # a landscape in colour, not an empty or black view

    x, y = _projected(view, view.ball_center)
    assert abs(x) < 0.95 and abs(y) < 0.95, (name, x, y)
    # in sight, not behind a wall: hiding the ball changes the picture where it is projected
    with_ball = _view_image(view)
    for item in (view.ball, view.axes, *view.axis_labels):   # labels may stand beyond the frame
        item.setVisible(False)
    without = _view_image(view)
    for item in (view.ball, view.axes, *view.axis_labels):
        item.setVisible(True)
    h, w = with_ball.shape[:2]
    col, row = int((x + 1) / 2 * w), int((1 - y) / 2 * h)
    patch = (slice(max(row - 3, 0), row + 4), slice(max(col - 3, 0), col + 4))
    assert np.abs(with_ball[patch] - without[patch]).max() > 40, name
    # the whole landscape is drawn within the view: nothing of it touches the border
    border = np.concatenate([without[0], without[-1], without[:, 0], without[:, -1]])
    assert np.abs(border - without[0, 0]).max() < 10, name


def test_the_no_fit_region_is_in_sight_on_opening(qtbot, window):
    assert window.files.open_scene(scene_path("too_big"), remember=False)
    qtbot.wait(20)
    window.view.ball.setVisible(False)   # its stripes are red too
    r, g, b = np.moveaxis(_view_image(window.view), -1, 0)
    window.view.ball.setVisible(True)
    red = (r > 90) & (r > 2 * g) & (r > 1.8 * b)
    assert red.sum() > 300   # pixels of the red strip along the valley floor


def test_heights_the_ball_cannot_reach_are_cut_away(qtbot, window):
    assert window.files.open_scene(scene_path("valley"), remember=False)
    view = window.view
    assert view.cap < 3.0   # the walls of 4 y² reach 64 m on this grid; the ball starts below 2 m
    assert view.bounds[1, 2] <= view.cap and len(view.cut_edge.pos) > 0


def _app(*args, env=None):
    return subprocess.run([sys.executable, "-m", "rollball_app", *args], capture_output=True, text=True, timeout=300,
                          env=env or os.environ)


def test_the_command_line_runs_a_scene_and_saves_the_window(tmp_path):
    out = tmp_path / "bump.png"
    result = _app("bump", "--screenshot", str(out), "--run-to", "1.0", "--size", "1024x700")
    assert result.returncode == 0, result.stderr
    image = QtGui.QImage(str(out))
    assert (image.width(), image.height()) == (1024, 700)


@pytest.mark.parametrize("args, words", [
    (["nowhere", "--screenshot", "x.png"], "no such scene file or example"),
    (["hills", "--screenshot", "/nonexistent-folder/x.png"], "cannot write"),
    (["hills", "--size", "12"], "WIDTHxHEIGHT"),
    (["hills", "--run-to", "1"], "--run-to needs --screenshot"),
])
def test_the_command_line_fails_in_one_line(tmp_path, args, words):
    result = _app(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert words in lines[-1] and "Traceback" not in result.stderr


def test_start_while_the_integrator_is_prepared_waits_visibly_then_runs(qtbot, window):
    window.runs.prepare_integrator([sys.executable, "-c", "import time; time.sleep(2)"])
    window.runs.start()
    assert window.runs.state == "ready" and "Preparing the integrator (first run only)" in window.message.text()
    assert window.progress.maximum() == 0 and window.state_label.text() == "Preparing…"   # busy
    qtbot.waitUntil(lambda: window.runs.state != "ready", timeout=20_000)
    assert window.runs.state in ("running", "finished") and window.progress.maximum() == 1000
    assert window.runs.preparing is None


def test_reset_while_waiting_for_the_integrator_cancels_the_start(qtbot, window):
    window.runs.prepare_integrator([sys.executable, "-c", "import time; time.sleep(1)"])
    window.runs.start()
    window.runs.reset()
    qtbot.waitUntil(lambda: window.runs.preparing is None, timeout=20_000)
    qtbot.wait(100)
    assert window.runs.state == "ready"


def test_a_grid_too_coarse_for_the_landscape_is_said(qtbot, window):
    set_field(qtbot, window, "view.min", "-1000")
    set_field(qtbot, window, "view.max", "1000")
    set_field(qtbot, window, "view.step", "5")
    qtbot.waitUntil(lambda: window.scene.view.step == 5)
    assert "too coarse" in window.message.text()


def test_typing_in_a_text_field_neither_fires_shortcuts_nor_resets_the_run(qtbot, window):
    window.runs.start()
    window.runs.toggle_pause()
    field = window.panel.formula
    field.setFocus()
    qtbot.keyClicks(field, " ")
    qtbot.keyClick(field, QtCore.Qt.Key.Key_F)
    qtbot.keyClick(field, QtCore.Qt.Key.Key_Backspace)
    qtbot.wait(600)   # past the fields' settling delay
    assert field.text().endswith(" ") and window.runs.state == "paused"   # typed, and the run stays
    assert not window.follow_action.isChecked()


def test_what_a_stopped_run_computed_can_be_exported(qtbot, window, tmp_path):
    window.runs.start()
    qtbot.waitUntil(lambda: len(window.controller.buffer) > 10, timeout=20_000)
    window.runs.stop()
    assert window.export_action.isEnabled() and "can be exported" in window.message.text()
    out = tmp_path / "stopped.csv"
    assert window.exports.export_csv(out)
    assert len(out.read_text().splitlines()) > 10


def test_the_last_word_of_a_run_keeps_its_lift_off(qtbot, window, tmp_path):
    assert window.files.open_scene(scene_path("cylinder"), remember=False)   # the ball flies off and lands
    run_to_end(qtbot, window)
    text = window.message.text()
    assert text.startswith("Finished") and "lift-off at t = " in text and "landing at t = " in text
    data = window.scene.to_dict()   # glued on, as in 2011: it rolls down the side until it no longer fits
    data["contact"]["after_liftoff"] = "glued"
    Scene.from_dict(data).save(tmp_path / "glued.json")
    assert window.files.open_scene(tmp_path / "glued.json", remember=False)
    run_to_end(qtbot, window)
    text = window.message.text()
    assert text.startswith("Stopped early") and "lift-off at t = " in text and "not physical" in text


def test_start_goes_as_soon_as_its_method_is_ready(qtbot, window):
    says = ("import time; print('ready euler mk', flush=True); time.sleep(0.5); "
            "print('ready rk4 mk', flush=True); time.sleep(30)")
    window.runs.prepare_integrator([sys.executable, "-c", says])
    window.runs.start()   # hills: rk4 with Munthe-Kaas
    assert window.runs.state == "ready"
    qtbot.waitUntil(lambda: window.runs.state != "ready", timeout=20_000)   # long before the process ends
    assert window.runs.preparing is not None
    window.runs.preparing.kill()
