"""Every method converges at its order through slips that begin from rolling, grips, lift-offs
and landings on 3-D scenes, measured against the independent reference (tests/hybrid_reference.py).

Fixed-step methods: the largest error of the centre and of the contact point at the common
recorded times (multiples of SPACING), and each transition's time error, fitted against dt over
four step sizes (three halvings; the points above the reference's floor, at least three) chosen
where the error is well above the reference's (~1e-13)
and the steps resolve the scene (measured with friction null on the drop, where the run has no
slip: the fitted orders are the methods'). Expected: euler 1, rk4 4, gauss4 4, lawson5 5, gauss6 6,
within ORDER_SLACK; the transitions the same kinds in the same order as the reference's (no
invented slips), at strictly increasing times. Adaptive pairs: the error falls with the tolerance.
``python tests/test_hybrid_convergence.py`` prints the table."""

import functools
import math
import sys
import time
from pathlib import Path

if __name__ == "__main__":   # this checkout's rollball, not an installed one
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
import pytest

from rollball import Scene, simulate
from rollball.modes import Change
from rollball.scene import Contact, Start

from hybrid_reference import reference

SPACING = 0.04      # s: the common recorded times (multiples of the longest step where that is longer)
POSITION_FLOOR = 2e-12   # m: errors below this may be the reference's (its own about 1e-13 m); not fitted
TIME_FLOOR = 5e-13       # s: likewise for a transition's time (the reference's about 1e-13 s)
ORDER_SLACK = 0.6

# name -> (scene, t_end); the reference's transitions in the comments
SCENES = {
    # a steep tilted bowl thrown sideways: slips from rolling at 0.276 s (in 3-D), grips at 0.753 s
    "bowl": (Scene(landscape="1.5*x^2 + 0.9*y^2 + 0.3*x*y",
                   start=Start(x=-0.1, y=0.1, vx=1.2, vy=-0.6), contact=Contact(friction=0.2)), 0.9),
    # a smooth step-down with a sideways tilt and spin: slips from rolling at 0.177 s, lifts off at
    # 0.207 s, lands at 0.375 s (sliding: no restitution), grips at 0.388 s
    "drop": (Scene(landscape="-0.2*(1 + tanh(5*x)) + 0.01*y",
                   start=Start(x=-0.6, y=0.0, vx=2.0, vy=0.1, spin=2.0),
                   contact=Contact(friction=0.3, restitution=0.0)), 0.5),
}
# Both with friction null (the bowl only rolls; the drop rolls, flies and lands): the same fits,
# with the same steps, pass there on the code of 2026-11-28, so they measure each method's order
# where its contact modes are right.
SCENES["bowl_rolls"] = (Scene(landscape="1.5*x^2 + 0.9*y^2 + 0.3*x*y",
                              start=Start(x=-0.1, y=0.1, vx=1.2, vy=-0.6),
                              contact=Contact(friction=None)), 0.9)
SCENES["drop_rolls"] = (Scene(landscape="-0.2*(1 + tanh(5*x)) + 0.01*y",
                              start=Start(x=-0.6, y=0.0, vx=2.0, vy=0.1, spin=2.0),
                              contact=Contact(friction=None, restitution=0.0)), 0.5)
REFERENCE_KINDS = {"bowl": ["slip", "grip"], "drop": ["slip", "liftoff", "landing", "grip"],
                   "bowl_rolls": [], "drop_rolls": ["liftoff", "landing"]}

# method -> (order, step sizes); the bowl's motion is slower and smoother than the drop's, so
# its steps are twice as long (gauss6: 1.5 times) to keep its errors above the floors
FIXED = {
    "euler": (1, (2e-4, 1e-4, 5e-5, 2.5e-5)),
    "rk4": (4, (1e-2, 5e-3, 2.5e-3, 1.25e-3)),
    "gauss4": (4, (1e-2, 5e-3, 2.5e-3, 1.25e-3)),
    "lawson5": (5, (2e-2, 1e-2, 5e-3, 2.5e-3)),
    "gauss6": (6, (4e-2, 2e-2, 1e-2, 5e-3)),
}
LONGER = {"bowl": {"rk4": 2, "gauss4": 2, "lawson5": 2, "gauss6": 1.5}}
LONGER["bowl_rolls"] = LONGER["bowl"]


def steps_of(name, method):
    k = LONGER.get(name, {}).get(method, 1)
    return tuple(k * h for h in FIXED[method][1])


