"""Analysis → Sweep…: a tiny sweep run in the dialog, and a click on the map loads that run's start."""

import numpy as np
from PySide6 import QtCore

from rollball_app.controller import READY
from rollball_app.sweep_dialog import SweepDialog, tidy

from .guitools import set_field


def _open(qtbot, window) -> SweepDialog:
    window.sweep_action.trigger()
    dialog = window.findChild(SweepDialog)
    qtbot.waitExposed(dialog)
    return dialog


def _set_row(row, key, lo, hi, n):
    row.key.setCurrentIndex(row.key.findData(key))
    row.lo.setText(str(lo))
    row.hi.setText(str(hi))
    row.n.setValue(n)


def _run(qtbot, dialog):
    qtbot.mouseClick(dialog.run_button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: dialog.thread is None and dialog.table is not None, timeout=60_000)


def test_a_sweep_runs_in_the_dialog_and_a_click_loads_its_start(qtbot, window):
    dialog = _open(qtbot, window)
    _set_row(dialog.rows[0], "start.vx", -1.0, 1.0, 5)
    _set_row(dialog.rows[1], "start.spin", -2.0, 2.0, 3)
    dialog.color.setCurrentIndex(dialog.color.findData("x_end"))
    _run(qtbot, dialog)
    table = dialog.table
    assert len(table) == 15 and not table.partial and dialog.progress.value() == 15
    shown = dialog.image.image
    assert shown.shape == (3, 5)                                   # rows: spin, columns: vx
    np.testing.assert_array_equal(shown[2, 1], table["x_end"][1 * 3 + 2])   # vx = -0.5, spin = 2

    # click the cell of vx = 0.5, spin = -2 as a user does
    vb = dialog.plot_item.vb
    pos = dialog.plot.mapFromScene(vb.mapViewToScene(QtCore.QPointF(0.5, -2.0)))
    qtbot.mouseClick(dialog.plot.viewport(), QtCore.Qt.MouseButton.LeftButton, pos=pos)
    qtbot.waitUntil(lambda: window.scene.start.vx == 0.5)
    assert window.scene.start.spin == -2.0
    assert window.panel.numbers["start.vx"].text() == "0.5"
    assert window.controller.state == READY and window.start_action.isEnabled()
    window.undo_action.trigger()                                  # the loaded run is one undo step
    assert window.scene.start.vx == 0.0
    dialog.close()


def test_one_key_gives_a_curve_and_cancel_stops_the_sweep(qtbot, window):
    dialog = _open(qtbot, window)
    dialog.rows[1].enabled.setChecked(False)
    _set_row(dialog.rows[0], "start.vx", 0.0, 1.0, 3000)
    dialog.color.setCurrentIndex(dialog.color.findData("liftoff_time"))
    qtbot.mouseClick(dialog.run_button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: dialog.progress.value() > 0, timeout=60_000)
    qtbot.mouseClick(dialog.cancel_button, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: dialog.thread is None, timeout=60_000)
    assert dialog.table.partial and "cancelled" in dialog.status.text()
    assert dialog.note.text() == f"No run has a value to show (no lift-off: {dialog.table.done.sum()})"
    dialog.color.setCurrentIndex(dialog.color.findData("x_end"))
    x, y = dialog.curve.getData()
    assert len(x) == 3000 and np.isfinite(y).sum() == dialog.table.done.sum()
    dialog.close()


def test_bad_ranges_are_said_in_the_dialog(qtbot, window):
    dialog = _open(qtbot, window)
    dialog.rows[0].lo.setText("fast")
    qtbot.mouseClick(dialog.run_button, QtCore.Qt.MouseButton.LeftButton)
    assert "must be numbers" in dialog.status.text() and dialog.thread is None
    dialog.close()


def test_the_default_sweep_shows_a_map_says_its_method_and_loads_tidy_values(qtbot, window):
    set_field(qtbot, window, "duration", "0.5")   # short runs; the default keys and outcome
    dialog = _open(qtbot, window)
    assert dialog.method_note.text().startswith("Each run: RK4, step h = 0.001 s, to t = 0.5 s")
    _set_row(dialog.rows[0], "start.vx", -2.0, 2.0, 81)   # spacing 0.05: values such as 1.9500000000000002
    dialog.rows[1].n.setValue(5)
    _run(qtbot, dialog)
    assert dialog.color.currentData() == "min_normal_force" and dialog.note.text() == ""
    assert dialog.colorbar.isVisible() and np.isfinite(dialog.image.image).all()   # not an empty map
    assert dialog.pick(1.95, 0.0) is not None
    qtbot.waitUntil(lambda: window.panel.numbers["start.vx"].text() == "1.95")
    assert window.panel.numbers["start.spin"].text() == "0.0"
    dialog.close()


