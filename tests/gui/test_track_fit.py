"""File → Import Measured Track… and Analysis → Fit to Track… (docs/design.md §10): the track's
points over the 3-D view, its residual in the status bar, a refused file, a fit driven in its
dialog to the values the example track was made with, Cancel, and Apply undone."""

import numpy as np
import pytest
from PySide6 import QtCore, QtWidgets

from rollball import Scene, Track
from rollball.examples import EXAMPLES_DIR
from rollball.landscape import landscape_of
from rollball_app.controller import PAUSED
from rollball_app.fit_dialog import FitDialog
from rollball_app.track_import import TrackImportDialog
from rollball_app.track_view import LIFT

from .guitools import run_to_end

TRACK = EXAMPLES_DIR / "billiard_track.csv"
TRUTH = {"contact.friction": 0.25, "start.vx": 2.2}   # what the example track was made with


@pytest.fixture
def billiard(window):
    window.files.open_scene(EXAMPLES_DIR / "billiard.json", remember=False)
    return window


def _choose(monkeypatch, path, mapping=0, length="m"):
    """The file dialog answers ``path``; the import dialog is answered with the mapping at that index
    and the length unit ``length``."""
    monkeypatch.setattr(QtWidgets.QFileDialog, "getOpenFileName", lambda *a, **k: (str(path), ""))

    def answer(dialog):
        dialog.mapping.setCurrentIndex(mapping)
        dialog.length_unit.setCurrentIndex(dialog.length_unit.findData(length))
        return QtWidgets.QDialog.DialogCode.Accepted

    monkeypatch.setattr(TrackImportDialog, "exec", answer)


def test_an_imported_track_is_drawn_on_the_surface_and_compared_with_the_scene(qtbot, billiard, monkeypatch):
    w = billiard
    _choose(monkeypatch, TRACK)
    w.measured.import_action.trigger()
    track = Track.load(TRACK)
    measured = w.measured
    assert measured.track is not None and len(track) == 69
    points = measured.seen.pos
    assert points.shape == (69, 3) and measured.seen.visible() and not measured.ahead.visible()
    np.testing.assert_allclose(points[:, :2], track.positions)   # x, y as measured
    scene = w.scene
    surface = landscape_of(scene).evaluate(points[:, 0], points[:, 1], scene.parameter_values)[0]
    np.testing.assert_allclose(points[:, 2], surface + LIFT * w.view.extent)   # on the surface
    assert "Imported billiard_track.csv: 69 positions (x, y)" in w.message.text()
    assert "3 frames without a position skipped" in w.message.text()
    assert w.measured.close_action.isEnabled()

    qtbot.waitUntil(lambda: measured.residuals is not None, timeout=30_000)
    assert not measured.residuals.explained             # the scene has μ 0.2 and v0 2.0, not the track's
    assert measured.label.isVisible() and "not explained" in measured.label.text()
    assert "the model does not explain the track" in w.message.text()

    # playback: the points up to the shown time full, those ahead faint (played to its end: a
    # seek while it still plays, as on a loaded machine after the computing is done, plays on)
    run_to_end(qtbot, w)
    w.runs.seek(0.5)
    assert w.controller.state == PAUSED
    up_to = int(np.sum(track.t <= w.controller.play_time + 1e-9))
    assert 0 < up_to < 69
    assert measured.seen_count() == up_to and len(measured.ahead.pos) == 69 - up_to

    # the plots: the track's x and y against time as dots, the run's centre beside them as lines,
    # the playback cursor on the track's plot too
    plot = w.plots.track_plot
    assert plot is not None and plot in w.plots.plots
    dots = {item.name(): item for item in plot.listDataItems() if item.name()}
    for k, axis in enumerate(("x", "y")):
        t, values = dots[f"track.{axis}"].getData()
        np.testing.assert_array_equal(t, track.t)
        np.testing.assert_array_equal(values, track.positions[:, k])
        t, run = w.plots.track_curves[axis].getData()
        assert len(t) > 10 and t[-1] == pytest.approx(w.scene.duration)   # (the computed run, as the other plots)
    assert w.plots.track_cursor.isVisible() and w.plots.track_cursor.value() == pytest.approx(0.5, abs=0.02)

    w.measured.close_action.trigger()
    assert measured.track is None and not measured.seen.visible() and not measured.ahead.visible()
    assert not measured.label.isVisible() and not w.measured.close_action.isEnabled()
    assert w.plots.track_plot is None and "plot.track" not in [plot.objectName() for plot in w.plots.plots]


def test_a_side_view_in_centimetres_is_drawn_as_measured(qtbot, billiard, monkeypatch, tmp_path):
    path = tmp_path / "side.csv"
    path.write_text("mass A\nt\tx (cm)\ty (cm)\n0.0\t10\t5\n0.1\t20\t6\n0.2\t30\t7\n")
    _choose(monkeypatch, path, mapping=1)   # the file's x, y are the scene's x, z
    assert billiard.measured.import_dialog()
    track = billiard.measured.track
    assert track.axes == ("x", "z")
    y = billiard.scene.start.y
    np.testing.assert_allclose(billiard.measured.seen.pos, [[0.1, y, 0.05], [0.2, y, 0.06], [0.3, y, 0.07]])


