"""Ctrl+Z in a scene field undoes the scene's last change, as the Edit menu does (not the
field's text, which would be recorded as one more change); Ctrl+Shift+Z and Ctrl+Y redo it."""

import pytest
from PySide6 import QtCore

from .guitools import set_field

CTRL, SHIFT = QtCore.Qt.KeyboardModifier.ControlModifier, QtCore.Qt.KeyboardModifier.ShiftModifier


@pytest.mark.parametrize("key", ["ball.radius", "landscape"])
def test_undo_keys_in_a_field_undo_the_scenes_change(qtbot, window, key):
    stack = window.undo_stack
    before = window.scene
    set_field(qtbot, window, key, "0.2" if key == "ball.radius" else "0.4*sin(x)*cos(y)")
    changed = window.scene
    assert changed != before and (stack.count(), stack.index()) == (1, 1)
    edit = window.panel.formula if key == "landscape" else window.panel.numbers[key]
    window.activateWindow()   # the keys reach the active window's field
    qtbot.waitActive(window)
    edit.setFocus()
    qtbot.waitUntil(edit.hasFocus)
    qtbot.keyClick(edit, QtCore.Qt.Key.Key_Z, CTRL)
    window.panel.apply()
    assert (stack.count(), stack.index()) == (1, 0)   # the change undone, nothing new recorded
    assert window.scene == before and window.redo_action.isEnabled()
    assert edit.text() == (window.panel.formula.text() if key == "landscape" else "0.1")
    qtbot.keyClick(edit, QtCore.Qt.Key.Key_Z, CTRL | SHIFT)
    window.panel.apply()
    assert (stack.count(), stack.index()) == (1, 1) and window.scene == changed
    qtbot.keyClick(edit, QtCore.Qt.Key.Key_Z, CTRL)
    qtbot.keyClick(edit, QtCore.Qt.Key.Key_Y, CTRL)
    window.panel.apply()
    assert (stack.count(), stack.index()) == (1, 1) and window.scene == changed