ADAPTIVE = ("dopri5", "dop853")
TOLERANCES = (1e-6, 1e-8, 1e-10)


@functools.lru_cache(maxsize=None)
def measure(name, method, step):
    """Run ``method`` on scene ``name`` (``step``: dt, or rtol = atol for the pairs) and measure it
    against the reference: a dict with the centre and contact errors (m, largest at the common
    times), the transitions' kinds and times, their time errors (s; None where the kinds differ
    from the reference's), the run's status and CPU time."""
    scene, t_end = SCENES[name]
    spacing = SPACING if method in ADAPTIVE else max(SPACING, steps_of(name, method)[0])
    t0 = time.process_time()
    if method in ADAPTIVE:
        run = simulate(scene, method=method, rtol=step, atol=step, t_end=t_end, record_dt=spacing)
    else:
        run = simulate(scene, method=method, dt=step, t_end=t_end,
                       record_every=int(round(spacing / step)))
    cpu = time.process_time() - t0
    t = run.t
    on_grid = np.abs(t - np.round(t / spacing) * spacing) < 1e-12
    ref = reference(scene, t_end, t[on_grid])
    kinds = [c.kind for c in run.transitions]
    ref_kinds = [c.kind for c in ref.transitions]
    times = [c.time for c in run.transitions]
    time_errors = ([abs(a - b.time) for a, b in zip(times, ref.transitions)]
                   if kinds == ref_kinds else None)
    return {
        "centre": float(np.max(np.linalg.norm(run.center[on_grid] - ref.center, axis=1))),
        "contact": float(np.max(np.linalg.norm(run.contact[on_grid] - ref.contact, axis=1))),
        "kinds": kinds, "ref_kinds": ref_kinds, "times": times, "time_errors": time_errors,
        "status": str(run.status), "message": run.message, "rows": int(on_grid.sum()),
        "reached": float(t[-1]), "cpu": cpu,
        "warned": run.transition_check is not None and not run.transition_check.converged,
    }


def fitted_order(steps, errors, floor):
    """The least-squares slope of log(error) against log(step) over the points above ``floor``,
    and how many there were."""
    pts = [(math.log(h), math.log(e)) for h, e in zip(steps, errors) if e is not None and e > floor]
    if len(pts) < 2:
        return float("nan"), len(pts)
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0]), len(pts)


def position_errors(name, method):
    steps = steps_of(name, method)
    return steps, [max(measure(name, method, h)["centre"], measure(name, method, h)["contact"])
                   for h in steps]


def _order_ok(method, p):
    order = FIXED[method][0]
    if method == "euler":   # first order: its constant is large and the fit looser
        return 0.6 <= p <= 1.5
    return abs(p - order) <= ORDER_SLACK


CASES = [(name, method) for name in SCENES for method in FIXED]
WITH_TRANSITIONS = [(name, method) for name, method in CASES if REFERENCE_KINDS[name]]


def test_the_reference_scenes_slip_grip_fly_and_land():
    for name, (scene, t_end) in SCENES.items():
        assert [c.kind for c in reference(scene, t_end, [0.0]).transitions] == REFERENCE_KINDS[name]


@pytest.mark.parametrize("name, method", CASES)
def test_fixed_step_transitions_are_the_references(name, method):
    """Every step size: the run reaches its end, with the reference's transitions (no invented
    slips, none missing) at strictly increasing times."""
    for h in steps_of(name, method):
        m = measure(name, method, h)
        assert m["status"] == "ok", f"dt {h}: {m['message']}"
        assert m["kinds"] == m["ref_kinds"], f"dt {h}: {m['kinds']} (reference {m['ref_kinds']})"
        assert all(b > a for a, b in zip(m["times"], m["times"][1:])), f"dt {h}: {m['times']}"


ROLLS = [(name, method) for name, method in CASES if name.endswith("_rolls")]
SLIPS = [(name, method) for name, method in CASES if not name.endswith("_rolls")]


@pytest.mark.parametrize("name, method", ROLLS)
def test_fixed_step_positions_converge_at_the_methods_order_where_nothing_slips(name, method):
    steps, errors = position_errors(name, method)
    p, n = fitted_order(steps, errors, POSITION_FLOOR)
    assert n >= 3, f"errors {errors}: below the reference's floor"
    assert _order_ok(method, p), f"fitted order {p:.2f} (expected {FIXED[method][0]}); errors {errors}"


