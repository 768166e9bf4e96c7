"""A ball that slips with Coulomb friction, against exact answers (docs/design.md §1, "Sliding", and §8):
each for a fixed-step method, an adaptive pair and a Gauss method, at two step sizes (the pairs:
two tolerances). ``python tests/test_sliding.py`` prints the errors measured."""

import math
import sys

import numpy as np
import pytest

from rollball import kernel
from rollball.sliding import BallState

from contact_runs import rolling_state, segment

G, R_BALL, M = 9.81, 0.1, 1.0
PLANE = "0*x"
# (method, the two steps: dt, or rtol for the pairs)
METHODS = [("rk4", (2e-2, 1e-2)), ("dopri5", (1e-6, 1e-9)), ("gauss4", (2e-2, 1e-2))]
CASES = [(method, step) for method, steps in METHODS for step in steps]


def _run(formula, state, method, step, **kw):
    if method in ("dopri5", "dop853"):
        return segment(formula, state, method=method, rtol=step, atol=step * 1e-3, dt=1e-3, **kw)
    return segment(formula, state, method=method, dt=step, **kw)


def _sliding(x, y, velocity, omega):
    return BallState(x, y, np.array(velocity, dtype=float), np.array(omega, dtype=float), np.eye(3))


def billiard_errors(method, step, mu=0.2, v0=2.0, backspin=0.0):
    """A ball on a plane sliding at v0 along x with omega0 = -backspin about y (0: no spin; >0
    opposes rolling): it grips at t* = (v0 + r w) / (3.5 mu g), then rolls at (5 v0 - 2 r w) / 7,
    having lost its kinetic energy's difference. Returns the errors (t*, final speed,
    dissipated), the grip's run and the rolling run after it."""
    start = _sliding(0.0, 0.0, (v0, 0.0, 0.0), (0.0, -backspin, 0.0))
    slide = _run(PLANE, start, method, step, sliding=True, mu=mu, t_end=1.0)
    assert (slide.status, slide.transition) == ("transition", "grip")
    roll = _run(PLANE, slide.state, method, step, sliding=False, mu=mu, t_end=0.2)
    assert roll.status == "ok"
    t_star = (v0 + R_BALL * backspin) / (3.5 * mu * G)
    v_end = (5.0 * v0 - 2.0 * R_BALL * backspin) / 7.0
    lost = 0.5 * M * v0 ** 2 + 0.2 * M * R_BALL ** 2 * backspin ** 2 - 0.7 * M * v_end ** 2
    speed = np.linalg.norm(roll.rows[-1, kernel.ROW_SLICES["velocity"]])
    return (slide.event[0] - t_star, speed - v_end, slide.state.dissipated - lost), slide, roll


@pytest.mark.parametrize("method, step", CASES)
@pytest.mark.parametrize("backspin", [0.0, 20.0])
def test_a_billiard_shot_skids_then_rolls(method, step, backspin):
    (dt_star, dv, dd), slide, roll = billiard_errors(method, step, backspin=backspin)
    assert abs(dt_star) < 1e-11 and abs(dv) < 1e-11 and abs(dd) < 1e-11
    if backspin == 0.0:   # 2/7 of the kinetic energy
        assert slide.state.dissipated == pytest.approx(2.0 / 7.0 * 0.5 * M * 4.0, rel=1e-11)
    # the rows: sliding ones slip and dissipate; rolling ones carry the dissipated energy on
    slips = slide.rows[:, kernel.ROW_SLIP]
    assert slips[0] == pytest.approx(2.0 + R_BALL * backspin) and np.all(np.diff(slips) < 0)
    assert np.all(roll.rows[:, kernel.ROW_SLIP] == 0.0)
    assert np.all(roll.rows[:, kernel.ROW_DISSIPATED] == slide.state.dissipated)
    total = slide.rows[:, kernel.ROW_ENERGY] + slide.rows[:, kernel.ROW_DISSIPATED]
    assert np.allclose(total, total[0], rtol=1e-12)


