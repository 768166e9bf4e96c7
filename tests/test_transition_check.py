"""Whether a run's changes of contact mode are converged (rollball/transition_check.py, docs/design.md
§1): each slip, grip and lift-off is taken again from a row before it with dt, dt/2 and dt/4
(adaptive: tolerances 100 and 10^4 times tighter), and the run warns where its time does not move
as the method's order says, or where its sequence holds a change the motion does not have."""

import dataclasses
import math
import threading
import types

import numpy as np
import pytest

from rollball import kernel, simulate, simulation, transition_check
from rollball.cli import main
from rollball.examples import EXAMPLES_DIR
from rollball.scene import Ball, Contact, Integrator, Scene, Start
from rollball.simulation import Simulation
from rollball.tableaus import get_method
from rollball.trajectory import ROLLING, SLIDING, SLIP_SPEED, T, Transition
from rollball.transition_check import verdict
from rollball.transition_verdict import CHANGED, CONVERGED, GROWS, LOOSE, NEGLIGIBLE, PLATEAU, Retake, TransitionCheck

G = 9.81
THETA = math.radians(30.0)
INCLINE = f"{math.tan(THETA)!r}*x"
# f'' jumps from 0 to -4 at x = 0: the ball rolls along the flat at 1.5 m/s, reaches the bend at
# t = 0.2 s and slips 8.4 ms later, where F·N has fallen. An explicit step across a jump of the
# curvature errs along the flow by O(h) (docs/design.md §1, the energy check), so the slip's time
# moves with the step and with where the jump falls in it: not at rk4's fourth order.
BEND = "-2*max(x,0)^2"
STEP_DOWN = "-0.2*(1 + tanh(5*x)) + 0.01*y"


def _scene(landscape, *, mu, method="rk4", dt=1e-3, duration=1.0, x=0.0, vx=0.0, vy=0.0, spin=0.0, omega=None):
    return Scene(landscape, ball=Ball(0.1, 1.0), start=Start(x, 0.0, vx, vy, spin, omega),
                 contact=Contact(friction=mu, restitution=0.6, after_liftoff="fly"),
                 integrator=Integrator(method, True, dt), duration=duration)


def _bend(method="rk4", dt=0.004):
    return _scene(BEND, mu=0.03, method=method, dt=dt, duration=0.5, x=-0.3, vx=1.5)


def _options(method):
    return dict(rtol=1e-8, atol=1e-11) if method == "dopri5" else {}


# -- converged: exact transitions, no warning ----------------------------------------------------

@pytest.mark.parametrize("method", ["rk4", "euler", "gauss4", "dopri5"])
def test_a_billiard_shot_grips_where_it_should_and_the_check_agrees(method):
    """Sliding at v0 = 2 m/s without spin on a plane (mu = 0.2): the grip at 2 v0 / (7 mu g),
    placed to round-off by every method (the slip velocity falls linearly)."""
    traj = simulate(_scene("0*x", mu=0.2, method=method, dt=0.01, vx=2.0, omega=(0.0, 0.0, 0.0), duration=0.5),
                    **_options(method))
    t_star = 4.0 / (7 * 0.2 * G)
    assert [c.kind for c in traj.transitions] == ["grip"]
    assert traj.transitions[0].time == pytest.approx(t_star, abs=1e-11)
    check = traj.transition_check
    assert check is not None and check.converged and check.warning() is None
    (retake,) = check.retakes
    assert retake.kind == "grip" and retake.verdict == NEGLIGIBLE
    assert all(t == pytest.approx(t_star, abs=1e-11) for t in retake.times)
    assert retake.start < t_star and len(retake.steps) == 3
    if method != "dopri5":   # the run's dt, halved, halved again
        assert retake.steps == (0.01, 0.005, 0.0025)
    assert traj.warnings() == []


