"""Drive the real window on a projector's screen under a window manager, through every text size
in editing, presentation, compare mode and both, and print what was measured as JSON (run by
``test_projector_layout.py`` under ``xvfb-run`` and openbox).

    python -m tests.gui.probe_layout SETTINGS.ini SCENE

Measured, not looked at: the window's width against the screen's, the 3-D view's height, which
labels overlap or are cut (readouts, run names, status, the plots' tick labels), the splitter's
heights before and after a compare → presentation → leave compare → Esc sequence.
"""

import json
import sys

from PySide6 import QtCore, QtGui, QtTest, QtWidgets

from rollball_app.main import prepare_qt

prepare_qt()
app = QtWidgets.QApplication(sys.argv[:1])

from rollball_app.compare_runs import CompareRun  # noqa: E402
from rollball_app.controller import FINISHED  # noqa: E402
from rollball_app.preferences import Preferences  # noqa: E402
from rollball_app.presentation import TEXT_SIZES  # noqa: E402
from rollball_app.window import SPEEDS, MainWindow  # noqa: E402
from rollball import parse_runs  # noqa: E402
from rollball.examples import EXAMPLES_DIR  # noqa: E402
from tests.gui.probing import settle, wait_until  # noqa: E402

KEY = QtCore.Qt.Key
RUNS = "rk4/classic,rk4,dopri5"   # two RK4s: names alike but for their last words


def key(window: MainWindow, k, modifiers=QtCore.Qt.KeyboardModifier.NoModifier) -> None:
    window.activateWindow()
    QtTest.QTest.keyClick(window, k, modifiers)
    settle(0.6)


def placed(window: MainWindow, widget: QtWidgets.QWidget) -> QtCore.QRect:
    return QtCore.QRect(widget.mapTo(window, QtCore.QPoint(0, 0)), widget.size())


def shown(widget: QtWidgets.QWidget) -> bool:
    return widget.isVisible() and not widget.visibleRegion().isEmpty()


def text_width(label: QtWidgets.QLabel, text: str | None = None) -> int:
    return label.fontMetrics().horizontalAdvance(label.text() if text is None else text)


def overlaps(window: MainWindow, widgets) -> list[str]:
    """Pairs of the shown widgets whose rectangles in the window intersect, as "a / b"."""
    rects = [(w.objectName() or type(w).__name__, placed(window, w)) for w in widgets if shown(w)]
    return [f"{a} / {b}" for i, (a, ra) in enumerate(rects) for b, rb in rects[i + 1:] if ra.intersects(rb)]


def tick_overlaps(plot) -> list[str]:
    """Tick labels of the plot's bottom axis drawn over one another."""
    axis = plot.getAxis("bottom")
    pixmap = QtGui.QPixmap(8, 8)
    painter = QtGui.QPainter(pixmap)
    try:
        specs = axis.generateDrawSpecs(painter)
    finally:
        painter.end()
    if not specs:
        return []
    metrics = QtGui.QFontMetricsF(axis.style["tickFont"] or QtGui.QFont())
    spans = sorted((rect.center().x() - metrics.horizontalAdvance(text) / 2,
                    rect.center().x() + metrics.horizontalAdvance(text) / 2, text) for rect, _, text in specs[2])
    return [f"{a[2]}|{b[2]}" for a, b in zip(spans, spans[1:]) if a[1] > b[0]]


def measure(window: MainWindow) -> dict:
    screen = window.screen().geometry()
    frame = window.geometry() if window.isFullScreen() else window.frameGeometry()
    readouts = window.readouts
    labels = [*readouts.titles.values(), *readouts.names, *(v for row in readouts.rows for v in row.values())]
    values = [v for row in readouts.rows for v in row.values() if shown(v)]
    names = [getattr(name, "shown_text", name.text)() for name in readouts.names if shown(name)]
    plots = window.bottom.currentWidget()
    plot_items = list(plots.plots.values()) if isinstance(plots.plots, dict) else plots.plots
    return {
        "text_size": window.presentation.preferred, "presentation": window.presentation.active,
        "compare": window.compare.active, "screen": [screen.width(), screen.height()],
        "frame": [frame.x(), frame.y(), frame.width(), frame.height()],
        "view_height": window.view.height(),
        "plots_shown": window.bottom.isVisible() and window.bottom.height() > 0, "readouts_shown": shown(readouts),
        "readouts_overlap": overlaps(window, labels),
        "values_cut": [v.text() for v in values if text_width(v) > v.contentsRect().width()],
        "names": names, "names_full": [name.text() for name in readouts.names],
        "status_overlap": overlaps(window, [window.message, window.state_label]),
        "state_cut": text_width(window.state_label) > window.state_label.contentsRect().width(),
        "ticks_overlap": [t for p in plot_items for t in tick_overlaps(p)] if window.bottom.isVisible() else [],
        "mode": readouts.rows[0]["mode"].text() if "mode" in readouts.rows[0] else None,
        "heights": {"readouts": readouts.height(), "timeline": window.timeline.height(),
                    "status": window.statusBar().height(), "toolbar": window.run_toolbar.height(),
                    "per_line": readouts.per_line},
        "splitter": window.splitter.sizes(), "slider_width": window.timeline.slider.width(),
    }


