"""Rolling resistance, spin friction and air through whole hybrid runs on 3-D scenes, against an
independent computation (tests/dissipative_reference.py: another formulation, scipy's DOP853),
itself checked here against the exact answers of docs/design.md §1 ("Dissipation"): every method
converges at its order on the contact point, the transition times and the energy each cause took,
through slips, grips, flights through air, bounces and a rest.

``python tests/test_dissipation_reference.py`` prints the errors."""

import math
import sys
from pathlib import Path

if __name__ == "__main__":   # this checkout's rollball, not an installed one
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
import pytest

from rollball.scene import Air, Ball, Contact, Scene, Start
from rollball.simulation import simulate

import dissipative_reference
from dissipative_reference import CAUSES, reference

G, R_BALL = 9.81, 0.1
AIR = Air(density=12.0, drag_coefficient=0.47)   # ten times air's: its drag plain in a second


def _scene(landscape, start, duration, mass=1.0, air=None, **contact):
    return Scene(landscape=landscape, gravity=G, ball=Ball(radius=R_BALL, mass=mass), start=start,
                 contact=Contact(**{"after_liftoff": "fly", **contact}), duration=duration,
                 **({"air": air} if air else {}))


# -- the reference against exact answers -------------------------------------------------------

def test_the_reference_meets_the_exact_answers():
    v0, c_rr, mu, m = 1.5, 0.05, 0.2, 2.0
    # a plane, rolling from v0: rests after 7 v0 / (5 c_rr g) s and 7 v0² / (10 c_rr g) m, all of
    # ½ (7/5) m v0² taken by the rolling resistance
    ref, by = reference(_scene("0*x", Start(x=0.0, y=0.0, vx=v0), 6.0, m, friction=0.3, rolling_resistance=c_rr),
                        6.0, [6.0])
    (rest,) = ref.transitions
    assert rest.kind == "rest" and rest.time == pytest.approx(7 * v0 / (5 * c_rr * G), abs=1e-12)
    assert rest.x == pytest.approx(7 * v0 ** 2 / (10 * c_rr * G), abs=1e-12)
    np.testing.assert_allclose(by[-1], [0.0, 0.0, 0.7 * m * v0 ** 2, 0.0, 0.0], rtol=0, atol=1e-12)
    # a billiard shot: grips at 2 v0 / ((7 μ − 5 c_rr) g), then rolls to rest
    ref, by = reference(_scene("0*x", Start(x=0.0, y=0.0, vx=v0, omega=(0.0, 0.0, 0.0)), 4.0, m, friction=mu,
                               rolling_resistance=c_rr), 4.0, [4.0])
    t_grip = 2 * v0 / ((7 * mu - 5 * c_rr) * G)
    t_rest = t_grip + 7 * (v0 - mu * G * t_grip) / (5 * c_rr * G)
    assert [(c.kind, c.time) for c in ref.transitions] == [("grip", pytest.approx(t_grip, abs=1e-12)),
                                                           ("rest", pytest.approx(t_rest, abs=1e-12))]
    assert by[-1, 0] == pytest.approx(mu * m * G * v0 * t_grip / 2, abs=1e-12)
    # spinning in place: ω·N falls at (5/2) μ_s g / r
    ref, by = reference(_scene("0*x", Start(x=0.0, y=0.0, vx=0.0, spin=40.0), 1.0, m, friction=0.3,
                               spin_friction=0.02), 1.0, [0.5])
    assert ref.omega[0, 2] == pytest.approx(40.0 - 2.5 * 0.02 * G / R_BALL * 0.5, abs=1e-12)
    # down an incline through air: v = v_t tanh((5/7) g sin θ t / v_t), v_t = √(m g sin θ / k)
    theta, k = math.atan(0.5), AIR.drag_factor(R_BALL)
    ref, by = reference(_scene("-0.5*x", Start(x=0.0, y=0.0, vx=0.0), 3.0, m, AIR, friction=0.3), 3.0, [3.0])
    v_t = math.sqrt(m * G * math.sin(theta) / k)
    assert np.linalg.norm(ref.velocity[0]) == pytest.approx(v_t * math.tanh(5 / 7 * G * math.sin(theta) * 3 / v_t),
                                                            abs=1e-12)
    # falling through air from rest at 10 m over a plane: it falls (v_t² / g) ln cosh(g t / v_t),
    # v_t = √(m g / k), and lands where its centre is r over the plane
    model = dissipative_reference.DissipativeModel(dissipative_reference.Landscape("0*x", {}), R_BALL, m, G, 0.3, 0.0,
                                                   0.0, 0.0, k)
    sol = dissipative_reference._Solution(model)
    start = np.zeros(dissipative_reference.N_STATE)
    start[2] = 10.0
    t, state, landed = dissipative_reference._flight(sol, 0.0, start, 5.0)
    v_t = math.sqrt(m * G / k)
    t_land = v_t / G * math.acosh(math.exp((10.0 - R_BALL) * G / v_t ** 2))
    assert landed and t == pytest.approx(t_land, abs=1e-12)
    assert -state[5] == pytest.approx(v_t * math.tanh(G * t_land / v_t), abs=1e-11)
    assert state[15] == pytest.approx(m * G * (10.0 - R_BALL) - 0.5 * m * state[5] ** 2, abs=1e-11)   # the air's


