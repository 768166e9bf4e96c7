"""A ball that flies off the tip of a cone, z = -0.3 sqrt(x² + y²), against exact answers.
``python tests/test_tip_flight.py`` prints the errors measured.

Rolled straight at the tip (start (-0.5, 0), horizontal velocity (2, 0)) the ball rolls up a
generator, an incline of slope 0.3: its centre decelerates at (5/7) g sin β (tan β = 0.3) and the
contact point reaches the tip in closed form. There the contact can only stay at the tip, the
centre turning about it on the sphere of radius r, which needs F·N = m (g e_z − v²/r) (e the unit
vector from the tip to the centre): at v²/r = 19 m/s² > g cos β = 9.4 m/s² that is negative, so the
ball leaves the tip as it reaches it, on the parabola from there. It lands where the centre's
closed-form distance to the cone (in the meridian half-plane: to the generator ray, or to the tip)
first comes down to r (brentq). Passed beside the tip (start (-0.5, 0.01)) the ball's contact point
also reaches the tip (the centre meets the sphere about it), at the time scipy's DOP853 on the
model's equations says (rollball/reference.py, as tests/test_cone_tip.py)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from conftest import make_scene
from rollball import simulate
from rollball.scene import Contact

CONE = "-0.3*sqrt(x^2+y^2)"
G, R = 9.81, 0.1
SLOPE = 0.3
L = math.sqrt(1 + SLOPE ** 2)
FLY = Contact(None, 0.0, "fly")


def cone(y0, duration=0.6):
    return make_scene(CONE, x=-0.5, y=y0, vx=2.0, duration=duration, contact=FLY)


def exact_tip():
    """Time to the tip, the centre and its velocity there (rolling straight up the generator)."""
    v0, s = 2.0 * L, 0.5 * L                  # speed and distance along the slope
    a = 5.0 / 7.0 * G * SLOPE / L
    v1 = math.sqrt(v0 * v0 - 2 * a * s)
    t = (v0 - v1) / a
    normal = np.array([-SLOPE, 0.0, 1.0]) / L    # the incoming face's
    return t, R * normal, v1 * np.array([1.0, 0.0, SLOPE]) / L


def distance_to_cone(c):
    """The closed-form distance from a point above the cone to it: in the meridian half-plane
    (ρ, z), to the generator ray z = -0.3 ρ (ρ ≥ 0) or, behind its start, to the tip."""
    rho, z = math.hypot(c[0], c[1]), c[2]
    along = (rho - SLOPE * z) / L
    return abs(SLOPE * rho + z) / L if along >= 0 else math.hypot(rho, z)


def exact_landing(center, velocity):
    def gap(tau):
        return distance_to_cone(center + velocity * tau + 0.5 * np.array([0.0, 0.0, -G]) * tau * tau) - R
    grid = np.linspace(1e-6, 1.0, 4001)
    values = np.array([gap(tau) for tau in grid])
    assert values[0] > 0
    first = int(np.flatnonzero(values < 0)[0])
    tau = brentq(gap, grid[first - 1], grid[first], xtol=1e-15, rtol=1e-15)
    return tau, center + velocity * tau + 0.5 * np.array([0.0, 0.0, -G]) * tau * tau


RUNS = [("euler", dict(dt=1e-4), 1e-4), ("rk4", dict(dt=1e-3), 2e-8), ("rk4", dict(dt=1e-4), 2e-8),
        ("lawson5", dict(dt=1e-3), 2e-8), ("gauss4", dict(dt=1e-3), 2e-8), ("gauss6", dict(dt=1e-3), 2e-8),
        ("dopri5", dict(), 2e-8), ("dop853", dict(), 2e-8)]


def errors(method, options):
    traj = simulate(cone(0.0), method=method, record_every=1 if method.startswith("dop") else 20, **options)
    t_tip, center, velocity = exact_tip()
    tau, landed = exact_landing(center, velocity)
    kinds = [change.kind for change in traj.transitions]
    lift, land = traj.transitions[:2]
    return traj, kinds, {"liftoff t": lift.time - t_tip, "liftoff place": math.hypot(lift.x, lift.y),
                         "landing t": land.time - (t_tip + tau), "landing x": land.x - landed[0] / 1.0}


def test_the_ball_is_fast_enough_to_leave_the_tip():
    _, center, velocity = exact_tip()
    e = center / R
    assert G * e[2] - velocity @ velocity / R < -9.0   # F·N / m it would need to turn about the tip


@pytest.mark.parametrize("method, options, bound", RUNS)
def test_rolled_at_the_tip_it_leaves_the_apex_on_the_parabola(method, options, bound):
    traj, kinds, errs = errors(method, options)
    assert kinds[:2] == ["liftoff", "landing"] and kinds.count("liftoff") == 1, kinds
    lift, land = traj.transitions[:2]
    assert traj.liftoff is not None and traj.liftoff.kink and traj.liftoff.time == lift.time
    assert land.time - lift.time > 0.1 and land.impact_speed > 0.5
    # (the landing's x is the foot on the far face: the centre's x less r sin β)
    errs["landing x"] -= -R * SLOPE / L
    assert max(abs(e) for e in errs.values()) < bound, errs
    flying = traj.mode == "flying"
    assert flying.any() and np.all(traj.normal_force[flying] == 0.0)
    # flight is exact: the energy is kept until the landing
    during = (traj.t > lift.time) & (traj.t < land.time)
    e = traj.energy[during]
    assert np.abs(e - e[0]).max() < 1e-12 * abs(e[0]) + 1e-12


@pytest.mark.parametrize("method, options", [("dopri5", dict(rtol=1e-10, atol=1e-13)), ("dop853", dict()),
                                             ("rk4", dict(dt=1e-4))])
def test_rolled_beside_the_tip_it_reaches_it_and_flies_once(method, options):
    from test_cone_tip import reference_tip_time
    t_tip = reference_tip_time(make_scene(CONE, x=-0.5, y=0.01, vx=2.0, duration=0.5))
    traj = simulate(cone(0.01), method=method, record_every=1 if method.startswith("dop") else 20, **options)
    kinds = [change.kind for change in traj.transitions]
    assert kinds[:2] == ["liftoff", "landing"] and kinds.count("liftoff") == 1, kinds
    lift, land = traj.transitions[:2]
    assert abs(lift.time - t_tip) < 1e-6 and math.hypot(lift.x, lift.y) < 1e-8
    assert land.time - lift.time > 0.1


def test_glued_the_tip_is_reported_as_before():
    traj = simulate(make_scene(CONE, x=-0.5, y=0.0, vx=2.0, duration=0.6), method="rk4", dt=1e-3)
    assert traj.transitions == () and traj.liftoff.kink and traj.status == "ok"


def test_a_ball_sliding_too_slowly_to_leave_the_tip_stops_there_saying_why():
    """A rolling ball too slow to leave the tip turns over it (tests/test_tip_turn.py); one that
    reaches it sliding (μ = 0.02 < (2/7) tan β: it slips at once and slides up) with
    v²/r < g cos β would slide over it, which the model does not follow: the run stops, ``pivot``."""
    traj = simulate(make_scene(CONE, x=-0.5, y=0.0, vx=1.7, duration=0.6, contact=Contact(0.02, 0.0, "fly")),
                    method="rk4", dt=1e-3)
    assert traj.mode[-1] == "sliding" and [str(c.kind) for c in traj.transitions] == ["slip"]
    assert traj.status == "does_not_fit" and traj.failure.reason == "pivot", traj.message
    assert traj.failure.value > 0 and math.hypot(traj.failure.x, traj.failure.y) < 1e-8
    assert traj.liftoff is None


if __name__ == "__main__":
    for method, options, _ in RUNS:
        traj, kinds, errs = errors(method, options)
        errs["landing x"] -= -R * SLOPE / L
        print(f"{method} {options}: {kinds[:3]}\n    " + ", ".join(f"{k} {v:+.2e}" for k, v in errs.items()))
