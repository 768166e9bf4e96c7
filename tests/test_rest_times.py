"""Where and when a rolling ball stops, against the exact answers of docs/design.md §13: on a plane
with rolling resistance, up an incline (it stays iff tan θ ≤ c_rr, else rolls back down), a shot
that skids first, and a spin that outlasts the rolling; each at two step sizes per fixed-step
method (the pair: two tolerances), and the energy each cause took."""

import dataclasses
import functools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rollball.scene import Ball, Contact, Integrator, Scene, Start
from rollball.simulation import simulate
from rollball.trajectory import DISSIPATION_CAUSES

G, R_BALL, M = 9.81, 0.1, 2.0
V0, C_RR = 1.5, 0.05
# (method, the two steps: dt, or rtol for the pair)
METHODS = [("euler", (2e-3, 1e-3)), ("rk4", (2e-2, 1e-2)), ("lawson5", (2e-2, 1e-2)), ("gauss4", (2e-2, 1e-2)),
           ("dopri5", (1e-6, 1e-9))]


def _scene(landscape, start, method, step, duration, stop_at_rest=True, **contact):
    adaptive = method == "dopri5"
    integrator = Integrator(method=method, dt=1e-3 if adaptive else step,
                            **({"rtol": step, "atol": step * 1e-3} if adaptive else {}))
    return Scene(landscape=landscape, gravity=G, ball=Ball(radius=R_BALL, mass=M), start=start,
                 contact=Contact(**{"friction": 0.3, **contact}), duration=duration, integrator=integrator,
                 stop_at_rest=stop_at_rest)


def _errors(method, steps, exact, measure):
    """measure(method, step) − exact at both steps."""
    return [np.asarray(measure(method, step)) - np.asarray(exact) for step in steps]


def _plane_stop(method, step):
    traj = simulate(_scene("0*x", Start(x=0.0, y=0.0, vx=V0), method, step, 6.0, rolling_resistance=C_RR))
    assert [c.kind for c in traj.transitions] == ["rest"] and str(traj.status) == "ok"
    assert traj.message.startswith("the ball comes to rest at t = ")
    rest = traj.transitions[0]
    return rest.time, rest.x, traj


@pytest.mark.parametrize("method, steps", METHODS)
def test_on_a_plane_it_stops_after_the_exact_time_and_distance(method, steps):
    """Deceleration (5/7) c_rr g: stops after 7 v₀ / (5 c_rr g) s and 7 v₀² / (10 c_rr g) m, all of
    the kinetic energy ½ (7/5) m v₀² taken by rolling resistance."""
    t_stop, distance = 7 * V0 / (5 * C_RR * G), 7 * V0 ** 2 / (10 * C_RR * G)
    errors = []
    for step in steps:
        t, x, traj = _plane_stop(method, step)
        errors.append(max(abs(t - t_stop), abs(x - distance)))
        by = traj.dissipated_by
        assert by["rolling"][-1] == pytest.approx(0.7 * M * V0 ** 2, rel=1e-3 if method == "euler" else 1e-12)
        assert traj.warnings() == []
        assert all(np.all(by[c] == 0.0) for c in DISSIPATION_CAUSES if c != "rolling")
        np.testing.assert_allclose(sum(by.values()), traj.dissipated, rtol=0, atol=1e-14)
    if method == "euler":   # first order: halving the step halves the error
        assert errors[1] < 1e-2 and 1.6 < errors[0] / errors[1] < 2.5
    else:   # the motion is a polynomial of degree 2: exact to round-off for these
        assert max(errors) < 1e-9


def _incline(method, step, c_rr, duration, tan=0.04):
    """A plane z = −tan θ x; the ball started up it (towards −x) at V0."""
    theta = math.atan(tan)
    vx = -V0 * math.cos(theta)
    traj = simulate(_scene(f"-{tan}*x", Start(x=0.0, y=0.0, vx=vx), method, step, duration, rolling_resistance=c_rr))
    return theta, traj