# -- RollBall against the reference ------------------------------------------------------------

SCENES = {
    # a tilted bowl thrown sideways, all three on: slips at 0.470 s (spinning about N at 0, which
    # the static spin couple holds while the ball slides over the curving surface) and grips at 1.108 s
    "bowl": (_scene("0.5*x^2 + 0.3*y^2 + 0.1*x*y", Start(x=-0.1, y=0.2, vx=1.2, vy=-0.3), 1.3, air=AIR,
                    friction=0.1, rolling_resistance=0.02, spin_friction=0.03), 1.3),
    # a smooth step-down with side spin: slips at 0.188 s, lifts off at 0.220 s, flies through air,
    # lands at 0.369 s and bounces 11 times (e = 0.6)
    "step": (_scene("-0.2*(1 + tanh(5*x)) + 0.01*y", Start(x=-0.6, y=0.0, vx=2.0, vy=0.1, spin=2.0), 0.6, air=AIR,
                    friction=0.3, restitution=0.6, rolling_resistance=0.02, spin_friction=0.04), 0.6),
    # a tilted well: rolls to a stop at about 4.2 s, spins in place and rests at 4.652 s
    "well": (_scene("0.4*x^2 + 0.25*y^2 + 0.05*x*y", Start(x=0.5, y=-0.4, vx=-0.3, vy=0.5, spin=3.0), 6.0,
                    air=AIR, friction=0.5, rolling_resistance=0.06, spin_friction=0.02), 6.0),
    # a billiard shot in a bowl, no spin: both couples static at the start, the rolling couple's turning
    # the ball at once (μ > c_rr) while the spin couple holds ω·N at 0; grips at 0.323 s
    "billiard": (_scene("0.3*x^2 + 0.2*y^2 - 0.05*x*y", Start(x=-0.6, y=0.3, vx=1.5, vy=0.4, omega=(0.0, 0.0, 0.0)),
                        2.0, air=AIR, friction=0.2, rolling_resistance=0.03, spin_friction=0.05), 2.0),
}
KINDS = {"bowl": ["slip", "grip"], "step": ["slip", "liftoff"] + ["landing"] * 12, "well": ["rest"],
         "billiard": ["grip"]}
SPACING = 0.02   # the compared rows: a multiple of every step below
# method -> (order, three steps)
FIXED = {"rk4": (4, (0.01, 0.005, 0.0025)), "lawson5": (5, (0.02, 0.01, 0.005)),
         "gauss4": (4, (0.01, 0.005, 0.0025)), "gauss6": (6, (0.02, 0.01, 0.005))}


