"""Compare mode's summary: for every run, how it ended, its true error at the end and at its
largest, and what it cost. One column per run (in the run's colour), one row per quantity."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from rollball.trajectory import MODES

QUANTITIES = ("Status", "Error at end (m)", "Max error (m)", "Max energy error", "Steps", "Evaluations",
              "Compute time (s)", "Mode at end", "Landings", "Dissipated (J)")
TIPS = {"Error at end (m)": "Distance of the contact point from the reference's at the last common time",
        "Max error (m)": "Largest distance of the contact point from the reference's",
        "Max energy error": "Largest |E − E_ref| relative to the energy scale",
        "Evaluations": "Right-hand-side evaluations, rejected tries included",
        "Compute time (s)": "Time the worker spent advancing this run (the runs share two cores)",
        "Mode at end": "Rolling, sliding or flying at the last computed moment",
        "Landings": "How often the ball came down after a lift-off (each with its marker on the time slider)",
        "Dissipated (J)": "Energy taken by sliding friction and landings"}


def summary_values(run) -> list[str]:
    """A run's column: what is known so far (errors once the reference is)."""
    sim = run.simulation
    buffer = run.buffer
    values = [str(sim.status) if sim.status else "running", "…", "…", "…", f"{sim.steps:,}",
              f"{sim.evaluations:,}", f"{run.seconds:.2g}" if sim.done else "…",
              MODES[buffer.mode_of(len(buffer) - 1)] if len(buffer) else "…",
              f"{sum(1 for c in run.transitions if c.kind == 'landing')}",
              f"{buffer.dissipated[-1]:.3g}" if len(buffer) else "…"]
    if run.errors is not None:
        contact, energy = run.errors["contact"], run.errors["energy"]
        known = np.isfinite(contact)
        values[1:4] = ([f"{contact[known][-1]:.1e}", f"{contact[known].max():.1e}",   # 2 digits: narrow columns
                        f"{np.nanmax(energy):.1e}"] if known.any() else ["—"] * 3)
    return values


class SummaryTable(QtWidgets.QTableWidget):
    def __init__(self, parent=None):
        super().__init__(len(QUANTITIES), 0, parent, objectName="summary")
        self.setVerticalHeaderLabels(QUANTITIES)
        for i, name in enumerate(QUANTITIES):
            self.verticalHeaderItem(i).setToolTip(TIPS.get(name, ""))
        self.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.verticalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        # the dock takes the width every run's column needs, where the window has it
        self.setSizeAdjustPolicy(QtWidgets.QAbstractScrollArea.SizeAdjustPolicy.AdjustToContents)
        self.runs = []

    def set_runs(self, runs) -> None:
        self.runs = list(runs)
        self.setColumnCount(len(self.runs))
        for c, run in enumerate(self.runs):
            header = QtWidgets.QTableWidgetItem(f"{c + 1}")
            header.setForeground(pg.mkColor(run.color))
            header.setToolTip(run.label)
            self.setHorizontalHeaderItem(c, header)
        self.fill()

    def fill(self) -> None:
        for c, run in enumerate(self.runs):
            for r, text in enumerate(summary_values(run)):
                item = QtWidgets.QTableWidgetItem(text)
                item.setTextAlignment(QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter)
                self.setItem(r, c, item)

    def value(self, quantity: str, run: int) -> str:
        return self.item(QUANTITIES.index(quantity), run).text()
