"""Flights that are right or stop honestly, against independent answers: the distance of the
centre to the curve z = f(x) sampled densely (and refined by scipy's minimize_scalar), the first
sign change of the gap on a fine grid in time, then scipy's brentq; or closed forms.

A ball that never comes back (``-10*x^2`` from its top), a spike 0.5 mm wide in the flight path,
smooth drops whose steep flank kept Newton's method from a foot."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from rollball import Scene, Status, simulate, sweep
from rollball.examples import EXAMPLES_DIR
from rollball.flight import Flight, FreeState, Surface
from rollball.landscape import landscape_for
from rollball.trajectory import FLYING, Reason

G, R = 9.81, 0.1
LIFTOFF = json.loads((EXAMPLES_DIR / "liftoff.json").read_text())


def scene(landscape, duration=1.0, method="rk4", friction=None, **start):
    data = json.loads(json.dumps(LIFTOFF))
    data["landscape"], data["duration"] = landscape, duration
    data["start"].update(start)
    data["contact"]["friction"] = friction
    data["integrator"]["method"] = method
    return Scene.from_dict(data)


def curve_distance(curve, cx, cz, samples=20001):
    """The distance from (cx, cz) to the curve z = curve(x): the nearest point is within
    |cz − curve(cx)| of cx; the nearest of dense samples there, refined by minimize_scalar."""
    reach = abs(cz - curve(cx)) + 1e-9
    xs = np.linspace(cx - reach, cx + reach, samples)
    d2 = (xs - cx) ** 2 + (curve(xs) - cz) ** 2
    i = int(np.argmin(d2))
    lo, hi = xs[max(i - 1, 0)], xs[min(i + 1, samples - 1)]
    best = minimize_scalar(lambda x: (x - cx) ** 2 + (curve(x) - cz) ** 2, bounds=(lo, hi), method="bounded",
                           options={"xatol": 1e-14})
    return math.sqrt(min(best.fun, d2[i]))


def first_contact(curve, center, velocity, t0, t1, count=2000):
    """The first root of the gap along the parabola from (center, velocity) at time 0 in (t0, t1]."""
    def gap(t):
        cx, cz = center[0] + velocity[0] * t, center[2] + velocity[2] * t - 0.5 * G * t * t
        return curve_distance(curve, cx, cz) - R

    grid = np.linspace(t0, t1, count)
    values = np.array([gap(t) for t in grid])
    below = np.flatnonzero(values < 0)
    if not len(below):
        return None
    k = int(below[0])
    return brentq(gap, grid[k - 1], grid[k], xtol=1e-15, rtol=1e-15)


def flying_start(traj):
    """The first recorded flying row's time, centre and velocity: the parabola is exact from it."""
    i = int(np.flatnonzero(traj.modes == FLYING)[0])
    return traj.t[i], traj.center[i], traj.velocity[i]


# -- a ball that never comes back -----------------------------------------------------------------

def test_a_ball_off_the_top_of_a_steeper_parabola_never_lands():
    """From the top of z = −10x² at 5 m/s the centre's parabola z = r − 0.196 x² stays ever farther
    from the surface (the dense distance says it grows from r), so there is no landing: the search
    used to take a far point where c − φ is along N, with a negative signed distance, for the foot
    and land the ball 6 m away from itself at t = 1.3973 s."""
    surface = Surface(landscape_for("-10*x^2"))
    start = FreeState(0.0, np.array([0.0, 0.0, R]), np.array([5.0, 0.0, 0.0]), np.zeros(3), np.eye(3))
    flight = Flight(surface, start, radius=R, mass=1.0, gravity=G)
    assert flight.landing(2.0) is None

    def curve(x):
        return -10.0 * np.asarray(x) ** 2

    for t in (0.3, 1.0, 1.4228115869430378, 2.0):
        c = flight.centers(np.array([t]))[0][0]
        expected = curve_distance(curve, c[0], c[2], samples=400001)
        assert expected > R
        # the foot from the last foot of the old search's look (where it found the far point)
        foot = surface.foot(c, np.array([0.56054106, 0.0]))
        assert foot.distance == pytest.approx(expected, rel=1e-9)
        assert foot.distance == pytest.approx(math.dist(c, (foot.x, foot.y, curve(foot.x))), rel=1e-12)


