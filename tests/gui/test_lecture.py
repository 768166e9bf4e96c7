"""Lecture tools: presentation mode, the time slider, animation export, better images, help,
scene undo and revert — driven as a lecturer drives them."""

import os
import subprocess
import sys

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from rollball_app.controller import FINISHED, PAUSED
from rollball_app.timeline import STEPS
from rollball.examples import EXAMPLES_DIR

from .guitools import run_to_end, set_field


@pytest.fixture
def window(window, qtbot):
    """The window, active, so its keyboard shortcuts reach it."""
    window.activateWindow()
    qtbot.waitActive(window)
    return window


def points(label) -> float:
    label.ensurePolished()
    return label.font().pointSizeF()


def drawn_center(window) -> np.ndarray:
    """Where the view draws the ball: the translation of its transform."""
    m = np.array(window.view.ball.transform().data()).reshape(4, 4)   # column-major
    return m[3, :3]


def test_presentation_enlarges_the_text_and_esc_restores_it(qtbot, window):
    readout, tick = window.readouts["t"], window.plots.plots[0].getAxis("bottom")
    before, status = points(readout), points(window.message)
    window.presentation_action.trigger()
    assert window.isFullScreen() and window.presentation.active
    assert points(readout) >= 2 * before and points(window.message) >= 2 * status
    assert tick.style["tickFont"].pointSizeF() >= 2 * QtWidgets.QApplication.font().pointSizeF()
    qtbot.waitUntil(window.presentation.bar.isVisible)   # the toolbar lays it out
    assert not window.scene_dock.isVisible()
    assert window.closeup_frame.isVisible()
    assert window.view.trail.width >= 6
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Escape)
    assert not window.presentation.active and not window.isFullScreen()
    assert points(readout) == before and points(window.message) == status
    assert tick.style["tickFont"] is None
    assert window.scene_dock.isVisible() and not window.closeup_frame.isVisible()


def test_text_size_is_a_preference(qtbot, window, preferences):
    before = points(window.readouts["t"])
    larger = next(a for a in window.text_size_group.actions() if a.data() == 1.5)
    larger.trigger()
    assert points(window.readouts["t"]) == pytest.approx(1.5 * before)
    assert preferences.font_scale() == 1.5
    field = window.panel.numbers["duration"]
    assert field.font().pointSizeF() == pytest.approx(1.5 * QtWidgets.QApplication.font().pointSizeF())
    assert window.view.axis_labels[0].font.pointSizeF() == pytest.approx(1.5 * 8)
    window.presentation_action.trigger()   # presentation doubles the preferred size: the status
    assert points(window.message) == pytest.approx(3.0 * before)
    # and the readouts as far as the screen's width holds all of them (3 × is too wide here)
    assert 2.0 * before < points(window.readouts["t"]) <= 3.0 * before
    screen = window.screen().availableGeometry().width()
    assert window.readouts.minimumSizeHint().width() <= screen
    window.presentation_action.trigger()
    assert points(window.readouts["t"]) == pytest.approx(1.5 * before)


def test_the_slider_shows_a_chosen_time(qtbot, window):
    set_field(qtbot, window, "duration", "2")
    run_to_end(qtbot, window)
    trajectory = window.controller.simulation.trajectory()
    window.timeline.slider.setValue(round(0.37 * STEPS))   # as a drag leaves it (the run is 2 s)
    t = window.controller.play_time
    assert t == pytest.approx(0.74) and window.controller.state == PAUSED
    i = np.searchsorted(trajectory.t, t, side="right") - 1
    # a float32 transform; a row apart is ~1e-3 m
    np.testing.assert_allclose(drawn_center(window), trajectory.center[i], rtol=0, atol=1e-6)
    assert window.readouts["t"].text() == f"{trajectory.t[i]:.4f} s"
    assert all(cursor.value() == trajectory.t[i] for cursor in window.plots.cursors)
    window.speed.setCurrentIndex(window.speed.findText("Real time"))
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Right)             # a frame (16 ms at real time) on
    assert window.controller.play_time == pytest.approx(t + 0.016)
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Left)
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Left)
    assert window.controller.play_time == pytest.approx(t - 0.016)
    qtbot.keyClick(window, QtCore.Qt.Key.Key_End)
    assert window.controller.play_time == 2.0
    # a float32 transform; a row apart is ~1e-3 m
    np.testing.assert_allclose(drawn_center(window), trajectory.center[-1], rtol=0, atol=1e-6)
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Home)
    assert window.controller.play_time == 0.0
    window.runs.toggle_pause()                                       # replay from here
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=10_000)


