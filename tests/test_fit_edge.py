"""The edge of the no-fit region, r·κ = 1, located where an independent computation puts it.

The valley example 4 y² − 0.3 x with balls too big for its bottom (r·κ ≥ 1 for r > 0.1305): near
the edge the contact point speeds up without bound, so a step of 1 ms can jump the thin no-fit
strip with both ends fitting. The truth here: the reference equations (scipy's DOP853) with the
largest principal curvature in closed form, stopped where r·κ reaches 1.
"""

import functools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rollball import Reason, Scene, Status, simulate, sweep
from rollball.examples import EXAMPLES_DIR
from rollball.geometry import fit_ratio
from rollball.landscape import landscape_for
from rollball.reference import reference_rhs, reference_solution
from rollball.scene import Ball, Integrator, Start
from rollball.simulation import initial_state
from rollball.sweeps.grid import with_values

VALLEY = Scene.load(EXAMPLES_DIR / "valley.json")
KEYS = ("ball.radius", "start.vy")


def valley_fit(radius, y):
    """r·κ_max of 4 y² − 0.3 x: a cylinder (κ_min = 0), so κ_max is the trace of G⁻¹ II, with
    G = I + ∇f ∇fᵀ, II = Hess f / W, W² = 1 + |∇f|²: 8 · 1.09 / (1.09 + 64 y²)^1.5."""
    return radius * 8 * 1.09 / (1.09 + 64 * y * y) ** 1.5


@functools.cache
def edge_time(scene, gap=1e-6):
    """When the reference contact point reaches r·κ = 1 − gap (it cannot pass the edge itself: its
    speed there is unbounded; the last 1e-6 of r·κ takes well under a microsecond)."""
    alpha, v = initial_state(landscape_for(scene.landscape), scene)

    def event(t, y):
        return valley_fit(scene.ball.radius, y[1]) - (1 - gap)

    event.terminal = True
    sol = solve_ivp(reference_rhs(scene), (0.0, scene.duration), np.concatenate([alpha, v, np.eye(3).ravel()]),
                    method="DOP853", rtol=1e-12, atol=1e-12, events=event)
    return sol.t_events[0][0] if sol.t_events[0].size else None


# (radius, vy): before the sub-step search, the first ran on to t = 3 s at x = 94 m, the second
# stopped 38 ms late (it had jumped the strip once), the third 4.5 ms late, the fourth (r·κ = 1.007
# at the bottom, a strip 1.6 cm wide) ran on to the end
CASES = [(0.16, -1.0), (0.14, 0.0), (0.2, 1.0), (0.131356, 2.5932)]


@pytest.mark.parametrize("radius, vy", CASES)
def test_too_big_ball_stops_at_the_edge_the_reference_reaches(radius, vy):
    scene = with_values(VALLEY, KEYS, (radius, vy))
    t_star = edge_time(scene)
    assert t_star is not None
    traj = simulate(scene)
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.NO_FIT
    # rk4 with 1 ms steps: the edge to a fiftieth of a step (measured: 1.5 µs at most)
    assert traj.failure.time == pytest.approx(t_star, abs=2e-5)
    assert traj.t[-1] <= traj.failure.time < traj.t[-1] + 1e-9
    # the last row is at the edge, on the side where the ball fits, and every row fits
    fits = valley_fit(radius, traj.contact[:, 1])
    assert (fits < 1).all() and fits[-1] > 1 - 1e-5
    assert valley_fit(radius, traj.failure.y) == pytest.approx(1.0, abs=1e-5)
    # the app's no-fit region is drawn by the same r·κ
    d = landscape_for(scene.landscape).evaluate(traj.failure.x, traj.failure.y)
    assert fit_ratio(d, radius) == pytest.approx(1.0, abs=1e-5)


@pytest.mark.parametrize("method, tolerance", [("euler", 5e-3), ("gauss4", 2e-5), ("dopri5", 2e-5)])
def test_every_kind_of_method_stops_at_the_edge(method, tolerance):
    """Explicit, implicit (whose stage equations stop converging at the edge) and adaptive steps
    alike, each to its accuracy (euler's error is of the order of its step)."""
    scene = with_values(VALLEY, KEYS, CASES[0])
    traj = simulate(scene, method=method)
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.NO_FIT
    assert traj.failure.time == pytest.approx(edge_time(scene), abs=tolerance)
    assert valley_fit(scene.ball.radius, traj.failure.y) == pytest.approx(1.0, abs=1e-5)


