"""Analysis → Fit to Track…: scene values fitted to the measured track (``rollball.fit``).

A table lists the values a fit may vary (the start, gravity, the contact's friction and
restitution, the scene's parameters), each with a box to fit it and optional bounds (blank: the
value's valid range). Fit runs in the background as the app's runs and sweeps do, saying how many
runs it has made; Cancel stops it before its next run. The result fills the table with each
estimate ± its standard error, says the correlations, the residual RMS against the track's noise
in words, and plots the residuals against time with the ±2σ band of the noise. Apply puts the
estimates into the scene as one undoable change (``applied``).
"""

from __future__ import annotations

import math
from pathlib import Path

import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from rollball import Scene, Track
from rollball.fit_options import LOSSES
from rollball.fitting import LIMITS, Fit, check_fit_keys, fit
from rollball.sweeps.grid import PARAMETER_PREFIX, unit, value_of

from .inputs import format_number
from .sweep_dialog import keys_of
from .worker import Worker

# The values a fit offers: those of a sweep that change how the ball moves and are not measured
# with a ruler or scale (not the mass, which does not change the motion, nor the radius; nor the
# step or duration, which a fit does not vary)
SKIPPED = ("ball.mass", "ball.radius", "integrator.dt", "duration")
LOSS_TEXT = {"linear": "Least squares", "soft_l1": "Robust: soft L1", "huber": "Robust: Huber",
             "cauchy": "Robust: Cauchy", "arctan": "Robust: arctan"}
AXIS_COLORS = {"x": "#1f77b4", "y": "#ff7f0e", "z": "#2ca02c"}
CHECK, KEY, SCENE, LOW, HIGH, ESTIMATE, ERROR = range(7)
HEADERS = ("Fit", "Value", "Scene", "From", "To", "Estimate", "± Std. error")


def fit_keys(scene: Scene) -> list[str]:
    """The keys the dialog lists for a scene, in the sweep's order."""
    return [key for key in keys_of(scene) if key not in SKIPPED]


def why_not(scene: Scene, key: str) -> str | None:
    """Why the scene's value cannot be fitted (a null friction: the ball always rolls), or None."""
    try:
        check_fit_keys(scene, [key])
    except ValueError as error:
        return str(error)
    return None


def default_range(scene: Scene, key: str) -> tuple[float, float]:
    """The bounds a fit uses when none are given (as ``rollball.fit`` does)."""
    if key.startswith(PARAMETER_PREFIX):
        p = scene.parameters[scene.parameter_names.index(key[len(PARAMETER_PREFIX):])]
        return (-math.inf if p.min is None else p.min), (math.inf if p.max is None else p.max)
    return LIMITS.get(key, (-math.inf, math.inf))


