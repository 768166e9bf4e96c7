"""A flight through air (m c̈ = m g − k|ċ|ċ, ``rollball.drag_flight``) against exact answers and an
independent integration written differently: free fall from rest in closed form (v_t tanh, ln cosh);
an oblique throw against scipy's Radau on the speed and path-angle equations (V̇ = −g sin γ − (k/m)V²,
γ̇ = −g cos γ / V) with its own event for the landing on a plane; E + D_air constant; the landing
search's bounds and its honesty guards with air; and the liftoff example flown through air."""

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from test_flight_honest import SPIKE, curve_distance, spike_curve

from rollball import Scene, Status, simulate
from rollball.drag_flight import DragFlight, new_flight
from rollball.examples import EXAMPLES_DIR
from rollball.flight import Flight, FreeState, Surface
from rollball.landscape import landscape_for
from rollball.trajectory import FLYING, Reason

G, R, M = 9.81, 0.1, 1.0
AIR = {"density": 1.2, "drag_coefficient": 0.47}
K = 0.5 * AIR["density"] * AIR["drag_coefficient"] * math.pi * R * R   # kg/m
V_T = math.sqrt(M * G / K)   # the terminal speed, 33.3 m/s


def flight(landscape, center, velocity, drag=K, omega=(0.0, 0.0, 0.0)):
    start = FreeState(0.0, np.array(center, float), np.array(velocity, float), np.array(omega, float), np.eye(3))
    return DragFlight(Surface(landscape_for(landscape)), start, radius=R, mass=M, gravity=G, drag=drag)


def independent(center, velocity, t_end, drag=K, floor=None):
    """The throw from ``center`` with ``velocity`` (not vertical) integrated by Radau as speed V, path
    angle γ above the horizontal, distance s along the horizontal direction and height z, and the
    air's energy; with ``floor``, stopped where z reaches it. Returns the solution and the direction."""
    rate = drag / M
    horizontal = math.hypot(velocity[0], velocity[1])
    direction = np.array([velocity[0], velocity[1]]) / horizontal

    def motion(t, y):
        v, gamma = y[0], y[1]
        return [-G * math.sin(gamma) - rate * v * v, -G * math.cos(gamma) / v, v * math.cos(gamma),
                v * math.sin(gamma), drag * v ** 3]

    events = None
    if floor is not None:
        def events(t, y):
            return y[3] - floor
        events.terminal, events.direction = True, -1
    y0 = [float(np.linalg.norm(velocity)), math.atan2(velocity[2], horizontal), 0.0, center[2], 0.0]
    solution = solve_ivp(motion, (0.0, t_end), y0, method="Radau", rtol=1e-13, atol=1e-14, dense_output=True,
                         events=events)
    assert solution.success
    return solution, direction


def as_centers(y, center, direction):
    """The centres (n, 3) and velocities (n, 3) of the independent solution's states y (5, n)."""
    v, gamma, s, z = y[0], y[1], y[2], y[3]
    centers = np.column_stack([center[0] + s * direction[0], center[1] + s * direction[1], z])
    velocities = np.column_stack([v * np.cos(gamma) * direction[0], v * np.cos(gamma) * direction[1],
                                  v * np.sin(gamma)])
    return centers, velocities


# -- the motion ------------------------------------------------------------------------------------

def test_free_fall_from_rest_follows_the_closed_form():
    """v(t) = v_t tanh(g t / v_t), z(t) = z₀ − (v_t²/g) ln cosh(g t / v_t), to 10⁻¹⁰ relative, over
    5 s (to 0.96 v_t)."""
    fall = flight("0", (0.3, -0.2, 200.0), (0.0, 0.0, 0.0))
    times = np.linspace(0.0, 5.0, 251)
    centers, velocities = fall.centers(times)
    x = G * times / V_T
    speed = V_T * np.tanh(x)
    drop = (V_T * V_T / G) * (np.log1p(np.exp(-2.0 * x)) + x - math.log(2.0))   # ln cosh, without overflow
    assert np.all(np.abs(-velocities[:, 2] - speed) <= 1e-10 * speed)
    assert np.all(np.abs((200.0 - centers[:, 2]) - drop) <= 1e-10 * np.maximum(drop, 1e-300))
    assert np.all(centers[:, :2] == [0.3, -0.2]) and np.all(velocities[:, :2] == 0.0)
    state = fall.state(2.0)
    assert state.velocity[2] == pytest.approx(-V_T * math.tanh(G * 2.0 / V_T), rel=1e-10)


