"""The Qt binding keeps Python's reference counts: PySide6 6.12.0 released None and the bools once
too often in every call returning nothing, which ended a session with a fatal error."""

import sys

from PySide6 import QtCore, QtWidgets


def test_calls_returning_nothing_keep_none_and_bools_alive(qtbot):
    label = QtWidgets.QLabel()
    qtbot.addWidget(label)
    none, true, false = sys.getrefcount(None), sys.getrefcount(True), sys.getrefcount(False)
    for i in range(2000):
        label.setText("x")
        label.setVisible(i % 2 == 0)
        label.update()
        label.objectNameChanged.emit("a")
    timer = QtCore.QTimer()
    timer.setSingleShot(True)
    assert abs(sys.getrefcount(None) - none) < 50
    assert abs(sys.getrefcount(True) - true) < 50 and abs(sys.getrefcount(False) - false) < 50
