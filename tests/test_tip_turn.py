"""A ball rolling slowly onto the tip of a cone turns over it (rollball/tip.py) rather than stopping:
its contact stays at the tip T, its centre moves on the sphere of radius r about it. Rolled
straight at the tip, in the plane of a generator, the turn is planar: with θ the angle of c − T
from the vertical, r θ̈ = (5/7) g sin θ, so θ̇² = θ̇₀² + (10 g / 7 r)(cos θ₀ − cos θ) and its time
is a quadrature; F·N = m (g cos θ − r θ̇²) and the friction it needs |F_t| = (2/7) m g |sin θ|. On
either side the ball rolls on a generator, an incline: closed forms too."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from conftest import make_scene
from rollball import simulate
from rollball.flight import FreeState, energy
from rollball.landscape import landscape_of
from rollball.scene import Contact
from rollball.simulation import Simulation
from rollball.tip import FACE, Tip, turn_about

G, RADIUS = 9.81, 0.1
SLOPE = 0.3
CONE = f"-{SLOPE}*sqrt(x^2+y^2)"
BETA = math.atan(SLOPE)


def cone(vx, *, y0=0.0, friction=None, duration=0.8, landscape=CONE):
    return make_scene(landscape, x=-0.5, y=y0, vx=vx, duration=duration, contact=Contact(friction, 0.0, "fly"))


def at_tip(vx, slope=SLOPE):
    """Rolled from x = −0.5 up a generator of this slope: the time the contact point reaches the
    tip, and the speed then."""
    beta = math.atan(slope)
    v0, a, length = vx / math.cos(beta), 5.0 / 7.0 * G * math.sin(beta), 0.5 / math.cos(beta)
    v1 = math.sqrt(v0 * v0 - 2.0 * a * length)
    return (v0 - v1) / a, v1


def turn_rate(theta, v1, theta0=-BETA):
    """θ̇ at θ of the turn about the tip begun at θ₀ at the speed v1, from its energy."""
    return math.sqrt((v1 / RADIUS) ** 2 + 10.0 / 7.0 * G / RADIUS * (math.cos(theta0) - math.cos(theta)))


def turn_time(v1, upto, theta0=-BETA):
    return quad(lambda theta: 1.0 / turn_rate(theta, v1, theta0), theta0, upto, epsabs=1e-14, epsrel=1e-13)[0]


def far_contact(vx, duration):
    """The contact point's x at ``duration``: up the near generator, over the tip (θ from −β to β),
    down the far generator."""
    t_tip, v1 = at_tip(vx)
    t_down = t_tip + turn_time(v1, BETA)
    v2 = RADIUS * turn_rate(BETA, v1)
    tau = duration - t_down
    along = v2 * tau + 0.5 * (5.0 / 7.0 * G * math.sin(BETA)) * tau * tau
    return along * math.cos(BETA)


def test_the_turn_ends_on_the_far_face_at_the_closed_form_time_and_speed():
    """The turn alone (``tip.turn_about``) from the tip at θ₀ = −β, rolling at v1 = 0.8 m/s: it
    comes down on the far generator's face (ê = its normal, θ = β) when the quadrature says, at
    the speed the energy says (the same v1: the cone is symmetric), keeping E."""
    landscape = landscape_of(make_scene(CONE))
    tip = Tip.near(3e-10, -2e-10, lambda xs, ys: landscape.evaluate(xs, ys))
    assert tip is not None and np.abs(tip.point).max() < 1e-15
    v1 = 0.8
    e0 = np.array([-math.sin(BETA), 0.0, math.cos(BETA)])
    velocity = v1 * np.array([math.cos(BETA), 0.0, math.sin(BETA)])
    start = FreeState(0.25, RADIUS * e0, velocity, np.cross(e0, velocity) / RADIUS, np.eye(3))
    times = 0.25 + np.arange(1, 200) * 1e-3
    turn = turn_about(tip, start, e0, radius=RADIUS, mass=1.0, gravity=G, friction=math.inf, t_end=1.0, times=times)
    assert turn.how == FACE
    assert turn.state.t - 0.25 == pytest.approx(turn_time(v1, BETA), abs=1e-11)
    assert np.linalg.norm(turn.state.velocity) == pytest.approx(v1, abs=1e-11)
    np.testing.assert_allclose(turn.state.center / RADIUS, [math.sin(BETA), 0.0, math.cos(BETA)], atol=1e-10)
    states = [start, *turn.states, turn.state]
    energies = [energy(s.velocity, s.omega, s.center[2], 1.0, RADIUS, G) for s in states]
    assert len(turn.states) > 20 and np.ptp(energies) < 1e-10
    assert all(abs(np.linalg.norm(s.center) - RADIUS) < 1e-13 for s in turn.states)
    assert min(turn.forces) > 0.0


@pytest.mark.parametrize("method, options", [("rk4", dict(dt=1e-3)), ("dopri5", dict(rtol=1e-8))])
def test_a_slow_ball_turns_over_the_tip_and_rolls_down_the_far_side(method, options):
    """Rolled at the tip at 1.6 m/s it arrives with v²/r = 6.9 m/s² < g cos β = 9.4 m/s² (too slow
    to leave it, which stopped the run before, ``pivot``): it turns over the tip and rolls down the
    far generator, where it is at the closed form's place at the end."""
    vx, duration = 1.6, 0.8
    traj = simulate(cone(vx, duration=duration), method=method, **options)
    assert traj.status == "ok" and traj.transitions == () and set(traj.mode) == {"rolling"}, traj.message
    assert traj.contact[-1, 0] == pytest.approx(far_contact(vx, duration), abs=1e-10)
    t_tip, v1 = at_tip(vx)
    t_down = t_tip + turn_time(v1, BETA)
    turning = (traj.t > t_tip + 1e-8) & (traj.t < t_down - 1e-8)
    assert turning.sum() >= 10 and np.all(np.abs(traj.contact[turning]) < 1e-12)   # at the tip
    np.testing.assert_allclose(np.linalg.norm(traj.center[turning], axis=1), RADIUS, rtol=0, atol=1e-12)
    theta = np.arctan2(traj.center[turning, 0], traj.center[turning, 2])
    speed = np.linalg.norm(traj.velocity[turning], axis=1)
    np.testing.assert_allclose(speed, [RADIUS * turn_rate(th, v1) for th in theta], rtol=0, atol=1e-10)
    np.testing.assert_allclose(traj.normal_force[turning], G * np.cos(theta) - speed ** 2 / RADIUS, rtol=0, atol=1e-9)
    assert np.max(np.abs(traj.energy - traj.energy[0])) < 1e-9   # nothing lost over the tip