class FitDialog(QtWidgets.QDialog):
    applied = QtCore.Signal(object)   # the Fit to put into the scene

    def __init__(self, scene: Scene, track: Track, point: str, parent=None):
        super().__init__(parent)
        self.setWindowTitle("Fit to Track")
        self.setObjectName("fitDialog")
        self.scene, self.track, self.point = scene, track, point
        self.result: Fit | None = None
        self.thread: Worker | None = None
        self.runs = 0
        name = Path(track.source).name or "the track"
        what = "centre" if point == "center" else "contact point"
        heading = QtWidgets.QLabel(f"Fit the scene to {name}: {len(track)} positions ({', '.join(track.axes)}) "
                                   f"from t = {track.t[0]:.4g} to {track.t[-1]:.4g} s, of the ball's {what}. "
                                   f"Tick the values to fit; blank bounds are the value's valid range.",
                                   wordWrap=True)
        self.keys: list[str] = []
        self.table = QtWidgets.QTableWidget(0, len(HEADERS), objectName="values")
        self.table.setHorizontalHeaderLabels(HEADERS)
        self.table.verticalHeader().hide()
        self.bounds: dict[str, tuple[QtWidgets.QLineEdit, QtWidgets.QLineEdit]] = {}
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(KEY, QtWidgets.QHeaderView.ResizeMode.Stretch)
        self.table.itemChanged.connect(lambda _item: self._update_buttons())

        self.loss = QtWidgets.QComboBox(objectName="loss")
        for loss in LOSSES:
            self.loss.addItem(LOSS_TEXT[loss], loss)
        self.loss.setToolTip("Least squares, or a robust loss scaled by the track's noise: far-off positions "
                             "(frames that tracked something else) count less")
        self.fit_button = QtWidgets.QPushButton("Fit", objectName="fit", default=True)
        self.fit_button.clicked.connect(self.run)
        self.cancel_button = QtWidgets.QPushButton("Cancel", objectName="cancel", enabled=False)
        self.cancel_button.clicked.connect(self.cancel)
        self.progress = QtWidgets.QProgressBar(objectName="progress", minimum=0, maximum=1, textVisible=False)
        self.runs_label = QtWidgets.QLabel(objectName="runs")
        controls = QtWidgets.QHBoxLayout()
        controls.addWidget(QtWidgets.QLabel("Loss"))
        controls.addWidget(self.loss)
        controls.addWidget(self.fit_button)
        controls.addWidget(self.cancel_button)
        controls.addWidget(self.progress, 1)
        controls.addWidget(self.runs_label)

        self.status = QtWidgets.QLabel("Tick one or more values, then Fit.", objectName="status", wordWrap=True)
        self.status.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        self.plot = pg.PlotWidget(background="w")
        self.plot.setObjectName("residualPlot")
        self.plot.setLabel("bottom", "t", units="s")
        self.plot.setLabel("left", "track − model (mm)")
        self.plot.showGrid(x=True, y=True, alpha=0.25)
        self.plot.addLegend(offset=(-10, 10), brush=pg.mkBrush(255, 255, 255, 220), pen=pg.mkPen("#bbb"),
                            labelTextColor="#333")
        self.plot.setMinimumHeight(150)
        self.apply_button = QtWidgets.QPushButton("Apply to Scene", objectName="apply", enabled=False)
        self.apply_button.setToolTip("Put the estimates into the scene (Edit → Undo puts the old values back)")
        self.apply_button.clicked.connect(self.apply)
        close = QtWidgets.QPushButton("Close", objectName="close")
        close.clicked.connect(self.close)
        bottom = QtWidgets.QHBoxLayout()
        bottom.addStretch(1)
        bottom.addWidget(self.apply_button)
        bottom.addWidget(close)

        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(heading)
        layout.addWidget(self.table, 2)
        layout.addLayout(controls)
        layout.addWidget(self.status)
        layout.addWidget(self.plot, 2)
        layout.addLayout(bottom)
        self.resize(720, 680)
        self._fill()

    def set_scene(self, scene: Scene) -> None:
        """The scene shown in the main window changed: the next fit starts from it (the rows keep
        their boxes and bounds; a fit under way goes on from the scene it started from)."""
        if scene != self.scene:
            self.scene = scene
            self._fill()

    def _fill(self) -> None:
        """One row per value the scene offers, with the scene's value; what was ticked or typed stays."""
        ticked = set(self.checked())
        typed = {key: (lo.text(), hi.text()) for key, (lo, hi) in self.bounds.items()}
        estimates = {key: (self.table.item(row, ESTIMATE).text(), self.table.item(row, ERROR).text())
                     for row, key in enumerate(self.keys)}
        self.table.blockSignals(True)
        self.keys, self.bounds = fit_keys(self.scene), {}
        self.table.setRowCount(len(self.keys))
        for row, key in enumerate(self.keys):
            self._add_row(row, key)
            item = self.table.item(row, CHECK)
            if key in ticked and item.flags() & QtCore.Qt.ItemFlag.ItemIsEnabled:
                item.setCheckState(QtCore.Qt.CheckState.Checked)
            for edit, text in zip(self.bounds[key], typed.get(key, ("", ""))):
                edit.setText(text)
            for column, text in zip((ESTIMATE, ERROR), estimates.get(key, ("", ""))):
                self.table.item(row, column).setText(text)
        self.table.blockSignals(False)
        self._update_buttons()

    def _add_row(self, row: int, key: str) -> None:
        scene = self.scene
        reason = why_not(scene, key)
        check = QtWidgets.QTableWidgetItem()
        check.setFlags(QtCore.Qt.ItemFlag.ItemIsUserCheckable
                       | (QtCore.Qt.ItemFlag.ItemIsEnabled if reason is None else QtCore.Qt.ItemFlag.NoItemFlags))
        check.setCheckState(QtCore.Qt.CheckState.Unchecked)
        u = unit(key)
        label = QtWidgets.QTableWidgetItem(f"{key} ({u})" if u else key)
        value = value_of(scene, key)
        shown = QtWidgets.QTableWidgetItem(format_number(value) if math.isfinite(value) else "null")
        for item in (check, label, shown):
            item.setToolTip(reason or "")
        self.table.setItem(row, CHECK, check)
        for column, item in ((KEY, label), (SCENE, shown), (ESTIMATE, QtWidgets.QTableWidgetItem()),
                             (ERROR, QtWidgets.QTableWidgetItem())):
            item.setFlags(item.flags() & ~QtCore.Qt.ItemFlag.ItemIsEditable)
            self.table.setItem(row, column, item)
        lo, hi = default_range(scene, key)
        edits = []
        for column, limit in ((LOW, lo), (HIGH, hi)):
            edit = QtWidgets.QLineEdit(objectName=f"{key}.{'from' if column == LOW else 'to'}")
            edit.setPlaceholderText(format_number(limit) if math.isfinite(limit) else ("−∞" if column == LOW else "∞"))
            edit.setFrame(False)
            edit.setEnabled(reason is None)
            self.table.setCellWidget(row, column, edit)
            edits.append(edit)
        self.bounds[key] = (edits[0], edits[1])

    # -- what is asked -------------------------------------------------------------------

    def check(self, key: str, on: bool = True) -> None:
        """Tick (or untick) a value to fit."""
        self.table.item(self.keys.index(key), CHECK).setCheckState(
            QtCore.Qt.CheckState.Checked if on else QtCore.Qt.CheckState.Unchecked)

    def checked(self) -> list[str]:
        return [key for row, key in enumerate(self.keys)
                if self.table.item(row, CHECK).checkState() == QtCore.Qt.CheckState.Checked]

    def given_bounds(self) -> dict[str, tuple[float, float]]:
        """key -> (lo, hi) for the ticked values with a bound typed; ValueError naming the field."""
        out = {}
        for key in self.checked():
            lo_edit, hi_edit = self.bounds[key]
            if not (lo_edit.text().strip() or hi_edit.text().strip()):
                continue
            default = default_range(self.scene, key)
            pair = []
            for edit, side, fallback in ((lo_edit, "from", default[0]), (hi_edit, "to", default[1])):
                text = edit.text().strip()
                try:
                    pair.append(float(text) if text else fallback)
                except ValueError:
                    raise ValueError(f"{key}: the bound '{side}' must be a number, not {text!r}") from None
            out[key] = (pair[0], pair[1])
        return out

    def _update_buttons(self) -> None:
        idle = self.thread is None
        self.fit_button.setEnabled(idle and bool(self.checked()))
        self.cancel_button.setEnabled(not idle)

    # -- running -------------------------------------------------------------------------

    def run(self) -> None:
        """Fit the ticked values in the background (one fit at a time)."""
        if self.thread is not None:
            return
        keys = self.checked()
        try:
            bounds = self.given_bounds()
        except ValueError as error:
            self.status.setText(str(error))
            return
        scene, track, point, loss = self.scene, self.track, self.point, self.loss.currentData()
        self.result, self.runs = None, 0
        self.apply_button.setEnabled(False)
        self._clear_estimates()
        self.status.setText(f"Fitting {', '.join(keys)}…")
        self.runs_label.setText("0 runs")
        self.progress.setRange(0, 0)   # busy: how many runs a fit takes is not known beforehand
        self.thread = Worker(lambda progress, cancel: fit(scene, track, keys, bounds=bounds, loss=loss, point=point,
                                                          progress=progress, cancel=cancel), name="fit")
        # to methods of this dialog: what the worker says after the dialog has gone is dropped
        self.thread.progressed.connect(self._progressed)
        self.thread.done.connect(self._finished)
        self.thread.failed.connect(self._failed)
        self.thread.cancelled.connect(self._cancelled)
        self.thread.ended.connect(self._thread_ended)
        self.thread.start()
        self._update_buttons()

    def cancel(self) -> None:
        if self.thread is not None:
            self.thread.cancel(wait=False)

    def _progressed(self, args: tuple) -> None:
        self.runs = args[0]
        self.runs_label.setText(f"{self.runs} runs")

    def _thread_ended(self) -> None:
        self.thread = None   # the worker lets go of itself
        self.progress.setRange(0, 1)
        self.progress.setValue(1 if self.result is not None else 0)
        self._update_buttons()

    def _failed(self, message: str) -> None:
        self.status.setText(f"The fit could not be made: {message}")

    def _cancelled(self) -> None:
        self.status.setText(f"Cancelled after {self.runs} runs; nothing was fitted and the scene is unchanged.")

    def _clear_estimates(self) -> None:
        for row in range(len(self.keys)):
            self.table.item(row, ESTIMATE).setText("")
            self.table.item(row, ERROR).setText("")
        self.plot.clear()

    def _finished(self, result: Fit) -> None:
        self.result = result
        for key, value, error in zip(result.keys, result.values, result.errors):
            if key not in self.keys:
                continue   # a parameter the scene has lost while the fit ran
            row = self.keys.index(key)
            self.table.item(row, ESTIMATE).setText(f"{value:.6g}")
            self.table.item(row, ERROR).setText(f"{error:.2g}" if math.isfinite(error) else "not determined")
        res = result.residuals
        lines = [(f"{'Converged' if result.converged else 'Not converged'} after {result.runs} runs "
                  f"({result.seconds:.2f} s of CPU)."),
                 f"Residual RMS {res.rms * 1000:.3g} mm: {res.verdict()}."]
        for i in range(len(result.keys)):
            for j in range(i + 1, len(result.keys)):
                c = result.correlation[i, j]
                lines.append(f"Correlation of {result.keys[i]} and {result.keys[j]}: "
                             + (f"{c:+.3f}" if math.isfinite(c) else "not determined"))
        self.status.setText("\n".join(lines))
        self.apply_button.setEnabled(True)
        self._plot(res)

    def _plot(self, res) -> None:
        plot = self.plot
        plot.clear()
        t = res.track.t
        for k, axis in enumerate(res.track.axes):
            plot.plot(t, res.values[:, k] * 1000, pen=None, symbol="o", symbolSize=5,
                      symbolBrush=AXIS_COLORS[axis], symbolPen=None, name=axis)
        band = 2 * res.noise * 1000
        for level in (band, -band):
            plot.addItem(pg.InfiniteLine(pos=level, angle=0, pen=pg.mkPen("#777", style=QtCore.Qt.PenStyle.DashLine)))
        plot.setTitle("The fitted scene's residuals; dashed: ±2σ of the noise", size="9pt", color="#333")

    def estimates(self) -> dict[str, float]:
        """key -> estimate of the last fit (empty before one)."""
        return {} if self.result is None else dict(zip(self.result.keys, map(float, self.result.values)))

    def apply(self) -> None:
        if self.result is not None:
            self.applied.emit(self.result)
            self.apply_button.setEnabled(False)
            self.status.setText(self.status.text() + "\nApplied to the scene: Edit → Undo puts the old values back.")

    def closeEvent(self, event) -> None:
        if self.thread is not None:
            self.thread.cancel()
        super().closeEvent(event)

