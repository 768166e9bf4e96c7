"""A scene with named parameters in the real window: drawn with its values, run, saved back;
a slider per parameter that reshapes the landscape without compiling anything."""

import json
import math
import time

import numpy as np
import pytest
from PySide6 import QtCore

from rollball import Scene
from rollball.scene import VERSION, Parameter
from rollball import landscape as core_landscape
from rollball.examples import EXAMPLES_DIR
from rollball_app.parameters import (SLIDER_STEPS, ParameterRows, slider_position, slider_range,
                                     slider_value)

from .guitools import apply_fields, run_to_end, set_field

RIPPLES = EXAMPLES_DIR / "ripples.json"


def drawn_heights(window):
    """The surface's heights as the view last drew them (on its grid)."""
    return np.array(window.view._drawn, copy=True)


@pytest.fixture
def ripples(window):
    assert window.files.open_scene(RIPPLES, remember=False)
    return window


def test_a_scene_with_parameters_is_drawn_with_its_values_runs_and_saves_them(qtbot, ripples, dialogs, tmp_path):
    window = ripples
    scene = window.scene
    assert scene.parameter_names == ("a", "k") and dialogs == []
    axis = window.view._axis
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    expected = 0.5 * np.sin(xs) * np.cos(ys)
    drawn = drawn_heights(window)
    shown = np.isfinite(drawn)
    assert shown.mean() > 0.5 and np.allclose(drawn[shown], expected[shown], atol=1e-12)
    assert [row.edit.text() for row in window.panel.parameter_rows.rows.values()] == ["0.5", "1.0"]
    run_to_end(qtbot, window)
    assert window.controller.simulation.scene.parameters == scene.parameters
    path = tmp_path / "mine.json"
    row = window.panel.parameter_rows.rows["a"]
    row.edit.setText("0.25")
    window.panel._edited("parameters.a")
    apply_fields(qtbot, window)
    assert window.scene.parameter_values == (0.25, 1.0)
    assert window.files.save_to(path)
    saved = json.loads(path.read_text())
    assert saved["version"] == VERSION
    assert saved["parameters"] == {"a": {"value": 0.25, "min": 0.0, "max": 1.0},
                                   "k": {"value": 1.0, "min": 0.5, "max": 3.0}}
    assert Scene.load(path) == window.scene


def test_the_formula_accepts_the_scenes_parameter_names_only(qtbot, ripples):
    window = ripples
    set_field(qtbot, window, "landscape", "a*cos(k*x)")
    assert window.panel.error_text == "" and window.scene.landscape == "a*cos(k*x)"
    set_field(qtbot, window, "landscape", "b*cos(k*x)")
    assert window.panel.marked == "landscape" and "b" in window.panel.error_text
    assert window.scene.landscape == "a*cos(k*x)"


def test_a_parameter_typed_wrong_is_marked_at_its_field(qtbot, ripples):
    window = ripples
    row = window.panel.parameter_rows.rows["k"]
    row.edit.setText("two")
    window.panel._edited("parameters.k")
    apply_fields(qtbot, window)
    assert window.panel.marked == "parameters.k" and window.panel.error_text == "k: not a number"
    assert row.message.isVisible()
    row.edit.setText("2")
    window.panel._edited("parameters.k")
    apply_fields(qtbot, window)
    assert window.panel.error_text == "" and window.scene.parameter_values == (0.5, 2.0)


