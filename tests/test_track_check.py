"""A track against a run of its scene (docs/design.md §10): the model's position at the track's
times is interpolated between the run's rows to well below a millimetre, checked against exact
motions (closed forms, and the independent hybrid reference for a bouncing ball); the figures
and the verdict say whether the model explains the track."""

import dataclasses

import numpy as np
import pytest
from exact_tracks import billiard, incline, noisy
from hybrid_reference import reference

from rollball import Scene, Track, residuals
from rollball.examples import EXAMPLES_DIR
from rollball.sweeps.grid import with_values
from rollball.track_check import ROUGH, model_at, run_for

BILLIARD = Scene.load(EXAMPLES_DIR / "billiard.json")
INCLINE = Scene.from_dict({
    "format": "rollball-scene", "version": 3, "landscape": "-a*x", "parameters": {"a": 0.5},
    "ball": {"radius": 0.1, "mass": 1.0}, "start": {"x": -1.0, "y": 0.0, "vx": 0.5, "vy": 0.3, "spin": 0.0},
    "integrator": {"method": "rk4", "munthe_kaas": True, "dt": 0.005}, "duration": 1.0})
# a ball that flies off the edge of a step down, lands on the lower floor and bounces (e = 0.6)
BOUNCE = with_values(dataclasses.replace(Scene.load(EXAMPLES_DIR / "liftoff.json"), landscape="-0.4*tanh(3*x)"),
                     ["start.x", "start.vx", "contact.restitution", "duration", "integrator.dt"],
                     [-0.8, 4.0, 0.6, 0.7, 0.002])
FRAMES = np.arange(1, 61) / 60


def exact(times, centre, axes=("x", "y", "z")):
    return Track(times, axes, centre[:, ["xyz".index(a) for a in axes]])


def test_the_centre_between_rows_is_the_exact_motion_sliding_rolling_and_on_a_slope():
    """Cubic Hermite from the rows' positions and velocities: at 1 ms steps (billiard, through its
    change from sliding to rolling) and 5 ms steps (incline), within 1e-9 m of the closed form."""
    times = np.sort(np.concatenate([FRAMES, [2 * 2.0 / (7 * 0.2 * 9.81)]]))   # also at the grip itself
    res = residuals(BILLIARD, exact(times, billiard(times, 0.2, 2.0)), noise=1e-3)
    assert res.max < 1e-9 and res.covered
    res = residuals(INCLINE, exact(FRAMES, incline(FRAMES, 0.5, 0.5, 0.3, -1.0, 0.0)), noise=1e-3)
    assert res.max < 1e-9


def test_the_contact_point_between_rows_is_the_exact_contact_point():
    """On the incline the contact point is the centre minus r N; linear interpolation between 5 ms
    rows is within h²/8 |α̈| (9.8 µm) of it."""
    centre = incline(FRAMES, 0.5, 0.5, 0.3, -1.0, 0.0)
    contact = centre - 0.1 * np.array([0.5, 0.0, 1.0]) / np.sqrt(1.25)
    res = residuals(INCLINE, exact(FRAMES, contact), point="contact", noise=1e-3)
    assert res.max < 0.005 ** 2 / 8 * 5 / 7 * 9.81 * 0.5 / 1.25 * np.sqrt(1.25) * 1.01


def test_the_centre_in_a_step_that_ends_with_a_landing_is_the_flights_parabola():
    """A landing's row holds the velocity after the impact: the step before it is the parabola
    from its start (Hermite with the velocity after the impact is 1.3 mm off at 2 ms steps)."""
    traj = run_for(BOUNCE, Track([0.0, 0.7], ("x", "z"), np.zeros((2, 2))))
    landings = [c.time for c in traj.transitions if c.kind == "landing"]
    assert len(landings) >= 1
    times = np.sort(np.concatenate([FRAMES[FRAMES < 0.7], [t - d for t in landings for d in (1e-4, 5e-4, 1e-3)],
                                    landings]))
    truth = reference(BOUNCE, 0.7, times)
    model = model_at(traj, BOUNCE, exact(times, truth.center))
    assert np.abs(model - truth.center).max() < 1e-8


def test_a_noisy_track_of_the_scene_is_explained_and_a_wrong_scene_is_not():
    track = noisy(FRAMES, incline(FRAMES, 0.5, 0.5, 0.3, -1.0, 0.0), ("x", "z"), 1e-3, seed=4)
    res = residuals(INCLINE, track)
    assert res.explained and res.noise_estimated   # (the noise of 60 frames estimated to ±15 %)
    assert set(res.per_axis) == {"x", "z"} and all(0.7e-3 < rms < 1.3e-3 for rms, _ in res.per_axis.values())
    wrong = residuals(with_values(INCLINE, ["parameters.a"], [0.45]), track, noise=1e-3)
    assert not wrong.explained and wrong.ratio > ROUGH and not wrong.noise_estimated
    assert wrong.verdict().startswith("the model does not explain the track")
    assert wrong.max_time == pytest.approx(1.0)   # the slope's error grows with time


def test_a_run_that_stops_before_the_tracks_end_does_not_explain_it():
    """A ball too big for the valley's bottom stops the run (does_not_fit) early."""
    valley = Scene.load(EXAMPLES_DIR / "too_big.json")
    times = np.linspace(0.1, 3.0, 30)
    res = residuals(valley, Track(times, ("x", "y"), np.zeros((30, 2))), noise=1e-3)
    assert not res.covered and not res.explained and "stopped" in res.verdict()


def test_a_point_and_a_noise_that_are_not_are_refused():
    track = Track(FRAMES, ("x", "z"), np.zeros((60, 2)))
    with pytest.raises(ValueError, match="point must be"):
        residuals(INCLINE, track, point="top")
    with pytest.raises(ValueError, match="noise"):
        residuals(INCLINE, track, noise=-1.0)
