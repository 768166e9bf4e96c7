"""Small live plots against time: relative energy error and ‖RᵀR − I‖ (log scale), normal force,
and beside the energy error, where something can take the ball's energy, its budget (``budget``).

Log scales show whole decades, labelled only at powers of ten (10⁻⁸) and only as many as fit the
axis' length in its font: pyqtgraph's own log ticks label every 2·10ⁿ … 9·10ⁿ when the data span
a decade or two, and those labels pile up on a short axis.
"""

from __future__ import annotations

import math

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.trajectory import CENTER, CONTACT, FLYING, NORMAL_FORCE

from .budget import TITLE as BUDGET_TITLE, EnergyBudget
from .contact_view import ModeSpans
from .help import TOPIC

FLOOR = 1e-17       # log plots show exact zeros at this level
# the energy plot's title, and where the ball can slide or fly: the dissipation D counted as accounted for
ENERGY_TITLES = {False: "|E − E₀| / E₀ (orange: gained)", True: "|E + D − E₀| / E₀ (orange: gained)"}
GAIN_COLOR = "#e67e22"   # the energy curve where the energy has grown
MAX_POINTS = 2000   # per curve; longer runs are thinned for drawing
TITLE_POINTS = 9    # plot titles at font scale 1
LABEL_PITCH = 1.6   # labels on a log axis at least this many text heights apart
DECADE_STEPS = (1, 2, 3, 5, 10, 20, 50)   # decades from one label to the next, smallest that fits
MINOR_PIXELS = 40   # a decade at least this long shows minor ticks at 2·10ⁿ … 9·10ⁿ
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
# A measured track's coordinates against time (``LivePlots.set_track``): its points as dots, the
# run's same coordinate as a line, each axis in its colour (Okabe–Ito: vermillion, blue, green)
TRACK_TITLE = "Track {} (m)"   # the axes measured; dots: the track, lines: the run (short: four plots share a row)
AXIS_COLORS = {"x": "#d55e00", "y": "#0072b2", "z": "#009e73"}


def power_of_ten(exponent: float) -> str:
    """10⁻⁸ for -8."""
    return "10" + str(round(exponent)).translate(SUPERSCRIPT)


def decade_range(values: np.ndarray) -> tuple[int, int]:
    """The whole decades (log10 units) holding the finite positive values, at least one decade."""
    finite = values[np.isfinite(values) & (values > 0)]
    if len(finite) == 0:
        return round(math.log10(FLOOR)), 0
    low = math.floor(math.log10(max(float(finite.min()), FLOOR)))
    high = math.ceil(math.log10(float(finite.max())))
    return low, max(high, low + 1)


def fit_decades(plot, values: np.ndarray, axis: str = "y") -> None:
    """Show the whole decades holding ``values`` on a log plot's ``axis`` ("x" or "y"); the range
    is only set when it changes, so an update that stays within it does not lay the axis out again."""
    low, high = decade_range(values)
    if list(plot.viewRange()["xy".index(axis)]) != [low, high]:
        plot.setRange(**{f"{axis}Range": (low, high)}, padding=0.0)


def cache_axes(plot) -> None:
    """Keep each axis (ticks, labels, grid lines) as a picture in screen pixels, drawn again only
    when the axis changes: a curve or cursor that moves then repaints without drawing text and
    grid anew (with software rendering a plot update costs about a fifth of what it did)."""
    for side in ("left", "bottom"):
        plot.getAxis(side).setCacheMode(QtWidgets.QGraphicsItem.CacheMode.DeviceCoordinateCache)


