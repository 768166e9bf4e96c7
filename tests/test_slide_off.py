"""Sliding off the cylinder, against an independent computation: the ball rolls from rest near the
top of the cylinder (radius 1, on a floor at 0.1), slips where the friction rolling needs reaches
μ F·N (μ = 0.3), slides on with kinetic friction, leaves where F·N reaches 0, flies and lands on
the floor, once. ``python tests/test_slide_off.py`` prints the errors measured.

The reference is written here from the mechanics, not from RollBall's code. While the ball slides
its centre moves on the circle of radius ρ = 1 + r at the angle θ from the vertical, and with
F·N = m (g cos θ − ρ θ'²) the friction μ F·N acts against the slip (backwards):
ρ θ'' = g sin θ − μ (g cos θ − ρ θ'²), (2/5) m r² ω' = μ F·N r, integrated by scipy's DOP853 to
F·N = 0. The slip's place is the closed form 2 sin θ = μ (17 cos θ − 10 cos θ₀) (brentq), its
time that of the rolling ball's ρ θ'' = (5/7) g sin θ (DOP853 again). The landing is
brentq on the closed-form distance from the parabola to the cylinder and its floor."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from rollball import Scene, simulate
from rollball.flight import FreeState

from test_flight import CYLINDER, G, RADIUS, X0, expected_landing

MU = 0.3
RHO = 1.0 + RADIUS
THETA0 = math.asin(X0)


def exact_slip():
    """θ, θ' and t where the rolling ball slips: rolling, ρ θ'' = (5/7) g sin θ from rest at θ₀,
    integrated to the closed form's θ."""
    theta_s = brentq(lambda t: 2.0 * math.sin(t) - MU * (17.0 * math.cos(t) - 10.0 * math.cos(THETA0)), THETA0,
                     math.acos(10.0 / 17.0 * math.cos(THETA0)), xtol=1e-15, rtol=1e-15)

    def slips(t, y):
        return y[0] - theta_s
    slips.terminal = True
    sol = solve_ivp(lambda t, y: [y[1], 5.0 / 7.0 * G * math.sin(y[0]) / RHO], (0.0, 5.0), [THETA0, 0.0],
                    method="DOP853", rtol=1e-13, atol=1e-14, events=slips)
    (t,), ((_, rate),) = sol.t_events[0], sol.y_events[0]
    assert rate ** 2 == pytest.approx(G * (math.cos(THETA0) - math.cos(theta_s)) / (0.7 * RHO), rel=1e-12)
    return theta_s, rate, float(t)


def exact_liftoff():
    """(t, FreeState) where the sliding ball leaves the cylinder."""
    theta_s, rate_s, t_s = exact_slip()

    def rhs(t, y):
        theta, rate, omega = y
        normal = G * math.cos(theta) - RHO * rate * rate   # F·N / m
        return [rate, (G * math.sin(theta) - MU * normal) / RHO, 2.5 * MU * normal / RADIUS]

    def leaves(t, y):
        return G * math.cos(y[0]) - RHO * y[1] ** 2
    leaves.terminal, leaves.direction = True, -1
    sol = solve_ivp(rhs, (t_s, t_s + 1.0), [theta_s, rate_s, RHO * rate_s / RADIUS], method="DOP853",
                    rtol=1e-13, atol=1e-14, events=leaves)
    (t,), ((theta, rate, omega),) = sol.t_events[0], sol.y_events[0]
    assert RHO * rate - RADIUS * omega > 0.1   # it still slips there (forwards)
    center = RHO * np.array([math.sin(theta), 0.0, math.cos(theta)])
    velocity = RHO * rate * np.array([math.cos(theta), 0.0, -math.sin(theta)])
    return float(t), FreeState(float(t), center, velocity, np.array([0.0, omega, 0.0]), np.eye(3))


def scene():
    return Scene.from_dict({
        "format": "rollball-scene", "version": 3, "landscape": CYLINDER,
        "ball": {"radius": RADIUS, "mass": 1.0}, "start": {"x": X0, "y": 0.0},
        "contact": {"friction": MU, "after_liftoff": "fly"}, "duration": 1.75,
        "view": {"min": -2.0, "max": 2.0, "step": 0.05}})


# (method, options, bound on the errors of the lift-off's and the landing's time and place)
RUNS = [
    ("euler", dict(dt=1e-4), 1e-3),
    ("rk4", dict(dt=1e-3), 5e-12),
    ("rk4", dict(dt=5e-4), 1e-12),
    ("lawson5", dict(dt=1e-3), 5e-12),
    ("gauss4", dict(dt=1e-3), 5e-12),
    ("gauss6", dict(dt=1e-3), 5e-12),
    ("dopri5", dict(), 2e-6),                       # the scene's tolerances: rtol 1e-6
    ("dopri5", dict(rtol=1e-10, atol=1e-13), 2e-10),
    ("dop853", dict(), 5e-8),
]


def errors(method, options):
    traj = simulate(scene(), method=method, record_every=1 if method.startswith("dop") else 50, **options)
    kinds = [change.kind for change in traj.transitions]
    t_lift, state = exact_liftoff()
    t_land = t_lift + expected_landing(state)
    return traj, kinds, {
        "slip t": traj.transitions[0].time - exact_slip()[2],
        "liftoff t": traj.transitions[1].time - t_lift,
        "liftoff x": traj.transitions[1].x - state.center[0] / RHO,
        "landing t": traj.transitions[2].time - t_land,
        "landing x": traj.transitions[2].x - (state.center[0] + state.velocity[0] * (t_land - t_lift)),
    }


@pytest.mark.parametrize("method, options, bound", RUNS)
def test_one_liftoff_is_one_flight_that_lands_where_the_reference_says(method, options, bound):
    traj, kinds, errs = errors(method, options)
    # one flight: the ball slips, leaves once and lands once (on the floor, where it stays)
    assert kinds[:3] == ["slip", "liftoff", "landing"], kinds
    assert kinds.count("liftoff") == 1 and kinds.count("landing") == 1, kinds
    lift, land = traj.transitions[1:3]
    assert land.time - lift.time > 0.15 and land.impact_speed > 3.0
    assert max(abs(e) for e in errs.values()) < bound, errs
    assert traj.status == "ok"
    flying = traj.mode == "flying"
    assert np.all(traj.normal_force[flying] == 0.0)


def test_the_sliding_ball_stays_on_the_tangent_plane():
    """c'.N is 0 in the exact sliding motion: the rows just before the lift-off keep it to the
    integrator's accuracy (it used to grow while a slip started, where the friction's direction
    took it in at the stiff rate μ F·N / (m |u|))."""
    traj = simulate(scene(), method="rk4", dt=1e-3, t_end=1.42)
    sliding = traj.mode == "sliding"
    assert sliding.sum() > 100
    centre, velocity = traj.center[sliding], traj.velocity[sliding]
    normal = centre / np.linalg.norm(centre, axis=1)[:, None]   # (the cylinder's axis is the y axis)
    assert np.abs(np.einsum("ij,ij->i", velocity, normal)).max() < 1e-10


if __name__ == "__main__":
    for method, options, _ in RUNS:
        traj, kinds, errs = errors(method, options)
        print(f"{method} {options}: {kinds}\n    " + ", ".join(f"{k} {v:+.2e}" for k, v in errs.items()))
