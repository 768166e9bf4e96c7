"""Rolling resistance, spin friction and air in the compiled kernel, against exact answers
(docs/design.md §1, "Dissipation"): kernel runs in one contact mode (``contact_runs.segment``),
each for the fixed-step methods at two steps and the adaptive pairs at two tolerances, and the
energy each cause took (the state's quadratures, the rows' dissipated_rolling, _spin, _air)."""

import dataclasses
import math
import sys

import numpy as np
import pytest

from rollball import kernel, simulate
from rollball.examples import scene_path
from rollball.scene import Air, Ball, Contact, Scene, Start
from rollball.sliding import BallState

from contact_runs import rolling_state, segment

G, R_BALL, M = 9.81, 0.1, 1.0
PLANE = "0*x"
THETA = 0.3
INCLINE = f"-{math.tan(THETA)}*x"   # falls along +x at the angle THETA
V = kernel.ROW_SLICES["velocity"]
# (method, the two steps: dt, or rtol for the pairs)
METHODS = [("euler", (2e-3, 1e-3)), ("rk4", (4e-2, 2e-2)), ("lawson5", (4e-2, 2e-2)), ("gauss4", (4e-2, 2e-2)),
           ("dopri5", (1e-6, 1e-9)), ("dop853", (1e-6, 1e-9))]
CASES = [(method, step) for method, steps in METHODS for step in steps]
# The motions with rolling resistance or spin friction alone are polynomials of low degree in
# time, which every method follows to round-off (ROUND); the energy each cause took is a
# quadrature, Euler's to its first order (EULER at its steps here).
ROUND, EULER = 1e-12, 1e-2


def _tol(method):
    return EULER if method == "euler" else ROUND


def _run(formula, state, method, step, sliding=False, **kw):
    if method in ("dopri5", "dop853"):
        return segment(formula, state, sliding=sliding, method=method, rtol=step, atol=step * 1e-3, dt=1e-3, **kw)
    return segment(formula, state, sliding=sliding, method=method, dt=step, **kw)


def _speed(rows):
    return np.linalg.norm(rows[:, V], axis=1)


def _balance(rows):
    """The largest change of energy + dissipated along a run (0 in the exact motion)."""
    total = rows[:, kernel.ROW_ENERGY] + rows[:, kernel.ROW_DISSIPATED]
    return np.max(np.abs(total - total[0]))


def _causes(rows):
    return rows[:, kernel.ROW_ROLLING], rows[:, kernel.ROW_SPIN], rows[:, kernel.ROW_AIR]


# -- rolling resistance ------------------------------------------------------------------------

@pytest.mark.parametrize("method, step, classic", [(method, step, False) for method, step in CASES]
                         + [(method, step, True) for method, step in CASES if method in ("euler", "rk4", "lawson5")])
def test_rolling_on_a_plane_slows_at_five_sevenths_c_g_and_comes_to_rest(method, step, classic):
    """(also with the classic orientation, R in the state before the quadratures)"""
    c, v0 = 0.05, 1.0
    seg = _run(PLANE, rolling_state(PLANE, 0.0, 0.0, v0, 0.0), method, step, t_end=5.0, rolling_resistance=c,
               munthe_kaas=not classic)
    assert (seg.status, seg.transition) == ("transition", "rest")
    t_rest = 7.0 * v0 / (5.0 * c * G)
    assert seg.event[0] == pytest.approx(t_rest, abs=ROUND)
    assert seg.event[1] == pytest.approx(7.0 * v0 ** 2 / (10.0 * c * G), abs=_tol(method))
    t = seg.rows[:, 0]
    assert t[-1] == seg.event[0] and len(t) > 5
    assert np.abs(_speed(seg.rows) - (v0 - 5.0 / 7.0 * c * G * t)).max() < ROUND   # all along the run
    assert np.abs(seg.state.omega).max() < ROUND
    # the energy went to rolling resistance, all of it, and nothing else took any
    rolling, spin, air = _causes(seg.rows)
    e = seg.rows[:, kernel.ROW_ENERGY]
    assert np.abs(rolling - (e[0] - e)).max() < _tol(method) and not spin.any() and not air.any()
    assert rolling[-1] == pytest.approx(0.7 * M * v0 ** 2, abs=_tol(method))
    assert np.array_equal(seg.rows[:, kernel.ROW_DISSIPATED], rolling)
    assert seg.state.dissipated == rolling[-1] and seg.state.dissipated_by == (rolling[-1], 0.0, 0.0)


