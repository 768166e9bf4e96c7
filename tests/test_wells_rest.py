"""The three wells (resources/examples/wells.json: c_rr 0.04, μ_s 0.05, started at rest) bring the
ball to rest after a 16 s path over turning points: dopri5 finds that rest where dop853 at rtol
10⁻¹² does, time and place, its error shrinking with the tolerance (docs/design.md §1,
"Dissipation": the couples' side turns counted per call once made them static and kept it rolling);
the fixed steps hand its turning points, where ω_t passes close to 0, to the stiff stretch."""

import dataclasses
import functools

import numpy as np
import pytest

from rollball.examples import EXAMPLES_DIR
from rollball.scene import Air, Scene
from rollball.simulation import simulate


def _run(method, rtol=None, dt=None, record_dt=None, atol=None, munthe_kaas=True):
    """wells with ``method`` at ``rtol`` or ``dt``, checked to end at its one rest (fixed steps: with no warning)."""
    scene = Scene.load(EXAMPLES_DIR / "wells.json")
    step = {"rtol": rtol, **({} if atol is None else {"atol": atol})} if dt is None else {"dt": dt}
    traj = simulate(dataclasses.replace(scene, integrator=dataclasses.replace(scene.integrator, method=method,
                                                                              munthe_kaas=munthe_kaas, **step)),
                    record_dt=record_dt)
    assert [c.kind for c in traj.transitions] == ["rest"] and str(traj.status) == "ok", (method, rtol, traj.message)
    assert traj.message.startswith("the ball comes to rest at t = ")
    assert dt is None or traj.warnings() == [], traj.message
    return traj


def _rest(traj):
    rest = traj.transitions[0]
    return np.array([rest.time, rest.x, rest.y]), traj.dissipated[-1]


@functools.lru_cache(maxsize=1)
def _reference_run():
    return _run("dop853", 1e-12, record_dt=0.5, atol=1e-12)


def _reference():
    return _rest(_reference_run())


def test_dopri5_brings_the_ball_to_rest_where_dop853_does():
    """Measured: 2.0·10⁻⁷ s at rtol 10⁻⁹, 1.4·10⁻⁷ s at 10⁻¹¹ (the place within 2·10⁻⁸ m); the
    energy taken, 7.4652 J, to 10⁻⁶ J. (4.8·10⁻⁵ and 5.8·10⁻⁷ s while a static spin couple's limit
    inside a step was not located: both now at what the rest's own location leaves, docs/design.md §1.)"""
    reference, taken = _reference()
    errors = []
    for rtol in (1e-9, 1e-11):
        rest, dissipated = _rest(_run("dopri5", rtol))
        errors.append(np.abs(rest - reference))
        assert abs(dissipated - taken) < 1e-6
    assert errors[0][0] < 1e-6 and np.max(errors[0][1:]) < 1e-7, errors
    assert errors[1][0] < 1e-6 and np.max(errors[1][1:]) < 1e-7, errors


def _contact_at(traj, times):
    return np.array([traj.contact[np.flatnonzero(np.abs(traj.t - t) < 1e-9)[0]] for t in times])


@pytest.mark.parametrize("method, order, steps", [("rk4", 4, (0.002, 0.001)), ("gauss4", 4, (0.002, 0.001)),
                                                  ("lawson5", 5, (0.004, 0.002))])
def test_the_fixed_steps_pass_its_turning_points_at_their_order(method, order, steps):
    """Over its last turning points (14 to 16 s: the centre's least speeds 3·10⁻² to 10⁻⁴ m/s) the
    pull beats the couple and ω_t turns about within 10⁻² to 10⁻⁵ s, and at its rest it turns through
    90° as it stops: where ω_t's direction turns faster than 1/sqrt(r/g) the fixed steps hand the
    stretch to dop853 (``physics.turning_point``). The contact point at 12 and 16 s converges at the
    method's order and the rest is where dop853 at 10⁻¹² puts it, with no warning. (Measured: rk4
    at dt 0.002, 0.001: 2.5·10⁻⁹, 1.6·10⁻¹⁰ m at 12 s, the rest 2.2·10⁻⁹ and 4.7·10⁻¹¹ s off; with a
    bound within a step's reach instead, 5.6·10⁻⁷, 2.9·10⁻⁸ m and 3.5·10⁻⁵, 1.2·10⁻⁷ s, irregular below.)"""
    reference = _contact_at(_reference_run(), (12.0, 16.0))
    errors = []
    for dt in steps:
        traj = _run(method, dt=dt)
        errors.append(np.max(np.abs(_contact_at(traj, (12.0, 16.0)) - reference), axis=1))
        assert abs(traj.transitions[0].time - _reference()[0][0]) < 5e-8, (method, dt)
    coarse, fine = errors
    assert np.all(coarse < 5e-8) and np.all(fine < coarse / 2 ** order * 2), errors


