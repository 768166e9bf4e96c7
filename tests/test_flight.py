"""Flight against exact answers: off the cylinder and onto its floor, where an independent root
finder (scipy's brentq on a closed-form distance, not RollBall's code) puts the landing.

The cylinder of radius 1 stands on a floor at height 0.1: z = sqrt(max(1 - x², 0.01)). A ball
of radius r rolling off it from rest at the contact angle θ₀ (sin θ₀ = x₀) leaves where
cos θ = (10/17) cos θ₀ with its centre, on the circle of radius ρ = 1 + r, moving at
v² = g ρ cos θ along the tangent; from there it falls freely.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from rollball import Scene, simulate
from rollball.flight import FreeState, Flight, Surface
from rollball.landscape import landscape_for

G, RADIUS, X0 = 9.81, 0.1, 0.05
CYLINDER = "sqrt(max(1 - x^2, 0.01))"
FLOOR = 0.1
EDGE = math.sqrt(1 - FLOOR ** 2)   # where the arc meets the floor


def liftoff_state():
    """The exact state where the ball leaves the cylinder: time-free (t = 0 here)."""
    rho = 1 + RADIUS
    cos_theta = 10 / 17 * math.sqrt(1 - X0 ** 2)
    sin_theta = math.sqrt(1 - cos_theta ** 2)
    speed = math.sqrt(G * rho * cos_theta)
    center = np.array([rho * sin_theta, 0.0, rho * cos_theta])
    velocity = speed * np.array([cos_theta, 0.0, -sin_theta])
    omega = np.array([0.0, speed / RADIUS, 0.0])   # rolling: ω = N × ċ / r
    return FreeState(0.0, center, velocity, omega, np.eye(3))


def distance_to_surface(x, z):
    """The closed-form distance from (x, z) to the arc x² + z² = 1 (|x| ≤ EDGE, z > 0) and the floor
    z = FLOOR (|x| ≥ EDGE) — each piece by elementary geometry."""
    angle, edge_angle = math.atan2(abs(x), z), math.atan2(EDGE, FLOOR)
    arc = math.hypot(x, z) - 1 if angle <= edge_angle else math.hypot(abs(x) - EDGE, z - FLOOR)
    floor = z - FLOOR if abs(x) >= EDGE else math.hypot(abs(x) - EDGE, z - FLOOR)
    return min(abs(arc), abs(floor))


def expected_landing(state):
    def gap(t):
        c = state.center + state.velocity * t + 0.5 * np.array([0, 0, -G]) * t * t
        return distance_to_surface(c[0], c[2]) - RADIUS
    grid = np.linspace(1e-3, 1.0, 2001)
    values = np.array([gap(t) for t in grid])
    first = int(np.flatnonzero(values < 0)[0])   # the first sign change on a fine grid...
    return brentq(gap, grid[first - 1], grid[first], xtol=1e-15, rtol=1e-15)   # ...located


def test_the_ball_off_the_cylinder_lands_where_brentq_says():
    state = liftoff_state()
    flight = Flight(Surface(landscape_for(CYLINDER)), state, radius=RADIUS, mass=1.0, gravity=G)
    t, foot = flight.landing(5.0)
    expected = expected_landing(state)
    landed = flight.state(t).center
    assert abs(t - expected) < 1e-13
    assert foot.y == 0.0 and foot.x > EDGE and landed[2] == pytest.approx(FLOOR + RADIUS, abs=1e-13)
    x_expected = state.center[0] + state.velocity[0] * expected
    assert foot.x == pytest.approx(x_expected, abs=1e-12)


# -- whole runs: rolling, the lift-off, the flight, the landing and rolling on -----------------------

def cylinder_scene(**contact):
    return Scene.from_dict({
        "format": "rollball-scene", "version": 3, "landscape": CYLINDER,
        "ball": {"radius": RADIUS, "mass": 1.0}, "start": {"x": X0, "y": 0.0},
        "contact": {"after_liftoff": "fly", **contact}, "duration": 2.0,
        "view": {"min": -2.0, "max": 2.0, "step": 0.05}})


def exact_liftoff_time():
    """t(θ) of the rolling ball from rest at θ₀: θ'² = g (cos θ₀ − cos θ) / (0.7 ρ), by quadrature
    (scipy's quad; the 1/√ singularity at θ₀ taken out by θ = θ₀ + s², and cos θ₀ − cos θ written
    2 sin((θ + θ₀)/2) sin(s²/2), which does not cancel near θ₀: the difference of cosines did, and
    put the time off by 3.3e-12 s; mpmath at 40 digits agrees with this to 1e-15)."""
    rho, theta0 = 1 + RADIUS, math.asin(X0)
    theta_l = math.acos(10 / 17 * math.cos(theta0))

    def integrand(s):
        if s == 0:
            return 2 / math.sqrt(G * math.sin(theta0) / (0.7 * rho))
        drop = 2 * math.sin(theta0 + 0.5 * s * s) * math.sin(0.5 * s * s)   # cos θ₀ − cos θ
        return 2 * s / math.sqrt(G * drop / (0.7 * rho))
    return quad(integrand, 0.0, math.sqrt(theta_l - theta0), epsabs=1e-13, epsrel=1e-13, limit=200)[0]


@pytest.mark.parametrize("dt", [1e-3, 5e-4])
def test_off_the_cylinder_onto_the_floor_at_two_steps(dt):
    traj = simulate(cylinder_scene(), dt=dt, record_every=20)
    kinds = [change.kind for change in traj.transitions]
    assert kinds[:2] == ["liftoff", "landing"], kinds
    lift, land = traj.transitions[:2]
    t_lift = exact_liftoff_time()
    x_lift = math.sin(math.acos(10 / 17 * math.sqrt(1 - X0 ** 2)))
    t_land = t_lift + expected_landing(liftoff_state())
    state = liftoff_state()
    x_land = state.center[0] + state.velocity[0] * (t_land - t_lift)
    errors = {"liftoff t": abs(lift.time - t_lift), "liftoff x": abs(lift.x - x_lift),
              "landing t": abs(land.time - t_land), "landing x": abs(land.x - x_land)}
    print(f"dt = {dt}: " + ", ".join(f"{k} {v:.2e}" for k, v in errors.items()))
    assert max(errors.values()) < 1e-8
    assert traj.liftoff_time == lift.time   # the first lift-off is still reported
    assert traj.status == "ok" and traj.mode[-1] == "rolling"
    flying = traj.mode == "flying"
    assert np.all(traj.normal_force[flying] == 0.0)
    assert np.all((traj.t[flying] > lift.time) & (traj.t[flying] < land.time))
    # energy: exact in flight, and what the landing took is accounted for
    assert land.energy_lost > 0 and np.max(np.abs(traj.energy_error())) < 1e-8


def test_rebounds_on_the_floor_lose_their_height_by_e_squared():
    """A narrow bump launches the ball onto the plain beyond it (flat to 10⁻¹² m past x = 1.1),
    where it bounces: each rebound leaves at e times the speed it hit with, so its apex, and the
    speed of the next landing, follow exactly."""
    e = 0.5
    scene = Scene.from_dict({
        "format": "rollball-scene", "version": 3, "landscape": "0.2*exp(-20*x^2)",
        "start": {"x": -1.0, "y": 0.0, "vx": 3.0}, "contact": {"restitution": e}, "duration": 1.5})
    traj = simulate(scene, dt=1e-3, record_every=10)
    landings = [change for change in traj.transitions if change.kind == "landing" and change.x > 1.1]
    assert len(landings) >= 4, traj.transitions
    speeds = np.array([change.impact_speed for change in landings])
    apexes = (e * speeds) ** 2 / (2 * G)    # each rebound's apex above the floor
    assert apexes[1:] / apexes[:-1] == pytest.approx(e * e, rel=1e-9)