@pytest.mark.parametrize("friction", [0.5, None])
def test_the_run_off_the_top_flies_to_its_end(friction):
    traj = simulate(scene("-10*x^2", duration=2.0, friction=friction, x=0.0, vx=5.0))
    assert traj.status is Status.OK
    assert [change.kind for change in traj.transitions] == ["liftoff"]
    t = traj.t[-1]
    assert t == 2.0 and traj.center[-1] == pytest.approx([5.0 * t, 0.0, R - 0.5 * G * t * t], abs=1e-12)
    assert np.ptp(traj.energy) <= 1e-12 * abs(traj.energy[0])   # (it went from 18.48 J to −5.12 J)


def test_a_sweep_of_the_run_off_the_top_flies_too():
    table = sweep(scene("-10*x^2", duration=2.0, friction=0.5, x=0.0, vx=5.0), {"start.vx": [4.0, 5.0]}, workers=1)
    assert list(table["status"]) == ["ok", "ok"]
    assert np.all(np.asarray(table["t_reached"]) == 2.0)
    assert np.all(np.asarray(table["energy_drift"]) < 1e-12)


# -- a spike in the flight path --------------------------------------------------------------------

SPIKE = "0.5*exp(-x^2) + 0.4*exp(-((x-1.1)/{w})^2)"


def spike_curve(width):
    return lambda x: 0.5 * np.exp(-np.asarray(x) ** 2) + 0.4 * np.exp(-((np.asarray(x) - 1.1) / width) ** 2)


def test_a_spike_half_a_millimetre_wide_is_hit_where_an_independent_distance_says():
    """The centre's parabola passes through the spike (0.4 m tall, 0.5 mm wide): the ball meets its
    flank first. The search used to see no spike (its foot grid is coarser) and fly through."""
    width = 0.0005
    center, velocity = np.array([0.6, 0.0, 0.6]), np.array([3.0, 0.0, 0.0])
    start = FreeState(0.0, center, velocity, np.zeros(3), np.eye(3))
    flight = Flight(Surface(landscape_for(SPIKE.format(w=width))), start, radius=R, mass=1.0, gravity=G)
    t, foot = flight.landing(1.0)
    expected = first_contact(spike_curve(width), center, velocity, 1e-3, 0.2)
    assert t == pytest.approx(expected, abs=1e-9)
    assert abs(foot.x - 1.1) < 2 * width


@pytest.mark.parametrize("method, width", [("rk4", 0.0005), ("euler", 0.002)])
def test_the_liftoff_flight_hits_a_spike_in_its_path(method, width):
    traj = simulate(scene(SPIKE.format(w=width), method=method))
    assert traj.status is Status.OK
    landing = next(change for change in traj.transitions if change.kind == "landing")
    t0, center, velocity = flying_start(traj)
    expected = first_contact(spike_curve(width), center, velocity, 1e-4, 0.5)
    assert landing.time == pytest.approx(t0 + expected, abs=1e-9)
    assert abs(landing.x - 1.1) < 2 * width   # on the spike, not behind it


def test_a_spike_too_narrow_to_find_stops_the_run_with_its_reason(monkeypatch):
    """Where the foot search cannot find the spike's nearest point even from the samples that showed
    it, the run stops, naming it (here the search's samples are switched off by hand)."""
    from rollball import flight as module
    monkeypatch.setattr(module, "MAX_HINTS", 0)
    traj = simulate(scene(SPIKE.format(w=0.0005)))
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.NARROW_FEATURE
    assert "narrower than the landing search can follow" in traj.message
    assert abs(traj.failure.x - 1.1) < 1e-3


# -- smooth drops ----------------------------------------------------------------------------------

