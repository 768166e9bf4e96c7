"""Every example runs as it did before the landscapes took parameters and their derivatives
were made node by node: the same rows to round-off (recorded with the code of that time).
The examples that have since become version-3 scenes that fly (liftoff, cylinder, bump) are run as
they were shipped in version 2 (tests/data/examples_v2/): the 2011 model's code path."""

import json
from pathlib import Path

import numpy as np
import pytest

from rollball import Scene, simulate
from rollball.examples import example_scenes

DATA = Path(__file__).parent / "data"
BEFORE = json.loads((DATA / "examples_before.json").read_text())
EXAMPLES = {path.stem: scene for path, scene in example_scenes()}
EXAMPLES.update({path.stem: Scene.load(path) for path in (DATA / "examples_v2").glob("*.json")})


@pytest.mark.parametrize("name", sorted(BEFORE))
def test_every_example_runs_as_before(name):
    before = BEFORE[name]
    traj = simulate(EXAMPLES[name], t_end=before["t_end"])
    assert (traj.status, traj.steps) == (before["status"], before["steps"])
    if before["liftoff_time"] is None:
        assert traj.liftoff_time is None
    else:
        assert traj.liftoff_time == pytest.approx(before["liftoff_time"], rel=1e-12)
    picked = before["picked"]
    now = np.column_stack([traj.t, traj.contact, traj.velocity, traj.omega, traj.energy, traj.normal_force])[picked]
    expected = np.array(before["rows"])
    scale = np.maximum(np.abs(expected).max(axis=0), 1.0)
    assert np.all(np.abs(now - expected) <= 1e-12 * scale), np.abs(now - expected).max(axis=0)