# Where the ball slips and grips, the fitted orders measured are 3.3-4.6 (rk4, gauss4), 4.5-4.6
# (lawson5) and 4.9-5.9 (gauss6): the stiff stretches are dop853's (docs/design.md §8), the rest the
# method's; the coarsest steps are not yet in the asymptotic range everywhere.
SLIP_SLACK = 1.1


@pytest.mark.parametrize("name, method", SLIPS)
def test_fixed_step_positions_converge_at_about_the_methods_order_through_slips_and_grips(name, method):
    """Through a slip that begins from rolling in 3-D and a grip, every fixed-step method
    converges at about its order (before the stiff stretches were taken apart, their errors grew
    as the step shrank), and at the shortest step the error is below 1 nm (euler: its order)."""
    steps, errors = position_errors(name, method)
    p, n = fitted_order(steps, errors, POSITION_FLOOR)
    assert n >= 3, f"errors {errors}: below the reference's floor"
    if method == "euler":
        assert _order_ok(method, p), f"fitted order {p:.2f}; errors {errors}"
    else:
        assert p >= FIXED[method][0] - SLIP_SLACK, f"fitted order {p:.2f}; errors {errors}"
        assert errors[-1] <= 1e-9, errors


@pytest.mark.parametrize("name, method", [case for case in WITH_TRANSITIONS if case in ROLLS])
def test_fixed_step_transition_times_converge_at_the_methods_order_where_nothing_slips(name, method):
    order, steps = FIXED[method][0], steps_of(name, method)
    measured = [measure(name, method, h) for h in steps]
    for h, m in zip(steps, measured):
        assert m["time_errors"] is not None, f"dt {h}: {m['kinds']} (reference {m['ref_kinds']})"
    largest = [max(m["time_errors"]) for m in measured]
    p, n = fitted_order(steps, largest, TIME_FLOOR)
    assert n >= 2, f"errors {largest}: below the reference's floor"
    if n >= 3:
        assert _order_ok(method, p), f"fitted order {p:.2f} over {n} points; errors {largest}"
    else:
        assert p >= (0.6 if method == "euler" else order - ORDER_SLACK), f"fitted order {p:.2f}; errors {largest}"


@pytest.mark.parametrize("name, method", [case for case in WITH_TRANSITIONS if case in SLIPS])
def test_fixed_step_transition_times_converge_at_the_methods_order_through_slips_and_grips(name, method):
    """Slips that begin from rolling in 3-D, lift-offs, landings and grips: the largest transition
    time error falls at the method's order between the two shortest steps whose errors are above
    the reference's floor (the asymptotic end: the coarsest step is not yet asymptotic for gauss6 on
    the bowl, order 3.1 from 0.06 to 0.03 and 6.5 from 0.03 to 0.015, and the finest errors of the
    higher orders reach the floor). Before the slips' stiff stretches
    began and ended where the slip's relative rate is bounded independently of the step
    (``loops.slip_stiff``), rk4's and gauss4's fell at order 2-3 on the bowl and stopped near 1e-11 s
    on the step-down."""
    steps = steps_of(name, method)
    measured = [measure(name, method, h) for h in steps]
    for h, m in zip(steps, measured):
        assert m["time_errors"] is not None, f"dt {h}: {m['kinds']} (reference {m['ref_kinds']})"
    largest = [max(m["time_errors"]) for m in measured]
    above = [(h, e) for h, e in zip(steps, largest) if e > TIME_FLOOR][-2:]
    p, n = fitted_order([h for h, _ in above], [e for _, e in above], TIME_FLOOR)
    assert n >= 2, f"errors {largest}: below the reference's floor"
    assert _order_ok(method, p), f"fitted order {p:.2f} over {n} points; errors {largest}"


@pytest.mark.parametrize("name, method", [case for case in WITH_TRANSITIONS if case in SLIPS])
def test_fixed_step_transition_times_are_right_or_the_run_says_so(name, method):
    """At every step size each transition is within 1e-6 s of the reference's (euler: 1e-3 s;
    measured: at most 2.8e-7 s, euler 8.1e-4 s), or the run's transition check says its
    transitions are not converged."""
    bound = 1e-3 if method == "euler" else 1e-6
    for h in steps_of(name, method):
        m = measure(name, method, h)
        assert m["time_errors"] is not None, f"dt {h}: {m['kinds']} (reference {m['ref_kinds']})"
        assert max(m["time_errors"]) <= bound or m["warned"], f"dt {h}: {m['time_errors']}, no warning"