def test_a_method_passed_in_itself_is_taken_again_with_itself():
    """A tableau that is not a registered method (dopri5's main weights as fixed steps, order 5)."""
    method = get_method("dopri5").weights()
    traj = simulate(_scene("0*x", mu=0.2, dt=0.01, vx=2.0, omega=(0.0, 0.0, 0.0), duration=0.5), method=method)
    check = traj.transition_check
    assert check.method == "dopri5-main" and check.order == 5 and check.skipped == 0
    assert [r.verdict for r in check.retakes] == [NEGLIGIBLE] and traj.warnings() == []


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
def test_a_slip_that_turns_about_on_an_incline_is_one_slip_and_not_invented(method):
    """Thrown 1 m/s up a 30° incline without spin (mu = 0.1 < (2/7) tan 30°): the slip speed falls
    to 0 at up / (g (sin + 3.5 mu cos)), where rolling would need more friction, so the slip
    turns about and the ball slides back down: one slip (no transition), the turn among the
    kernel's changes at its exact time, nothing invented."""
    up = 1.0
    scene = _scene(INCLINE, mu=0.1, method=method, dt=0.01, vx=up * math.cos(THETA), omega=(0.0, 0.0, 0.0),
                   duration=0.3)
    run = simulation.Simulation(scene, **_options(method))
    run.advance()
    traj = run.trajectory()
    t_turn = up / (G * (math.sin(THETA) + 3.5 * 0.1 * math.cos(THETA)))
    assert traj.transitions == () and [c.kind for c in run.changes] == ["slip"]
    assert run.changes[0].time == pytest.approx(t_turn, abs=1e-10)
    assert set(traj.mode) == {"sliding"} and traj.transition_check is None
    assert traj.warnings() == []


def test_on_an_incline_rolling_or_slipping_at_once_there_is_nothing_to_retake():
    rolls = simulate(_scene(INCLINE, mu=0.2, duration=0.3))   # mu >= (2/7) tan 30°: rolls on
    assert rolls.transitions == () and rolls.transition_check is None and rolls.warnings() == []
    slips = simulate(_scene(INCLINE, mu=0.1, duration=0.3))   # slips at t = 0: no row before it
    assert [(c.kind, c.time) for c in slips.transitions] == [("slip", 0.0)]
    assert slips.transition_check.retakes == () and slips.transition_check.skipped == 1
    assert slips.warnings() == []


def test_a_slip_and_a_liftoff_off_the_cylinder_are_converged():
    scene = Scene.load(EXAMPLES_DIR / "cylinder.json")
    traj = simulate(dataclasses.replace(scene, contact=Contact(0.3, 0.0, "fly")), dt=0.002)
    assert [c.kind for c in traj.transitions] == ["slip", "liftoff", "landing"]
    check = traj.transition_check
    assert [r.kind for r in check.retakes] == ["slip", "liftoff"]   # (a landing is a flight's root: exact)
    assert check.converged and traj.warnings() == [], check


def test_the_2011_model_and_unchecked_runs_have_no_check():
    glued = simulate(Scene("0*x", start=Start(0.0, 0.0, 1.0, 0.0, 0.0), contact=Contact(None, 0.0, "glued"),
                           duration=0.2))
    assert glued.transition_check is None
    run = Simulation(_bend())
    run.judge_energy = False   # (compare, sweeps and previews run so)
    run.advance()
    assert run.transitions and run.trajectory().transition_check is None


# -- not converged: a real case, and the step-down scene of today's kernel -------------------------

def test_a_slip_just_past_a_jump_of_the_curvature_is_not_converged_with_rk4():
    traj = simulate(_bend())
    assert [c.kind for c in traj.transitions][:2] == ["slip", "liftoff"]
    check = traj.transition_check
    slip = check.retakes[0]
    assert slip.kind == "slip" and slip.verdict in (PLATEAU, GROWS) and slip.start <= 0.2 < slip.time
    first, second = slip.moves
    assert max(first, second) > 1e-6 and first < 2 ** 2.5 * second   # nowhere near 16-fold less each time
    assert check.retakes[1].kind == "liftoff" and check.retakes[1].converged   # (smooth before it)
    (note,) = traj.warnings()
    assert note.startswith(f"the slip at {slip.time:.6g} s moved by {first:.2g} s when the step was halved and by "
                           f"{second:.2g} s when it was halved again (rk4 should move it by about 1/16 as much each "
                           f"time): not converged")
    assert note.endswith("try a smaller step or dopri5")