@pytest.mark.parametrize("method, steps", METHODS)
def test_up_an_incline_it_stays_where_tan_theta_is_within_c_rr(method, steps):
    """tan θ = 0.04 ≤ c_rr = 0.05: up the slope it decelerates at (5/7) g (sin θ + c_rr cos θ),
    stops after v₀ / that and stays there."""
    for step in steps:
        theta, traj = _incline(method, step, C_RR, 3.0)
        up = 5 / 7 * G * (math.sin(theta) + C_RR * math.cos(theta))
        assert [c.kind for c in traj.transitions] == ["rest"]
        rest = traj.transitions[0]
        tol = 1e-2 if method == "euler" else 1e-9
        assert rest.time == pytest.approx(V0 / up, abs=tol)
        assert rest.x == pytest.approx(-V0 ** 2 / (2 * up) * math.cos(theta), abs=tol)


@pytest.mark.parametrize("method, steps", METHODS)
def test_up_an_incline_steeper_than_c_rr_it_rolls_back_down(method, steps):
    """tan θ = 0.04 > c_rr = 0.02: it stops for an instant at v₀ / a_up, is pulled on (no rest),
    and rolls back down at (5/7) g (sin θ − c_rr cos θ)."""
    c_rr, t_end = 0.02, 6.0
    errors = []
    for step in steps:
        theta, traj = _incline(method, step, c_rr, t_end)
        assert traj.transitions == () and traj.t[-1] == t_end and set(traj.mode) == {"rolling"}
        up = 5 / 7 * G * (math.sin(theta) + c_rr * math.cos(theta))
        down = 5 / 7 * G * (math.sin(theta) - c_rr * math.cos(theta))
        t1 = V0 / up
        along = -V0 ** 2 / (2 * up) + 0.5 * down * (t_end - t1) ** 2   # along the slope, downhill positive
        errors.append(abs(traj.contact[-1, 0] - along * math.cos(theta)))
    if method == "euler":
        assert errors[1] < 2e-2 and 1.6 < errors[0] / errors[1] < 2.5
    else:
        assert max(errors) < 1e-8


@pytest.mark.parametrize("method, steps", METHODS)
def test_a_skidding_shot_grips_then_stops(method, steps):
    """A billiard shot (μ = 0.2, ω₀ = 0): it grips at t* = 2 v₀ / ((7 μ − 5 c_rr) g), having slowed
    at μ g, then rolls to a stop at (5/7) c_rr g."""
    mu = 0.2
    t_grip = 2 * V0 / ((7 * mu - 5 * C_RR) * G)
    v_grip = V0 - mu * G * t_grip
    t_stop = t_grip + 7 * v_grip / (5 * C_RR * G)
    for step in steps:
        traj = simulate(_scene("0*x", Start(x=0.0, y=0.0, vx=V0, omega=(0.0, 0.0, 0.0)), method, step, 4.0,
                               friction=mu, rolling_resistance=C_RR))
        assert [c.kind for c in traj.transitions] == ["grip", "rest"]
        tol = 1e-2 if method == "euler" else 1e-8
        assert traj.transitions[0].time == pytest.approx(t_grip, abs=tol)
        assert traj.transitions[1].time == pytest.approx(t_stop, abs=tol)
        # sliding friction takes μ m g ∫ u dt, the slip u falling linearly from v₀ to 0 over t*; the
        # rolling resistance the rest of ½ m v₀² (while it skids too: the friction spins the ball up)
        by, rel = traj.dissipated_by, (1e-2 if method == "euler" else 1e-9)
        assert by["sliding"][-1] == pytest.approx(mu * M * G * V0 * t_grip / 2, rel=rel)
        assert by["rolling"][-1] == pytest.approx(0.5 * M * V0 ** 2 - mu * M * G * V0 * t_grip / 2, rel=rel)
        assert by["impacts"][-1] == by["spin"][-1] == by["air"][-1] == 0.0


