"""A ball rolling slowly over a ridge turns over its edge (rollball/ridge.py) rather than flying:
on a roof of two planes, against the closed forms of the rolling on each plane and of the turn
about the edge (its time from the energy, by quadrature), with no energy lost; where holding the
turn would need a pull it leaves the edge then; where the friction cannot hold it the run stops."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from rollball import Scene, simulate
from rollball.scene import Ball, Contact, Integrator, Start

G, RADIUS = 9.81, 0.1
UP, DOWN = 0.25, 0.15            # the roof min(UP x, -DOWN x): up to the edge at x = 0, then down
PHI1, PHI2 = -math.atan(UP), math.atan(DOWN)   # the faces' normals, from the vertical towards +x


def roof(vx: float, friction=None, duration=1.0, method="rk4", dt=1e-3, down=DOWN) -> Scene:
    return Scene(f"min({UP}*x, -{down}*x)", gravity=G, ball=Ball(RADIUS, 1.0), start=Start(-0.3, 0.0, vx, 0.0, 0.0),
                 integrator=Integrator(method, True, dt), duration=duration, contact=Contact(friction, 0.0, "fly"))


def at_edge(vx: float) -> tuple[float, float]:
    """The time the contact point reaches the edge rolling up the near face, and the speed then."""
    alpha = math.atan(UP)
    v0, a, length = vx / math.cos(alpha), 5.0 / 7.0 * G * math.sin(alpha), 0.3 / math.cos(alpha)
    v1 = math.sqrt(v0 * v0 - 2.0 * a * length)
    return (v0 - v1) / a, v1


def turn_rate(theta: float, v1: float) -> float:
    """θ̇ at θ of the turn about the edge, from E: (7/10) r² θ̇² + g r cos(φ₁ + θ) = const."""
    square = (v1 / RADIUS) ** 2 + 10.0 / 7.0 * G / RADIUS * (math.cos(PHI1) - math.cos(PHI1 + theta))
    return math.sqrt(square)


def turn_time(v1: float, upto: float) -> float:
    return quad(lambda theta: 1.0 / turn_rate(theta, v1), 0.0, upto, epsabs=1e-14, epsrel=1e-13)[0]


@pytest.mark.parametrize("method, dt", [("rk4", 1e-3), ("dopri5", 1e-3)])
def test_a_slow_ball_turns_over_the_edge_and_rolls_down_the_far_face(method, dt):
    vx, duration = 1.1, 1.0
    traj = simulate(roof(vx, duration=duration, method=method, dt=dt))
    assert traj.status == "ok" and traj.transitions == () and set(traj.mode) == {"rolling"}, traj.message
    t_edge, v1 = at_edge(vx)
    turn = PHI2 - PHI1
    t_down = t_edge + turn_time(v1, turn)
    v2 = RADIUS * turn_rate(turn, v1)
    tau = duration - t_down
    along = v2 * tau + 0.5 * (5.0 / 7.0 * G * math.sin(PHI2)) * tau * tau
    assert traj.contact[-1, 0] == pytest.approx(along * math.cos(PHI2), abs=1e-8)
    turning = (traj.t > t_edge + 1e-9) & (traj.t < t_down - 1e-9)
    assert turning.sum() >= 10 and np.all(np.abs(traj.contact[turning, 0]) < 1e-12)   # on the edge
    centre = np.linalg.norm(traj.center[turning] - np.column_stack([traj.contact[turning], np.zeros(turning.sum())]),
                            axis=1)
    np.testing.assert_allclose(centre, RADIUS, rtol=0, atol=1e-12)
    energy = traj.energy - traj.energy[0]
    assert np.max(np.abs(energy)) < 1e-9   # nothing lost: a real ball's turn over an edge is smooth
    assert np.all(traj.normal_force[turning] > 0.0)


def test_a_faster_ball_leaves_the_edge_where_holding_it_would_need_a_pull():
    """On a roof whose far face is steep (slope 1), a ball arriving slowly enough to turn
    (r θ̇₀² < g cos φ₁) speeds up as it turns and F·N falls to 0 at θ* (r θ̇(θ*)² = g cos(φ₁ + θ*)):
    it lifts off the edge there, and lands on the far face."""
    alpha, v1 = math.atan(UP), math.sqrt(9.0 * RADIUS)   # r θ̇₀² = 9 < g cos φ₁ = 9.52
    v0 = math.sqrt(v1 * v1 + 2.0 * (5.0 / 7.0 * G * math.sin(alpha)) * 0.3 / math.cos(alpha))
    vx = v0 * math.cos(alpha)
    t_edge, arrived = at_edge(vx)
    assert arrived == pytest.approx(v1, rel=1e-12)
    theta = brentq(lambda th: RADIUS * turn_rate(th, v1) ** 2 - G * math.cos(PHI1 + th), 0.0, math.atan(1.0) - PHI1)
    assert 0.3 < theta < math.atan(1.0) - PHI1 - 0.3   # well inside the turn
    traj = simulate(roof(vx, duration=0.6, down=1.0))
    kinds = [str(change.kind) for change in traj.transitions]
    assert traj.status == "ok" and kinds[:2] == ["liftoff", "landing"], traj.message
    assert traj.transitions[0].time == pytest.approx(t_edge + turn_time(v1, theta), abs=1e-9)
    assert traj.transitions[0].x == pytest.approx(0.0, abs=1e-12)
    assert traj.liftoff.time == traj.transitions[0].time


def lopsided(method: str, dt: float, landscape: str = "min(0.1*x, -0.5*x)", vx: float | None = None) -> Scene:
    """Up a face of slope 0.1 to the edge, a face of slope 0.5 beyond it, arriving with
    r θ̇₀² = 9 m/s² (vx None), so that the ball lifts off mid-turn; or ``landscape`` at ``vx``."""
    if vx is None:
        alpha, v1 = math.atan(0.1), math.sqrt(9.0 * RADIUS)
        vx = math.sqrt(v1 * v1 + 2.0 * (5.0 / 7.0 * G * math.sin(alpha)) * 0.3 / math.cos(alpha)) * math.cos(alpha)
    return Scene(landscape, gravity=G, ball=Ball(RADIUS, 1.0), start=Start(-0.3, 0.0, vx, 0.0, 0.0),
                 integrator=Integrator(method, True, dt), duration=0.6, contact=Contact(None, 0.0, "fly"))


@pytest.mark.parametrize("method", ["rk4", "lawson5"])
def test_fixed_steps_reach_a_lopsided_edge_without_sampling_its_far_face(method):
    """These are exact on the near face's plane, so the lift-off from the edge is the quadrature's
    at every dt: the step that approaches the edge keeps its stages short of it too (rk4's lifted
    off 9.0·10⁻⁵, 8.9·10⁻⁵, 3.9·10⁻⁵ s early at dt 10⁻³, 5·10⁻⁴, 2.5·10⁻⁴, its last stage on the far
    face)."""
    phi1, v1 = -math.atan(0.1), math.sqrt(9.0 * RADIUS)
    t_edge = (math.sqrt(v1 * v1 + 2.0 * (5.0 / 7.0 * G * math.sin(-phi1)) * 0.3 / math.cos(phi1)) - v1) / (
        5.0 / 7.0 * G * math.sin(-phi1))

    def rate(th):
        return math.sqrt((v1 / RADIUS) ** 2 + 10.0 / 7.0 * G / RADIUS * (math.cos(phi1) - math.cos(phi1 + th)))
    theta = brentq(lambda th: RADIUS * rate(th) ** 2 - G * math.cos(phi1 + th), 0.0, math.atan(0.5) - phi1)
    lifts = t_edge + quad(lambda th: 1.0 / rate(th), 0.0, theta, epsabs=1e-14, epsrel=1e-13)[0]
    for dt in (1e-3, 5e-4, 2.5e-4):
        traj = simulate(lopsided(method, dt))
        assert [str(c.kind) for c in traj.transitions] == ["liftoff", "landing"], traj.message
        assert traj.transitions[0].time == pytest.approx(lifts, abs=1e-9), dt


def test_rk4_converges_at_its_order_through_a_lopsided_edge_whose_faces_bend():
    """min(0.1 x, −0.5 x) − 0.1 x², rolled at 1.2 m/s: it turns, lifts off the edge mid-turn and
    lands; the lift-off's time and the contact point at the end converge at order 4 (the differences
    of successive halvings). Before, the state the turn starts from was carried to the edge along
    the tangent plane from as far as 2·10⁻⁵ s before it (O(τ²) in the bending): 1.7 and 2.9."""
    runs = [simulate(lopsided("rk4", dt, "min(0.1*x, -0.5*x) - 0.1*x^2", 1.2)) for dt in (4e-2, 2e-2, 1e-2, 5e-3)]
    assert all([str(c.kind) for c in traj.transitions] == ["liftoff", "landing"] for traj in runs)
    lifts = np.abs(np.diff([traj.transitions[0].time for traj in runs]))
    ends = np.array([np.linalg.norm(a.contact[-1] - b.contact[-1]) for a, b in zip(runs, runs[1:])])
    for moves in (lifts, ends):
        orders = np.log2(moves[:-1] / moves[1:])
        assert np.all(np.abs(orders - 4.0) < 0.3), (moves, orders)


def test_where_friction_cannot_hold_the_turn_the_run_stops_and_says_so():
    """Turning over the edge needs |F_t| = (2/7) m g |sin(φ)| against F·N = m (g cos φ − r θ̇²): at
    its start (φ = φ₁) μ = 1 holds it as μ null does; μ just below what the start needs stops."""
    vx = 1.1
    _, v1 = at_edge(vx)
    needed = (2.0 / 7.0) * G * math.sin(-PHI1) / (G * math.cos(PHI1) - v1 * v1 / RADIUS)
    held = simulate(roof(vx, friction=1.0, duration=0.6))
    free = simulate(roof(vx, duration=0.6))
    assert held.status == "ok" and np.array_equal(held.contact, free.contact)
    stopped = simulate(roof(vx, friction=0.99 * needed, duration=0.6))
    assert stopped.status == "does_not_fit" and stopped.failure.reason == "ridge_slip", stopped.message
    assert "ridge" in stopped.message and "more friction" in stopped.message


def _sliding_up(v1: float, mu: float = 0.01) -> tuple[Scene, float]:
    """The roof with a ball started sliding up its near face (ω = 0) that reaches the edge at v1,
    still sliding (its slip falls at g sin α + (7/2) μ g cos α, its speed at g (sin α + μ cos α)),
    and the time it does."""
    alpha = math.atan(UP)
    a = G * (math.sin(alpha) + mu * math.cos(alpha))
    v0 = math.sqrt(v1 * v1 + 2.0 * a * 0.3 / math.cos(alpha))
    scene = Scene(f"min({UP}*x, -{DOWN}*x)", gravity=G, ball=Ball(RADIUS, 1.0),
                  start=Start(-0.3, 0.0, v0 * math.cos(alpha), 0.0, omega=(0.0, 0.0, 0.0)),
                  integrator=Integrator("rk4", True, 1e-3), duration=1.0, contact=Contact(mu, 0.0, "fly"))
    return scene, (v0 - v1) / a


@pytest.mark.parametrize("method", ["rk4", "lawson5", "gauss6", "dopri5", "dop853"])
def test_a_ball_sliding_onto_an_edge_too_slowly_to_leave_it_stops_and_says_so(method):
    """A sliding ball that reaches the edge at v1 with v1²/r < g cos α would turn over it rubbing on
    it, which the model does not follow: the run stops there (``ridge_pivot``), naming the normal
    force the turn needs, m (g cos α − v1²/r) (at v1 = 0.5 m/s: 7.02 N). Before, it "lifted off"
    and "landed" at the same instant, the energy jumping by 1.4 % and the run ending ok with a
    warning that blamed the step. Faster than √(g r cos α) it leaves the edge and lands on the far face."""
    scene, t_edge = _sliding_up(0.5)
    step = {"dt": 1e-3} if method in ("rk4", "lawson5", "gauss6") else {"rtol": 1e-10, "atol": 1e-10}
    run = simulate(scene, method=method, **step)
    assert run.status == "does_not_fit" and run.failure.reason == "ridge_pivot", run.message
    assert "sliding, too slowly to leave its edge" in run.message
    assert not run.transitions and set(run.mode) == {"sliding"}   # (sliding from its start)
    assert abs(run.failure.time - t_edge) < 1e-8 and abs(run.failure.x) < 1e-9
    expected = G * math.cos(math.atan(UP)) - 0.5 ** 2 / RADIUS
    assert abs(run.failure.value - expected) < 1e-6, (run.failure.value, expected)
    fast, t_fast = _sliding_up(1.2)
    flies = simulate(fast, method=method, **step)
    kinds = [c.kind for c in flies.transitions]
    assert flies.status == "ok" and kinds[:2] == ["liftoff", "landing"], (flies.message, kinds)
    assert abs(flies.transitions[0].time - t_fast) < 1e-8
    assert flies.transitions[1].time - flies.transitions[0].time > 0.01 and flies.transitions[1].x > 0.0


def test_a_ball_that_only_just_leaves_the_edge_comes_down_on_it_and_the_run_says_so():
    """Rolling up the near face (slope angle α) it reaches the edge at v1: where r g cos α < v1² it
    leaves the edge, but below r g / cos α its parabola comes back to the edge's circle (distance r
    from the edge) while the edge is still the nearest point of the surface, τ* later: a landing
    on an edge, which the model does not follow. The run stops at the lift-off (``edge_landing``,
    τ* in the failure's value); τ* here by brentq on the parabola's distance to the edge. Before,
    the landing search missed that root, found one 30 ms later on the edge that was none (its
    centre 0.100028 m from it) and stopped there as ``false_landing``. Just above r g / cos α the
    ball clears the edge and lands on the far face."""
    alpha = math.atan(UP)
    low, high = math.sqrt(RADIUS * G * math.cos(alpha)), math.sqrt(RADIUS * G / math.cos(alpha))
    for v1, returns in ((low + 0.4 * (high - low), True), (high * 1.01, False)):
        v0 = math.sqrt(v1 * v1 + 2.0 * (5.0 / 7.0 * G * math.sin(alpha)) * 0.3 / math.cos(alpha))
        t_edge, _ = at_edge(v0 * math.cos(alpha))
        traj = simulate(roof(v0 * math.cos(alpha), duration=0.6))
        assert traj.transitions[0].kind == "liftoff" and abs(traj.transitions[0].time - t_edge) < 1e-9

        def gap(tau, v1=v1):   # the centre's distance to the edge (the origin, in x-z) less r
            x = -RADIUS * math.sin(alpha) + v1 * math.cos(alpha) * tau
            z = RADIUS * math.cos(alpha) + v1 * math.sin(alpha) * tau - 0.5 * G * tau * tau
            return math.hypot(x, z) - RADIUS
        if returns:
            assert traj.status == "does_not_fit" and traj.failure.reason == "edge_landing", traj.message
            assert "comes down on that edge again" in traj.message and traj.warnings() == []
            taus = np.linspace(1e-5, 0.1, 10_000)   # (the gap rises from 0 after the lift-off, then falls)
            first = int(np.flatnonzero(np.array([gap(tau) for tau in taus]) < 0.0)[0])
            tau = brentq(gap, taus[first - 1], taus[first])
            assert abs(traj.failure.value - tau) < 1e-8, (traj.failure.value, tau)
            x, z = (-RADIUS * math.sin(alpha) + v1 * math.cos(alpha) * tau,
                    RADIUS * math.cos(alpha) + v1 * math.sin(alpha) * tau - 0.5 * G * tau * tau)
            assert 0.0 < math.atan2(x, z) + alpha < alpha + math.atan(DOWN)   # over the edge, not a face
        else:
            kinds = [c.kind for c in traj.transitions]
            assert traj.status == "ok" and kinds[:2] == ["liftoff", "landing"], traj.message
            assert traj.transitions[1].x > 0.0