def test_the_unit_chosen_applies_where_the_header_names_none(qtbot, billiard, monkeypatch, tmp_path):
    path = tmp_path / "top.csv"
    path.write_text("t,x,y,z\n0.0,10,5,10\n0.1,20,6,10\n")
    _choose(monkeypatch, path, length="cm")
    assert billiard.measured.import_dialog()
    np.testing.assert_allclose(billiard.measured.track.positions, [[0.1, 0.05, 0.1], [0.2, 0.06, 0.1]])
    np.testing.assert_allclose(billiard.measured.seen.pos, billiard.measured.track.positions)   # z as measured


def test_a_bad_track_file_is_refused_in_one_line_and_the_track_shown_stays(qtbot, billiard, dialogs, tmp_path):
    assert billiard.measured.load(TRACK)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,x,y\n0.1,1,2\n0.2,abc,3\n")
    assert not billiard.measured.load(bad)
    (kind, title, text), = dialogs
    assert (kind, title) == ("warning", "Cannot import track")
    assert text == "bad.csv: line 3: column x: abc is not a number"
    assert billiard.message.text() == text
    assert len(billiard.measured.track) == 69 and len(billiard.measured.seen.pos) == 69   # nothing lost


def _fit_dialog(qtbot, window) -> FitDialog:
    window.measured.fit_action.trigger()
    dialog = window.findChild(FitDialog)
    qtbot.waitExposed(dialog)
    return dialog


def test_a_fit_finds_the_track_values_and_apply_is_one_undoable_change(qtbot, billiard):
    w = billiard
    w.measured.load(TRACK)
    before = w.scene
    dialog = _fit_dialog(qtbot, w)
    assert not dialog.fit_button.isEnabled()   # nothing ticked yet
    for key in TRUTH:
        dialog.check(key)
    qtbot.mouseClick(dialog.fit_button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: dialog.thread is None, timeout=60_000)
    result = dialog.result
    assert result is not None and result.converged
    for key, value, error in zip(result.keys, result.values, result.errors):
        assert abs(value - TRUTH[key]) < 3 * error, (key, value, error)
        row = dialog.keys.index(key)
        assert dialog.table.item(row, 5).text() == f"{value:.6g}" and dialog.table.item(row, 6).text() == f"{error:.2g}"
    assert dialog.runs_label.text() == f"{result.runs} runs"
    assert "the model explains the track" in dialog.status.text()
    assert "Correlation of start.vx and contact.friction" in dialog.status.text()

    qtbot.mouseClick(dialog.apply_button, QtCore.Qt.MouseButton.LeftButton)
    estimates = dialog.estimates()
    assert w.scene.contact.friction == estimates["contact.friction"] and w.scene.start.vx == estimates["start.vx"]
    assert "Fitted to the track billiard_track.csv" in w.scene.description
    assert w.undo_action.text() == "&Undo Apply Fit to Track"
    qtbot.waitUntil(lambda: w.measured.residuals is not None and w.measured.residuals.explained, timeout=30_000)
    row = dialog.keys.index("start.vx")
    assert float(dialog.table.item(row, 2).text()) == estimates["start.vx"]   # the next fit starts there
    w.undo_action.trigger()                                  # one step puts every old value back
    assert w.scene == before
    assert dialog.table.item(row, 2).text() == "2.0" and dialog.checked() == ["start.vx", "contact.friction"]
    assert w.panel.numbers["start.vx"].text() == "2.0"
    dialog.close()


def test_cancel_stops_a_fit(qtbot, billiard, monkeypatch):
    import threading

    import rollball.fitting

    real = rollball.fitting.run_for
    gate, calls = threading.Event(), []

    def slow(scene, track):   # the third run waits until Cancel was clicked: the count cannot run on
        calls.append(scene)
        if len(calls) > 2:
            gate.wait(30)
        return real(scene, track)

    monkeypatch.setattr(rollball.fitting, "run_for", slow)
    w = billiard
    w.measured.load(TRACK)
    before = w.scene
    dialog = _fit_dialog(qtbot, w)
    for key in TRUTH:
        dialog.check(key)
    qtbot.mouseClick(dialog.fit_button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: dialog.runs >= 2, timeout=30_000)
    assert dialog.cancel_button.isEnabled() and not dialog.fit_button.isEnabled()
    qtbot.mouseClick(dialog.cancel_button, QtCore.Qt.MouseButton.LeftButton)
    gate.set()
    qtbot.waitUntil(lambda: dialog.thread is None, timeout=10_000)
    assert dialog.result is None and not dialog.apply_button.isEnabled()
    assert dialog.status.text().startswith(f"Cancelled after {dialog.runs} runs")
    assert dialog.runs <= 3   # stopped before its next run (a fit of two values takes more than that)
    assert w.scene == before and dialog.fit_button.isEnabled()

    qtbot.mouseClick(dialog.fit_button, QtCore.Qt.MouseButton.LeftButton)   # again, then closed meanwhile
    worker = dialog.thread
    qtbot.waitUntil(lambda: dialog.runs >= 1, timeout=30_000)
    dialog.close()
    assert not worker.is_running() and w.scene == before


def test_a_value_the_scene_cannot_start_from_is_offered_but_not_tickable(qtbot, window):
    """The hills example has a null friction (the ball always rolls): nothing to start a fit from."""
    window.measured.load(TRACK)
    dialog = _fit_dialog(qtbot, window)
    row = dialog.keys.index("contact.friction")
    assert not dialog.table.item(row, 0).flags() & QtCore.Qt.ItemFlag.ItemIsEnabled
    assert "null" in dialog.table.item(row, 0).toolTip()
    assert Scene.load(EXAMPLES_DIR / "hills.json").contact.friction is None
    dialog.close()
