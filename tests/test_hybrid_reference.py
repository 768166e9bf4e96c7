"""The hybrid reference (tests/hybrid_reference.py) checked against exact answers, and RollBall's
dopri5 at rtol = atol = 1e-12 checked against it on four 3-D scenes that slip, grip, fly and land.
``python tests/test_hybrid_reference.py`` prints the numbers."""

import math
import sys
import time
from pathlib import Path

if __name__ == "__main__":   # this checkout's rollball, not an installed one
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
import pytest
from scipy.integrate import quad

from rollball import Scene, simulate
from rollball.scene import Contact, Start

import hybrid_reference
from hybrid_reference import reference

G = 9.81
R_BALL = 0.1

# name -> (scene, t_end); the reference's transitions are given in the comments
SCENES = {
    # a tilted bowl thrown sideways: slips from rolling at 0.398 s, grips at 1.191 s
    "bowl": (Scene(landscape="0.5*x^2 + 0.3*y^2 + 0.1*x*y",
                   start=Start(x=-0.1, y=0.2, vx=1.2, vy=-0.3), contact=Contact(friction=0.1)), 1.3),
    # gentle hills from a rolling start: slips from rolling at 0.646 s (in 3-D)
    "hills": (Scene(landscape="0.3*sin(x)*cos(0.7*y)",
                    start=Start(x=-1.57, y=0.1, vx=0.6, vy=0.3), contact=Contact(friction=0.03)), 0.9),
    # a saddle with side spin: slides from the start, grips at 0.273 s, slips again at 1.089 s
    "saddle": (Scene(landscape="0.2*(x^2 - y^2)",
                     start=Start(x=0.3, y=0.4, vx=0.3, vy=0.5, omega=(8.0, 0.0, 0.0)),
                     contact=Contact(friction=0.2)), 1.2),
    # a smooth step-down: slips at 0.177 s, lifts off at 0.207 s, lands at 0.375 s and bounces
    # (e = 0.6) until a rebound is slower than v_rest at 0.438 s
    "step": (Scene(landscape="-0.2*(1 + tanh(5*x)) + 0.01*y",
                   start=Start(x=-0.6, y=0.0, vx=2.0, vy=0.1, spin=2.0),
                   contact=Contact(friction=0.3, restitution=0.6)), 0.6),
}
EXPECTED_KINDS = {
    "bowl": ["slip", "grip"],
    "hills": ["slip"],
    "saddle": ["grip", "slip"],
    "step": ["slip", "liftoff"] + ["landing"] * 12,
}
RECORD_DT = 0.01


def _grid(t_end, spacing=RECORD_DT):
    return np.arange(0.0, t_end + 0.5 * spacing, spacing)


# -- exact answers ------------------------------------------------------------------------

def billiard_errors(v0=2.0, mu=0.2, backspin=0.0):
    """On a plane, sliding at v0 along x with ω0 = (0, −backspin, 0): grips at
    t* = (v0 + r ω0) / (3.5 μ g) and rolls on at (5 v0 − 2 r ω0) / 7."""
    scene = Scene(landscape="0*x", start=Start(x=0.0, y=0.0, vx=v0, vy=0.0, omega=(0.0, -backspin, 0.0)),
                  contact=Contact(friction=mu))
    t_star = (v0 + R_BALL * backspin) / (3.5 * mu * G)
    ref = reference(scene, 1.5 * t_star, [1.2 * t_star, 1.5 * t_star])
    assert [t.kind for t in ref.transitions] == ["grip"]
    v_end = (5.0 * v0 - 2.0 * R_BALL * backspin) / 7.0
    grip = ref.transitions[0]
    # where: x(t*) = v0 t* − ½ μ g t*²
    x_star = v0 * t_star - 0.5 * mu * G * t_star ** 2
    return (grip.time - t_star, grip.x - x_star,
            float(np.max(np.abs(np.linalg.norm(ref.velocity, axis=1) - v_end))),
            float(np.max(np.abs(ref.omega[:, 1] - v_end / R_BALL))))