@pytest.mark.parametrize("method, steps", METHODS[1:2] + METHODS[-1:])
def test_a_spin_that_outlasts_the_rolling_stops_in_place(method, steps):
    """Rolling at v₀ spinning at s₀ about N on a plane: the rolling stops after 7 v₀ / (5 c_rr g),
    the spin (falling at (5/2) μ_s g / r all along) at 2 r s₀ / (5 μ_s g), later; the ball rests
    there (no transition at the rolling's stop), and without stop_at_rest stays to the end."""
    s0, mu_s = 40.0, 0.02
    t_roll, t_spin = 7 * V0 / (5 * C_RR * G), 2 * R_BALL * s0 / (5 * mu_s * G)
    assert t_spin > t_roll
    for step in steps:
        scene = _scene("0*x", Start(x=0.0, y=0.0, vx=V0, spin=s0), method, step, 12.0, rolling_resistance=C_RR,
                       spin_friction=mu_s)
        traj = simulate(scene)
        assert [c.kind for c in traj.transitions] == ["rest"]
        assert traj.transitions[0].time == pytest.approx(t_spin, abs=1e-9)
        assert traj.transitions[0].x == pytest.approx(7 * V0 ** 2 / (10 * C_RR * G), abs=1e-9)
        spinning = traj.mode == "resting"
        assert traj.t[spinning][0] == pytest.approx(t_roll, abs=0.02)
        by = traj.dissipated_by
        assert by["spin"][-1] == pytest.approx(0.2 * M * R_BALL ** 2 * s0 ** 2, rel=1e-8)
        assert by["rolling"][-1] == pytest.approx(0.7 * M * V0 ** 2, rel=1e-8)
        tail = simulate(dataclasses.replace(scene, stop_at_rest=False))
        assert tail.t[-1] == 12.0 and tail.mode[-1] == "resting" and np.all(tail.velocity[-1] == 0.0)


BOWL = "0.5*(x^2 + y^2)"
ORDERS = [("euler", 1, (0.002, 0.001)), ("rk4", 4, (0.04, 0.02)), ("lawson5", 5, (0.08, 0.04)),
          ("gauss4", 4, (0.04, 0.02))]


def _bowl_rest(method, **options):
    """Started still at x = 0.3 in a bowl z = (x² + y²)/2 (tan θ = x there, above c_rr = 0.08):
    pulled down, it rolls to a stop where it is held; the rest's time and place."""
    scene = _scene(BOWL, Start(x=0.3, y=0.0), method, options.get("dt", 1e-3), 4.0, rolling_resistance=0.08)
    traj = simulate(scene, method=method, **options)
    assert [c.kind for c in traj.transitions] == ["rest"]
    rest = traj.transitions[0]
    assert abs(rest.x) <= 0.08 * (1 + 1e-9)   # held: tan θ = |x| ≤ c_rr
    return rest.time, rest.x


@pytest.mark.parametrize("method, order, steps", ORDERS)
def test_the_rest_time_on_a_bowl_converges_at_the_method_order(method, order, steps):
    """No closed form on a bowl: against dop853 at tolerance 10⁻¹³, each halving of the step
    shrinks the rest time's error about 2^p-fold (within a factor 3)."""
    reference = _bowl_rest("dop853", rtol=1e-13, atol=1e-15, record_dt=0.1)
    errors = [abs(_bowl_rest(method, dt=dt)[0] - reference[0]) for dt in steps]
    assert 2 ** order / 3 < errors[0] / errors[1] < 2 ** order * 3


# A 2-D path to rest: a tilted trough z = (x² + 0.6 y²)/2 + 0.05 x, the ball started off its axis with
# a sideways velocity, so that its path curves all the way to the stop; c_rr = 0.08 holds it where it
# stops (tan θ ≈ 0.053 there), and spin friction μ_s = 0.05 holds ω·N at 0 all along (static: the
# reference's couple about N stays within 5 % of μ_s r F_n).
TROUGH, TROUGH_C_RR, TROUGH_SPIN = (1.0, 0.6, 0.05), 0.08, 0.05
TROUGH_START = (0.35, 0.1, -0.1, 0.45)   # x, y, vx, vy
TROUGH_ORDERS = [("euler", 1, (2e-3, 1e-3, 5e-4)), ("rk4", 4, (2e-2, 1e-2, 5e-3)), ("lawson5", 5, (4e-2, 2e-2, 1e-2)),
                 ("gauss4", 4, (2e-2, 1e-2, 5e-3))]   # (at 0.04 gauss4 is not yet in its asymptotic range)