def _errors(name, method, **options):
    """The largest distance of the contact point from the reference's on the compared rows (up to
    0.05 s before a rest), the largest error of a transition's time and of the energy a cause
    took (at the last compared row), and the transitions' kinds."""
    scene, t_end = SCENES[name]
    grid = np.round(np.arange(0.0, t_end + 1e-9, SPACING), 10)
    ref, by = reference(scene, t_end, grid)
    rests = [c.time for c in ref.transitions if c.kind == "rest"]
    keep = grid < (rests[0] - 0.05 if rests else math.inf)
    traj = simulate(scene, method=method, t_end=t_end, **options)
    rows = np.array([np.flatnonzero(np.abs(traj.t - t) < 1e-9)[0] for t in grid[keep]])
    place = float(np.max(np.linalg.norm(traj.contact[rows] - ref.contact[keep], axis=1)))
    kinds = [c.kind for c in traj.transitions]
    times = max(abs(a.time - b.time) for a, b in zip(traj.transitions, ref.transitions))
    energy = max(abs(traj.dissipated_by[cause][rows[-1]] - by[keep][-1, k]) for k, cause in enumerate(CAUSES))
    return np.array([place, times, energy]), kinds


@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("method", FIXED)
def test_every_fixed_step_method_converges_at_its_order(name, method):
    """Three halvings: the contact point, the transitions' times and the energy the causes took
    fall at the method's order (fitted over the last halving, to within 1.2: the error constants
    of the transitions' times vary between steps; the finest errors below 1e-8 m and s)."""
    order, steps = FIXED[method]
    errors = []
    for dt in steps:
        e, kinds = _errors(name, method, dt=dt)
        assert kinds == KINDS[name]
        errors.append(e)
    errors = np.array(errors)
    assert np.all(errors[-1] < 1e-8), errors
    # (a figure already at the reference's floor, 1e-12, shows no order)
    fitted = np.log2(errors[1] / errors[2])
    assert np.all((fitted > order - 1.2) | (errors[2] < 1e-12)), (errors, fitted)


@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("method, rtol, bound", [("dopri5", 1e-10, 1e-8), ("dop853", 1e-12, 1e-10)])
def test_the_pairs_meet_the_reference_at_a_tight_tolerance(name, method, rtol, bound):
    e, kinds = _errors(name, method, rtol=rtol, atol=rtol, dt=1e-3, record_dt=SPACING)
    assert kinds == KINDS[name]
    assert np.all(e < bound), e


def test_a_grip_the_pairs_pass_beside_is_placed_where_the_slip_reaches_zero():
    """A slip that falls almost along a line while friction only just beats the pull: near 0 its part
    across the pull relaxes far faster than it falls, and a pair's step carries it round 0. The grip
    is where the slip at the step's start reaches 0 at the relaxed rate (``events.grip_ahead``), not
    where the step's slip came closest to 0 or crossed the plane of its start (measured before:
    dop853 at rtol 1e-10 2.9e-7 s early, gauss4's stretch at dt 0.0025 2.5e-8 s, each with a warning)."""
    scene = _scene("0.5*exp(-x^2)", Start(x=-1.2, y=0.05, vx=4.0, vy=0.1, spin=1.0), 1.2, air=AIR, friction=0.4,
                   restitution=0.3, rolling_resistance=0.02, spin_friction=0.05)
    ref, _ = reference(scene, 1.2, [0.0])
    assert [c.kind for c in ref.transitions] == ["slip", "grip"]
    for options in ({"method": "dop853", "rtol": 1e-10, "atol": 1e-10, "dt": 1e-3}, {"method": "gauss4", "dt": 0.0025}):
        traj = simulate(scene, **options)
        assert [c.kind for c in traj.transitions] == ["slip", "grip"] and traj.warnings() == [], options
        assert abs(traj.transitions[1].time - ref.transitions[1].time) < 1e-9, options


if __name__ == "__main__":
    for name in SCENES:
        print(name, [(c.kind, round(c.time, 9)) for c in reference(*SCENES[name], [0.0]).transitions])
        for method, (order, steps) in FIXED.items():
            cells = [f"{dt:g}: " + " ".join(f"{v:.1e}" for v in _errors(name, method, dt=dt)[0]) for dt in steps]
            print(f"  {method:8s}", "  ".join(cells))
        for method, rtol in (("dopri5", 1e-10), ("dop853", 1e-12)):
            print(f"  {method:8s} {rtol:g}:", " ".join(f"{v:.1e}" for v in _errors(
                name, method, rtol=rtol, atol=rtol, dt=1e-3, record_dt=SPACING)[0]))
    print(dissipative_reference.__name__, "ok")
