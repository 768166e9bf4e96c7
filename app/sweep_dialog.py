"""Analysis → Sweep…: the scene over a grid of one or two keys, as a map to click on.

The user picks one or two scene keys with their ranges and the outcome to colour by; the
sweep runs in a background thread (``rollball.sweep`` on every core) with a progress bar and
a Cancel button. Two keys give an image with a colour bar, one key a curve. Clicking a run
emits ``startChosen`` with the scene of that run, which the main window loads ready to run.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from rollball import Scene, get_method, sweep
from rollball.sweeps import KEYS, OUTCOMES, Grid
from rollball.sweeps.batch import sweep_method
from rollball.sweeps.grid import PARAMETER_PREFIX, value_of, with_values
from rollball.sweeps.plot import label

from .inputs import format_number
from .parameters import slider_range
from .worker import Worker

# What a fresh dialog offers: (key, half-width around the scene's value, N), first and second
DEFAULTS = (("start.vx", 2.0, 41), ("start.spin", 4.0, 21))
DEFAULT_COLOR = "min_normal_force"   # lift-off where it is ≤ 0; a value for every run


def tidy(values: np.ndarray) -> np.ndarray:
    """Grid values rounded to the grid's own precision (from a tenth of its spacing, in
    decimals, to as many more as keep every value within a millionth of a spacing): 1.95
    where the spacing is 0.05, not 1.9500000000000002; 1.75 where it is 1.25."""
    spacing = np.min(np.abs(np.diff(values))) if len(values) > 1 else 0.0
    if not spacing > 0:
        return values
    decimals = max(0, int(np.ceil(-np.log10(spacing))) + 1)
    while decimals < 17 and np.max(np.abs(np.round(values, decimals) - values)) > 1e-6 * spacing:
        decimals += 1
    return np.round(values, decimals)


def method_text(scene: Scene) -> str:
    """Which method and step every run of a sweep of the scene uses."""
    method = get_method(scene.integrator.method)
    try:
        sweep_method(scene)
    except ValueError as error:
        return f"Cannot sweep with {method.label}: {error}"
    return (f"Each run: {method.label}, step h = {scene.integrator.dt:g} s, to t = {scene.duration:g} s "
            f"(the scene's method and step; the ball's turning is not followed, so Munthe-Kaas or "
            f"classic makes no difference)")


def keys_of(scene: Scene) -> dict[str, str]:
    """The keys a sweep of the scene may vary, with their units: the start values and the
    like (``KEYS``), then the scene's parameters (``parameters.NAME``, no unit)."""
    return dict(KEYS) | {PARAMETER_PREFIX + name: "" for name in scene.parameter_names}


def parameter_span(scene: Scene, key: str) -> tuple[float, float]:
    """The range a parameter's row offers when it is chosen: the parameter's own (as its
    slider does), or one around its value."""
    name = key[len(PARAMETER_PREFIX):]
    p = next(p for p in scene.parameters if p.name == name)
    return slider_range(p.value, p.min, p.max)


# The range a contact key's row offers when it is chosen: friction from 0 to twice the scene's (to 1
# where it is null: always enough), restitution from 0 to 1.
CONTACT_SPANS = {
    "contact.friction": lambda contact: (0.0, 1.0 if contact.friction is None else max(2.0 * contact.friction, 0.1)),
    "contact.restitution": lambda contact: (0.0, 1.0),
}


class AxisRow:
    """One varied key: which, from, to, how many values. Choosing a parameter of the scene
    fills in its range."""

    def __init__(self, form: QtWidgets.QFormLayout, title: str, key: str, lo: float, hi: float, n: int,
                 optional: bool, scene: Scene):
        self.scene = scene
        self.key = QtWidgets.QComboBox(objectName=f"{title}.key")
        keys = keys_of(scene)
        for k, unit in keys.items():
            self.key.addItem(f"{k} ({unit})" if unit else k, k)
        self.key.setCurrentIndex(list(keys).index(key))
        self.key.setToolTip("The scene key to vary; parameters.NAME: a parameter of the formula "
                            "(the landscape is compiled once for the whole sweep)")
        self.lo = QtWidgets.QLineEdit(format_number(lo), objectName=f"{title}.from")
        self.hi = QtWidgets.QLineEdit(format_number(hi), objectName=f"{title}.to")
        self.n = QtWidgets.QSpinBox(objectName=f"{title}.n", minimum=1, maximum=10_000, value=n)
        row = QtWidgets.QHBoxLayout()
        self.enabled = QtWidgets.QCheckBox(objectName=f"{title}.enabled", checked=True) if optional else None
        if self.enabled is not None:
            row.addWidget(self.enabled)
            self.enabled.toggled.connect(lambda on: [w.setEnabled(on) for w in (self.key, self.lo, self.hi, self.n)])
        for text, widget in (("", self.key), ("from", self.lo), ("to", self.hi), ("values", self.n)):
            if text:
                row.addWidget(QtWidgets.QLabel(text))
            row.addWidget(widget, 2 if widget is self.key else 1)
        form.addRow(title, row)
        self.key.currentIndexChanged.connect(self._key_chosen)

    def _key_chosen(self) -> None:
        key = self.key.currentData()
        if key.startswith(PARAMETER_PREFIX):
            lo, hi = parameter_span(self.scene, key)
        elif key in CONTACT_SPANS:
            lo, hi = CONTACT_SPANS[key](self.scene.contact)
        else:
            return
        self.lo.setText(format_number(lo))
        self.hi.setText(format_number(hi))

    @property
    def used(self) -> bool:
        return self.enabled is None or self.enabled.isChecked()

    def values(self) -> tuple[str, np.ndarray]:
        """(key, values); ValueError naming the field when a number does not parse."""
        key = self.key.currentData()
        try:
            lo, hi = float(self.lo.text()), float(self.hi.text())
        except ValueError:
            raise ValueError(f"{key}: 'from' and 'to' must be numbers") from None
        n = self.n.value()
        return key, (np.array([lo]) if n == 1 else tidy(np.linspace(lo, hi, n)))


