"""The energy budget: where the ball's energy went, as a stacked plot against time.

The lowest band is the ball's energy E, kinetic and potential (the potential counted from the
lowest point of the drawn landscape, where a ball at rest there has none); above it, one band
per cause that acts in the run, the energy it has taken so far (``Trajectory.dissipated_by``:
sliding friction, impacts, rolling resistance, spin friction, air; ``acting`` says which). The stack's top is
E + ΣD, what the energy check holds constant: a flat top is the check at a glance, and where
the ball comes to rest the bands say what took its energy. The key beside the plot gives each band's
value at the moment shown.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pyqtgraph as pg
from PySide6 import QtGui

from rollball import Trajectory
from rollball.trajectory import DISSIPATION_CAUSES, ENERGY, T

# What each cause is called and its colour (Okabe–Ito hues, dark enough to read on a projector's
# washed-out white; sliding and impacts in the colours of the sliding trail and the landing marker)
CAUSE_WORDS = {"sliding": "sliding", "impacts": "impacts", "rolling": "rolling", "spin": "spin", "air": "air"}
CAUSE_COLORS = {"sliding": "#56b4e9", "impacts": "#cc79a7", "rolling": "#d55e00", "spin": "#e69f00",
                "air": "#7f7f7f"}
ENERGY_COLOR = "#009e73"                # the ball's own energy, kinetic + potential
ENERGY_WORDS = "E"
BAND_ALPHA = 170                        # of 255: bands opaque enough to tell apart on a projector
TOP_PEN = pg.mkPen("#222", width=1.5)   # the stack's top: E + ΣD
LABEL_PITCH = 1.2                       # text heights from one of the axis' labels to the next, at least
TITLE = "Energy budget (J)"
SHORT_TITLE = "Budget (J)"              # with a run's name (compare mode), where four plots share a row
assert set(CAUSE_WORDS) == set(DISSIPATION_CAUSES) == set(CAUSE_COLORS)


def causes_on(scene) -> tuple[str, ...]:
    """The causes that can take energy in ``scene``, in ``DISSIPATION_CAUSES``' order: sliding
    where there is a friction coefficient (the ball can slip), impacts where it flies and lands,
    and each of rolling resistance, spin friction and air where its value is not 0."""
    contact = scene.contact
    on = {"sliding": contact.friction is not None, "impacts": contact.after_liftoff == "fly",
          "rolling": contact.rolling_resistance > 0.0, "spin": contact.spin_friction > 0.0,
          "air": scene.air.density > 0.0}
    return tuple(cause for cause in DISSIPATION_CAUSES if on[cause])


def acting(causes, trajectory: Trajectory | None) -> tuple[str, ...]:
    """Of a scene's ``causes`` (``causes_on``), those whose mechanism is on in a run
    (``trajectory``, as far as it has been computed; None: none yet), the budget's bands: each
    cause with a coefficient (sliding's μ, c_rr, μ_s, the air's density) acts wherever the ball
    moves so and is listed from the start, at 0 J until it takes some; impacts have none, a
    landing is what takes them: listed once the run has landed (not where it never flies, flies
    to its end or is cut short before it lands)."""
    landed = trajectory is not None and trajectory.landings > 0
    return tuple(cause for cause in causes if cause != "impacts" or landed)


def floor_energy(scene, landscape) -> float:
    """The energy of a ball at rest at the lowest point of the drawn landscape (J): where the
    budget's potential energy is counted from."""
    v = scene.view
    n = max(2, min(400, int(round((v.max - v.min) / v.step)) + 1))
    grid = np.linspace(v.min, v.max, n)
    x, y = np.meshgrid(grid, grid, indexing="ij")
    heights = np.asarray(landscape.height(x.ravel(), y.ravel()), dtype=float)
    heights = heights[np.isfinite(heights)]
    lowest = float(heights.min()) if len(heights) else 0.0
    m = scene.ball.mass
    return m * scene.gravity * (lowest + scene.ball.radius)