@pytest.mark.parametrize("method, step", CASES)
def test_rolling_down_an_incline_against_rolling_resistance(method, step):
    c, v0 = 0.05, 0.5
    seg = _run(INCLINE, rolling_state(INCLINE, 0.0, 0.0, v0, 0.0), method, step, t_end=1.0, rolling_resistance=c)
    assert seg.status == "ok"
    a = 5.0 / 7.0 * G * (math.sin(THETA) - c * math.cos(THETA))
    speed = _speed(seg.rows)
    assert np.abs(speed - (speed[0] + a * seg.rows[:, 0])).max() < ROUND
    assert _balance(seg.rows) < _tol(method)
    # the rate c r F_n |omega_t| = c m g cos(theta) |c'|: D = c m g cos(theta) times the path
    path = speed[0] * seg.rows[:, 0] + 0.5 * a * seg.rows[:, 0] ** 2
    assert np.abs(seg.rows[:, kernel.ROW_ROLLING] - c * M * G * math.cos(THETA) * path).max() < _tol(method)


@pytest.mark.parametrize("method, step", CASES)
@pytest.mark.parametrize("c", [0.2, 0.4])
def test_sent_uphill_it_stops_then_rolls_back_or_stays(method, step, c):
    """Started uphill the ball stops at v0 / a_up (the rest transition); from there it rolls
    back down at a_down where tan(theta) > c_rr, and stays where tan(theta) <= c_rr (the
    static couple holds it)."""
    v0 = 0.5
    seg = _run(INCLINE, rolling_state(INCLINE, 0.0, 0.0, -v0, 0.0), method, step, t_end=2.0, rolling_resistance=c,
               mu=1.0)
    assert (seg.status, seg.transition) == ("transition", "rest")
    speed0 = _speed(seg.rows)[0]
    a_up = 5.0 / 7.0 * G * (math.sin(THETA) + c * math.cos(THETA))
    assert seg.event[0] == pytest.approx(speed0 / a_up, abs=ROUND)
    back = _run(INCLINE, seg.state, method, step, t_end=0.5, rolling_resistance=c, mu=1.0)
    assert back.status == "ok"
    t, speed = back.rows[:, 0], _speed(back.rows)
    if math.tan(THETA) > c:   # (0.309)
        a_down = 5.0 / 7.0 * G * (math.sin(THETA) - c * math.cos(THETA))
        assert np.abs(speed - a_down * t).max() < ROUND
        assert back.rows[-1, kernel.ROW_CONTACT] > seg.rows[-1, kernel.ROW_CONTACT]   # down the slope: +x
    else:
        assert speed.max() < ROUND and np.ptp(back.rows[:, kernel.ROW_CONTACT]) < ROUND
        assert np.ptp(back.rows[:, kernel.ROW_ROLLING]) < ROUND   # and loses nothing more


# -- spin friction -------------------------------------------------------------------------------

@pytest.mark.parametrize("method, step", CASES)
def test_a_ball_spinning_in_place_stops_at_2_r_w0_over_5_mu_s_g(method, step):
    mu_s, w0 = 0.1, 10.0
    spinning = BallState(0.0, 0.0, np.zeros(3), np.array([0.0, 0.0, w0]), np.eye(3))
    seg = _run(PLANE, spinning, method, step, t_end=1.0, spin_friction=mu_s)
    assert seg.status == "ok"   # (the spin's stop is the kernel's own: the run goes on from it)
    t = seg.rows[:, 0]
    assert 2.0 * R_BALL * w0 / (5.0 * mu_s * G) < 0.5
    exact = np.maximum(w0 - 2.5 * mu_s * G / R_BALL * t, 0.0)
    assert np.abs(seg.rows[:, kernel.ROW_OMEGA + 2] - exact).max() < ROUND
    assert np.abs(seg.rows[:, kernel.ROW_CONTACT:kernel.ROW_CONTACT + 2]).max() == 0.0
    rolling, spin, air = _causes(seg.rows)
    assert spin[-1] == pytest.approx(0.2 * M * R_BALL ** 2 * w0 ** 2, abs=_tol(method)) and not rolling.any()
    assert _balance(seg.rows) < _tol(method)


@pytest.mark.parametrize("method, step", CASES)
def test_spin_friction_while_rolling_on_a_plane(method, step):
    mu_s = 0.1
    seg = _run(PLANE, rolling_state(PLANE, 0.0, 0.0, 1.0, 0.0, spin=5.0), method, step, t_end=0.5,
               spin_friction=mu_s)
    assert seg.status == "ok"
    t = seg.rows[:, 0]
    assert np.abs(seg.rows[:, kernel.ROW_OMEGA + 2] - np.maximum(5.0 - 2.5 * mu_s * G / R_BALL * t, 0.0)).max() < ROUND
    assert np.abs(_speed(seg.rows) - 1.0).max() < ROUND   # the spin's couple does not brake the rolling