def test_dragging_a_slider_redraws_at_once_without_compiling_and_is_one_undo_step(qtbot, ripples, monkeypatch):
    window = ripples
    compiles = []
    real = core_landscape._compile
    monkeypatch.setattr(core_landscape, "_compile", lambda source: compiles.append(source) or real(source))
    formulas = []
    real_landscape = core_landscape.Landscape.__init__

    def counted(self, *args, **kwargs):
        formulas.append(args)
        real_landscape(self, *args, **kwargs)
    monkeypatch.setattr(core_landscape.Landscape, "__init__", counted)
    run_to_end(qtbot, window)
    before = window.scene
    undo_steps = window.undo_stack.count()
    row = window.panel.parameter_rows.rows["a"]
    slider = row.slider
    first = drawn_heights(window)
    slider.setSliderDown(True)            # a drag: pressed, moved several times, released
    times = []
    for position in (600, 700, 800, 900):
        started = time.perf_counter()
        slider.setValue(position)         # applied at once, no typing pause
        times.append(time.perf_counter() - started)
        assert window.scene.parameter_values[0] == pytest.approx(position / SLIDER_STEPS)
    slider.setSliderDown(False)
    assert row.edit.text() == "0.9" and window.scene.parameter_values == (0.9, 1.0)
    drawn = drawn_heights(window)
    both = np.isfinite(drawn) & np.isfinite(first)
    assert np.allclose(drawn[both], 1.8 * first[both], atol=1e-9)     # a from 0.5 to 0.9, redrawn
    assert compiles == [] and formulas == []                           # nothing parsed or compiled
    assert window.controller.state == "ready"                          # the run was reset
    assert window.undo_stack.count() == undo_steps + 1
    assert window.undo_stack.undoText() == "Change parameter a"
    assert max(times) < 10 * 0.150, times     # the goal with a tenfold margin (the bench says more)
    window.undo_stack.undo()
    assert window.scene == before and row.edit.text() == "0.5"
    assert slider.value() == SLIDER_STEPS // 2
    assert np.allclose(drawn_heights(window)[both], first[both], atol=1e-12)
    window.undo_stack.redo()
    assert window.scene.parameter_values == (0.9, 1.0)


def test_a_formula_keystroke_redraws_the_landscape(qtbot, ripples):
    window = ripples
    field = window.panel.formula
    field.setCursorPosition(len(field.text()))
    qtbot.keyClicks(field, "+x")
    apply_fields(qtbot, window)
    assert window.scene.landscape == "a*sin(k*x)*cos(k*y)+x"
    axis = window.view._axis
    drawn = drawn_heights(window)
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    shown = np.isfinite(drawn)
    assert np.allclose(drawn[shown], (0.5 * np.sin(xs) * np.cos(ys) + xs)[shown], atol=1e-9)


def test_a_parameter_without_a_range_gets_one_around_its_value(qtbot, window, tmp_path):
    assert slider_range(0.5, None, None) == (-0.5, 1.5)
    assert slider_range(-3.0, None, None) == (-6.0, 0.0)
    assert slider_range(2.0, 0.0, 5.0) == (0.0, 5.0)
    assert slider_value(500, -0.5, 1.5) == 0.5
    data = Scene.load(RIPPLES).to_dict()
    data["parameters"] = {"a": 0.5, "k": 1.0}
    path = tmp_path / "plain.json"
    path.write_text(json.dumps(data))
    assert window.files.open_scene(path)
    row = window.panel.parameter_rows.rows["k"]
    assert (row.low, row.high) == (0.0, 2.0) and row.slider.value() == SLIDER_STEPS // 2
    row.slider.setValue(SLIDER_STEPS)
    assert window.scene.parameter_values == (0.5, 2.0)
    assert window.files.save_to(path)
    assert json.loads(path.read_text())["parameters"] == {"a": 0.5, "k": 2.0}


def test_the_parameter_rows_follow_the_text_size(qtbot, ripples):
    window = ripples
    row = window.panel.parameter_rows.rows["a"]
    normal = row.edit.font().pointSizeF()
    window._set_text_size(1.5)
    assert row.edit.font().pointSizeF() == pytest.approx(1.5 * normal)
    assert row.label.font().pointSizeF() == pytest.approx(1.5 * normal)
    window._set_text_size(1.0)