def thinned(n: int) -> np.ndarray:
    """Indices of at most about MAX_POINTS of n rows, the last one included."""
    stride = max(1, -(-n // MAX_POINTS))
    return np.r_[np.arange(0, n, stride), n - 1] if n else np.zeros(0, dtype=int)


def least_width(graphics: pg.GraphicsLayoutWidget, items) -> float:
    """The width ``items`` need side by side in the view's layout, their titles and axes in their fonts."""
    layout = graphics.ci.layout
    left, _, right, _ = layout.getContentsMargins()
    needed = sum(item.effectiveSizeHint(QtCore.Qt.SizeHint.MinimumSize).width() for item in items)
    return needed + layout.horizontalSpacing() * (len(items) - 1) + left + right


def place_row(graphics: pg.GraphicsLayoutWidget, placed: list, wanted: list, folding, row: int) -> list:
    """Lay ``wanted`` out side by side in ``row`` of the view's layout, in place of ``placed``,
    leaving out those of ``folding`` in turn while the width cannot hold them (and taking back
    one left out earlier where it fits alone); returns what is placed. An item left out stays in
    the scene, hidden (it is deleted with the view)."""
    every, wanted, left_out = list(wanted), list(wanted), []
    for item in folding:
        if least_width(graphics, wanted) <= graphics.width():
            break
        wanted.remove(item)
        left_out.append(item)
    for item in left_out[:-1]:   # one folded earlier may fit alone where the last one folded did not
        trial = [other for other in every if other in wanted or other is item]
        if least_width(graphics, trial) <= graphics.width():
            wanted = trial
    if wanted == placed:
        return placed
    for item in placed:
        graphics.ci.removeItem(item)
        if item not in wanted:
            graphics.scene().addItem(item)
            item.hide()
    for col, item in enumerate(wanted):
        graphics.ci.addItem(item, row=row, col=col)
        item.show()
    return wanted


class DecadeAxis(pg.AxisItem):
    """A log axis with labels only at powers of ten, spaced to fit: every decade, or every 2nd,
    3rd, 5th, … when the axis is short for its span; unlabelled ticks at the other decades and,
    where a decade is long enough, at 2·10ⁿ … 9·10ⁿ. Labels are spaced by their extent along the
    axis: their height on a vertical axis, the widest one's width on a horizontal one. Labels at
    the two ends may reach half that extent past the axis, so a range of whole decades is
    labelled at both ends."""

    def __init__(self, orientation: str = "left", **options):
        super().__init__(orientation, **options)
        self.setStyle(maxTextLevel=0)

    def text_height(self) -> float:
        return self.metrics().height()

    def metrics(self) -> QtGui.QFontMetricsF:
        return QtGui.QFontMetricsF(self.style["tickFont"] or QtGui.QFont())

    def label_extent(self, low: float, high: float) -> float:
        """Pixels a label takes along the axis, the largest of the decades from low to high."""
        if self.orientation in ("left", "right"):
            return self.text_height()
        metrics = self.metrics()
        exponents = range(math.floor(low), math.ceil(high) + 1) if math.isfinite(low) and math.isfinite(high) \
            else range(0)
        return max((metrics.horizontalAdvance(power_of_ten(k)) for k in exponents), default=self.text_height())

    def tickValues(self, minVal, maxVal, size):  # noqa: N802 (pyqtgraph's names)
        low, high = sorted((minVal, maxVal))
        if not (math.isfinite(low) and math.isfinite(high)) or high - low <= 0:
            return []
        exponents = range(math.ceil(low - 1e-9), math.floor(high + 1e-9) + 1)
        per_decade = size / (high - low)                  # pixels
        # pixels from one label to the next, at least: a label and a gap of part of a text height
        pitch = self.label_extent(low, high) + (LABEL_PITCH - 1) * self.text_height()
        step = next((s for s in DECADE_STEPS if s * per_decade >= pitch), math.ceil(pitch / per_decade))
        labelled = [k for k in exponents if k % step == 0]
        if len(labelled) < 2 and len(exponents) >= 2 and (exponents[-1] - exponents[0]) * per_decade >= pitch:
            labelled = [exponents[0], exponents[-1]]      # a short axis: its two ends, as they fit
        levels = [(float(step), [float(k) for k in labelled]),
                  (1.0, [float(k) for k in exponents if k not in labelled])]
        if per_decade >= MINOR_PIXELS:
            mantissas = np.log10(np.arange(2, 10))
            minor = [k + m for k in range(math.floor(low), math.ceil(high)) for m in mantissas]
            levels.append((None, [v for v in minor if low <= v <= high]))
        return levels

    def tickStrings(self, values, scale, spacing):  # noqa: N802
        return [power_of_ten(v) for v in values]

    def boundingRect(self):  # noqa: N802
        rect = super().boundingRect()
        margin = self.label_extent(*self.range) / 2 + 1
        return rect.adjusted(0, -margin, 0, margin) if self.orientation in ("left", "right") \
            else rect.adjusted(-margin, 0, margin, 0)


class TimeAxis(pg.AxisItem):
    """A time axis whose labels never run together: the finest of 1, 2, 5 × 10ⁿ seconds that
    leaves a gap of two spaces between the widest labels, in the axis' font; only those ticks
    are labelled (pyqtgraph labels its minor ticks too where its own estimate finds room, and a
    narrow plot then reads "0.51.0")."""

    def __init__(self, orientation: str = "bottom", **options):
        super().__init__(orientation, **options)
        self.setStyle(maxTextLevel=0)

    def tickSpacing(self, minVal, maxVal, size):  # noqa: N802 (pyqtgraph's names)
        low, high = sorted((minVal, maxVal))
        span = high - low
        if not (math.isfinite(span) and span > 0 and size > 0):
            return super().tickSpacing(minVal, maxVal, size)
        metrics = QtGui.QFontMetricsF(self.style["tickFont"] or QtGui.QFont())
        gap = metrics.horizontalAdvance("  ")
        exponent = math.floor(math.log10(span)) - 3
        while True:
            for mantissa in (1, 2, 5):
                spacing = mantissa * 10.0 ** exponent
                values = np.arange(math.ceil(low / spacing), math.floor(high / spacing) + 1) * spacing
                widest = max((metrics.horizontalAdvance(text) for text in self.tickStrings(values, 1.0, spacing)),
                             default=0.0)
                if spacing / span * size >= widest + gap or len(values) <= 1:
                    minor = spacing / (2 if mantissa == 5 else 5 if mantissa == 1 else 2)
                    return [(spacing, 0.0), (minor, 0.0)]
            exponent += 1


class LivePlots(QtWidgets.QWidget):
    """Three plots in one graphics view: in a window composed with OpenGL, every widget that
    repaints costs a share of the frame, so the plots are one widget, not three."""

    def __init__(self, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.graphics = pg.GraphicsLayoutWidget()
        self.graphics.setBackground("w")
        self.graphics.scene().sigMouseMoved.connect(self._hovered)
        layout.addWidget(self.graphics)
        self.setMinimumSize(3 * 150, 120)   # three side by side in a 1024-pixel window
        self.curves = {}
        self.plots: list[pg.PlotItem] = []
        self.cursors = []
        for name, title, units, log in (
            ("energy", ENERGY_TITLES[False], "", True),
            ("orthogonality", "‖RᵀR − I‖", "", True),
            ("force", "Normal force F·N", "N", False),
        ):
            axes = {"left": DecadeAxis(), "bottom": TimeAxis()} if log else {"bottom": TimeAxis()}
            plot = self.graphics.addPlot(row=0, col=len(self.plots), axisItems=axes)
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
            cache_axes(plot)
            if name == "force":
                dashed = pg.mkPen("#c0392b", style=QtCore.Qt.PenStyle.DashLine)
                plot.addItem(pg.InfiniteLine(pos=0.0, angle=0, pen=dashed))
            cursor = pg.InfiniteLine(pos=0.0, angle=90, pen=pg.mkPen("#555", width=1))
            cursor.setVisible(False)
            plot.addItem(cursor, ignoreBounds=True)
            self.cursors.append(cursor)
            self.plots.append(plot)
            self.curves[name] = plot.plot(pen=pg.mkPen("#1f5fa8", width=1), skipFiniteCheck=True)
        # where the energy has grown (the ball could climb above where it started): over the
        # |E − E0| curve in another colour, so a gain is told from a loss on the log axis
        self.curves["energy_gain"] = self.plots[0].plot(pen=pg.mkPen(GAIN_COLOR, width=2), connect="finite")
        # where the ball slides or flies: shaded spans behind the normal force (0 in flight)
        self.mode_spans = ModeSpans(self.plots[2])
        self.scale = 1.0
        self.landings: list[float] = []   # the times of the shown run's landings (set with its transitions)
        self.track = None                 # (track, point) shown in a fourth plot (``set_track``)
        self.track_plot: pg.PlotItem | None = None
        self.budget_plot: pg.PlotItem | None = None   # where the scene can lose energy (``set_budget``)
        self.budget: EnergyBudget | None = None
        self.arranged = list(self.plots)              # the items side by side, left to right (``_arrange``)
        self.floor = 0.0                              # the budget's zero of energy (``budget.floor_energy``)
        self.show_run(None, 0)

    def _hovered(self, pos: QtCore.QPointF) -> None:
        """The view takes the help topic of the plot under the mouse, for F1 (``app.help``)."""
        for plot in self.plots:
            if plot.sceneBoundingRect().contains(pos):
                self.graphics.setProperty(TOPIC, plot.property(TOPIC))

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
        if self.budget is not None:
            self.budget.set_text_size(8 * min(scale, 1.5))
        self._arrange()   # (what fits the width)

    def show_contact(self, on: bool) -> None:
        """Title the energy plot for a scene whose ball can slide or fly (``on``: its error counts
        the energy dissipated as accounted for) or not."""
        plot = self.plots[0]
        if plot.property("plotTitle") != ENERGY_TITLES[on]:
            plot.setProperty("plotTitle", ENERGY_TITLES[on])
            plot.setTitle(ENERGY_TITLES[on], size=f"{TITLE_POINTS * self.scale:g}pt", color="#333")

    def set_duration(self, t_end: float) -> None:
        """Fix the time axis to the run: it is not re-laid out at every update."""
        for plot in self.plots:
            plot.setXRange(0.0, t_end, padding=0.02)

    def _arrange(self) -> None:
        """The plots side by side: the energy error, its budget and the budget's key beside it,
        ‖RᵀR − I‖, the normal force, the track. Where the width cannot hold them all in their text
        (presentation on a 1024-pixel projector), ‖RᵀR − I‖ folds away, then the normal force: for
        a ball that slows down the budget tells more (they come back as soon as there is room)."""
        key = self.budget.key if self.budget is not None else None
        wanted = [item for item in (self.plots[0], self.budget_plot, key, *self.plots[1:3], self.track_plot)
                  if item is not None]
        folding = self.plots[1:3] if self.budget is not None else []   # ‖RᵀR − I‖, then the force
        self.arranged = place_row(self.graphics, self.arranged, wanted, folding, row=0)

    @property
    def folded(self) -> list[pg.PlotItem]:
        """The plots folded away for want of width."""
        return [plot for plot in self.plots if plot not in self.arranged]

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._arrange()

    def _new_plot(self, name: str, title: str) -> pg.PlotItem:
        """A linear plot against time with the others' time range, a title and a playback cursor."""
        plot = pg.PlotItem(axisItems={"bottom": TimeAxis()})
        plot.setObjectName(f"plot.{name}")
        plot.setProperty("plotTitle", title)
        plot.setTitle(title, size=f"{TITLE_POINTS * self.scale:g}pt", color="#333")
        plot.setLabel("bottom", "t", units="s")
        plot.showGrid(x=True, y=True, alpha=0.25)
        plot.setMouseEnabled(x=False, y=False)
        cache_axes(plot)
        cursor = pg.InfiniteLine(pos=0.0, angle=90, pen=pg.mkPen("#555", width=1))
        cursor.setVisible(self.cursors[0].isVisible())
        cursor.setValue(self.cursors[0].value())
        plot.addItem(cursor, ignoreBounds=True)
        plot.setXRange(*self.plots[0].viewRange()[0], padding=0.0)
        plot.cursor = cursor
        return plot

    def set_budget(self, causes, floor: float = 0.0) -> None:
        """The energy budget beside the energy error, with a band per cause of ``causes`` (the
        scene's ``budget.causes_on``) acting in the run shown (``budget.acting``) and the ball's
        energy counted from ``floor`` (J); none where no cause is on (the 2011 model: the energy
        error says it all)."""
        self.floor = floor
        if not causes:
            if self.budget_plot is not None:
                self.cursors.remove(self.budget_plot.cursor)
                self.plots.remove(self.budget_plot)
                self.budget_plot = self.budget = None
                self._arrange()
            return
        if self.budget_plot is None:
            self.budget_plot = self._new_plot("budget", BUDGET_TITLE)
            self.budget = EnergyBudget(self.budget_plot, relayout=self._arrange)
            self.plots.append(self.budget_plot)
            self.cursors.append(self.budget_plot.cursor)
            self._arrange()
            self.set_font_scale(self.scale)
        self.budget.set_causes(causes)

    def show_budget(self, trajectory, index: int, at: int) -> None:
        """The budget of a ``Trajectory``'s rows 0..index, its legend's values at row ``at``."""
        if self.budget is not None:
            self.budget.show_rows(trajectory, thinned(index + 1), at, self.floor)

    def set_track(self, track, point: str = "center") -> None:
        """A fourth plot of the measured ``track``'s coordinates against time, its points as dots
        and the run's ``point`` ("center" or "contact") as lines beside them, with the playback
        cursor (None: the plot goes)."""
        if self.track_plot is not None:
            self.cursors.remove(self.track_cursor)
            self.plots.remove(self.track_plot)
            self.track_plot = None
        self.track = None if track is None else (track, point)
        if track is None:
            self._arrange()
            return
        plot = self._new_plot("track", TRACK_TITLE.format(", ".join(track.axes)))
        self.track_cursor = plot.cursor
        self.track_curves = {}
        for axis, values in zip(track.axes, track.positions.T):
            color = AXIS_COLORS[axis]
            plot.plot(track.t, values, pen=None, symbol="o", symbolSize=4, symbolPen=None, symbolBrush=color,
                      name=f"track.{axis}")
            self.track_curves[axis] = plot.plot(pen=pg.mkPen(color, width=1.5), skipFiniteCheck=True)
        self.plots.append(plot)
        self.cursors.append(self.track_cursor)
        self.track_plot = plot   # (the four share the width the three had: the window grows no wider)
        self._arrange()
        self.set_font_scale(self.scale)

    def _show_track_run(self, buffer, picked: np.ndarray | None) -> None:
        """The run's coordinates the track measures, at the rows ``picked`` (None: none)."""
        if self.track_plot is None:
            return
        track, point = self.track
        columns = CENTER if point == "center" else CONTACT
        for k, axis in enumerate(("x", "y", "z")):
            curve = self.track_curves.get(axis)
            if curve is None:
                continue
            if picked is None or columns.start + k >= columns.stop:   # (no contact height in the rows)
                curve.setData([], [])
            else:
                curve.setData(buffer.t[picked], buffer.rows[picked, columns.start + k])

    def show_run(self, buffer, index: int) -> None:
        """Plot rows 0..index of a ``RunBuffer`` (None or empty: clear)."""
        if buffer is None or len(buffer) == 0:
            self._show_track_run(buffer, None)
            self.mode_spans.show(np.zeros(0), np.zeros(0))
            for curve in self.curves.values():
                curve.setData([], [])
            for plot in self.plots[:2]:  # empty: show the range errors live in
                fit_decades(plot, np.array([FLOOR, 1.0]))
            return
        picked = thinned(index + 1)
        self._show_track_run(buffer, picked)
        t = buffer.t[picked]
        drift = buffer.energy_error[picked]
        self.curves["energy_gain"].setData(t, np.where(drift > 0, np.maximum(drift, FLOOR), np.nan))
        for plot, name, values in ((self.plots[0], "energy", np.abs(drift)),
                                   (self.plots[1], "orthogonality", buffer.orthogonality_error[picked])):
            values = np.maximum(values, FLOOR)
            self.curves[name].setData(t, values)
            fit_decades(plot, values)
        modes = buffer.mode[: index + 1]
        self.mode_spans.show(buffer.t[: index + 1], modes, self.landings)
        self.curves["force"].setData(t, np.where(modes[picked] == FLYING, 0.0, buffer.rows[picked, NORMAL_FORCE]))
