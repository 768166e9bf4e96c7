"""A scene's named parameters in the app: the landscape with their values, and a slider per
parameter in the Scene panel, where parameters are added and removed.

The compiled landscape takes the parameters' values as arguments (docs/design.md §3, §4), so a
new value compiles nothing: ``Valued`` is the scene's landscape with its values, and draws,
plays back and evaluates like a landscape without parameters. ``ParameterRows`` shows a slider
per parameter over its range (or, without one, ``value ± max(1, |value|)``) with the value's
field beside it; dragging changes the scene at once, as fast as it is drawn. "Add…" asks for
a name, a value and an optional range (``ParameterDialog``, checked as a scene file is), and a
row's × removes it; the other rows keep what was typed in them, and the formula is checked
again with the new names (a formula still using a removed name is refused, its text kept).
"""

from __future__ import annotations

import math
import sys

import numpy as np
from PySide6 import QtCore, QtWidgets

from rollball import Scene, SceneError
from rollball.formula import MAX_PARAMETERS
from rollball.landscape import Landscape, landscape_of

SLIDER_STEPS = 1000      # positions of a slider between the ends of its range


class Valued:
    """A landscape with its parameters' values: ``evaluate``, ``height`` and ``record`` need no
    values (everything else is the landscape's own)."""

    def __init__(self, landscape: Landscape, values=()):
        self.landscape = landscape
        self.values = tuple(float(v) for v in values)

    def evaluate(self, x, y, values=None) -> np.ndarray:
        return self.landscape.evaluate(x, y, self.values if values is None else values)

    def height(self, x, y, values=None) -> np.ndarray:
        return self.evaluate(x, y, values)[0]

    def record(self, values=None) -> np.ndarray:
        return self.landscape.record(self.values if values is None else values)

    def __getattr__(self, name):
        return getattr(self.landscape, name)

    def __repr__(self) -> str:
        return f"Valued({self.landscape!r}, {self.values!r})"


def valued(scene: Scene) -> Valued:
    """The scene's (shared, cached) landscape with its parameters' values."""
    return Valued(landscape_of(scene), scene.parameter_values)


def slider_range(value: float, low: float | None, high: float | None) -> tuple[float, float]:
    """The range a slider offers: the parameter's own, or ``value ± max(1, |value|)`` (within
    the finite floats: the range of a value near the largest float ends there)."""
    if low is not None and high is not None:
        return low, high
    half = max(1.0, abs(value))
    return max(value - half, -sys.float_info.max), min(value + half, sys.float_info.max)


def slider_value(position: int, low: float, high: float) -> float:
    """The value at a slider position, rounded to the slider's resolution (a thousandth of the
    range, to one more digit): what a drag gives reads as a plain number. Finite for any finite
    range, even one whose width is not a finite float (the ends are weighed, not subtracted)."""
    t = min(max(position / SLIDER_STEPS, 0.0), 1.0)
    value = low * (1.0 - t) + high * t if t < 1.0 else high
    step = high / SLIDER_STEPS - low / SLIDER_STEPS
    if not (step > 0 and math.isfinite(step) and math.isfinite(value)):
        return float(value) if math.isfinite(value) else float(low)
    digits = 1 - math.floor(math.log10(step))
    try:
        rounded = round(value, max(0, digits))
    except OverflowError:   # (rounding at the largest floats may leave them)
        return float(value)
    return float(rounded) if math.isfinite(rounded) else float(value)


def slider_position(value: float, low: float, high: float) -> int:
    if not high > low or math.isnan(value) or value <= low:
        return 0
    if value >= high:
        return SLIDER_STEPS
    width = high / 2 - low / 2     # halves: finite even where high - low is not
    share = (value / 2 - low / 2) / width if width > 0 else 0.5
    return int(round(min(max(share, 0.0), 1.0) * SLIDER_STEPS))


def format_number(value: float) -> str:
    return repr(float(value))