def test_a_classic_run_takes_its_stiff_stretches_to_the_same_rest():
    """A Munthe-Kaas run takes its stiff steps with the kernel's pair (``loops.stiff_step``); a
    classic one (the orientation a matrix in the state, which the pair does not carry) stops before
    them and the mode machine takes each stretch in Python (``ModeMachine._stiff_stretch``). The
    motion does not depend on the orientation: both meet dop853 at 10⁻¹² as closely, at rk4's
    order. (Measured at dt 0.004, 0.002, both: 4.0·10⁻⁸, 2.5·10⁻⁹ m; the rest 3.7·10⁻⁸, 2.2·10⁻⁹ s late.)"""
    reference = _contact_at(_reference_run(), (12.0, 16.0))
    errors = []
    for dt in (0.004, 0.002):
        traj = _run("rk4", dt=dt, munthe_kaas=False)
        errors.append(np.max(np.abs(_contact_at(traj, (12.0, 16.0)) - reference)))
        assert abs(traj.transitions[0].time - _reference()[0][0]) < 5e-8, dt
    assert errors[0] < 1e-7 and errors[1] < errors[0] / 2 ** 4 * 2, errors


@pytest.mark.parametrize("x, y, rest", [(0.45833333333333304, -0.625, 13.0899), (-1.25, 1.583333333333333, 16.2421)])
def test_a_ball_settling_in_a_well_is_not_stopped_by_its_last_steps_round_off(x, y, rest):
    """Two starts of the basin map's grid whose ball settles in well 1 after turning sideways: the
    stiff stretch's last steps before the rest move the contact point by about 10⁻¹⁵ m, and the
    normal's round-off over such a chord looked like a bend of r·κ = 1.6 and 1.2: the runs stopped
    "does not fit" at their rest (``events.looks``: a chord within round-off has no bend to judge)."""
    scene = Scene.load(EXAMPLES_DIR / "wells.json")
    traj = simulate(dataclasses.replace(scene, start=dataclasses.replace(scene.start, x=x, y=y)))
    assert str(traj.status) == "ok" and [c.kind for c in traj.transitions] == ["rest"], traj.message
    assert traj.transitions[0].time == pytest.approx(rest, abs=1e-4)
    assert np.hypot(traj.transitions[0].x - 0.9732, traj.transitions[0].y) < 0.02   # in well 1


def test_a_stiff_stretch_takes_the_pairs_own_steps_and_records_the_grid_between():
    """Where the stiff pair's next step reaches past the grid step it was given, the stretch goes
    on in that step to the last grid time it reaches (``loops.stiff_step``), the rows due between
    from the pair's dense output: what is recorded does not change the motion (every 3rd row of a
    run recording every step, bit for bit, at the grid's times k·dt, the rest the same), and the
    wells with air cost fewer evaluations than one pair's step for every grid step in a stretch
    took (41 515, docs/design.md §1; measured 37 298, 33 136 with no stretch at all)."""
    scene = dataclasses.replace(Scene.load(EXAMPLES_DIR / "wells.json"), duration=16.0)
    every, third = (simulate(scene, record_every=n) for n in (1, 3))
    assert str(every.status) == str(third.status) == "ok"
    assert np.array_equal(third.t[:-1], 3 * np.arange(len(third.t) - 1) * 0.002) and third.t[-1] == 16.0
    assert np.array_equal(third.contact[:-1], every.contact[:-1:3])
    assert np.array_equal(third.contact[-1], every.contact[-1])
    assert np.array_equal(third.dissipated[:-1], every.dissipated[:-1:3])
    windy = dataclasses.replace(scene, air=Air(density=1.2, drag_coefficient=0.47))
    assert simulate(windy).evaluations < 38000


def test_the_rows_inside_a_stiff_stretch_are_the_motions_at_every_step():
    """Every row of a fixed-step run with a stiff stretch meets dop853 at 10⁻¹² at the method's
    order, the rows of a pair's step cut at a couple's side turn too: that step is taken again
    by the pair to the turn (``events.locate_transition``), and the rows before the turn are that
    step's dense output (``loops.stiff_step``), as the adaptive runs' are. (Measured on the wells
    with air to 6.8 s, rk4: 7.6·10⁻⁹ and 5.0·10⁻¹⁰ m at dt 0.002 and 0.001; before, the rows at
    6.722 and 6.724 s were read off the shorter step's stages with the whole step's length,
    7.9·10⁻⁶ and 1.3·10⁻⁵ m off, and 1.0·10⁻⁵ m at dt 0.0005: not converging.)"""
    scene = dataclasses.replace(Scene.load(EXAMPLES_DIR / "wells.json"), duration=6.8,
                                air=Air(density=1.2, drag_coefficient=0.47))
    errors = []
    for dt in (0.002, 0.001):
        reference = simulate(scene, method="dop853", rtol=1e-12, atol=1e-12, record_dt=dt)
        traj = simulate(scene, method="rk4", dt=dt)
        assert str(traj.status) == "ok" and np.allclose(traj.t, reference.t, rtol=0.0, atol=1e-12)
        errors.append(np.max(np.abs(traj.center - reference.center)))
    assert errors[0] < 2e-8 and errors[1] < errors[0] / 2 ** 4 * 2, errors
