"""The numbers under the 3-D view: time, energy, its error, ‖RᵀR − I‖, normal force, speed,
and where the contact can slip or the ball fly (a scene beyond the 2011 model), the contact's
mode (rolling, sliding, flying), the slip speed and the energy dissipated (the energy error
counts it as accounted for).

One row of values per run; with several runs each row starts with the run's colour and name.
Where the window is narrow a name drops what all runs' names share (", h = 0.001") and then is
shortened with "…", never so far that two runs read the same (whole in its tooltip); and the
quantities wrap onto a second line of titles and values rather than widen the window.
"""

from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.trajectory import ENERGY, FLYING, MODES, NORMAL_FORCE, T, VELOCITY

QUANTITIES = (("t", "Time t"), ("mode", "Mode"), ("energy", "Energy E"), ("drift", "(E − E₀)/E₀"),
              ("orth", "‖RᵀR − I‖"), ("force", "Normal force F·N"), ("speed", "Speed |ċ|"), ("slip", "Slip |u|"),
              ("dissipated", "Dissipated"))
MODE_QUANTITIES = ("mode",)                   # shown where the ball can change mode, in compare mode too
CONTACT_QUANTITIES = ("slip", "dissipated")   # shown for scenes beyond the 2011 model, one run at a time
LEAST_PER_LINE = 3     # quantities on a line, at least, when the readouts wrap
FORCE_ZERO = 1e-12     # times m·g: a normal force this small is shown as 0 (the lift-off moment's, located
                       # where F·N = 0 up to rounding)
# titles that change where the contact quantities are shown: shorter, so all fit a 1024-pixel window
TITLES = {False: {"drift": "(E − E₀)/E₀", "force": "Normal force F·N"},
          True: {"drift": "(E+D−E₀)/E₀", "force": "Force F·N"}}   # D: the energy dissipated
FORMATS = {"t": "{:.4f} s", "mode": "{}", "energy": "{:.8g} J", "drift": "{:.2e}", "orth": "{:.2e}",
           "force": "{:.5g} N", "speed": "{:.5g} m/s", "slip": "{:.3g} m/s", "dissipated": "{:.5g} J"}
WIDEST = {"t": 99.0, "mode": "sliding", "energy": -0.12345678, "drift": -1e-10, "orth": 1e-10, "force": -0.12345,
          "speed": 0.12345, "slip": 0.123, "dissipated": 0.12345}   # a value as wide as each readout usually shows
TIPS = {"mode": "The contact's mode: rolling (no slip), sliding (slipping against friction), flying "
                 "(off the surface) or resting (at rest, held by rolling resistance and friction)",
        "force": "The normal force F·N the surface pushes the ball with (0 in flight)",
        "drift": "The energy's change since the start, what sliding friction and landings dissipated (D) counted "
                 "as accounted for: the integrator's error alone",
        "slip": "Slip speed: how fast the ball's point at the contact moves over the surface (0 while it rolls; in "
                "flight, its point nearest the surface)",
        "dissipated": "Energy dissipated so far by sliding friction, landings, rolling resistance, spin friction and "
                      "air (each cause's share: the energy budget's key)"}


def distinct_names(names: list[str]) -> list[tuple[str, int]]:
    """Each run's name without the ", "-separated parts all runs share ("RK4 classic" for
    "RK4 classic, h = 0.001" beside "Euler classic, h = 0.001"), and how many of its characters
    tell it from every other run's: (short name, characters kept at least before a "…")."""
    parts = [name.split(", ") for name in names]
    shared = set.intersection(*(set(p) for p in parts)) if len(parts) > 1 else set()
    shorts = [", ".join(p for p in run if p not in shared) or name for run, name in zip(parts, names)]
    kept = []
    for i, short in enumerate(shorts):
        others = [o for j, o in enumerate(shorts) if j != i]
        k = next((k for k in range(1, len(short) + 1) if all(o[:k] != short[:k] for o in others)), len(short))
        kept.append((short, k))
    return kept


class _Value(QtWidgets.QLabel):
    """A value in a monospace font, as wide as its ``WIDEST`` text at least: values that come
    and go as the ball moves do not re-lay out the window."""

    def __init__(self, name: str, key: str):
        super().__init__("—", objectName=name)
        self.widest = FORMATS[key].format(WIDEST[key])
        self.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        font = self.font()
        font.setFamily("monospace")
        font.setStyleHint(QtGui.QFont.StyleHint.Monospace)
        self.setFont(font)

    def _at_least(self, size: QtCore.QSize) -> QtCore.QSize:
        width = self.fontMetrics().horizontalAdvance(self.widest) + 2 * self.margin() + 4
        return QtCore.QSize(max(size.width(), width), size.height())

    def sizeHint(self) -> QtCore.QSize:
        return self._at_least(super().sizeHint())

    def minimumSizeHint(self) -> QtCore.QSize:
        return self._at_least(QtCore.QSize(0, super().minimumSizeHint().height()))


