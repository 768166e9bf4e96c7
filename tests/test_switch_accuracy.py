"""Changes of contact mode located to the method's own accuracy, and those that begin and end
inside one step, against exact answers: the cylinder's lift-off time (a quadrature, test_flight)
at several steps, and a lift-off over a small bump that lasts less than a step (scipy's DOP853
with its event location on the independent equations of rollball.reference)."""

import math

import numpy as np
import pytest
from conftest import make_scene
from scipy.integrate import solve_ivp

from rollball import simulate
from rollball.landscape import landscape_for
from rollball.reference import normal_force_zeros, reference_rhs
from rollball.scene import Contact
from rollball.tableaus import get_method

from test_flight import cylinder_scene, exact_liftoff_time

# Steps where each method's lift-off time error lies above round-off (1e-14 s here) and in its
# asymptotic range. The dense outputs of Lawson5 (a cubic Hermite) and the Gauss methods (the
# collocation polynomial) are of order 3: located on them, the lift-off time's error went as
# h^4 (Lawson5, Gauss6: fitted 2.5 to 7.5, not monotone, at these steps).
LADDERS = {"rk4": (0.02, 0.01, 0.005), "gauss4": (0.02, 0.01, 0.005), "lawson5": (0.04, 0.02, 0.01),
           "gauss6": (0.08, 0.04, 0.02)}


@pytest.mark.parametrize("method", list(LADDERS))
def test_the_liftoff_time_converges_at_the_methods_order(method):
    t_exact = exact_liftoff_time()
    dts = LADDERS[method]
    errors = []
    for dt in dts:
        traj = simulate(cylinder_scene(), method=method, dt=dt, t_end=t_exact + 0.05, record_every=1000)
        lift = next(change for change in traj.transitions if change.kind == "liftoff")
        errors.append(abs(lift.time - t_exact))
    print(method, ", ".join(f"dt {dt}: {e:.2e} s" for dt, e in zip(dts, errors)))
    assert min(errors) > 1e-14   # (the fit is of the method, not of round-off)
    order = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert order >= get_method(method).order - 0.3, (method, order, errors)


# -- a lift-off that begins and ends inside one step -------------------------------------------------

FLY = Contact(friction=None, restitution=0.0, after_liftoff="fly")
BUMP = make_scene("0.01*exp(-(x/0.1)^2)", x=-0.5, vx=2.47, duration=0.3, contact=FLY)
DIP_DT = 0.015   # no multiple of it falls inside the 7 ms the rolling ball's F·N is below 0




@pytest.fixture(scope="module")
def dip():
    return normal_force_zeros(BUMP, BUMP.duration)


def test_the_bump_dips_below_zero_inside_one_step(dip):
    down, up = dip[:2]
    assert len(dip) == 2 and 0 < up - down < DIP_DT
    assert math.floor(down / DIP_DT) == math.floor(up / DIP_DT)   # both ends of that step roll


@pytest.mark.parametrize("method, tolerance", [("rk4", 1e-6), ("lawson5", 2e-7), ("gauss6", 2e-8)])
def test_a_liftoff_inside_one_step_is_found(dip, method, tolerance):
    traj = simulate(BUMP, method=method, dt=DIP_DT)
    kinds = [change.kind for change in traj.transitions]
    assert kinds[:2] == ["liftoff", "landing"], kinds
    assert abs(traj.transitions[0].time - dip[0]) < tolerance


# -- a slip that begins and ends inside one step -------------------------------------------------------

SLIP_MU, SLIP_DT = 0.084, 0.005
SLIPPY = make_scene("0.01*exp(-(x/0.1)^2)", x=-0.5, vx=2.4, duration=0.3,
                    contact=Contact(friction=SLIP_MU, restitution=0.0, after_liftoff="fly"))


def slip_zeros(scene, mu, t0, t1, spacing=1e-4):
    """The times |F_t| − μ F·N of the rolling ball (the 2011 equations) crosses 0 in [t0, t1]: the
    contact force m (c̈ − g) from c̈ = r (ω̇ × N + ω × Ṅ), ω̇ = T⁻¹(v̇ − Ṫ ω) with T = m r² (2/5 I − [N]²)
    (not the torque formula the kernel uses), along scipy's DOP853 solution (rtol = atol = 1e-13),
    sign changes on a grid located by brentq. (scipy's own event location, which looks at the
    ends of its steps, misses the first of these two short slips at μ = 0.08.)"""
    from scipy.optimize import brentq

    from rollball.reference import _skew
    from rollball.simulation import initial_state

    landscape = landscape_for(scene.landscape)
    r, m, g0 = scene.ball.radius, scene.ball.mass, scene.gravity
    rhs = reference_rhs(scene)
    alpha, v = initial_state(landscape, scene)
    sol = solve_ivp(rhs, (0.0, t1), np.concatenate([alpha, v, np.eye(3).ravel()]), method="DOP853",
                    rtol=1e-13, atol=1e-13, dense_output=True)

    def condition(t):
        y = sol.sol(t)
        alpha, v = y[:2], y[2:5]
        _, fx, fy, fxx, fxy, fyy = landscape.evaluate(alpha[0], alpha[1])
        n = np.array([-fx, -fy, 1.0])
        N = n / np.linalg.norm(n)
        dN = (np.eye(3) - np.outer(N, N)) @ np.array([[-fxx, -fxy], [-fxy, -fyy], [0, 0]]) / np.linalg.norm(n)
        T = m * r * r * (0.4 * np.eye(3) - _skew(N) @ _skew(N))
        omega = np.linalg.solve(T, v)
        dy = rhs(t, y)
        N_dot = dN @ dy[:2]
        T_dot = -m * r * r * (_skew(N_dot) @ _skew(N) + _skew(N) @ _skew(N_dot))
        omega_dot = np.linalg.solve(T, dy[2:5] - T_dot @ omega)
        force = m * (r * (np.cross(omega_dot, N) + np.cross(omega, N_dot)) + np.array([0.0, 0.0, g0]))
        normal = force @ N
        return np.linalg.norm(force - normal * N) - mu * normal

    grid = np.arange(t0, t1, spacing)
    values = np.array([condition(t) for t in grid])
    changes = np.flatnonzero(np.diff(np.sign(values)) != 0)
    return [brentq(condition, grid[i], grid[i + 1], xtol=1e-15) for i in changes]


@pytest.fixture(scope="module")
def slips():
    return slip_zeros(SLIPPY, SLIP_MU, 0.15, 0.25)


def test_the_bump_asks_for_more_friction_than_there_is_inside_one_step(slips):
    assert len(slips) == 4   # a short slip on each side of the crest
    start, end = slips[:2]
    assert 0 < end - start < SLIP_DT and math.floor(start / SLIP_DT) == math.floor(end / SLIP_DT)


@pytest.mark.parametrize("method, tolerance", [("rk4", 2e-8), ("lawson5", 1e-9), ("gauss6", 1e-10)])
def test_a_slip_inside_one_step_is_found(slips, method, tolerance):
    traj = simulate(SLIPPY, method=method, dt=SLIP_DT, t_end=0.22)
    first = traj.transitions[0]
    assert first.kind == "slip" and abs(first.time - slips[0]) < tolerance, (first, slips[0])