def test_an_oblique_throw_matches_an_independent_integration():
    """Thrown at 20 m/s, 35° up towards (3, 4), spinning: centre and velocity within 10⁻¹⁰ of the
    scale of Radau's speed-and-angle solution over 3 s; ω and R as in vacuum."""
    speed, angle = 20.0, math.radians(35.0)
    velocity = speed * np.array([0.6 * math.cos(angle), 0.8 * math.cos(angle), math.sin(angle)])
    center = np.array([1.0, 2.0, 50.0])
    omega = np.array([3.0, -1.0, 2.0])
    throw = flight("0", center, velocity, omega=omega)
    times = np.linspace(0.0, 3.0, 61)
    solution, direction = independent(center, velocity, 3.0)
    expected_c, expected_v = as_centers(solution.sol(times), center, direction)
    centers, velocities = throw.centers(times)
    assert np.max(np.abs(centers - expected_c)) <= 1e-10 * 50.0
    assert np.max(np.abs(velocities - expected_v)) <= 1e-10 * speed
    assert throw.air_dissipated(times) == pytest.approx(solution.sol(times)[4], rel=1e-10, abs=1e-10)
    vacuum = Flight(throw.surface, throw.start, radius=R, mass=M, gravity=G)
    assert np.array_equal(throw.state(2.0).R, vacuum.state(2.0).R)
    assert np.array_equal(throw.state(2.0).omega, omega)


def test_energy_and_the_airs_share_add_up_to_a_constant():
    """½ m|ċ|² + m g c_z + D_air stays what it was to 10⁻¹⁰ relative, fast (above v_t: thrown down at
    60 m/s) and slow; and each row's energy + dissipated does too."""
    for velocity in ((12.0, -3.0, 8.0), (10.0, 0.0, -60.0)):
        throw = flight("0", (0.0, 0.0, 400.0), velocity)
        times = np.linspace(0.0, 4.0, 401)
        centers, velocities = throw.centers(times)
        total = 0.5 * M * np.sum(velocities ** 2, axis=1) + M * G * centers[:, 2] + throw.air_dissipated(times)
        assert np.ptp(total) <= 1e-10 * total[0]
        rows = throw.rows(times, 1.5)
        from rollball.trajectory import DISSIPATED, ENERGY
        kept = rows[:, ENERGY] + rows[:, DISSIPATED]
        assert np.ptp(kept) <= 1e-10 * kept[0] and rows[0, DISSIPATED] == 1.5


def test_its_own_error_is_far_below_its_tolerance_against_a_finer_integration(monkeypatch):
    """The dense output at DOP853's RTOL against the same flight integrated at the finest tolerance
    scipy takes (2.2·10⁻¹⁴): within 10⁻¹¹ of the scale."""
    from rollball import drag_flight

    args = ("0", (0.0, 0.0, 100.0), (15.0, 5.0, 10.0))
    times = np.linspace(0.0, 3.0, 301)
    centers = flight(*args).centers(times)[0]
    monkeypatch.setattr(drag_flight, "RTOL", 100 * np.finfo(float).eps)
    finer = flight(*args).centers(times)[0]
    assert np.max(np.abs(centers - finer)) <= 1e-11 * 100.0


# -- the bounds the landing search certifies its steps with -------------------------------------------

@pytest.mark.parametrize("velocity", [(3.0, 0.0, 2.0), (0.0, 0.0, 0.0), (10.0, 0.0, -80.0), (40.0, 10.0, 30.0)])
def test_path_time_and_sag_bound_the_true_path(velocity):
    """From several states (at rest, slower and faster than v_t): the path over ``path_time``(L) is
    no longer than L (its length integrated from the speed), and the path departs from its chord
    by at most ``sag``."""
    throw = flight("0", (0.0, 0.0, 500.0), velocity)
    for t in (0.0, 0.7):
        for length in (1e-4, 0.05, 1.0, 30.0):
            delta = throw.path_time(t, length)
            assert 0.0 < delta < math.inf

            def speed(s):
                return float(np.linalg.norm(throw.centers(np.array([s]))[1][0]))
            travelled = quad(speed, t, t + delta, epsabs=1e-13, epsrel=1e-12, limit=200)[0]
            assert travelled <= length * (1.0 + 1e-12)
            assert travelled >= 0.3 * length   # (a bound that is not uselessly short)
        for s in (t + 0.01, t + 0.5, t + 2.0):
            times = np.linspace(t, s, 401)
            centers = throw.centers(times)[0]
            share = ((times - t) / (s - t))[:, None]
            chord = centers[0] + share * (centers[-1] - centers[0])
            assert np.max(np.linalg.norm(centers - chord, axis=1)) <= throw.sag(t, s)


# -- landings ----------------------------------------------------------------------------------------