def test_the_slips_stiff_stretches_keep_rk4s_order_on_the_grip():
    """Just after the bowl's slip begins (|u| growing from 0) and before its grip (|u| falling to 0
    while B pulls across it) the friction's direction changes ever faster: the fixed steps hand
    the steps where the slip changes by as much as itself within SLIP_TIME sqrt(r/g), or turns
    faster than 1/sqrt(r/g), to the stiff pair (``loops.slip_stiff``). With |u| < a h the only
    test, where the stretches began and ended moved with the step, and rk4's grip time fell at
    order about 2 (2.1e-8 s off at dt 0.003). Measured now: 1.1e-10, 8.1e-12, 5.6e-13 s at dt
    0.004, 0.002, 0.001 (order 3.8), the centre and contact 7.5e-10, 4.5e-11, 2.8e-12 m (order 4.0)."""
    steps = (0.004, 0.002, 0.001)
    measured = [measure("bowl", "rk4", h) for h in steps]
    grips = [m["time_errors"][-1] for m in measured]
    positions = [max(m["centre"], m["contact"]) for m in measured]
    assert all(m["kinds"] == m["ref_kinds"] for m in measured)
    assert grips[1] <= 5e-11 and fitted_order(steps, grips, TIME_FLOOR)[0] >= 3.4, grips
    assert fitted_order(steps, positions, POSITION_FLOOR)[0] >= 3.6 and positions[2] <= 1e-11, positions
    # the classic scheme's stretches are the mode machine's (``ModeMachine._stiff``, from the grid
    # rows): its grips the same (measured: within 1e-13 s of the Munthe-Kaas runs')
    scene, t_end = SCENES["bowl"]
    grip = reference(scene, t_end, [0.0]).transitions[-1].time
    classic = [simulate(scene, method="rk4", munthe_kaas=False, dt=h, t_end=t_end) for h in steps]
    assert all([c.kind for c in run.transitions] == measured[0]["ref_kinds"] for run in classic)
    grips = [abs(run.transitions[-1].time - grip) for run in classic]
    assert grips[1] <= 5e-11 and fitted_order(steps, grips, TIME_FLOOR)[0] >= 3.4, grips


def test_a_slips_stretches_are_taken_at_the_slip_tolerance_where_no_couple_can_stop_the_ball(monkeypatch):
    """Without rolling resistance and spin friction the stiff stretches are a slip's, taken at
    SLIP_TOLERANCE (10⁻¹²): the bowl's grip moves by less than 10⁻¹² s from the stretches at
    STIFF_TOLERANCE (1.6·10⁻¹³ and 3.6·10⁻¹³ measured, both within 6·10⁻¹³ s of the reference's),
    for a fifth fewer evaluations (8 361 against 10 798 at rk4's dt 0.001; before the slip's
    direction was taken on the slow motion to first order, 14 690 against 23 659 and a move of
    10⁻¹⁴ s); with either couple the stretches stay at STIFF_TOLERANCE (a rest after a slow turning
    point is ill-conditioned)."""
    from rollball import mode_machine
    from rollball.scene import Contact as C

    assert mode_machine.stiff_tolerance(C(friction=0.2)) == mode_machine.SLIP_TOLERANCE == 1e-12
    assert mode_machine.stiff_tolerance(C(friction=0.2, rolling_resistance=0.01)) == mode_machine.STIFF_TOLERANCE
    assert mode_machine.stiff_tolerance(C(friction=0.2, spin_friction=0.01)) == mode_machine.STIFF_TOLERANCE == 1e-13
    scene, t_end = SCENES["bowl"]
    grip = reference(scene, t_end, [0.0]).transitions[-1].time
    for munthe_kaas in (True, False):   # (the kernel's stretches; the mode machine's)
        loose = simulate(scene, method="rk4", munthe_kaas=munthe_kaas, dt=0.001, t_end=t_end)
        with monkeypatch.context() as patched:
            patched.setattr(mode_machine, "SLIP_TOLERANCE", mode_machine.STIFF_TOLERANCE)
            tight = simulate(scene, method="rk4", munthe_kaas=munthe_kaas, dt=0.001, t_end=t_end)
        assert [c.kind for c in loose.transitions] == [c.kind for c in tight.transitions] == ["slip", "grip"]
        assert abs(loose.transitions[-1].time - tight.transitions[-1].time) < 1e-12
        assert abs(loose.transitions[-1].time - grip) < 1e-11
        assert loose.evaluations < 0.8 * tight.evaluations, (loose.evaluations, tight.evaluations)


