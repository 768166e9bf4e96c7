"""A field that keeps the scene from being valid is marked, and explained right under it in the
words of its label; the window keeps the last valid scene."""

import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from .guitools import apply_fields, set_field


def _in_sight(widget) -> bool:
    """Shown and not scrolled out of its scroll area."""
    return widget.isVisible() and not widget.visibleRegion().isEmpty()


def _directly_under(message, edit) -> bool:
    top = message.mapTo(message.window(), message.rect().topLeft())
    bottom = edit.mapTo(edit.window(), edit.rect().bottomLeft())
    return 0 <= top.y() - bottom.y() <= 12 and abs(top.x() - bottom.x()) <= 12


def test_max_below_min_marks_max_under_the_field_and_fixing_it_clears(qtbot, window):
    window.resize(1024, 700)   # the Grid fields are below the fold at this size
    panel, scene, surface = window.panel, window.scene, window.view.surface
    edit = panel.numbers["view.max"]
    edit.selectAll()
    for char in "\u22125":   # a typeset minus, as copied from a text (QTest types Latin-1 only)
        QtWidgets.QApplication.sendEvent(edit, QtGui.QKeyEvent(QtCore.QEvent.Type.KeyPress, 0,
                                                               QtCore.Qt.KeyboardModifier.NoModifier, char))
    apply_fields(qtbot, window)
    assert panel.marked == "view.max"
    message = panel.messages["view.max"]
    assert message.text().startswith("Max:") and "Min (-4 m)" in message.text()
    assert "view." not in panel.error_text   # the labels the user sees, not the file's keys
    assert _directly_under(message, panel.numbers["view.max"])
    qtbot.waitUntil(lambda: _in_sight(message))   # scrolled into sight
    assert panel.numbers["view.max"].styleSheet() and not panel.numbers["view.min"].styleSheet()
    assert panel.row_labels["view.max"].styleSheet() and panel.messages["view.min"].isHidden()
    assert window.scene == scene and window.view.surface is surface   # the last valid state stays

    set_field(qtbot, window, "view.max", "4")
    assert panel.marked is None and panel.error_text == "" and message.isHidden()
    assert not panel.numbers["view.max"].styleSheet() and not panel.row_labels["view.max"].styleSheet()


def test_a_bad_formula_marks_the_formula_field_and_fixing_it_clears(qtbot, window):
    panel = window.panel
    set_field(qtbot, window, "landscape", "0.5*sin(x)*cos(z)")
    assert panel.marked == "landscape" and panel.formula.styleSheet()
    assert _in_sight(panel.formula_error) and _directly_under(panel.formula_error, panel.formula)
    assert "unknown name 'z'" in panel.formula_error.text()
    set_field(qtbot, window, "landscape", "0.5*sin(x)*cos(y)")
    assert panel.marked is None and not panel.formula.styleSheet() and panel.formula_error.isHidden()


@pytest.mark.parametrize("edits, marked, words", [
    ([("view.min", "5")], "view.min", "Min: must be less than Max"),
    ([("view.max", "1e6")], "view.max", "Max: 10,000,041 grid points per side"),
    ([("view.step", "1e-5")], "view.step", "Spacing: 800,001 grid points per side"),
    # the field that is wrong on its own stays marked while another is edited
    ([("view.min", "inf"), ("view.max", "3")], "view.min", "Min: must be a finite number"),
    ([("view.max", "-5"), ("ball.radius", "0.2")], "view.max", "Max: Min (-4 m) must be less than Max"),
])
def test_the_field_whose_change_broke_the_scene_is_marked(qtbot, window, edits, marked, words):
    for key, text in edits:
        set_field(qtbot, window, key, text)
    assert window.panel.marked == marked
    assert window.panel.messages[marked].text().startswith(words)


def test_a_start_outside_the_drawn_grid_is_noticed_at_the_field_just_changed(qtbot, window):
    panel = window.panel
    set_field(qtbot, window, "start.x", "10")
    assert window.scene.start.x == 10   # a valid scene: it runs, but the ball is drawn nowhere
    assert panel.noticed == "start.x" and panel.marked is None and panel.error_text == ""
    assert panel.notice_text.startswith("x: the start (10, -0.2) m is outside the drawn grid, -4 to 4 m")
    set_field(qtbot, window, "view.max", "12")   # the grid now holds it
    assert panel.noticed is None and panel.notice_text == "" and panel.messages["start.x"].isHidden()
    set_field(qtbot, window, "view.max", "5")
    assert panel.noticed == "view.max" and panel.notice_text.startswith("Max: the start (10, -0.2) m")
    set_field(qtbot, window, "view.max", "-5")   # refused: the refusal replaces the notice
    assert panel.marked == "view.max" and panel.noticed is None and panel.error_text.startswith("Max:")