def incline_errors(method, step, theta, mu, t_end=0.4):
    """From rest on z = tan(theta) x: rolls at a = 5/7 g sin(theta) iff mu >= 2/7 tan(theta), else
    slips at once and slides at a = g (sin(theta) - mu cos(theta)), its spin growing at
    5 mu g cos(theta) / (2 r). Returns the errors of the distance run down the slope and of the
    angular velocity, and whether it slid."""
    formula = f"{math.tan(theta)!r}*x"
    start = rolling_state(formula, 0.0, 0.0, 0.0, 0.0)
    run = _run(formula, start, method, step, sliding=False, mu=mu, t_end=t_end)
    slid = run.status == "transition"
    if slid:
        assert run.transition == "slip" and run.event[0] == 0.0
        run = _run(formula, run.state, method, step, sliding=True, mu=mu, t_end=t_end)
        a = G * (math.sin(theta) - mu * math.cos(theta))
        spin = 2.5 * mu * G * math.cos(theta) / R_BALL * t_end
    else:
        a = 5.0 / 7.0 * G * math.sin(theta)
        spin = a * t_end / R_BALL
    assert run.status == "ok", run.status
    centre = run.rows[:, kernel.ROW_SLICES["center"]]
    distance = np.linalg.norm(centre[-1] - centre[0])
    omega = np.linalg.norm(run.rows[-1, kernel.ROW_SLICES["omega"]])
    return distance - 0.5 * a * t_end ** 2, omega - spin, slid


@pytest.mark.parametrize("method, step", CASES)
@pytest.mark.parametrize("mu, slides", [(0.1, True), (0.2, False)])
def test_on_an_incline_it_rolls_iff_friction_is_two_sevenths_tan(method, step, mu, slides):
    """(2/7) tan 30° = 0.165."""
    ds, dw, slid = incline_errors(method, step, math.radians(30.0), mu)
    assert slid == slides
    assert abs(ds) < 1e-11 and abs(dw) < 1e-10


CURVED = "0.5*sin(x)*cos(y)"


def curved_start():
    """Sliding at (0.3, -0.2) along the surface, spinning about the vertical."""
    x, y = 0.3, -0.2
    fx, fy = 0.5 * math.cos(x) * math.cos(y), -0.5 * math.sin(x) * math.sin(y)
    vx, vy = 0.8, 0.5
    return _sliding(x, y, (vx, vy, fx * vx + fy * vy), (0.0, 0.0, 6.0))


def curved_error(method, step, t_end=0.4, mu=0.05):
    """max |E + D - E0| / E0 over the rows of a sliding run on a curved surface."""
    run = _run(CURVED, curved_start(), method, step, sliding=True, mu=mu, t_end=t_end)
    assert run.status == "ok" and run.rows[-1, kernel.ROW_SLIP] > 0.1   # (slides throughout)
    total = run.rows[:, kernel.ROW_ENERGY] + run.rows[:, kernel.ROW_DISSIPATED]
    return float(np.max(np.abs(total - total[0])) / abs(total[0])), run


@pytest.mark.parametrize("method, steps, order, bound", [("rk4", (4e-2, 2e-2), 4, 1e-4),
                                                         ("gauss4", (4e-2, 2e-2), 4, 1e-4),
                                                         ("lawson5", (4e-2, 2e-2), 5, 1e-5),
                                                         ("euler", (2e-3, 1e-3), 1, 1e-2)])
def test_on_a_curved_surface_energy_and_dissipation_balance_at_the_methods_order(method, steps, order, bound):
    coarse, run = curved_error(method, steps[0])
    fine, _ = curved_error(method, steps[1])
    assert run.rows[-1, kernel.ROW_DISSIPATED] > 0.05     # friction did work...
    assert fine < bound
    assert coarse / fine == pytest.approx(2.0 ** order, rel=0.3)    # ...and the balance errs at the order


def test_on_a_curved_surface_the_pair_keeps_the_balance_to_its_tolerance():
    loose, run = curved_error("dopri5", 1e-6)
    tight, _ = curved_error("dopri5", 1e-9)
    assert loose < 1e-5 and tight < 1e-8 and tight < loose / 100


