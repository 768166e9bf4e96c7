"""Whose an energy error is: where one recorded interval holds most of it, the run takes that
interval again with a shorter step (tighter tolerances, adaptive). On a smooth landscape the
error shrinks as the method's order predicts and is the step's; over a kink or a jump of the
curvature it does not shrink and is the landscape's (docs/design.md §1)."""

import dataclasses
import threading

import numpy as np
import pytest

from conftest import make_scene
from rollball import simulate, simulation
from rollball.scene import Contact, Start
from rollball.energy_check import _judged
from rollball.simulation import Simulation

BUMP = "0.3*exp(-(x/0.3)^2)"  # smooth


def bump(dt):
    return make_scene(BUMP, x=-0.8, vx=3.0, duration=0.5, dt=dt)


def test_a_smooth_landscape_at_too_large_a_step_is_the_steps():
    traj = simulate(bump(0.15), method="rk4")
    check = traj.energy_check
    assert check is not None and not check.landscape
    assert check.shrink > 16.0  # rk4: 4^4 = 256 for a step 4 times shorter
    notes = traj.warnings()
    assert len(notes) == 1 and "the step is too large" in notes[0] and "landscape" not in notes[0]


def test_a_smooth_landscape_at_loose_tolerances_is_the_steps():
    traj = simulate(bump(0.05), method="dopri5", rtol=1e-3, atol=1e-4)
    check = traj.energy_check
    assert check is not None and not check.landscape, check
    assert "the step is too large" in traj.warnings()[0]


@pytest.mark.parametrize("method", ["rk4", "euler", "dopri5"])
def test_a_kink_is_the_landscapes(method):
    options = dict(rtol=1e-3, atol=1e-4) if method == "dopri5" else {}
    traj = simulate(make_scene("min(0.5*x, -0.1*x)", x=-0.5, vx=2.0, duration=0.5, dt=1e-3), method=method,
                    **options)
    check = traj.energy_check
    assert check is not None and check.landscape
    assert check.time <= traj.liftoff.time <= check.end  # where the run crossed the kink
    assert "the landscape's, not the step's" in traj.warnings()[0]


def test_a_jump_of_the_curvature_is_the_landscapes():
    # f'' jumps from 0 to 8 at x = 0 (f and its slope are continuous): no kink, no lift-off
    traj = simulate(make_scene("4*max(x,0)^2", x=-0.5, vx=2.0, duration=0.5, dt=0.05), method="rk4")
    assert traj.liftoff is None
    check = traj.energy_check
    assert check is not None and check.landscape and check.shrink < 16.0
    assert check.time <= 0.25 <= check.end and abs(check.x) < 0.1
    notes = traj.warnings()
    assert len(notes) == 1 and "the landscape is not smooth there" in notes[0]
    assert f"t = {check.time:.6g}" in notes[0] and "the step is too large" not in notes[0]


@pytest.mark.parametrize("dt", [0.02, 0.04, 0.05])
def test_rk4_across_a_jump_of_the_curvature_at_large_steps_is_the_landscapes(dt):
    # f'' jumps from -8 to 8 at x = 0, crossed at 7 m/s. Taken again with one step 4 times shorter the
    # interval's error shrank 172-, 53- and 19-fold (the step's, against the old threshold 16); with
    # steps 16 to 256 times shorter, each 4 times shorter shrinks it about 16-fold: a jump's h^2
    traj = simulate(make_scene("4*x*abs(x)", x=-0.5, vx=2.0, duration=0.5, dt=dt), method="rk4")
    check = traj.energy_check
    assert check is not None and check.landscape and check.shrink < 64.0, check
    i, j = np.searchsorted(traj.t, [check.time, check.end])
    assert traj.contact[i, 0] < 0.0 < traj.contact[j, 0]  # the interval crosses the jump
    assert "the landscape is not smooth there" in traj.warnings()[0]


def test_euler_across_a_jump_of_the_curvature_is_judged_by_rk4():
    # the curvature jumps from 4 to 6 at x = 0: euler's own energy error shrinks 4-fold per step 4
    # times shorter, the jump's 16-fold, so euler cannot tell them apart (it judged this the step's);
    # rk4 (256-fold where the landscape is smooth) can
    traj = simulate(make_scene("3*max(x,0)^2 + 2*min(x,0)^2", x=0.5, vx=-1.0, duration=1.0, dt=0.05), method="euler")
    check = traj.energy_check
    assert check is not None and check.landscape and check.finer.startswith("rk4"), check
    assert check.expected == 256 and check.shrink < 64.0
    i, j = np.searchsorted(traj.t, [check.time, check.end])
    assert traj.contact[i, 0] > 0.0 > traj.contact[j, 0]


@pytest.mark.parametrize("landscape, x, vx, duration, method, dt", [
    ("-0.5*exp(-4*(x^2+y^2))", -0.6, 2.0, 1.0, "rk4", 0.15),
    ("-0.5*exp(-4*(x^2+y^2))", -0.6, 2.0, 1.0, "lawson5", 0.25),
    (BUMP, -0.8, 3.0, 0.5, "euler", 0.15)])