def incline_errors(slope, mu):
    """On z = −slope·x from rest: rolls with a = (5/7) g sin θ iff μ ≥ (2/7) tan θ, else slides
    with a = g (sin θ − μ cos θ). Returns the error of the distance along the slope at 0.5 s and
    whether it slipped."""
    theta = math.atan(slope)
    scene = Scene(landscape=f"-{slope}*x", start=Start(x=0.0, y=0.0, vx=0.0, vy=0.0),
                  contact=Contact(friction=mu))
    rolls = mu >= 2.0 / 7.0 * math.tan(theta)
    a = 5.0 / 7.0 * G * math.sin(theta) if rolls else G * (math.sin(theta) - mu * math.cos(theta))
    ts = np.array([0.0, 0.25, 0.5])
    ref = reference(scene, 0.5, ts)
    along = np.linalg.norm(ref.center - ref.center[0], axis=1)
    spin = np.abs(ref.omega[:, 1])
    if rolls:
        spin_exact = a * ts / R_BALL
    else:   # the torque μ F_n r with F_n = m g cos θ: ω̇ = (5/2) μ g cos θ / r
        spin_exact = 2.5 * mu * G * math.cos(theta) * ts / R_BALL
    return (float(np.max(np.abs(along - 0.5 * a * ts ** 2))), float(np.max(np.abs(spin - spin_exact))),
            [t.kind for t in ref.transitions], ref.mode)


CYL = 1.0   # the cylinder's radius


def cylinder_errors(theta0=0.2):
    """A ball rolled from rest at θ0 on top of the cylinder z = sqrt(1 − x²) (no slip) leaves it
    at cos θ = (10/17) cos θ0, with θ̇² = (10/7) g (cos θ0 − cos θ) / (R + r); the time from
    t = ∫ dθ / θ̇. Returns the errors of the lift-off's time, contact x and centre speed."""
    scene = Scene(landscape=f"sqrt({CYL} - x^2)", start=Start(x=CYL * math.sin(theta0), y=0.0),
                  contact=Contact(friction=None))
    rho = CYL + R_BALL
    theta1 = math.acos(10.0 / 17.0 * math.cos(theta0))
    k = 10.0 / 7.0 * G / rho
    # t = ∫ dθ / sqrt(k (cos θ0 − cos θ)); the 1/sqrt singularity at θ0 by θ = θ0 + s²
    t_lift, _ = quad(lambda s: 2.0 * s / math.sqrt(k * (math.cos(theta0) - math.cos(theta0 + s * s)))
                     if s > 0 else 2.0 / math.sqrt(k * math.sin(theta0)),
                     0.0, math.sqrt(theta1 - theta0), epsabs=1e-14, epsrel=1e-14, limit=200)
    t_end = t_lift + 0.02
    ref = reference(scene, t_end, [t_lift])
    kinds = [t.kind for t in ref.transitions]
    lift = ref.transitions[0]
    speed = math.sqrt(k * (math.cos(theta0) - math.cos(theta1))) * rho
    return (lift.time - t_lift, lift.x - CYL * math.sin(theta1),
            float(np.linalg.norm(ref.velocity[0]) - speed), kinds)


@pytest.mark.parametrize("backspin", [0.0, 20.0])
def test_reference_billiard_grips_when_and_where_exact(backspin):
    dt, dx, dv, dw = billiard_errors(backspin=backspin)
    assert abs(dt) < 1e-11 and abs(dx) < 1e-11 and dv < 1e-11 and dw < 1e-10


@pytest.mark.parametrize("slope, mu", [(0.3, 0.2), (0.3, 0.05)])
def test_reference_incline_rolls_or_slides_as_exact(slope, mu):
    distance, spin, kinds, modes = incline_errors(slope, mu)
    assert distance < 1e-12 and spin < 1e-11
    assert kinds == []
    rolls = mu >= 2.0 / 7.0 * slope   # tan θ = slope
    assert set(modes) == ({"rolling"} if rolls else {"sliding"})


def test_reference_cylinder_lifts_off_at_ten_seventeenths():
    dt, dx, dv, kinds = cylinder_errors()
    assert kinds[0] == "liftoff"
    assert abs(dt) < 1e-10 and abs(dx) < 1e-11 and abs(dv) < 1e-11