def test_lift_off_is_a_marker_to_jump_to(qtbot, window):
    window.files.open_scene(EXAMPLES_DIR / "liftoff.json", remember=False)
    run_to_end(qtbot, window)
    liftoff = window.controller.simulation.liftoff_time
    (position, marker), (_, landing) = window.timeline.slider.markers   # the ball flies, and lands
    assert marker.time == liftoff and position == round(STEPS * liftoff / window.controller.t_end)
    assert "landing" in landing.text and landing.time > liftoff
    assert "lift-off" in window.timeline.events.text()
    window.timeline.events.linkActivated.emit(repr(liftoff))     # the link beside the slider
    assert window.controller.play_time == liftoff
    window.runs.seek(0.0)
    window.liftoff_action.trigger()                             # and the key L
    assert window.controller.play_time == liftoff


def frames_of(path) -> np.ndarray:
    if path.suffix == ".gif":
        return iio.imread(path, index=None)[..., :3]
    reader = imageio_ffmpeg.read_frames(str(path))
    width, height = next(reader)["size"]
    return np.stack([np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in reader])


@pytest.mark.parametrize("suffix", [".mp4", ".gif"])
def test_exported_animation_has_every_frame_and_the_ball_moves(qtbot, window, tmp_path, suffix):
    set_field(qtbot, window, "duration", "1")
    run_to_end(qtbot, window)
    window.runs.seek(0.6)
    path = tmp_path / f"run{suffix}"
    assert window.exports.export_animation(path, fps=10, t0=0.2, t1=0.9, size=(200, 150), caption=False)
    frames = frames_of(path)
    assert frames.shape == (8, 150, 200, 3)                      # 0.2, 0.3, ..., 0.9 s
    moved = np.argwhere(np.abs(frames[-1].astype(int) - frames[0]).sum(axis=2) > 100)
    assert len(moved) > 15                                       # the ball (and its trail) moved ...
    assert np.all(np.ptp(moved, axis=0) < 100)                   # ... and only they changed
    assert window.controller.play_time == 0.6                    # the shown moment is back
    assert list(tmp_path.iterdir()) == [path]


def test_a_cancelled_export_writes_nothing(qtbot, window, tmp_path):
    set_field(qtbot, window, "duration", "0.5")
    run_to_end(qtbot, window)
    path = tmp_path / "keep.gif"
    path.write_bytes(b"old")
    assert not window.exports.export_animation(path, fps=10, size=(64, 48), progress=lambda done, total: done < 3)
    assert path.read_bytes() == b"old" and list(tmp_path.iterdir()) == [path]
    with pytest.raises(ValueError, match=".mp4 or .gif"):
        window.exports.export_animation(tmp_path / "run.avi", fps=10, size=(64, 48))


def test_image_at_twice_the_size_with_caption_and_plots(qtbot, window, tmp_path):
    set_field(qtbot, window, "duration", "0.5")
    run_to_end(qtbot, window)
    assert window.exports.suggest(".png").name == "hills-t0.50s.png"
    path = tmp_path / "slide.png"
    assert window.exports.save_image(path, scale=2, caption=True, plots=True)
    image = QtGui.QImage(str(path))
    assert image.width() == 2 * window.view.width()
    assert image.height() > 2 * window.view.height() + window.plots.height()


