"""The energy budget: a stacked plot beside the energy error of the ball's energy and what each
cause has taken so far, only the causes that are on, its top the conserved E + ΣD, its key giving
each band's value at the moment shown; live during a run, and in compare mode of the run followed."""

import numpy as np
import pyqtgraph as pg
import pytest

from rollball import Scene, Trajectory
from rollball.examples import EXAMPLES_DIR
from rollball.kernel import ROW_SIZE
from rollball.trajectory import DISSIPATION_CAUSES, Transition
from rollball_app.budget import EnergyBudget, acting, causes_on, floor_energy
from rollball_app.controller import RUNNING
from rollball_app.parameters import valued
from rollball_app.error_plots import ErrorPlots
from rollball_app.plots import LivePlots, least_width

from .guitools import FASTEST, run_to_end
from .test_compare import compare_to_end


def _scene(**changes) -> Scene:
    data = Scene.load(EXAMPLES_DIR / "billiard.json").to_dict()
    for key, value in changes.items():
        group, _, name = key.rpartition(".")
        holder = data.setdefault(group, {}) if group else data
        if value is None and key == "start.omega":
            del holder[name]   # the rolling start
        else:
            holder[name] = value
    return Scene.from_dict(data)


def test_the_causes_on_are_those_the_scene_has():
    assert causes_on(Scene.load(EXAMPLES_DIR / "hills.json")) == ()   # the 2011 model: none
    assert causes_on(_scene()) == ("sliding", "impacts")               # friction, flies and lands
    scene = _scene(**{"contact.friction": None, "contact.after_liftoff": "glued", "start.omega": None,
                      "contact.rolling_resistance": 0.05, "air": {"density": 1.2, "drag_coefficient": 0.47}})
    assert causes_on(scene) == ("rolling", "air")
    assert causes_on(_scene(**{"contact.spin_friction": 0.1})) == ("sliding", "impacts", "spin")


def test_a_cause_is_listed_where_its_mechanism_is_on_in_the_run():
    """The coefficients' causes from the start; impacts, which have none, once the run has landed."""
    causes = ("sliding", "impacts", "rolling")
    assert acting(causes, None) == ("sliding", "rolling")
    assert acting(causes, Trajectory(np.zeros((2, ROW_SIZE)))) == ("sliding", "rolling")
    assert acting(causes, _landed()) == causes


def _landed() -> Trajectory:
    """Three rows, t = 0, 1, 2, a landing at t = 1 that took 3.35 J."""
    rows = np.zeros((3, ROW_SIZE))
    rows[:, 0] = [0.0, 1.0, 2.0]
    return Trajectory(rows, transitions=(Transition(1.0, "landing", 0.0, 0.0, 2.0, 3.35),))


def test_a_band_that_comes_lays_the_plots_out_again(qtbot):
    """Where a landing brings the impacts' line to the key beside the budget, the plots are laid out
    again for the wider key: none runs off the right edge (the normal force folds)."""
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.resize(1920, 190)
    plots.show()
    qtbot.waitExposed(plots)
    plots.set_budget(("impacts",), 0.0)
    assert plots.budget.causes == ()
    energy, orthogonality, force = plots.plots[:3]
    width = round(least_width(plots.graphics, [energy, plots.budget_plot, plots.budget.key, orthogonality, force])) + 2
    plots.resize(width, 190)
    qtbot.wait(10)
    assert plots.folded == []
    plots.show_budget(_landed(), 2, 2)
    qtbot.wait(10)
    assert plots.budget.causes == ("impacts",) and plots.budget.values["impacts"] == pytest.approx(3.35)
    assert plots.folded
    for item in plots.arranged:
        assert item.sceneBoundingRect().right() <= plots.graphics.width() + 1


def _liftoff(tmp_path, duration: float):
    """The lift-off example (no friction: impacts are all that can take its energy; it leaves the
    hill at 0.45 s and lands at 0.89 s) to ``duration``."""
    scene = Scene.load(EXAMPLES_DIR / "liftoff.json")
    data = scene.to_dict() | {"duration": duration}
    path = tmp_path / "flight.json"
    Scene.from_dict(data).save(path)
    return path


