"""Analysis → Speed against error: a quick comparison in the background, its plots, its export,
and a clicked point loaded into the main window."""

import csv
import json

import pyqtgraph as pg

from app.controller import RUNNING
from app.speed_window import CSV_NAME

from .guitools import set_field


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

    assert speed.export(tmp_path)
    data = json.loads((tmp_path / "compare.json").read_text())
    assert data["format"] == "rollball-compare" and data == json.loads(json.dumps(comparison.to_dict()))
    assert (tmp_path / "compare.png").read_bytes().startswith(b"\x89PNG") and (tmp_path / "compare.md").exists()
    with open(tmp_path / CSV_NAME, newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == len(data["runs"])
    assert [float(row["error_contact"]) for row in rows] == [run["error"]["contact"] for run in data["runs"]]

    points = scatter(speed.time_plot)
    spot = points.points()[-1]
    result = spot.data()
    assert "click: load it" in points.opts["tip"](x=0, y=0, data=result)
    points.sigClicked.emit(points, [spot], None)
    integrator = window.scene.integrator
    assert (integrator.method, integrator.munthe_kaas) == (result.spec.method, result.spec.munthe_kaas)
    assert (integrator.dt if result.dt is not None else integrator.rtol) == (result.dt or result.rtol)
    assert window.controller.state == RUNNING and not window.compare.active


def test_a_comparison_can_be_cancelled(qtbot, window):
    window.show_speed_against_error()
    speed = window.speed_window
    qtbot.waitUntil(lambda: speed.progress.maximum() > 1 or speed.thread is None, timeout=30_000)
    speed.cancel()
    qtbot.waitUntil(lambda: speed.thread is None, timeout=30_000)
    assert speed.status.text() == "Cancelled" and speed.comparison is None
    assert speed.run_button.isEnabled() and not speed.export_button.isEnabled()
