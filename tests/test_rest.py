"""A ball that stops (docs/design.md §1, "Rest"): the mode "resting" and the transition "rest", the
hold condition (tan θ ≤ c_rr and tan θ ≤ μ), a held ball spinning in place until spin friction
stops it, against the exact answers, and where the energy went (``Trajectory.dissipated_by``)."""

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from rollball.examples import scene_path
from rollball.modes import AFTER, MODES, TRANSITION_KINDS, Change, Mode
from rollball.resting import holds
from rollball.scene import Air, Ball, Contact, Integrator, Scene, Start
from rollball.simulation import Simulation, simulate
from rollball.sliding import BallState
from rollball.transition_check import _invented
from rollball.trajectory import DISSIPATION_CAUSES, Transition, read_csv

G, R_BALL, M = 9.81, 0.1, 2.0


def _scene(landscape="0*x", *, start=Start(x=0.0, y=0.0), duration=5.0, method="rk4", dt=0.01, **contact):
    return Scene(landscape=landscape, gravity=G, ball=Ball(radius=R_BALL, mass=M), start=start,
                 contact=Contact(**{"friction": 0.3, **contact}), duration=duration,
                 integrator=Integrator(method=method, dt=dt))


def test_resting_is_a_mode_and_rest_a_transition():
    assert Mode.RESTING == 3 and str(Mode.RESTING) == "resting" and MODES[3] == "resting"
    assert Change.REST == "rest" and "rest" in TRANSITION_KINDS and AFTER[Change.REST] is Mode.RESTING
    sentence = Transition(1.5, Change.REST, 0.25, 0.0).sentence()
    assert sentence.startswith("rest at t = 1.5 s, (x, y) = (0.25, 0)") and "comes to rest" in sentence


def test_a_rest_at_the_instant_of_a_grip_is_no_invented_change():
    """A ball that grips standing still comes to rest at that instant; two grips at one instant,
    or a rest before the change before it, are still invented."""
    rows = np.zeros((2, 40))
    run = SimpleNamespace(transitions=[Transition(1.0, Change.GRIP, 0, 0), Transition(1.0, Change.REST, 0, 0)])
    assert _invented(run, rows, np.zeros(2, dtype=np.int8)) == []
    run.transitions[1] = Transition(0.5, Change.REST, 0, 0)
    assert len(_invented(run, rows, np.zeros(2, dtype=np.int8))) == 1


@pytest.mark.parametrize("tan, c_rr, mu, held", [
    (0.0, 0.0, 0.3, True), (0.05, 0.06, 0.3, True), (0.07, 0.06, 0.3, False), (0.05, 0.06, 0.04, False),
    (0.05, 0.06, math.inf, True)])
def test_held_iff_the_tilt_is_within_both_bounds(tan, c_rr, mu, held):
    normal = np.array([-tan, 0.0, 1.0]) / math.sqrt(1.0 + tan * tan)
    assert holds(normal, rolling_resistance=c_rr, friction=mu) is held


def test_held_at_the_bound_itself():
    """A plane tilted by exactly atan(c_rr): the ball stays (its normal known to round-off)."""
    theta = math.atan(0.05)
    normal = np.array([-math.sin(theta), 0.0, math.cos(theta)])
    assert holds(normal, rolling_resistance=0.05, friction=0.3)


def _spin_scene(stop_at_rest, omega0=30.0, mu_s=0.05, duration=5.0, dt=0.01):
    scene = _scene(start=Start(x=0.0, y=0.0, spin=omega0), duration=duration, dt=dt, rolling_resistance=0.01,
                   spin_friction=mu_s)
    return dataclasses.replace(scene, stop_at_rest=stop_at_rest)


