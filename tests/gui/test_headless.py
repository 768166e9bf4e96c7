"""The headless commands and the exports: refusals in one line before anything runs, a clean
way out (no crash at exit, no temporary files after SIGTERM), pictures and videos that keep
the scale and the ball; and the compute time and compiler messages the window shows."""

import glob
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import shiboken6
from PySide6 import QtCore, QtGui

from rollball_app import worker
from rollball_app.garbage import collect_on_gui_thread
from rollball_app.main import close_down
from rollball_app.picture import labels_at
from rollball_app.window import MainWindow
from rollball.examples import scene_path

from .guitools import run_to_end, set_field

DISPLAY = "-screen 0 1400x900x24 +extension GLX +render"


def _app(*args, env=None, timeout=60):
    return subprocess.run([sys.executable, "-m", "rollball_app", *args], capture_output=True, text=True,
                          timeout=timeout, env=env or os.environ)


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "s.json"
    shutil.copy(scene_path("flat"), path)
    return path


# -- refusals: one line on stderr, exit 2, before a window opens -------------------------------

@pytest.mark.parametrize("args, words", [
    (["{scene}", "--screenshot", ""], "empty file name"),
    (["{scene}", "--record", ""], ".mp4 or .gif"),
    (["{scene}", "--screenshot", "{scene}"], "is the scene being run"),
    (["{scene}", "--record", "{tmp}"], ".mp4 or .gif"),
    (["{scene}", "--screenshot", "{tmp}"], "is a folder"),
    (["{notjson}", "--record", "{tmp}/a.mp4"], "notjson.json"),
    (["{notjson}", "--screenshot", "{tmp}/a.png"], "notjson.json"),
    (["{scene}", "--record", "{tmp}/a.mp4", "--fps", "0.001"], "--fps: from 1 to 120"),
    (["{scene}", "--record", "{tmp}/a.mp4", "--fps", "500"], "--fps: from 1 to 120"),
    (["{scene}", "--record", "{tmp}/a.mp4", "--size", "16x16"], "from 320x240 to 7680x4320"),
    (["{scene}", "--screenshot", "{tmp}/a.png", "--size", "9000x9000"], "from 320x240 to 7680x4320"),
    (["{scene}", "--record", "{tmp}/missing/a.mp4"], "no such folder"),
])
def test_a_headless_command_that_cannot_be_done_is_refused_in_one_line_before_it_runs(tmp_path, scene_file,
                                                                                       args, words):
    notjson = tmp_path / "notjson.json"
    notjson.write_text("this is not json")
    before = scene_file.read_bytes()
    names = {"scene": str(scene_file), "notjson": str(notjson), "tmp": str(tmp_path)}
    started = time.monotonic()
    result = _app(*(a.format(**names) for a in args))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0] and lines[0].startswith("rollball-app: error:"), result.stderr
    assert time.monotonic() - started < 30   # no dialog waited on, no run
    assert scene_file.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notjson.json", "s.json"]


# -- a clean way out ------------------------------------------------------------------------

def test_record_of_a_run_that_leaves_the_grid_exits_0_with_every_frame(tmp_path):
    out = tmp_path / "liftoff.mp4"
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), HOME=str(tmp_path))
    result = _app("liftoff", "--run-to", "2", "--record", str(out), "--fps", "10", "--size", "320x240",
                  env=env, timeout=300)
    assert result.returncode == 0, result.stderr   # was SIGSEGV (-11) at exit, most often with small sizes
    assert "Traceback" not in result.stderr and "Exported 21 frames" in result.stdout
    assert not (tmp_path / "RollBall").exists()    # the user's preferences are not touched