def _trough_surface(x, y):
    """The trough's unit normal N at (x, y), the columns of ∂c/∂(x, y) for the centre c = P + r N
    over the contact point P = (x, y, f), and ∂N/∂x, ∂N/∂y."""
    a, b, s = TROUGH
    fx, fy = a * x + s, b * y
    w = math.sqrt(1.0 + fx * fx + fy * fy)
    n = np.array([-fx, -fy, 1.0]) / w
    nx = np.array([-a, 0.0, 0.0]) / w - n * (fx * a) / w ** 2
    ny = np.array([0.0, -b, 0.0]) / w - n * (fy * b) / w ** 2
    return n, np.array([1.0, 0.0, fx]) + R_BALL * nx, np.array([0.0, 1.0, fy]) + R_BALL * ny, nx, ny


def _trough_rates(_, state):
    """Newton–Euler for the rolling ball in the world frame, state (x, y, ω) — not the kernel's
    angular momentum about the contact point: ċ = r ω × N, m c̈ = m g + F, I ω̇ = −r N × F + M_rr + s N,
    with the rolling constraint c̈ = r ω̇ × N + r ω × Ṅ, the rolling resistance's couple
    M_rr = −c_rr r F_n ω̂_t and the static spin couple s N that keeps ω·N at 0 ((ω·N)˙ = 0)."""
    w = state[2:5]
    n, cx, cy, nx, ny = _trough_surface(state[0], state[1])
    jac = np.column_stack([cx, cy])
    contact_rate = np.linalg.solve(jac.T @ jac, jac.T @ (R_BALL * np.cross(w, n)))
    n_rate = nx * contact_rate[0] + ny * contact_rate[1]
    g = np.array([0.0, 0.0, -G])
    normal_force = M * R_BALL * np.dot(np.cross(w, n_rate), n) - M * np.dot(g, n)
    turn = w - np.dot(w, n) * n
    couple = -TROUGH_C_RR * R_BALL * normal_force * turn / np.linalg.norm(turn)
    system = np.zeros((4, 4))
    system[:3, :3] = 0.4 * M * R_BALL ** 2 * np.eye(3) + M * R_BALL ** 2 * (np.eye(3) - np.outer(n, n))
    system[:3, 3], system[3, :3] = -n, n
    right = np.append(-M * R_BALL ** 2 * np.cross(n, np.cross(w, n_rate)) + M * R_BALL * np.cross(n, g) + couple,
                      -np.dot(w, n_rate))
    solved = np.linalg.solve(system, right)
    assert abs(solved[3]) <= 0.06 * TROUGH_SPIN * R_BALL * normal_force   # the spin couple static throughout
    return np.concatenate([contact_rate, solved[:3]])


def _trough_turn(state):
    n = _trough_surface(state[0], state[1])[0]
    w = state[2:5]
    return float(np.linalg.norm(w - np.dot(w, n) * n))


@functools.lru_cache(maxsize=1)
def _trough_reference():
    """The rest (t, x, y) by scipy's DOP853 at rtol 10⁻¹³ on ``_trough_rates`` to |ω_t| = ε = 10⁻¹⁰,
    an event solve_ivp locates with brentq on its dense output: |ω_t| falls at a rate a there that
    varies little, and the rest is ε / a later (the centre moving r ε² / (2a) on, nothing)."""
    x0, y0, vx, vy = TROUGH_START
    n = _trough_surface(x0, y0)[0]
    velocity = np.array([vx, vy, -(n[0] * vx + n[1] * vy) / n[2]])
    eps = 1e-10
    stops = lambda t, s: _trough_turn(s) - eps   # noqa: E731
    stops.terminal, stops.direction = True, -1
    run = solve_ivp(_trough_rates, (0.0, 10.0), np.concatenate([[x0, y0], np.cross(n, velocity) / R_BALL]),
                    method="DOP853", rtol=1e-13, atol=1e-16, events=stops, dense_output=True)
    t_eps = float(run.t_events[0][0])
    rate = (_trough_turn(run.sol(t_eps - 1e-8)) - eps) / 1e-8
    x, y = run.y_events[0][0][:2]
    return t_eps + eps / rate, float(x), float(y)