def test_a_spin_in_place_stops_at_the_exact_time():
    """ω = ω₀ N, no speed, on a plane: ω·N falls linearly at (5/2) μ_s g / r and stops at
    2 r ω₀ / (5 μ_s g); the run ends there (stop_at_rest), its message saying so."""
    omega0, mu_s = 30.0, 0.05
    traj = simulate(_spin_scene(True))
    stop = 2.0 * R_BALL * omega0 / (5.0 * mu_s * G)
    assert [(c.kind, c.x, c.y) for c in traj.transitions] == [("rest", 0.0, 0.0)]
    assert traj.transitions[0].time == pytest.approx(stop, rel=1e-14)
    assert str(traj.status) == "ok" and traj.t[-1] == pytest.approx(stop, rel=1e-14)
    assert traj.message == f"the ball comes to rest at t = {stop:.6g} s, (x, y) = (0, 0)"
    assert set(traj.mode) == {"resting"}
    spin = traj.omega[:, 2]
    np.testing.assert_allclose(spin, omega0 - 2.5 * mu_s * G / R_BALL * traj.t, rtol=0, atol=1e-12)
    assert spin[-1] == 0.0 and np.all(traj.velocity == 0.0) and np.all(traj.center == traj.center[0])
    # R turns about N by ∫ s dt = ω₀ t − (5/4) μ_s g t² / r
    angle = omega0 * traj.t - 1.25 * mu_s * G / R_BALL * traj.t ** 2
    np.testing.assert_allclose(traj.R[:, 0, 0], np.cos(angle), atol=1e-9)
    np.testing.assert_allclose(traj.R[:, 1, 0], np.sin(angle), atol=1e-9)
    np.testing.assert_allclose(traj.normal_force, M * G, rtol=1e-15)
    # the energy went to spin friction, all of it: ½ I ω₀²
    by = traj.dissipated_by
    assert by["spin"][-1] == pytest.approx(0.5 * 0.4 * M * R_BALL ** 2 * omega0 ** 2, rel=1e-14)
    assert all(np.all(by[cause] == 0.0) for cause in DISSIPATION_CAUSES if cause != "spin")
    assert traj.energy_drift < 1e-14


def test_without_stop_at_rest_the_ball_rests_to_the_end():
    """The rest is a transition and the run goes on to its end time, still, in mode "resting",
    rows at the run's own recording times."""
    traj = simulate(_spin_scene(False))
    stop = 2.0 * R_BALL * 30.0 / (5.0 * 0.05 * G)
    assert [c.kind for c in traj.transitions] == ["rest"] and traj.transitions[0].time == pytest.approx(stop)
    assert traj.t[-1] == 5.0 and "reached t = 5 s" in traj.message
    after = traj.t > traj.transitions[0].time
    assert after.sum() > 100 and set(traj.mode[after]) == {"resting"}
    np.testing.assert_allclose(np.diff(traj.t[after]), 0.01, rtol=1e-9)   # the run's grid of dt
    assert np.all(traj.omega[after] == 0.0) and np.all(traj.energy[after] == traj.energy[-1])
    assert traj.energy_drift < 1e-14


def test_without_spin_friction_the_ball_spins_in_place_to_the_end():
    traj = simulate(_spin_scene(True, mu_s=0.0))
    assert traj.transitions == () and set(traj.mode) == {"resting"} and traj.t[-1] == 5.0
    assert np.all(traj.omega[:, 2] == 30.0) and np.all(traj.dissipated == 0.0)