def test_reference_leaves_at_once_a_surface_that_cannot_hold_the_ball_at_the_start():
    """A start on a crest faster than the surface can hold (F_n < 0): a lift-off at t = 0 and a
    flight, as RollBall has it (held-out scene of 2 December, where the reference slid on glued to
    the surface and gripped 0.368 s in while RollBall flew 0.23 m away); both land and grip at the
    same times (measured: within 3e-15 s, the centre at the end within 8e-13 m)."""
    scene = Scene(landscape="-0.59*(1 + tanh(0.77*5*x)) + 0.18*y",
                  start=Start(x=-0.33, y=-0.19, vx=1.82, vy=-0.31, omega=(-7.5, -7.6, 0.7)),
                  contact=Contact(friction=0.5, restitution=0.0))
    ref = reference(scene, 1.0, [1.0])
    run = simulate(scene, method="dop853", rtol=1e-12, atol=1e-12, t_end=1.0)
    assert [c.kind for c in ref.transitions] == [c.kind for c in run.transitions] == ["liftoff", "landing", "grip"]
    assert ref.transitions[0].time == run.transitions[0].time == 0.0
    for mine, theirs in zip(run.transitions[1:], ref.transitions[1:]):
        assert abs(mine.time - theirs.time) < 1e-12, (mine, theirs)
    assert np.linalg.norm(run.center[-1] - ref.center[0]) < 1e-10


def test_reference_keeps_the_centre_on_its_contact_point():
    """c is integrated, and α carried with it: they stay consistent (c = C(α)) at every segment's end."""
    for name, (scene, t_end) in SCENES.items():
        assert reference(scene, t_end, [0.0]).drift < 1e-12, name


@pytest.mark.parametrize("name", sorted(SCENES))
def test_reference_scenes_do_what_they_are_for(name):
    scene, t_end = SCENES[name]
    ref = reference(scene, t_end, _grid(t_end))
    assert [t.kind for t in ref.transitions] == EXPECTED_KINDS[name]


def threshold_changes(name, onset=1e-9, grip=1e-10):
    """How far the reference moves when the slip speed up to which a slip's onset holds ŝ = B̂
    (1e-8 m/s) and the one where a grip is located (1e-9 m/s) are 10 times smaller: the largest
    change of the centre at the recorded times (m) and of a transition's time (s)."""
    scene, t_end = SCENES[name]
    times = _grid(t_end)
    base = reference(scene, t_end, times)
    saved = hybrid_reference.ONSET_SPEED, hybrid_reference.GRIP_SPEED
    try:
        hybrid_reference.ONSET_SPEED, hybrid_reference.GRIP_SPEED = onset, grip
        other = hybrid_reference.evaluate(hybrid_reference.solve(scene.dumps(), t_end), t_end, times)
    finally:
        hybrid_reference.ONSET_SPEED, hybrid_reference.GRIP_SPEED = saved
    assert [t.kind for t in other.transitions] == [t.kind for t in base.transitions]
    return (float(np.max(np.linalg.norm(other.center - base.center, axis=1))),
            max(abs(a.time - b.time) for a, b in zip(other.transitions, base.transitions)))


@pytest.mark.parametrize("name", ["bowl", "hills"])
def test_reference_does_not_depend_on_its_speed_thresholds(name):
    """DESIGN §12: holding ŝ = B̂ until |u| = 1e-8 m/s is as good as the exact onset."""
    centre, when = threshold_changes(name)
    assert centre < 1e-12 and when < 1e-12


# -- RollBall against the reference -----------------------------------------------------------