@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("method", ADAPTIVE)
def test_adaptive_error_falls_with_the_tolerance(name, method):
    measured = [measure(name, method, tol) for tol in TOLERANCES]
    for tol, m in zip(TOLERANCES, measured):
        assert m["status"] == "ok", f"rtol {tol}: {m['message']}"
        assert m["kinds"] == m["ref_kinds"], f"rtol {tol}: {m['kinds']} (reference {m['ref_kinds']})"
    errors = [max(m["centre"], m["contact"]) for m in measured]
    assert all(b < a / 10.0 for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] <= 1e-8, errors
    assert max(measured[-1]["time_errors"], default=0.0) <= 1e-8, measured[-1]["time_errors"]


@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("method", ADAPTIVE)
def test_each_adaptive_transition_is_within_what_its_tolerance_allows(name, method):
    """Each transition is within LOOSE_FACTOR times rtol sqrt(r/g) of the reference's (the time its
    tolerance allows; measured: at most 53 times), and no run warns. dopri5's grip on the bowl was
    3.9e-4 s late at rtol 1e-6 and 8.7e-6 s at 1e-8 (about 3 900 and 87 times that time): its slip
    passed beside 0 step after step, swinging from side to side for 0.4 ms, before a step crossed
    it; the transition check flagged it "loose". A pair's step whose slip speed rises where friction
    could hold the slip now grips where the slip passes closest to 0 (``events.passed_beside``):
    2.1e-6 and 2.6e-8 s."""
    from rollball.transition_check import LOOSE_FACTOR, MOVE_FLOOR

    scene = SCENES[name][0]
    unit = math.sqrt(scene.ball.radius / scene.gravity)
    for tol in TOLERANCES:
        m = measure(name, method, tol)
        allowed = LOOSE_FACTOR * max(MOVE_FLOOR, tol * unit)
        assert max(m["time_errors"], default=0.0) <= allowed and not m["warned"], (tol, m["time_errors"])


@pytest.mark.parametrize("method", ADAPTIVE)
def test_the_pairs_grip_on_the_bowl_within_their_tolerance_at_a_loose_one(method):
    """At rtol 1e-4 dopri5 took the bowl's slip past its 0 without a grip at all (the run ended
    sliding), and dop853 took the last 50 ms of the slip in one step and gripped at its end 1e-2 s
    late, 0.039 m/s of slip left. Now a step that passes beside the zero grips where it passes
    closest (``events.passed_beside``), and a grip that leaves a slip the step did not resolve is
    taken again with a shorter step (``loops.grip_left``): each grip within what the tolerance allows
    (LOOSE_FACTOR rtol sqrt(r/g): measured 0.3 and 14 times rtol sqrt(r/g)), with no warning, and the
    slip left behind on gripping at most sqrt(rtol g r), below which a slip is slow to the pairs
    (``loops.slow_slip``)."""
    from rollball.transition_check import LOOSE_FACTOR

    scene, t_end = SCENES["bowl"]
    grip = reference(scene, t_end, [0.0]).transitions[-1]
    run = simulate(scene, method=method, rtol=1e-4, atol=1e-4, t_end=t_end, record_dt=None)
    assert [c.kind for c in run.transitions] == [Change.SLIP, Change.GRIP], run.transitions
    unit = math.sqrt(scene.ball.radius / scene.gravity)
    assert abs(run.transitions[-1].time - grip.time) < LOOSE_FACTOR * 1e-4 * unit and run.warnings() == []
    at = np.flatnonzero(run.t == run.transitions[-1].time)[-1]
    # (measured: 1.7e-3 and 7.7e-3 m/s; at rtol 1e-6, 2.1e-5 and 3.7e-6)
    assert run.slip_speed[at] <= math.sqrt(1e-4 * scene.gravity * scene.ball.radius)
    assert np.all(run.slip_speed[at + 1:] == 0.0) and np.all(run.mode[at + 1:] == "rolling")


# A shallower bowl thrown sideways, not one of SCENES (nor their steps): a rolling start there needs
# more friction than μ F_n, so the ball slides from t = 0 (a slip at 0, which the reference starts in)
# and grips at 0.7285 s with |B| well below its friction's rate.
THROWN = (Scene(landscape="0.5*x^2 + 0.3*y^2 + 0.1*x*y", start=Start(x=0.6, y=-0.4, vx=0.3, vy=1.6),
                contact=Contact(friction=0.1)), 0.8)
