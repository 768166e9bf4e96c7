"""Compare mode's plots and table: each run's true error against the reference over time
(contact point in m, relative energy, ‖RᵀR − I‖; log scales), one legend naming the runs and
the reference, and the summary of every run at the end.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from .plots import FLOOR, MAX_POINTS

PANELS = (("contact", "Contact point error (m)"), ("energy", "Relative energy error"),
          ("orthogonality", "‖RᵀR − I‖"))
SUMMARY = ("Run", "Status", "Error at end (m)", "Max error (m)", "Max energy error", "Steps",
           "Evaluations", "Compute time (s)")
REFERENCE_PEN = pg.mkPen("#555", width=1, style=QtCore.Qt.PenStyle.DashLine)


def _thinned(n: int) -> np.ndarray:
    """Indices of at most about MAX_POINTS of n rows, the last one included."""
    stride = max(1, -(-n // MAX_POINTS))
    return np.r_[np.arange(0, n, stride), n - 1] if n else np.zeros(0, dtype=int)


class ErrorPlots(QtWidgets.QWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.graphics = pg.GraphicsLayoutWidget()
        self.graphics.setBackground("w")
        self.graphics.setMinimumHeight(170)
        self.plots: dict[str, pg.PlotItem] = {}
        for col, (key, title) in enumerate(PANELS):
            plot = self.graphics.addPlot(row=0, col=col)
            plot.setTitle(title, size="9pt", color="#333")
            plot.setLabel("bottom", "t", units="s")
            plot.setLogMode(y=True)
            plot.showGrid(x=True, y=True, alpha=0.25)
            plot.setMouseEnabled(x=False, y=False)
            self.plots[key] = plot
        self.legend = pg.LegendItem(labelTextSize="8pt", verSpacing=-4)
        self.graphics.addItem(self.legend, row=0, col=len(PANELS))
        self.reference_line = pg.InfiniteLine(angle=0, pen=REFERENCE_PEN)
        self.reference_label = ""
        self.table = QtWidgets.QTableWidget(0, len(SUMMARY), objectName="summary")
        self.table.setHorizontalHeaderLabels(SUMMARY)
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        layout.addWidget(self.graphics, 3)
        layout.addWidget(self.table, 2)
        self.curves: list[dict[str, pg.PlotDataItem]] = []
        self.runs = []

    def set_runs(self, runs, t_end: float) -> None:
        """A curve per run and panel in the run's colour; the legend names them."""
        for plot in self.plots.values():
            plot.clear()
            plot.setXRange(0.0, t_end, padding=0.02)
            plot.setYRange(np.log10(FLOOR), 0.0, padding=0.0)
            plot.enableAutoRange(axis="y")
        self.legend.clear()
        self.runs = list(runs)
        self.curves = []
        for run in self.runs:
            pen = pg.mkPen(run.color, width=1.5)
            curves = {key: plot.plot(pen=pen, skipFiniteCheck=True) for key, plot in self.plots.items()}
            self.legend.addItem(curves["contact"], run.label)
            self.curves.append(curves)
        self.plots["contact"].addItem(self.reference_line)
        self.reference_line.setVisible(False)
        self.reference_label = "Reference: computing…"
        self.legend.addItem(pg.PlotDataItem(pen=REFERENCE_PEN), self.reference_label)
        self.table.setRowCount(len(self.runs))
        for r, run in enumerate(self.runs):
            self._cell(r, 0, run.label, run.color)
            for c in range(1, len(SUMMARY)):
                self._cell(r, c, "…")

    def set_reference(self, method: str, estimate: float) -> None:
        """Name the reference and its own error; its error is drawn as a floor in the contact plot."""
        self.legend.removeItem(self.reference_label)
        self.reference_label = f"Reference: {method}, its error ≈ {estimate:.1g} m"
        self.legend.addItem(pg.PlotDataItem(pen=REFERENCE_PEN), self.reference_label)
        self.reference_line.setPos(np.log10(max(estimate, FLOOR)))
        self.reference_line.setVisible(True)

    def set_visible(self, index: int, visible: bool) -> None:
        for curve in self.curves[index].values():
            curve.setVisible(visible)

    def show_time(self, t: float) -> None:
        """Each run's errors up to time t (the true errors once the reference is known)."""
        for run, curves in zip(self.runs, self.curves):
            n = run.index_at(t) + 1 if len(run.buffer) else 0
            picked = _thinned(n)
            times = run.buffer.t[picked]
            curves["orthogonality"].setData(times, np.maximum(run.buffer.orthogonality_error[picked], FLOOR))
            if run.errors is None:
                continue
            for key in ("contact", "energy"):
                values = run.errors[key][:n][picked] if n else np.zeros(0)
                known = np.isfinite(values)
                curves[key].setData(times[known], np.maximum(values[known], FLOOR))

    def fill_summary(self) -> None:
        """Each run's end status, errors and cost (errors once the reference is known)."""
        for r, run in enumerate(self.runs):
            sim = run.simulation
            self._cell(r, 1, str(sim.status) if sim.status else "running")
            self._cell(r, 5, f"{sim.steps:,}")
            self._cell(r, 6, f"{sim.evaluations:,}")
            self._cell(r, 7, f"{run.seconds:.3g}")
            if run.errors is not None:
                contact, energy = run.errors["contact"], run.errors["energy"]
                known = np.isfinite(contact)
                self._cell(r, 2, f"{contact[known][-1]:.2e}" if known.any() else "—")
                self._cell(r, 3, f"{contact[known].max():.2e}" if known.any() else "—")
                self._cell(r, 4, f"{np.nanmax(energy):.2e}" if np.isfinite(energy).any() else "—")

    def _cell(self, row: int, col: int, text: str, color: str | None = None) -> None:
        item = QtWidgets.QTableWidgetItem(text)
        if color:
            item.setForeground(pg.mkColor(color))
        if col > 1:
            item.setTextAlignment(QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter)
        self.table.setItem(row, col, item)