def test_undo_restores_a_changed_field_and_revert_goes_back_to_the_file(qtbot, window):
    saved = window.scene
    set_field(qtbot, window, "ball.radius", "0.25")
    set_field(qtbot, window, "start.x", "0.5")
    assert window.undo_action.text() == "&Undo Change start x"
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Z, QtCore.Qt.KeyboardModifier.ControlModifier)
    assert window.scene.start.x == saved.start.x and window.panel.numbers["start.x"].text() == "0.3"
    assert window.scene.ball.radius == 0.25
    window.undo_action.trigger()
    assert window.scene == saved and not window.isWindowModified()
    qtbot.keyClick(window, QtCore.Qt.Key.Key_Z,
                   QtCore.Qt.KeyboardModifier.ControlModifier | QtCore.Qt.KeyboardModifier.ShiftModifier)
    assert window.scene.ball.radius == 0.25 and window.panel.numbers["ball.radius"].text() == "0.25"
    assert window.revert_action.isEnabled()
    window.revert_action.trigger()
    assert window.scene == saved and not window.revert_action.isEnabled()
    window.undo_action.trigger()                                  # a revert is undone like any change
    assert window.scene.ball.radius == 0.25


def test_help_pages_teach_and_the_shortcuts_page_lists_every_shortcut(qtbot, window):
    window.model_help_action.trigger()
    browser = window.help_window.browser
    text = browser.toPlainText()
    for words in ("T(α) = m r²", "α′ = r E−1 C′T (ω × N)", "Lift-off", "Does not fit", "Munthe-Kaas"):
        assert words in text
    window.keys_help_action.trigger()
    keys = browser.toPlainText()
    for action in (window.undo_action, window.presentation_action, window.animation_action, window.back_action,
                   window.leave_action):
        assert action.shortcut().toString(QtGui.QKeySequence.SequenceFormat.NativeText) in keys
        assert action.text().replace("&", "").rstrip("…") in keys
    window.plots_help_action.trigger()
    assert "logarithmic" in browser.toPlainText()
    assert "F1: Help → The model" in window.readouts["force"].toolTip()
    QtGui.QCursor.setPos(window.readouts["force"].mapToGlobal(window.readouts["force"].rect().center()))
    window.context_help_action.trigger()
    assert window.help_window.page == "model.html"
    assert "lift-off" in browser.toPlainText().lower()


def test_headless_record_writes_the_video_and_exits_0(tmp_path):
    out = tmp_path / "hills.mp4"
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), HOME=str(tmp_path))
    result = subprocess.run([sys.executable, "-m", "rollball_app", "flat", "--run-to", "0.5", "--record", str(out),
                             "--fps", "20", "--size", "320x240"], env=env, capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    assert "Exported 11 frames" in result.stdout and "Traceback" not in result.stderr
    assert imageio_ffmpeg.count_frames_and_secs(str(out))[0] == 11
    bad = subprocess.run([sys.executable, "-m", "rollball_app", "--record", str(tmp_path / "x.avi")], env=env,
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and ".mp4 or .gif" in bad.stderr
    assert not (tmp_path / "x.avi").exists()


def test_arrow_and_home_keys_still_edit_text_in_a_field(qtbot, window):
    set_field(qtbot, window, "duration", "0.5")
    run_to_end(qtbot, window)
    window.runs.seek(0.25)
    edit = window.panel.formula
    edit.setFocus()
    edit.setCursorPosition(3)
    for key in (QtCore.Qt.Key.Key_Left, QtCore.Qt.Key.Key_Home, QtCore.Qt.Key.Key_End):
        qtbot.keyClick(edit, key)
    assert edit.cursorPosition() == len(edit.text())
    assert window.controller.play_time == 0.25


def test_compare_mode_records_every_ball(qtbot, window, tmp_path):
    from .test_compare import compare_to_end

    set_field(qtbot, window, "duration", "1")
    compare_to_end(qtbot, window, "euler/classic,rk4")
    path = tmp_path / "compare.gif"
    assert window.exports.export_animation(path, fps=5, size=(160, 120))
    assert frames_of(path).shape == (6, 120, 160, 3)
    assert window.exports.picture((160, 120), caption=True).height() > 120
    assert all(run.label in window.exports.caption() for run in window.controller.runs)
