"""A scene's named parameters in the app: the landscape with their values, and a slider per
parameter in the Scene panel.

The compiled landscape takes the parameters' values as arguments (docs/design.md §3, §4), so a
new value compiles nothing: ``Valued`` is the scene's landscape with its values, and draws,
plays back and evaluates like a landscape without parameters. ``ParameterRows`` shows a slider
per parameter over its range (or, without one, ``value ± max(1, |value|)``) with the value's
field beside it; dragging changes the scene at once, as fast as it is drawn.
"""

from __future__ import annotations

import math

import numpy as np
from PySide6 import QtCore, QtWidgets

from rollball import Scene
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
    """The range a slider offers: the parameter's own, or ``value ± max(1, |value|)``."""
    if low is not None and high is not None:
        return low, high
    half = max(1.0, abs(value))
    return value - half, value + half


def slider_value(position: int, low: float, high: float) -> float:
    """The value at a slider position, rounded to the slider's resolution (a thousandth of the
    range, to one more digit): what a drag gives reads as a plain number."""
    step = (high - low) / SLIDER_STEPS
    value = low + position * step
    digits = max(0, 1 - math.floor(math.log10(step))) if step > 0 else 6
    return float(round(value, digits))


def slider_position(value: float, low: float, high: float) -> int:
    if not high > low:
        return 0
    return int(round(min(max((value - low) / (high - low), 0.0), 1.0) * SLIDER_STEPS))


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
        self._set_tips()
        v = QtWidgets.QVBoxLayout(self)
        v.setContentsMargins(0, 0, 0, 0)
        v.setSpacing(1)
        h = QtWidgets.QHBoxLayout()
        h.addWidget(self.label)
        h.addWidget(self.slider, 1)
        h.addWidget(self.edit)
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
    """A row per parameter of the scene (none: the widget is hidden). ``edited(name)`` when a
    value is typed (the panel waits for a pause), ``dragged(name)`` when a slider moved (the
    panel applies it at once); ``gesture`` counts slider drags, so the changes of one drag make
    one undo step."""

    edited = QtCore.Signal(str)
    dragged = QtCore.Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.rows: dict[str, ParameterRow] = {}
        self.gesture = 0            # increases with every drag begun
        self.dragging = False
        self._layout = QtWidgets.QVBoxLayout(self)
        self._layout.setContentsMargins(0, 2, 0, 0)
        self._layout.setSpacing(2)
        self.title = QtWidgets.QLabel("Parameters")
        self.title.setToolTip("The formula's named numbers (from the scene file): drag a slider to "
                              "reshape the landscape; nothing is compiled")
        self._layout.addWidget(self.title)
        self.setVisible(False)

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
            row = ParameterRow(p.name, p.value, p.min, p.max, self)
            row.edit.textEdited.connect(lambda _text, n=p.name: self.edited.emit(n))
            row.slider.valueChanged.connect(lambda position, n=p.name: self._slid(n, position))
            row.slider.sliderPressed.connect(self._pressed)
            row.slider.sliderReleased.connect(self._released)
            self._layout.addWidget(row)
            self.rows[p.name] = row
        self.setVisible(bool(self.rows))
        return True

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
