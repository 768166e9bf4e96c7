"""Small live plots against time: relative energy error and ‖RᵀR − I‖ (log scale), normal force."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.trajectory import NORMAL_FORCE

FLOOR = 1e-17       # log plots show exact zeros at this level
MAX_POINTS = 2000   # per curve; longer runs are thinned for drawing
TITLE_POINTS = 9    # plot titles at font scale 1


class LivePlots(QtWidgets.QWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.curves = {}
        self.plots = []
        self.cursors = []
        for name, title, units, log in (
            ("energy", "|E − E₀| / E₀", "", True),
            ("orthogonality", "‖RᵀR − I‖", "", True),
            ("force", "Normal force F·N", "N", False),
        ):
            plot = pg.PlotWidget(background="w")
            plot.setObjectName(f"plot.{name}")
            plot.setProperty("plotTitle", title)
            plot.setTitle(title, size=f"{TITLE_POINTS}pt", color="#333")
            plot.setLabel("bottom", "t", units="s")
            if units:
                plot.setLabel("left", units=units)
                plot.getAxis("left").enableAutoSIPrefix(False)  # newtons, not mN or kN
            plot.setLogMode(y=log)
            plot.showGrid(x=True, y=True, alpha=0.25)
            plot.setMouseEnabled(x=False, y=False)
            plot.setMinimumSize(150, 150)   # three side by side in a 1024-pixel window
            if name == "force":
                plot.addItem(pg.InfiniteLine(pos=0.0, angle=0, pen=pg.mkPen("#c0392b", style=QtCore.Qt.PenStyle.DashLine)))
            cursor = pg.InfiniteLine(pos=0.0, angle=90, pen=pg.mkPen("#555", width=1))
            cursor.setVisible(False)
            plot.addItem(cursor, ignoreBounds=True)
            self.cursors.append(cursor)
            self.plots.append(plot)
            self.curves[name] = plot.plot(pen=pg.mkPen("#1f5fa8", width=1), skipFiniteCheck=True)
            layout.addWidget(plot)
        self.scale = 1.0
        self.show_run(None, 0)

    def set_cursor(self, t: float | None) -> None:
        """A vertical line at the shown time t (None: none)."""
        for cursor in self.cursors:
            cursor.setVisible(t is not None)
            if t is not None:
                cursor.setValue(t)

    def set_font_scale(self, scale: float) -> None:
        """Titles, axis labels and tick numbers at ``scale`` times their normal size."""
        self.scale = scale
        font = QtGui.QFont(self.font())
        font.setPointSizeF(font.pointSizeF() * scale)
        normal = scale == 1.0
        for plot in self.plots:
            plot.setTitle(plot.property("plotTitle"), size=f"{TITLE_POINTS * scale:g}pt", color="#333")
            for side in ("left", "bottom"):
                axis = plot.getAxis(side)
                axis.setTickFont(None if normal else font)
                axis.label.setFont(font)
            plot.getAxis("left").setWidth(None if normal else int(round(40 * scale)))
            plot.getAxis("bottom").setHeight(None if normal else int(round(30 * scale)))

    def set_duration(self, t_end: float) -> None:
        """Fix the time axis to the run: it is not re-laid out at every update."""
        for plot in self.plots:
            plot.setXRange(0.0, t_end, padding=0.02)

    def show_run(self, buffer, index: int) -> None:
        """Plot rows 0..index of a ``RunBuffer`` (None or empty: clear)."""
        if buffer is None or len(buffer) == 0:
            for curve in self.curves.values():
                curve.setData([], [])
            for plot in self.plots[:2]:  # empty: show the range errors live in (log10 units)
                plot.setYRange(np.log10(FLOOR), 0.0, padding=0.0)
            self.autoscaled = False
            return
        if not self.autoscaled:  # data: the y axes follow it
            for plot in self.plots:
                plot.enableAutoRange(axis="y")
            self.autoscaled = True
        stride = max(1, -(-(index + 1) // MAX_POINTS))
        picked = np.r_[np.arange(0, index + 1, stride), index]
        t = buffer.t[picked]
        self.curves["energy"].setData(t, np.maximum(np.abs(buffer.energy_error[picked]), FLOOR))
        self.curves["orthogonality"].setData(t, np.maximum(buffer.orthogonality_error[picked], FLOOR))
        self.curves["force"].setData(t, buffer.rows[picked, NORMAL_FORCE])
