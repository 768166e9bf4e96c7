"""The window's modes together: editing, compare, presentation, scrubbing, opening a scene, and
a restart after each — driven through the real window's actions and keys."""

import shutil
from pathlib import Path

import numpy as np
import pytest
from PySide6 import QtCore, QtWidgets

from rollball_app.compare_runs import CompareRun
from rollball_app.controller import FINISHED
from rollball_app.modes import DEFAULT_SIZE, PRESENTATION_PLOTS_LEAST, VIEW_SHARE, fitted, layout
from rollball_app.preferences import Preferences
from rollball_app.timeline import STEPS
from rollball_app.window import MainWindow
from rollball import parse_runs
from rollball.examples import EXAMPLES_DIR

from .probing import run_probe
from .guitools import FASTEST, apply_fields, set_field

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def window(window, qtbot):
    """The window, active, so its keyboard shortcuts reach it."""
    window.activateWindow()
    qtbot.waitActive(window)
    return window


@pytest.fixture
def compared(qtbot, window):
    """Compare mode with Euler, RK4 classic and RK4 Munthe-Kaas played to t = 1 s."""
    set_field(qtbot, window, "duration", "1")
    window.compare_action.trigger()   # Run → Compare Methods
    assert window.compare.active
    window.compare.enter([CompareRun.of(spec, window.scene)
                          for spec in parse_runs("euler/classic,rk4/classic,rk4")])
    window.speed.setCurrentIndex(FASTEST)
    with qtbot.waitSignal(window.controller.measured, timeout=60_000):
        window.runs.start()
        qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=60_000)
    return window


def restarted(qtbot, window, preferences) -> MainWindow:
    """Quit (as the window is) and start again with the same preferences."""
    window.document.saved_scene = window.scene
    window.close()
    again = MainWindow(Preferences(QtCore.QSettings(preferences.settings.fileName(),
                                                    QtCore.QSettings.Format.IniFormat)))
    qtbot.addWidget(again)
    again.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    again.show()
    qtbot.waitExposed(again)
    return again


def editing_layout(window) -> bool:
    return (window.scene_dock.isVisible() and window.scene_panel_action.isChecked()
            and window.scene_panel_action.isEnabled() and not window.compare.dock.isVisible()
            and not window.compare.active and not window.presentation.active and not window.isFullScreen()
            and window.bottom.currentWidget() is window.plots)


def test_the_layouts_of_the_modes():
    editing = layout(compare=False, presentation=False)
    assert editing.scene_panel and not editing.compare_panel and not editing.full_screen
    assert not layout(False, False, scene_wanted=False).scene_panel
    compare = layout(compare=True, presentation=False, scene_wanted=False)
    assert compare.scene_panel and compare.compare_panel and compare.error_plots   # the Scene tab stays
    for on in (False, True):
        shown = layout(compare=on, presentation=True)
        assert shown.full_screen and shown.closeup and shown.presentation_bar
        assert not shown.scene_panel and not shown.compare_panel and shown.error_plots == on


def test_the_scene_panel_comes_back_after_compare_and_after_a_restart(qtbot, window, preferences):
    ctrl_k = (QtCore.Qt.Key.Key_K, QtCore.Qt.KeyboardModifier.ControlModifier)
    window.activateWindow()   # a shortcut reaches the active window only (another test's may have been)
    qtbot.waitUntil(window.isActiveWindow, timeout=10_000)
    qtbot.keyClick(window, *ctrl_k)
    qtbot.waitUntil(window.compare.dock.isVisible, timeout=10_000)
    assert window.bottom.currentWidget() is window.compare.error_plots
    qtbot.keyClick(window, *ctrl_k)
    assert editing_layout(window)
    qtbot.keyClick(window, *ctrl_k)   # and quit while comparing
    again = restarted(qtbot, window, preferences)
    assert editing_layout(again)
    # a layout saved with the Scene panel hidden (as older versions could) does not hide it
    again.scene_panel_action.trigger()
    assert not again.scene_dock.isVisible()
    preferences.settings.setValue("windowState", again.saveState())
    preferences.settings.sync()
    third = restarted(qtbot, again, preferences)
    assert editing_layout(third)
    third.document.saved_scene = third.scene
    third.close()


def test_reset_layout_brings_every_panel_back(qtbot, window):
    size = window.size()
    window.scene_panel_action.trigger()
    window.scene_dock.setFloating(True)
    window.resize(700, 650)
    window.reset_layout_action.trigger()
    assert editing_layout(window) and not window.scene_dock.isFloating()
    assert window.size() == size   # the default size (as fitted to this screen)
    in_menus = window._all_actions()
    assert window.reset_layout_action in in_menus and window.scene_panel_action in in_menus   # View menu


def test_presentation_saved_is_not_the_normal_layout(qtbot, window, preferences):
    geometry = window.geometry()
    qtbot.keyClick(window, QtCore.Qt.Key.Key_F11)
    assert window.presentation.active and window.isFullScreen()
    again = restarted(qtbot, window, preferences)   # quit in presentation
    assert editing_layout(again) and again.size() == geometry.size()
    again.document.saved_scene = again.scene
    again.close()