class EnergyAxis(pg.AxisItem):
    """The budget's joules: labels only at the finest of 1, 2, 5 × 10ⁿ J that leaves them
    ``LABEL_PITCH`` text heights apart (a short plot in presentation's large text has room for
    few: pyqtgraph's own choice there writes 1.5 over 1.0 over 0.5)."""

    def __init__(self, orientation: str = "left", **options):
        super().__init__(orientation, **options)
        self.enableAutoSIPrefix(False)   # joules, not mJ
        self.setStyle(maxTextLevel=0)

    def tickSpacing(self, minVal, maxVal, size):  # noqa: N802 (pyqtgraph's names)
        span = abs(maxVal - minVal)
        if not (np.isfinite(span) and span > 0 and size > 0):
            return super().tickSpacing(minVal, maxVal, size)
        pitch = LABEL_PITCH * QtGui.QFontMetricsF(self.style["tickFont"] or QtGui.QFont()).height()
        exponent = int(np.floor(np.log10(span))) - 3
        while True:
            for mantissa in (1, 2, 5):
                spacing = mantissa * 10.0 ** exponent
                if spacing / span * size >= pitch:
                    return [(spacing, 0.0), (spacing / (5 if mantissa != 2 else 4), 0.0)]
            exponent += 1


class EnergyBudget:
    """The stacked bands on a pyqtgraph plot, and their key (``key``, a label the owner places
    beside the plot: a legend inside would hide a short plot's bands) that gives each band's value
    at the moment shown, top band first. ``set_causes`` says which causes the scene has on; a band
    each gets those of them acting in the run shown (``acting``; ``causes``); ``show`` draws rows."""

    def __init__(self, plot: pg.PlotItem, across: bool = False, relayout: Callable[[], None] | None = None):
        """``across``: the key two bands a line (above the plots), else a line per band (beside it);
        ``relayout``: the owner's, called where a band comes or goes (the key's size with it)."""
        self.plot = plot
        self.across = across
        self.relayout: Callable[[], None] | None = None
        plot.setAxisItems({"left": EnergyAxis()})
        self.possible: tuple[str, ...] = ()   # the scene's causes (``causes_on``)
        self.causes: tuple[str, ...] = ()     # those with a band: acting in the run shown
        self.key = pg.LabelItem(justify="left")
        self.key.setObjectName("budget.key")
        self.values: dict[str, float] = {}   # each band's value at the moment shown (J), by name
        self.text_size = 8.0
        self._base = pg.PlotDataItem(skipFiniteCheck=True)   # y = 0 under the lowest band
        self.tops: dict[str, pg.PlotDataItem] = {}
        self.bands: list[pg.FillBetweenItem] = []
        self.total = pg.PlotDataItem(pen=TOP_PEN, skipFiniteCheck=True)   # E + ΣD, over the bands
        self.total.setZValue(2)
        plot.addItem(self.total)
        self.set_causes(())
        self.relayout = relayout   # (from here on: the owner places the key once it has it)

    def _bands(self) -> list[tuple[str, str, str]]:
        """(name, colour, words) of each band, bottom to top."""
        return [("energy", ENERGY_COLOR, ENERGY_WORDS)] + [(c, CAUSE_COLORS[c], CAUSE_WORDS[c]) for c in self.causes]

    def set_causes(self, causes) -> None:
        """The scene's ``causes`` (``causes_on``), before a run: a band for the ball's energy and
        for each of them acting in a run not yet started (``acting``)."""
        self.possible = tuple(causes)
        self._set_bands(acting(self.possible, None))

    def _set_bands(self, causes: tuple[str, ...]) -> None:
        """A band for the ball's energy and for each of ``causes`` (kept where they are those)."""
        if causes == self.causes and self.tops:
            return
        self.causes = causes
        for item in [*self.bands, *self.tops.values()]:
            self.plot.removeItem(item)
        self.tops, self.bands = {}, []
        below = self._base
        for name, color, words in self._bands():
            brush = pg.mkBrush(*pg.mkColor(color).getRgb()[:3], BAND_ALPHA)
            top = pg.PlotDataItem(pen=pg.mkPen(color, width=1), skipFiniteCheck=True)
            band = pg.FillBetweenItem(below, top, brush=brush)
            band.setZValue(-5)
            self.plot.addItem(top)
            self.plot.addItem(band)
            self.tops[name], below = top, top
            self.bands.append(band)
        self._say({})
        if self.relayout is not None:
            self.relayout()

    def show_rows(self, trajectory: Trajectory, picked: np.ndarray, at: int, floor: float) -> None:
        """A ``Trajectory``'s rows ``picked`` (increasing: 0 to the last shown, thinned for
        drawing), the ball's energy counted from ``floor`` (J), the key's values at row ``at``."""
        self._set_bands(acting(self.possible, trajectory))
        if not len(trajectory) or not len(picked):
            self.show(np.zeros(0), np.zeros(0), {})
            return
        index = int(picked[-1])
        upto = dataclasses.replace(trajectory, data=trajectory.data[: index + 1])
        by = upto.dissipated_by   # over every row: a cause's share is found interval by interval
        energy = upto.data[:, ENERGY] - floor
        self.show(upto.data[picked, T], energy[picked], {cause: values[picked] for cause, values in by.items()})
        row = min(at, index)   # the key at the very row shown, not the nearest one drawn
        self._say({"energy": float(energy[row]), **{cause: float(by[cause][row]) for cause in self.causes}})

    def show(self, t: np.ndarray, energy: np.ndarray, dissipated_by: dict[str, np.ndarray],
             at: int | None = None) -> None:
        """Rows' times, the ball's energy above the floor and the energy each cause has taken so
        far (every cause of ``DISSIPATION_CAUSES``, zeros where it is off); the key's values
        at row ``at`` (None: the last)."""
        if not len(t):
            for item in (self._base, self.total, *self.tops.values()):
                item.setData([], [])
            self._say({})
            return
        self._base.setData(t, np.zeros(len(t)))
        level = np.asarray(energy, dtype=float).copy()
        self.tops["energy"].setData(t, level)
        row = len(t) - 1 if at is None else at
        values = {"energy": float(level[row])}
        for cause in self.causes:
            taken = np.asarray(dissipated_by[cause], dtype=float)
            level = level + taken
            self.tops[cause].setData(t, level)
            values[cause] = float(taken[row])
        self.total.setData(t, level)
        top = float(np.nanmax(level)) if np.isfinite(level).any() else 1.0
        low = min(0.0, float(np.nanmin(energy)))
        self.plot.setYRange(low, max(top, low + 1e-12) * 1.1, padding=0.0)
        self._say(values)

    def _say(self, values: dict[str, float]) -> None:
        """Each band's value at the moment shown, in the key: top band first, as they are stacked."""
        self.values = values
        lines = []
        for name, color, words in reversed(self._bands()):
            value = values.get(name)
            lines.append(f'<span style="color:{color}">■</span>&nbsp;{words}'
                         + ("" if value is None else f"&nbsp;{value:.3g}&nbsp;J"))
        if self.across:   # two bands a line: the key above the plots no wider than two of them
            lines = ["&nbsp;&nbsp; ".join(lines[k:k + 2]) for k in range(0, len(lines), 2)]
        text = "<br>".join(lines)
        self.key.setText(text, size=f"{self.text_size:g}pt", color="#222")

    def set_text_size(self, points: float) -> None:
        self.text_size = points
        self._say(self.values)


def title(name: str = "", color: str = "#333") -> str:
    """The budget plot's title; in compare mode it names the run it shows (the one the camera
    follows) in the run's colour."""
    return f'{SHORT_TITLE} <span style="color:{color}">● {name}</span>' if name else TITLE