class ParameterRow(QtWidgets.QWidget):
    """One parameter: its name, a slider over its range and the value's field (with the
    message under it, hidden while the value is valid)."""

    def __init__(self, name: str, value: float, low: float | None, high: float | None, parent=None):
        super().__init__(parent)
        self.name = name
        self.declared = (low, high) if low is not None else None   # written back to the file
        self.low, self.high = slider_range(value, low, high)
        self.label = QtWidgets.QLabel(name, objectName=f"parameters.{name}.label")
        self.label.setMinimumWidth(24)
        self.slider = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal, objectName=f"parameters.{name}.slider",
                                        minimum=0, maximum=SLIDER_STEPS)
        self.slider.setPageStep(SLIDER_STEPS // 20)
        self.edit = QtWidgets.QLineEdit(objectName=f"parameters.{name}")
        self.edit.setMaximumWidth(90)
        self.message = QtWidgets.QLabel(wordWrap=True, objectName=f"parameters.{name}.error")
        self.message.setTextFormat(QtCore.Qt.TextFormat.PlainText)
        self.message.hide()
        self.remove = QtWidgets.QToolButton(text="\u00d7", objectName=f"parameters.{name}.remove", autoRaise=True)
        self.remove.setToolTip(f"Remove parameter {name} (the formula must then do without it)")
        self._set_tips()
        v = QtWidgets.QVBoxLayout(self)
        v.setContentsMargins(0, 0, 0, 0)
        v.setSpacing(1)
        h = QtWidgets.QHBoxLayout()
        h.addWidget(self.label)
        h.addWidget(self.slider, 1)
        h.addWidget(self.edit)
        h.addWidget(self.remove)
        v.addLayout(h)
        v.addWidget(self.message)
        self.set_value(value)

    def _set_tips(self) -> None:
        where = "its range" if self.declared else "no range given: around its value"
        tip = f"Parameter {self.name} of the formula, {self.low:g} to {self.high:g} ({where})"
        self.slider.setToolTip(tip)
        self.edit.setToolTip(f"Parameter {self.name} of the formula (any number; the slider offers "
                             f"{self.low:g} to {self.high:g})")

    def set_value(self, value: float) -> None:
        """Show ``value`` in the field and on the slider (no signals)."""
        if self.declared is None and not self.low <= value <= self.high:
            self.low, self.high = slider_range(value, None, None)   # a value typed far away: around it
            self._set_tips()
        self.edit.setText(format_number(value))
        blocked = self.slider.blockSignals(True)
        self.slider.setValue(slider_position(value, self.low, self.high))
        self.slider.blockSignals(blocked)

    def value_at(self, position: int) -> float:
        return slider_value(position, self.low, self.high)

    def spec(self, value: float):
        """The parameter as a scene file holds it."""
        if self.declared is None:
            return value
        return {"value": value, "min": self.declared[0], "max": self.declared[1]}


class ParameterRows(QtWidgets.QWidget):
    """A row per parameter of the scene under a title with an "Add…" button. ``edited(name)``
    when a value is typed (the panel waits for a pause), ``dragged(name)`` when a slider moved
    (the panel applies it at once), ``changed(name)`` when a parameter was added or removed
    (applied at once); ``gesture`` counts slider drags, so the changes of one drag make one
    undo step."""

    edited = QtCore.Signal(str)
    dragged = QtCore.Signal(str)
    changed = QtCore.Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.rows: dict[str, ParameterRow] = {}
        self.gesture = 0            # increases with every drag begun
        self.dragging = False
        self._layout = QtWidgets.QVBoxLayout(self)
        self._layout.setContentsMargins(0, 2, 0, 0)
        self._layout.setSpacing(2)
        self.title = QtWidgets.QLabel("Parameters")
        self.title.setToolTip("The formula's named numbers: drag a slider to reshape the landscape; "
                              "nothing is compiled")
        self.add_button = QtWidgets.QPushButton("Add Parameter\u2026", objectName="parameters.add")
        self.add_button.setToolTip("A named number for the formula (e.g. a in a*sin(x)), with a slider")
        self.add_button.clicked.connect(lambda: self.ask_new(self.propose()))
        self.propose = lambda: ""   # the name the dialog proposes (the panel's: one the formula lacks)
        self.dialog: ParameterDialog | None = None
        self.removed: dict[str, tuple[str, str, str]] = {}   # a removed row's value and range, as typed
        header = QtWidgets.QHBoxLayout()
        header.addWidget(self.title)
        header.addStretch(1)
        header.addWidget(self.add_button)
        self._layout.addLayout(header)
        self._show_title()

    @property
    def edits(self) -> dict[str, QtWidgets.QLineEdit]:
        return {f"parameters.{name}": row.edit for name, row in self.rows.items()}

    @property
    def messages(self) -> dict[str, QtWidgets.QLabel]:
        return {f"parameters.{name}": row.message for name, row in self.rows.items()}

    @property
    def labels(self) -> dict[str, QtWidgets.QLabel]:
        return {f"parameters.{name}": row.label for name, row in self.rows.items()}

    def set_parameters(self, parameters) -> bool:
        """Show the scene's parameters; the rows are made anew only when the names or declared
        ranges differ (so a slider's range stays put under undo). True when they were."""
        wanted = [(p.name, None if p.min is None else (p.min, p.max)) for p in parameters]
        if wanted == [(name, row.declared) for name, row in self.rows.items()]:
            for p in parameters:
                self.rows[p.name].set_value(p.value)
            return False
        for row in self.rows.values():
            self._layout.removeWidget(row)
            row.deleteLater()
        self.rows = {}
        for p in parameters:
            self._add_row(p.name, p.value, p.min, p.max)
        self._show_title()
        return True

    def _add_row(self, name: str, value: float, low: float | None, high: float | None) -> ParameterRow:
        row = ParameterRow(name, value, low, high, self)
        row.edit.textEdited.connect(lambda _text, n=name: self.edited.emit(n))
        row.slider.valueChanged.connect(lambda position, n=name: self._slid(n, position))
        row.slider.sliderPressed.connect(self._pressed)
        row.slider.sliderReleased.connect(self._released)
        row.remove.clicked.connect(lambda _=False, n=name: self.remove(n))
        self._layout.addWidget(row)
        self.rows[name] = row
        return row

    def _show_title(self) -> None:
        self.title.setText("Parameters" if self.rows else "No parameters")
        self.title.setEnabled(bool(self.rows))
        self.add_button.setEnabled(len(self.rows) < MAX_PARAMETERS)

    def add(self, name: str, value: float, low: float | None = None, high: float | None = None) -> None:
        """A new row (the others keep what was typed in them); ``changed(name)``."""
        self._add_row(name, value, low, high)
        self._show_title()
        self.changed.emit(name)

    def remove(self, name: str) -> None:
        """Take a parameter's row away; ``changed(name)``."""
        row = self.rows.pop(name)
        low, high = row.declared or ("", "")
        self.removed[name] = (row.edit.text(), "" if low == "" else format_number(low),
                              "" if high == "" else format_number(high))
        self._layout.removeWidget(row)
        row.hide()
        row.deleteLater()
        self._show_title()
        self.changed.emit(name)

    def ask_new(self, name: str = "") -> "ParameterDialog":
        """The dialog asking for a new parameter (``name`` proposed, with its value and range
        as they were if it was removed); on OK it is added."""
        if self.dialog is not None:
            self.dialog.close()
        self.dialog = ParameterDialog(tuple(self.rows), name, self)
        if name in self.removed:
            for edit, text in zip((self.dialog.value, self.dialog.low, self.dialog.high), self.removed[name]):
                edit.setText(text)
        self.dialog.chosen.connect(self.add)
        self.dialog.setAttribute(QtCore.Qt.WidgetAttribute.WA_DeleteOnClose)
        self.dialog.destroyed.connect(lambda *_: setattr(self, "dialog", None))
        self.dialog.open()
        return self.dialog

    def _pressed(self) -> None:
        self.gesture += 1
        self.dragging = True

    def _released(self) -> None:
        self.dragging = False

    def _slid(self, name: str, position: int) -> None:
        row = self.rows[name]
        row.edit.setText(format_number(row.value_at(position)))
        if not self.dragging:       # a click on the track or a key: a step of its own
            self.gesture += 1
        self.dragged.emit(name)

    def specs(self) -> tuple[dict, str | None, str | None]:
        """(parameters as a scene file holds them, None, None), or ({}, key, message) for a
        value that is not a number."""
        out = {}
        for name, row in self.rows.items():
            text = row.edit.text().strip().replace("\u2212", "-")
            try:
                value = float(text)
            except ValueError:
                return {}, f"parameters.{name}", f"{name}: " + ("not a number" if text else "missing")
            out[name] = row.spec(value)
        return out, None, None


class ParameterDialog(QtWidgets.QDialog):
    """A new parameter: its name, value and, optionally, the range its slider offers. Checked
    as a scene file is (the core's own rules: an identifier that is not x, y, pi, e or a
    function's name, not taken, finite numbers, min below max); OK only when it passes, with
    the reason beside the field otherwise. ``chosen(name, value, min, max)`` on OK."""

    chosen = QtCore.Signal(str, float, object, object)

    def __init__(self, taken: tuple[str, ...], name: str = "", parent=None):
        super().__init__(parent)
        self.setWindowTitle("Add Parameter")
        self.setObjectName("parameterDialog")
        self.taken = taken
        self.name = QtWidgets.QLineEdit(name, objectName="name", placeholderText="e.g. a")
        self.value = QtWidgets.QLineEdit("1.0", objectName="value")
        self.low = QtWidgets.QLineEdit(objectName="min", placeholderText="none")
        self.high = QtWidgets.QLineEdit(objectName="max", placeholderText="none")
        self.name.setToolTip("A name the formula can use: letters, digits and _, not x, y, pi, e nor a "
                             "function's name")
        self.low.setToolTip("The slider's range (optional: both ends or neither; the value may lie outside)")
        self.high.setToolTip(self.low.toolTip())
        self.message = QtWidgets.QLabel(objectName="message", wordWrap=True)
        self.message.setTextFormat(QtCore.Qt.TextFormat.PlainText)
        self.message.setStyleSheet("color: #c0392b;")
        self.buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Ok
                                                  | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        self.ok = self.buttons.button(QtWidgets.QDialogButtonBox.StandardButton.Ok)
        self.ok.setText("Add")
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        form = QtWidgets.QFormLayout()
        form.addRow("Name", self.name)
        form.addRow("Value", self.value)
        rng = QtWidgets.QHBoxLayout()
        rng.addWidget(self.low)
        rng.addWidget(QtWidgets.QLabel("to"))
        rng.addWidget(self.high)
        form.addRow("Slider range", rng)
        form.addRow(self.message)
        column = QtWidgets.QVBoxLayout(self)
        column.addLayout(form)
        column.addStretch(1)              # room to spare goes above the buttons, never under them
        column.addWidget(self.buttons)
        for edit in (self.name, self.value, self.low, self.high):
            edit.textChanged.connect(self.check)
        self.check()

    def parameter(self) -> tuple[tuple | None, str]:
        """((name, value, min, max), "") when the fields make a parameter, else (None, why)."""
        name = self.name.text().strip()
        if not name:
            return None, "Name: missing"
        if name in self.taken:
            return None, f"Name: the scene has a parameter {name} already"
        spec, numbers = {}, {"value": self.value, "min": self.low, "max": self.high}
        for key, edit in numbers.items():
            text = edit.text().strip().replace("\u2212", "-")
            if not text and key != "value":
                continue
            try:
                spec[key] = float(text)
            except ValueError:
                return None, f"{key.capitalize()}: " + ("not a number" if text else "missing")
        try:   # the core's own check, as of a scene file holding it
            scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "0",
                                     "parameters": {name: spec}})
        except SceneError as error:
            field = error.key.rsplit(".", 1)[-1] if error.key.count(".") >= 2 else "name"
            return None, f"{field.capitalize()}: {error.reason}"
        p = scene.parameters[0]
        return (p.name, p.value, p.min, p.max), ""

    def check(self) -> None:
        parameter, why = self.parameter()
        self.ok.setEnabled(parameter is not None)
        shown = bool(why) and bool(self.name.text().strip())
        if why == self.message.text() and shown == self.message.isVisibleTo(self):
            return
        self.message.setText(why)
        self.message.setVisible(shown)
        self._fit_height()

    def _fit_height(self) -> None:
        """As tall as the fields, the message (shown, hidden, one line or two) and the buttons
        need at the dialog's width: a message gone leaves no empty strip. (Before it is shown, the
        dialog takes its size hint anyway.)"""
        if not self.isVisible():
            return
        column = self.layout()
        column.invalidate()
        column.activate()
        height = (column.totalHeightForWidth(self.width()) if column.hasHeightForWidth()
                  else column.totalSizeHint().height())
        self.resize(self.width(), max(height, column.totalMinimumSize().height()))

    def accept(self) -> None:
        parameter, _ = self.parameter()
        if parameter is None:
            return
        super().accept()
        self.chosen.emit(*parameter)
