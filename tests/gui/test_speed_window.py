"""Analysis → Speed against error: a quick comparison in the background, its plots, its export,
and a clicked point loaded into the main window."""

import csv
import json

import numpy as np
import pyqtgraph as pg
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from rollball_app.controller import RUNNING
from rollball_app.speed_window import CSV_NAME, LEGEND_CORNERS, SpeedWindow, legend_cover, place_legend
from rollball import Scene
from rollball.comparison import Comparison, Reference, RunResult, RunSpec
from rollball.examples import EXAMPLES_DIR
from rollball.trajectory import Status

from .guitools import assert_legible, exponent, label_rects, set_field


def scatter(plot) -> pg.ScatterPlotItem:
    return next(item for item in plot.items() if isinstance(item, pg.ScatterPlotItem))


def test_a_quick_comparison_is_plotted_exported_and_loaded(qtbot, window, tmp_path):
    set_field(qtbot, window, "duration", "0.5")
    window.show_speed_against_error()
    speed = window.speed_window
    qtbot.waitUntil(lambda: speed.comparison is not None and speed.thread is None, timeout=60_000)
    comparison = speed.comparison
    names = [label.text for _, label in speed.time_plot.plotItem.legend.items]
    assert names == [spec.label for spec in comparison.specs]
    orders = [label.text for _, label in speed.step_plot.plotItem.legend.items]
    # an order wherever one was measured (gauss6 reaches the reference's floor in two steps)
    measured = {o.spec.label: o.orientation is not None for o in comparison.orders}
    assert orders and all((": order " in name) == measured[name.split(":")[0]] for name in orders)
    assert sum(measured.values()) >= 6
    rk4 = next(o for o in comparison.orders if str(o.spec) == "rk4")
    assert f"RK4 Munthe-Kaas: order {rk4.orientation:.2f}" in orders
    assert speed.status.text() == comparison.summary() and speed.export_button.isEnabled()
    for plot in (speed.time_plot, speed.step_plot):  # each legend hides none of the lines
        assert legend_cover(plot) == 0

    assert speed.export(tmp_path)
    data = json.loads((tmp_path / "compare.json").read_text())
    assert data["format"] == "rollball-compare" and data == json.loads(json.dumps(comparison.to_dict()))
    assert (tmp_path / "compare.png").read_bytes().startswith(b"\x89PNG") and (tmp_path / "compare.md").exists()
    with open(tmp_path / CSV_NAME, newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == len(data["runs"])
    # an error below the reference's accuracy is no number in either (empty in the CSV, null in the JSON)
    assert [float(row["error_contact"]) if row["error_contact"] else None for row in rows] == \
        [run["error"]["contact"] for run in data["runs"]]

    # the mouse on a point: its tooltip names a run, and a click loads exactly that run
    plot = speed.step_plot
    spot = scatter(plot).points()[-1]
    at = plot.mapFromScene(plot.plotItem.vb.mapViewToScene(spot.pos()))
    move = QtGui.QMouseEvent(QtCore.QEvent.Type.MouseMove, QtCore.QPointF(at),
                             QtCore.QPointF(plot.viewport().mapToGlobal(at)), QtCore.Qt.MouseButton.NoButton,
                             QtCore.Qt.MouseButton.NoButton, QtCore.Qt.KeyboardModifier.NoModifier)
    QtWidgets.QApplication.sendEvent(plot.viewport(), move)   # the mouse comes to rest on the point
    qtbot.waitUntil(lambda: "click: load it" in plot.toolTip())
    named = plot.toolTip().splitlines()[0]   # e.g. "RK4 Munthe-Kaas, h = 0.05 s"
    result = speed.run_at(plot, plot.mapToScene(at))
    assert named == plot.toolTip().splitlines()[0] and result is not None
    qtbot.mouseClick(plot.viewport(), QtCore.Qt.MouseButton.LeftButton, pos=at)
    integrator = window.scene.integrator
    assert (integrator.method, integrator.munthe_kaas) == (result.spec.method, result.spec.munthe_kaas)
    assert (integrator.dt if result.dt is not None else integrator.rtol) == (result.dt or result.rtol)
    assert named.startswith(result.spec.label + ", ")
    assert window.controller.state == RUNNING and not window.compare.active


def test_a_comparison_can_be_cancelled(qtbot, window):
    window.show_speed_against_error()
    speed = window.speed_window
    qtbot.waitUntil(lambda: speed.progress.maximum() > 1 or speed.thread is None, timeout=30_000)
    speed.cancel()
    qtbot.waitUntil(lambda: speed.thread is None, timeout=30_000)
    assert speed.status.text() == "Cancelled" and speed.comparison is None
    assert speed.run_button.isEnabled() and not speed.export_button.isEnabled()


def made_up(times: tuple[float, float], errors: tuple[float, float], steps: tuple[float, float]) -> Comparison:
    """A comparison whose runs' compute times, errors and steps span the given decades (log10)."""
    reference = Reference("dop853", 1e-12, 1e-15, 1e-16, {"contact": 1e-16, "orientation": 1e-16},
                          Status.OK, "", 100, 1.0)
    comparison = Comparison(Scene.load(EXAMPLES_DIR / "hills.json"), 1.0, 0.01, True, "test", reference)
    for shift, spec in enumerate((RunSpec("rk4"), RunSpec("rk4", munthe_kaas=False), RunSpec("dopri5"))):
        for t, e, h in zip(*(np.linspace(low, high, 5) for low, high in (times, errors, steps))):
            error = 10.0 ** (e - 0.1 * shift)
            comparison.runs.append(RunResult(spec, 10.0 ** h if spec.fixed_step else None,
                                             None if spec.fixed_step else 1e-6, None, Status.OK, 10, 0, 40,
                                             10.0 ** t, {"contact": error, "orientation": error}, False))
    return comparison


def inside(plot, axis) -> bool:
    """The axis' labels lie wholly in the plot's widget (none cut off at its edge)."""
    view = plot.sceneRect().adjusted(-0.5, -0.5, 0.5, 0.5)
    return all(view.contains(axis.mapRectToScene(rect)) for rect, _ in label_rects(axis))


# (compute times, errors, step sizes) in decades: within one, one or two, many
SPANS = [((-3.3, -3.1), (-9.2, -8.9), (-2.2, -2.1)), ((-2.5, -0.7), (-9, -7.3), (-3, -1.5)),
         ((-4, 1.2), (-14.5, -0.5), (-5, -1)), ((0.1, 0.3), (-1.85, 0.8), (-0.9, -0.2))]


@pytest.mark.parametrize("size", [(1100, 560), (700, 400)])
def test_both_panels_label_both_axes_at_powers_of_ten_that_never_overlap(qtbot, size):
    speed = SpeedWindow()
    qtbot.addWidget(speed)
    speed.resize(*size)
    speed.show()
    qtbot.waitExposed(speed)
    for times, errors, steps in SPANS:
        speed.show_comparison(made_up(times, errors, steps))
        qtbot.wait(1)   # laid out
        # the step panel: the fixed-step runs only, 0.1 decade apart (the time panel: 0.2 with dopri5)
        for plot, x, lowest in ((speed.time_plot, times, errors[0] - 0.2), (speed.step_plot, steps, errors[0] - 0.1)):
            for side, span in (("bottom", x), ("left", (lowest, errors[1]))):
                shown = assert_legible(qtbot, plot.getAxis(side))
                assert inside(plot, plot.getAxis(side)), (side, span)
                low, high = plot.viewRange()[side == "left"]
                assert low <= exponent(shown[0]) < exponent(shown[-1]) <= high
                assert (low, high) == (np.floor(span[0]), max(np.ceil(span[1]), np.floor(span[0]) + 1))


def test_the_legend_takes_the_corner_that_hides_the_least(qtbot):
    """Lines filling the bottom left push the legend to another corner; the first corner is kept
    while it hides nothing."""
    speed = SpeedWindow()
    qtbot.addWidget(speed)
    speed.resize(900, 500)
    speed.show()
    plot = speed.time_plot
    plot.plot([1e-5, 1e-1], [1e-1, 1e-12], name="falling")
    plot.plot([1e-5, 1e-2], [1e-12, 1e-12], name="along the bottom")
    plot.setRange(xRange=(-5, 0), yRange=(-13, 0), padding=0.0)
    plot.plotItem.legend.anchor(*LEGEND_CORNERS[0])
    assert legend_cover(plot) > 0
    place_legend(plot)
    assert legend_cover(plot) == 0
    assert plot.plotItem.legend.pos().x() > plot.getViewBox().width() / 2   # moved to the right
    plot.clear()
    plot.plotItem.legend.clear()
    plot.plot([1e-1, 1], [1e-1, 1e-3], name="top right")
    place_legend(plot)
    assert legend_cover(plot) == 0 and plot.plotItem.legend.pos().x() < plot.getViewBox().width() / 2