def test_spin_friction_holds_a_rolling_ball_from_spinning_up_on_a_curved_surface():
    """Rolling over 0.5 sin x cos y the geometry turns omega.N (by 3 rad/s here); a spin friction
    able to hold it (the static couple, up to mu_s r F_n) keeps it at 0, and takes no energy."""
    hills = "0.5*sin(x)*cos(y)"
    start = rolling_state(hills, 0.4, -0.3, 1.0, 0.5)
    spins = []
    for mu_s in (1e-12, 1.0):
        seg = segment(hills, start, sliding=False, method="rk4", dt=1e-3, t_end=3.0, spin_friction=mu_s)
        assert seg.status == "ok"
        x, y = seg.rows[:, kernel.ROW_CONTACT], seg.rows[:, kernel.ROW_CONTACT + 1]
        fx, fy = 0.5 * np.cos(x) * np.cos(y), -0.5 * np.sin(x) * np.sin(y)
        normal = np.column_stack([-fx, -fy, np.ones_like(x)]) / np.sqrt(1.0 + fx * fx + fy * fy)[:, None]
        spins.append(np.abs(np.einsum("ij,ij->i", seg.rows[:, kernel.ROW_OMEGA:kernel.ROW_OMEGA + 3], normal)).max())
        assert _balance(seg.rows) < 1e-12
    assert spins[0] > 1.0 and spins[1] < 1e-10
    assert np.abs(seg.rows[:, kernel.ROW_SPIN]).max() < 1e-12   # (held: the static couple does no work)


@pytest.mark.parametrize("method, step", [("rk4", 2e-2), ("dopri5", 1e-9)])
def test_a_held_ball_stays_still_and_its_rolling_couple_static_whatever_its_spin(method, step):
    """Why a rolling ball's static rolling couple never reaches its limit inside a step: holding omega_t
    at 0 it holds the ball still (c' = r omega x N = 0 for omega along N), so its pull, gravity's
    moment m g r N x z about the contact point, and its limit c_rr r m g N_z stay what they were.
    Spinning in place on an incline with tan theta < c_rr, the ball does not move while spin friction
    runs the spin down at (5/2) mu_s g cos theta / r, and rolling resistance takes nothing."""
    c_rr, tan, mu_s, w0 = 0.05, 0.04, 0.1, 10.0
    normal = np.array([tan, 0.0, 1.0]) / math.hypot(tan, 1.0)
    spinning = BallState(0.0, 0.0, np.zeros(3), w0 * normal, np.eye(3))
    seg = _run(f"-{tan}*x", spinning, method, step, t_end=1.0, rolling_resistance=c_rr, spin_friction=mu_s)
    assert seg.status == "ok"
    t = seg.rows[:, 0]
    exact = np.maximum(w0 - 2.5 * mu_s * G * normal[2] / R_BALL * t, 0.0)
    assert 0.0 in exact and np.abs(seg.rows[:, kernel.ROW_OMEGA:kernel.ROW_OMEGA + 3]
                                   - exact[:, None] * normal).max() < ROUND
    assert np.abs(seg.rows[:, kernel.ROW_CONTACT:kernel.ROW_CONTACT + 2]).max() < ROUND
    rolling, spin, _ = _causes(seg.rows)
    assert np.abs(rolling).max() < ROUND and spin[-1] == pytest.approx(0.2 * M * R_BALL ** 2 * w0 ** 2, abs=ROUND)


# A circular trough of radius RHO along x, the ball inside: its centre on a cylinder of radius
# RHO - r, at the angle phi across from the bottom (the normal (0, -sin phi, cos phi)).
RHO = 1.0
TROUGH = f"0*x + {RHO} - sqrt({RHO}^2 - y^2)"