def test_a_scene_without_parameters_shows_no_rows(qtbot, window):
    rows = window.panel.parameter_rows
    assert rows.rows == {} and rows.title.text() == "No parameters" and rows.add_button.isVisible()
    assert window.files.open_scene(RIPPLES, remember=False)
    assert list(rows.rows) == ["a", "k"] and rows.title.text() == "Parameters"
    assert window.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    assert rows.rows == {} and rows.title.text() == "No parameters"


def _add(qtbot, window, name=None, value="1.5", low="", high=""):
    """Add Parameter… as a user does: the dialog, its fields, Add."""
    rows = window.panel.parameter_rows
    qtbot.mouseClick(rows.add_button, QtCore.Qt.MouseButton.LeftButton)
    dialog = rows.dialog
    qtbot.waitExposed(dialog)
    if name is not None:
        dialog.name.setText(name)
    dialog.value.setText(value)
    dialog.low.setText(low)
    dialog.high.setText(high)
    return dialog


def test_a_parameter_is_added_for_a_name_the_formula_lacks_and_undone(qtbot, window):
    panel = window.panel
    before = window.scene
    set_field(qtbot, window, "landscape", "0.5*sin(b*x)*cos(y)")
    assert panel.marked == "landscape" and "unknown name 'b'" in panel.error_text
    dialog = _add(qtbot, window, low="0.5", high="3")
    assert dialog.name.text() == "b"                          # the name the formula lacks, proposed
    assert dialog.ok.isEnabled() and dialog.message.text() == ""
    qtbot.mouseClick(dialog.ok, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)                               # the formula is checked with b
    scene = window.scene
    assert scene.landscape == "0.5*sin(b*x)*cos(y)" and panel.error_text == ""
    assert [(p.name, p.value, p.min, p.max) for p in scene.parameters] == [("b", 1.5, 0.5, 3.0)]
    assert panel.formula.text() == "0.5*sin(b*x)*cos(y)"     # the text as typed
    assert window.undo_stack.undoText() == "Add parameter b"
    axis = window.view._axis
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    drawn = drawn_heights(window)
    shown = np.isfinite(drawn)
    assert np.allclose(drawn[shown], (0.5 * np.sin(1.5 * xs) * np.cos(ys))[shown], atol=1e-9)
    window.undo_stack.undo()
    assert window.scene == before and panel.parameter_rows.rows == {}
    window.undo_stack.redo()
    assert window.scene == scene and list(panel.parameter_rows.rows) == ["b"]


@pytest.mark.parametrize("name, value, low, high, why", [
    ("x", "1", "", "", "Name: 'x' is taken by the formula's own variables"),
    ("pi", "1", "", "", "Name: 'pi' is taken by the formula's own constants"),
    ("sin", "1", "", "", "Name: 'sin' is the name of a function"),
    ("2a", "1", "", "", "Name: a parameter's name must be an identifier (a letter, then letters, digits or _)"),
    ("a", "1", "", "", "Name: the scene has a parameter a already"),
    ("c", "one", "", "", "Value: not a number"),
    ("c", "1", "0", "", "Max: missing (a range has both ends)"),
    ("c", "1", "2", "1", "Min: must be less than max (got 2.0 and 1.0)"),
    ("c", "inf", "", "", "Value: must be a finite number"),
])
def test_a_new_parameter_is_checked_as_a_scene_file_is(qtbot, ripples, name, value, low, high, why):
    dialog = _add(qtbot, ripples, name, value, low, high)
    assert not dialog.ok.isEnabled() and dialog.message.text() == why
    dialog.reject()
    assert list(ripples.panel.parameter_rows.rows) == ["a", "k"]