class _Name(QtWidgets.QLabel):
    """A run's colour and name: whole where it fits, else without what all runs share, shortened
    with "…" to the width it is given but never below the characters that tell it from the
    other runs (whole in its tooltip)."""

    def __init__(self, text: str, color: str, name: str, short: str = "", kept: int = 0):
        super().__init__(text, objectName=name)
        self.short = f"● {short}" if short else text
        self.kept = len("● ") + kept if short else len(text)
        self.setToolTip(text)
        self.setStyleSheet(f"color: {color}; font-weight: bold;")

    def minimumSizeHint(self) -> QtCore.QSize:
        hint = super().minimumSizeHint()
        least = self.fontMetrics().horizontalAdvance(self.short[:self.kept] + "…") + 2
        return QtCore.QSize(min(hint.width(), least), hint.height())

    def shown_text(self) -> str:
        """What is drawn in the width the label has."""
        width, metrics = self.contentsRect().width(), self.fontMetrics()
        if metrics.horizontalAdvance(self.text()) <= width:
            return self.text()
        return metrics.elidedText(self.short, QtCore.Qt.TextElideMode.ElideRight, width)

    def paintEvent(self, event) -> None:
        painter = QtGui.QPainter(self)
        self.style().drawItemText(painter, self.contentsRect(), int(self.alignment()), self.palette(),
                                  self.isEnabled(), self.shown_text(), self.foregroundRole())

    @property
    def elided(self) -> bool:
        return self.shown_text() != self.text()


