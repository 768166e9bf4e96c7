"""The model against exact answers: incline, flat ground, bowl period, energy, lift-off, fit."""

import math

import numpy as np
import pytest

from rollball import Reason, Status, simulate
from rollball.examples import EXAMPLES_DIR
from rollball.scene import Scene, SceneError
from conftest import V2_EXAMPLES

G = 9.81
COMBOS = [(m, mk) for m in ("euler", "rk4", "lawson5") for mk in (True, False)]


@pytest.mark.parametrize("method", ["rk4", "lawson5"])
@pytest.mark.parametrize("munthe_kaas", [True, False])
@pytest.mark.parametrize("s", [0.5, 50.0])  # z = -s x: slope angle theta with tan(theta) = s
def test_incline_accelerates_at_five_sevenths_g_sin_theta(scene_factory, method, munthe_kaas, s):
    scene = scene_factory(f"-{s}*x", x=-1.0, y=0.5, vx=0.3, vy=0.4, radius=0.2, mass=2.0,
                          method=method, munthe_kaas=munthe_kaas, dt=0.01)
    traj = simulate(scene, t_end=1.0)
    sin_theta = s / math.hypot(1, s)
    down = np.array([1.0, 0.0, -s]) / math.hypot(1, s)
    a = 5 / 7 * G * sin_theta
    c0, v0 = traj.center[0], traj.velocity[0]
    t = traj.t[:, None]
    # the motion is a polynomial of degree 2 in t, which these methods integrate exactly
    np.testing.assert_allclose(traj.center, c0 + v0 * t + 0.5 * a * t**2 * down, atol=1e-12)
    np.testing.assert_allclose(traj.velocity, v0 + a * t * down, atol=1e-12)
    np.testing.assert_allclose(traj.normal_force, 2.0 * G / math.hypot(1, s), rtol=1e-12)


@pytest.mark.parametrize("method, munthe_kaas", COMBOS)
@pytest.mark.parametrize("formula", ["0", "x - x + 0*y"])
def test_flat_ground_straight_constant_speed_and_spin(scene_factory, method, munthe_kaas, formula):
    scene = scene_factory(formula, x=-1.0, y=0.5, vx=1.2, vy=-0.7, spin=3.0, method=method,
                          munthe_kaas=munthe_kaas, dt=0.01)
    traj = simulate(scene, t_end=2.0)
    assert traj.status is Status.OK
    c0 = np.array([-1.0, 0.5, 0.1])
    v = np.array([1.2, -0.7, 0.0])
    np.testing.assert_allclose(traj.center, c0 + traj.t[:, None] * v, atol=1e-12)
    np.testing.assert_allclose(traj.velocity, np.broadcast_to(v, traj.velocity.shape), atol=1e-13)
    np.testing.assert_allclose(traj.omega[:, 2], 3.0, atol=1e-13)  # spin about the normal
    np.testing.assert_allclose(traj.normal_force, G, rtol=1e-14)
    np.testing.assert_allclose(traj.energy, traj.energy[0], rtol=1e-14)


def _upward_crossings(t, x):
    i = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


@pytest.mark.parametrize("k, r", [(1.0, 0.1), (2.0, 0.2)])
def test_bowl_small_oscillation_period(scene_factory, k, r):
    scene = scene_factory(f"{k}*(x^2 + y^2)/2", radius=r, x=1e-3, dt=1e-3)
    expected = 2 * math.pi * math.sqrt(7 * (1 / k - r) / (5 * G))
    traj = simulate(scene, t_end=3.2 * expected)
    crossings = _upward_crossings(traj.t, traj.contact[:, 0])
    assert len(crossings) == 3
    periods = np.diff(crossings)
    np.testing.assert_allclose(periods, expected, rtol=1e-5)


def test_bowl_normal_force_at_the_bottom(scene_factory):
    # the centre runs through the bottom on a circle of radius 1/k - r: F.N = m g + m V^2 / (1/k - r)
    k, r, m = 1.0, 0.1, 1.5
    scene = scene_factory("(x^2 + y^2)/2", radius=r, mass=m, x=0.4, dt=1e-4)
    traj = simulate(scene, t_end=1.0)
    x = traj.contact[:, 0]
    i = np.nonzero((x[:-1] > 0) & (x[1:] <= 0))[0][0]
    w = x[i] / (x[i] - x[i + 1])
    speed = np.linalg.norm((1 - w) * traj.velocity[i] + w * traj.velocity[i + 1])
    force = (1 - w) * traj.normal_force[i] + w * traj.normal_force[i + 1]
    assert force == pytest.approx(m * G + m * speed**2 / (1 / k - r), rel=1e-6)


@pytest.mark.parametrize("formula, start", [
    ("0.5*sin(x)*cos(y)", dict(x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)),
    ("0.3*(x^2 - y^2)", dict(x=1.0, y=0.05)),
    ("0.6*exp(-(x^2 + y^2))", dict(x=-2.5, y=0.35, vx=2.5)),
])
@pytest.mark.parametrize("method", ["rk4", "lawson5"])
def test_energy_is_conserved(scene_factory, formula, start, method):
    traj = simulate(scene_factory(formula, method=method, dt=1e-3, **start), t_end=5.0)
    assert traj.status is Status.OK
    assert traj.energy_drift < 1e-10
    # and it is a real exchange between kinetic and potential energy
    assert np.ptp(traj.center[:, 2]) > 0.05


def test_euler_drifts_in_energy(scene_factory):
    traj = simulate(scene_factory("0.5*sin(x)*cos(y)", method="euler", x=0.3, y=-0.2, vx=1.0), t_end=5.0)
    assert traj.energy_drift > 1e-4


