"""The time slider: shows the playback time of a computed run and sets it.

Drag or click anywhere to show that moment; markers (lift-off, where a run stopped) sit on the
groove and jump there when clicked. The part not yet computed is drawn hatched and cannot be
reached.

An event is shown once playback has reached it ("where will it land?" is not answered before
the ball gets there), or from the start with ``set_show_future``. Markers closer than
``MERGE_PIXELS`` are drawn as one, with their count beside it. Beside the slider the most telling
events (``telling``: lift-off, the first landing, ...) are links, as many as fit without the
slider keeping less than ``SLIDER_SHARE`` of the width; every shown event is in the menu after them.
"""

from __future__ import annotations

from dataclasses import dataclass
from html import escape

from PySide6 import QtCore, QtGui, QtWidgets

STEPS = 10_000          # slider positions over the run
MARKER_PIXELS = 6       # a click this close to a marker jumps to it
MERGE_PIXELS = 12       # markers closer than this are drawn as one (their count beside it)
MAX_LINKS = 2           # events named beside the slider at most; every event is in its menu
SLIDER_SHARE = 0.5      # of the time line's width the slider keeps, whatever the links beside it
# which events make the links, most telling first: the first of each kind, in this order
TELLING = ("lift-off", "landing", "stop", "slip", "grip")


@dataclass(frozen=True)
class Marker:
    time: float
    color: str
    text: str           # tooltip, e.g. "lift-off at t = 1.23 s"
    short: str = ""     # the link's text beside the slider, when shorter than ``text``
    kind: str = ""      # one of ``TELLING`` (which events become links first)


def telling(markers: list[Marker], count: int) -> list[Marker]:
    """The ``count`` most telling of ``markers``: the first of each kind in ``TELLING``'s order
    (lift-off, the first landing, where a run stopped, the first slip and grip), then the others
    in time order; returned in time order."""
    firsts = {}
    for m in sorted(markers, key=lambda m: m.time):
        firsts.setdefault(m.kind, m)
    ranked = sorted(firsts.values(), key=lambda m: TELLING.index(m.kind) if m.kind in TELLING else len(TELLING))
    ranked += [m for m in sorted(markers, key=lambda m: m.time) if m not in ranked]
    return sorted(ranked[:count], key=lambda m: m.time)


