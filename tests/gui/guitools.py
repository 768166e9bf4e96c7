"""Steps a user takes and what they see, shared by the GUI tests."""

import contextlib
import itertools
import re

from PySide6 import QtCore, QtGui
from pytestqt.exceptions import TimeoutError

from rollball_app.controller import FINISHED
from rollball_app.window import SPEEDS

FASTEST = len(SPEEDS) - 1


def run_to_end(qtbot, window, timeout=30_000):
    """Start (at the fastest playback) and wait until the run has played to its end."""
    window.speed.setCurrentIndex(FASTEST)
    window.runs.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=timeout)


def set_field(qtbot, window, key, text):
    """Type into a scene field as a user would and let the typing pause pass."""
    edit = window.panel.formula if key == "landscape" else window.panel.numbers[key]
    edit.selectAll()
    qtbot.keyClicks(edit, text)
    apply_fields(qtbot, window)


def apply_fields(qtbot, window):
    """End the typing pause now and wait for a formula's background check, if any."""
    window.panel.apply()
    qtbot.waitUntil(lambda: not window.panel.checking, timeout=60_000)


POWER = re.compile(r"^10⁻?[⁰¹²³⁴⁵⁶⁷⁸⁹]+$")
SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def exponent(label: str) -> int:
    return int(label[2:].translate(SUPERSCRIPT))


def label_rects(axis) -> list[tuple[QtCore.QRectF, str]]:
    """The tick labels the axis draws: (rectangle in the axis' coordinates, text)."""
    pixmap = QtGui.QPixmap(8, 8)   # text measured as on screen
    painter = QtGui.QPainter(pixmap)
    try:
        _, _, texts = axis.generateDrawSpecs(painter)
    finally:
        painter.end()
    return [(rect, text) for rect, _, text in texts]


def drawn_labels(axis) -> list[tuple[float, float, str]]:
    """The tick labels the axis draws: (centre along the axis in pixels, extent along it, text),
    top to bottom or left to right; the extent is the font's text height on a vertical axis and
    the text's width on a horizontal one."""
    texts = label_rects(axis)
    if axis.orientation in ("left", "right"):
        height = QtGui.QFontMetricsF(axis.style["tickFont"] or QtGui.QFont()).height()
        return sorted((rect.center().y(), height, text) for rect, text in texts)
    return sorted((rect.center().x(), rect.width(), text) for rect, text in texts)


def assert_legible(qtbot, axis) -> list[str]:
    """Labels are powers of ten, at least two, in order, and no two overlap in the axis' font:
    their heights on a vertical axis, their widths on a horizontal one."""
    metrics = QtGui.QFontMetricsF(axis.style["tickFont"] or QtGui.QFont())
    vertical = axis.orientation in ("left", "right")
    length = axis.geometry().height() if vertical else axis.geometry().width()
    low, high = axis.range
    ticks = axis.tickValues(low, high, length + 2)[0][1]   # the labelled level, as pyqtgraph asks for it
    strings = axis.tickStrings(ticks, 1.0, 1.0)
    assert len(strings) >= 2 and all(POWER.match(s) for s in strings), strings
    assert [exponent(s) for s in strings] == [round(v) for v in ticks]
    # where they sit on the axis (pixels from its top or left), measured in the axis font
    placed = sorted(((high - v if vertical else v - low) / (high - low) * length,
                     metrics.height() if vertical else metrics.horizontalAdvance(s), s)
                    for v, s in zip(ticks, strings))
    assert all(b - a >= (da + db) / 2 for (a, da, _), (b, db, _) in itertools.pairwise(placed)), placed
    # and what pyqtgraph lays out from them: all of them, once the axis has made room for its labels
    expected = [s for _, _, s in placed]
    with contextlib.suppress(TimeoutError):
        qtbot.waitUntil(lambda: [s for _, _, s in drawn_labels(axis)] == expected, timeout=5000)
    drawn = drawn_labels(axis)
    assert [s for _, _, s in drawn] == expected, (axis.range, drawn)
    assert all(b - a >= (da + db) / 2 for (a, da, _), (b, db, _) in itertools.pairwise(drawn)), drawn
    return strings


def type_contact(qtbot, window, key, text):
    """Type ``text`` into the scene panel's contact field ``key`` (empty: clear it) and apply the fields."""
    edit = window.panel.contact.edits[key]
    edit.selectAll()
    if text:
        qtbot.keyClicks(edit, text)
    else:
        qtbot.keyClick(edit, QtCore.Qt.Key.Key_Delete)
    apply_fields(qtbot, window)