class Readouts(QtWidgets.QWidget):
    """``readouts[key]`` is the first run's label for a quantity (``QUANTITIES``)."""

    runsChanged = QtCore.Signal()   # a row per run: their height changed

    def __init__(self, parent=None):
        super().__init__(parent)
        self.grid = QtWidgets.QGridLayout(self)
        self.grid.setContentsMargins(6, 2, 6, 2)
        self.grid.setVerticalSpacing(1)
        self.titles: dict[str, QtWidgets.QLabel] = {}
        for key, title in QUANTITIES:
            name = QtWidgets.QLabel(title, objectName=f"readoutTitle.{key}")
            name.setStyleSheet("color: #555;")
            name.setToolTip(TIPS.get(key, ""))
            self.titles[key] = name
        self.contact_shown = True
        self.mode_shown = True
        self.per_line = len(QUANTITIES)   # quantities on a line of titles and values
        self.rows: list[dict[str, QtWidgets.QLabel]] = []
        self.names: list[QtWidgets.QLabel] = []
        self.dots: list[QtWidgets.QLabel] = []   # the runs' colours again where the quantities wrap
        self.set_runs([None])

    def __getitem__(self, key: str) -> QtWidgets.QLabel:
        return self.rows[0][key]

    def set_runs(self, runs: list[tuple[str, str] | None]) -> None:
        """One row per run: ``(name, colour)``, or ``[None]`` for a single unnamed run. The
        first row's labels stay the same widgets (what is attached to them stays)."""
        for widget in [*self.names, *self.dots, *(label for row in self.rows[1:] for label in row.values())]:
            self.grid.removeWidget(widget)
            widget.hide()   # gone from the window now, not when the event loop deletes it
            widget.deleteLater()
        self.rows, self.names, self.dots = self.rows[:1], [], []
        named = [run for run in runs if run is not None]
        shorts = distinct_names([name for name, _ in named]) if len(named) > 1 else [("", 0)] * len(named)
        for r, ((name, color), (short, kept)) in enumerate(zip(named, shorts)):
            self.names.append(_Name(f"● {name}", color, f"readout.run{r}", short, kept))
            dot = QtWidgets.QLabel("●", objectName=f"readout.dot{r}")
            dot.setStyleSheet(f"color: {color}; font-weight: bold;")
            dot.setToolTip(name)
            self.dots.append(dot)
        for r in range(len(self.rows), len(runs)):
            prefix = "readout." if r == 0 else f"readout{r}."
            self.rows.append({key: _Value(prefix + key, key) for key, _ in QUANTITIES})
        self.show_contact(self.mode_shown, self.contact_shown)
        self.clear()
        self.runsChanged.emit()

    def show_contact(self, on: bool, columns: bool = True) -> None:
        """Show the mode, the slip speed and the energy dissipated (a scene whose ball can slip or
        fly), or not (the 2011 model: it always rolls, they are always 0); ``columns`` False: the
        titles say the energy error counts the dissipation and the mode is shown, but the slip's
        and dissipation's columns are left out (compare mode: they would not fit a row per run)."""
        for key, title in TITLES[on].items():
            self.titles[key].setText(title)
        self.mode_shown = on
        self.contact_shown = on and columns
        self._place()

    def shown_keys(self) -> list[str]:
        hidden = (() if self.mode_shown else MODE_QUANTITIES) + (() if self.contact_shown else CONTACT_QUANTITIES)
        return [key for key, _ in QUANTITIES if key not in hidden]

    # -- wrapping --------------------------------------------------------------------

    def _spacing(self) -> int:
        """Between two columns: a space of the values' font and a little more (a value never runs
        into the next)."""
        label = self.rows[0]["t"]
        label.ensurePolished()
        return label.fontMetrics().horizontalAdvance(" ") + 2

    def width_for(self, per_line: int) -> int:
        """The least width of the readouts with ``per_line`` quantities on a line."""
        keys, spacing = self.shown_keys(), self._spacing()
        columns = []
        for j in range(min(per_line, len(keys))):
            widgets = [w for k in keys[j::per_line] for w in (self.titles[k], *(row[k] for row in self.rows))]
            for widget in widgets:
                widget.ensurePolished()
            columns.append(max(w.minimumSizeHint().width() for w in widgets))
        if self.names:
            for name in self.names:
                name.ensurePolished()
            columns.append(max(name.minimumSizeHint().width() for name in self.names))
        margins = self.grid.contentsMargins()
        return sum(columns) + spacing * (len(columns) - 1) + margins.left() + margins.right()

    def one_line_width(self) -> int:
        return self.width_for(len(QUANTITIES))

    def _fitting(self, width: int) -> int:
        """The most quantities on a line that ``width`` holds (at least ``LEAST_PER_LINE``)."""
        most = len(self.shown_keys())
        return next((n for n in range(most, LEAST_PER_LINE, -1) if self.width_for(n) <= width), LEAST_PER_LINE)

    def _place(self, per_line: int | None = None) -> None:
        """Lay out the titles, names and values: ``per_line`` quantities on a line, each further
        line of titles and values below the first (its rows marked with the runs' colours)."""
        keys, hidden = self.shown_keys(), [key for key, _ in QUANTITIES if key not in self.shown_keys()]
        self.per_line = per_line = min(per_line or self._fitting(self.width()), len(keys))
        for widget in [*self.titles.values(), *self.names, *self.dots, *(w for row in self.rows for w in row.values())]:
            self.grid.removeWidget(widget)
        for key in hidden:
            self.titles[key].hide()
            for row in self.rows:
                row[key].hide()
        for row in range(self.grid.rowCount()):
            self.grid.setRowStretch(row, 0)
        lines = -(-len(keys) // per_line)
        for line in range(lines):
            top = line * (len(self.rows) + 1)
            for j, key in enumerate(keys[line * per_line:(line + 1) * per_line]):
                self.grid.addWidget(self.titles[key], top, j + 1)
                self.titles[key].show()
                for r, row in enumerate(self.rows):
                    self.grid.addWidget(row[key], top + 1 + r, j + 1)
                    row[key].show()
            marks = self.names if line == 0 else self.dots
            for r, mark in enumerate(marks):
                self.grid.addWidget(mark, top + 1 + r, 0)
                mark.show()
        for dot in self.dots if lines == 1 else ():
            dot.hide()
        self.grid.setHorizontalSpacing(self._spacing())
        self.updateGeometry()

    def height_for(self, width: int) -> int:
        """The least height of the readouts laid out in ``width`` pixels."""
        lines = -(-len(self.shown_keys()) // self._fitting(width))
        label = self.rows[0]["t"]
        row = max(label.sizeHint().height(), self.titles["t"].sizeHint().height()) + self.grid.verticalSpacing()
        margins = self.grid.contentsMargins()
        return lines * (len(self.rows) + 1) * row + margins.top() + margins.bottom()

    def fit_width(self, width: int) -> None:
        """Lay the quantities out for ``width`` pixels now (before a resize to it)."""
        self._place(self._fitting(width))

    def minimumSizeHint(self) -> QtCore.QSize:   # the quantities wrap rather than widen the window
        return QtCore.QSize(self.width_for(LEAST_PER_LINE), super().minimumSizeHint().height())

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        if self._fitting(event.size().width()) != self.per_line:
            self._place()

    def changeEvent(self, event) -> None:
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.FontChange):
            for label in self.findChildren(QtWidgets.QLabel):
                label.ensurePolished()
            self._place()

    # -- values ----------------------------------------------------------------------

    def clear(self) -> None:
        """Before a run: only the time, at 0."""
        for row in self.rows:
            for label in row.values():
                label.setText("—")
            row["t"].setText("0 s")

    def show_row(self, r: int, buffer, i: int) -> None:
        """Run r's values at row i of its ``RunBuffer``."""
        row = buffer.rows[i]
        mode = buffer.mode_of(i)
        force = 0.0 if mode == FLYING or abs(row[NORMAL_FORCE]) <= FORCE_ZERO * buffer.mass * buffer.gravity \
            else row[NORMAL_FORCE]
        values = {"t": row[T], "mode": MODES[mode], "energy": row[ENERGY], "drift": buffer.energy_error[i],
                  "orth": buffer.orthogonality_error[i], "force": force,
                  "speed": np.linalg.norm(row[VELOCITY]), "slip": buffer.slip_speed[i],
                  "dissipated": buffer.dissipated[i]}
        for key, label in self.rows[r].items():   # (a flight over no surface has no slip speed: —)
            value = values[key]
            label.setText(value if isinstance(value, str) else
                          FORMATS[key].format(value) if np.isfinite(value) else "—")