def test_a_landing_on_a_plane_is_where_the_independent_integration_lands():
    """Thrown from 1 m at 12 m/s, 40° up over z = 0: it lands where Radau's event z = r says (time
    within 10⁻⁹ s, point within 10⁻⁹ m), shorter and sooner than in vacuum."""
    speed, angle = 12.0, math.radians(40.0)
    velocity = np.array([speed * math.cos(angle), 0.0, speed * math.sin(angle)])
    center = np.array([0.0, 0.0, 1.0])
    throw = flight("0", center, velocity)
    t, foot = throw.landing(10.0)
    solution, direction = independent(center, velocity, 10.0, floor=R)
    (t_expected,), (y_expected,) = solution.t_events[0], solution.y_events[0]
    assert t == pytest.approx(t_expected, abs=1e-9)
    assert foot.x == pytest.approx(y_expected[2], abs=1e-9) and abs(foot.y) <= 1e-12
    assert throw.centers(np.array([t]))[0][0, 2] == pytest.approx(R, abs=1e-12)
    vacuum = Flight(throw.surface, throw.start, radius=R, mass=M, gravity=G).landing(10.0)
    assert t < vacuum[0] - 0.01 and foot.x < vacuum[1].x - 0.1


def test_a_spike_in_the_path_through_air_is_hit_where_an_independent_distance_says():
    """The centre's path passes through a spike 0.4 m tall and 0.5 mm wide: the ball meets its flank
    where the first root of the gap along the independent path says (to 10⁻⁹ s)."""
    width = 0.0005
    center, velocity = np.array([0.6, 0.0, 0.6]), np.array([3.0, 0.0, 0.0])
    throw = flight(SPIKE.format(w=width), center, velocity, drag=20 * K)
    t, foot = throw.landing(1.0)
    solution, direction = independent(center, velocity, 0.5, drag=20 * K)
    curve = spike_curve(width)

    def gap(s):
        c = as_centers(solution.sol(np.array([s])), center, direction)[0][0]
        return curve_distance(curve, c[0], c[2]) - R

    from scipy.optimize import brentq
    grid = np.linspace(1e-3, 0.3, 1500)
    k = int(np.flatnonzero(np.array([gap(s) for s in grid]) < 0)[0])
    assert t == pytest.approx(brentq(gap, grid[k - 1], grid[k], xtol=1e-15), abs=1e-9)
    assert abs(foot.x - 1.1) < 2 * width


def test_a_surface_falling_away_faster_than_the_ball_means_no_landing():
    """Off the top of z = −10x² at 5 m/s through thick air: no landing in 2 s, the centre ever
    farther than r from the surface (a densely sampled distance)."""
    throw = flight("-10*x^2", (0.0, 0.0, R), (5.0, 0.0, 0.0), drag=5 * K)
    assert throw.landing(2.0) is None
    for t in (0.3, 1.0, 2.0):
        c = throw.centers(np.array([t]))[0][0]
        assert curve_distance(lambda x: -10.0 * np.asarray(x) ** 2, c[0], c[2], samples=400001) > R


def liftoff(air=None, duration=1.0, landscape=None):
    data = json.loads((EXAMPLES_DIR / "liftoff.json").read_text())
    data["version"], data["duration"] = 4, duration
    if air is not None:
        data["air"] = air
    if landscape is not None:
        data["landscape"] = landscape
    return Scene.from_dict(data)


def test_a_spike_too_narrow_to_find_stops_a_flight_through_air_with_its_reason(monkeypatch):
    from rollball import flight as module
    monkeypatch.setattr(module, "MAX_HINTS", 0)
    traj = simulate(liftoff(AIR, landscape=SPIKE.format(w=0.0005)))
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.NARROW_FEATURE
    assert abs(traj.failure.x - 1.1) < 1e-3


# -- a run ------------------------------------------------------------------------------------------

def test_the_liftoff_example_through_air_flies_shorter_and_lower_and_keeps_e_plus_d():
    """The liftoff example with air (ρ 1.2, C_d 0.47) and in vacuum: the flight through air lands
    sooner, nearer and peaks lower; over the flight E + D is constant to 10⁻¹⁰ relative and D grew by
    the air's share; across the landing E + D goes on (the impact's loss and the air's are in D)."""
    vacuum, air = simulate(liftoff()), simulate(liftoff(AIR))
    assert vacuum.status is Status.OK and air.status is Status.OK
    assert "a flight is exact" in vacuum.message and "a flight through air is integrated apart" in air.message
    landings = [next(c for c in traj.transitions if c.kind == "landing") for traj in (vacuum, air)]
    assert landings[1].time < landings[0].time and landings[1].x < landings[0].x - 0.01
    flying = [traj.modes == FLYING for traj in (vacuum, air)]
    assert air.center[flying[1], 2].max() < vacuum.center[flying[0], 2].max()
    kept = air.energy + air.dissipated
    flown = np.flatnonzero(flying[1])
    assert np.ptp(kept[flown]) <= 1e-10 * abs(kept[0])
    assert air.dissipated[flown[-1]] - air.dissipated[flown[0]] > 0.01
    after = flown[-1] + 1   # the first row after the landing, in contact
    assert kept[after] == pytest.approx(kept[flown[-1]], rel=1e-9)