def test_a_ball_too_slow_to_climb_over_the_tip_turns_back_onto_the_near_face():
    """Arriving at 0.2 m/s the ball cannot raise its centre the r (1 − cos β) over the top
    (v² < (10/7) g r (1 − cos β)): it turns up to θ_m where θ̇ = 0, back to −β, and rolls down the
    generator it came up, at 0.2 m/s again (by symmetry: the time out and back are equal)."""
    v1, duration = 0.2, 1.2
    v0 = math.sqrt(v1 * v1 + 2.0 * (5.0 / 7.0 * G * math.sin(BETA)) * 0.5 / math.cos(BETA))
    vx = v0 * math.cos(BETA)
    t_tip, arrived = at_tip(vx)
    assert arrived == pytest.approx(v1, rel=1e-12)
    # θ = θ_m − u²: θ̇² = k (cos θ_m − cos θ) = −2k sin(θ_m − u²/2) sin(u²/2), and 2u / θ̇ stays
    # finite at the top
    k = 10.0 / 7.0 * G / RADIUS
    top = -math.acos(math.cos(BETA) + (v1 / RADIUS) ** 2 / k)
    half = quad(lambda u: 2.0 * u / math.sqrt(-2.0 * k * math.sin(top - u * u / 2) * math.sin(u * u / 2)) if u > 0
                else 2.0 / math.sqrt(-k * math.sin(top)), 0.0, math.sqrt(top + BETA), epsabs=1e-14, epsrel=1e-13)[0]
    tau = duration - (t_tip + 2.0 * half)
    back = v1 * tau + 0.5 * (5.0 / 7.0 * G * math.sin(BETA)) * tau * tau
    traj = simulate(cone(vx, duration=duration), method="rk4", dt=1e-3)
    assert traj.status == "ok" and traj.transitions == () and set(traj.mode) == {"rolling"}, traj.message
    assert traj.contact[-1, 0] == pytest.approx(-back * math.cos(BETA), abs=1e-10)
    assert np.max(np.abs(traj.energy - traj.energy[0])) < 1e-9