def _trough_limit_time(phi0, xdot, mu_s):
    """Released across the trough at phi0 while rolling along it at xdot, a ball whose spin friction
    holds omega.N at 0 keeps xdot (v's component along the tangent e_phi has no rate there) and swings
    as the pendulum (RHO - r) phi'' = -(5/7) g sin phi, phi'^2 = k (cos phi - cos phi0), k = (10/7) g /
    (RHO - r); the pull on v.N is (2/5) m r² omega_t.N' = -(2/5) m r xdot phi', the static couple's
    limit mu_s r F_n with F_n = m (g cos phi + (RHO - r) phi'^2). Returns the time the pull reaches
    the limit, from the angle where it does: the integral of dphi / |phi'| from there up to phi0."""
    from scipy.integrate import quad
    from scipy.optimize import brentq
    big = RHO - R_BALL
    k = 10.0 / 7.0 * G / big

    def rate2(phi):   # phi'^2, without cancellation near phi0
        return 2.0 * k * math.sin(0.5 * (phi0 + phi)) * math.sin(0.5 * (phi0 - phi))

    phi = brentq(lambda f: 0.4 * xdot * math.sqrt(rate2(f)) - mu_s * (G * math.cos(f) + big * rate2(f)), 0.0, phi0,
                 xtol=1e-16, rtol=1e-15)

    def smooth(f):   # 1 / |phi'| times sqrt(phi0 - phi), which quad's weight takes
        u = 0.5 * (phi0 - f)
        return math.sqrt((u / math.sin(u) if u > 0.0 else 1.0) / (k * math.sin(0.5 * (phi0 + f))))

    return quad(smooth, phi, phi0, weight="alg", wvar=(0.0, -0.5), epsabs=1e-15, epsrel=1e-14)[0]


# (method, step, how far off the limit's time it may be: rk4's and gauss4's are 5e-14 and 2e-14 s off,
# dopri5's 6e-10 and 7e-12, dop853's 4e-12 and 1e-14, each placed by the method's own step)
LIMIT_RUNS = [("rk4", 1e-3, 1e-12), ("gauss4", 1e-3, 1e-12), ("dopri5", 1e-6, 1e-8), ("dopri5", 1e-9, 1e-10),
              ("dop853", 1e-6, 1e-10), ("dop853", 1e-9, 1e-12)]


@pytest.mark.parametrize("method, step, off", LIMIT_RUNS)
def test_a_static_spin_couple_gives_way_where_the_pull_reaches_its_limit(method, step, off):
    """Across a circular trough, the pull on omega.N grows from 0 through mu_s r F_n at a time known
    by quadrature (``_trough_limit_time``): the kernel ends a step there (the couple's law has a
    kink, static to kinetic) and goes on with the kinetic couple, so omega.N is held at 0 up to that
    time, turns the way the pull does after it, and the spin dissipation never falls."""
    phi0, xdot, mu_s = 0.5, 2.0, 0.05
    t_limit = _trough_limit_time(phi0, xdot, mu_s)
    start = rolling_state(TROUGH, 0.0, RHO * math.sin(phi0), xdot, 0.0)
    seg = _run(TROUGH, start, method, step, t_end=t_limit + 0.02, spin_friction=mu_s, record_dt=1e-3)
    assert seg.status == "ok" and seg.transition is None
    assert seg.turned == pytest.approx(t_limit, abs=off)
    t, y = seg.rows[:, 0], seg.rows[:, kernel.ROW_CONTACT + 1]
    normal = np.column_stack([np.zeros_like(y), -y / RHO, np.sqrt(RHO ** 2 - y ** 2) / RHO])
    spin = np.einsum("ij,ij->i", seg.rows[:, kernel.ROW_OMEGA:kernel.ROW_OMEGA + 3], normal)
    held = t < seg.turned
    # (held to round-off by the fixed steps, to the pairs' own error)
    assert held.sum() > 100 and np.abs(spin[held]).max() < (1e3 * step if method.startswith("dop") else 1e-10)
    # (the pull -(2/5) m r xdot phi' is positive: phi falls while it swings down)
    assert spin[-1] > 1e-3 and np.all(np.diff(spin[~held]) > 0.0)
    assert np.diff(seg.rows[:, kernel.ROW_SPIN]).min() >= -ROUND