def test_grid_values_are_rounded_to_the_grid_precision():
    assert list(tidy(np.linspace(-2.0, 2.0, 81))[78:]) == [1.9, 1.95, 2.0]
    assert 1.9500000000000002 in np.linspace(-2.0, 2.0, 81)   # (what a plain grid holds)
    assert list(tidy(np.linspace(0.0, 1e-3, 3))) == [0.0, 0.0005, 0.001]
    assert list(tidy(np.linspace(0.5, 3.0, 3))) == [0.5, 1.75, 3.0]       # not 1.8


def test_a_parameter_is_swept_like_any_key_and_a_click_loads_its_value(qtbot, window):
    from rollball.examples import EXAMPLES_DIR
    assert window.files.open_scene(EXAMPLES_DIR / "ripples.json", remember=False)
    dialog = _open(qtbot, window)
    row = dialog.rows[0]
    keys = [row.key.itemData(i) for i in range(row.key.count())]
    assert keys[-2:] == ["parameters.a", "parameters.k"] and row.key.itemText(len(keys) - 1) == "parameters.k"
    row.key.setCurrentIndex(row.key.findData("parameters.k"))      # its range is filled in
    assert (row.lo.text(), row.hi.text()) == ("0.5", "3.0")
    dialog.rows[1].enabled.setChecked(False)
    row.n.setValue(3)                                              # k = 0.5, 1.75, 3
    dialog.color.setCurrentIndex(dialog.color.findData("x_end"))
    _run(qtbot, dialog)
    table = dialog.table
    assert table.keys == ("parameters.k",) and len(table) == 3 and table.done.all()
    assert dialog.plot_item.getAxis("bottom").labelText == "parameters.k"
    scene = dialog.pick(1.75, 0.0)
    assert scene.parameter_values == (0.5, 1.75)
    qtbot.waitUntil(lambda: window.scene.parameter_values == (0.5, 1.75))
    assert window.panel.parameter_rows.rows["k"].edit.text() == "1.75"
    window.undo_action.trigger()
    assert window.scene.parameter_values == (0.5, 1.0)
    dialog.close()


def test_friction_and_restitution_are_swept_with_their_own_ranges(qtbot, window):
    from rollball.examples import EXAMPLES_DIR
    assert window.files.open_scene(EXAMPLES_DIR / "billiard.json", remember=False)
    dialog = _open(qtbot, window)
    row = dialog.rows[0]
    mu = window.scene.contact.friction
    row.key.setCurrentIndex(row.key.findData("contact.friction"))     # 0 to twice the scene's
    assert (float(row.lo.text()), float(row.hi.text())) == (0.0, 2 * mu)
    row.key.setCurrentIndex(row.key.findData("contact.restitution"))
    assert (row.lo.text(), row.hi.text()) == ("0.0", "1.0")
    _set_row(row, "contact.friction", 0.1, 0.4, 2)
    dialog.rows[1].enabled.setChecked(False)
    dialog.color.setCurrentIndex(dialog.color.findData("first_slip_time"))
    _run(qtbot, dialog)
    table = dialog.table
    assert table.keys == ("contact.friction",) and table.done.all() and set(table["status"]) == {"ok"}
    np.testing.assert_array_equal(table["first_slip_time"], 0.0)   # struck without spin: it slides at once
    # the axes read the friction's own values, 0.1 to 0.4 (no "(x0.001)" and ticks 100 to 400)
    bottom = dialog.plot_item.getAxis("bottom")
    assert "x0." not in bottom.labelString() and bottom.scale == 1.0
    dialog.close()


def test_a_sweep_says_whether_its_runs_went_to_worker_processes_or_threads(qtbot, window):
    from rollball.examples import EXAMPLES_DIR

    window.files.open_scene(EXAMPLES_DIR / "liftoff.json", remember=False)
    dialog = _open(qtbot, window)
    dialog.rows[1].enabled.setChecked(False)
    # runs that can come to rest go through the mode machine, whose Python holds the interpreter's
    # lock: worker processes (enough runs to repay starting them)
    _set_row(dialog.rows[0], "contact.rolling_resistance", 0.001, 0.01, 120)
    _run(qtbot, dialog)
    table = dialog.table
    assert table.done.all() and table.error is None and (table["landings"] >= 0).all()
    where = "worker processes" if table.workers > 1 else "worker threads"
    assert table.processes == (table.workers > 1) and f"on {table.workers} {where}" in dialog.status.text()
    # runs that only roll and fly (friction empty) stay in the compiled batch loop: threads
    _set_row(dialog.rows[0], "start.vx", 3.0, 6.0, 120)
    _run(qtbot, dialog)
    table = dialog.table
    assert table.done.all() and table.error is None and (table["landings"] >= 1).sum() > 60
    assert not table.processes and f"on {table.workers} worker threads" in dialog.status.text()
    dialog.close()
