"""Huge friction coefficients act as "always enough friction" (closed forms, docs/design.md §1, "Huge friction"):
a ball that rolls stays rolling (on an incline, a = (5/7) g sin θ), one sliding from its start grips
at once (t* = 2 v₀/(7 μ g) → 0) with 5/7 of its speed and 2/7 of its kinetic energy dissipated.
μ = 1e308 made μ F·N overflow to inf (a slip at 5.7e-17 s, then "the initial state overflows"),
μ = 1e300 sliding "spun too fast for the step"."""

import json
import math

import numpy as np
import pytest

from rollball import Scene, Status, simulate
from rollball.examples import EXAMPLES_DIR

G = 9.81
BASE = json.loads((EXAMPLES_DIR / "liftoff.json").read_text())


def scene(landscape, friction, **start):
    data = json.loads(json.dumps(BASE))
    data["landscape"], data["duration"] = landscape, 0.5
    data["start"].update(start)
    data["contact"]["friction"] = friction
    return Scene.from_dict(data)


@pytest.mark.parametrize("mu", [1e300, 1e308, 1.7976931348623157e308])
def test_a_ball_rolling_up_an_incline_with_huge_friction_rolls(mu):
    traj = simulate(scene("0.2*x", mu, x=0.0, vx=1.0))
    assert traj.status is Status.OK, traj.message
    assert traj.transitions == () and np.all(traj.dissipated == 0.0)
    t = traj.t[-1]
    along = np.array([1.0, 0.0, 0.2]) / math.sqrt(1.04)
    speed = math.sqrt(1.04) - 5 / 7 * G * 0.2 / math.sqrt(1.04) * t   # along the slope, up
    assert traj.velocity[-1] == pytest.approx(speed * along, abs=1e-12)


@pytest.mark.parametrize("mu", [1e150, 1e300, 1e308])
def test_a_ball_sliding_with_huge_friction_grips_at_once(mu):
    traj = simulate(scene("0*x", mu, x=0.0, vx=1.0, omega=[0.0, 0.0, 0.0]))
    assert traj.status is Status.OK, traj.message
    assert [change.kind for change in traj.transitions] == ["grip"]
    assert traj.transitions[0].time <= 1e-99   # 2 v₀/(7 μ g), μ taken as at most 1e100
    assert traj.velocity[-1] == pytest.approx([5 / 7, 0.0, 0.0], abs=1e-14)
    assert traj.dissipated[-1] == pytest.approx(2 / 7 * 0.5, rel=1e-12)