@pytest.mark.parametrize("method, steps", [("rk4", (4e-3, 2e-3)), ("gauss4", (4e-3, 2e-3)), ("dopri5", (1e-7, 1e-9))])
def test_a_sliding_ball_loses_to_each_cause_what_its_rate_says(method, steps):
    """Sliding over 0.5 sin x cos y with friction, rolling resistance, spin friction and air: the
    energy plus all that was dissipated stays constant at the method's order, and the air took
    k ∫|c'|³."""
    hills, k = "0.5*sin(x)*cos(y)", 0.05
    vz = 2.0 * 0.5 * math.cos(0.4) * math.cos(-0.3) + 0.5 * (-0.5 * math.sin(0.4) * math.sin(-0.3))
    start = BallState(0.4, -0.3, np.array([2.0, 0.5, vz]), np.array([0.0, 0.0, 3.0]), np.eye(3))
    balances = []
    for step in steps:
        kw = {"record_dt": 1e-3} if method == "dopri5" else {}
        seg = _run(hills, start, method, step, sliding=True, mu=0.1, t_end=0.3, rolling_resistance=0.05,
                   spin_friction=0.05, air=k, **kw)
        assert seg.status == "ok" and seg.rows[:, kernel.ROW_SLIP].min() > 0.1
        balances.append(_balance(seg.rows))
        rolling, spin, air = _causes(seg.rows)
        assert rolling[-1] > 0.01 and spin[-1] > 0.01
        speed3 = _speed(seg.rows) ** 3
        integral = np.sum(0.5 * (speed3[1:] + speed3[:-1]) * np.diff(seg.rows[:, 0]))
        assert air[-1] == pytest.approx(k * integral, rel=1e-4)   # (the trapezoid's own error, ~dt²)
    assert balances[0] < (1e-7 if method == "dopri5" else 1e-8) and balances[1] < 1e-9
    if method != "dopri5":
        assert 12.0 < balances[0] / balances[1] < 20.0


# -- air -------------------------------------------------------------------------------------------

# the error bound of the speed for (method, step) (measured: about a third of it), and the order
AIR_BOUNDS = {"euler": (2.5e-3, 1), "rk4": (5e-9, 4), "lawson5": (3e-12, 5), "gauss4": (5e-10, 4),
              "dopri5": (1e-5, None), "dop853": (2e-8, None)}


@pytest.mark.parametrize("method, steps", METHODS)
def test_rolling_down_an_incline_against_the_air_tends_to_its_terminal_speed(method, steps):
    """From rest, m (7/5) v' = m g sin(theta) - k v^2: v = v_t tanh((5/7) g sin(theta) t / v_t),
    v_t = sqrt(m g sin(theta) / k); the air takes k v^3 (the rows' dissipated_air, all of the loss)."""
    k = 0.05
    v_t = math.sqrt(M * G * math.sin(THETA) / k)
    errors = []
    for step in steps:
        kw = {"record_dt": 0.05} if method in ("dopri5", "dop853") else {}
        seg = _run(INCLINE, rolling_state(INCLINE, 0.0, 0.0, 0.0, 0.0), method, step, t_end=4.0, air=k, **kw)
        assert seg.status == "ok" and seg.rows[-1, 0] == 4.0
        t = seg.rows[:, 0]
        errors.append(np.abs(_speed(seg.rows) - v_t * np.tanh(5.0 / 7.0 * G * math.sin(THETA) * t / v_t)).max())
        rolling, spin, air = _causes(seg.rows)
        assert not rolling.any() and not spin.any()
        assert _balance(seg.rows) < 20.0 * AIR_BOUNDS[method][0]
    bound, order = AIR_BOUNDS[method]
    assert errors[0] < bound and errors[1] < bound * (2.0 ** -order if order else 1e-2)
    if order:   # the order shows
        assert 2.0 ** (order - 0.3) < errors[0] / errors[1] < 2.0 ** (order + 0.3)


# -- sliding --------------------------------------------------------------------------------------

@pytest.mark.parametrize("method, step", CASES)
def test_a_billiard_shot_against_rolling_resistance_grips_at_2_v0_over_7mu_minus_5c_g(method, step):
    mu, c, v0 = 0.2, 0.05, 2.0
    start = BallState(0.0, 0.0, np.array([v0, 0.0, 0.0]), np.zeros(3), np.eye(3))
    slide = _run(PLANE, start, method, step, sliding=True, mu=mu, t_end=2.0, rolling_resistance=c)
    assert (slide.status, slide.transition) == ("transition", "grip")
    t_grip = 2.0 * v0 / ((7.0 * mu - 5.0 * c) * G)
    assert slide.event[0] == pytest.approx(t_grip, abs=ROUND)
    # the rolling resistance took c m g r omega: c m g r (5 (mu - c) g / 2 r) t^2 / 2
    assert slide.state.dissipated_by[0] == pytest.approx(1.25 * c * M * G * G * (mu - c) * t_grip ** 2,
                                                         abs=_tol(method))
    assert _balance(slide.rows) < _tol(method)
    roll = _run(PLANE, slide.state, method, step, sliding=False, mu=mu, t_end=0.5, rolling_resistance=c)
    assert roll.status == "ok"
    v_grip = v0 - mu * G * t_grip
    assert np.abs(_speed(roll.rows) - (v_grip - 5.0 / 7.0 * c * G * roll.rows[:, 0])).max() < ROUND
    # the energy each cause took goes on from where the slide left it
    assert roll.rows[0, kernel.ROW_ROLLING] == slide.rows[-1, kernel.ROW_ROLLING]
    assert roll.rows[0, kernel.ROW_DISSIPATED] == pytest.approx(slide.rows[-1, kernel.ROW_DISSIPATED], abs=1e-15)



