"""A run whose contact changes mode (rollball/simulation.py): kernel runs in one mode each, flights
between them, the rows on one clock, the transitions in order; the 2011 model untouched."""

import math

import numpy as np
import pytest

from rollball import Scene, Simulation, simulate

G = 9.81


def plane(mu, v0, omega=(0.0, 0.0, 0.0), duration=1.0):
    return Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "0*x",
                            "start": {"x": 0.0, "y": 0.0, "vx": v0, "vy": 0.0, "omega": list(omega)},
                            "contact": {"friction": mu}, "duration": duration})


@pytest.mark.parametrize("dt", [1e-2, 5e-3])
def test_a_billiard_shot_skids_then_rolls(dt):
    """μ = 0.2, v₀ = 2 m/s, ω₀ = 0: grips at t* = 2 v₀/(7 μ g), rolls on at 5 v₀/7, having lost
    2/7 of its kinetic energy; with backspin ω₀ the final speed is (5 v₀ − 2 r ω₀)/7."""
    mu, v0, r = 0.2, 2.0, 0.1
    traj = simulate(plane(mu, v0), dt=dt)
    assert [c.kind for c in traj.transitions] == ["grip"]
    grip = traj.transitions[0]
    errors = {"t*": abs(grip.time - 2 * v0 / (7 * mu * G)), "speed": abs(traj.velocity[-1, 0] - 5 * v0 / 7),
              "dissipated": abs(traj.dissipated[-1] - 2 / 7 * 0.5 * v0 * v0)}
    print(f"dt = {dt}: " + ", ".join(f"{k} {v:.2e}" for k, v in errors.items()))
    assert max(errors.values()) < 1e-10
    assert list(traj.mode[:2]) == ["sliding", "sliding"] and traj.mode[-1] == "rolling"
    assert np.all(np.diff(traj.t) > 0)    # one clock, no row twice
    assert np.abs(traj.energy_error()).max() < 1e-10   # what friction took is accounted for
    w0 = 15.0   # backspin: about the axis that opposes rolling (rolling forward spins about +y)
    back = simulate(plane(mu, v0, (0.0, -w0, 0.0)), dt=dt)
    assert back.velocity[-1, 0] == pytest.approx((5 * v0 - 2 * r * w0) / 7, abs=1e-10)


def test_rows_arrive_the_same_in_chunks():
    scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "0.2*exp(-20*x^2)",
                             "start": {"x": -1.0, "y": 0.0, "vx": 3.0}, "contact": {"restitution": 0.5},
                             "duration": 1.2})
    whole = Simulation(scene, record_every=5)
    whole.advance()
    pieces = Simulation(scene, record_every=5)
    got = []
    while not pieces.done:
        got.append(pieces.advance(37))
        assert 0.0 <= pieces.progress <= 1.0
    assert np.array_equal(np.concatenate(got), whole.rows)
    a, b = whole.trajectory(), pieces.trajectory()
    assert a.transitions == b.transitions and list(a.mode) == list(b.mode)
    assert a.steps == b.steps and a.evaluations == b.evaluations
    assert [c.kind for c in a.transitions][:2] == ["liftoff", "landing"]
    assert a.liftoff_time == a.transitions[0].time   # the first lift-off is still reported
    assert a.landings == sum(c.kind == "landing" for c in a.transitions) >= 3


def test_the_2011_model_is_one_kernel_run():
    scene = Scene.from_dict({"format": "rollball-scene", "version": 2, "landscape": "0.5*exp(-x^2)",
                             "start": {"x": -2.5, "y": 0.0, "vx": 5.0}, "duration": 1.0})
    run = Simulation(scene)
    run.advance()
    traj = run.trajectory()
    assert not run.segmented and traj.transitions == () and traj.liftoff_time is not None
    assert set(traj.mode) == {"rolling"} and not traj.dissipated.any()
    flying = simulate(Scene.from_dict({**scene.to_dict(), "contact": {"after_liftoff": "fly"}}))
    assert flying.liftoff_time == pytest.approx(traj.liftoff_time, abs=1e-12)
    assert "flying" in set(flying.mode) and math.isclose(flying.t[-1], 1.0)


def test_a_flight_beyond_the_landscape_ends_the_run():
    """sqrt(x) ends at x = 0, where the ball, rolling towards it, has already left the surface: it
    flies on over nothing, and the run ends where no surface is found below it."""
    scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "sqrt(x)",
                             "start": {"x": 0.5, "y": 0.0, "vx": -3.0}, "duration": 1.0})
    traj = simulate(scene)
    assert [c.kind for c in traj.transitions] == ["liftoff"]
    assert traj.status == "nonfinite" and traj.failure.reason == "off_domain"
    assert traj.t[-1] == traj.failure.time < 1.0 and traj.mode[-1] == "flying"
    assert np.isfinite(traj.data).all()


def _off_grid(traj, spacing):
    """The row times that are neither a multiple of spacing, nor a change of mode, nor the end."""
    changes = {c.time for c in traj.transitions} | {traj.t[-1]}
    k = traj.t / spacing
    return [t for t, n in zip(traj.t, k) if abs(n - round(n)) > 1e-6 and t not in changes]


BOUNCING = {"format": "rollball-scene", "version": 3, "landscape": "0.2*exp(-20*x^2)",
            "start": {"x": -1.0, "y": 0.0, "vx": 3.0}, "contact": {"restitution": 0.5}, "duration": 1.2}


@pytest.mark.parametrize("every", [1, 7])
def test_every_segment_steps_and_records_on_the_runs_one_grid(every):
    """After a lift-off, the landings and a grip, the kernel runs step and record as a run with one clock
    from t = 0 would: fixed steps end at multiples of dt (every = 1: every step is a row), the rows at
    multiples of dt·every; adaptive rows at multiples of record_dt."""
    dt = 2e-3
    bouncing = Scene.from_dict(BOUNCING)
    for scene, kinds in ((bouncing, {"liftoff", "landing"}), (plane(0.2, 2.0, duration=0.5), {"grip"})):
        traj = simulate(scene, dt=dt, record_every=every)
        assert kinds <= {c.kind for c in traj.transitions}
        after = (np.asarray(traj.mode) != "flying") & (traj.t > traj.transitions[0].time)
        assert np.sum(after) > 0.03 / (dt * every)   # rows of kernel runs after the first change
        assert _off_grid(traj, dt * every) == []
        assert np.all(np.diff(traj.t) > 0)
        adaptive = simulate(scene, method="dopri5", rtol=1e-8, record_dt=0.01)
        assert kinds <= {c.kind for c in adaptive.transitions}
        assert _off_grid(adaptive, 0.01) == [] and np.all(np.diff(adaptive.t) > 0)


def test_the_grid_a_segment_joins():
    """A kernel run from t_start has passed the grid times k·dt at or before it; one less than
    10⁻⁹·dt after it counts as passed (its first step takes the sliver with it, no step of 1e-17 s)."""
    from rollball.kernel import grid_steps_before

    assert grid_steps_before(0.0, 0.1) == 0 and grid_steps_before(0.05, 0.1) == 0
    assert grid_steps_before(0.3, 0.1) == 3          # 0.3 / 0.1 = 2.9999999999999996
    assert grid_steps_before(0.1 * 7 - 1e-12, 0.1) == 7 and grid_steps_before(0.1 * 7 - 1e-9, 0.1) == 6
    assert grid_steps_before(0.71, 0.1) == 7
