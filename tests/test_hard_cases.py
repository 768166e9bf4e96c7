"""Numerical hard cases, each with its documented outcome (summarised in docs/guide/limits.md).

Exact answers tested elsewhere and not repeated here: the cylinder lift-off cos θ = (10/17) cos θ₀
(test_physics), a ball too big at the start, running off the domain of sqrt (test_physics), the
incline with a slope of 50 (test_physics), constant landscapes on grids (test_landscape).
"""

import math
import time

import mpmath
import numpy as np
import pytest
from conftest import make_scene

from rollball import Reason, Status, machine_code, simulate
from rollball.kernel import rodrigues
from rollball.landscape import landscape_for
from rollball.reference import reference_rhs, reference_solution
from rollball.simulation import initial_state

METHODS = ["euler", "rk4", "lawson5"]
HILLS = dict(x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)


def assert_honest(traj, seconds, elapsed):
    """Finished in time, every row finite, no row after a reported failure."""
    assert elapsed < seconds
    assert np.isfinite(traj.data).all()
    if traj.status in (Status.NONFINITE, Status.DOES_NOT_FIT) and len(traj):
        assert traj.t[-1] <= traj.failure.time


def timed(scene, **kwargs):
    """The run's own processor time: the landscape and the kernel's machine code are made first
    (seconds on a loaded machine with the test run's empty cache), and the run is timed in
    processor time of this thread (the kernel runs in it), so the bounds above, 10x or more what
    the runs take, judge the run and not the machine's load."""
    landscape_for(scene.landscape).compiled  # noqa: B018
    machine_code.entries()
    start = time.thread_time()
    traj = simulate(scene, **kwargs)
    return traj, time.thread_time() - start


# -- large steps ----------------------------------------------------------------------------------

# status at t = 200 s on the sine-cosine hills, per (method, Munthe-Kaas, h)
LARGE_STEP_STATUS = {
    ("euler", True): {0.05: "ok", 0.1: "nonfinite", 0.2: "nonfinite", 0.5: "nonfinite"},
    ("euler", False): {h: "nonfinite" for h in (0.05, 0.1, 0.2, 0.5)},
    ("rk4", True): {h: "ok" for h in (0.05, 0.1, 0.2, 0.5)},
    ("rk4", False): {0.05: "ok", 0.1: "ok", 0.2: "nonfinite", 0.5: "nonfinite"},
    ("lawson5", True): {h: "ok" for h in (0.05, 0.1, 0.2, 0.5)},
    ("lawson5", False): {0.05: "ok", 0.1: "ok", 0.2: "nonfinite", 0.5: "nonfinite"},
}


@pytest.mark.parametrize("h", [0.05, 0.1, 0.2, 0.5])
@pytest.mark.parametrize("munthe_kaas", [True, False], ids=["munthe-kaas", "classic"])
@pytest.mark.parametrize("method", METHODS)
def test_large_steps_end_with_a_status_never_a_crash(method, munthe_kaas, h):
    """Steps of 0.05 … 0.5 s on the hills for 200 s, each run well under a second.

    Euler gains energy until the state overflows (status nonfinite, 'step is too large'); the
    classic matrix update lets R grow until it overflows (nonfinite, 'orientation R overflowed');
    Munthe-Kaas keeps every recorded R a rotation to 1e-13 whatever the step. RK4 and Lawson5
    stay bounded; their energy drift grows with h (RK4 3e-5 at h = 0.05, 1.7 at h = 0.5).
    """
    scene = make_scene("0.5*sin(x)*cos(y)", method=method, munthe_kaas=munthe_kaas, dt=h, **HILLS)
    traj, elapsed = timed(scene, t_end=200.0)
    assert_honest(traj, 5.0, elapsed)
    assert traj.status == LARGE_STEP_STATUS[method, munthe_kaas][h]
    if traj.status is Status.NONFINITE:
        expected = Reason.UNDEFINED if munthe_kaas else Reason.ORIENTATION_OVERFLOW
        assert traj.failure.reason is expected
        assert ("step is too large" if munthe_kaas else "orientation R overflowed") in traj.message
    if munthe_kaas:
        assert traj.orthogonality_error().max() < 1e-13