OBLIQUE = f"{CONE} - 0.2*x"   # up a generator of slope 0.1 to the tip, down one of slope 0.5 beyond it
NEAR, FAR = math.atan(0.1), math.atan(0.5)


def oblique():
    """Rolled up the oblique cone to arrive at its tip with r θ̇₀² = 9 < g cos β₁ = 9.76 m/s²: the
    start's vx, the time it reaches the tip and its speed then, the angle θ* where it lifts off
    (r θ̇² = g cos θ*) and the time it does."""
    v1 = math.sqrt(9.0 * RADIUS)
    v0 = math.sqrt(v1 * v1 + 2.0 * (5.0 / 7.0 * G * math.sin(NEAR)) * 0.5 / math.cos(NEAR))
    vx = v0 * math.cos(NEAR)
    t_tip, arrived = at_tip(vx, 0.1)
    theta = brentq(lambda th: RADIUS * turn_rate(th, v1, -NEAR) ** 2 - G * math.cos(th), 0.0, FAR)
    return vx, t_tip, arrived, theta, t_tip + turn_time(v1, theta, -NEAR)


def test_a_ball_that_speeds_up_in_the_turn_leaves_the_tip_where_holding_it_needs_a_pull():
    """On the oblique cone −0.3 ρ − 0.2 x a ball arriving with r θ̇₀² = 9 < g cos β₁ turns, speeds
    up and lifts off at θ* where r θ̇² = g cos θ*, well inside the turn: then it flies and lands."""
    vx, t_tip, arrived, theta, lifts = oblique()
    assert arrived == pytest.approx(math.sqrt(9.0 * RADIUS), rel=1e-12)
    assert 0.2 < theta < FAR - 0.15
    traj = simulate(cone(vx, duration=0.8, landscape=OBLIQUE), method="dopri5", rtol=1e-10)
    kinds = [str(change.kind) for change in traj.transitions]
    assert traj.status == "ok" and kinds[:2] == ["liftoff", "landing"], traj.message
    lift = traj.transitions[0]
    assert lift.time == pytest.approx(lifts, abs=1e-9)
    assert math.hypot(lift.x, lift.y) < 1e-12
    assert traj.liftoff.time == lift.time and traj.liftoff.kink


@pytest.mark.parametrize("method", ["rk4", "lawson5", "gauss4"])
def test_fixed_steps_reach_the_lopsided_tip_without_sampling_its_far_face(method):
    """These are exact on the near generator's plane, so the lift-off off the oblique cone's tip is
    the quadrature's at every dt: the sub-steps that approach the tip keep their stages short of it
    too (a stage past it samples the far face, whose rates differ by a finite amount: rk4 lifted off
    1.9·10⁻⁴, 9.1·10⁻⁵, 4.0·10⁻⁵ s early at dt 10⁻³, 5·10⁻⁴, 2.5·10⁻⁴, first order)."""
    vx, *_, lifts = oblique()
    for dt in (1e-3, 5e-4, 2.5e-4):
        traj = simulate(cone(vx, duration=0.6, landscape=OBLIQUE), method=method, dt=dt)
        assert [str(change.kind) for change in traj.transitions][:1] == ["liftoff"], traj.message
        assert traj.transitions[0].time == pytest.approx(lifts, abs=1e-9), dt