# -- grips and slips with the couples (docs/design.md §1, "Dissipation") -------------------------

def _billiard(c, mu=0.2, v0=2.0, backspin=0.0, duration=6.0):
    return Scene(landscape=PLANE, gravity=G, ball=Ball(radius=R_BALL, mass=M), duration=duration,
                 start=Start(x=0.0, y=0.0, vx=v0, omega=(0.0, -backspin, 0.0)),
                 contact=Contact(friction=mu, rolling_resistance=c))


# (method, its two steps: dt, or rtol for the pairs) through the whole run, the mode machine's too
RUNS = [("euler", (2e-3, 1e-3)), ("rk4", (1e-2, 5e-3)), ("lawson5", (1e-2, 5e-3)), ("gauss4", (1e-2, 5e-3)),
        ("dopri5", (1e-6, 1e-9))]


def _simulate(scene, method, step):
    if method == "dopri5":
        return simulate(scene, method=method, rtol=step, atol=step * 1e-3)
    return simulate(scene, method=method, dt=step)


@pytest.mark.parametrize("method, steps", RUNS)
@pytest.mark.parametrize("above", [True, False])
def test_a_slip_stopping_on_an_incline_grips_iff_mu_covers_what_rolling_with_c_rr_needs(method, steps, above):
    """Thrown down the incline with topspin (r omega = v0 + delta), the slip u = v - r omega < 0 grows
    at g cos(theta) (tan(theta) + 7/2 mu + 5/2 c) and reaches 0 at t0. Rolling down against the couple,
    (2/5) m r² omega' = r F - c r F_n and a = r omega' give a = (5/7) g (sin(theta) - c cos(theta)) and
    F = (2/7) m g sin(theta) + (5/7) c m g cos(theta): the ball grips iff mu >= (2/7) tan(theta) + (5/7) c
    and rolls on at that a; else the slip turns about (no transition) and it slides on at
    g (sin(theta) - mu cos(theta))."""
    c, v0, delta, t_end = 0.05, 1.0, 0.2, 0.5
    need = 2.0 / 7.0 * math.tan(THETA) + 5.0 / 7.0 * c
    mu = need * (1.01 if above else 0.99)
    start = Start(x=0.0, y=0.0, vx=v0 * math.cos(THETA), omega=(0.0, (v0 + delta) / R_BALL, 0.0))
    scene = Scene(landscape=INCLINE, gravity=G, ball=Ball(radius=R_BALL, mass=M), duration=t_end, start=start,
                  contact=Contact(friction=mu, rolling_resistance=c))
    t0 = delta / (G * math.cos(THETA) * (math.tan(THETA) + 3.5 * mu + 2.5 * c))
    v_grip = v0 + G * (math.sin(THETA) + mu * math.cos(THETA)) * t0
    rolling = 5.0 / 7.0 * G * (math.sin(THETA) - c * math.cos(THETA))
    sliding = G * (math.sin(THETA) - mu * math.cos(THETA))
    a = rolling if above else sliding
    for step in steps:
        traj = _simulate(scene, method, step)
        assert traj.status == "ok" and traj.data[-1, 0] == t_end
        if above:
            assert [str(t.kind) for t in traj.transitions] == ["grip"]
            assert traj.transitions[0].time == pytest.approx(t0, abs=1e-9)
        else:
            assert not traj.transitions and set(traj.modes) == {1}
        assert _speed(traj.data)[-1] == pytest.approx(v_grip + a * (t_end - t0), abs=1e-9)


