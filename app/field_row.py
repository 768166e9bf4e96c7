"""One field of the scene panel as the user sees it: the field, its unit beside it and its
message under it (hidden while the field is valid). The panel's fields and the contact's are
built by ``field_row``."""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

ERROR_STYLE = "color: #c0392b;"
UNIT_WIDTH = 42   # px: the units line up


def message_label(name: str) -> QtWidgets.QLabel:
    """A field's message: plain text, wrapped, hidden until there is something to say."""
    label = QtWidgets.QLabel(wordWrap=True, objectName=name)
    label.setTextFormat(QtCore.Qt.TextFormat.PlainText)
    label.setStyleSheet(ERROR_STYLE)
    label.hide()
    return label


def field_row(field: QtWidgets.QWidget, unit: str, key: str) -> tuple[QtWidgets.QWidget, QtWidgets.QLabel]:
    """The row for the field of ``key`` (its unit beside it, its message under it) and the message."""
    row = QtWidgets.QWidget()
    v = QtWidgets.QVBoxLayout(row)
    v.setContentsMargins(0, 0, 0, 0)
    v.setSpacing(1)
    h = QtWidgets.QHBoxLayout()
    h.addWidget(field, 1)
    units = QtWidgets.QLabel(unit)
    units.setMinimumWidth(UNIT_WIDTH)
    h.addWidget(units)
    v.addLayout(h)
    message = message_label(f"{key}.error")
    v.addWidget(message)
    return row, message
