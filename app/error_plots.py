"""Compare mode's plots: each run's true error against the reference over time (contact point
in m, relative energy; log scales) and its ‖RᵀR − I‖, with one legend naming the runs and the
reference with its own error estimate; where something can take the ball's energy, the energy
budget of the run the camera follows beside the energy error, its title naming that run.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtGui, QtWidgets

from . import budget
from .readouts import distinct_names
from .plots import FLOOR, DecadeAxis, TimeAxis, cache_axes, fit_decades, place_row, thinned

PANELS = (("contact", "Contact point error (m)"), ("energy", "Relative energy error"),
          ("orthogonality", "‖RᵀR − I‖"))
REFERENCE_PEN = pg.mkPen("#555", width=1, style=QtCore.Qt.PenStyle.DashLine)
LEGEND_COLUMNS = 3   # at most: fewer where the names do not fit side by side (1024-pixel window)


def short_names(labels: list[str]) -> list[str]:
    """The runs' names as short as a plot's title needs them: their first words where those tell
    them apart ("RK4", "Euler"), else what is not shared (``readouts.distinct_names``)."""
    firsts = [label.split(" ")[0].rstrip(",") for label in labels]
    if len(set(firsts)) == len(firsts):
        return firsts
    return [short for short, _ in distinct_names(labels)]


class ErrorPlots(QtWidgets.QWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.graphics = pg.GraphicsLayoutWidget()
        self.graphics.setBackground("w")
        self.graphics.setMinimumHeight(190)
        self.legend = pg.LegendItem(labelTextSize="8pt", labelTextColor="#333", colCount=LEGEND_COLUMNS, horSpacing=12,
                                    verSpacing=-6)
        self.graphics.addItem(self.legend, row=0, col=0, colspan=len(PANELS))
        self.plots: dict[str, pg.PlotItem] = {}
        for col, (key, title) in enumerate(PANELS):
            plot = self.graphics.addPlot(row=1, col=col, axisItems={"left": DecadeAxis(), "bottom": TimeAxis()})
            plot.setTitle(title, size="9pt", color="#333")
            plot.setLabel("bottom", "t", units="s")
            plot.setLogMode(y=True)
            plot.showGrid(x=True, y=True, alpha=0.25)
            plot.setMouseEnabled(x=False, y=False)
            cache_axes(plot)
            self.plots[key] = plot
        self.reference_line = pg.InfiniteLine(angle=0, pen=REFERENCE_PEN)
        self.reference_label = ""
        self.estimate: float | None = None   # the reference's own error, once known
        layout.addWidget(self.graphics)
        self.curves: list[dict[str, pg.PlotDataItem]] = []
        self.runs = []
        self.budget_plot: pg.PlotItem | None = None   # where the scene can lose energy (``set_budget``)
        self.budget: budget.EnergyBudget | None = None
        self.floor = 0.0
        self.followed = 0                             # the run whose budget is shown
        self.arranged = list(self.plots.values())     # the panels side by side (``_arrange``)
        self.scale = self.words = 1.0                 # the text's scale, the titles' (``set_font_scale``)

    def set_budget(self, causes, floor: float = 0.0) -> None:
        """The energy budget beside the energy error, a band per cause in ``causes``, the ball's
        energy counted from ``floor`` (J); none where no cause is on."""
        self.floor = floor
        if self.budget_plot is not None and not causes:
            self.graphics.removeItem(self.budget.key)
            self.graphics.ci.removeItem(self.legend)
            self.graphics.addItem(self.legend, row=0, col=0, colspan=len(PANELS))
            self.budget_plot = self.budget = None
            self._arrange()
        if causes and self.budget_plot is None:
            self.budget_plot = pg.PlotItem(axisItems={"bottom": TimeAxis()})
            self.budget_plot.setLabel("bottom", "t", units="s")
            self.budget_plot.showGrid(x=True, y=True, alpha=0.25)
            self.budget_plot.setMouseEnabled(x=False, y=False)
            self.budget_plot.setXRange(*self.plots["energy"].viewRange()[0], padding=0.0)
            cache_axes(self.budget_plot)
            self.budget = budget.EnergyBudget(self.budget_plot, across=True)
            self.graphics.ci.removeItem(self.legend)   # the runs' legend over the errors, the key over the budget
            self.graphics.addItem(self.legend, row=0, col=0, colspan=2)
            self.graphics.addItem(self.budget.key, row=0, col=2, colspan=2)
            self._arrange()
            self.set_font_scale(self.scale)
        if self.budget is not None:
            self.budget.set_causes(causes)
        self._title_budget()

    def _arrange(self) -> None:
        """The panels side by side, the budget beside the energy error; where the width cannot
        hold the four (presentation on a 1024-pixel projector), ‖RᵀR − I‖ folds away until there is room."""
        plots = self.plots
        wanted = [plots["contact"], plots["energy"], self.budget_plot, plots["orthogonality"]]
        folding = [plots["orthogonality"]] if self.budget_plot is not None else []
        self.arranged = place_row(self.graphics, self.arranged, [p for p in wanted if p is not None], folding, row=1)

    def _title_budget(self) -> None:
        """The budget's title names the run it shows (the one followed)."""
        if self.budget_plot is not None:
            shown = self.followed < len(self.runs)
            name = short_names([run.label for run in self.runs])[self.followed] if shown else ""
            text = budget.title(name, self.runs[self.followed].color if shown else "#333")
            self.budget_plot.setTitle(text, size=f"{9 * self.words:g}pt", color="#333")

    def set_font_scale(self, scale: float) -> None:
        """Titles, axis labels, tick numbers and the legend at ``scale`` times their normal size."""
        font = QtGui.QFont(self.font())
        font.setPointSizeF(font.pointSizeF() * scale)
        normal = scale == 1.0
        self.scale = scale
        words = self.words = min(scale, 1.5)   # titles and legend: large, but the curves keep their height
        for (_, title), plot in zip(PANELS, self.plots.values()):
            plot.setTitle(title, size=f"{9 * words:g}pt", color="#333")
        for plot in [*self.plots.values(), *([self.budget_plot] if self.budget_plot is not None else [])]:
            for side in ("left", "bottom"):
                axis = plot.getAxis(side)
                axis.setTickFont(None if normal else font)
                axis.label.setFont(font)
            plot.getAxis("left").setWidth(None if normal else int(round(40 * scale)))
            plot.getAxis("bottom").setHeight(None if normal else int(round(20 * scale)))
            plot.showLabel("bottom", normal)   # in large text the seconds' name gives the curves room
        if self.budget is not None:
            self.budget.set_text_size(8 * words)
            self._title_budget()
        self.legend.opts["labelTextSize"] = f"{8 * words:g}pt"
        for _, label in self.legend.items:
            label.setText(label.text, size=f"{8 * words:g}pt")
        self._arrange()
        self._fit_legend()

    def set_runs(self, runs, t_end: float) -> None:
        """A curve per run and panel in the run's colour; the legend names them."""
        for plot in self.plots.values():
            plot.clear()
            plot.setXRange(0.0, t_end, padding=0.02)
            fit_decades(plot, np.array([FLOOR, 1.0]))
        if self.budget is not None:
            self.budget_plot.setXRange(0.0, t_end, padding=0.02)
            self.budget.show(np.zeros(0), np.zeros(0), {})
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
        self.estimate = None
        self.reference_label = "Reference: computing…"
        if self.runs:   # nothing to refer to before a comparison
            self.legend.addItem(pg.PlotDataItem(pen=REFERENCE_PEN), self.reference_label)
        self._title_budget()
        self._fit_legend()

    def set_reference(self, method: str, estimate: float) -> None:
        """Name the reference and its own error; its error is drawn as a floor in the contact plot."""
        self.legend.removeItem(self.reference_label)
        self.reference_label = f"Reference: {method}, own error ≈ {estimate:.1g} m"
        self.legend.addItem(pg.PlotDataItem(pen=REFERENCE_PEN), self.reference_label)
        self.reference_line.setPos(np.log10(max(estimate, FLOOR)))
        self.reference_line.setVisible(True)
        self.estimate = estimate
        self._fit_legend()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._arrange()
        self._fit_legend()

    def _fit_legend(self) -> None:
        """As many legend columns as the width holds: a legend wider than the view would push
        the last panel out of sight."""
        for columns in range(LEGEND_COLUMNS, 0, -1):
            self.legend.setColumnCount(columns)
            needed = self.graphics.ci.layout.effectiveSizeHint(QtCore.Qt.SizeHint.MinimumSize).width()
            if needed <= self.graphics.width():
                break
        self.graphics.ci.setGeometry(self.graphics.range)   # the view's width again, not the old legend's

    def set_visible(self, index: int, visible: bool) -> None:
        for curve in self.curves[index].values():
            curve.setVisible(visible)
        self._fit()

    def show_time(self, t: float, followed: int = 0) -> None:
        """Each run's errors up to time t (the true errors once the reference is known), and the
        budget of run ``followed``."""
        self._show_budget(t, followed)
        for run, curves in zip(self.runs, self.curves):
            n = run.index_at(t) + 1 if len(run.buffer) else 0
            picked = thinned(n)
            times = run.buffer.t[picked]
            curves["orthogonality"].setData(times, np.maximum(run.buffer.orthogonality_error[picked], FLOOR))
            if run.errors is None:
                continue
            for key in ("contact", "energy"):
                values = run.errors[key][:n][picked] if n else np.zeros(0)
                known = np.isfinite(values)
                curves[key].setData(times[known], np.maximum(values[known], FLOOR))
        self._fit()

    def _show_budget(self, t: float, followed: int) -> None:
        if self.budget is None or followed >= len(self.runs):
            return
        if followed != self.followed:
            self.followed = followed
            self._title_budget()
        run = self.runs[followed]
        n = run.index_at(t) + 1 if len(run.buffer) else 0
        self.budget.show_rows(run.trajectory(), thinned(n), n - 1, self.floor)

    def _fit(self) -> None:
        """Each panel shows the whole decades of its visible curves (and the reference's floor)."""
        for key, plot in self.plots.items():
            shown = [curves[key].getOriginalDataset()[1] for curves in self.curves if curves[key].isVisible()]
            shown = [values for values in shown if values is not None and len(values)]
            if key == "contact" and self.estimate is not None:
                shown.append(np.array([max(self.estimate, FLOOR)]))
            fit_decades(plot, np.concatenate(shown) if shown else np.array([FLOOR, 1.0]))