BENT = f"{OBLIQUE} - 0.1*x^2"   # (its faces bend: no method is exact on them)


@pytest.mark.parametrize("method, landscape, steps, order", [
    ("euler", BENT, (1e-3, 5e-4, 2.5e-4, 1.25e-4), 1), ("rk4", BENT, (4e-2, 2e-2, 1e-2, 5e-3), 4),
    ("gauss4", BENT, (4e-2, 2e-2, 1e-2, 5e-3), 4), ("lawson5", f"{BENT} - 0.3*x^3", (4e-2, 2e-2, 1e-2), 5)])
def test_the_fixed_step_methods_converge_at_their_order_through_a_lopsided_tip(method, landscape, steps, order):
    """On the oblique cone whose faces bend, rolled at its tip at 1.3768 m/s (it turns, lifts off
    mid-turn, lands on the far face and rolls down it): the lift-off's time and the contact point at
    the end converge at the method's order, from the differences of successive halvings (rk4
    measured 4.01, 3.98 and 4.00, 3.98; lawson5 4.5 and 4.8 before its differences reach the turn's
    10⁻¹¹ s). Before, rk4's and lawson5's moved by 10⁻³ s at one of these steps."""
    runs = [simulate(cone(1.3768, duration=0.8, landscape=landscape), method=method, dt=dt) for dt in steps]
    assert all([str(c.kind) for c in traj.transitions] == ["liftoff", "landing"] for traj in runs)
    lifts = np.diff([traj.transitions[0].time for traj in runs])
    ends = [np.linalg.norm(a.contact[-1] - b.contact[-1]) for a, b in zip(runs, runs[1:])]
    for moves in (np.abs(lifts), np.array(ends)):
        orders = np.log2(moves[:-1] / moves[1:])
        assert np.all(orders > order - (0.55 if order == 5 else 0.1)) and np.all(orders < order + 0.3), (moves, orders)


def test_the_transition_check_takes_a_liftoff_in_a_turn_again_from_before_the_turn():
    """At rk4 dt 10⁻⁴ the oblique cone's lift-off comes 390 steps into the turn over the tip, whose
    rows are the turn's (``Simulation.turns``), from which no kernel run can start: the retake starts
    from the last row before the turn (the rows 64 steps before the lift-off are in it, and the
    check skipped it) and takes the approach and the turn again."""
    vx, t_tip, _, _, lifts = oblique()
    run = Simulation(cone(vx, duration=0.8, landscape=OBLIQUE), method="rk4", dt=1e-4)
    run.advance()
    [(began, ended)] = run.turns
    assert began == pytest.approx(t_tip, abs=1e-8) and ended == run.transitions[0].time
    check = run.transition_check
    assert check.skipped == 0 and [r.kind for r in check.retakes] == ["liftoff"], check
    (retake,) = check.retakes
    assert retake.start < began, retake
    # (dt and dt/4 exact; dt/2's step ending 8·10⁻⁷ s past the tip still falls short of it, its last
    # stage on the far face, and lifts off 10⁻⁵ s early: the check's verdict says so)
    assert retake.times[0] == pytest.approx(lifts, abs=1e-9) and retake.times[2] == pytest.approx(lifts, abs=1e-9)