def merged(placed: list[tuple[int, Marker]], pixels: int) -> list[tuple[int, list[Marker]]]:
    """Markers at pixel positions ``placed`` (x, marker), in order, grouped where each is closer
    than ``pixels`` to the one before it: (the first's x, the group's markers)."""
    groups: list[tuple[int, list[Marker]]] = []
    last = None
    for x, marker in sorted(placed, key=lambda xm: (xm[0], xm[1].time)):
        if groups and x - last < pixels:
            groups[-1][1].append(marker)
        else:
            groups.append((x, [marker]))
        last = x
    return groups


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

    def groups(self) -> list[tuple[int, list[Marker]]]:
        """The markers as drawn: (x in pixels, the markers merged there)."""
        return merged([(self._x(v), m) for v, m in self.markers], MERGE_PIXELS)

    def _group_near(self, x: int) -> list[Marker] | None:
        best = min(self.groups(), key=lambda g: abs(g[0] - x), default=None)
        return best[1] if best and abs(best[0] - x) <= MARKER_PIXELS else None

    def _marker_near(self, x: int) -> Marker | None:
        group = self._group_near(x)
        return group[0] if group else None

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        x = round(event.position().x())
        marker = self._marker_near(x)
        if marker is not None:
            self.markerClicked.emit(marker.time)
            return
        self.setValue(min(self._value(x), self.available))
        super().mousePressEvent(event)   # and drag from there

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:
        group = self._group_near(round(event.position().x()))
        self.setToolTip("\n".join(m.text for m in group) if group else "")
        super().mouseMoveEvent(event)

    def paintEvent(self, event) -> None:
        super().paintEvent(event)
        painter = QtGui.QPainter(self)
        if self.available < STEPS:
            painter.fillRect(QtCore.QRect(QtCore.QPoint(self._x(self.available), self.height() // 2 - 2),
                                          QtCore.QPoint(self._x(STEPS), self.height() // 2 + 2)),
                             QtGui.QBrush(QtGui.QColor("#bbbbbb"), QtCore.Qt.BrushStyle.Dense5Pattern))
        h = self.height()
        for x, group in self.groups():
            painter.setPen(QtCore.Qt.PenStyle.NoPen)
            painter.setBrush(QtGui.QColor(group[0].color))
            painter.drawPolygon(QtGui.QPolygon([QtCore.QPoint(x - 5, 0), QtCore.QPoint(x + 5, 0),
                                                QtCore.QPoint(x, 7)]))
            painter.drawRect(x - 1, 0, 2, h)
            if len(group) > 1:   # merged: how many, on a pale badge beside the marker
                font = QtGui.QFont(self.font())
                font.setBold(True)
                painter.setFont(font)
                text = f"×{len(group)}"
                box = QtGui.QFontMetrics(font).boundingRect(text).adjusted(-2, 0, 2, 0)
                box.moveTo(x + 4, max(0, (h - box.height()) // 2))
                painter.setPen(QtGui.QColor(group[0].color).darker(160))
                painter.setBrush(QtGui.QColor(255, 255, 255, 230))
                painter.drawRoundedRect(box, 3, 3)
                painter.drawText(box, QtCore.Qt.AlignmentFlag.AlignCenter, text)
        painter.end()


class TimeSlider(QtWidgets.QWidget):
    """``seeked(t)`` when the user picks a time (dragging, clicking, a marker, a link, the
    events' menu)."""

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
        self.more = QtWidgets.QToolButton(objectName="eventsMenu")
        self.more.setPopupMode(QtWidgets.QToolButton.ToolButtonPopupMode.InstantPopup)
        self.more.setAutoRaise(True)
        # as tall as the row the slider and the time make, no taller (a tool button's frame grew the
        # time line by 6 px, which a 768-pixel screen in compare mode did not have)
        self.more.setSizePolicy(QtWidgets.QSizePolicy.Policy.Preferred, QtWidgets.QSizePolicy.Policy.Ignored)
        self.more.setMenu(QtWidgets.QMenu(self.more))
        self.more.menu().triggered.connect(lambda action: self.seeked.emit(float(action.data())))
        self.more.hide()
        self.label = QtWidgets.QLabel(objectName="timeLabel")
        self.label.setMinimumWidth(150)
        self.label.setAlignment(QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter)
        self.label.installEventFilter(self)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(6, 0, 6, 0)
        layout.addWidget(self.slider, 1)
        layout.addWidget(self.events)
        layout.addWidget(self.more)
        layout.addWidget(self.label)
        self.t_end = 0.0
        self.markers: list[Marker] = []   # every event of the run so far, shown or not yet
        self.reached = 0.0                # the playback time: events up to here are shown
        self.show_future = False          # every event shown, reached or not
        self.slider.valueChanged.connect(self._moved)
        self.slider.markerClicked.connect(self.seeked)
        self._setting = False
        self._links_for = None            # what the links were last laid out for
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
        """Every event of the run so far; those reached (``shown``) are on the slider and beside it."""
        self.markers = list(markers)
        self._show()

    def set_show_future(self, on: bool) -> None:
        """Show every event from the start (on), or each once playback reaches it."""
        self.show_future = on
        self._show()

    @property
    def shown(self) -> list[Marker]:
        """The events on show: those playback has reached, or all of them."""
        return [m for m in self.markers if self.show_future or m.time <= self.reached]

    def _show(self) -> None:
        shown = self.shown
        placed = [(self._position(m.time), m) for m in shown]
        if placed != self.slider.markers:
            self.slider.markers = placed
            self.slider.update()
        self._lay_out_links()

    def _lay_out_links(self) -> None:
        """The most telling shown events as links, as many (up to ``MAX_LINKS``) as fit beside the
        time's label with the menu button, the slider keeping ``SLIDER_SHARE`` of the width; the
        menu lists every shown event."""
        shown = self.shown
        key = (tuple(shown), self.width(), self.label.width())
        if key == self._links_for:
            return
        self._links_for = key
        menu = self.more.menu()
        menu.clear()
        for m in shown:
            action = menu.addAction(m.text)
            action.setData(m.time)
        layout = self.layout()
        margins = layout.contentsMargins()
        room = ((1 - SLIDER_SHARE) * self.width() - self.label.width() - margins.left() - margins.right()
                - 3 * layout.spacing())
        # the most links that fit, each with its time, else only its kind ("lift-off"); else the menu alone
        tries = [(count, timed) for count in range(min(MAX_LINKS, len(shown)), 0, -1) for timed in (True, False)]
        for count, timed in tries + [(0, False)]:
            links = telling(shown, count)
            more = len(shown) - count
            self.events.setText(" · ".join(
                f'<a href="{m.time!r}">{escape((m.short or m.text) if timed else (m.kind or m.short or m.text))}</a>'
                for m in links))
            self.more.setText(f"+{more}" if count else f"{len(shown)} events")
            needed = (self.events.sizeHint().width() if count else 0) + (self.more.sizeHint().width() if more else 0)
            if needed <= room:
                break
        self.events.setVisible(count > 0)
        self.more.setVisible(more > 0)
        self.more.setToolTip("Every event shown so far: pick one to show that moment")
        self.events.setToolTip("Click a time to show that moment" + (f"; {more} more in the menu beside "
                                                                      "and marked on the slider" if more else ""))

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._lay_out_links()

    def eventFilter(self, watched, event) -> bool:
        if watched is self.label and event.type() == QtCore.QEvent.Type.Resize:
            self._lay_out_links()   # the time's label grew (larger text): less room for links
        return super().eventFilter(watched, event)

    def changeEvent(self, event) -> None:
        """Larger text (presentation, Text Size) makes the links wider: laid out again."""
        super().changeEvent(event)
        if event.type() in (QtCore.QEvent.Type.StyleChange, QtCore.QEvent.Type.FontChange):
            self._links_for = None
            self._lay_out_links()

    def set_time(self, t: float, shown: float | None = None) -> None:
        """Put the handle at time t (no ``seeked``); the label says ``shown``, the time of the
        row drawn (the readouts' time), or t. Events up to t are shown."""
        self._setting = True
        try:
            self.slider.setValue(self._position(t))
        finally:
            self._setting = False
        self.label.setText(f"{t if shown is None else shown:.4f} s / {self.t_end:g} s" if self.t_end > 0 else "—")
        if t != self.reached:
            self.reached = t
            self._show()

    def _moved(self, value: int) -> None:
        if self._setting:
            return
        if value > self.slider.available:   # not computed yet: hold at the edge
            self.slider.setValue(self.slider.available)
            return
        self.seeked.emit(self.t_end * value / STEPS)
