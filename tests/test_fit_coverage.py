"""Fits find the truth as often as their standard errors say (docs/design.md §10, issue 33).

Synthetic tracks are made from exact motions (closed forms; for the bouncing ball the independent
hybrid reference, tests/hybrid_reference.py) with 1 mm of Gaussian noise, and fitted back from
other starting values. Over 50 fixed seeds the true value must lie within 2 standard errors of
the estimate in about 95 % of the fits: 42 to 50 of 50 (for a coverage of 95.4 %, fewer than 42
happen with probability 1 %; a standard error half what it should be would give about 34).
"""

import numpy as np
from exact_tracks import billiard, incline, noisy
from hybrid_reference import reference
from test_track_check import BILLIARD, BOUNCE, INCLINE

from rollball import fit
from rollball.sweeps.grid import with_values

SEEDS = range(50)
BAND = (42, 50)


def coverage(scene, keys, start, truth, tracks) -> list[int]:
    """How many fits, per key, have the truth within 2 standard errors."""
    inside = np.zeros(len(keys), dtype=int)
    begin = with_values(scene, keys, start)
    for track in tracks:
        result = fit(begin, track, keys)
        assert result.converged and result.residuals.explained, result.lines()
        inside += np.abs(result.values - truth) <= 2 * result.errors
    return inside.tolist()


def test_rolling_start_speed_and_the_slope_of_an_incline():
    times = np.arange(1, 61) / 60
    centre = incline(times, 0.5, 0.5, 0.3, -1.0, 0.0)
    tracks = (noisy(times, centre, ("x", "y", "z"), 1e-3, seed) for seed in SEEDS)
    for count in coverage(INCLINE, ["start.vx", "parameters.a"], [0.45, 0.45], [0.5, 0.5], tracks):
        assert BAND[0] <= count <= BAND[1]


def test_sliding_friction_and_start_speed_of_a_billiard_shot():
    """Seen from above for 0.6 s: sliding until t* = 0.29 s, then rolling."""
    times = np.arange(1, 37) / 60
    centre = billiard(times, 0.2, 2.0)
    tracks = (noisy(times, centre, ("x", "y"), 1e-3, seed) for seed in SEEDS)
    for count in coverage(BILLIARD, ["contact.friction", "start.vx"], [0.25, 1.9], [0.2, 2.0], tracks):
        assert BAND[0] <= count <= BAND[1]


def test_restitution_of_a_bouncing_ball():
    """Seen from the side: the ball flies off a step, lands at t = 0.40 s and bounces."""
    times = np.arange(1, 43) / 60
    centre = reference(BOUNCE, 0.7, times).center
    tracks = (noisy(times, centre, ("x", "z"), 1e-3, seed) for seed in SEEDS)
    (count,) = coverage(BOUNCE, ["contact.restitution"], [0.57], [0.6], tracks)   # (4 SE off: runs with a landing cost)
    assert BAND[0] <= count <= BAND[1]