GRIP_TOLERANCES = (1e-7, 3e-8, 1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11)


@pytest.mark.parametrize("method", ADAPTIVE)
def test_the_pairs_grips_are_within_what_every_tolerance_allows(method):
    """At every tolerance from 1e-7 to 1e-11 the grip is within LOOSE_FACTOR rtol sqrt(r/g) of the
    reference's (the time the tolerance allows), with no warning. A located grip that leaves more
    slip than GRIP_SLIP rtol sqrt(g r) is taken again with a shorter step (``loops.grip_slip``):
    while it could leave up to sqrt(rtol g r) (``loops.slow_slip``), dop853 at rtol 1e-10 left
    1.6e-6 m/s here and gripped 4.4e-8 s late (about 4 400 times rtol sqrt(r/g); the transition check
    said so). Measured now: dop853 at most 11 times rtol sqrt(r/g) (0.2 below rtol 1e-7), dopri5 at
    most 84 (at 1e-7; its grips are as before, none of them left more than that slip)."""
    from rollball.transition_check import LOOSE_FACTOR

    scene, t_end = THROWN
    grip = reference(scene, t_end, [0.0]).transitions[0]
    assert grip.kind == "grip"
    unit = math.sqrt(scene.ball.radius / scene.gravity)
    errors = []
    for tol in GRIP_TOLERANCES:
        run = simulate(scene, method=method, rtol=tol, atol=tol, t_end=t_end, record_dt=None)
        assert [(c.kind, c.time) for c in run.transitions][:1] == [(Change.SLIP, 0.0)], run.transitions
        assert [c.kind for c in run.transitions[1:]] == [Change.GRIP] and run.warnings() == [], (tol, run.message)
        errors.append(abs(run.transitions[1].time - grip.time) / (tol * unit))
    assert max(errors) <= LOOSE_FACTOR, errors


def _table():
    lines = []
    for name in SCENES:
        ref_kinds = REFERENCE_KINDS[name]
        lines.append(f"{name}: reference {' '.join(ref_kinds)}")
        lines.append(f"  {'method':8s} {'step':>8s} {'position':>9s} {'t error':>9s}  status, transitions")
        for method in list(FIXED) + list(ADAPTIVE):
            steps = steps_of(name, method) if method in FIXED else TOLERANCES
            for h in steps:
                m = measure(name, method, h)
                err = max(m["centre"], m["contact"])
                terr = f"{max(m['time_errors']):9.1e}" if m["time_errors"] else "        -"
                kinds = "same" if m["kinds"] == ref_kinds else " ".join(m["kinds"])
                lines.append(f"  {method:8s} {h:8.2e} {err:9.1e} {terr}  {m['status']}, {kinds}")
            if method in FIXED:
                p, _ = fitted_order(*position_errors(name, method), POSITION_FLOOR)
                tl = [max(measure(name, method, h)["time_errors"] or [float("nan")]) for h in steps]
                pt, nt = fitted_order(steps, [None if math.isnan(e) else e for e in tl], TIME_FLOOR)
                lines.append(f"  {method:8s} fitted order: position {p:.2f}, transition times {pt:.2f} "
                             f"({nt} points); expected {FIXED[method][0]}")
    return "\n".join(lines)


if __name__ == "__main__":
    print(_table())


@pytest.mark.parametrize("name", ["bowl", "drop"])
def test_what_is_recorded_does_not_change_the_motion(name):
    """The stiff stretches of a slip's onset and of a grip take the pair's own steps, however many
    grid steps one spans, the rows due between from its dense output (``loops.stiff_step``): a run
    recording every 3rd step has the rows, bit for bit, and the transitions of the same run
    recording every step, its times strictly increasing."""
    scene, t_end = SCENES[name]
    every, third = (simulate(scene, method="rk4", dt=1.25e-3, t_end=t_end, record_every=n) for n in (1, 3))
    assert str(every.status) == str(third.status) == "ok"
    assert [(c.kind, c.time) for c in third.transitions] == [(c.kind, c.time) for c in every.transitions]
    assert np.all(np.diff(every.t) > 0) and np.all(np.diff(third.t) > 0)
    common = np.intersect1d(every.t, third.t)
    assert len(common) >= len(third.t) - len(third.transitions) - 1
    assert np.array_equal(every.contact[np.searchsorted(every.t, common)],
                          third.contact[np.searchsorted(third.t, common)])
