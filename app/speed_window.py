"""Analysis → Speed against error: ``rollball.compare`` on the current scene in the background,
shown as two log-log panels (error against compute time; error against step size with the
fitted orders), exported in the command line's formats. Both axes show whole decades, labelled
at powers of ten as the other log plots are. Clicking a point asks the main window
to load that method and step (``runChosen``)."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from rollball import METHODS, Scene, compare
from rollball.comparison import RunResult

from .compare_runs import COLORS
from .plots import DecadeAxis, fit_decades
from .worker import Worker

CSV_NAME = "compare.csv"
SPEC_COLORS = COLORS + ("#e377c2", "#7f7f7f", "#bcbd22", "#17becf")   # one per method, as the CLI's figure
ORIENTATION_CEILING = 10.0   # a classic R far off SO(3) would squash the rest of the step panel
# Where a panel's legend may sit (pyqtgraph's anchor: the legend's corner, the plot's, an offset
# in pixels), in order of preference: the first that hides the least of the lines is taken.
LEGEND_CORNERS = (((0, 1), (0, 1), (10, -10)), ((1, 1), (1, 1), (-10, -10)),
                  ((1, 0), (1, 0), (-10, 10)), ((0, 0), (0, 0), (10, 10)))
SAMPLES_PER_SEGMENT = 16
PICK_PIXELS = 8              # a point this near the mouse is the one its tooltip and click mean


def runs_csv(comparison) -> str:
    """One row per run of ``compare.json``'s runs, its keys as the header (errors flattened to
    ``error_contact`` and so on), numbers at full precision."""
    rows = comparison.to_dict()["runs"]
    flat = [{**{k: v for k, v in row.items() if k != "error"},
             **{f"error_{k}": v for k, v in row["error"].items()}} for row in rows]
    out = io.StringIO()
    if flat:
        writer = csv.DictWriter(out, fieldnames=list(flat[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows({k: ("" if v is None else repr(v) if isinstance(v, float) else v)
                          for k, v in row.items()} for row in flat)
    return out.getvalue()


def _tip(x, y, data) -> str:
    run = data
    setting = f"h = {run.dt:g} s" if run.dt is not None else f"rtol = {run.rtol:g}"
    return (f"{run.spec.label}, {setting}\ncontact error {run.error['contact']:.3g} m\n"
            f"orientation error {run.error['orientation']:.3g}\ncompute time {run.seconds:.3g} s\n"
            f"{run.steps:,} steps, {run.evaluations:,} evaluations\nclick: load it in the main window")


class SpeedWindow(QtWidgets.QWidget):
    """A window of its own, over the main one."""

    runChosen = QtCore.Signal(object)   # a RunResult: its spec and dt or rtol

    def __init__(self, parent=None):
        super().__init__(parent, QtCore.Qt.WindowType.Window)
        self.setWindowTitle("Speed against error — RollBall")
        self.resize(1100, 560)
        self.scene: Scene | None = None
        self.thread: Worker | None = None
        self.comparison = None
        layout = QtWidgets.QVBoxLayout(self)
        bar = QtWidgets.QHBoxLayout()
        self.quick = QtWidgets.QCheckBox("Quick", objectName="quick", checked=True)
        self.quick.setToolTip("Fewer steps and tolerances per method (about a minute)")
        self.run_button = QtWidgets.QPushButton("Compute", objectName="compute")
        self.run_button.clicked.connect(self.run)
        self.cancel_button = QtWidgets.QPushButton("Cancel", objectName="cancel", enabled=False)
        self.cancel_button.clicked.connect(self.cancel)
        self.progress = QtWidgets.QProgressBar(objectName="progress", minimum=0, maximum=1)
        self.status = QtWidgets.QLabel(objectName="status")
        self.status.setWordWrap(True)   # a long result takes a second line rather than widen the window past the screen
        self.export_button = QtWidgets.QPushButton("Export…", objectName="export", enabled=False)
        self.export_button.setToolTip(f"compare.json, compare.md, compare.png (as rollball compare "
                                      f"--out writes them) and {CSV_NAME}, into a folder")
        self.export_button.clicked.connect(self.export_dialog)
        for widget in (self.quick, self.run_button, self.cancel_button, self.progress):
            bar.addWidget(widget)
        bar.addWidget(self.status, 1)
        bar.addWidget(self.export_button)
        layout.addLayout(bar)
        plots = QtWidgets.QHBoxLayout()
        self.time_plot = self._plot("Error against compute time", "compute time", "s", "contact-point error (m)")
        self.step_plot = self._plot("Error against step size (fitted orders)", "step size h", "s",
                                    "orientation error ‖R − R_ref‖")
        plots.addWidget(self.time_plot)
        plots.addWidget(self.step_plot)
        layout.addLayout(plots, 1)

    def _plot(self, title: str, x: str, units: str, y: str) -> pg.PlotWidget:
        plot = pg.PlotWidget(background="w", axisItems={"left": DecadeAxis("left"), "bottom": DecadeAxis("bottom")})
        plot.setTitle(title, size="10pt", color="#333")
        plot.setLabel("bottom", x, units=units)
        plot.getAxis("bottom").enableAutoSIPrefix(False)
        plot.setLabel("left", y)
        plot.getAxis("left").enableAutoSIPrefix(False)
        plot.setLogMode(x=True, y=True)
        # room on the right for half the last label along the bottom (a wide one, 10⁻¹⁰)
        plot.plotItem.layout.setContentsMargins(1, 1, plot.getAxis("bottom").label_extent(-10, -10) / 2, 1)
        plot.showGrid(x=True, y=True, alpha=0.25)
        plot.addLegend(offset=(10, -10), labelTextSize="8pt", labelTextColor="#333")  # (placed: place_legend)
        # one point under the mouse, for the tooltip and the click alike (points of several
        # series can lie on each other: each series' own tooltip and click could pick two runs)
        plot.scene().sigMouseMoved.connect(lambda pos, p=plot: p.setToolTip(
            _tip(0, 0, run) if (run := self.run_at(p, pos)) is not None else ""))
        plot.scene().sigMouseClicked.connect(lambda event, p=plot: self._clicked(p, event))
        return plot

    def run_at(self, plot: pg.PlotWidget, scene_pos: QtCore.QPointF) -> RunResult | None:
        """The run whose point is nearest to ``scene_pos`` (within ``PICK_PIXELS``); of points
        on each other, the one drawn on top."""
        view = plot.plotItem.vb
        best, best_distance = None, PICK_PIXELS
        for item in plot.items():
            if not isinstance(item, pg.ScatterPlotItem) or not item.isVisible():
                continue
            for spot in item.points():
                at = view.mapViewToScene(spot.pos())
                distance = math.hypot(at.x() - scene_pos.x(), at.y() - scene_pos.y())
                if distance <= best_distance:   # later items are drawn over earlier ones
                    best, best_distance = spot.data(), distance
        return best

    def _clicked(self, plot: pg.PlotWidget, event) -> None:
        if event.button() != QtCore.Qt.MouseButton.LeftButton:
            return
        run = self.run_at(plot, event.scenePos())
        if run is not None:
            event.accept()
            self.runChosen.emit(run)

    # -- computing -------------------------------------------------------------------

    def compute(self, scene: Scene) -> None:
        """Compare every method on this scene (the window shows itself)."""
        self.scene = scene
        self.show()
        self.raise_()
        self.run()

    def run(self) -> None:
        if self.scene is None or self.thread is not None:
            return
        scene, quick = self.scene, self.quick.isChecked()
        self.thread = Worker(lambda progress, cancel: compare(scene, quick=quick, progress=progress, cancel=cancel),
                             name="speed against error")
        # to methods of this window: what the worker says after the window has gone is dropped
        self.thread.progressed.connect(self._progressed)
        self.thread.done.connect(self._done)
        self.thread.failed.connect(self._failed)
        self.thread.cancelled.connect(self._cancelled)
        self.progress.setMaximum(0)
        self.status.setText("Computing the reference…")
        self.run_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        self.thread.start()

    def cancel(self) -> None:
        if self.thread is not None:
            self.thread.cancel()

    def _progressed(self, args: tuple) -> None:
        self._progress(*args)

    def _failed(self, message: str) -> None:
        self._ended(f"Cannot compare: {message}")

    def _cancelled(self) -> None:
        self._ended("Cancelled")

    def _progress(self, done: int, total: int, text: str) -> None:
        self.progress.setMaximum(total)
        self.progress.setValue(done)
        self.status.setText(text)

    def _ended(self, text: str) -> None:
        self.thread = None   # the worker lets go of itself
        self.progress.setMaximum(1)
        self.progress.setValue(1 if self.comparison is not None else 0)
        self.status.setText(text)
        self.run_button.setEnabled(True)
        self.cancel_button.setEnabled(False)
        self.export_button.setEnabled(self.comparison is not None)

    def _done(self, comparison) -> None:
        self.comparison = comparison
        self.show_comparison(comparison)
        self._ended(comparison.summary())

    # -- drawing ---------------------------------------------------------------------

    def show_comparison(self, comparison) -> None:
        for plot in (self.time_plot, self.step_plot):
            plot.clear()
            plot.plotItem.legend.clear()
        orders = {order.spec: order for order in comparison.orders}
        for spec in comparison.specs:
            color = SPEC_COLORS[list(METHODS).index(spec.method) % len(SPEC_COLORS)]
            pen = pg.mkPen(color, width=1.5, style=QtCore.Qt.PenStyle.SolidLine if spec.munthe_kaas
                           else QtCore.Qt.PenStyle.DotLine)
            runs = [r for r in comparison.runs if r.spec == spec and r.ok]
            timed = [r for r in runs if r.error["contact"] > 0]
            self._series(self.time_plot, timed, [r.seconds for r in timed], [r.error["contact"] for r in timed],
                         pen, color, spec.label, spec.munthe_kaas)
            if spec.fixed_step:
                stepped = [r for r in runs if r.error["orientation"] > 0]
                order = orders.get(spec)
                slope = order.orientation if order is not None else None
                name = spec.label + (f": order {slope:.2f}" if slope is not None else "")
                self._series(self.step_plot, stepped, [r.dt for r in stepped],
                             [r.error["orientation"] for r in stepped], pen, color, name, spec.munthe_kaas)
        floor = pg.mkPen("#999", width=1, style=QtCore.Qt.PenStyle.DashLine)
        for plot, key in ((self.time_plot, "contact"), (self.step_plot, "orientation")):
            line = pg.InfiniteLine(pos=np.log10(comparison.reference.floor(key)), angle=0, pen=floor)
            plot.addItem(line)
        for plot, ceiling in ((self.time_plot, np.inf), (self.step_plot, ORIENTATION_CEILING)):
            lines = [item.getOriginalDataset() for item in plot.listDataItems() if isinstance(item, pg.PlotDataItem)]
            x, y = (np.concatenate(values) for values in zip(*lines)) if lines else (np.ones(1), np.ones(1))
            fit_decades(plot, x, "x")
            fit_decades(plot, np.minimum(y, ceiling), "y")
            place_legend(plot)

    def _series(self, plot, runs, x, y, pen, color, name, munthe_kaas) -> None:
        """A line per run spec and its runs as points: filled Munthe-Kaas, crosses classic."""
        if not runs:
            return
        plot.plot(x, y, pen=pen, name=name)
        # a scatter item is placed in the plot's log10 coordinates itself
        points = pg.ScatterPlotItem(x=np.log10(x), y=np.log10(y), data=runs, brush=pg.mkBrush(color),
                                    pen=None if munthe_kaas else pg.mkPen(color, width=2),
                                    symbol="o" if munthe_kaas else "x", size=8, hoverable=True, hoverSize=11,
                                    tip=None)   # the plot's tooltip names the one point picked (run_at)
        plot.addItem(points)

    # -- export ----------------------------------------------------------------------

    def export_dialog(self) -> None:
        folder = QtWidgets.QFileDialog.getExistingDirectory(self, "Export the comparison into a folder")
        if folder:
            self.export(Path(folder))

    def export(self, folder: Path) -> bool:
        """The command line's files (compare.json, compare.md, compare.png) and compare.csv."""
        if self.comparison is None:
            return False
        from rollball import comparison_report
        from rollball.files import replace_together

        try:  # the four files replaced together, or none of them
            files, _ = comparison_report.render(self.comparison)
            files[CSV_NAME] = runs_csv(self.comparison)
            replace_together(folder, files, kept_name=comparison_report.KEPT_NAME)
        except (OSError, ValueError) as error:
            message = getattr(error, "strerror", None) or str(error)
            self.status.setText(f"Cannot export to {folder}: {message}")
            QtWidgets.QMessageBox.warning(self, "Cannot export", f"{folder}: {message}")
            return False
        self.status.setText(f"Exported compare.json, compare.md, compare.png and {CSV_NAME} to {folder}")
        return True

    def closeEvent(self, event) -> None:
        self.cancel()
        super().closeEvent(event)