# -- long runs ------------------------------------------------------------------------------------

# (method, Munthe-Kaas): (energy drift range, largest ||R^T R - I||) after 10^6 steps of 1 ms
LONG_RUN = {
    ("rk4", True): ((0, 1e-10), 1e-12),
    ("rk4", False): ((0, 1e-10), 1e-4),
    ("lawson5", True): ((0, 1e-10), 1e-12),
    ("lawson5", False): ((0, 1e-10), 1e-6),
    ("euler", True): ((1, 10), 1e-12),
}


@pytest.mark.parametrize("method, munthe_kaas", list(LONG_RUN))
def test_long_run_stays_bounded(method, munthe_kaas):
    """10⁶ steps of 1 ms (1000 s) on the hills, recorded every 10⁴ steps, under 2 s each.

    RK4 and Lawson5 keep the energy to round-off (drift ≈ 1e-11); Euler gains energy (drift ≈ 2.6).
    Munthe-Kaas R stays orthogonal to 3e-13; the classic R drifts to ≈ 3e-6 (RK4), 7e-8 (Lawson5).
    """
    scene = make_scene("0.5*sin(x)*cos(y)", method=method, munthe_kaas=munthe_kaas, **HILLS)
    traj, elapsed = timed(scene, t_end=1000.0, record_every=10_000)
    assert_honest(traj, 10.0, elapsed)
    assert traj.status is Status.OK and traj.steps == 10**6
    (low, high), orthogonality = LONG_RUN[method, munthe_kaas]
    assert low <= traj.energy_drift < high
    error = traj.orthogonality_error().max()
    assert error < orthogonality
    if not munthe_kaas:
        assert error > orthogonality / 1000  # it does drift, linearly in the number of steps


# -- very fast balls ------------------------------------------------------------------------------

