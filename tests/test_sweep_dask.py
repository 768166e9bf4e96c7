"""Sweeps on a Dask cluster (two worker processes on 127.0.0.1): the same table bit for bit."""

import dataclasses
import os
import signal

import numpy as np
import pytest

from rollball import Scene, sweep
from rollball.examples import EXAMPLES_DIR

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def scheduler():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=":0", worker_dashboard_address=":0") as cluster:
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


def test_a_lost_worker_does_not_lose_the_sweep(scheduler):
    """A worker process killed mid-sweep: Dask runs its batches again on the other worker (and
    the restarted one); the table is still complete and still equals the local one."""
    scene = dataclasses.replace(Scene.load(EXAMPLES_DIR / "liftoff.json"), duration=5.0)
    vary = {"start.vx": np.linspace(3, 6, 400)}
    with distributed.Client(scheduler) as client:
        victim = next(iter(client.run(os.getpid).values()))
    killed = []

    def progress(done, total, text):
        if not killed:
            os.kill(victim, signal.SIGKILL)
            killed.append(done)

    remote = sweep(scene, vary, scheduler=scheduler, progress=progress)
    assert killed and killed[0] < 400 and not remote.partial
    np.testing.assert_array_equal(remote.outcomes, sweep(scene, vary, workers=2).outcomes)


def test_a_failed_batch_ends_the_sweep_with_the_runs_finished(monkeypatch):
    from rollball.sweeps import batch

    real = batch.run

    def flaky(task):
        if task.lo > 0:
            raise RuntimeError("worker out of memory")
        return real(task)

    monkeypatch.setattr(batch, "run", flaky)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0") as cluster:
        table = sweep(Scene.load(EXAMPLES_DIR / "liftoff.json"), {"start.vx": np.linspace(3, 6, 40)},
                      scheduler=cluster.scheduler_address)
    assert table.partial and "worker out of memory" in table.error
    first = table.done.sum()                                  # the first batch, and only it
    assert 0 < first < 40 and table.done[:first].all()
