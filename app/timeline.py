"""The time slider: shows the playback time of a computed run and sets it.

Drag or click anywhere to show that moment; markers (lift-off, where a run stopped) sit on the
groove and jump there when clicked. The part not yet computed is drawn hatched and cannot be
reached.
"""

from __future__ import annotations

from dataclasses import dataclass
from html import escape

from PySide6 import QtCore, QtGui, QtWidgets

STEPS = 10_000          # slider positions over the run
MARKER_PIXELS = 6       # a click this close to a marker jumps to it
MAX_LINKS = 2           # events named beside the slider; the others are markers on it only


@dataclass(frozen=True)
class Marker:
    time: float
    color: str
    text: str           # tooltip, e.g. "lift-off at t = 1.23 s"
    short: str = ""     # the link's text beside the slider, when shorter than ``text``


class MarkedSlider(QtWidgets.QSlider):
    """A horizontal slider that jumps where it is clicked and paints event markers."""

    markerClicked = QtCore.Signal(float)

    def __init__(self, parent=None):
        super().__init__(QtCore.Qt.Orientation.Horizontal, parent)
        self.setRange(0, STEPS)
        self.setFocusPolicy(QtCore.Qt.FocusPolicy.NoFocus)   # the window's keys move it
        self.markers: list[tuple[int, Marker]] = []
        self.available = STEPS   # positions beyond this are not computed yet
        self.setMouseTracking(True)

    def _x(self, value: int) -> int:
        option = QtWidgets.QStyleOptionSlider()
        self.initStyleOption(option)
        groove = self.style().subControlRect(QtWidgets.QStyle.ComplexControl.CC_Slider, option,
                                             QtWidgets.QStyle.SubControl.SC_SliderGroove, self)
        handle = self.style().subControlRect(QtWidgets.QStyle.ComplexControl.CC_Slider, option,
                                             QtWidgets.QStyle.SubControl.SC_SliderHandle, self)
        span = groove.width() - handle.width()
        return groove.x() + handle.width() // 2 + QtWidgets.QStyle.sliderPositionFromValue(0, STEPS, value, span)

    def _value(self, x: int) -> int:
        left, right = self._x(0), self._x(STEPS)
        return round(STEPS * min(1.0, max(0.0, (x - left) / max(1, right - left))))

    def _marker_near(self, x: int) -> Marker | None:
        best = min(self.markers, key=lambda vm: abs(self._x(vm[0]) - x), default=None)
        return best[1] if best and abs(self._x(best[0]) - x) <= MARKER_PIXELS else None

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        x = round(event.position().x())
        marker = self._marker_near(x)
        if marker is not None:
            self.markerClicked.emit(marker.time)
            return
        self.setValue(min(self._value(x), self.available))
        super().mousePressEvent(event)   # and drag from there

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:
        marker = self._marker_near(round(event.position().x()))
        self.setToolTip(marker.text if marker else "")
        super().mouseMoveEvent(event)

    def paintEvent(self, event) -> None:
        super().paintEvent(event)
        painter = QtGui.QPainter(self)
        if self.available < STEPS:
            painter.fillRect(QtCore.QRect(QtCore.QPoint(self._x(self.available), self.height() // 2 - 2),
                                          QtCore.QPoint(self._x(STEPS), self.height() // 2 + 2)),
                             QtGui.QBrush(QtGui.QColor("#bbbbbb"), QtCore.Qt.BrushStyle.Dense5Pattern))
        for value, marker in self.markers:
            x = self._x(value)
            painter.setPen(QtCore.Qt.PenStyle.NoPen)
            painter.setBrush(QtGui.QColor(marker.color))
            h = self.height()
            painter.drawPolygon(QtGui.QPolygon([QtCore.QPoint(x - 5, 0), QtCore.QPoint(x + 5, 0),
                                                QtCore.QPoint(x, 7)]))
            painter.drawRect(x - 1, 0, 2, h)
        painter.end()


class TimeSlider(QtWidgets.QWidget):
    """``seeked(t)`` when the user picks a time (dragging, clicking, a marker)."""

    seeked = QtCore.Signal(float)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setObjectName("timeline")
        self.slider = MarkedSlider()
        self.slider.setObjectName("timeSlider")
        self.slider.setToolTip("Drag to show any moment; ←/→ by frame, Home/End")
        self.events = QtWidgets.QLabel(objectName="events")
        self.events.setTextFormat(QtCore.Qt.TextFormat.RichText)
        self.events.setToolTip("Click a time to show that moment")
        self.events.linkActivated.connect(lambda href: self.seeked.emit(float(href)))
        self.label = QtWidgets.QLabel(objectName="timeLabel")
        self.label.setMinimumWidth(150)
        self.label.setAlignment(QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(6, 0, 6, 0)
        layout.addWidget(self.slider, 1)
        layout.addWidget(self.events)
        layout.addWidget(self.label)
        self.t_end = 0.0
        self.slider.valueChanged.connect(self._moved)
        self.slider.markerClicked.connect(self.seeked)
        self._setting = False
        self.set_span(0.0)

    def set_span(self, t_end: float) -> None:
        """The run's time span [0, t_end] (0: nothing to show; the slider is disabled)."""
        self.t_end = t_end
        self.set_markers([])
        self.set_available(0.0)
        self.set_time(0.0)

    def _position(self, t: float) -> int:
        return round(STEPS * min(1.0, max(0.0, t / self.t_end))) if self.t_end > 0 else 0

    def set_available(self, t: float) -> None:
        """Rows exist up to time t: the slider reaches that far."""
        self.slider.available = self._position(t)
        self.slider.setEnabled(self.t_end > 0 and t > 0)
        self.slider.update()

    def set_markers(self, markers: list[Marker]) -> None:
        """Events on the slider, and the first ``MAX_LINKS`` as links beside it (the window
        keeps its width however many bounces a run has)."""
        self.slider.markers = [(self._position(m.time), m) for m in markers]
        self.slider.update()
        links = " · ".join(f'<a href="{m.time!r}">{escape(m.short or m.text)}</a>' for m in markers[:MAX_LINKS])
        more = len(markers) - MAX_LINKS
        self.events.setText(("Go to: " + links + (f" · +{more}" if more > 0 else "")) if markers else "")
        self.events.setToolTip("Click a time to show that moment" + (f"; {more} more marked on the slider "
                                                                      "(click a marker)" if more > 0 else ""))

    def set_time(self, t: float, shown: float | None = None) -> None:
        """Put the handle at time t (no ``seeked``); the label says ``shown``, the time of the
        row drawn (the readouts' time), or t."""
        self._setting = True
        try:
            self.slider.setValue(self._position(t))
        finally:
            self._setting = False
        self.label.setText(f"{t if shown is None else shown:.4f} s / {self.t_end:g} s" if self.t_end > 0 else "—")

    def _moved(self, value: int) -> None:
        if self._setting:
            return
        if value > self.slider.available:   # not computed yet: hold at the edge
            self.slider.setValue(self.slider.available)
            return
        self.seeked.emit(self.t_end * value / STEPS)
