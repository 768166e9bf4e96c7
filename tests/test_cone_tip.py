"""A ball rolling at the tip of a cone: the exact motion of the model reaches the tip in finite time
(scipy's DOP853 on rollball/reference.py's equations, stopped 1e-8 m from it), where the normal
turns through a finite angle and the model's ball would jump across. The tip is found as a lift-off
at a kink (the real ball leaves the surface there), at the time the reference reaches it, whatever
the step; the energy error the jump leaves is reported as the landscape's, not the step's."""

import numpy as np
import pytest

from conftest import make_scene
from rollball import simulate
from rollball.landscape import landscape_for
from rollball.reference import reference_rhs
from rollball.simulation import initial_state

CONE = "-0.3*sqrt(x^2+y^2)"


def cone(y0):
    return make_scene(CONE, x=-0.5, y=y0, vx=2.0, duration=0.5)


def reference_tip_time(scene, near=1e-8):
    """When the reference's contact point comes within ``near`` of the tip (terminal event)."""
    from scipy.integrate import solve_ivp

    a0, v0 = initial_state(landscape_for(scene.landscape), scene)

    def close(t, y):
        return np.hypot(y[0], y[1]) - near

    close.terminal = True
    sol = solve_ivp(reference_rhs(scene), (0.0, scene.duration), np.concatenate([a0, v0, np.eye(3).ravel()]),
                    method="DOP853", rtol=1e-12, atol=1e-14, events=close)
    assert sol.status == 1
    return float(sol.t_events[0][0])


@pytest.mark.parametrize("y0", [0.01, 0.0])
@pytest.mark.parametrize("dt", [1e-4, 1e-5])
def test_passing_the_tip_of_a_cone_is_a_liftoff_there(y0, dt):
    t_tip = reference_tip_time(cone(y0))
    traj = simulate(cone(y0), method="rk4", dt=dt)
    lift = traj.liftoff
    assert lift is not None and lift.kink
    assert abs(lift.time - t_tip) < dt
    assert np.hypot(lift.x, lift.y) < 2.0 * dt * 2.0  # within a step's travel (about 2 m/s) of the tip


def test_the_energy_jump_at_the_tip_is_the_landscapes_not_the_steps():
    jumps = []
    for dt in (1e-4, 1e-5):
        traj = simulate(cone(0.01), method="rk4", dt=dt)
        notes = traj.warnings()
        assert traj.energy_drift > 0.05  # the jump does not shrink with the step...
        jumps.append(traj.energy_drift)
        assert len(notes) == 1 and "the landscape's, not the step's" in notes[0]
        assert "step is too large" not in notes[0]
    assert jumps[1] > 0.5 * jumps[0]


def test_an_energy_error_from_too_large_a_step_is_still_the_steps(scene_factory):
    # a bowl at a step far too large for rk4: no kink, the energy error is the step's
    traj = simulate(scene_factory("2*(x^2+y^2)", x=0.8, duration=5.0, dt=0.08))
    notes = traj.warnings()
    assert notes and "the step is too large" in notes[0]


def test_adaptive_runs_stop_or_lift_off_at_the_tip():
    t_tip = reference_tip_time(cone(0.01))
    for method, rtol in (("dopri5", 1e-6), ("dopri5", 1e-10), ("dop853", 1e-10)):
        traj = simulate(cone(0.01), method=method, rtol=rtol, atol=rtol * 1e-3, record_dt=0.01)
        where = traj.liftoff if traj.status == "ok" else traj.failure
        assert where is not None, (method, rtol, traj.message)
        assert abs(where.time - t_tip) < 1e-6 and np.hypot(where.x, where.y) < 1e-6, (method, rtol, where)


@pytest.mark.parametrize("dt", [1e-3, 1e-5])
def test_the_energy_jump_over_a_lopsided_roof_is_the_landscapes(dt):
    # a 1-D roof whose sides differ: the model's centre jumps across the kink and the energy with
    # it, 5 % at any step
    traj = simulate(make_scene("min(0.5*x, -0.1*x)", x=-0.5, vx=2.0, duration=0.5, dt=dt))
    assert traj.liftoff is not None and traj.liftoff.kink and abs(traj.liftoff.x) < 1e-9
    assert 0.04 < traj.energy_drift < 0.06
    notes = traj.warnings()
    assert len(notes) == 1 and "the landscape's, not the step's" in notes[0]


@pytest.mark.parametrize("y0", [0.01, 0.0])
@pytest.mark.parametrize("method, options, slack", [
    ("dopri5", dict(rtol=1e-10, atol=1e-13, record_dt=0.01), 1e-6),
    ("dop853", dict(rtol=1e-10, atol=1e-13, record_dt=0.01), 1e-6),
    ("gauss4", dict(dt=1e-3), 1e-3),
    ("gauss6", dict(dt=1e-3), 1e-3)])
def test_tight_runs_report_the_tip(y0, method, options, slack):
    # where a step cannot pass the tip (the adaptive step underflows, the implicit stage
    # equations do not converge, a step's secant bends like r·κ >= 1), the tip is found around it:
    # a lift-off at the apex, and a stop that says why, not a step's failure
    t_tip = reference_tip_time(cone(y0))
    traj = simulate(cone(y0), method=method, **options)
    lift = traj.liftoff
    assert lift is not None and abs(lift.time - t_tip) < slack, (traj.message, lift)
    assert np.hypot(lift.x, lift.y) < (1e-6 if slack < 1e-3 else 1e-3), lift
    assert traj.status == "ok" or traj.failure.reason == "tip", traj.message
    if traj.failure is not None:
        assert np.hypot(traj.failure.x, traj.failure.y) < 1e-8 and abs(traj.failure.time - t_tip) < slack
        assert "the tip of a cone" in traj.message and "too large" not in traj.message