def _trough_rest(scheme, step, **options):
    """The rest's (t, x, y) with ``scheme`` at ``step`` (dt, or rtol for dopri5), the run checked
    (one transition, a rest, no warning); ``options``: simulate's, overriding the scene's."""
    x0, y0, vx, vy = TROUGH_START
    scene = _scene("0.5*(x^2 + 0.6*y^2) + 0.05*x", Start(x=x0, y=y0, vx=vx, vy=vy), scheme, step, 8.0,
                   rolling_resistance=TROUGH_C_RR, spin_friction=TROUGH_SPIN)
    traj = simulate(scene, **options)
    assert [c.kind for c in traj.transitions] == ["rest"] and str(traj.status) == "ok", (scheme, step)
    assert traj.warnings() == [], (scheme, step)
    rest = traj.transitions[0]
    speed = np.linalg.norm(traj.velocity, axis=1)
    moving = traj.velocity[speed > 1e-3 * speed.max()]
    heading = np.unwrap(np.arctan2(moving[:, 1], moving[:, 0]))
    assert abs(heading[-1] - heading[0]) > 2 * math.pi   # a 2-D path: its heading turns by more than a turn
    # where the rolling stopped (the first row resting) ω_t is 0 up to a share of the speeds (the zero
    # located on a step's dense output along ω_t at the step's start; 1.4·10⁻⁸ for dopri5 at rtol
    # 10⁻⁸, 2·10⁻⁹ at most else)
    stop = np.flatnonzero(traj.mode == "resting")[0]
    assert set(traj.mode[:stop]) == {"rolling"} and set(traj.mode[stop:]) == {"resting"}
    normal = _trough_surface(*traj.contact[stop])[0]
    turn = traj.omega[stop] - np.dot(traj.omega[stop], normal) * normal
    assert np.linalg.norm(turn) * R_BALL <= 3e-8 * speed.max()
    assert traj.t[stop] <= rest.time and np.all(traj.velocity[stop + 1:] == 0.0)
    return np.array([rest.time, rest.x, rest.y])


def test_the_trough_reference_agrees_with_the_kernel_at_a_tight_tolerance():
    """Two formulations (the test's Newton–Euler in ω, the kernel's angular momentum about the contact
    point) and two integrations agree on the rest to 10⁻¹¹ s and m."""
    np.testing.assert_allclose(_trough_rest("dopri5", 1e-13, method="dop853", rtol=1e-13, atol=1e-15, record_dt=0.01),
                               _trough_reference(), rtol=0, atol=1e-11)


@pytest.mark.parametrize("method, order, steps", TROUGH_ORDERS)
def test_on_a_curved_path_the_rest_converges_at_the_method_order(method, order, steps):
    """Near the stop the direction of ω_t relaxes towards the pull's at the rate |G| / |ω_t|, stiff
    for a fixed step: the rest's time and place, at three steps, each halving shrinking the error
    about 2^p-fold (within a factor 3), with no warning."""
    reference = np.array(_trough_reference())
    errors = [np.abs(_trough_rest(method, dt) - reference) for dt in steps]
    for coarse, fine in zip(errors, errors[1:]):
        assert 2 ** order / 3 < coarse[0] / fine[0] < 2 ** order * 3, errors
        assert np.max(fine[1:]) < np.max(coarse[1:]) / 2 ** order * 3, errors


def test_on_a_curved_path_dopri5_meets_the_rest_within_its_tolerance():
    """The pair's error control resolves the stiff direction itself: the rest within 100 rtol
    (s and m) at rtol 10⁻⁸ and 10⁻¹⁰."""
    reference = np.array(_trough_reference())
    errors = [np.max(np.abs(_trough_rest("dopri5", rtol) - reference)) for rtol in (1e-8, 1e-10)]
    assert errors[0] < 1e-6 and errors[1] < 1e-8 and errors[1] < errors[0] / 10