@pytest.mark.parametrize("height, rate", [(2.0, 5.0), (5.0, 50.0)])
def test_a_ball_off_a_smooth_drop_flies_and_lands_where_brentq_says(height, rate):
    """z = −h (1 + tanh(k x)) from x = −1 at 3 m/s (μ = 0.5): it slips, leaves the brink and lands on
    the floor below. It used to stop "the landscape cannot be evaluated there" at the lift-off:
    Newton's method at round-off on the steep flank never passed the closest-point test."""
    traj = simulate(scene(f"-{height}*(1+tanh({rate}*x))", duration=2.0, friction=0.5, x=-1.0, vx=3.0))
    assert traj.status is Status.OK, traj.message
    kinds = [change.kind for change in traj.transitions]
    assert "liftoff" in kinds and "landing" in kinds
    landing = next(change for change in traj.transitions if change.kind == "landing")
    t0, center, velocity = flying_start(traj)

    def curve(x):
        return -height * (1 + np.tanh(rate * np.asarray(x)))

    expected = first_contact(curve, center, velocity, 1e-4, landing.time - t0 + 0.05, count=800)
    assert landing.time == pytest.approx(t0 + expected, abs=1e-9)


@pytest.mark.parametrize("rtol", [1e-8, 1e-10])
def test_an_adaptive_pair_does_not_step_over_a_drop_on_its_flat_approach(rtol):
    """−1.52 (1 + tanh(50 x)) + 0.05 y from (−1.17, −0.17) at (4.27, 0.3) m/s, e = 1: on the nearly
    flat approach dopri5's steps grew to 0.3 s (1.2 m of travel) and one passed over the drop
    without a stage on it; the ball carried on along the floor 3 m below without flying (7 steps
    for 2 s, status ok, the energy 2.2 times its scale off, "the step is too large" the warning).
    A pair's step whose height change its end slopes do not explain, travelling more than r, is
    taken again shorter (``loops.crossed_unseen``): it flies off the brink where rk4 and dop853 say
    and lands where they do."""
    from rollball.scene import Contact, Start

    drop = Scene("-1.52*(1 + tanh(50*x)) + 0.05*y", start=Start(-1.17, -0.17, 4.27, 0.3, 2.3),
                 contact=Contact(None, 1.0), duration=2.0)
    traj = simulate(drop, method="dopri5", rtol=rtol, atol=rtol)
    truth = simulate(drop, method="dop853", rtol=1e-12, atol=1e-12)
    assert traj.status is Status.OK and traj.warnings() == [], traj.warnings()
    kinds = [change.kind for change in traj.transitions]
    assert kinds == [change.kind for change in truth.transitions] and kinds[:2] == ["liftoff", "landing"], kinds
    for change, right in zip(traj.transitions, truth.transitions):
        assert abs(change.time - right.time) < 1e3 * rtol, (change, right)


# -- the roof --------------------------------------------------------------------------------------

def test_the_flight_off_a_roofs_ridge_starts_at_the_ridge_and_lands_on_the_far_plane():
    """min(0.25 x, −0.15 x): the ball rolls up the plane 0.25 x, leaves at the ridge (a kink) and
    flies a parabola onto the plane −0.15 x, where the centre's signed distance to it,
    (c_z + 0.15 c_x)/√1.0225, comes down to r (a quadratic in time). The run's last state before the
    ridge is ~2·10⁻⁶ s before it: the flight used to start there and dip below the plane it was
    still on, a landing 1.7·10⁻⁶ s before the lift-off it followed, and a second lift-off."""
    traj = simulate(scene("min(0.25*x, -0.15*x)", x=-0.8, y=0.1, vx=2.5))
    assert traj.status is Status.OK
    assert [change.kind for change in traj.transitions] == ["liftoff", "landing"]
    liftoff, landing = traj.transitions
    assert abs(liftoff.x) < 1e-12 and landing.time - liftoff.time > 0.1
    assert np.all(np.diff(traj.t) > 0)
    t0, c, v = flying_start(traj)
    a, b = -0.5 * G, v[2] + 0.15 * v[0]
    k = c[2] + 0.15 * c[0] - R * math.sqrt(1.0225)
    tau = (-b - math.sqrt(b * b - 4 * a * k)) / (2 * a)
    assert landing.time == pytest.approx(t0 + tau, abs=1e-12)
    assert landing.x == pytest.approx(c[0] + v[0] * tau - 0.15 * R / math.sqrt(1.0225), abs=1e-12)
    # the flight starts at the ridge with the speed rolling up to it gives: |ċ|² = |ċ₀|² − (10/7) g Δz
    i = int(np.flatnonzero(traj.modes == FLYING)[0])
    speed2 = float(np.sum(traj.velocity[i] ** 2)) + 2 * G * (traj.center[i, 2] - (R / math.sqrt(1.0625)))
    assert speed2 == pytest.approx(2.5 ** 2 * 1.0625 - 10 / 7 * G * 0.2, rel=1e-9)