def test_the_command_line_prints_the_warning(tmp_path, capsys):
    path = tmp_path / "bend.json"
    _bend().save(path)
    assert main(["simulate", str(path)]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    assert "WARNING: the slip at" in line and "not converged" in line


@pytest.mark.parametrize("dt", [0.00125, 0.000625])
def test_a_step_down_run_whose_transitions_are_wrong_says_so(dt):
    """The ball rolls down a smooth step, slips and grips again in 3-D. Whatever the kernel does
    there, a run whose changes of mode are not those of a tight dop853 run (other kinds, or times
    off by more than 1e-6 s) must warn, or its check's first moves must say how far off it is."""
    scene = _scene(STEP_DOWN, mu=0.3, dt=dt, duration=0.8, x=-1.0, vx=1.5, vy=0.1, spin=2.0)
    reference = simulate(scene, method="dop853", rtol=1e-12, atol=1e-15).transitions
    traj = simulate(scene)
    kinds = [c.kind for c in traj.transitions]
    wrong = kinds != [c.kind for c in reference] or any(
        abs(c.time - r.time) > 1e-6 for c, r in zip(traj.transitions, reference))
    if wrong:
        check = traj.transition_check
        if check.converged:   # then each retake's first move says how far the run's time is off
            for retake, right in zip(check.retakes, reference):
                assert abs(retake.times[0] - right.time) <= 3.0 * max(retake.moves[0], 1e-10), retake
        else:
            assert any("not converged" in note or "does not have" in note for note in traj.warnings())


# -- the verdict on ladders of times --------------------------------------------------------------

RK4 = 2 ** (4 - transition_check.SLACK)


@pytest.mark.parametrize("times, expected", [
    ((0.5, 0.5 + 1e-6, 0.5 + 1e-6 + 1e-6 / 16), CONVERGED),         # rk4's 16-fold
    ((0.5, 0.5 + 1e-6, 0.5 + 1e-6 - 1e-6 / 8), CONVERGED),          # 8-fold, the other side
    ((0.5, 0.5 + 1e-6, 0.5 + 1e-6 + 1e-6 / 4), PLATEAU),            # 4-fold: second order
    ((0.5, 0.5 + 1e-6, 0.5 + 1e-6 + 0.9e-6), PLATEAU),              # hardly shrinks
    ((0.5, 0.5 + 1e-7, 0.5 + 1e-7 + 3e-7), GROWS),                  # a finer step moves it more
    ((0.5, 0.5 + 1e-13, 0.5 + 2e-8), GROWS),                        # from round-off to a move
    ((0.5, None, None), CHANGED),
    ((0.5, 0.50001, None), CHANGED),
    ((0.5, 0.5 + 3e-11, 0.5 + 5e-11), NEGLIGIBLE),                   # every move below MOVE_FLOOR
    ((0.5, 0.5 + 1e-6, 0.5 + 1e-6 + 5e-11), CONVERGED),             # the finest move is round-off
])
def test_the_verdict_on_a_ladder(times, expected):
    assert verdict(times, shrink=RK4) == expected


def test_the_verdict_follows_the_order_and_the_adaptive_shrink():
    ladder = (1.0, 1.0 + 1e-5, 1.0 + 1e-5 + 0.5e-5)   # halves: euler's order
    assert verdict(ladder, shrink=2 ** (1 - transition_check.SLACK)) == CONVERGED
    assert verdict(ladder, shrink=RK4) == PLATEAU
    tight = (1.0, 1.0 + 1e-6, 1.0 + 1e-6 + 1e-8)     # 100-fold per tolerances 100 times tighter
    assert verdict(tight, shrink=transition_check.ADAPTIVE_SHRINK) == CONVERGED
    # the same moves, but the first above what the run's tolerance allows: its own error is too large
    allowed = abs(tight[1] - tight[0]) / 2
    assert verdict(tight, shrink=transition_check.ADAPTIVE_SHRINK, allowed=allowed) == LOOSE
    assert verdict((1.0, 1.0 + 1e-6, 1.0 + 1e-6 + 0.5e-6), shrink=transition_check.ADAPTIVE_SHRINK) == PLATEAU
    # adaptive: moves below what the tolerance allows (rtol·√(r/g), 1e-7 s at rtol 1e-6) say nothing
    noise = (1.0, 1.0 + 1e-9, 1.0 + 1e-9 + 1.8e-9)
    assert verdict(noise, shrink=transition_check.ADAPTIVE_SHRINK) == GROWS
    assert verdict(noise, shrink=transition_check.ADAPTIVE_SHRINK, floor=1e-7) == NEGLIGIBLE


def test_the_warning_names_the_transition_its_moves_and_the_steps():
    grip = Retake(1, "grip", 0.74655, 0.72, (0.00125, 0.000625, 0.0003125),
                  (0.74655, 0.74655 + 3.4e-5, 0.74655 + 3.4e-5 + 2e-5), ("grip at 0.74655 s",) * 3, PLATEAU)
    slip = Retake(0, "slip", 0.5448, 0.5412, grip.steps, (0.5448, None, None),
                  ("slip at 0.5448 s", "no change of mode by 0.55 s", "no change of mode by 0.55 s"), CHANGED)
    note = TransitionCheck("rk4", 4, False, (grip,)).warning()
    assert note == ("the grip at 0.74655 s moved by 3.4e-05 s when the step was halved and by 2e-05 s when it was "
                    "halved again (rk4 should move it by about 1/16 as much each time): not converged; try a smaller "
                    "step or dopri5")
    note = TransitionCheck("rk4", 4, False, (slip, grip), unchecked=3).warning()
    assert note.startswith("the slip at 0.5448 s is not there when the step was halved (taken again from t = 0.5412 s: "
                           "no change of mode by 0.55 s): not converged (nor is the grip at 0.74655 s)")
    assert note.endswith("(only the first 2 transitions were taken again)")
    adaptive = TransitionCheck("dopri5", 5, True, (dataclasses.replace(grip, steps=(1e-6, 1e-8, 1e-10)),))
    assert "with tolerances 100 times tighter" in adaptive.warning() and "try tighter tolerances" in adaptive.warning()
    assert TransitionCheck("rk4", 4, False, (dataclasses.replace(grip, verdict=CONVERGED),)).warning() is None


# -- changes the sequence itself shows to be invented ------------------------------------------------

def _rows(times, modes, slips):
    rows = np.zeros((len(times), kernel.ROW_SIZE))
    rows[:, T], rows[:, SLIP_SPEED] = times, slips
    return rows, np.array(modes, dtype=np.int8)


def test_a_slip_turning_about_where_the_slip_had_not_stopped_is_invented():
    run = types.SimpleNamespace(transitions=[Transition(0.1, "slip", 0, 0), Transition(0.3, "slip", 0, 0)])
    rows, modes = _rows([0.0, 0.1, 0.2, 0.3, 0.4], [ROLLING, ROLLING, SLIDING, SLIDING, SLIDING],
                        [0.0, 0.0, 1e-3, 2e-3, 1e-3])
    (note,) = transition_check._invented(run, rows, modes)
    assert note.startswith("the slip at 0.3 s, a turn of the slip, comes where the slip speed is 0.002 m/s, not 0")
    rows[3, SLIP_SPEED] = 1e-12   # it stopped: a real turn about
    assert transition_check._invented(run, rows, modes) == []


def test_changes_at_one_instant_are_invented_but_not_after_a_landing():
    rows, modes = _rows([0.0, 0.1, 0.2], [ROLLING, ROLLING, SLIDING], [0.0, 0.0, 0.1])
    at_once = types.SimpleNamespace(transitions=[Transition(0.15, "grip", 0, 0), Transition(0.15, "slip", 0, 0)])
    (note,) = transition_check._invented(at_once, rows, modes)
    assert note == "the slip at 0.15 s comes at the instant of the grip before it"
    landed = types.SimpleNamespace(transitions=[Transition(0.15, "landing", 0, 0), Transition(0.15, "slip", 0, 0)])
    assert transition_check._invented(landed, rows, modes) == []


# -- where and how often the check runs ------------------------------------------------------------

def test_the_check_runs_once_where_the_run_runs_and_not_for_its_retakes(monkeypatch):
    threads = []
    real = simulation.check_transitions

    def spy(run):
        threads.append(threading.get_ident())
        return real(run)

    monkeypatch.setattr(simulation, "check_transitions", spy)
    run = Simulation(_bend())
    worker = threading.Thread(target=run.advance)
    worker.start()
    worker.join()
    assert threads == [worker.ident]
    assert run.trajectory().transition_check is run.transition_check is not None
    assert threads == [worker.ident]   # reading it computes nothing


def test_the_first_transitions_only_are_checked(monkeypatch):
    monkeypatch.setattr(transition_check, "MAX_CHECKED", 1)
    check = simulate(_bend()).transition_check
    assert [r.kind for r in check.retakes] == ["slip"] and check.unchecked == 1
    assert check.warning().endswith("(only the first 1 transition was taken again)")


def test_a_retake_that_moves_a_converged_transition_is_reported(monkeypatch):
    """The verdict's plumbing: retakes whose times are shifted as a first-order method's would be
    make the billiard's exact grip a warning in ``Trajectory.warnings``."""
    real = transition_check._retake

    def shifted(run, row, t_row, mode, t_stop, wanted, **options):
        changes = real(run, row, t_row, mode, t_stop, wanted, **options)
        return [dataclasses.replace(c, time=c.time + 1e-3 * options["dt"]) for c in changes]

    monkeypatch.setattr(transition_check, "_retake", shifted)
    traj = simulate(_scene("0*x", mu=0.2, dt=0.01, vx=2.0, omega=(0.0, 0.0, 0.0), duration=0.5))
    (retake,) = traj.transition_check.retakes
    assert retake.verdict == PLATEAU
    assert "the grip at 0.291248 s moved by 5e-06 s when the step was halved" in traj.warnings()[0]