def test_cylinder_lift_off_where_cos_theta_is_ten_seventeenths():
    scene = Scene.load(V2_EXAMPLES / "cylinder.json")
    traj = simulate(scene, dt=1e-4)
    assert traj.liftoff_time is not None
    x = np.interp(traj.liftoff_time, traj.t, traj.contact[:, 0])
    cos_theta0 = math.sqrt(1 - scene.start.x**2)
    assert math.sqrt(1 - x**2) == pytest.approx(10 / 17 * cos_theta0, abs=1e-5)
    # the glued model carries on past the lift-off until the landscape ends at x = 1
    assert traj.t[-1] > traj.liftoff_time
    assert traj.status in (Status.NONFINITE, Status.DOES_NOT_FIT)
    assert np.isfinite(traj.data).all()


def test_liftoff_example_reports_a_time_and_still_finishes():
    traj = simulate(Scene.load(EXAMPLES_DIR / "liftoff.json"))
    assert traj.status is Status.OK
    assert 0.2 < traj.liftoff_time < 0.6
    i = np.searchsorted(traj.t, traj.liftoff_time)
    assert traj.normal_force[i - 1] > 0 >= traj.normal_force[i]
    assert (traj.normal_force[:i] > 0).all()


def test_too_big_ball_stops_with_does_not_fit():
    scene = Scene.load(EXAMPLES_DIR / "too_big.json")
    traj = simulate(scene)
    assert traj.status is Status.DOES_NOT_FIT
    assert "does not fit" in traj.message and "t = " in traj.message
    assert traj.failure.reason is Reason.NO_FIT and traj.failure.value >= 1.0
    assert traj.t[-1] <= traj.failure.time < scene.duration
    # every row is a state where the ball still fits: the largest principal curvature of the
    # cylinder 4 y^2 - 0.3 x is the trace of G^-1 II, 8 * 1.09 / (1.09 + 64 y^2)^1.5
    y = traj.contact[:, 1]
    assert (scene.ball.radius * 8 * 1.09 / (1.09 + 64 * y**2) ** 1.5 < 1).all()
    # the same valley with the smaller ball is fine
    assert simulate(Scene.load(EXAMPLES_DIR / "valley.json")).status is Status.OK


def test_ball_that_does_not_fit_at_the_start(scene_factory):
    traj = simulate(scene_factory("4*y^2", radius=0.2))
    assert traj.status is Status.DOES_NOT_FIT
    assert len(traj) == 1 and traj.t[0] == 0


def test_running_off_the_domain_stops_nonfinite(scene_factory):
    traj = simulate(scene_factory("sqrt(x)", x=1.0, vx=-3.0), t_end=2.0)
    assert traj.status is Status.NONFINITE
    assert "non-finite" in traj.message and traj.failure.reason is Reason.UNDEFINED
    assert np.isfinite(traj.data).all()
    assert 0 < traj.t[-1] < 2.0


def test_start_outside_the_domain(scene_factory):
    traj = simulate(scene_factory("sqrt(x)", x=-1.0))
    assert traj.status is Status.NONFINITE
    assert len(traj) == 0
    assert "start point" in traj.message and traj.failure.reason is Reason.START_UNDEFINED
    assert (traj.failure.x, traj.failure.y) == (-1.0, 0.0)


def test_classic_euler_orientation_overflow_is_named(scene_factory):
    scene = scene_factory("0", vx=10.0, method="euler", dt=0.1)  # |omega| h = 10 rad per step
    classic = simulate(scene, munthe_kaas=False, t_end=200.0)
    assert classic.status is Status.NONFINITE
    assert "orientation R overflowed" in classic.message
    assert classic.failure.reason is Reason.ORIENTATION_OVERFLOW and classic.failure.value == 1.0
    assert np.isfinite(classic.data).all()
    assert simulate(scene, munthe_kaas=True, t_end=200.0).status is Status.OK


def test_overflowing_start_blames_the_start_values_not_the_landscape(scene_factory):
    # values that overflow on their own are refused by the scene rules, naming the key
    for options, key in ((dict(vx=1e300), "start.vx"), (dict(radius=1e300), "ball.radius")):
        with pytest.raises(SceneError) as info:
            scene_factory("0", **options)
        assert info.value.key == key
    # a start speed that overflows only with the landscape's slope (vz = f_x vx) stops the run
    for scene in (scene_factory("1e200*x", vx=1e100), scene_factory("1e200*x*y", y=1.0, vx=1e120)):
        traj = simulate(scene, t_end=0.1)
        assert traj.status is Status.NONFINITE and len(traj) == 0
        assert traj.failure.reason is Reason.START_OVERFLOW
        assert "landscape" not in traj.message and "classic" not in traj.message


def test_no_gravity_is_no_lift_off(scene_factory):
    traj = simulate(scene_factory("0.1*x", vx=1.0, vy=0.5, gravity=0.0), t_end=1.0)
    assert traj.status is Status.OK and traj.liftoff_time is None
    assert (traj.normal_force == 0).all()


def test_cost_is_counted(scene_factory):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, y=-0.2, vx=1.0)
    traj = simulate(scene, method="rk4", dt=0.01, t_end=1.0)
    assert (traj.steps, traj.rejected, traj.evaluations) == (100, 0, 1 + 4 * 100)
    traj = simulate(scene, method="dopri5", rtol=1e-3, atol=1e-6, dt=1.0, t_end=1.0)
    assert traj.rejected >= 1  # a first step of 1 s is too large for rtol 1e-3
    assert traj.evaluations == 1 + 6 * (traj.steps + traj.rejected)
    assert traj.failure is None
