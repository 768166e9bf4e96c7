"""The numbers under the 3-D view: time, energy, its error, ‖RᵀR − I‖, normal force, speed,
and where the contact can slip or the ball fly (a scene beyond the 2011 model), the slip speed
and the energy dissipated (the energy error counts it as accounted for).

One row of values per run; with several runs each row starts with the run's colour and name,
shortened with "…" when the window is narrow (whole in its tooltip).
"""

from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.trajectory import ENERGY, FLYING, NORMAL_FORCE, T, VELOCITY

QUANTITIES = (("t", "Time t"), ("energy", "Energy E"), ("drift", "(E − E₀)/E₀"), ("orth", "‖RᵀR − I‖"),
              ("force", "Normal force F·N"), ("speed", "Speed |ċ|"), ("slip", "Slip |u|"),
              ("dissipated", "Dissipated"))
CONTACT_QUANTITIES = ("slip", "dissipated")   # shown for scenes beyond the 2011 model
# titles that change where the contact quantities are shown: shorter, so all fit a 1024-pixel window
TITLES = {False: {"drift": "(E − E₀)/E₀", "force": "Normal force F·N"},
          True: {"drift": "(E+D−E₀)/E₀", "force": "Force F·N"}}   # D: the energy dissipated
FORMATS = {"t": "{:.4f} s", "energy": "{:.8g} J", "drift": "{:.2e}", "orth": "{:.2e}", "force": "{:.5g} N",
           "speed": "{:.5g} m/s", "slip": "{:.3g} m/s", "dissipated": "{:.5g} J"}
WIDEST = {"t": 99.0, "energy": -0.12345678, "drift": -1e-10, "orth": 1e-10, "force": -0.12345,
          "speed": 0.12345, "slip": 0.123, "dissipated": 0.12345}   # a value as wide as each readout usually shows
TIPS = {"force": "The normal force F·N the surface pushes the ball with (0 in flight)",
        "drift": "The energy's change since the start, what sliding friction and landings dissipated (D) counted "
                 "as accounted for: the integrator's error alone",
        "slip": "Slip speed: how fast the ball's point at the contact moves over the surface (0 while it rolls; in "
                "flight, its point nearest the surface)",
        "dissipated": "Energy dissipated so far by sliding friction and by landings"}
SHORTEST_NAME = 14   # characters of a run's name kept, at least, before the "…" ("● RK4 Munthe-K…")


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
    """A run's colour and name, shortened with "…" to the width it is given (whole in its tooltip)."""

    def __init__(self, text: str, color: str, name: str):
        super().__init__(text, objectName=name)
        self.setToolTip(text)
        self.setStyleSheet(f"color: {color}; font-weight: bold;")

    def minimumSizeHint(self) -> QtCore.QSize:
        hint = super().minimumSizeHint()
        short = self.fontMetrics().horizontalAdvance(self.text()[:SHORTEST_NAME] + "…")
        return QtCore.QSize(min(hint.width(), short), hint.height())

    def paintEvent(self, event) -> None:
        rect = self.contentsRect()
        text = self.fontMetrics().elidedText(self.text(), QtCore.Qt.TextElideMode.ElideRight, rect.width())
        painter = QtGui.QPainter(self)
        self.style().drawItemText(painter, rect, int(self.alignment()), self.palette(), self.isEnabled(), text,
                                  self.foregroundRole())

    @property
    def elided(self) -> bool:
        return self.fontMetrics().horizontalAdvance(self.text()) > self.contentsRect().width()


class Readouts(QtWidgets.QWidget):
    """``readouts[key]`` is the first run's label for a quantity (``QUANTITIES``)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.grid = QtWidgets.QGridLayout(self)
        self.grid.setContentsMargins(6, 2, 6, 2)
        self.grid.setVerticalSpacing(1)
        self.titles: dict[str, QtWidgets.QLabel] = {}
        for i, (key, title) in enumerate(QUANTITIES):
            name = QtWidgets.QLabel(title, objectName=f"readoutTitle.{key}")
            name.setStyleSheet("color: #555;")
            name.setToolTip(TIPS.get(key, ""))
            self.grid.addWidget(name, 0, i + 1)
            self.titles[key] = name
        self.contact_shown = True
        self.rows: list[dict[str, QtWidgets.QLabel]] = []
        self.names: list[QtWidgets.QLabel] = []
        self.set_runs([None])

    def __getitem__(self, key: str) -> QtWidgets.QLabel:
        return self.rows[0][key]

    def set_runs(self, runs: list[tuple[str, str] | None]) -> None:
        """One row per run: ``(name, colour)``, or ``[None]`` for a single unnamed run. The
        first row's labels stay the same widgets (what is attached to them stays)."""
        for widget in [*self.names, *(label for row in self.rows[1:] for label in row.values())]:
            self.grid.removeWidget(widget)
            widget.hide()   # gone from the window now, not when the event loop deletes it
            widget.deleteLater()
        self.rows, self.names = self.rows[:1], []
        for r, run in enumerate(runs):
            if run is not None:
                name, color = run
                tag = _Name(f"● {name}", color, f"readout.run{r}")
                self.grid.addWidget(tag, r + 1, 0)
                self.names.append(tag)
            if r < len(self.rows):
                continue
            prefix = "readout." if r == 0 else f"readout{r}."
            row = {key: _Value(prefix + key, key) for key, _ in QUANTITIES}
            for i, label in enumerate(row.values()):
                self.grid.addWidget(label, r + 1, i + 1)
            self.rows.append(row)
        self.show_contact(self.contact_shown)
        self.clear()

    def show_contact(self, on: bool, columns: bool = True) -> None:
        """Show the slip speed and the energy dissipated (a scene whose ball can slip or fly), or
        not (the 2011 model: they are always 0); ``columns`` False: the titles say the energy
        error counts the dissipation, but its columns are left out (compare mode: they would
        not fit a row per run)."""
        for key, title in TITLES[on].items():
            self.titles[key].setText(title)
        on = on and columns
        self.contact_shown = on
        for key in CONTACT_QUANTITIES:
            self.titles[key].setVisible(on)
            for row in self.rows:
                row[key].setVisible(on)

    def clear(self) -> None:
        """Before a run: only the time, at 0."""
        for row in self.rows:
            for label in row.values():
                label.setText("—")
            row["t"].setText("0 s")

    def show_row(self, r: int, buffer, i: int) -> None:
        """Run r's values at row i of its ``RunBuffer``."""
        row = buffer.rows[i]
        flying = buffer.mode_of(i) == FLYING
        values = {"t": row[T], "energy": row[ENERGY], "drift": buffer.energy_error[i],
                  "orth": buffer.orthogonality_error[i], "force": 0.0 if flying else row[NORMAL_FORCE],
                  "speed": np.linalg.norm(row[VELOCITY]), "slip": buffer.slip_speed[i],
                  "dissipated": buffer.dissipated[i]}
        for key, label in self.rows[r].items():   # (a flight over no surface has no slip speed: —)
            label.setText(FORMATS[key].format(values[key]) if np.isfinite(values[key]) else "—")
