"""Modes in combination, as a lecturer mixes them: an export while playing, an export in
presentation with compare mode, another scene opened while a comparison is still computing,
a scene opened in presentation while playing, a Speed against Error run loaded in compare mode."""

import numpy as np
from PySide6 import QtGui

from rollball_app.compare_runs import CompareRun
from rollball_app.controller import FINISHED, READY, RUNNING
from rollball_app.picture import inset_corner
from rollball_app.worker import Worker
from rollball import parse_runs
from rollball.examples import EXAMPLES_DIR

from .guitools import FASTEST, set_field
from .test_lecture import frames_of


def _compare(qtbot, window, runs: str = "euler/classic,rk4") -> None:
    window.compare_action.setChecked(True)
    window.compare.enter([CompareRun.of(spec, window.scene) for spec in parse_runs(runs)])


def test_an_export_during_playback_leaves_it_playing_from_where_it_was(qtbot, window, tmp_path):
    set_field(qtbot, window, "duration", "4")
    window.speed.setCurrentIndex(3)   # real time: still playing when the export is asked for
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.computed and window.controller.play_time > 0.3, timeout=30_000)
    assert window.controller.state == RUNNING
    path = tmp_path / "during.gif"
    assert window.exports.export_animation(path, fps=5, t0=0.0, t1=1.0, size=(160, 120), caption=False)
    after = window.controller.play_time
    assert frames_of(path).shape == (6, 120, 160, 3)
    assert window.controller.state == RUNNING   # playback goes on ...
    assert 0.3 < after < 1.5                    # ... from the moment it was at, not from the export's last frame
    qtbot.waitUntil(lambda: window.controller.play_time > after + 0.1, timeout=10_000)


def test_presentation_with_compare_exports_every_ball_and_the_closeup_and_stays(qtbot, window, tmp_path):
    set_field(qtbot, window, "duration", "0.5")
    _compare(qtbot, window)
    window.speed.setCurrentIndex(FASTEST)
    with qtbot.waitSignal(window.controller.measured, timeout=60_000):
        window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=60_000)
    window.presentation_action.setChecked(True)
    qtbot.waitUntil(window.isFullScreen, timeout=5_000)
    assert window.closeup.isVisible() and window.compare.active
    picture = window.exports.picture((640, 360), caption=True)
    assert picture.height() > 360
    right, top = inset_corner(window.view, window.closeup)   # where it covers no axis on screen
    w, h = round(0.3 * 640), 40
    inset = picture.copy(640 - w - 6 if right else 6, 6 if top else 360 - h - 6, w, h)   # the same corner
    assert np.std(np.array([QtGui.QColor(inset.pixel(x, y)).value() for x in range(0, inset.width(), 7)
                            for y in range(0, inset.height(), 5)])) > 5   # drawn, not blank
    path = tmp_path / "lecture.gif"
    assert window.exports.export_animation(path, fps=4, size=(160, 120))
    assert frames_of(path).shape[0] == 3
    assert window.isFullScreen() and window.presentation.active and window.compare.active
    assert not window.scene_dock.isVisible() and not window.compare.dock.isVisible()
    window.presentation_action.setChecked(False)
    qtbot.waitUntil(lambda: not window.isFullScreen(), timeout=5_000)
    assert window.compare.dock.isVisible()


def test_opening_a_scene_while_a_comparison_computes_drops_it_whole(qtbot, window):
    set_field(qtbot, window, "duration", "30")   # the reference takes a while
    _compare(qtbot, window, "euler/classic,rk4,dopri5")
    window.runs.start()
    qtbot.waitUntil(lambda: len(window.controller.buffer or ()) > 0, timeout=30_000)
    measured = []
    window.controller.measured.connect(lambda: measured.append(window.scene.landscape))
    assert window.files.open_scene(EXAMPLES_DIR / "bowl.json", remember=False)
    assert window.controller.state == READY and window.compare.active
    qtbot.waitUntil(lambda: not Worker.running, timeout=15_000)   # the old runs and reference cancelled
    assert measured == [] and window.compare.summary.columnCount() == 0
    set_field(qtbot, window, "duration", "0.3")
    window.speed.setCurrentIndex(FASTEST)
    with qtbot.waitSignal(window.controller.measured, timeout=60_000):
        window.runs.start()
    assert measured == [window.scene.landscape]   # measured once, on the new scene
    assert all(run.errors is not None for run in window.controller.runs)


def test_a_scene_opened_in_presentation_while_playing_stays_in_presentation(qtbot, window):
    set_field(qtbot, window, "duration", "4")
    window.speed.setCurrentIndex(3)
    window.runs.start()
    window.presentation_action.setChecked(True)
    qtbot.waitUntil(window.isFullScreen, timeout=5_000)
    qtbot.waitUntil(lambda: window.controller.play_time > 0.1, timeout=30_000)
    window.examples_menu.actions()[1].trigger()   # File → Examples, as the lecture goes on
    assert window.controller.state == READY
    assert window.isFullScreen() and window.presentation.active and not window.scene_dock.isVisible()
    assert window.closeup.isVisible()
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.play_time > 0.05, timeout=30_000)
    window.presentation_action.setChecked(False)
    qtbot.waitUntil(lambda: not window.isFullScreen(), timeout=5_000)
    assert window.scene_dock.isVisible() and not window.presentation.active


def test_a_run_loaded_from_speed_against_error_leaves_compare_mode(qtbot, window):
    from rollball.comparison import RunSpec

    class Chosen:   # what Speed against Error's click hands over
        spec, dt, rtol, atol = RunSpec("rk4", False), 0.01, None, None

    _compare(qtbot, window)
    window.runs.start()
    window.runs.load_run(Chosen())
    assert not window.compare.active and not window.compare.dock.isVisible()
    assert window.scene.integrator.method == "rk4" and window.scene.integrator.dt == 0.01
    assert window.controller.state == RUNNING and len(window.controller.runs) == 1
    assert window.scene_dock.isVisible() and window.bottom.currentWidget() is window.plots