@pytest.mark.parametrize("munthe_kaas", [True, False])
def test_the_orientation_follows_omega_while_sliding(munthe_kaas):
    """Without friction (mu = 0) a ball sliding on a plane keeps its velocity and spin: a spin of
    6 rad/s about z turns R by 6 t (Munthe-Kaas: exactly; classic: to its order)."""
    start = _sliding(0.0, 0.0, (1.0, 0.0, 0.0), (0.0, 0.0, 6.0))
    run = segment(PLANE, start, sliding=True, mu=0.0, method="rk4", dt=1e-2, t_end=0.1, munthe_kaas=munthe_kaas)
    assert run.status == "ok" and run.state.x == pytest.approx(0.1, abs=1e-15)
    angle = 0.6
    expected = np.array([[math.cos(angle), -math.sin(angle), 0.0], [math.sin(angle), math.cos(angle), 0.0],
                         [0.0, 0.0, 1.0]])
    assert np.allclose(run.state.R, expected, atol=1e-14 if munthe_kaas else 1e-7)
    assert np.all(run.rows[:, kernel.ROW_DISSIPATED] == 0.0)


def test_a_sliding_start_that_does_not_slip_grips_at_once():
    """A sliding run from a state that rolls (here: at rest, spinning about the normal) stops at
    t = 0 as a grip where rolling needs no more than mu F.N."""
    start = _sliding(0.0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 6.0))
    run = segment(PLANE, start, sliding=True, mu=0.2, method="rk4", dt=1e-2, t_end=0.5)
    assert (run.status, run.transition, run.event, len(run.rows)) == ("transition", "grip", (0.0, 0.0, 0.0), 1)


def test_a_slip_that_turns_about_stops_as_a_slip_and_slides_on():
    """Thrown up a steep incline (mu < 2/7 tan theta) without spin: the slip speed falls to 0 where
    rolling would need more friction than mu F.N, so the slip turns about instead of gripping;
    the next run slides on from zero slip (no grip at its start)."""
    theta, mu = math.radians(30.0), 0.1
    formula = f"{math.tan(theta)!r}*x"
    up = 1.0   # m/s up the slope, along +x
    velocity = up * np.array([math.cos(theta), 0.0, math.sin(theta)])
    run = segment(formula, _sliding(0.0, 0.0, velocity, (0.0, 0.0, 0.0)), sliding=True, mu=mu, method="rk4",
                  dt=1e-2, t_end=1.0)
    assert (run.status, run.transition) == ("transition", "slip")
    # u = c' - r w x N falls at g (sin + mu cos) + 5/2 mu g cos until 0
    t_turn = up / (G * (math.sin(theta) + 3.5 * mu * math.cos(theta)))
    assert run.event[0] == pytest.approx(t_turn, abs=1e-11)
    on = segment(formula, run.state, sliding=True, mu=mu, method="rk4", dt=1e-2, t_end=0.3)
    assert on.status == "ok" and on.rows[-1, kernel.ROW_SLIP] > 0.1


if __name__ == "__main__":
    print("errors of each exact answer (method, dt or rtol):")
    for method, step in CASES:
        for backspin in (0.0, 20.0):
            (dt_star, dv, dd), _, _ = billiard_errors(method, step, backspin=backspin)
            print(f"plane, backspin {backspin:g} rad/s, {method} {step:g}: t* {dt_star:.2e} s, "
                  f"final speed {dv:.2e} m/s, dissipated {dd:.2e} J")
        for mu in (0.1, 0.2):
            ds, dw, slid = incline_errors(method, step, math.radians(30.0), mu)
            print(f"incline 30°, mu {mu}: {'slides' if slid else 'rolls'}, {method} {step:g}: distance {ds:.2e} m, "
                  f"omega {dw:.2e} rad/s")
    for method, steps in (("rk4", (4e-2, 2e-2)), ("gauss4", (4e-2, 2e-2)), ("lawson5", (4e-2, 2e-2)),
                          ("euler", (2e-3, 1e-3)), ("dopri5", (1e-6, 1e-9)), ("dop853", (1e-6, 1e-9))):
        errors = [curved_error(method, step)[0] for step in steps]
        print(f"curved 0.5 sin x cos y, mu 0.05, max |E + D - E0|/E0, {method} {steps[0]:g}, {steps[1]:g}: "
              f"{errors[0]:.2e}, {errors[1]:.2e} (ratio {errors[0] / errors[1]:.3g})")
    sys.exit(0)