def test_where_friction_cannot_hold_the_turn_the_run_stops_and_says_so():
    """The turn needs μ ≥ (2/7) g sin β / (g cos β − v1²/r) at its start (and end): μ = 1 holds it as
    μ null does; μ just below that stops the run at the tip (while rolling up to it needs only
    (2/7) tan β)."""
    vx = 1.6
    t_tip, v1 = at_tip(vx)
    needed = (2.0 / 7.0) * G * math.sin(BETA) / (G * math.cos(BETA) - v1 * v1 / RADIUS)
    held, free = simulate(cone(vx, friction=1.0)), simulate(cone(vx))
    assert held.status == "ok" and np.array_equal(held.contact, free.contact)
    stopped = simulate(cone(vx, friction=0.99 * needed))
    assert stopped.status == "does_not_fit" and stopped.failure.reason == "tip_slip", stopped.message
    assert stopped.failure.time == pytest.approx(t_tip, abs=1e-8)
    assert "tip" in stopped.message and "more friction" in stopped.message


@pytest.mark.parametrize("method, options", [("dopri5", dict(rtol=1e-10)), ("rk4", dict(dt=1e-4))])
def test_passed_beside_the_tip_it_turns_over_it_in_three_dimensions_and_goes_on(method, options):
    """Rolled at 1.6 m/s from (−0.5, 0.01) the ball's contact point reaches the tip (its centre meets
    the sphere about it) off the generator's plane: it turns about the tip sideways and rolls on
    down the cone, with no transition, its centre on the sphere and E kept during the turn."""
    traj = simulate(cone(1.6, y0=0.01), method=method, **options)
    assert traj.status == "ok" and traj.transitions == () and set(traj.mode) == {"rolling"}, traj.message
    at = np.flatnonzero(np.hypot(traj.contact[:, 0], traj.contact[:, 1]) < 1e-9)
    assert len(at) >= 10 and np.all(np.diff(at) == 1)   # one turn
    assert np.ptp(traj.contact[at], axis=0).max() == 0.0
    tip = np.append(traj.contact[at[0]], 0.0)
    np.testing.assert_allclose(np.linalg.norm(traj.center[at] - tip, axis=1), RADIUS, rtol=0, atol=1e-12)
    assert np.ptp(traj.energy[at[0]: at[-1] + 2]) < 1e-9 and np.all(traj.normal_force[at] > 0.0)
    # the turn ends on the face, ê at its normal (N_z = cos β), and rolls on from 10⁻⁸ m down it
    on = at[-1] + 1
    assert math.hypot(*traj.contact[on]) == pytest.approx(1e-8 * math.cos(BETA), rel=1e-3)
    assert traj.center[on, 2] / RADIUS == pytest.approx(math.cos(BETA), abs=1e-6)
    assert traj.contact[-1, 0] > 0.2 and traj.contact[-1, 1] > 0.05   # down the far side, turned aside


def test_the_fixed_step_methods_converge_across_the_turn():
    """Euler against the closed form of the straight run, at its order 1; rk4 on a cone whose faces
    bend (−0.3 ρ − 0.3 x², rolled straight at its tip: a planar turn) at its order 4, from the
    differences of three halvings; dopri5 on the straight run at rtol 10⁻⁶ (rk4 and dopri5 are exact
    on the straight run's planes)."""
    exact = far_contact(1.6, 0.8)
    errors = [abs(simulate(cone(1.6), method="euler", dt=dt).contact[-1, 0] - exact) for dt in (1e-3, 5e-4, 2.5e-4)]
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all(np.abs(orders - 1.0) < 0.05), (errors, orders)
    ends = [simulate(cone(1.6, landscape=f"{CONE} - 0.3*x^2"), method="rk4", dt=dt).contact[-1]
            for dt in (1e-2, 5e-3, 2.5e-3)]
    steps = [np.linalg.norm(a - b) for a, b in zip(ends, ends[1:])]
    assert math.log2(steps[0] / steps[1]) > 3.5, steps
    assert simulate(cone(1.6), method="dopri5", rtol=1e-6).contact[-1, 0] == pytest.approx(exact, abs=1e-12)