def open_window(settings: str, scene: str) -> MainWindow:
    window = MainWindow(Preferences(QtCore.QSettings(settings, QtCore.QSettings.Format.IniFormat)))
    window.files.open_scene(EXAMPLES_DIR / f"{scene}.json", remember=False)
    window.show()
    settle(1.0)
    window.activateWindow()
    settle(0.3)
    return window


def run_to_end(window: MainWindow) -> None:
    window.speed.setCurrentIndex(len(SPEEDS) - 1)
    window.runs.start()
    wait_until(lambda: window.controller.state == FINISHED)
    settle(0.5)


def text_size(window: MainWindow, scale: float) -> None:
    """View → Text Size → the size, as a click on the menu item does."""
    next(a for a in window.text_size_group.actions() if a.data() == scale).trigger()
    settle(0.3)


def settled(window: MainWindow, full_screen: bool) -> dict:
    """What is measured once the window manager has made the window full screen (or not) and
    the layout has stopped changing (a busy machine takes its time)."""
    screen = window.screen().geometry()
    wait_until(lambda: window.isFullScreen() == full_screen
               and (window.geometry() == screen) == full_screen, 20.0)
    last = None
    for _ in range(50):
        settle(0.2)
        now = (window.geometry().getRect(), window.view.height(), window.readouts.height())
        if now == last:
            break
        last = now
    return measure(window)


def every_text_size(window: MainWindow, states: list) -> None:
    for _, scale in TEXT_SIZES:
        text_size(window, scale)
        states.append(settled(window, False))
        key(window, KEY.Key_F11)
        states.append(settled(window, True))
        key(window, KEY.Key_Escape)
        settled(window, False)
    text_size(window, 1.0)


def main() -> None:
    settings, scene = sys.argv[1], sys.argv[2]
    report = {"states": []}
    window = open_window(settings, scene)
    # compare → F11 → leave compare → Esc: the editing heights back; and after View → Reset Layout
    report["splitter_editing"] = window.splitter.sizes()
    for k in (KEY.Key_K, KEY.Key_F11, KEY.Key_K, KEY.Key_Escape):
        key(window, k, QtCore.Qt.KeyboardModifier.ControlModifier if k == KEY.Key_K else
            QtCore.Qt.KeyboardModifier.NoModifier)
    settle(3.5)   # the window manager's moves after full screen have settled
    report["splitter_after"] = window.splitter.sizes()
    window.reset_layout_action.trigger()
    settle(1.0)
    report["splitter_reset"] = window.splitter.sizes()
    run_to_end(window)
    every_text_size(window, report["states"])
    # compare mode (Ctrl+K) with three runs, two of them RK4
    key(window, KEY.Key_K, QtCore.Qt.KeyboardModifier.ControlModifier)
    window.compare.enter([CompareRun.of(spec, window.scene) for spec in parse_runs(RUNS)])
    run_to_end(window)
    every_text_size(window, report["states"])
    # a restart at Large: the Scene panel reaches all of its rows
    text_size(window, 1.25)
    window.document.saved_scene = window.scene
    window.close()
    settle(0.3)
    window = open_window(settings, scene)
    scroll = window.scene_dock.widget()
    inner = scroll.widget()
    report["restart_frame"] = [window.frameGeometry().width(), window.frameGeometry().height()]
    report["panel_reachable"] = (inner.width() <= scroll.viewport().width()
                                 or scroll.horizontalScrollBar().isVisible())
    report["panel_needs"] = [inner.minimumSizeHint().width(), scroll.viewport().width()]
    window.document.saved_scene = window.scene
    window.close()
    print(json.dumps(report))


if __name__ == "__main__":
    main()
