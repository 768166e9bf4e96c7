"""A formula typed into the Scene panel: applied as soon as the text in the field is known to be
valid (no typing pause), a refused text marked only when the pause ends, and a burst of typing
one undo step."""

import pytest

LONG_PAUSE_MS = 600_000   # a pause that never ends by itself during a test: only its keys count


@pytest.fixture
def panel(window):
    panel = window.panel
    panel._timer.setInterval(LONG_PAUSE_MS)
    return panel


def type_keys(qtbot, panel, text):
    """Type ``text`` key by key, each key's background check in before the next key."""
    for char in text:
        qtbot.keyClick(panel.formula, char)
        qtbot.waitUntil(lambda: not panel.checking, timeout=60_000)


def test_a_valid_new_formula_is_drawn_without_waiting_for_the_typing_pause(qtbot, window, panel):
    field = panel.formula
    field.setCursorPosition(len(field.text()))
    surface = window.view.surface
    qtbot.keyClicks(field, "+0.25*x")
    qtbot.waitUntil(lambda: window.scene.landscape == "0.5*sin(x)*cos(y)+0.25*x", timeout=60_000)
    assert panel._timer.isActive()   # the pause has not ended
    assert window.view.surface is not surface and panel.marked is None


def test_a_refused_text_is_marked_only_when_the_pause_ends(qtbot, window, panel):
    field, scene = panel.formula, window.scene
    field.setCursorPosition(len(field.text()))
    type_keys(qtbot, panel, "+z")
    assert ("0.5*sin(x)*cos(y)+z", ()) in panel._checked   # checked, and refused
    assert panel.marked is None and panel.error_text == "" and not field.styleSheet()
    assert window.scene == scene
    panel._timer.timeout.emit()   # the pause ends
    assert panel.marked == "landscape" and "unknown name 'z'" in panel.error_text
    assert window.scene == scene


def test_a_burst_of_typing_is_one_undo_step(qtbot, window, panel):
    scene, steps = window.scene, window.undo_stack.count()
    applied = []
    panel.sceneChanged.connect(lambda new: applied.append(new.landscape))
    panel.formula.selectAll()
    type_keys(qtbot, panel, "0.3*sin(x)")
    qtbot.waitUntil(lambda: window.scene.landscape == "0.3*sin(x)", timeout=60_000)
    assert len(applied) >= 2   # texts valid on the way ("0", …) were drawn too
    panel._timer.timeout.emit()   # the pause ends
    assert window.undo_stack.count() == steps + 1 and window.scene.landscape == "0.3*sin(x)"
    panel.formula.setCursorPosition(len(panel.formula.text()))
    type_keys(qtbot, panel, "+x")
    panel._timer.timeout.emit()
    assert window.undo_stack.count() == steps + 2   # the next burst: the next step
    window.undo_stack.undo()
    assert window.scene.landscape == "0.3*sin(x)" and panel.formula.text() == "0.3*sin(x)"
    window.undo_stack.undo()
    assert window.scene == scene and panel.formula.text() == scene.landscape
