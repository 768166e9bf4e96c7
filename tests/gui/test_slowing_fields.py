"""The scene panel's fields for what slows a ball down (scene version 4): rolling resistance,
spin friction, the air (a choice that fills density and drag coefficient, or both typed) and
whether a run stops at rest — validated as the scene format is, undoable, saved and loaded."""

import json

from PySide6 import QtCore

from rollball import Scene
from rollball.examples import EXAMPLES_DIR

from .guitools import apply_fields, type_contact as _type


def _choose_air(qtbot, window, index):
    combo = window.panel.contact.air
    combo.setCurrentIndex(index)
    combo.activated.emit(index)
    apply_fields(qtbot, window)


def test_the_fields_show_the_scene_and_make_it(qtbot, window):
    contact = window.panel.contact
    assert not window.scene.dissipates   # hills: nothing slows the ball
    assert contact.text("contact.rolling_resistance") == "0.0" and contact.text("air.density") == "0.0"
    assert contact.air.currentText() == "none" and contact.stop_at_rest.isChecked()
    _type(qtbot, window, "contact.rolling_resistance", "0.05")
    _type(qtbot, window, "contact.spin_friction", "0.01")
    qtbot.mouseClick(contact.stop_at_rest, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)
    scene = window.scene
    assert (scene.contact.rolling_resistance, scene.contact.spin_friction) == (0.05, 0.01)
    assert scene.stop_at_rest is False and scene.dissipates and window.panel.error_text == ""


def test_the_airs_choice_fills_both_fields_and_typing_shows_which_it_is(qtbot, window):
    contact = window.panel.contact
    _choose_air(qtbot, window, 1)
    assert (window.scene.air.density, window.scene.air.drag_coefficient) == (1.2, 0.47)
    assert (contact.text("air.density"), contact.text("air.drag_coefficient")) == ("1.2", "0.47")
    assert window.undo_stack.undoText() == "Change air"
    window.undo_stack.undo()   # one step: both values and the choice back
    assert window.scene.air.density == 0.0 and contact.air.currentText() == "none"
    assert contact.text("air.drag_coefficient") == "0.0"
    window.undo_stack.redo()
    assert contact.air.currentIndex() == 1 and window.scene.air.drag_coefficient == 0.47
    _type(qtbot, window, "air.drag_coefficient", "0.3")
    assert window.scene.air.drag_coefficient == 0.3 and contact.air.currentText().startswith("as typed")
    _type(qtbot, window, "air.drag_coefficient", "0.47")
    assert contact.air.currentIndex() == 1
    _choose_air(qtbot, window, 0)
    assert window.scene.air.density == 0.0 and window.scene.air.drag_coefficient == 0.0
    assert contact.air.currentText() == "none"


def test_refusals_are_explained_under_the_field_in_its_words(qtbot, window):
    panel = window.panel
    scene = window.scene
    _type(qtbot, window, "contact.rolling_resistance", "-0.1")
    assert panel.marked == "contact.rolling_resistance"
    message = panel.contact.messages["contact.rolling_resistance"]
    assert message.isVisible() and message.text().startswith("Rolling resist.: must not be negative")
    _type(qtbot, window, "contact.rolling_resistance", "x")
    assert panel.error_text == "Rolling resist.: not a number"
    _type(qtbot, window, "contact.rolling_resistance", "")
    assert panel.error_text == "Rolling resist.: missing"
    _type(qtbot, window, "contact.rolling_resistance", "0")
    assert panel.error_text == ""
    # a density without a drag coefficient: the field typed into is marked, naming the other in words
    _type(qtbot, window, "air.density", "1.2")
    assert panel.marked == "air.density"
    assert "Drag coeff. C_d" in panel.error_text and "air." not in panel.error_text
    assert window.scene == scene   # nothing lost: the last valid scene stays
    assert panel.contact.text("air.density") == "1.2"   # nor what was typed
    _type(qtbot, window, "air.drag_coefficient", "0.5")
    assert panel.error_text == "" and window.scene.air.density == 1.2 and window.scene.air.drag_coefficient == 0.5


def test_undo_names_the_field_and_puts_it_back(qtbot, window):
    _type(qtbot, window, "contact.rolling_resistance", "0.02")
    assert window.undo_stack.undoText() == "Change rolling resistance"
    _type(qtbot, window, "contact.spin_friction", "0.1")
    assert window.undo_stack.undoText() == "Change spin friction"
    qtbot.mouseClick(window.panel.contact.stop_at_rest, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)
    assert window.undo_stack.undoText() == "Change stop at rest"
    window.undo_stack.undo()
    assert window.panel.contact.stop_at_rest.isChecked() and window.scene.stop_at_rest
    window.undo_stack.undo()
    window.undo_stack.undo()
    assert window.panel.contact.text("contact.rolling_resistance") == "0.0"
    assert window.scene.contact.rolling_resistance == 0.0


def test_saved_as_version_4_and_loaded(qtbot, window, tmp_path):
    _type(qtbot, window, "contact.rolling_resistance", "0.05")
    _choose_air(qtbot, window, 1)
    qtbot.mouseClick(window.panel.contact.stop_at_rest, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)
    path = tmp_path / "slowing.json"
    window.files.save_to(path)
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["version"] == 4 and data["contact"]["rolling_resistance"] == 0.05
    assert data["air"] == {"density": 1.2, "drag_coefficient": 0.47} and data["stop_at_rest"] is False
    window.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    window.files.open_scene(path, remember=False)
    contact = window.panel.contact
    assert contact.text("contact.rolling_resistance") == "0.05" and contact.air.currentIndex() == 1
    assert not contact.stop_at_rest.isChecked()


def test_a_version_3_file_saved_unchanged_in_meaning(qtbot, window, tmp_path):
    original = EXAMPLES_DIR / "billiard.json"
    assert json.loads(original.read_text(encoding="utf-8"))["version"] == 3
    window.files.open_scene(original, remember=False)
    assert not window.files.dirty and window.panel.error_text == ""
    window.panel.apply()   # the fields as shown make the very scene the file holds
    assert window.scene == Scene.load(original) and not window.files.dirty
    path = tmp_path / "billiard.json"
    window.files.save_to(path)
    assert Scene.load(path) == Scene.load(original)
    assert json.loads(path.read_text(encoding="utf-8"))["version"] == 4



def test_help_on_the_new_fields_is_the_budget_section(window):
    from rollball_app import help as helps
    from rollball_app.help import page_html

    for key in ("contact.rolling_resistance", "air", "stop_at_rest"):
        assert helps.topic_at(window.panel.contact.edits[key]) == "plots.html#budget"
    page = page_html("plots.html")
    assert 'name="budget"' in page and "Rolling resist." in page and "Drag coeff. C_d" in page