def test_compare_and_presentation_and_back(qtbot, compared, preferences):
    w = compared
    sizes, geometry = w.splitter.sizes(), w.geometry()
    tick = w.compare.error_plots.plots["contact"].getAxis("left")
    qtbot.keyClick(w, QtCore.Qt.Key.Key_F11)
    assert w.presentation.active and w.compare.active
    assert not w.compare.dock.isVisible() and not w.scene_dock.isVisible()   # the view takes the room
    assert w.bottom.currentWidget() is w.compare.error_plots
    assert tick.style["tickFont"].pointSizeF() >= 2 * QtWidgets.QApplication.font().pointSizeF()
    assert w.closeup.isVisible() and w.closeup.color == w.controller.runs[w.compare.followed].color
    qtbot.keyClick(w, QtCore.Qt.Key.Key_Escape)
    assert not w.presentation.active and w.compare.active and w.compare.dock.isVisible()
    assert tick.style["tickFont"] is None and not w.closeup.isVisible()
    qtbot.waitUntil(lambda: w.geometry() == geometry)
    assert w.splitter.sizes() == sizes or sum(w.splitter.sizes()) != sum(sizes)
    # and presentation entered again, then quit: the next start is the editing layout
    qtbot.keyClick(w, QtCore.Qt.Key.Key_F11)
    again = restarted(qtbot, w, preferences)
    assert editing_layout(again) and again.size() == geometry.size()
    again.document.saved_scene = again.scene
    again.close()


def test_f11_and_esc_cycles_put_everything_back(qtbot, window):
    geometry, title = window.geometry(), window.windowTitle()
    for keys in ((QtCore.Qt.Key.Key_F11, QtCore.Qt.Key.Key_Escape), (QtCore.Qt.Key.Key_F11, QtCore.Qt.Key.Key_F11),
                 (QtCore.Qt.Key.Key_F11, QtCore.Qt.Key.Key_Escape)):
        # (a shortcut reaches the active window only: leaving full screen may leave the window
        # inactive for a moment on a loaded virtual display with no window manager)
        window.activateWindow()
        qtbot.waitActive(window)
        qtbot.keyClick(window, keys[0])
        assert window.presentation.active and window.leave_action.isEnabled()
        qtbot.keyClick(window, keys[1])
        assert not window.presentation.active and not window.leave_action.isEnabled()
        qtbot.waitUntil(lambda: window.geometry() == geometry)
        assert editing_layout(window) and window.windowTitle() == title


