"""Sweeps on a Dask cluster (two worker processes on 127.0.0.1): the same table bit for bit."""

import numpy as np
import pytest

from rollball import Scene, sweep
from rollball.examples import EXAMPLES_DIR

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def scheduler():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, worker_dashboard_address=None) as cluster:
        yield cluster.scheduler_address


def test_a_dask_sweep_equals_the_local_one_bit_for_bit(scheduler):
    scene = Scene.load(EXAMPLES_DIR / "liftoff.json")
    vary = {"start.vx": np.linspace(3, 6, 9), "ball.radius": [0.1, -0.1, 0.2]}  # a refused scene too
    calls = []
    remote = sweep(scene, vary, scheduler=scheduler, progress=lambda d, t, text: calls.append(d))
    local = sweep(scene, vary, workers=2)
    np.testing.assert_array_equal(remote.codes, local.codes)
    np.testing.assert_array_equal(remote.outcomes, local.outcomes)
    assert remote.messages == local.messages and len(remote.messages) == 9
    assert remote.workers == 2 and remote.scheduler == scheduler and calls[-1] == 27


def test_an_unreachable_scheduler_is_a_clear_error(monkeypatch):
    monkeypatch.setattr("rollball.sweeps.runner.CONNECT_TIMEOUT", "0.5s")
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler"):
        sweep(Scene.load(EXAMPLES_DIR / "liftoff.json"), {"start.vx": [1.0]}, scheduler="tcp://127.0.0.1:9")