class SweepDialog(QtWidgets.QDialog):
    startChosen = QtCore.Signal(object)  # the Scene of the clicked run

    def __init__(self, scene: Scene, parent=None):
        super().__init__(parent)
        self.setWindowTitle("Sweep")
        self.setObjectName("sweepDialog")
        self.scene = scene
        self.table = None
        self.thread: Worker | None = None

        form = QtWidgets.QFormLayout()
        rows = []
        for title, (key, half, n) in zip(("Vary", "and"), DEFAULTS):
            centre = value_of(scene, key)
            rows.append(AxisRow(form, title, key, centre - half, centre + half, n, optional=title == "and",
                                scene=scene))
        self.rows = rows
        self.color = QtWidgets.QComboBox(objectName="color")
        for name in OUTCOMES:
            self.color.addItem(label(name), name)
        # an outcome every finished run has (lift-off, say, is blank on a scene where none lifts off)
        self.color.setCurrentIndex(OUTCOMES.index(DEFAULT_COLOR))
        self.color.currentIndexChanged.connect(self._show)
        form.addRow("Colour by", self.color)
        try:
            used = method_text(scene)
        except KeyError:
            used = ""
        self.method_note = QtWidgets.QLabel(used, objectName="method", wordWrap=True)
        self.method_note.setStyleSheet("color: #555;")
        form.addRow(self.method_note)

        self.run_button = QtWidgets.QPushButton("Run", objectName="run", default=True)
        self.run_button.clicked.connect(self.run)
        self.cancel_button = QtWidgets.QPushButton("Cancel", objectName="cancel", enabled=False)
        self.cancel_button.clicked.connect(self.cancel)
        self.progress = QtWidgets.QProgressBar(objectName="progress", minimum=0, maximum=1)
        self.progress.setFormat("%v of %m runs")
        self.status = QtWidgets.QLabel("Choose keys and ranges, then Run. Click the map to load a run's start.",
                                       objectName="status", wordWrap=True)
        buttons = QtWidgets.QHBoxLayout()
        buttons.addWidget(self.run_button)
        buttons.addWidget(self.cancel_button)
        buttons.addWidget(self.progress, 1)

        self.plot = pg.GraphicsLayoutWidget()
        self.plot.setObjectName("sweepPlot")
        self.plot.setBackground("w")
        self.plot_item = self.plot.addPlot(row=0, col=0)
        self.plot_item.showGrid(x=True, y=True, alpha=0.2)
        for side in ("left", "bottom"):   # (the labels carry the units: no "(x0.001)" scale on a friction's 0.1–0.6)
            self.plot_item.getAxis(side).enableAutoSIPrefix(False)
        self.image = pg.ImageItem(axisOrder="row-major")
        self.curve = pg.PlotDataItem(symbol="o", symbolSize=5, pen=pg.mkPen("#1f77b4"))
        self.colorbar = pg.ColorBarItem(colorMap=pg.colormap.get("viridis"), interactive=False, width=14)
        self.colorbar.setImageItem(self.image)
        self.plot.addItem(self.colorbar, row=0, col=1)
        self.colorbar.setVisible(False)
        self.plot.scene().sigMouseClicked.connect(self._clicked)
        self.note = QtWidgets.QLabel(objectName="note")

        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(form)
        layout.addLayout(buttons)
        layout.addWidget(self.plot, 1)
        layout.addWidget(self.note)
        layout.addWidget(self.status)
        self.resize(760, 640)

    # -- running ---------------------------------------------------------------------

    def vary(self) -> dict:
        return dict(row.values() for row in self.rows if row.used)

    def run(self) -> None:
        """Start the sweep in the background (one at a time)."""
        if self.thread is not None:
            return
        try:
            vary = self.vary()
            grid = Grid.of(vary)
        except ValueError as error:
            self.status.setText(str(error))
            return
        self.progress.setMaximum(grid.size)
        self.progress.setValue(0)
        self.status.setText(f"Running {grid.size:,} runs…")
        scene = self.scene
        self.thread = Worker(lambda progress, cancel: sweep(scene, vary, cancel=cancel, progress=progress),
                             name="sweep")
        # to methods of this dialog: what the worker says after the dialog has gone is dropped
        self.thread.progressed.connect(self._progressed)
        self.thread.done.connect(self._finished)
        self.thread.failed.connect(self._failed)
        self.thread.ended.connect(self._thread_ended)
        self.run_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        self.thread.start()

    def cancel(self) -> None:
        if self.thread is not None:
            self.thread.cancel(wait=False)

    def _progressed(self, args: tuple) -> None:
        self.progress.setValue(args[0])

    def _thread_ended(self) -> None:
        self.thread = None   # the worker lets go of itself
        self.run_button.setEnabled(True)
        self.cancel_button.setEnabled(False)

    def _failed(self, message: str) -> None:
        self.status.setText(f"The sweep could not run: {message}")

    def _finished(self, table) -> None:
        self.table = table
        counts = ", ".join(f"{n:,} {name}" for name, n in table.counts().items())
        done = int(table.done.sum())
        where = f"{table.workers} worker {'processes' if table.processes else 'threads'}"
        self.status.setText(f"{done:,} runs in {table.seconds:.2f} s on {where} ({counts})"
                            + (f" — stopped early: {table.error}" if table.error
                               else " — cancelled" if table.partial else "")
                            + ". Click a run to load its start into the main window.")
        self._show()

    # -- showing and picking -----------------------------------------------------------

    def _show(self) -> None:
        table = self.table
        if table is None:
            return
        name = self.color.currentData()
        values = table[name]
        item = self.plot_item
        item.clear()
        keys, axes = table.keys, table.grid.axes
        item.setLabel("bottom", label(keys[0]))
        blank = ~np.isfinite(values) & table.done
        why = {status: int(n) for status, n in zip(*np.unique(table["status"][blank], return_counts=True))}
        if "ok" in why:  # finished runs without this value
            why["no lift-off" if name == "liftoff_time" else f"no {name}"] = why.pop("ok")
        none = blank.sum() == table.done.sum()
        self.note.setText("" if not why else
                          ("No run has a value to show" if none else "Blank: runs without a value")
                          + " (" + ", ".join(f"{text}: {n:,}" for text, n in why.items()) + ")")
        if blank.sum() == table.done.sum():
            self.colorbar.setVisible(False)
        elif len(keys) == 1:
            item.setLabel("left", label(name))
            self.curve.setData(axes[0], values, connect="finite")
            item.addItem(self.curve)
            self.colorbar.setVisible(False)
        else:
            item.setLabel("left", label(keys[1]))
            order = np.ix_(np.argsort(axes[0]), np.argsort(axes[1]))
            grid = values.reshape(table.grid.shape)[order].T    # rows: the second key, ascending
            self.image.setImage(grid, autoLevels=False)
            (x0, x1), (y0, y1) = _span(axes[0]), _span(axes[1])
            self.image.setRect(QtCore.QRectF(x0, y0, x1 - x0, y1 - y0))
            item.addItem(self.image)
            finite = grid[np.isfinite(grid)]
            lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
            self.colorbar.setLevels((lo, hi if hi > lo else lo + 1.0))
            self.colorbar.setVisible(True)
        item.autoRange()

    def _clicked(self, event) -> None:
        if self.table is None or event.button() != QtCore.Qt.MouseButton.LeftButton:
            return
        point = self.plot_item.vb.mapSceneToView(event.scenePos())
        self.pick(point.x(), point.y())

    def pick(self, x: float, y: float) -> Scene | None:
        """The run nearest to (x, y) in the plot's coordinates: emit its scene and return it
        (None outside the grid or for a run whose scene was refused)."""
        table = self.table
        axes = table.grid.axes
        coords = (x,) if len(axes) == 1 else (x, y)
        index = []
        for axis, c in zip(axes, coords):
            lo, hi = _span(axis)
            if not lo <= c <= hi:
                return None
            index.append(int(np.argmin(np.abs(axis - c))))
        run = int(np.ravel_multi_index(index, table.grid.shape))
        if run in table.messages:
            self.status.setText(f"That run's scene was refused: {table.messages[run]}")
            return None
        values = [axis[i] for axis, i in zip(axes, index)]
        scene = with_values(table.scene, table.keys, values)
        self.status.setText("Loaded " + ", ".join(f"{k} = {format_number(v)}" for k, v in zip(table.keys, values))
                            + " into the main window: press Start to run it.")
        self.startChosen.emit(scene)
        return scene

    def closeEvent(self, event) -> None:
        if self.thread is not None:
            self.thread.cancel()
        super().closeEvent(event)


def _span(axis: np.ndarray) -> tuple[float, float]:
    """The extent of an axis's cells: half a spacing beyond its first and last values."""
    lo, hi = float(axis.min()), float(axis.max())
    half = 0.5 * (hi - lo) / (len(axis) - 1) if len(axis) > 1 else max(abs(lo) * 0.05, 0.5)
    return lo - half, hi + half
