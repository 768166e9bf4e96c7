"""The scene panel's contact fields: friction μ, restitution e, after lift-off and the start's ω,
validated as the scene format is (the message under the field), undoable, saved and loaded."""

from rollball import Scene

from .guitools import apply_fields, type_contact as _type


def test_the_fields_show_the_scene_and_make_it(qtbot, window):
    panel = window.panel
    assert window.scene.contact.friction is None   # hills, a version-2 example: the 2011 model
    assert panel.contact.text("contact.friction") == "" and panel.contact.text("start.omega") == ""
    assert panel.contact.after_liftoff.currentData() == "glued"
    _type(qtbot, window, "contact.friction", "0.2")
    _type(qtbot, window, "contact.restitution", "0.5")
    _type(qtbot, window, "start.omega", "0, 0 , 3")
    combo = panel.contact.after_liftoff
    combo.setCurrentIndex(combo.findData("fly"))
    combo.activated.emit(combo.currentIndex())
    apply_fields(qtbot, window)
    contact = window.scene.contact
    assert (contact.friction, contact.restitution, contact.after_liftoff) == (0.2, 0.5, "fly")
    assert window.scene.start.omega == (0.0, 0.0, 3.0) and panel.error_text == ""
    _type(qtbot, window, "start.omega", "")   # empty: the rolling start
    _type(qtbot, window, "contact.friction", "")   # empty: always rolls again
    assert window.scene.contact.friction is None and window.scene.start.omega is None


def test_refusals_are_explained_under_the_field_in_its_words(qtbot, window):
    panel = window.panel
    scene = window.scene
    _type(qtbot, window, "contact.restitution", "1.5")
    assert panel.marked == "contact.restitution"
    message = panel.contact.messages["contact.restitution"]
    assert message.isVisible() and message.text().startswith("Restitution e: must be from 0 to 1")
    assert window.scene == scene
    _type(qtbot, window, "contact.restitution", "0")
    _type(qtbot, window, "contact.friction", "-1")
    assert panel.marked == "contact.friction" and "must not be negative" in panel.error_text
    _type(qtbot, window, "contact.friction", "abc")
    assert panel.error_text == "Friction μ: not a number"
    _type(qtbot, window, "contact.friction", "")
    _type(qtbot, window, "start.omega", "1, 2")
    assert panel.marked == "start.omega" and "three numbers" in panel.error_text
    # a spinning start that does not roll needs friction: ω is marked, in the panel's words
    _type(qtbot, window, "start.omega", "0, 0, 30")
    assert panel.marked == "start.omega"
    assert "does not roll" in panel.error_text and "contact." not in panel.error_text
    assert window.scene == scene
    _type(qtbot, window, "contact.friction", "0.3")   # with friction it may slip: the scene is valid
    assert panel.error_text == "" and window.scene.start.omega == (0.0, 0.0, 30.0)


def test_undo_names_the_field_and_puts_it_back(qtbot, window):
    _type(qtbot, window, "contact.friction", "0.25")
    assert window.undo_stack.undoText() == "Change friction"
    _type(qtbot, window, "start.omega", "1, 0, 0")
    _type(qtbot, window, "start.omega", "")
    assert window.undo_stack.undoText() == "Change start ω"
    window.undo_stack.undo()
    assert window.panel.contact.text("start.omega") == "1.0, 0.0, 0.0"
    window.undo_stack.undo()
    window.undo_stack.undo()
    assert window.panel.contact.text("contact.friction") == "" and window.scene.contact.friction is None


def test_saved_and_loaded_with_the_scene(qtbot, window, tmp_path):
    _type(qtbot, window, "contact.friction", "0.4")
    _type(qtbot, window, "start.omega", "0, 0, 2")
    path = tmp_path / "spin.json"
    window.scene.save(path)
    saved = Scene.load(path)
    assert saved.contact.friction == 0.4 and saved.start.omega == (0.0, 0.0, 2.0)
    window.files.open_scene(path, remember=False)
    assert window.panel.contact.text("contact.friction") == "0.4"
    assert window.panel.contact.text("start.omega") == "0.0, 0.0, 2.0"


def test_help_on_a_contact_field_is_the_model_pages_contact_section(window):
    from rollball_app import help as helps
    from rollball_app.help import page_html

    for key in ("contact.friction", "contact.after_liftoff", "start.omega"):
        assert helps.topic_at(window.panel.contact.edits[key]) == "model.html#contact"
    page = page_html("model.html")
    assert 'name="contact"' in page and "Friction μ" in page and "Start ω" in page
    assert "White line" in page_html("plots.html")