def test_a_smooth_landscape_at_steps_that_do_not_resolve_it_is_the_steps(landscape, x, vx, duration, method, dt):
    # one step crosses the whole pit or bump: a step 4 times shorter shrinks the error 11-, 26- and
    # (euler's own) 1.8-fold, less than the method's order says, and these were judged the landscape's;
    # shorter steps resolve it and shrink it as the order says
    traj = simulate(make_scene(landscape, x=x, y=0.1 if "y" in landscape else 0.0, vx=vx, duration=duration, dt=dt),
                    method=method)
    check = traj.energy_check
    assert check is not None and not check.landscape and check.shrink > check.expected / 4, check
    assert "the step is too large" in traj.warnings()[0]


def sliding(landscape, *, x, vx, dt, duration, friction=0.05, y=0.0):
    """A ball shot without spin (it slides from the start), flying where it lifts off."""
    scene = make_scene(landscape, x=x, y=y, vx=vx, duration=duration, dt=dt,
                       contact=Contact(friction=friction, restitution=0.0, after_liftoff="fly"))
    return dataclasses.replace(scene, start=Start(x, y, vx, 0.0, 0.0, omega=(0.0, 0.0, 0.0)))


@pytest.mark.parametrize("method, dt", [("rk4", 0.2), ("lawson5", 0.3)])
def test_a_sliding_ball_on_a_smooth_landscape_at_too_large_a_step_is_the_steps(method, dt):
    # it slides throughout (the check used to judge only runs that rolled throughout); the
    # interval is taken again from its sliding state (x, y, ċ, ω, D), and E + D's change over it
    # shrinks at the method's order (rk4 156-fold, lawson5 1235-fold per step 4 times shorter)
    traj = simulate(sliding("-0.5*exp(-4*(x^2+y^2))", x=-0.6, y=0.1, vx=1.0, dt=dt, duration=0.6), method=method)
    assert set(traj.mode) == {"sliding"}
    check = traj.energy_check
    assert check is not None and not check.landscape and check.shrink > check.expected / 4, check
    assert "the step is too large" in traj.warnings()[0]


def test_a_sliding_ball_across_a_jump_of_the_curvature_is_the_landscapes():
    # f'' jumps from 0 to 8 at x = 0: a step 4 times shorter shrinks E + D's change there ~4-fold
    traj = simulate(sliding("4*max(x,0)^2", x=-0.5, vx=2.0, dt=0.05, duration=0.5), method="rk4")
    check = traj.energy_check
    assert check is not None and check.landscape and check.shrink < 64.0, check
    i, j = np.searchsorted(traj.t, [check.time, check.end])
    assert traj.mode[j] == "sliding" and traj.contact[i, 0] < 0.0 < traj.contact[j, 0]
    assert "the landscape is not smooth there" in traj.warnings()[0]


def test_a_run_that_slid_then_rolls_across_a_jump_of_the_curvature_is_the_landscapes():
    # slides, grips at t = 2 v0 / (7 mu g) = 0.204 s, then rolls across the jump at x = 0: the
    # interval is taken again from its rolling state, in a run that may change mode as this one did
    traj = simulate(sliding("4*max(x,0)^2", x=-1.0, vx=3.5, friction=0.5, dt=0.05, duration=0.5), method="rk4")
    assert [change.kind for change in traj.transitions] == ["grip"]
    check = traj.energy_check
    assert check is not None and check.landscape and check.shrink < 64.0, check
    assert check.time > traj.transitions[0].time
    i, j = np.searchsorted(traj.t, [check.time, check.end])
    assert traj.mode[j] == "rolling" and traj.contact[i, 0] < 0.0 < traj.contact[j, 0]


def test_intervals_of_flight_or_with_a_landing_are_not_taken_again():
    # a flight is exact and an impact's loss is in D: only what the contact integrated is judged
    # (off the crest at x = 0 where the curvature turns, onto the floor at -0.5)
    run = Simulation(sliding("max(-4*x*abs(x), -0.5)", x=-1.0, vx=3.0, friction=1.0, dt=0.1, duration=0.6),
                     method="rk4")
    run.advance()
    traj = run.trajectory()
    kinds = [change.kind for change in traj.transitions]
    assert "liftoff" in kinds and "landing" in kinds
    judged = _judged(run, run.rows)
    flying = traj.mode[1:] == "flying"
    assert flying.any() and not judged[flying].any()
    for change in traj.transitions:
        if change.kind == "landing":
            k = np.searchsorted(traj.t, change.time) - 1   # the interval that ends at or holds it
            assert not judged[k]


def test_no_check_where_the_energy_is_kept():
    assert simulate(bump(0.01), method="rk4").energy_check is None


def test_the_check_runs_where_the_run_runs(monkeypatch):
    threads = []
    real = simulation.energy_check

    def spy(run):
        threads.append(threading.get_ident())
        return real(run)

    monkeypatch.setattr(simulation, "energy_check", spy)
    run = Simulation(bump(0.15), method="rk4")
    worker = threading.Thread(target=run.advance)
    worker.start()
    worker.join()
    assert len(threads) == 1 and threads[0] == worker.ident
    assert run.trajectory().energy_check is not None  # reading it computes nothing
    assert len(threads) == 1
