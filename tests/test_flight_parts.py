"""Free flight, the landing search and the impact (rollball/flight.py) against closed forms and an
independent root finder."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize, minimize_scalar

from rollball.flight import FreeState, Flight, Surface, energy, impact, rest_speed
from rollball.kernel.interface import ROW_SLICES
from rollball.landscape import landscape_for

G, R, M = 9.81, 0.1, 1.3


def flight(formula, center, velocity, omega=(0.0, 0.0, 0.0), gravity=G):
    start = FreeState(0.0, np.array(center, float), np.array(velocity, float), np.array(omega, float), np.eye(3))
    return Flight(Surface(landscape_for(formula)), start, radius=R, mass=M, gravity=gravity)


def test_flight_is_the_parabola_and_a_turn_at_constant_rate():
    f = flight("0*x", (0.0, 0.0, 2.0), (1.0, -0.5, 2.0), omega=(3.0, -1.0, 7.0))
    t = 0.37
    s = f.state(t)
    assert np.allclose(s.center, [t, -0.5 * t, 2.0 + 2.0 * t - 0.5 * G * t * t], rtol=0, atol=1e-15)
    assert np.allclose(s.velocity, [1.0, -0.5, 2.0 - G * t], rtol=0, atol=1e-15)
    # R(t) = exp(A(omega) t): a turn by |omega| t about omega, by Rodrigues' formula written out here
    w = np.array([3.0, -1.0, 7.0])
    k = w / np.linalg.norm(w)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    angle = np.linalg.norm(w) * t
    assert np.allclose(s.R, np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K, atol=1e-14)
    rows = f.rows(np.linspace(0.0, 0.6, 7), dissipated=0.25)
    e = rows[:, ROW_SLICES["energy"]][:, 0]
    assert np.ptp(e) <= 1e-14 * abs(e[0])   # exact: no integrator in flight
    assert np.all(rows[:, ROW_SLICES["normal_force"]] == 0.0)
    assert np.allclose(rows[:, ROW_SLICES["contact"]], rows[:, ROW_SLICES["center"]][:, :2])   # foot on a plane
    Rs = rows[:, ROW_SLICES["R"]].reshape(-1, 3, 3)
    assert np.abs(np.einsum("nji,njk->nik", Rs, Rs) - np.eye(3)).max() < 1e-14


def test_the_landing_on_a_plane_is_located_to_round_off():
    f = flight("0.25", (0.3, 0.0, 1.5), (2.0, 1.0, 0.5))
    t, foot = f.landing(10.0)
    # c_z(t) = 0.25 + r: 1.5 + 0.5 t − g t²/2 = 0.35
    exact = (0.5 + math.sqrt(0.25 + 2 * G * 1.15)) / G
    assert abs(t - exact) <= 4e-16 * 3 and foot.distance == pytest.approx(R, abs=1e-15)
    assert (foot.x, foot.y) == pytest.approx((0.3 + 2 * exact, exact), abs=1e-14)
    assert f.landing(0.5 * exact) is None   # still flying at t_end


def test_a_narrow_ridge_in_the_way_is_hit_not_flown_through():
    """Skimming past a ridge 3 cm wide: the first contact, from an independent distance (scipy's
    minimize_scalar on the curve z = f(x), Brent's root finder in time)."""
    formula, height = "0.5*exp(-(x-1)^2/0.001)", lambda x: 0.5 * np.exp(-(x - 1) ** 2 / 0.001)
    f = flight(formula, (0.0, 0.0, 0.55), (3.0, 0.0, 0.0), gravity=0.0)
    t, foot = f.landing(10.0)

    def gap(time):
        cx, cz = 3.0 * time, 0.55
        best = minimize_scalar(lambda x: (x - cx) ** 2 + (height(x) - cz) ** 2, bounds=(0.9, 1.1), method="bounded",
                               options={"xatol": 1e-12})
        return math.sqrt(best.fun) - R

    expected = brentq(gap, 0.2, 1.0 / 3.0, xtol=1e-14)
    assert t == pytest.approx(expected, abs=1e-9) and foot.x < 1.0


def about_contact(velocity, omega, normal):
    """The angular momentum about the contact point of a ball below its centre along -normal."""
    return 0.4 * M * R * R * omega + M * R * np.cross(normal, velocity)


def test_a_sticking_impact_keeps_the_angular_momentum_about_the_contact_point():
    n = np.array([0.0, 0.0, 1.0])
    v, w = np.array([2.0, 0.5, -3.0]), np.array([1.0, -4.0, 2.0])
    hit = impact(v, w, n, mass=M, radius=R, restitution=0.0, friction=math.inf)
    assert hit.sticking and hit.normal_speed == 3.0 and hit.rebound == 0.0
    assert np.allclose(about_contact(hit.velocity, hit.omega, n), about_contact(v, w, n), rtol=0, atol=1e-14)
    u = hit.velocity - R * np.cross(hit.omega, n)   # the contact point is at rest after
    assert np.abs(u).max() < 1e-14
    before, after = energy(v, w, 0.0, M, R, G), energy(hit.velocity, hit.omega, 0.0, M, R, G)
    assert hit.energy_lost == pytest.approx(before - after, rel=1e-14) and hit.energy_lost > 0
    # a ball sliding on without spin keeps 5/7 of its speed along the surface (billiards)
    plain = impact([2.0, 0.0, -1.0], [0.0, 0.0, 0.0], n, mass=M, radius=R, restitution=0.0, friction=math.inf)
    assert plain.velocity == pytest.approx([10.0 / 7.0, 0.0, 0.0], abs=1e-15)


def test_a_sliding_impact_takes_mu_times_the_normal_impulse():
    n = np.array([0.6, 0.0, 0.8])
    t1 = np.array([0.8, 0.0, -0.6])
    v = 4.0 * t1 - 2.0 * n
    hit = impact(v, np.zeros(3), n, mass=M, radius=R, restitution=0.5, friction=0.1)
    j_n = (1 + 0.5) * M * 2.0
    assert not hit.sticking and hit.rebound == pytest.approx(1.0)
    assert hit.impulse == pytest.approx(j_n * n - 0.1 * j_n * t1, abs=1e-14)
    assert np.dot(hit.velocity, n) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(about_contact(hit.velocity, hit.omega, n), about_contact(v, np.zeros(3), n), atol=1e-14)
    # enough friction: it sticks
    assert impact(v, np.zeros(3), n, mass=M, radius=R, restitution=0.5, friction=1.0).sticking
    # a frictionless surface gives no tangential impulse
    assert np.allclose(impact(v, np.zeros(3), n, mass=M, radius=R, restitution=0.5, friction=0.0).impulse, j_n * n)


def test_rebound_apex_heights_scale_by_e_squared():
    e = 0.6
    f = flight("0*x", (0.0, 0.0, 1.1), (0.5, 0.0, 0.0))
    apexes = []
    for _ in range(4):
        t, foot = f.landing(100.0)
        s = f.state(t)
        hit = impact(s.velocity, s.omega, foot.normal, mass=M, radius=R, restitution=e, friction=math.inf)
        assert hit.rebound > rest_speed(R, G)
        apexes.append(hit.rebound ** 2 / (2 * G))
        f = Flight(f.surface, type(s)(t, s.center, hit.velocity, hit.omega, s.R), radius=R, mass=M, gravity=G)
        f_apex = f.state(t + hit.rebound / G).center[2] - R   # the flight's own apex
        assert f_apex == pytest.approx(apexes[-1], rel=1e-12)
    ratios = np.array(apexes[1:]) / np.array(apexes[:-1])
    assert ratios == pytest.approx(e * e, rel=1e-12)
    assert apexes[0] == pytest.approx(e * e * 1.0, rel=1e-12)   # dropped from 1 m above contact


def test_a_slow_rebound_settles_and_counts_the_energy():
    n = np.array([0.0, 0.0, 1.0])
    slow = rest_speed(R, G) / 2
    hit = impact([1.0, 0.0, -slow / 0.5], [0.0, 0.0, 0.0], n, mass=M, radius=R, restitution=0.5, friction=math.inf)
    assert hit.rebound < rest_speed(R, G) and not hit.settled   # (no rest speed given: it never settles)
    rest = impact([1.0, 0.0, -slow / 0.5], [0.0, 0.0, 0.0], n, mass=M, radius=R, restitution=0.5, friction=math.inf,
                  rest=rest_speed(R, G))
    assert rest.settled and rest.velocity[2] == 0.0 and rest.rebound == 0.0
    assert rest.energy_lost == pytest.approx(hit.energy_lost + 0.5 * M * hit.rebound ** 2, rel=1e-14)
    assert rest.impulse[2] == pytest.approx(hit.impulse[2] - M * hit.rebound, rel=1e-14)
    fast = impact([1.0, 0.0, -4 * slow / 0.5], [0.0, 0.0, 0.0], n, mass=M, radius=R, restitution=0.5,
                  friction=math.inf, rest=rest_speed(R, G))
    assert not fast.settled and fast.rebound == pytest.approx(4 * slow, rel=1e-14)   # (twice the rest speed)
    assert rest_speed(0.1, 9.81) == pytest.approx(math.sqrt(2 * 9.81 * 1e-7))


def test_the_tip_of_a_thin_tall_bump_is_hit_where_an_independent_distance_says():
    """A ball rising off a floor towards a bump 8 cm tall and 1 cm wide meets its tip first. The
    first contact from an independent distance (the curve z = f(x) sampled densely, the nearest
    sample refined by scipy's minimize_scalar; the first sign change of the gap on a fine grid in
    time, then brentq). The landing search used to put it 1.2e-4 s late, inside the bump."""
    xb, height, width = 0.25, 0.08, 0.01
    f = flight(f"{height}*exp(-((x-{xb})/{width})^2)", (0.0, 0.0, R + 1e-3), (3.0, 0.0, 1.0))
    t, foot = f.landing(2.0)

    def curve(x):
        return height * np.exp(-((x - xb) / width) ** 2)

    def gap(time):
        cx, cz = 3.0 * time, R + 1e-3 + time - 0.5 * G * time * time
        xs = np.linspace(cx - 0.3, cx + 0.3, 6001)
        d2 = (xs - cx) ** 2 + (curve(xs) - cz) ** 2
        i = int(np.argmin(d2))
        best = minimize_scalar(lambda x: (x - cx) ** 2 + (curve(x) - cz) ** 2, bounds=(xs[i - 1], xs[i + 1]),
                               method="bounded", options={"xatol": 1e-13})
        return math.sqrt(min(best.fun, d2[i])) - R

    grid = np.linspace(1e-3, 0.1, 400)
    first = int(np.flatnonzero(np.array([gap(time) for time in grid]) < 0)[0])
    expected = brentq(gap, grid[first - 1], grid[first], xtol=1e-15)
    assert t == pytest.approx(expected, abs=1e-12)
    assert abs(foot.x - xb) < 0.01   # on the tip


def test_the_closest_surface_point_is_the_cylinders_radial_one():
    """Surface.foot (the grid, the starts and Newton's method, compiled) and Surface.feet (Newton's
    method from given starts) against the closed form on z = sqrt(4 − x²): the closest point of
    a centre above is along its radius, (2 c_x, c_y, 2 c_z)/|(c_x, c_z)|, at distance |(c_x, c_z)| − 2.
    With or without a guess; NaN where no surface point is near (under the cylinder's edge)."""
    surface = Surface(landscape_for("sqrt(4 - x^2)"))
    centers = np.array([[0.3, -0.7, 2.4], [-1.1, 0.2, 2.05], [1.9, 3.0, 0.9], [0.0, 0.0, 2.1]])
    rho = np.hypot(centers[:, 0], centers[:, 2])
    for guess in (None, (0.0, 0.0)):
        for c, r in zip(centers, rho):
            foot = surface.foot(c, guess)
            assert (foot.x, foot.y, foot.distance) == pytest.approx((2 * c[0] / r, c[1], r - 2), abs=1e-14)
            assert foot.normal == pytest.approx([c[0] / r, 0.0, c[2] / r], abs=1e-14)
    alpha, normals, distances = surface.feet(centers, centers[:, :2])
    assert alpha == pytest.approx(np.column_stack([2 * centers[:, 0] / rho, centers[:, 1]]), abs=1e-14)
    assert distances == pytest.approx(rho - 2, abs=1e-14)
    beside = surface.foot(np.array([3.0, 0.0, -1.0]))   # no surface within reach of the point below
    assert math.isnan(beside.x) and math.isnan(beside.distance) and np.isnan(beside.normal).all()


def test_a_look_of_the_landing_search_is_one_compiled_call(monkeypatch):
    """A look at the gap (the point below, the grid, the starts, Newton's method from each and the
    nearest foot) is one call of the compiled kernel where its first foot passes (issue 30: a
    look was three calls and some forty array operations)."""
    from rollball import machine_code

    f = flight("0.3*sin(3*x)*cos(2*y)", (0.1, -0.2, 1.0), (1.0, 0.5, 0.0))
    f.gap(0.05)   # (packed once)
    calls = []
    original = machine_code.Arguments.__call__
    monkeypatch.setattr(machine_code.Arguments, "__call__", lambda self: calls.append(self.name) or original(self))
    h, foot = f.gap(0.1, (0.2, -0.1))
    assert calls == ["nearest_feet"] and h > 0


@pytest.mark.parametrize("spacing", [0.0, 0.05])
@pytest.mark.parametrize("symmetric", [False, True])
def test_the_compiled_first_search_finds_the_feet_the_samples_and_newton_give(spacing, symmetric):
    """Surface._first_feet (kernel.feet.nearest_feet) against the same search written here in numpy:
    the grid of half-width |c_z − f| about each centre (21 × 21; with a spacing, as few samples
    per side as put them that far apart at most, at least 3 and at most 21) and the hints
    sampled, Newton's method (Surface.feet) from the point below, the guess, the three nearest
    samples and the hints, a tip put in where nearer, the smallest |D| kept: the same numbers.
    The kernel samples its grid from the middle outwards and skips samples that cannot be among
    the three nearest; on a surface symmetric in x and y, centres on the diagonal have samples
    exactly as near as their mirror images, and the three nearest are still those of a stable sort."""
    from rollball.flight import BEST_SAMPLES

    formula = "0.3*cos(3*x)*cos(3*y) + 0.05*x*y" if symmetric else "0.3*sin(3*x)*cos(2*y) + 0.05*x*y"
    surface = Surface(landscape_for(formula))
    surface.hints = [np.array([0.4, 0.3, 1e-4]), np.array([-0.2, 0.5, 1e-4])]
    surface.tips = [np.array([0.7, -0.6, 0.2])]
    rng = np.random.default_rng(7)
    centers = np.column_stack([rng.uniform(-1, 1, 12), rng.uniform(-1, 1, 12), rng.uniform(0.3, 0.9, 12)])
    centers[0] = [0.7, -0.6, 0.25]   # nearest to the tip
    if symmetric:   # (the grid's x and y offsets the same numbers: mirror samples tie exactly)
        centers[1:6, 1] = centers[1:6, 0] = [0.0, 0.0, 0.35, -0.5, 0.8]
        centers[1:6, 2] = [0.95, 1.3, 0.9, 0.6, 1.5]
    guess = np.array([0.1, 0.2])
    hints = np.array(surface.hints)
    alpha, normal, distance, below, sampled, spacings, points = surface._first_feet(centers, guess, hints, spacing)
    sides, ties = set(), 0   # (centres whose three nearest samples tie among themselves or with the next)
    for i, c in enumerate(centers):
        f0 = surface.evaluate(c[0], c[1])[0]
        reach = abs(c[2] - f0)
        side = 21 if spacing == 0.0 else min(21, max(3, math.ceil(2.0 * reach / spacing) + 1))
        sides.add(side)
        unit = np.linspace(-1.0, 1.0, side)
        gx = np.concatenate([np.repeat(c[0] + reach * unit, side), hints[:, 0]])
        gy = np.concatenate([np.tile(c[1] + reach * unit, side), hints[:, 1]])
        far = (gx - c[0]) ** 2 + (gy - c[1]) ** 2 + (surface.evaluate(gx, gy)[0] - c[2]) ** 2
        order = np.argsort(far, kind="stable")[:BEST_SAMPLES]
        ties += int(np.sum(far <= far[order[-1]]) > BEST_SAMPLES or len(set(far[order])) < BEST_SAMPLES)
        starts = np.vstack([c[:2], guess, np.column_stack([gx[order], gy[order]]), hints[:, :2]])
        a, n, d = surface.feet(np.repeat(c[None], len(starts), 0), starts)
        tip = surface.tips[0]
        arm = np.linalg.norm(c - tip)
        nearer = ~(np.abs(d) <= arm)
        a[nearer], n[nearer], d[nearer] = tip[:2], (c - tip) / arm, arm
        k = int(np.argmin(np.where(np.isnan(d), np.inf, np.abs(d))))
        assert below[i] == f0 and sampled[i] == np.sqrt(far.min()) and spacings[i] == 2.0 * reach / (side - 1)
        assert np.array_equal(points[i], np.column_stack([gx[order], gy[order]]))
        assert np.array_equal(alpha[i], a[k]) and np.array_equal(normal[i], n[k]) and distance[i] == d[k]
    assert np.array_equal(alpha[0], surface.tips[0][:2])
    assert sides == {21} if spacing == 0.0 else len(sides) > 3   # (the reaches 0.3-1.9: sides 13 to 21)
    if symmetric:   # (the tie order exercised: the random centres of the other surface need not tie)
        assert ties >= 5


@pytest.mark.parametrize("across", [0.11, 0.12])
def test_a_bump_beside_the_path_is_hit_where_an_independent_distance_says(across):
    """A ball flying straight (no gravity) 5 cm over a floor passes beside a bump 30 cm tall whose
    peak is 11-12 cm off its path: nothing under the centre's path comes near (the track sees
    nothing) and Newton's method from the point below finds the floor, so only the looks' grids
    can find the bump's flank (looks 5 cm apart, 7 per side, flew past the first bump; 5 per side,
    past the second). The first contact from an independent distance (the surface sampled densely
    about the bump, the nearest sample refined by scipy's Nelder-Mead; the first sign change of
    the gap on a grid in time, then brentq)."""
    width = 0.03
    f = flight(f"0.3*exp(-((x-1)^2 + (y-{across})^2)/{width}^2)", (0.0, 0.0, 0.15), (3.0, 0.0, 0.0), gravity=0.0)
    t, foot = f.landing(1.0)

    def height(x, y):
        return 0.3 * np.exp(-((x - 1.0) ** 2 + (y - across) ** 2) / width ** 2)

    xs, ys = np.meshgrid(np.linspace(0.8, 1.2, 401), np.linspace(-0.05, 0.3, 351), indexing="ij")

    def gap(time):
        c = np.array([3.0 * time, 0.0, 0.15])
        d2 = (xs - c[0]) ** 2 + (ys - c[1]) ** 2 + (height(xs, ys) - c[2]) ** 2
        i = np.unravel_index(np.argmin(d2), d2.shape)
        best = minimize(lambda p: (p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2 + (height(p[0], p[1]) - c[2]) ** 2,
                        [xs[i], ys[i]], method="Nelder-Mead",
                        options={"xatol": 1e-13, "fatol": 1e-30, "maxiter": 4000})
        return math.sqrt(min(best.fun, d2[i], c[2] ** 2)) - R

    grid = np.linspace(0.25, 0.34, 46)
    first = int(np.flatnonzero(np.array([gap(time) for time in grid]) < 0)[0])
    expected = brentq(gap, grid[first - 1], grid[first], xtol=1e-15)
    assert t == pytest.approx(expected, abs=1e-12)
    assert 0.05 < foot.y < across   # on the bump's flank


def test_the_looks_just_after_a_lift_off_are_taken_eight_at_a_time(monkeypatch):
    """Lifting off a plane at 1 cm/s the gap passes GRAZE × r (1e-7 m) after some 1.6e-5 s: the
    looks doubling from a first look 1e-9 s after it (fourteen of them; FIRST_STEP made so short,
    to take two batches) are taken eight at a time, and the first one clear is the one the looks
    taken one by one find (a foot search each before)."""
    from rollball import flight as flight_module
    from rollball.flight import GRAZE

    monkeypatch.setattr(flight_module, "FIRST_STEP", 1e-9)
    f = flight("0.25", (0.3, 0.0, 0.35), (0.0, 0.0, 1e-2))
    t, step = 0.0, 1e-9
    for _ in range(40):   # one by one, from the plane's exact gap
        t, step = t + step, 2.0 * step
        if 1e-2 * t - 0.5 * G * t * t > GRAZE * R:
            break
    h0, foot0 = f.gap(0.0)
    calls = []
    original = Surface.feet_of
    monkeypatch.setattr(Surface, "feet_of", lambda self, c, guess=None, spacing=0.0: calls.append(len(c))
                        or original(self, c, guess, spacing))
    s, h, foot = f._clear_off(0.0, h0, foot0, 1.0)
    assert s == t and h == pytest.approx(1e-2 * t - 0.5 * G * t * t, rel=1e-6) and calls == [8, 8]
