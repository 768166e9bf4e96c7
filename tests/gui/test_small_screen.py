"""The window on a projector's screen (1024×700): it fits, and in compare mode with four runs
every control and readout is on screen, whole, and the runs' names are readable."""

from PySide6 import QtCore, QtWidgets

from rollball_app.compare_runs import CompareRun
from rollball_app.controller import FINISHED
from rollball import parse_runs

from .guitools import FASTEST, set_field

SCREEN = QtCore.QSize(1024, 700)
FOUR = "euler/classic,rk4/classic,rk4,dopri5"


def _on_screen(window, widget) -> bool:
    """Shown, not scrolled away, and wholly inside the window."""
    corner = widget.mapTo(window, QtCore.QPoint(0, 0))
    inside = window.rect().contains(QtCore.QRect(corner, widget.size()))
    return widget.isVisible() and not widget.visibleRegion().isEmpty() and inside


def _whole(label: QtWidgets.QLabel) -> bool:
    return label.fontMetrics().horizontalAdvance(label.text()) <= label.contentsRect().width()


def test_the_window_fits_1024_by_700_with_its_toolbar_whole(window):
    assert window.minimumSizeHint().boundedTo(SCREEN) == window.minimumSizeHint()
    window.resize(SCREEN)
    bar = window.findChild(QtWidgets.QToolBar, "runToolbar")
    shown = [action for action in bar.actions() if action.isVisible()]   # the presentation bar: in presentation
    for widget in (*map(bar.widgetForAction, shown), window.progress, window.speed):
        if widget is not None and not isinstance(widget, QtWidgets.QToolBar):
            assert _on_screen(window, widget), widget   # not folded into the toolbar's » menu


def test_compare_mode_with_four_runs_fits_1024_by_700(qtbot, window):
    set_field(qtbot, window, "duration", "0.2")
    window.compare.enter([CompareRun.of(spec, window.scene) for spec in parse_runs(FOUR)])
    window.speed.setCurrentIndex(FASTEST)
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=60_000)
    qtbot.waitUntil(lambda: window.compare.summary.value("Max error (m)", 3) not in ("…", ""), timeout=60_000)
    hint = window.minimumSizeHint()
    assert hint.boundedTo(SCREEN) == hint, hint
    window.resize(SCREEN)
    qtbot.waitUntil(lambda: window.size() == SCREEN)
    qtbot.wait(50)

    panel = window.compare.panel
    controls = [panel.presets, panel.add_button, panel.follow, panel.compare_button, window.compare.summary]
    for row in panel.rows:
        controls += [row.swatch, row.method, row.munthe_kaas, row.setting, row.shown]
    readouts = window.readouts
    values = [label for row in readouts.rows for label in row.values() if not label.isHidden()]   # (not slip:
    assert readouts["speed"] in values and readouts["slip"] not in values    # hills is the 2011 model)
    for widget in controls + values + readouts.names + [window.view, window.timeline, window.message]:
        assert _on_screen(window, widget), widget.objectName() or widget
    assert not [label.text() for label in values if not _whole(label)]   # no value clipped
    plots = window.compare.error_plots   # every panel and the legend within the plots' view
    for item in (*plots.plots.values(), plots.legend):
        assert item.mapRectToScene(item.boundingRect()).right() <= plots.graphics.width(), item
    summary = window.compare.summary
    assert summary.horizontalScrollBar().maximum() == 0   # every run's column in sight
    for name, run in zip(readouts.names, window.controller.runs):   # shortened, never lost
        assert name.toolTip() == f"● {run.label}" and name.width() >= name.minimumSizeHint().width()
    window.resize(1280, 860)   # the default size: the names whole
    qtbot.waitUntil(lambda: not any(name.elided for name in readouts.names))
