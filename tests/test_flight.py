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
from scipy.optimize import brentq

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