def test_a_run_that_flies_but_has_not_landed_lists_no_impacts(qtbot, window, tmp_path):
    """Cut short in flight, the run has had no impact: the key says the ball's energy alone, no
    "impacts 0 J"; run on past its landing, the impacts are listed with what the landing took."""
    window.files.open_scene(_liftoff(tmp_path, 0.8), remember=False)
    budget = window.plots.budget
    assert budget.possible == ("impacts",) and budget.causes == ()   # before the run: nothing has landed
    run_to_end(qtbot, window)
    trajectory = window.controller.runs[0].trajectory()
    assert "flying" in trajectory.mode and trajectory.landings == 0
    assert budget.causes == () and set(budget.tops) == {"energy"} and "impacts" not in budget.key.text
    assert set(budget.values) == {"energy"}
    window.files.open_scene(_liftoff(tmp_path, 1.0), remember=False)
    run_to_end(qtbot, window)
    trajectory = window.controller.runs[0].trajectory()
    [landing] = [change for change in trajectory.transitions if change.kind == "landing"]
    assert budget.causes == ("impacts",) and "impacts" in budget.key.text
    assert budget.values["impacts"] == pytest.approx(landing.energy_lost, rel=1e-12) and landing.energy_lost > 0.0


def test_the_floor_is_a_ball_at_rest_at_the_lowest_point_drawn():
    scene = Scene.load(EXAMPLES_DIR / "bowl.json")   # z = (x² + y²)/2, lowest 0 at the centre
    m, g, r = scene.ball.mass, scene.gravity, scene.ball.radius
    assert floor_energy(scene, valued(scene)) == pytest.approx(m * g * r, abs=1e-12)


def test_bands_stack_to_the_conserved_top_and_the_key_says_each_at_the_moment_shown(qtbot):
    widget = pg.GraphicsLayoutWidget()
    qtbot.addWidget(widget)
    plot = widget.addPlot()
    budget = EnergyBudget(plot)
    budget.set_causes(("rolling", "air"))
    t = np.linspace(0.0, 2.0, 5)
    rolling, air = np.array([0.0, 0.1, 0.2, 0.3, 0.4]), np.array([0.0, 0.05, 0.1, 0.15, 0.2])
    energy = 1.0 - rolling - air   # a ball that gives 0.6 J of its 1 J to rolling resistance and air
    by = {cause: np.zeros(5) for cause in DISSIPATION_CAUSES} | {"rolling": rolling, "air": air}
    budget.show(t, energy, by, at=2)
    assert set(budget.tops) == {"energy", "rolling", "air"}      # a band for each cause on, no more
    assert np.allclose(budget.tops["rolling"].yData, energy + rolling)
    assert np.allclose(budget.total.yData, 1.0)                   # E + ΣD: the flat top
    assert budget.values == pytest.approx({"energy": 0.7, "rolling": 0.2, "air": 0.1})
    text = budget.key.text
    assert text.index("air") < text.index("rolling") < text.index("E&nbsp;")   # top band first
    assert "rolling&nbsp;0.2&nbsp;J" in text and "sliding" not in text


def test_no_budget_for_the_2011_model_one_for_a_scene_that_loses_energy(qtbot, window):
    assert window.plots.budget_plot is None   # hills: nothing takes the ball's energy
    window.files.open_scene(EXAMPLES_DIR / "billiard.json", remember=False)
    plots = window.plots
    assert plots.budget_plot is not None and plots.budget.possible == ("sliding", "impacts")
    columns = sorted((plots.graphics.ci.items[p][0][1], p.objectName()) for p in plots.plots)
    assert [name for _, name in columns][:2] == ["plot.energy", "plot.budget"]   # beside the energy error
    window.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    assert plots.budget_plot is None and len(plots.plots) == 3