def test_sigterm_during_record_removes_its_temporary_files_and_writes_nothing(tmp_path):
    out = tmp_path / "long.mp4"
    staging = tmp_path / "tmp"
    staging.mkdir()
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), HOME=str(tmp_path), TMPDIR=str(staging))
    process = subprocess.Popen([sys.executable, "-m", "rollball_app", "bump", "--run-to", "6", "--record",
                                str(out), "--fps", "60", "--size", "320x240"], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 300
        while not glob.glob(str(staging / "rollball-animation-*")):   # frames are being written
            assert process.poll() is None and time.monotonic() < deadline, process.communicate()
            time.sleep(0.05)
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 128 + signal.SIGTERM, err
    assert "stopped by SIGTERM" in err and "Traceback" not in err
    assert list(staging.iterdir()) == [] and not out.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_close_down_deletes_the_window_while_python_is_whole(qtbot, qapp, preferences):
    window = MainWindow(preferences)
    window.files.open_scene(scene_path("hills"), remember=False)
    window.show()
    qtbot.waitExposed(window)
    window.runs.start()
    qtbot.waitUntil(lambda: len(window.controller.buffer or ()) > 0, timeout=30_000)
    window.document.saved_scene = window.scene
    view, plots = window.view, window.plots
    try:
        close_down(qapp, window)
    finally:
        collect_on_gui_thread()   # as the other tests of this folder expect
    assert not any(shiboken6.isValid(o) for o in (window, view, plots))


def test_closing_while_the_integrator_is_prepared_says_nothing(qtbot, window):
    window.runs.prepare_integrator([sys.executable, "-c", "import time; print('ready euler mk', flush=True); "
                                                     "time.sleep(30)"])
    qtbot.wait(50)
    window.close()   # pytest-qt fails the test on any exception raised in a Qt callback
    assert window.runs.preparing is None
    qtbot.wait(200)


def test_an_unusable_preferences_file_is_ignored_with_a_warning(tmp_path):
    folder = tmp_path / "RollBall"
    folder.mkdir()
    os.mkfifo(folder / "RollBall.conf")   # QSettings would block on it for good
    code = ("from rollball_app.main import application; from rollball_app.window import MainWindow; "
            "app = application(); app.setOrganizationName('RollBall'); app.setApplicationName('RollBall'); "
            "w = MainWindow(); print(type(w.preferences.settings).__name__)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                            env=dict(os.environ, XDG_CONFIG_HOME=str(tmp_path)))
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["SessionSettings"]
    assert "is a named pipe (FIFO), not a regular file: ignored" in result.stderr


# -- exports keep the scale and the ball -----------------------------------------------------

def test_pictures_carry_the_axis_numbers_and_names(qtbot, window, tmp_path):
    view = window.view
    size = (4 * view.width(), 4 * view.height())   # Save Image at 4×
    placed = labels_at(view, size)
    assert {"x (m)", "y (m)"} <= {item.text for _, _, item in placed}
    with_labels = window.exports.picture(size)
    for item in view.axis_labels:
        item.setVisible(False)
    without = window.exports.picture(size)
    for item in view.axis_labels:
        item.setVisible(True)
    changed = [x for x, y, item in placed
               if any(with_labels.pixel(int(x) + dx, int(y) - dy) != without.pixel(int(x) + dx, int(y) - dy)
                      for dx in range(0, 60, 2) for dy in range(0, 40, 2)
                      if 0 <= int(x) + dx < size[0] and 0 <= int(y) - dy < size[1])]
    assert len(changed) >= 0.8 * len(placed)   # (labels beyond the frame's edge cannot show)
    path = tmp_path / "four.png"
    assert window.exports.save_image(path, scale=4)
    assert QtGui.QImage(str(path)).size() == QtCore.QSize(*size)


def test_the_axis_numbers_and_names_are_framed_with_the_landscape(qtbot, window):
    from rollball.examples import example_names

    for name in example_names():
        assert window.files.open_scene(scene_path(name), remember=False)
        w, h = window.view.width(), window.view.height()
        placed = labels_at(window.view, (w, h))
        assert any(item.text == "x (m)" for _, _, item in placed), name
        outside = [(round(x), round(y), item.text) for x, y, item in placed
                   if not (0 <= x <= w - 20 and 12 <= y <= h)]   # room for the text itself
        assert outside == [], (name, outside)


def test_an_exported_video_keeps_the_ball_in_frame_when_it_leaves_the_grid(qtbot, window, tmp_path):
    assert window.files.open_scene(scene_path("liftoff"), remember=False)
    set_field(qtbot, window, "duration", "2")
    run_to_end(qtbot, window)
    view, size = window.view, (320, 240)
    assert window.controller.buffer.rows[-1, 1] > view.bounds[1, 0] + 1   # x well beyond the grid
    spots = []

    def where(_done, _total):   # after each frame: where the ball is in it
        w, h = size[0], size[1] - 2 * 11   # the caption bar below the view
        matrix = view.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * view.viewMatrix()
        p = matrix.map(QtGui.QVector4D(*map(float, view.ball_center), 1.0))
        spots.append((p.x() / p.w(), p.y() / p.w()))
        return True
    assert window.exports.export_animation(tmp_path / "liftoff.gif", fps=10, size=size, progress=where)
    assert len(spots) == 21 and np.all(np.abs(spots) < 0.95), spots
    assert view.framed and view.bounds[1, 0] == pytest.approx(3.0, abs=0.2)   # the window's camera is back


def test_nothing_is_exported_over_the_open_scene(qtbot, window, scene_file, dialogs):
    before = scene_file.read_bytes()
    assert window.files.open_scene(scene_file)
    assert not window.exports.save_image(scene_file)
    assert "scene being run" in dialogs[-1][2]
    run_to_end(qtbot, window)
    with pytest.raises(OSError, match="scene being run"):
        window.exports.export_animation(scene_file, fps=5, size=(320, 240))
    assert scene_file.read_bytes() == before


# -- compute time, compiler messages -------------------------------------------------------------

class _Sleeper:
    """A run whose chunks take wall-clock time but no processor time (a busy machine)."""

    def __init__(self):
        self.done, self.progress, self.chunks = False, 0.0, 0

    def advance(self, _steps):
        time.sleep(0.05)
        self.chunks += 1
        self.progress = self.chunks
        self.done = self.chunks >= 4
        return np.zeros((0, 3))

    def cancel(self):
        self.done = True


def test_compute_time_is_the_runs_own_processor_time(qtbot):
    seconds = [0.0]
    thread = worker.stream_worker([_Sleeper()], [lambda rows: rows], seconds=seconds)
    started = time.perf_counter()
    thread.start()
    assert thread.wait(10)
    assert time.perf_counter() - started >= 0.2
    assert seconds[0] < 0.05   # four chunks of 0.05 s asleep: no processor time


def test_a_formula_the_compiler_refuses_says_why_in_one_clean_line(qtbot, window, monkeypatch):
    import rollball_app.inputs as inputs

    noisy = ("Failed in nopython mode pipeline (step: nopython frontend)\n\x1b[1mNo implementation of function "
             "Function(<built-in function gamma>) found for signature:\n \n >>> gamma(float64, float64)\n"
             "\x1b[0m\x1b[37m\x1b[1mDuring: typing of call at /home/u/.cache/rollball/landscape_0a1b.py (8)\x1b[0m\n"
             'File "../../.cache/rollball/landscape_0a1b.py", line 8:\x1b[0m\n')

    class Refused:
        @property
        def compiled(self):
            raise RuntimeError(noisy)
    monkeypatch.setattr(inputs, "landscape_for", lambda text, names=(): Refused())
    set_field(qtbot, window, "landscape", "x*y + 1")
    text = window.panel.formula_error.text()
    assert text.startswith("cannot compile the formula: no version of gamma takes float64, float64"), text
    assert "\x1b" not in text and "cache" not in text and "/" not in text and "\n" not in text