@pytest.mark.parametrize("method, steps", RUNS)
@pytest.mark.parametrize("backspin", [0.0, 10.0])
def test_a_billiard_shot_against_rolling_resistance_grips_rolls_and_comes_to_rest(method, steps, backspin):
    """A shot from v0 with backspin w0 (omega_y = -w0) on cloth with mu > c: friction and the couple
    both spin the ball forward until omega_y = 0 at t1 = w0 r / ((5/2)(mu + c) g) (the couple's side
    turns while the ball still slides); then omega_y' = (5/2)(mu - c) g / r, and the slip v - r omega_y
    ends at t* = (2 v0 + 5 (mu - c) g t1) / ((7 mu - 5 c) g) (t* = 2 v0 / ((7 mu - 5 c) g) without
    spin); it rolls on at v* = v0 - mu g t*, slowing at (5/7) c g, and rests 7 v* / (5 c g) later,
    7 v*² / (10 c g) further on. All of it polynomial: each method meets it to round-off at both steps
    (Euler the distance to its first order); the rolling resistance took c m g r ∫|omega_y|."""
    mu, c, v0 = 0.2, 0.05, 2.0
    t1 = backspin * R_BALL / (2.5 * (mu + c) * G)
    t_grip = (2.0 * v0 + 5.0 * (mu - c) * G * t1) / ((7.0 * mu - 5.0 * c) * G)
    v_grip = v0 - mu * G * t_grip
    t_rest = t_grip + 7.0 * v_grip / (5.0 * c * G)
    x_rest = v0 * t_grip - 0.5 * mu * G * t_grip ** 2 + 7.0 * v_grip ** 2 / (10.0 * c * G)
    rolled = backspin * t1 / 2.0 + 2.5 * (mu - c) * G / R_BALL * (t_grip - t1) ** 2 / 2.0   # ∫|omega_y| to t*
    errors = []
    for step in steps:
        traj = _simulate(_billiard(c, mu, v0, backspin), method, step)
        assert traj.status == "ok" and "comes to rest" in traj.message
        assert [str(t.kind) for t in traj.transitions] == ["grip", "rest"]
        grip, rest = traj.transitions
        assert grip.time == pytest.approx(t_grip, abs=1e-9) and rest.time == pytest.approx(t_rest, abs=1e-9)
        assert traj.data[-1, 0] == rest.time and _speed(traj.data)[-1] < 1e-9
        errors.append(abs(rest.x - x_rest))
        by = traj.dissipated_by
        assert by["rolling"][-1] == pytest.approx(c * M * G * R_BALL * rolled + 0.7 * M * v_grip ** 2,
                                                  abs=_tol(method))
        energy = 0.5 * M * v0 ** 2 + 0.2 * M * (R_BALL * backspin) ** 2
        assert by["rolling"][-1] + by["sliding"][-1] == pytest.approx(energy, abs=_tol(method))
    if method == "euler":   # its distance to first order
        assert errors[0] < 1.5 * steps[0] and 1.8 < errors[0] / errors[1] < 2.2
    else:
        assert max(errors) < 1e-9


def test_huge_rolling_resistance_holds_the_spin_and_the_ball_slides_to_rest():
    """c_rr 1e300: the couple holds omega at 0, the ball slides to a stop at v0 / (mu g),
    v0² / (2 mu g) on, and rests there (the slip and the rolling stop at once), friction having
    taken all its energy."""
    mu, v0 = 0.2, 2.0
    traj = simulate(_billiard(1e300, mu, v0), method="rk4", dt=1e-3)
    assert traj.status == "ok" and "comes to rest" in traj.message
    assert [str(t.kind) for t in traj.transitions] == ["rest"]
    rest = traj.transitions[0]
    assert rest.time == pytest.approx(v0 / (mu * G), abs=1e-12)
    assert rest.x == pytest.approx(v0 ** 2 / (2.0 * mu * G), abs=1e-12)
    assert traj.data[-1, 0] == rest.time
    assert traj.dissipated_by["sliding"][-1] == pytest.approx(0.5 * M * v0 ** 2, abs=1e-12)
    assert np.abs(traj.dissipated_by["rolling"]).max() < 1e-12   # (held: the static couple does no work)


@pytest.mark.parametrize("method, steps", RUNS)
def test_slid_uphill_against_a_couple_friction_cannot_turn_it_rests_where_it_stops(method, steps):
    """mu < c_rr: friction's torque mu r F_n never overcomes the couple's c_rr r F_n, so omega stays 0
    and a ball sent up the incline without spin slides, slowing at g (sin(theta) + mu cos(theta)),
    and stops at v0 / that; there tan(theta) <= mu and <= c_rr hold it: a rest."""
    mu, c, v0 = 0.35, 0.5, 1.0
    a = G * (math.sin(THETA) + mu * math.cos(THETA))
    scene = Scene(landscape=INCLINE, gravity=G, ball=Ball(radius=R_BALL, mass=M), duration=1.0,
                  start=Start(x=0.0, y=0.0, vx=-v0 * math.cos(THETA), omega=(0.0, 0.0, 0.0)),
                  contact=Contact(friction=mu, rolling_resistance=c))
    for step in steps:
        traj = _simulate(scene, method, step)
        assert traj.status == "ok" and [str(t.kind) for t in traj.transitions] == ["rest"]
        rest = traj.transitions[0]
        assert rest.time == pytest.approx(v0 / a, abs=1e-9)
        assert rest.x == pytest.approx(-v0 ** 2 / (2.0 * a) * math.cos(THETA), abs=1e-9 if method != "euler" else step)