@pytest.mark.parametrize("sliding", [False, True])
@pytest.mark.parametrize("munthe_kaas", [True, False])
def test_a_state_goes_into_a_run_and_comes_back(sliding, munthe_kaas):
    """``start_arrays`` then ``stopped_state`` give the state back in every layout; the rolling
    run's v is T omega, T = m r² (7/5 I − N Nᵀ) (docs/design.md §1), where the state rolls."""
    from rollball.geometry import unit_normal
    from rollball.landscape import landscape_for
    from rollball.sliding import start_arrays, stopped_state

    d = landscape_for(CURVED).evaluate(0.3, -0.2)
    normal = unit_normal(d)
    omega = np.array([1.0, -2.0, 3.0])
    rolls = BallState(0.3, -0.2, R_BALL * np.cross(omega, normal), omega, np.eye(3), 0.25)
    p = kernel.parameters(R_BALL, M, G, dissipated=0.0 if sliding else rolls.dissipated)
    arrays = start_arrays(rolls, d, sliding=sliding, munthe_kaas=munthe_kaas, stages=4, rows=2, radius=R_BALL, mass=M)
    assert len(arrays["z"]) == kernel.state_size(munthe_kaas, sliding)
    if not sliding:
        T = M * R_BALL ** 2 * (1.4 * np.eye(3) - np.outer(normal, normal))
        assert np.allclose(arrays["z"][2:5], T @ omega, rtol=1e-14)
    back = stopped_state(arrays["z"], arrays["R"], p, normal)
    assert (back.x, back.y, back.dissipated) == (0.3, -0.2, 0.25)
    assert np.allclose(back.velocity, rolls.velocity, rtol=1e-14) and np.allclose(back.omega, omega, rtol=1e-14)
    assert np.array_equal(back.R, np.eye(3))


def test_the_momentum_about_the_contact_point_is_kept_by_a_grip():
    """A slipping state's v = (2/5) m r² omega + m r N x c' (the angular momentum about the contact
    point): on a plane from v0 = 2 m/s without spin, m r v0 about the axis N x c', which is T omega
    of the rolling ball at 5 v0 / 7."""
    state = _sliding(0.0, 0.0, (2.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    normal = np.array([0.0, 0.0, 1.0])
    v = state.momentum(normal, R_BALL, M)
    assert np.allclose(v, [0.0, M * R_BALL * 2.0, 0.0], rtol=1e-15)
    rolling = np.array([0.0, 5.0 / 7.0 * 2.0 / R_BALL, 0.0])   # omega of the ball rolling at 5 v0 / 7
    assert np.allclose(M * R_BALL ** 2 * 1.4 * rolling, v, rtol=1e-15)


@pytest.mark.parametrize("method", ["rk4", "dopri5", "gauss4"])
@pytest.mark.parametrize("mu", [0.1, 0.2])
def test_a_scene_on_an_incline_slides_or_rolls_as_its_friction_says(method, mu):
    """The same through ``simulate`` and a version-3 scene: from rest on a 30° incline the ball slips
    at t = 0 and slides on where mu < (2/7) tan 30°, else rolls; its speed after 0.5 s is a t."""
    from rollball import Scene, simulate

    theta = math.radians(30.0)
    scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": f"{math.tan(theta)!r}*x",
                             "start": {"x": 0.0, "y": 0.0, "vx": 0.0, "vy": 0.0}, "contact": {"friction": mu},
                             "integrator": {"method": method, "dt": 0.01}, "duration": 0.5})
    traj = simulate(scene)
    slides = mu < 2.0 / 7.0 * math.tan(theta)
    a = G * (math.sin(theta) - mu * math.cos(theta)) if slides else 5.0 / 7.0 * G * math.sin(theta)
    assert [(c.kind, c.time) for c in traj.transitions] == ([("slip", 0.0)] if slides else [])
    assert traj.mode[-1] == ("sliding" if slides else "rolling")
    assert np.linalg.norm(traj.velocity[-1]) == pytest.approx(a * 0.5, abs=1e-11)
    assert (traj.dissipated[-1] > 0.0) == slides