def test_new_flight_is_the_closed_form_in_vacuum_and_refuses_a_bad_drag():
    start = FreeState(0.0, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.zeros(3), np.eye(3))
    surface = Surface(landscape_for("0"))
    assert type(new_flight(surface, start, radius=R, mass=M, gravity=G)) is Flight
    assert type(new_flight(surface, start, radius=R, mass=M, gravity=G, drag=K)) is DragFlight
    for bad in (-1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="drag"):
            DragFlight(surface, start, radius=R, mass=M, gravity=G, drag=bad)



def test_air_too_thick_to_integrate_stops_the_run_saying_so():
    """Drag so strong that no step can follow it (ρ = 10³⁰: k|ċ|/m ≈ 10²⁸/s, the ball would stop within
    10⁻²⁸ s): the rolling run stops in its first step, status nonfinite, and the failure and message
    name the drag, not the landscape."""
    traj = simulate(liftoff({"density": 1e30, "drag_coefficient": 0.47}))
    assert traj.status is Status.NONFINITE and traj.failure.reason is Reason.STIFF_DRAG
    assert traj.failure.value > 1e20 and traj.failure.time == 0.0
    assert "the air's drag slows the ball faster than the steps can follow" in traj.message
    assert "landscape" not in traj.message and traj.transitions == ()


@pytest.mark.parametrize("density, method", [(1e30, "euler"), (1e30, "dopri5"), (1e30, "gauss4"), (1e6, "rk4")])
def test_air_too_thick_for_the_method_names_the_drag(density, method):
    """However the unstable steps show (the state or the rotation overflowing, no stage iteration
    converging, no adaptive step small enough), the stop is the drag's, at the start where it was."""
    traj = simulate(liftoff({"density": density, "drag_coefficient": 0.47}), method=method)
    assert traj.status is Status.NONFINITE and traj.failure.reason is Reason.STIFF_DRAG
    assert (traj.failure.time, traj.failure.x, traj.failure.y) == (0.0, -2.5, 0.0)


def test_a_landscape_that_cannot_be_evaluated_stops_a_run_through_air_saying_so():
    """Ordinary air (k|ċ|/m · dt ≈ 10⁻⁴) leaves a non-finite stop where the landscape is undefined its
    own reason: the ball, glued on, rolls up to the rim of the bowl −sqrt(1 − x²) and past it."""
    data = liftoff(AIR).to_dict()
    data.update(landscape="-sqrt(1 - x^2)", duration=3.0)
    data["start"]["x"], data["contact"]["after_liftoff"] = 0.0, "glued"
    traj = simulate(Scene.from_dict(data))
    assert traj.status is Status.NONFINITE and traj.failure.reason is Reason.UNDEFINED
    assert "the landscape cannot be evaluated there" in traj.message


def test_a_flight_too_stiff_to_integrate_in_its_steps_stops_saying_so(monkeypatch):
    """In thick air (k = 10⁶ kg/m: v_t = 3 mm/s) the motion is stiff and DOP853's steps are ≲ 3/√(g k/m):
    a fall from 2 m takes about √(g k/m)/3 ≈ 1000 steps a second; more than a flight may take (here
    300) stops the landing search with the reason."""
    from rollball import drag_flight
    monkeypatch.setattr(drag_flight, "MAX_STEPS", 300)
    fall = flight("0", (0.0, 0.0, 2.0), (5.0, 0.0, 3.0), drag=1e6)
    with pytest.raises(FloatingPointError, match="takes more than 300 steps"):
        fall.landing(5.0)


def test_a_flight_whose_drag_overflows_fails_as_a_stiff_flight_not_an_exception():
    """A speed whose cube overflows (here 10²⁰⁰ m/s) makes the energy the drag takes infinite: the
    flight's motion fails with the drag's FloatingPointError (which the run turns into its stop),
    never an OverflowError out of the motion's formula."""
    fall = flight("0", (0.0, 0.0, 2.0), (1e200, 0.0, 0.0), drag=1.0)
    with pytest.raises(FloatingPointError, match="drag"):
        fall.centers(np.array([1e-3]))