def line_points(plot) -> np.ndarray:
    """The plot's lines sampled along every segment, in scene coordinates (2 x n)."""
    view = plot.getViewBox()
    to_scene = view.childTransform() * view.sceneTransform()
    samples = [np.zeros((2, 0))]
    t = np.linspace(0.0, 1.0, SAMPLES_PER_SEGMENT)[:, None]
    for item in plot.listDataItems():
        x, y = item.getData()   # (in the plot's log10 coordinates)
        if x is None or len(x) == 0:
            continue
        if len(x) == 1:
            samples.append(np.array([x, y], dtype=float))
            continue
        samples.append(np.array([(x[:-1] + t * np.diff(x)).ravel(), (y[:-1] + t * np.diff(y)).ravel()]))
    x, y = np.concatenate(samples, axis=1)
    return np.array([to_scene.m11() * x + to_scene.m21() * y + to_scene.dx(),
                     to_scene.m12() * x + to_scene.m22() * y + to_scene.dy()])


def legend_cover(plot, points: np.ndarray | None = None) -> int:
    """How many of the line samples (``line_points``) the plot's legend hides where it is."""
    points = line_points(plot) if points is None else points
    box = plot.plotItem.legend.sceneBoundingRect()
    x, y = points
    return int(np.count_nonzero((x >= box.left()) & (x <= box.right()) & (y >= box.top()) & (y <= box.bottom())))


def place_legend(plot) -> None:
    """Put the legend in the first of LEGEND_CORNERS where it hides the least of the lines."""
    points = line_points(plot)
    covers = []
    for corner in LEGEND_CORNERS:
        plot.plotItem.legend.anchor(*corner)
        covers.append(legend_cover(plot, points))
    plot.plotItem.legend.anchor(*LEGEND_CORNERS[int(np.argmin(covers))])