def test_a_ball_flying_off_the_landscapes_domain_is_told_so():
    """Off the top of the half cylinder z = √(1 − x²) at 4 m/s the ball flies beyond |x| = 1, where
    there is no surface: the run stops saying so, never lands."""
    traj = simulate(scene("sqrt(1-x^2)", duration=2.0, x=0.0, vx=4.0))
    assert traj.status is Status.NONFINITE and traj.failure.reason is Reason.OFF_DOMAIN
    assert "leaves the landscape's domain" in traj.message
    assert [change.kind for change in traj.transitions] == ["liftoff"]
    assert traj.center[-1, 0] > 1.0 + R


def test_compares_reference_for_the_run_off_the_top_flies_and_agrees_with_itself():
    """``rollball compare`` measures every run against a reference (dop853, two tolerances): the
    false landing made the reference disagree with itself by 2 m (and "fastest" unresolvable)."""
    from rollball.comparison import reference_run
    traj, own_error = reference_run(scene("-10*x^2", duration=2.0, friction=0.5, x=0.0, vx=5.0))
    assert traj.status is Status.OK and [change.kind for change in traj.transitions] == ["liftoff"]
    assert own_error <= 1e-12
    assert traj.center[-1] == pytest.approx([10.0, 0.0, R - 0.5 * G * 4.0], abs=1e-12)


def test_a_ball_falling_past_a_ridges_kink_lands_where_the_closed_form_distance_says():
    """Over z = −|x| the nearest surface point of a centre above the ridge is the kink itself, where
    Newton's method has no root: the beam search of the samples converges to it. The distance to the
    two half-planes and the kink is closed form; brentq on it. (It used to stop: no surface below.)"""
    start = FreeState(0.0, np.array([-0.5, 0.0, 0.6]), np.array([1.2, 0.0, 0.0]), np.zeros(3), np.eye(3))
    flight = Flight(Surface(landscape_for("-abs(x)")), start, radius=R, mass=1.0, gravity=G)
    t, foot = flight.landing(2.0)

    def distance(cx, cz):
        left = abs(cz - cx) / math.sqrt(2) if cx + cz <= 0 else math.hypot(cx, cz)    # z = x, x ≤ 0
        right = abs(cz + cx) / math.sqrt(2) if cx - cz >= 0 else math.hypot(cx, cz)   # z = −x, x ≥ 0
        return min(left, right)

    def gap(time):
        return distance(-0.5 + 1.2 * time, 0.6 - 0.5 * G * time * time) - R

    grid = np.linspace(0.0, 1.0, 2001)
    k = int(np.flatnonzero(np.array([gap(time) for time in grid]) < 0)[0])
    assert t == pytest.approx(brentq(gap, grid[k - 1], grid[k], xtol=1e-15), abs=1e-12)
    # the centre passed over the kink, nearest to it, before it came down on the plane z = x
    c = flight.centers(np.array([0.2]))[0][0]   # (its projections on both lines are off their half-planes)
    assert flight.surface.foot(c).distance == pytest.approx(math.hypot(c[0], c[2]), rel=1e-12)


def test_a_landing_not_r_from_its_foot_stops_the_run(monkeypatch):
    """Every landing is checked when it is made: a search that returned the old false landing off
    the top of -10*x^2 (t = 1.3973 s, foot x = 0.98891 with the centre 6 m away) stops the run."""
    from rollball import flight as module
    surface = Surface(landscape_for("-10*x^2"))
    false = surface.foot(np.array([6.98629368, 0.0, -9.47618835]))

    def search(self, t_end):
        return 1.3972587365513256, false

    monkeypatch.setattr(module.Flight, "_search", search)
    monkeypatch.setattr(module.Flight, "compiled", False)   # (the kernel's search leaves such a landing to this one)
    traj = simulate(scene("-10*x^2", duration=2.0, friction=0.5, x=0.0, vx=5.0))
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason is Reason.FALSE_LANDING
    assert traj.failure.value == pytest.approx(6.005, abs=1e-3) and "not where the ball touches" in traj.message
    assert [change.kind for change in traj.transitions] == ["liftoff"]