def test_a_still_ball_is_held_iff_the_slope_allows():
    """Started still on a plane z = −0.05 x (tan θ = 0.05): with c_rr 0.06 it is at rest at once;
    with c_rr 0.04 it is pulled on and rolls down (no rest at its start)."""
    held = simulate(_scene("-0.05*x", rolling_resistance=0.06))
    assert [(c.kind, c.time) for c in held.transitions] == [("rest", 0.0)] and len(held) == 1
    assert held.message.startswith("the ball comes to rest at t = 0 s")
    pulled = simulate(_scene("-0.05*x", rolling_resistance=0.04, duration=0.5))
    assert pulled.t[-1] == 0.5 and pulled.transitions == () and set(pulled.mode) == {"rolling"}
    theta = math.atan(0.05)   # down the slope at (5/7) g (sin θ − c_rr cos θ)
    a = 5 / 7 * G * (math.sin(theta) - 0.04 * math.cos(theta))
    np.testing.assert_allclose(pulled.contact[:, 0], 0.5 * a * pulled.t ** 2 * math.cos(theta), rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
@pytest.mark.parametrize("stop_at_rest", [True, False])
def test_the_row_at_a_rolling_balls_rest_is_resting(tmp_path, method, stop_at_rest):
    """Rolling at v₀ on a plane against c_rr: the row at the rest instant, 7 v₀ / (5 c_rr g), is the
    first resting one (in the CSV too), every row before it rolling; rolling resistance took all
    of ½ (7/5) m v₀², and the causes sum to the total in every row."""
    v0, c_rr = 1.5, 0.05
    scene = dataclasses.replace(_scene(start=Start(x=0.0, y=0.0, vx=v0), duration=6.0, method=method,
                                       rolling_resistance=c_rr), stop_at_rest=stop_at_rest)
    traj = simulate(scene)
    [rest] = traj.transitions
    assert rest.kind == "rest" and rest.time == pytest.approx(7 * v0 / (5 * c_rr * G), abs=1e-9)
    at = int(np.flatnonzero(traj.t == rest.time)[0])
    assert set(traj.mode[:at]) == {"rolling"} and set(traj.mode[at:]) == {"resting"}
    assert (len(traj) == at + 1) is stop_at_rest
    traj.to_csv(tmp_path / "rest.csv")
    _, extra = read_csv(tmp_path / "rest.csv", extra=True)
    np.testing.assert_array_equal(extra["mode"], traj.mode)
    by = traj.dissipated_by
    assert by["rolling"][-1] == pytest.approx(0.7 * M * v0 ** 2, rel=1e-12)
    assert all(np.all(by[cause] == 0.0) for cause in DISSIPATION_CAUSES if cause != "rolling")
    np.testing.assert_allclose(sum(by.values()), traj.dissipated, rtol=1e-15, atol=0)


def test_a_ball_sliding_to_rest_gives_its_last_interval_to_sliding():
    """μ = 0.35 < c_rr = 0.5 on a plane, sent without spin: friction's torque never overcomes the
    couple, so ω stays 0 and the ball slides to a stop at v₀ / (μ g), where it rests (its row there
    resting). Sliding friction took all of ½ m v₀², the stopping interval's share too (the
    interval's motion is the slide, not the rest it ends in)."""
    v0, mu = 1.0, 0.35
    traj = simulate(_scene(start=Start(x=0.0, y=0.0, vx=v0, omega=(0.0, 0.0, 0.0)), friction=mu,
                           rolling_resistance=0.5))
    [rest] = traj.transitions
    assert rest.kind == "rest" and rest.time == pytest.approx(v0 / (mu * G), abs=1e-12)
    assert traj.t[-1] == rest.time and traj.mode[-1] == "resting" and set(traj.mode[:-1]) == {"sliding"}
    by = traj.dissipated_by
    assert by["sliding"][-1] == pytest.approx(0.5 * M * v0 ** 2, rel=1e-12)
    # (held at 0, the static couple does no work: its quadrature is round-off)
    assert all(np.abs(by[cause]).max() < 1e-15 for cause in DISSIPATION_CAUSES if cause != "sliding")
    np.testing.assert_allclose(sum(by.values()), traj.dissipated, rtol=1e-15, atol=0)


def test_dissipated_by_splits_sliding_and_impacts():
    """Each cause's energy: a billiard shot (μ = 0.2, v₀ = 2 m/s, no spin) loses m v₀²/7 to
    sliding; the lift-off example's landings lose what their impacts say. The causes sum to the
    total in every row."""
    v0 = 2.0
    scene = _scene(start=Start(x=0.0, y=0.0, vx=v0, omega=(0.0, 0.0, 0.0)), duration=1.0, friction=0.2)
    traj = simulate(scene)
    by = traj.dissipated_by
    assert by["sliding"][-1] == pytest.approx(M * v0 ** 2 / 7.0, rel=1e-10)
    np.testing.assert_allclose(sum(by.values()), traj.dissipated, rtol=0, atol=1e-15)
    flying = simulate(scene_path("liftoff"))
    assert flying.landings > 0
    by = flying.dissipated_by
    lost = sum(c.energy_lost for c in flying.transitions if c.kind == "landing")
    assert by["impacts"][-1] == pytest.approx(lost, rel=1e-15)
    np.testing.assert_allclose(sum(by.values()), flying.dissipated, rtol=0, atol=1e-12)


def _header(path):
    return next(line for line in path.read_text().splitlines() if not line.startswith("#")).split(",")


def test_the_causes_carry_across_a_flight():
    """The lift-off example with rolling resistance and air: what rolling resistance took before
    the flight is kept through it (the flight's rows carry it), the landings' impacts are their
    own, and the causes sum to the total in every row; E + ΣD stays."""
    scene = Scene.load(scene_path("liftoff"))
    scene = dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, rolling_resistance=0.01),
                                air=Air(1.2, 0.47))
    traj = simulate(scene)
    assert traj.landings > 0
    by = traj.dissipated_by
    flying = traj.mode == "flying"
    first = np.flatnonzero(flying)[0]
    assert by["rolling"][first - 1] > 0.0 and np.all(np.diff(by["rolling"]) >= 0.0)
    # the air takes its share in flight too, in its own column; a flight takes nothing else
    air = by["air"]
    assert air[first] > air[first - 1] and by["spin"][-1] == 0.0
    steps = np.flatnonzero(flying[1:] & flying[:-1]) + 1   # intervals within a flight
    assert np.all(np.diff(air)[steps - 1] > 0.0) and np.all(np.diff(by["rolling"])[steps - 1] == 0.0)
    np.testing.assert_allclose(np.diff(by["sliding"])[steps - 1], 0.0, atol=1e-12)   # (round-off of the sums)
    lost = sum(c.energy_lost for c in traj.transitions if c.kind == "landing")
    assert by["impacts"][-1] == pytest.approx(lost, rel=1e-15)
    np.testing.assert_allclose(sum(by.values()), traj.dissipated, rtol=0, atol=1e-12)


