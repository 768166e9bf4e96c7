"""The numbers under the 3-D view: time, energy, its error, ‖RᵀR − I‖, normal force, speed.

One row of values per run; with several runs each row starts with the run's colour and name.
"""

from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.trajectory import ENERGY, NORMAL_FORCE, T, VELOCITY

QUANTITIES = (("t", "Time t"), ("energy", "Energy E"), ("drift", "(E − E₀)/E₀"), ("orth", "‖RᵀR − I‖"),
              ("force", "Normal force F·N"), ("speed", "Speed |ċ|"))


def _value_label(name: str) -> QtWidgets.QLabel:
    label = QtWidgets.QLabel("—", objectName=name)
    label.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
    label.setMinimumWidth(96)   # six of them fit a 1024-pixel window beside the scene fields
    font = label.font()
    font.setFamily("monospace")
    font.setStyleHint(QtGui.QFont.StyleHint.Monospace)
    label.setFont(font)
    return label


class Readouts(QtWidgets.QWidget):
    """``readouts[key]`` is the first run's label for a quantity (``QUANTITIES``)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.grid = QtWidgets.QGridLayout(self)
        self.grid.setContentsMargins(6, 2, 6, 2)
        self.grid.setVerticalSpacing(1)
        for i, (_, title) in enumerate(QUANTITIES):
            name = QtWidgets.QLabel(title)
            name.setStyleSheet("color: #555;")
            self.grid.addWidget(name, 0, i + 1)
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
            widget.deleteLater()
        self.rows, self.names = self.rows[:1], []
        for r, run in enumerate(runs):
            if run is not None:
                name, color = run
                tag = QtWidgets.QLabel(f"● {name}", objectName=f"readout.run{r}")
                tag.setStyleSheet(f"color: {color}; font-weight: bold;")
                self.grid.addWidget(tag, r + 1, 0)
                self.names.append(tag)
            if r < len(self.rows):
                continue
            prefix = "readout." if r == 0 else f"readout{r}."
            row = {key: _value_label(prefix + key) for key, _ in QUANTITIES}
            for i, label in enumerate(row.values()):
                self.grid.addWidget(label, r + 1, i + 1)
            self.rows.append(row)
        self.clear()

    def clear(self) -> None:
        """Before a run: only the time, at 0."""
        for row in self.rows:
            for label in row.values():
                label.setText("—")
            row["t"].setText("0 s")

    def show_row(self, r: int, buffer, i: int) -> None:
        """Run r's values at row i of its ``RunBuffer``."""
        labels, row = self.rows[r], buffer.rows[i]
        labels["t"].setText(f"{row[T]:.4f} s")
        labels["energy"].setText(f"{row[ENERGY]:.8g} J")
        labels["drift"].setText(f"{buffer.energy_error[i]:.2e}")
        labels["orth"].setText(f"{buffer.orthogonality_error[i]:.2e}")
        labels["force"].setText(f"{row[NORMAL_FORCE]:.5g} N")
        labels["speed"].setText(f"{np.linalg.norm(row[VELOCITY]):.5g} m/s")