def test_the_add_parameter_dialog_fits_its_message_and_leaves_no_strip_under_its_buttons(qtbot, ripples):
    dialog = _add(qtbot, ripples, "c")
    layout = dialog.layout()

    def strip() -> int:   # the empty height under the buttons
        qtbot.wait(20)
        return dialog.height() - dialog.buttons.geometry().bottom() - 1 - layout.contentsMargins().bottom()
    assert strip() == 0 and not dialog.message.isVisible()
    for name in ("2a", "a", "c"):   # a long message (two lines), a short one, none
        dialog.name.setText(name)
        assert strip() == 0
        message = dialog.message
        assert message.isVisible() == (name != "c")
        if message.isVisible():   # wholly shown, above the buttons
            assert message.geometry().bottom() < dialog.buttons.geometry().top()
            assert message.height() >= message.heightForWidth(message.width())
    dialog.resize(dialog.width(), dialog.height() + 60)   # made taller by hand: the room goes above the buttons
    assert strip() == 0
    dialog.reject()


def test_removing_a_parameter_keeps_what_was_typed_and_the_formula_is_checked_again(qtbot, ripples):
    window, panel = ripples, ripples.panel
    rows = panel.parameter_rows
    rows.rows["k"].edit.setText("2")                   # typed, not applied yet
    qtbot.mouseClick(rows.rows["a"].remove, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)
    assert list(rows.rows) == ["k"] and rows.rows["k"].edit.text() == "2"
    assert panel.formula.text() == "a*sin(k*x)*cos(k*y)"        # kept, and refused
    assert panel.marked == "landscape" and "unknown name 'a'" in panel.error_text
    assert window.scene.parameter_names == ("a", "k")           # the last valid scene stays
    set_field(qtbot, window, "landscape", "0.3*sin(k*x)*cos(k*y)")
    assert window.scene.parameters == (Parameter("k", 2.0, 0.5, 3.0),) and panel.error_text == ""
    assert window.undo_stack.undoText() == "Remove parameter a"
    window.undo_stack.undo()
    assert list(rows.rows) == ["a", "k"] and window.scene.landscape == "a*sin(k*x)*cos(k*y)"
    assert rows.rows["k"].edit.text() == "1.0"


def test_a_parameter_removed_by_mistake_comes_back_as_it_was(qtbot, ripples):
    window, rows = ripples, ripples.panel.parameter_rows
    rows.rows["a"].edit.setText("0.75")                     # typed, then removed at once
    qtbot.mouseClick(rows.rows["a"].remove, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)
    assert "unknown name 'a'" in window.panel.error_text
    qtbot.mouseClick(rows.add_button, QtCore.Qt.MouseButton.LeftButton)
    dialog = rows.dialog
    fields = (dialog.name.text(), dialog.value.text(), dialog.low.text(), dialog.high.text())
    assert fields == ("a", "0.75", "0.0", "1.0")
    qtbot.mouseClick(dialog.ok, QtCore.Qt.MouseButton.LeftButton)
    apply_fields(qtbot, window)
    assert window.panel.error_text == "" and window.scene.parameters[-1] == Parameter("a", 0.75, 0.0, 1.0)


def test_the_faster_redraw_draws_what_pyqtgraph_would():
    """Vertex normals made in numpy are pyqtgraph's own (to float32 rounding), and the camera's
    distance in closed form is where the bisection it replaced ended."""
    import pyqtgraph.opengl as gl

    from rollball_app.view3d import FILL, SceneView, look, project, surface_mesh

    axis = np.linspace(-2, 2, 41)
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    z = np.sin(xs) * np.cos(ys) + xs * xs
    mesh = surface_mesh(axis, z, np.ones(z.shape + (4,)), cap=3.0)
    reference = gl.MeshData(vertexes=mesh.vertexes(), faces=mesh.faces()).vertexNormals()
    assert np.abs(mesh.vertexNormals() - reference).max() < 1e-5
    rng = np.random.default_rng(1)
    for _ in range(50):
        corners = rng.normal(size=(8, 3)) * rng.uniform(0.1, 5)
        center = corners.mean(axis=0)
        elevation, azimuth, aspect = rng.uniform(-10, 89), rng.uniform(0, 360), rng.uniform(0.4, 1.5)
        d = SceneView._fit_distance(corners, center, elevation, azimuth, 60.0, aspect)
        seen = project(corners, look(center, d * (1 + 1e-9), elevation, azimuth), center, 60.0, aspect)
        closer = project(corners, look(center, d * (1 - 1e-6), elevation, azimuth), center, 60.0, aspect)
        assert np.abs(seen).max() <= FILL and np.abs(closer).max() > FILL