def test_the_billiard_shot_gives_two_sevenths_of_its_energy_to_sliding(qtbot, window):
    """Struck at v₀ = 2 m/s without spin, the ball skids until it rolls at 5/7 v₀: sliding friction
    takes 2/7 of its kinetic energy ½ m v₀² = 2 J, what the budget's key says at the end."""
    window.files.open_scene(EXAMPLES_DIR / "billiard.json", remember=False)
    run_to_end(qtbot, window)
    budget = window.plots.budget
    assert budget.values["sliding"] == pytest.approx(2 / 7 * 2.0, rel=1e-3)
    assert "impacts" not in budget.values   # it never flew: no landing, no impacts listed
    assert np.ptp(budget.total.yData) < 1e-9    # E + ΣD: flat
    window.runs.seek(0.1)   # the key follows the moment shown: less so far
    window.drawing.plot()
    assert 0.0 < budget.values["sliding"] < 2 / 7 * 2.0 * 0.9


def test_compare_mode_shows_the_budget_of_the_run_followed_and_says_which(qtbot, window):
    window.files.open_scene(EXAMPLES_DIR / "billiard.json", remember=False)
    window.speed.setCurrentIndex(FASTEST)
    compare_to_end(qtbot, window, "rk4,euler")
    plots = window.compare.error_plots
    assert plots.budget is not None and "RK4" in plots.budget_plot.titleLabel.text
    window.compare.panel.follow.setCurrentIndex(1)
    window.drawing.plot()
    assert "Euler" in plots.budget_plot.titleLabel.text and "RK4" not in plots.budget_plot.titleLabel.text
    assert plots.budget.values["sliding"] == pytest.approx(2 / 7 * 2.0, rel=1e-2)


def test_the_budget_reads_each_cause_from_the_trajectory(qtbot, window, monkeypatch, tmp_path):
    """A constructed trajectory's causes (the budget reads ``Trajectory.dissipated_by``): rolling
    resistance and air get their bands, the others none."""
    scene = _scene(**{"contact.rolling_resistance": 0.05, "air": {"density": 1.2, "drag_coefficient": 0.47}})
    path = tmp_path / "rolling.json"
    scene.save(path)
    window.files.open_scene(path, remember=False)

    def by(self):
        n = len(self)
        ramp = np.linspace(0.0, 1.0, n)
        return {cause: np.zeros(n) for cause in DISSIPATION_CAUSES} | {"rolling": 0.3 * ramp, "air": 0.1 * ramp,
                                                                       "sliding": self.dissipated - 0.4 * ramp}
    monkeypatch.setattr(Trajectory, "dissipated_by", property(by))
    run_to_end(qtbot, window)
    budget = window.plots.budget
    assert budget.causes == ("sliding", "rolling", "air")
    assert budget.values["rolling"] == pytest.approx(0.3) and budget.values["air"] == pytest.approx(0.1)


@pytest.mark.parametrize(("width", "scale", "folded"),
                         [(1920, 2.0, []), (1024, 2.0, ["plot.orthogonality", "plot.force"]), (1024, 1.0, [])])
def test_what_the_width_cannot_hold_folds_away_the_budget_stays(qtbot, width, scale, folded):
    """Presentation on a 1024-pixel projector: text twice as large, four plots and the key do not
    fit side by side; ‖RᵀR − I‖ and then the normal force fold away, every plot left is whole."""
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.resize(width, 190)
    plots.show()
    qtbot.waitExposed(plots)
    plots.set_budget(("sliding", "impacts", "rolling", "spin", "air"), 0.0)
    plots.set_font_scale(scale)
    by = {cause: np.linspace(0.0, 0.123, 3) for cause in DISSIPATION_CAUSES}
    plots.budget.show(np.array([0.0, 1.0, 2.0]), np.array([1.0, 0.5, 0.4]), by)   # the key at its widest
    plots.resize(width + 1, 190)   # laid out again with the key's values
    qtbot.wait(10)
    assert [plot.objectName() for plot in plots.folded] == folded
    assert plots.budget_plot in plots.arranged
    for item in plots.arranged:
        assert item.sceneBoundingRect().right() <= plots.graphics.width() + 1