def test_sweep_runs_stop_where_simulate_stops_them_and_small_balls_roll_on():
    """The sweep's runs (the same compiled checks, without the orientation) end at the same edge;
    balls that fit (r·κ ≤ 0.92) roll the whole 3 s."""
    table = sweep(VALLEY, {"ball.radius": [0.12, 0.16], "start.vy": [-1.0, 2.5932]}, workers=1)
    values = table.grid.values()
    for i in range(len(table)):
        radius, vy = values[i]
        traj = simulate(with_values(VALLEY, KEYS, (radius, vy)))
        assert table["status"][i] == str(traj.status)
        assert table["t_reached"][i] == pytest.approx(traj.t[-1], abs=1e-12)
        if radius < 0.13:
            assert traj.status is Status.OK and traj.t[-1] == VALLEY.duration
            assert (valley_fit(radius, traj.contact[:, 1]) < 0.93).all()
        else:
            assert traj.status is Status.DOES_NOT_FIT
            assert math.isclose(valley_fit(radius, table["y_end"][i]), 1.0, abs_tol=1e-5)


def make(landscape, radius, method):
    return Scene(landscape=landscape, ball=Ball(radius, 1.0), start=Start(0.0, -0.5, 0.0, 2.0, 0.0),
                 integrator=Integrator(method, True, 1e-3), duration=1.0)


@pytest.mark.parametrize("method, tolerance", [("rk4", 5e-3), ("dopri5", 1e-5)])
def test_a_jump_of_the_curvature_where_the_ball_fits_is_crossed(method, tolerance):
    """Flat for y < 0, 4 y² beyond: r·κ jumps from 0 to 0.8 at y = 0, where the sub-step search
    starts. It crosses the jump and the ball rolls on, up the valley side and back, as the
    reference does (to the method's accuracy across a jump of the curvature: rk4 3.3 mm)."""
    scene = make("4*max(y,0)^2", 0.1, method)
    traj = simulate(scene)
    assert traj.status is Status.OK and traj.t[-1] == 1.0
    alpha, _, _ = reference_solution(scene, [0.0, 1.0], rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(traj.contact[-1], alpha[-1], atol=tolerance)


@pytest.mark.parametrize("method, tolerance", [("euler", 1e-12), ("dopri5", 2e-6)])
def test_a_jump_of_the_curvature_into_the_no_fit_region_stops_the_ball_there(method, tolerance):
    """Flat for y < 0, 8 y² beyond (r·κ = 2.4 from y = 0 on): the ball rolls straight at 2 m/s
    and stops at y = 0, t = 0.25 s exactly. (No fold leads up to this edge: rk4's inner stages
    can step over it unseen for a step or two.) dopri5 at its default rtol 1e-6 of the ball's
    size: 1.5e-6 s (an error scale relative to |y| alone found this edge to 8e-9 s only because
    it lies at y = 0, where that scale shrinks to atol; 2 m further out 1.6e-5 s either way)."""
    traj = simulate(make("8*max(y,0)^2", 0.15, method))
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.NO_FIT
    assert traj.failure.time == pytest.approx(0.25, abs=tolerance)
    assert traj.contact[-1, 1] == pytest.approx(0.0, abs=1e-9) and traj.contact[-1, 1] <= 0.0


BUMPS = Scene("1.98*sin(3*x)*cos(2*y)", start=Start(-0.41, 0.13, 0.91, -0.32, 0.1), duration=2.0)


@pytest.mark.parametrize("method, rtol", [("dopri5", 1e-8), ("dopri5", 1e-10), ("dop853", 1e-8), ("dop853", 1e-10)])
def test_the_pairs_stop_at_the_edge_they_cannot_step_past_as_not_fitting(method, rtol):
    """Bumps whose crests bend more than 1/r: the ball runs up to the edge r·κ = 1 at 1.21246 s
    (rk4 and dopri5 at 1e-8 stop there, the edge passed by a step's end). Where the pairs instead
    shrink their steps against the singular equations until they fall below round-off, r·κ at the
    last state is within ``loops.FIT_NEAR`` of 1 (measured 1 − 1.4e-6 to 1 − 7.7e-7): the stop is
    the ball's not fitting there, not "the equations are (nearly) singular" (``nonfinite``) as it was."""
    traj = simulate(BUMPS, method=method, rtol=rtol, atol=rtol)
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.NO_FIT, traj.message
    assert traj.failure.time == pytest.approx(1.21246, abs=1e-5)
    d = landscape_for(BUMPS.landscape).evaluate(traj.failure.x, traj.failure.y)
    assert fit_ratio(d, BUMPS.ball.radius) == pytest.approx(1.0, abs=1e-4)