def exact_rotation(u):
    """exp(A(u)) to 30 digits."""
    with mpmath.workdps(30):
        u = mpmath.matrix([mpmath.mpf(float(c)) for c in u])
        theta = mpmath.norm(u)
        A = mpmath.matrix([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        return np.array((mpmath.eye(3) + mpmath.sin(theta) / theta * A
                         + (1 - mpmath.cos(theta)) / theta**2 * A * A).tolist(), dtype=float)


@pytest.mark.parametrize("theta", [1e-12, 1e-8, 1e-5, 1e-4 * (1 - 1e-9), 1e-4, 1e-4 * (1 + 1e-9), 1e-3,
                                   0.1, 1.0, 3.0, math.pi - 1e-9, math.pi, 4.0, 2 * math.pi, 10.0, 100.0])
def test_rodrigues_is_exact_at_any_angle(theta):
    """exp(A(u)) R to round-off for angles from 1e-12 to 100 rad, also either side of the switch
    from the small-angle series to sin/cos at |u| = 1e-4."""
    u = theta * np.array([0.48, -0.6, 0.64])  # a unit axis
    R0 = exact_rotation(np.array([0.3, -1.1, 0.7]))
    out = np.empty((3, 3))
    rodrigues(u[0], u[1], u[2], R0, out)
    np.testing.assert_allclose(out, exact_rotation(u) @ R0, rtol=0, atol=2e-15)
    rodrigues(u[0], u[1], u[2], R0, R0)  # in place
    np.testing.assert_allclose(R0, out, rtol=0, atol=0)


@pytest.mark.parametrize("angle_per_step", [0.5, 1.0, 3.0, 6.0])
@pytest.mark.parametrize("method", METHODS + ["gauss4", "gauss6"])
def test_spinning_ball_munthe_kaas_is_exact_at_any_angle_per_step(method, angle_per_step):
    """On flat ground ω is constant, so Munthe-Kaas turns R exactly whatever |ω| h: after 1000
    steps R is the rotation by ω t to 1e-12, with every method (ω = (−6, 8, 50) rad/s)."""
    omega = np.array([-6.0, 8.0, 50.0])
    r = 0.1
    scene = make_scene("0", vx=omega[1] * r, vy=-omega[0] * r, spin=omega[2], method=method)
    h = angle_per_step / np.linalg.norm(omega)
    traj = simulate(scene, dt=h, t_end=1000 * h, record_every=100)
    assert traj.status is Status.OK
    np.testing.assert_allclose(traj.omega, np.broadcast_to(omega, traj.omega.shape), atol=1e-12)
    np.testing.assert_allclose(traj.R[-1], exact_rotation(omega * traj.t[-1]), atol=1e-11)


@pytest.mark.parametrize("angle_per_step", [0.5, 1.0, 3.0])
def test_spinning_ball_classic_rk4_shrinks_or_grows_as_its_stability_function(angle_per_step):
    """The classic RK4 update multiplies R's rotating part by P(iθ) = Σ (iθ)^k / k! (k ≤ 4) per step,
    θ = |ω| h: R shrinks for θ < 2√2 and grows beyond (|P| = 0.99997, 0.993, 1.27); exact to 1e-9."""
    scene = make_scene("0", spin=50.0, munthe_kaas=False)
    h = angle_per_step / 50.0
    n = 200
    traj = simulate(scene, dt=h, t_end=n * h, record_every=n)
    P = sum((1j * angle_per_step) ** k / math.factorial(k) for k in range(5))
    singular = np.linalg.svd(traj.R[-1], compute_uv=False)
    np.testing.assert_allclose(sorted(singular), sorted([1.0, abs(P) ** n, abs(P) ** n]), rtol=1e-9)


# method: h -> (largest R error with Munthe-Kaas, smallest R error of the classic update)
FAST_BALL = {"rk4": {1e-2: (1e-5, 0.1), 1e-3: (1e-9, 1e-5)},
             "lawson5": {1e-2: (1e-6, 1e-3), 1e-3: (1e-10, 1e-8)}}


@pytest.mark.parametrize("method", list(FAST_BALL))
def test_fast_ball_on_the_hills_against_the_reference(method):
    """A ball spinning at 100 rad/s rolls over the hills for 1 s, against the DOP853 reference.

    The motion does not depend on R: the contact point is within 1e-9 at h = 10 ms. At
    |ω| h ≈ 1 rad per step Munthe-Kaas keeps R within 4e-6 (RK4) and 2e-7 (Lawson5); the classic
    update is off by 0.5 (RK4, R no longer a rotation) and 0.02 (Lawson5); at h = 1 ms the errors
    are 4e-10 / 3e-11 against 8e-5 / 1e-7.
    """
    scene = make_scene("0.5*sin(x)*cos(y)", x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=100.0)
    alpha, _, R = reference_solution(scene, [0.0, 1.0])
    for h, (munthe_kaas_error, classic_error) in FAST_BALL[method].items():
        mk, classic = (simulate(scene, method=method, munthe_kaas=mk, dt=h, t_end=1.0, record_every=10**4)
                       for mk in (True, False))
        assert mk.status is classic.status is Status.OK
        np.testing.assert_allclose(mk.contact[-1], alpha[-1], atol=1e-9)
        assert np.abs(mk.R[-1] - R[-1]).max() < munthe_kaas_error
        assert np.abs(classic.R[-1] - R[-1]).max() > classic_error


# -- steep landscapes, walls, poles, kinks ---------------------------------------------------------

def test_exponential_wall_turns_the_ball_back_with_energy_conserved():
    """exp(20 (x − 1)), slope up to 20·e^20 if the ball got there: it climbs to the height where its
    energy is all potential (E₀ / m g, to 2e-6) and rolls back; energy drift below 1e-5."""
    scene = make_scene("exp(20*(x - 1))", vx=3.0, duration=3.0)
    traj, elapsed = timed(scene)
    assert_honest(traj, 5.0, elapsed)
    assert traj.status is Status.OK and traj.energy_drift < 1e-5
    top = traj.energy[0] / 9.81
    assert traj.center[:, 2].max() == pytest.approx(top, rel=2e-6)
    assert traj.velocity[-1, 0] == pytest.approx(-3.0, rel=1e-4)  # back on the flat part


@pytest.mark.parametrize("formula, start, outcome", [
    # climbing towards the pole of 1/x: turned back, energy conserved
    ("1/x", dict(x=1.0, vx=-1.0), dict(status="ok", drift=1e-12, liftoff=False)),
    # falling into the pole of 1/x from the left: a crest, lift-off, then the glued ball slides on,
    # creeping towards the pole (x = -7e-4 at 20 s, third derivative ~ 6/x^4): the step error grows
    ("1/x", dict(x=-1.0, vx=1.0), dict(status="ok", drift=1e-8, liftoff=True)),
    # log(x): over the crest (lift-off), then down the wall until x underflows: nonfinite at t ≈ 10 s
    ("log(x)", dict(x=1.0, vx=-1.0), dict(status="nonfinite", drift=1e-3, liftoff=True)),
    # steep exponential slope going down: energy conserved
    ("exp(10*x)", dict(x=0.2), dict(status="ok", drift=1e-7, liftoff=False)),
    # a cusp valley sqrt(|x|): the real ball leaves the surface before it reaches the cusp; the
    # glued one slides on into the cusp (infinite curvature), where it no longer fits
    ("sqrt(abs(x))", dict(x=1.0, vx=-2.0), dict(status="does_not_fit", drift=1e-2, liftoff=True)),
])
def test_poles_and_steep_walls(formula, start, outcome):
    """Each within a second: status, energy drift bound and lift-off as listed; all rows finite and
    none after a stop, whose message gives the time and position."""
    traj, elapsed = timed(make_scene(formula, duration=20.0, **start), record_every=100)
    assert_honest(traj, 5.0, elapsed)
    assert traj.status == outcome["status"]
    assert traj.energy_drift < outcome["drift"]
    assert (traj.liftoff_time is not None) == outcome["liftoff"]
    if traj.status is Status.NONFINITE:
        f = traj.failure
        assert f"t = {f.time:.6g} s" in traj.message and f"(x, y) = ({f.x:.6g}, {f.y:.6g})" in traj.message


def test_cusp_lift_off_comes_before_the_cusp():
    traj = simulate(make_scene("sqrt(abs(x))", x=1.0, vx=-2.0, duration=2.0))
    i = np.searchsorted(traj.t, traj.liftoff_time)
    assert traj.normal_force[i - 1] > 0 >= traj.normal_force[i]
    assert traj.contact[i, 0] > 0.01


@pytest.mark.parametrize("h", [1e-2, 1e-3, 1e-4])
def test_kink_in_a_valley_does_not_fit(h):
    """abs(x) has no second derivative at 0 (its Dirac delta is dropped), so the end-of-step fit
    check cannot see the kink; the secant curvature of the step across it (about √2 / step)
    can, and the kink is then located by bisection on the step's dense output: the run stops
    there, at the exact time, with energy conserved up to it."""
    traj = simulate(make_scene("abs(x)", x=-1.0, vx=2.0, dt=h, duration=2.0))
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.KINK
    # on the plane z = -x the contact point accelerates at (5/14) g along x from x = -1, vx = 2
    a = 5 / 14 * 9.81
    t_kink = (-2 + math.sqrt(4 + 2 * a)) / a
    assert traj.failure.time == pytest.approx(t_kink, abs=1e-9) and abs(traj.failure.x) < 1e-9
    assert traj.failure.value == pytest.approx(math.sqrt(2), rel=1e-6)  # the normal turns by 90°
    assert -h * h < traj.contact[-1, 0] < 1e-6 and t_kink - h * h < traj.t[-1] <= t_kink + 1e-9  # the last row
    assert "(x, y) = (" in traj.message
    assert traj.energy_drift < 1e-12


def test_adaptive_steps_stop_at_the_kink_too():
    traj = simulate(make_scene("abs(x)", x=-1.0, vx=2.0, method="dopri5", duration=2.0), record_dt=0.01)
    assert traj.status is Status.DOES_NOT_FIT
    assert abs(traj.contact[-1, 0]) < 1e-6 and traj.energy_drift < 1e-8


@pytest.mark.parametrize("h", [1e-2, 1e-3, 1e-4])
def test_kink_crossing_costs_energy_of_order_h(h):
    """What the model does at the kink of a ridge, -abs(x), where the ball fits: it crosses
    with an energy jump between h/20 and h (relative), depending on where the step lands."""
    traj = simulate(make_scene("-abs(x)", x=-1.0, vx=6.0, dt=h, duration=0.5))
    assert traj.status is Status.OK and traj.contact[-1, 0] > 1.0   # over the ridge
    assert h / 20 < traj.energy_drift < h


# -- the ball too big for a valley ------------------------------------------------------------------

def no_fit_time(scene, boundary_y):
    """When the reference contact point reaches y = boundary_y (the solver cannot go past it)."""
    alpha, v = initial_state(landscape_for(scene.landscape), scene)

    def event(t, y):
        return y[1] - boundary_y

    event.terminal = True
    from scipy.integrate import solve_ivp

    sol = solve_ivp(reference_rhs(scene), (0.0, 1.0), np.concatenate([alpha, v, np.eye(3).ravel()]),
                    method="DOP853", rtol=1e-12, atol=1e-12, events=event)
    return sol.t_events[0][0]


@pytest.mark.parametrize("h", [0.1, 0.01, 1e-3, 1e-4])
def test_fast_ball_across_a_valley_too_tight_for_it(h):
    """A ball of r = 0.2 thrown across 4 y² (r·κ = 1.6 at the bottom, no fit for |y| < 0.0758) at
    3 m/s. Its contact point speeds up without bound towards the boundary, so a fixed step can
    land beyond the no-fit region with both ends fitting; the kernel then takes the step again
    in sub-steps that close in on the boundary. The stop is where the reference reaches the
    boundary (t ≈ 0.0734 s): within the step for h = 0.1 (the sub-steps' own error), to a hundredth
    of the step for the smaller ones; the last row is the last sub-step before it."""
    scene = make_scene("4*y^2", y=-0.5, vy=3.0, radius=0.2)
    boundary = -math.sqrt((1.6 ** (2 / 3) - 1) / 64)
    t_star = no_fit_time(scene, boundary - 1e-6)
    traj, elapsed = timed(scene, dt=h, t_end=1.0)
    assert_honest(traj, 5.0, elapsed)
    assert traj.status is Status.DOES_NOT_FIT
    failure_time = traj.failure.time
    assert traj.t[-1] <= failure_time < traj.t[-1] + h
    assert abs(failure_time - t_star) < (h if h > 0.01 else h / 100)
    assert abs(traj.contact[-1, 1] - boundary) < 1e-6


def test_thin_groove_is_not_jumped():
    """A groove 1 mm deep and about 1 cm wide (r·κ = 2 at its bottom) crossed at 1 m/s with steps of
    1 cm: does_not_fit near x = 0, not a silent jump."""
    traj = simulate(make_scene("-0.001*exp(-(x/0.01)^2)", x=-0.5, vx=1.0, dt=0.01))
    assert traj.status is Status.DOES_NOT_FIT
    assert 0.45 < traj.t[-1] < 0.55


# -- constant derivatives ---------------------------------------------------------------------------

@pytest.mark.parametrize("formula, height", [
    ("0", 0.0), ("3", 3.0), ("x - x", 0.0), ("sin(x)^2 + cos(x)^2", 1.0), ("log(e) + 0*y", 1.0),
    ("(x + y)^2 - x^2 - 2*x*y - y^2", 0.0),
])
def test_landscapes_that_are_constants(formula, height):
    """Formulas that are, or simplify to, a constant: grids of the right shape, zero derivatives, and
    the ball rolls straight at constant speed at height c + r."""
    X_, Y_ = np.meshgrid(np.linspace(-1, 1, 4), np.linspace(-1, 1, 3), indexing="ij")
    values = landscape_for(formula).evaluate(X_, Y_)
    assert values.shape == (6, 4, 3)
    np.testing.assert_allclose(values[0], height, atol=1e-15)
    np.testing.assert_allclose(values[1:], 0, atol=1e-14)
    assert landscape_for(formula).evaluate(0.5, 0.5).shape == (6,)
    traj = simulate(make_scene(formula, vx=1.0, vy=-2.0, spin=5.0), t_end=1.0)
    assert traj.status is Status.OK
    np.testing.assert_allclose(traj.center[-1], [1.0, -2.0, height + 0.1], atol=1e-12)
    assert traj.energy_drift < 1e-14
