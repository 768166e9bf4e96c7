"""Drive the real window through its modes on a screen of a given size, under a window manager,
and print what was measured as JSON (run by ``test_modes.py`` under ``xvfb-run`` and openbox).

    python -m tests.gui.probe_modes SETTINGS.ini [quick]

(``quick``: without the second F11/Esc cycles.)
"""

import json
import sys
import time

from PySide6 import QtCore, QtTest, QtWidgets

from rollball_app.main import prepare_qt

prepare_qt()
app = QtWidgets.QApplication(sys.argv[:1])

# the app's modules load after the QApplication, as when the app starts (hence E402 below)
from rollball_app.controller import FINISHED  # noqa: E402
from rollball_app.preferences import Preferences  # noqa: E402
from rollball_app.window import SPEEDS, MainWindow  # noqa: E402
from rollball.examples import EXAMPLES_DIR  # noqa: E402
from tests.gui.probing import settle, wait_until  # noqa: E402

KEY = QtCore.Qt.Key


def rect(r: QtCore.QRect) -> list[int]:
    return [r.x(), r.y(), r.width(), r.height()]


def open_window(settings: str) -> MainWindow:
    window = MainWindow(Preferences(QtCore.QSettings(settings, QtCore.QSettings.Format.IniFormat)))
    window.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    window.show()
    settle(1.0)
    window.activateWindow()
    settle(0.3)
    return window


def key(window: MainWindow, k) -> None:
    window.activateWindow()
    QtTest.QTest.keyClick(window, k)
    settle(0.8)


def outside(window: MainWindow) -> list[str]:
    """The controls that should be on screen and are not wholly inside the window (or the
    window not wholly on its screen)."""
    screen = window.screen().geometry()
    frame = window.frameGeometry() if not window.isFullScreen() else window.geometry()
    out = [] if screen.contains(frame) else [f"window {rect(frame)} beyond screen {rect(screen)}"]
    widgets = [window.view, window.timeline.slider, window.timeline.label, window.message, window.state_label,
               window.speed, window.progress]
    # (slip and dissipation: where the ball can slide or fly)
    widgets += [label for row in window.readouts.rows for label in row.values()
                if not label.isHidden()] + window.readouts.names
    if window.presentation.active:
        widgets += window.presentation.bar.findChildren(QtWidgets.QToolButton)
    if window.compare.dock.isVisible():
        widgets += [window.compare.panel.compare_button, window.compare.panel.add_button]
    if window.bottom.isVisible():   # (presentation folds them where the 3-D view would be too low)
        widgets.append(window.bottom.currentWidget())
    for widget in widgets:
        corner = widget.mapTo(window, QtCore.QPoint(0, 0))
        if not (widget.isVisible() and window.rect().contains(QtCore.QRect(corner, widget.size()))):
            out.append(widget.objectName() or type(widget).__name__)
    return out


STARTED = time.monotonic()


def state(window: MainWindow) -> dict:
    return {"at": round(time.monotonic() - STARTED, 1), "geometry": rect(window.geometry()),
            "full_screen": window.isFullScreen(),
            "title": window.windowTitle(), "presentation": window.presentation.active,
            "compare": window.compare.active, "scene_panel": window.scene_dock.isVisible(),
            "compare_panel": window.compare.dock.isVisible(), "outside": outside(window),
            "minimum": [window.minimumSizeHint().width(), window.minimumSizeHint().height()],
            "view_height": window.view.height(),
            "plots_height": window.bottom.height() if window.bottom.isVisible() else 0}


def main() -> None:
    settings = sys.argv[1]
    report = {"screen": rect(app.primaryScreen().availableGeometry())}
    window = open_window(settings)
    report["start"] = state(window)
    key(window, KEY.Key_F11)
    report["presentation"] = state(window)
    key(window, KEY.Key_Escape)
    report["left"] = state(window)
    cycles = (("cycle1", KEY.Key_F11), ("cycle2", KEY.Key_F11), ("cycle3", KEY.Key_F11), ("cycle4", KEY.Key_Escape))
    for name, k in cycles if "quick" not in sys.argv else ():
        key(window, k)
        report[name] = state(window)
    # compare, played through, then presentation and back
    window.panel.numbers["duration"].setText("0.3")
    window.panel.apply()
    window.compare_action.trigger()
    settle(0.3)
    window.speed.setCurrentIndex(len(SPEEDS) - 1)
    window.runs.start()
    wait_until(lambda: window.controller.state == FINISHED)
    settle(0.5)
    report["compare"] = state(window)
    key(window, KEY.Key_F11)
    report["compare_presentation"] = state(window)
    report["error_plot_font"] = window.compare.error_plots.plots["contact"].getAxis("left").style["tickFont"] \
        .pointSizeF() if window.compare.error_plots.plots["contact"].getAxis("left").style["tickFont"] else None
    key(window, KEY.Key_Escape)
    report["compare_left"] = state(window)
    window.document.saved_scene = window.scene
    window.close()   # while comparing
    settle(0.3)
    window = open_window(settings)
    report["restart"] = state(window)
    window.document.saved_scene = window.scene
    window.close()
    print(json.dumps(report))


if __name__ == "__main__":
    main()