@pytest.mark.parametrize(("width", "folded"), [(1920, False), (1024, True)])
def test_compare_modes_plots_fold_their_orthogonality_for_the_budget_where_narrow(qtbot, width, folded):
    plots = ErrorPlots()
    qtbot.addWidget(plots)
    plots.resize(width, 260)
    plots.show()
    qtbot.waitExposed(plots)
    plots.set_budget(DISSIPATION_CAUSES, 0.0)
    plots.set_font_scale(2.0)
    by = {cause: np.linspace(0.0, 0.123, 3) for cause in DISSIPATION_CAUSES}
    plots.budget.show(np.array([0.0, 1.0, 2.0]), np.array([1.0, 0.5, 0.4]), by)   # the key at its widest
    plots.resize(width + 1, 260)
    qtbot.wait(10)
    assert (plots.plots["orthogonality"] not in plots.arranged) == folded
    assert plots.budget_plot in plots.arranged and plots.plots["energy"] in plots.arranged
    for item in [*plots.arranged, plots.budget.key]:   # the key above them widens nothing
        assert item.sceneBoundingRect().right() <= plots.graphics.width() + 1


def _spinning_top(tmp_path, stop_at_rest: bool):
    """A ball spinning in place on a plane, ω₀ = 20 rad/s about the normal: spin friction μ_s = 0.1
    stops it at t* = 2 r ω₀ / (5 μ_s g), having taken all of its energy ½ (2/5) m r² ω₀² = 0.8 J."""
    scene = Scene.from_dict({
        "format": "rollball-scene", "version": 4, "landscape": "0", "ball": {"radius": 0.1, "mass": 1.0},
        "start": {"x": 0.0, "y": 0.0, "vx": 0.0, "vy": 0.0, "spin": 0.0, "omega": [0.0, 0.0, 20.0]},
        "contact": {"friction": 0.3, "restitution": 0.0, "after_liftoff": "fly", "spin_friction": 0.1},
        "stop_at_rest": stop_at_rest, "duration": 3.0, "view": {"min": -1.0, "max": 1.0, "step": 0.1}})
    path = tmp_path / "top.json"
    scene.save(path)
    return path, 2 * 0.1 * 20.0 / (5 * 0.1 * scene.gravity)


def test_a_top_stopped_by_spin_friction_the_budget_the_rest_marker_and_the_last_word(qtbot, window, tmp_path):
    path, rest = _spinning_top(tmp_path, stop_at_rest=True)
    window.files.open_scene(path, remember=False)
    run_to_end(qtbot, window)
    budget = window.plots.budget
    assert budget.causes == ("sliding", "spin")
    assert budget.values["spin"] == pytest.approx(0.8, rel=1e-9)
    assert budget.values["energy"] == pytest.approx(0.0, abs=1e-9)
    assert np.ptp(budget.total.yData) < 1e-9
    rests = [marker for marker in window.timeline.markers if marker.kind == "rest"]
    assert len(rests) == 1 and rests[0].time == pytest.approx(rest, rel=1e-9)
    assert "comes to rest" in window.message.text() and "; rest at" not in window.message.text()   # said once
    assert window.progress.value() == window.progress.maximum()   # played to its end: the rest


def test_a_ball_held_spinning_and_then_still_reads_resting_to_the_end(qtbot, window, tmp_path):
    path, rest = _spinning_top(tmp_path, stop_at_rest=False)
    window.files.open_scene(path, remember=False)
    run_to_end(qtbot, window)
    assert window.controller.buffer.end_time == pytest.approx(3.0)   # on to its duration, the ball still
    assert window.readouts["mode"].text() == "resting"
    assert f"rest at t = {rest:.4g} s" in window.message.text()   # the run went on: its last word says when
    window.runs.seek(rest / 2)   # spinning in place, held: resting too, spin friction taking ½ I ω² as ω falls linearly
    buffer = window.controller.buffer
    t = buffer.t[buffer.index_at(rest / 2)]
    assert window.readouts["mode"].text() == "resting"
    assert window.plots.budget.values["spin"] == pytest.approx(0.8 * (1 - (1 - t / rest) ** 2), rel=1e-6)