def test_scrubbing_in_compare_mode_moves_the_slider_and_says_one_time(qtbot, compared):
    w = compared
    assert w.timeline.slider.isEnabled() and w.timeline.t_end == 1.0
    w.runs.seek(0.5)
    assert abs(w.timeline.slider.value() - STEPS // 2) <= 1
    label = w.timeline.label.text()
    assert label.endswith(" s / 1 s")
    shown = label.split(" s / ")[0]
    assert w.readouts.rows[0]["t"].text() == f"{shown} s"   # the slider and the readout: one time
    qtbot.keyClick(w, QtCore.Qt.Key.Key_Right)   # a frame later, by key
    assert w.timeline.slider.value() > STEPS // 2
    assert w.readouts.rows[0]["t"].text() == w.timeline.label.text().split(" / ")[0]
    # the slider itself: a click halfway sets the time there
    slider = w.timeline.slider
    qtbot.mouseClick(slider, QtCore.Qt.MouseButton.LeftButton, pos=QtCore.QPoint(slider._x(STEPS // 4),
                                                                                  slider.height() // 2))
    assert abs(w.controller.play_time - 0.25) < 0.02


def test_one_time_on_screen_when_rows_are_sparse(qtbot, window):
    set_field(qtbot, window, "duration", "2")
    window.panel.record_every.setValue(40)   # rows every 0.04 s: the played time falls between them
    window.speed.setCurrentIndex(FASTEST)
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=30_000)
    window.runs.seek(1.23)
    readout = window.readouts["t"].text()
    assert window.timeline.label.text() == f"{readout} / 2 s" and readout != "1.2300 s"


def test_opening_another_scene_in_compare_mode_drops_the_old_results(qtbot, compared):
    w = compared
    assert w.compare.summary.columnCount() == 3
    assert w.files.open_scene(EXAMPLES_DIR / "bowl.json", remember=False)
    assert w.compare.active and w.compare.dock.isVisible() and len(w.compare.panel.rows) == 3
    assert w.compare.summary.columnCount() == 0 and w.compare.error_plots.curves == []
    assert not w.controller.runs and not w.timeline.slider.isEnabled()
    assert len(w.view.balls) == 1
    w.runs.start()   # and a comparison on the new scene fills them again
    qtbot.waitUntil(lambda: w.controller.state == FINISHED, timeout=60_000)
    assert w.compare.summary.columnCount() == 3


def test_the_followed_ball_is_solid_and_the_others_ghosts(qtbot, compared):
    w = compared
    def alphas():
        return [float(ball.opts["meshdata"].faceColors()[:, 3].min()) for ball in w.view.balls]
    assert w.compare.followed == 0 and alphas()[0] == 1.0 and max(alphas()[1:]) < 1.0   # Euler solid
    assert w.view.balls[0].depthValue() < min(ball.depthValue() for ball in w.view.balls[1:])   # drawn first
    w.compare.panel.follow.setCurrentIndex(2)
    qtbot.waitUntil(lambda: alphas()[2] == 1.0)
    assert max(alphas()[:2]) < 1.0
    w.closeup_action.trigger()
    w.runs.seek(0.5)
    assert w.closeup.color == w.controller.runs[2].color   # the close-up in the followed run's colours


@pytest.mark.skipif(not (shutil.which("xvfb-run") and shutil.which("openbox")),
                    reason="needs xvfb-run and openbox (a window manager for full screen)")
@pytest.mark.parametrize("screen", ["1024x768", "1920x1080"])
def test_on_a_projector_screen_every_mode_fits_and_cycles_back(tmp_path, screen):
    """The real app under a window manager on a screen of that size: the window, presentation
    and compare in presentation fit it with every control inside; F11/Esc cycles put the window
    back exactly; quitting while comparing restarts in the editing layout."""
    quick = "" if screen == "1024x768" else "quick"   # the cycles once, on the small screen
    report = run_probe("probe_modes", screen, str(tmp_path / "preferences.ini"), quick, timeout=300)
    width, height = map(int, screen.split("x"))
    start = report["start"]
    assert not start["outside"] and start["geometry"][2] <= width and start["scene_panel"]
    for name in ("presentation", "cycle1", "cycle3", "compare_presentation"):
        if name not in report:
            continue
        state = report[name]
        assert state["full_screen"] and state["geometry"] == [0, 0, width, height], (name, state)
        assert state["minimum"][0] <= width and state["minimum"][1] <= height, (name, state)
        assert not state["outside"] and not state["scene_panel"] and not state["compare_panel"], (name, state)
    for name in ("left", "cycle2", "cycle4", "compare", "compare_left", "restart"):
        if name not in report:
            continue
        state = report[name]
        assert state["geometry"] == start["geometry"] and not state["full_screen"], (name, state)
        assert not state["outside"] and state["title"] == start["title"] and state["scene_panel"], (name, state)
    assert quick or "cycle4" in report
    assert report["compare_left"]["compare_panel"] and not report["restart"]["compare_panel"]
    assert not report["restart"]["compare"]
    assert report["error_plot_font"] >= 1.5 * 9
    # compare in presentation: the 3-D view keeps its share of the screen; the error plots keep their
    # least, or are folded away (View → Plots unfolds them)
    both = report["compare_presentation"]
    assert both["view_height"] >= VIEW_SHARE * height, both
    assert both["plots_height"] == 0 or both["plots_height"] >= PRESENTATION_PLOTS_LEAST, both


def test_help_explains_comparing_methods_honestly(qtbot, window):
    window.compare_help_action.trigger()
    text = " ".join(window.help_window.browser.toPlainText().split())
    for words in ("Compare mode (Run → Compare Methods, Ctrl+K)", "reference run", "true error",
                  "Speed against error", "Sweeps (Analysis → Sweep…)", "Gauss4", "Gauss6", "DOPRI5", "DOP853",
                  "ghosts", "The energy error is not the error"):
        assert words in text, words
    window.model_help_action.trigger()
    model = " ".join(window.help_window.browser.toPlainText().split())
    assert "tells you how far the computed run is from the true one" not in model
    assert "It is not a measure of how far the run is from the true one" in model
    assert "Gauss4" in model and "DOP853" in model
    assert "F1: Help → Comparing methods" in window.compare.summary.toolTip()


def test_an_energy_gain_is_drawn_apart_from_a_loss(qtbot, window):
    set_field(qtbot, window, "duration", "3")
    set_field(qtbot, window, "integrator.dt", "0.01")
    window.panel.methods.buttons()[0].click()   # Euler: its energy grows
    apply_fields(qtbot, window)
    assert window.scene.integrator.method == "euler"
    window.speed.setCurrentIndex(FASTEST)
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=30_000)
    window.runs.seek(float("inf"))
    window.drawing.plot()
    t, gain = window.plots.curves["energy_gain"].getOriginalDataset()
    drift = window.controller.runs[0].buffer.energy_error
    assert np.isfinite(gain).sum() > 0 and (drift > 0).any()
    assert np.all(np.isnan(gain) | (gain > 0))


def test_the_default_size_fits_the_screen_and_secondary_windows_stay_on_it(qtbot, window):
    small = QtCore.QRect(0, 0, 1024, 768)
    assert fitted(DEFAULT_SIZE, small) == QtCore.QSize(1016, 728)
    assert fitted(DEFAULT_SIZE, QtCore.QRect(0, 0, 1920, 1080)) == QtCore.QSize(*DEFAULT_SIZE)
    area = window.screen().availableGeometry()
    window.move(area.right() - 200, area.bottom() - 150)   # the main window mostly off to a corner
    window.compare_help_action.trigger()
    help_window = window.help_window
    qtbot.waitExposed(help_window)
    assert area.contains(help_window.frameGeometry()), (help_window.frameGeometry(), area)
