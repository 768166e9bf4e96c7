"""A kernel run stops where the contact changes mode (status "transition"), located on the dense
output: a lift-off where the ball flies, a slip where rolling needs more friction than μ F·N,
checked against the exact answers of a ball rolling off a cylinder."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rollball import kernel
from rollball.trajectory import Status

from contact_runs import rolling_state, segment

CYLINDER = "sqrt(1 - x^2)"    # radius 1; the ball (r = 0.1) starts near the top, at rest
X0 = 0.05
THETA0 = math.asin(X0)
METHODS = ("rk4", "dopri5", "gauss4")


def _liftoff_x():
    """The contact point where F·N = m g (17 cos θ − 10 cos θ₀) / 7 reaches 0."""
    return math.sin(math.acos(10.0 / 17.0 * math.cos(THETA0)))


def _slip_x(mu):
    """The contact point where the friction rolling needs, (2/7) m g sin θ, reaches μ F·N."""
    theta = brentq(lambda t: 2.0 * math.sin(t) - mu * (17.0 * math.cos(t) - 10.0 * math.cos(THETA0)), THETA0,
                   math.acos(10.0 / 17.0 * math.cos(THETA0)))
    return math.sin(theta)


@pytest.mark.parametrize("method", METHODS)
def test_a_flying_ball_stops_at_the_liftoff(method):
    start = rolling_state(CYLINDER, X0, 0.0, 0.0, 0.0)
    glued = segment(CYLINDER, start, sliding=False, method=method, dt=1e-3, t_end=1.6)
    flying = segment(CYLINDER, start, sliding=False, method=method, dt=1e-3, t_end=1.6, fly=True)
    assert glued.status == "ok" and glued.transition is None   # (glued: the 2011 model goes on)
    assert flying.status == "transition" and flying.transition == "liftoff"
    t, x, _ = flying.event
    assert x == pytest.approx(_liftoff_x(), abs=1e-9)
    assert abs(flying.force) < 1e-9          # the last row and state are at F·N = 0
    assert flying.rows[-1, kernel.ROW_T] == t and flying.rows[-1, kernel.ROW_CONTACT] == x
    assert flying.state.x == x
    assert t < glued.rows[-1, kernel.ROW_T]


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mu", [0.3, 1.0])
def test_a_rolling_ball_slips_where_friction_runs_out(method, mu):
    start = rolling_state(CYLINDER, X0, 0.0, 0.0, 0.0)
    run = segment(CYLINDER, start, sliding=False, method=method, dt=1e-3, t_end=1.6, mu=mu, fly=True)
    assert (run.status, run.transition) == ("transition", "slip")
    assert run.event[1] == pytest.approx(_slip_x(mu), abs=1e-9)
    assert run.need == pytest.approx(mu * run.force, rel=1e-9)
    assert run.force > 0.0
    # the state there rolls: its velocity is r ω × N, its slip 0
    normal = np.array([run.state.x, 0.0, math.sqrt(1.0 - run.state.x ** 2)])
    assert np.allclose(run.state.slip_velocity(normal, 0.1), 0.0, atol=1e-12)


@pytest.mark.parametrize("theta_deg, mu, slips", [(30.0, 0.1, True), (30.0, 0.2, False)])
def test_on_an_incline_a_start_at_rest_slips_at_once_iff_mu_is_below_two_sevenths_tan(theta_deg, mu, slips):
    """(2/7) tan 30° = 0.165: μ = 0.1 slips at t = 0, μ = 0.2 rolls on (and never slips)."""
    formula = f"{math.tan(math.radians(theta_deg))!r}*x"
    start = rolling_state(formula, 0.0, 0.0, 0.0, 0.0)
    run = segment(formula, start, sliding=False, method="rk4", dt=1e-2, t_end=0.5, mu=mu)
    if slips:
        assert (run.status, run.transition, run.event[0]) == ("transition", "slip", 0.0)
        assert len(run.rows) == 1
    else:
        assert run.status == "ok" and run.transition is None


def test_the_transition_is_declared_as_data():
    assert Status("transition") is Status.TRANSITION
    assert kernel.KERNEL_STATUSES[kernel.TRANSITION] == "transition"
    assert [kernel.transition_name(code) for code in (kernel.T_LIFTOFF, kernel.T_SLIP, kernel.T_GRIP,
                                                      kernel.T_REST)] == ["liftoff", "slip", "grip", "rest"]
    assert kernel.transition_name(kernel.T_NONE) is None
    assert "t = 1.5 s, (x, y) = (0.25, 0)" in kernel.transition_sentence("grip", 1.5, 0.25, 0.0)
    assert [mode for mode, _ in kernel.TRANSITIONS.values()] == ["flying", "sliding", "rolling", "resting"]
    assert kernel.transition_sentence("rest", 2.5, 1.0, 0.0) == "the ball comes to rest at t = 2.5 s, (x, y) = (1, 0)"
    # (the kernel's own stops, which Python never sees as a change of mode)
    assert kernel.transition_name(kernel.T_STIFF) is None and kernel.transition_name(kernel.T_SIDE) is None


@pytest.mark.parametrize("method", METHODS)
def test_a_flying_ball_stops_at_a_ridge(method):
    """Up the roof -|x| at 45° from x = -1 (6 m/s along x): the ball leaves the surface at the ridge
    x = 0, when (6√2 t − (5/7) g t² / (2√2)) / √2 = 1; the last state is the one just before it."""
    start = rolling_state("-abs(x)", -1.0, 0.0, 6.0, 0.0)
    run = segment("-abs(x)", start, sliding=False, method=method, dt=1e-3, t_end=0.5, fly=True)
    assert (run.status, run.transition) == ("transition", "liftoff")
    a = 5.0 / 7.0 * 9.81 / math.sqrt(2.0)
    t_ridge = (6.0 * math.sqrt(2.0) - math.sqrt(72.0 - 2.0 * a * math.sqrt(2.0))) / a
    t, x, _ = run.event
    assert t == pytest.approx(t_ridge, abs=1e-8) and abs(x) < 1e-8
    assert -1e-6 < run.state.x <= 0.0 and run.rows[-1, kernel.ROW_T] <= t


def test_after_a_slip_on_the_cylinder_every_method_slides_on_and_lifts_off_alike():
    """From the slip (μ = 0.3), where the friction rolling needs has just reached μ F·N, the slip
    starts from zero in a stiff direction (the friction would stop a small slip within a step):
    every method slides on (no grip at once), keeps energy + dissipated, and lifts off at the
    same place."""
    start = rolling_state(CYLINDER, X0, 0.0, 0.0, 0.0)
    slip = segment(CYLINDER, start, sliding=False, method="rk4", dt=1e-3, t_end=1.6, mu=0.3, fly=True)
    assert slip.transition == "slip"
    places = []
    for method in METHODS:
        run = segment(CYLINDER, slip.state, sliding=True, method=method, dt=1e-3, t_end=0.5, mu=0.3, fly=True)
        assert (run.status, run.transition) == ("transition", "liftoff")
        total = run.rows[:, kernel.ROW_ENERGY] + run.rows[:, kernel.ROW_DISSIPATED]
        assert np.abs(total - total[0]).max() < 1e-6 * abs(total[0]) and run.state.dissipated > 0.005
        places.append(run.event[1])
    assert max(places) - min(places) < 1e-4