def test_rolling_resistance_no_longer_stalls_a_slip_into_a_grip():
    """The wells with a steeper bowl, from rest at (-2.5, 2.5), c_rr 0.05: where the normal force
    falls the ball slips, grips later and flies; it comes to rest in a well, without the slip and
    the grip undoing each other at one instant (before, 16 of them at t = 1.094 s ended the run)."""
    scene = Scene.load(scene_path("wells"))
    scene = dataclasses.replace(scene, landscape=scene.landscape.replace("0.05*(x^2", "0.1*(x^2"),
                                start=Start(x=-2.5, y=2.5),
                                contact=dataclasses.replace(scene.contact, rolling_resistance=0.05, friction=1.0))
    traj = simulate(scene)
    assert traj.status == "ok" and "comes to rest" in traj.message
    kinds = [str(t.kind) for t in traj.transitions]
    assert kinds == ["slip", "grip", "slip", "liftoff", "landing", "rest"]
    times = [t.time for t in traj.transitions]
    assert all(b - a > 1e-3 for a, b in zip(times, times[1:]))
    assert times[0] == pytest.approx(1.0941, abs=1e-4)

# -- the layouts, the parameters and a whole run --------------------------------------------------

def test_without_dissipation_the_state_and_the_rows_are_as_before():
    assert kernel.state_size(True) == kernel.MK_SIZE and kernel.state_size(False, True) == kernel.SLIDING_CLASSIC_SIZE
    sizes = {kernel.state_size(mk, slides, resisted) for mk in (True, False) for slides in (True, False)
             for resisted in (True, False)} | {kernel.MOTION_SIZE, kernel.SLIDING_MOTION_SIZE}
    assert len(sizes) == 10   # every layout tells itself apart by its length
    seg = segment(PLANE, rolling_state(PLANE, 0.0, 0.0, 1.0, 0.0), sliding=False, t_end=0.1)
    assert len(seg.rows[0]) == kernel.ROW_SIZE and not np.any(seg.rows[:, kernel.ROW_ROLLING:])
    assert seg.state.dissipated_by == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("name", ["rolling_resistance", "spin_friction", "air"])
def test_parameters_refuse_a_negative_coefficient(name):
    with pytest.raises(ValueError, match=f"^{name} must be a number >= 0"):
        kernel.parameters(0.1, 1.0, 9.81, **{name: -0.1})


def test_a_scene_with_air_and_spin_friction_runs_through_the_simulation():
    """Scene version 4 through ``simulate``: the parameters reach the kernel, and the energy the
    air and the spin friction took is in the rows, the ball's energy plus it constant."""
    air = Air(density=1.2, drag_coefficient=0.47)
    scene = Scene(landscape=INCLINE, start=Start(0.0, 0.0, 0.5, 0.0, spin=3.0), duration=2.0,
                  contact=Contact(spin_friction=0.05), air=air)
    traj = simulate(scene, method="rk4", dt=1e-3)
    rows = traj.data
    assert rows[-1, 0] == 2.0
    rolling, spin, lost = _causes(rows)
    assert not rolling.any() and spin[-1] > 0.0 and lost[-1] > 0.0
    k = air.drag_factor(0.1)
    speed = _speed(rows)
    integral = np.sum(0.5 * (speed[1:] ** 3 + speed[:-1] ** 3) * np.diff(rows[:, 0]))   # k ∫|c'|³
    assert lost[-1] == pytest.approx(k * integral, rel=1e-6)
    assert _balance(rows) < 1e-10
    omega_n = np.einsum("ij,ij->i", rows[:, kernel.ROW_OMEGA:kernel.ROW_OMEGA + 3],
                        np.column_stack([np.full(len(rows), math.sin(THETA)), np.zeros(len(rows)),
                                         np.full(len(rows), math.cos(THETA))]))
    # spin friction: omega.N falls at (5/2) mu_s g cos(theta) / r (F_n = m g cos(theta))
    t_stop = omega_n[0] / (2.5 * 0.05 * G * math.cos(THETA) / R_BALL)
    assert t_stop < 2.0
    exact = np.maximum(omega_n[0] - 2.5 * 0.05 * G * math.cos(THETA) / R_BALL * rows[:, 0], 0.0)
    assert np.abs(omega_n - exact).max() < 1e-10


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