@pytest.mark.parametrize("stop_at_rest", [True, False])
def test_a_ball_rolled_to_rest_reads_resting_from_the_rest_on(qtbot, window, tmp_path, stop_at_rest):
    """Rolled at 1 m/s on a plane against c_rr = 0.1, the ball stops at 7 v₀ / (5 c_rr g) = 1.43 s:
    the readout says resting at that instant's frame (the last, with stop at rest) and after it,
    rolling before; rolling resistance took all of ½ (7/5) m v₀² = 0.7 J."""
    scene = Scene.from_dict({
        "format": "rollball-scene", "version": 4, "landscape": "0", "ball": {"radius": 0.1, "mass": 1.0},
        "start": {"x": 0.0, "y": 0.0, "vx": 1.0, "vy": 0.0, "spin": 0.0},
        "contact": {"friction": 0.3, "restitution": 0.0, "after_liftoff": "fly", "rolling_resistance": 0.1},
        "stop_at_rest": stop_at_rest, "duration": 2.0, "view": {"min": -1.0, "max": 3.0, "step": 0.1}})
    path = tmp_path / "roll.json"
    scene.save(path)
    window.files.open_scene(path, remember=False)
    run_to_end(qtbot, window)
    [rest] = window.controller.runs[0].transitions
    assert rest.kind == "rest" and rest.time == pytest.approx(7 * 1.0 / (5 * 0.1 * scene.gravity), abs=1e-9)
    buffer = window.controller.buffer
    assert buffer.t[-1] == (rest.time if stop_at_rest else 2.0)
    assert window.readouts["mode"].text() == "resting"
    assert window.plots.budget.values["rolling"] == pytest.approx(0.7, rel=1e-9)
    for moment, mode in ((rest.time, "resting"), (rest.time - 0.05, "rolling")):
        window.runs.seek(moment)
        assert window.readouts["mode"].text() == mode


def test_the_budget_grows_with_the_ball_while_it_plays(qtbot, window):
    window.files.open_scene(EXAMPLES_DIR / "billiard.json", remember=False)
    controller = window.controller
    window.speed.setCurrentIndex(window.speed.findText("Real time"))
    window.runs.start()
    qtbot.waitUntil(lambda: controller.state == RUNNING and controller.play_time > 0.3, timeout=60_000)
    window.drawing.plot()   # as a frame does
    buffer, budget = controller.buffer, window.plots.budget
    shown = buffer.t[buffer.index_at(controller.play_time)]
    assert budget.tops["energy"].xData[-1] == shown < 2.0   # up to the ball's moment, not the end
    assert budget.values["sliding"] == pytest.approx(2 / 7 * 2.0, rel=1e-3)   # it rolls from t* = 0.29 s on
    window.runs.stop()


def test_a_plot_folded_first_comes_back_where_it_fits_alone(qtbot):
    """‖RᵀR − I‖ folds first; where the normal force must fold too but ‖RᵀR − I‖ alone fits (a
    1024-pixel window beside the Scene panel), ‖RᵀR − I‖ is shown."""
    plots = LivePlots()
    qtbot.addWidget(plots)
    plots.resize(1920, 190)
    plots.show()
    qtbot.waitExposed(plots)
    plots.set_budget(("sliding", "impacts", "spin"), 0.0)
    energy, orthogonality, force = plots.plots[:3]
    width = least_width(plots.graphics, [energy, plots.budget_plot, plots.budget.key, orthogonality]) + 4
    assert least_width(plots.graphics, [energy, plots.budget_plot, plots.budget.key, force]) > width
    plots.resize(round(width), 190)
    qtbot.wait(10)
    assert plots.folded == [force]