def test_a_slider_keeps_the_camera_and_the_height_axis_follows(qtbot, ripples):
    window = ripples
    view = window.view
    view.orbit(30, 10)   # the user turned the camera
    camera = (view.opts["distance"], view.opts["elevation"], view.opts["azimuth"])

    def top():   # the height axis's upper end
        return float(view.axes.pos[:, 2].max())
    low = top()
    window.panel.parameter_rows.rows["a"].slider.setValue(SLIDER_STEPS)   # a = 1: twice as high
    assert (view.opts["distance"], view.opts["elevation"], view.opts["azimuth"]) == camera
    assert top() > low + 0.1   # (the surface is cut at the height the ball can reach)


BIGGEST = 1.7976931348623157e308


@pytest.mark.parametrize("value, low, high", [
    (0.0, -1.7e308, 1.7e308),            # a width that is not a finite float
    (BIGGEST, -BIGGEST, BIGGEST),
    (1.5e308, 1e308, BIGGEST),
    (0.0, 0.0, 5e-324),                  # a width below the smallest step
    (0.0, -1e-300, 1e-300),
    (1.7e308, None, None),               # no range: one around the value, within the floats
    (-BIGGEST, None, None),
    (1e300, None, None),
])
def test_a_slider_over_any_finite_range_never_raises_and_gives_values_within_it(qtbot, value, low, high):
    rows = ParameterRows()
    qtbot.addWidget(rows)
    dragged = []
    rows.dragged.connect(dragged.append)
    rows.add("k", value, low, high)
    row = rows.rows["k"]
    assert math.isfinite(row.low) and math.isfinite(row.high) and row.low < row.high
    assert 0 <= row.slider.value() <= SLIDER_STEPS
    for position in (0, 1, 2, SLIDER_STEPS // 2, SLIDER_STEPS - 1, SLIDER_STEPS, 0):
        row.slider.setValue(position)     # as a drag or a key would (an error here fails the test)
        shown = float(row.edit.text())
        assert math.isfinite(shown) and row.low <= shown <= row.high
        if row.high / SLIDER_STEPS - row.low / SLIDER_STEPS > 1e-300:   # (not 1000 values apart below)
            assert slider_position(shown, row.low, row.high) == pytest.approx(position, abs=1)
    assert dragged and set(dragged) == {"k"}
    row.set_value(value)
    assert 0 <= row.slider.value() <= SLIDER_STEPS


def test_the_slider_functions_are_finite_for_any_finite_range():
    for low, high in [(-BIGGEST, BIGGEST), (-1.7e308, 1.7e308), (0.0, BIGGEST), (-BIGGEST, 0.0), (0.0, 5e-324)]:
        values = [slider_value(position, low, high) for position in range(SLIDER_STEPS + 1)]
        assert all(math.isfinite(v) and low <= v <= high for v in values)
        assert values[0] == low and values[-1] == high
        assert values == sorted(values)
        for v in (low, high, values[SLIDER_STEPS // 2], -math.inf, math.inf, math.nan):
            assert 0 <= slider_position(v, low, high) <= SLIDER_STEPS
    assert slider_range(1.7e308, None, None) == (0.0, BIGGEST)
    assert slider_range(-1.7e308, None, None) == (-BIGGEST, 0.0)
    assert slider_value(500, -0.5, 1.5) == 0.5 and slider_value(1, 0.0, 1.0) == 0.001
