"""Compare mode, driven as a user drives it: several methods on one scene, their true errors."""

import numpy as np
import pytest
from PySide6 import QtGui

from rollball_app.compare_runs import COLORS, CompareRun, reference_spacing
from rollball_app.controller import FINISHED
from rollball import METHODS, parse_runs
from rollball.comparison import reference_method
from rollball.reference import reference_solution
from rollball.trajectory import CONTACT

from .guitools import FASTEST, set_field
from .test_plots import assert_legible

SPECS = "euler/classic,rk4,dopri5"


def compare_to_end(qtbot, window, specs=SPECS, timeout=60_000):
    window.compare.enter([CompareRun.of(spec, window.scene) for spec in parse_runs(specs)])
    window.speed.setCurrentIndex(FASTEST)
    with qtbot.waitSignal(window.controller.measured, timeout=timeout):
        window.runs.start()
        qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=timeout)


@pytest.fixture
def compared(qtbot, window):
    set_field(qtbot, window, "duration", "2")
    compare_to_end(qtbot, window)
    return window


def test_three_runs_play_to_the_end_each_in_its_colour(compared):
    w = compared
    runs = w.controller.runs
    assert [run.label for run in runs] == ["Euler classic, h = 0.001", "RK4 Munthe-Kaas, h = 0.001",
                                           f"{METHODS['dopri5'].label}, rtol = 1e-06"]
    assert [run.color for run in runs] == list(COLORS[:3])
    assert all(run.buffer.end_time == 2.0 for run in runs)
    assert len(w.view.balls) == len(w.view.trails) == 3
    assert all(len(trail.pos) > 100 for trail in w.view.trails)
    assert [row["t"].text() for row in w.readouts.rows] == ["2.0000 s"] * 3
    assert w.readouts.names[0].text() == "● Euler classic, h = 0.001"
    assert w.message.text() == "Finished comparing 3 runs"
    assert w.progress.value() == 1000


def test_the_legend_names_every_run_and_the_reference(compared):
    labels = [label.text for _, label in compared.compare.error_plots.legend.items]
    assert labels[:3] == [run.label for run in compared.controller.runs]
    reference, estimate = compared.controller.reference
    assert labels[3] == f"Reference: {METHODS[reference_method()].label} at rtol 1e-13, own error ≈ {estimate:.1g} m"
    assert 0 < estimate < 1e-9 and reference.t[-1] == 2.0


def test_error_plots_hold_data_for_every_run_and_euler_is_worst(qtbot, compared):
    for k, curves in enumerate(compared.compare.error_plots.curves):
        for key, curve in curves.items():
            t, y = curve.xData, curve.yData
            assert len(t) > 50 and t[-1] == 2.0, (k, key)
            assert np.all(np.isfinite(y)) and np.all(y > 0)
    for key, plot in compared.compare.error_plots.plots.items():   # whole decades, labelled legibly
        low, high = plot.viewRange()[1]
        data = np.concatenate([curves[key].yData for curves in compared.compare.error_plots.curves]
                              + [[compared.controller.reference[1]]] * (key == "contact"))   # its floor too
        assert low == np.floor(np.log10(data.min())) and high == np.ceil(np.log10(data.max()))
        assert_legible(qtbot, plot.getAxis("left"))
    euler, rk4, _ = (run.errors["contact"] for run in compared.controller.runs)
    assert np.nanmax(euler) > 1e4 * np.nanmax(rk4)
    # the classic Euler run's error at the end, measured against scipy's DOP853 instead
    alpha, _, _ = reference_solution(compared.scene, [2.0])
    run = compared.controller.runs[0]
    assert np.linalg.norm(run.buffer.rows[-1, CONTACT] - alpha[-1]) == pytest.approx(euler[-1], rel=1e-3)


def test_the_summary_compares_the_runs(compared):
    table = compared.compare.summary
    assert [table.value("Status", k) for k in range(3)] == ["ok"] * 3
    assert table.value("Steps", 0) == table.value("Steps", 1) == "2,000"
    assert table.value("Evaluations", 1) == "8,001"
    euler, rk4 = (float(table.value("Max error (m)", k)) for k in (0, 1))
    assert euler > 1e4 * rk4
    assert float(table.value("Error at end (m)", 0)) <= euler
    assert all(float(table.value("Compute time (s)", k)) > 0 for k in range(3))


def test_a_run_can_be_hidden_and_followed(qtbot, compared):
    w = compared
    w.compare.panel.rows[1].shown.setChecked(False)
    assert not w.view.balls[1].visible() and not w.view.trails[1].visible()
    assert not w.compare.error_plots.curves[1]["contact"].isVisible()
    w.compare.panel.follow.setCurrentIndex(2)
    w.follow_action.setChecked(True)
    assert w.view.followed == 2
    center = w.view.opts["center"]
    assert np.allclose([center.x(), center.y(), center.z()], w.view.centers[2])


def test_presets_and_the_panel_make_valid_runs(qtbot, window):
    window.compare_action.setChecked(True)
    assert window.compare.dock.isVisible()
    panel = window.compare.panel
    assert [str(run.spec) for run in panel.runs()] == ["euler/classic", "rk4/classic", "rk4"]
    panel.use_preset("Classic against Munthe-Kaas")
    assert len(panel.rows) == 6 and not panel.add_button.isEnabled()
    panel.rows[0].method.setCurrentIndex(panel.rows[0].method.findData("dopri5"))
    assert panel.runs()[0] == CompareRun(parse_runs("dopri5")[0], window.scene.integrator.rtol)
    assert not panel.rows[0].munthe_kaas.isEnabled()
    panel.rows[1].setting.setText("-1")
    panel.rows[1].setting.editingFinished.emit()
    assert "step size must be a number greater than 0" in panel.error.text()
    window.compare_action.setChecked(False)
    assert not window.compare.dock.isVisible() and window.bottom.currentWidget() is window.plots


def test_reference_rows_meet_every_run():
    scene_runs = [CompareRun(parse_runs("euler")[0], 0.002), CompareRun(parse_runs("rk4")[0], 0.01)]
    assert reference_spacing(scene_runs, 10.0) == 0.002
    assert reference_spacing([CompareRun(parse_runs("rk4")[0], 0.003), *scene_runs], 10.0) == 10.0 / 10_000
    assert reference_spacing([CompareRun(parse_runs("rk4")[0], 1e-5)], 10.0) == pytest.approx(2e-4)


def test_the_command_line_refuses_a_bad_spec(capsys):
    from rollball_app.main import main

    with pytest.raises(SystemExit) as exit:
        main(["--compare", "euler/classic,gauss9"])
    assert exit.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("rollball-app: error: --compare: unknown run 'gauss9'") and err.count("\n") == 1


def test_every_ball_stands_at_the_start_until_its_run_has_rows(qtbot, window):
    window.compare.enter([CompareRun.of(spec, window.scene) for spec in parse_runs(SPECS)])
    window.runs.start()   # the runs' first rows arrive through the event loop, not yet
    view = window.view
    first = view.balls[0].transform()
    assert len(view.balls) == 3 and all(ball.transform() == first for ball in view.balls)
    center = first.map(QtGui.QVector3D(0, 0, 0))
    assert np.allclose([center.x(), center.y(), center.z()], view.centers[0])
    assert first.map(QtGui.QVector3D(1, 0, 0)).distanceToPoint(center) == pytest.approx(window.scene.ball.radius)
    window.runs.reset()
