"""What docs/design.md ("Narrower than a step") and the model help page say a contact run cannot
see: a spike 0.4 m tall and 0.5 mm wide on the liftoff landscape, rolled across (the ball glued) by a
step longer than it, status ok; a step short enough lands a stage on its flank and stops there. If
a contact run learns to see it, this test says the pages are out of date."""

import json

import numpy as np
import pytest

from rollball import Scene, Status, simulate
from rollball.examples import EXAMPLES_DIR

SPIKE = "0.5*exp(-x^2) + 0.4*exp(-((x-1.1)/0.0005)^2)"


def spiked(method):
    data = json.loads((EXAMPLES_DIR / "liftoff.json").read_text())
    data["landscape"] = SPIKE
    data["start"].update(x=-1.5, vx=3.5)
    data["contact"]["after_liftoff"] = "glued"
    data["integrator"]["method"] = method
    return Scene.from_dict(data)


def step_across(traj):
    """The contact's x at the recorded steps either side of the spike's axis x = 1.1."""
    x = traj.contact[:, 0]
    i = int(np.searchsorted(x, 1.1))
    return x[i - 1], x[i]


@pytest.mark.parametrize("method, options, across", [("dopri5", {"rtol": 1e-8}, (1.017, 1.182)),
                                                      ("rk4", {"dt": 1e-2}, None)])
def test_a_step_longer_than_a_spike_rolls_across_it(method, options, across):
    traj = simulate(spiked(method), **options)
    assert traj.status is Status.OK
    before, after = step_across(traj)
    assert after - before > 20 * 0.0005   # (the step: far wider than the spike)
    if across is not None:
        assert (before, after) == pytest.approx(across, abs=1e-3)


def test_a_step_shorter_than_its_flank_stops_on_it():
    traj = simulate(spiked("rk4"), dt=1e-3)
    assert traj.status is Status.DOES_NOT_FIT
    assert traj.contact[-1, 0] == pytest.approx(1.098, abs=1e-3)