def compare(run, ref_scene, t_end, spacing=RECORD_DT):
    """Errors of a RollBall trajectory against the reference at the rows on the common grid
    (multiples of ``spacing``, away from transitions): the largest centre and contact-point
    error (m), and the transitions' time and place errors (s, m) matched in order (None when
    the kinds differ)."""
    t = run.t
    k = np.round(t / spacing)
    on_grid = np.abs(t - k * spacing) < 1e-12 * max(1.0, t_end)
    times = t[on_grid]
    ref = reference(ref_scene, t_end, times)
    centre = float(np.max(np.linalg.norm(run.center[on_grid] - ref.center, axis=1)))
    contact = float(np.max(np.linalg.norm(run.contact[on_grid] - ref.contact, axis=1)))
    kinds = [c.kind for c in run.transitions]
    ref_kinds = [c.kind for c in ref.transitions]
    if kinds != ref_kinds:
        return centre, contact, None, None, kinds, ref_kinds
    when = max((abs(a.time - b.time) for a, b in zip(run.transitions, ref.transitions)), default=0.0)
    where = max((math.hypot(a.x - b.x, a.y - b.y) for a, b in zip(run.transitions, ref.transitions)),
                default=0.0)
    return centre, contact, when, where, kinds, ref_kinds


def dopri5_errors(name, rtol=1e-12):
    scene, t_end = SCENES[name]
    t0 = time.process_time()
    run = simulate(scene, method="dopri5", rtol=rtol, atol=rtol, t_end=t_end, record_dt=RECORD_DT)
    run.provenance["cpu"] = time.process_time() - t0
    return run, compare(run, scene, t_end)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_dopri5_agrees_with_the_reference(name):
    run, (centre, contact, when, where, kinds, ref_kinds) = dopri5_errors(name)
    assert run.status == "ok", run.message
    assert kinds == ref_kinds
    # measured: at most 8.4e-10 m (centre), 9.2e-10 m (contact), 4.0e-10 s and 2.1e-9 m (the step's
    # late bounces); rtol 1e-13 gives 8 times less, so these are dopri5's own errors
    assert centre < 3e-9 and contact < 3e-9
    assert when < 1.5e-9 and where < 6e-9


if __name__ == "__main__":
    print("exact answers (reference − exact):")
    for backspin in (0.0, 20.0):
        dt, dx, dv, dw = billiard_errors(backspin=backspin)
        print(f"  billiard backspin {backspin:4}: grip time {dt:+.1e} s, x {dx:+.1e} m, "
              f"speed {dv:.1e} m/s, spin {dw:.1e} rad/s")
    for slope, mu in ((0.3, 0.2), (0.3, 0.05)):
        distance, spin, kinds, modes = incline_errors(slope, mu)
        print(f"  incline slope {slope} mu {mu}: distance {distance:.1e} m, spin {spin:.1e} rad/s, "
              f"mode {sorted(set(modes))}")
    dt, dx, dv, kinds = cylinder_errors()
    print(f"  cylinder: lift-off time {dt:+.1e} s, x {dx:+.1e} m, speed {dv:+.1e} m/s")
    for name in ("bowl", "hills"):
        centre, when = threshold_changes(name)
        print(f"  {name}: onset and grip speeds 10 times smaller move the centre {centre:.1e} m, "
              f"transitions {when:.1e} s")

    def fmt(v):
        return f"{v:8.1e}" if v is not None else "       -"

    print()
    print(f"{'scene':8s} {'ref CPU':>8s} {'rb CPU':>7s} {'centre':>8s} {'contact':>8s} "
          f"{'t err':>8s} {'x err':>8s}  transitions")
    for name, (scene, t_end) in SCENES.items():
        t0 = time.process_time()
        hybrid_reference.solve(scene.dumps(), t_end)   # uncached: its CPU time
        t1 = time.process_time()
        run, (centre, contact, when, where, kinds, ref_kinds) = dopri5_errors(name)
        t2 = t1 + run.provenance["cpu"]
        same = "same" if kinds == ref_kinds else f"DIFFER: {kinds} vs {ref_kinds}"
        print(f"{name:8s} {t1 - t0:8.2f} {t2 - t1:7.2f} {centre:8.1e} {contact:8.1e} {fmt(when)} "
              f"{fmt(where)}  {same} ({len(ref_kinds)}: {' '.join(ref_kinds[:4])}"
              f"{' …' if len(ref_kinds) > 4 else ''}) status {run.status}")
    sys.exit(0)