def test_the_csv_has_each_cause_for_a_scene_that_dissipates(tmp_path):
    traj = simulate(dataclasses.replace(_scene(start=Start(x=0.0, y=0.0, vx=1.0, spin=20.0), rolling_resistance=0.1,
                                               spin_friction=0.02), stop_at_rest=False))
    assert set(traj.mode) == {"rolling", "resting"}
    traj.to_csv(tmp_path / "spin.csv")
    header = _header(tmp_path / "spin.csv")
    columns = [f"dissipated_{cause}" for cause in DISSIPATION_CAUSES]
    assert header[header.index("dissipated") + 1:] == columns
    rows, extra = read_csv(tmp_path / "spin.csv", extra=True)
    np.testing.assert_array_equal(rows, traj.data[:, : rows.shape[1]])
    for cause in DISSIPATION_CAUSES:
        np.testing.assert_array_equal(extra[f"dissipated_{cause}"], traj.dissipated_by[cause])


def test_a_scene_that_does_not_dissipate_keeps_its_columns(tmp_path):
    traj = simulate(_scene(start=Start(x=0.0, y=0.0, vx=1.0), duration=0.1))
    traj.to_csv(tmp_path / "roll.csv")
    header = _header(tmp_path / "roll.csv")
    assert header[-3:] == ["mode", "slip_speed", "dissipated"]


def test_air_alone_takes_all_that_is_dissipated_rolling_down_an_incline():
    """Air only (ρ = 1.2, C_d = 0.47), rolling down z = −0.3 x: it never rests (tan θ > c_rr = 0),
    all the energy dissipated is the air's, k ∫ |ċ|³ dt by the rows (trapezoids), and E + ΣD stays."""
    scene = dataclasses.replace(_scene("-0.3*x", duration=2.0, dt=1e-3), air=Air(1.2, 0.47))
    traj = simulate(scene)
    assert traj.transitions == () and set(traj.mode) == {"rolling"}
    by = traj.dissipated_by
    assert by["air"][-1] > 0.0 and all(np.all(by[c] == 0.0) for c in DISSIPATION_CAUSES if c != "air")
    np.testing.assert_array_equal(by["air"], traj.dissipated)
    power = Air(1.2, 0.47).drag_factor(R_BALL) * np.linalg.norm(traj.velocity, axis=1) ** 3
    assert by["air"][-1] == pytest.approx(np.trapezoid(power, traj.t), rel=1e-6)
    assert traj.energy_drift < 1e-10


def test_a_run_from_a_state_of_a_scene_that_starts_held_goes_from_that_state():
    """``Simulation.from_state`` (the checks' retakes) of a scene whose ball starts held: the run
    is the state's, rolling on a plane to a stop after 7 v / (5 c_rr g), not the start's stay."""
    scene = _scene(start=Start(x=0.0, y=0.0), rolling_resistance=0.05)
    run = Simulation(scene)
    state = BallState(0.0, 0.0, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0 / R_BALL, 0.0]), np.eye(3))
    redo = run.from_state(state, 1.0, Mode.ROLLING, t_end=6.0)
    assert [(c.kind, c.time) for c in redo.transitions] == [("rest", pytest.approx(1.0 + 7 / (5 * 0.05 * G)))]
    assert redo.rows[0, 0] == 1.0
