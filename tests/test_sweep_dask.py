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


def test_a_dask_sweep_over_parameters_equals_the_local_one_bit_for_bit(scheduler):
    scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "a*sin(k*x)*cos(y)",
                             "parameters": {"a": 0.5, "k": {"value": 1.0, "min": 0.5, "max": 4.0}},
                             "duration": 1.0})
    vary = {"parameters.a": np.linspace(0, 1, 5), "parameters.k": [0.5, 2.0]}
    remote = sweep(scene, vary, scheduler=scheduler)
    local = sweep(scene, vary, workers=2)
    np.testing.assert_array_equal(remote.codes, local.codes)
    np.testing.assert_array_equal(remote.outcomes, local.outcomes)
    assert not remote.messages and len(set(local.outcomes[:, 2])) > 1


def test_an_unreachable_scheduler_is_a_clear_error():
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler"):
        sweep(Scene.load(EXAMPLES_DIR / "liftoff.json"), {"start.vx": [1.0]}, scheduler="tcp://127.0.0.1:9",
              connect_timeout=0.5)


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
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster:
        table = sweep(Scene.load(EXAMPLES_DIR / "liftoff.json"), {"start.vx": np.linspace(3, 6, 40)},
                      scheduler=cluster.scheduler_address)
    assert table.partial and "worker out of memory" in table.error
    first = table.done.sum()                                  # the first batch, and only it
    assert 0 < first < 40 and table.done[:first].all()


# -- bounded waits (issue 23): loopback servers that never answer, answer garbage, or have no workers

LIFTOFF = EXAMPLES_DIR / "liftoff.json"


@pytest.fixture
def loopback_server():
    """A TCP server on 127.0.0.1 that accepts and then stays silent, or answers garbage."""
    import socket
    import threading

    servers = []

    def start(answer: bytes | None):
        listener = socket.socket()
        listener.bind(("127.0.0.1", 0))
        listener.listen(8)
        conns = []

        def serve():
            while True:
                try:
                    conn, _ = listener.accept()
                except OSError:
                    return
                conns.append(conn)
                if answer is not None:
                    conn.sendall(answer)

        threading.Thread(target=serve, daemon=True).start()
        servers.append((listener, conns))
        return f"tcp://127.0.0.1:{listener.getsockname()[1]}"

    yield start
    for listener, conns in servers:
        for conn in conns:
            conn.close()
        listener.close()


@pytest.mark.parametrize("answer, words", [
    (None, "no answer from the Dask scheduler at tcp://127.0.0.1:"),
    # a length prefix of 2^64 - 1 bytes, then text: a Dask client reading it once tried to allocate 3 EiB
    (b"\xff" * 16 + b"HTTP/1.1 400 Bad Request\r\n\r\n" * 20, "did not answer as a Dask scheduler does"),
])
def test_a_port_that_never_answers_or_answers_garbage_is_refused_in_bounded_time(loopback_server, answer, words):
    import time

    address = loopback_server(answer)
    start = time.monotonic()
    with pytest.raises(ValueError, match=words):
        sweep(Scene.load(LIFTOFF), {"start.vx": [1.0]}, scheduler=address, connect_timeout=0.5)
    assert time.monotonic() - start < 5


@pytest.fixture(scope="module")
def no_workers():
    with distributed.LocalCluster(n_workers=0, processes=False, host="127.0.0.1", protocol="tcp",
                                  dashboard_address=":0") as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        yield cluster.scheduler_address


def test_a_scheduler_without_workers_is_given_up_on_after_the_worker_timeout(no_workers):
    import time

    start = time.monotonic()
    with pytest.raises(ValueError, match="has no workers: none joined within 0.5 s"):
        sweep(Scene.load(LIFTOFF), {"start.vx": [1.0]}, scheduler=no_workers, worker_timeout=0.5)
    assert time.monotonic() - start < 5


def test_the_first_ctrl_c_stops_the_wait_for_workers(no_workers, tmp_path, capsys):
    import threading
    import time

    from rollball.cli import main

    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    try:
        code = main(["sweep", str(LIFTOFF), "--vary", "start.vx=3:6:4", "--scheduler", no_workers,
                     "--worker-timeout", "60", "--out", str(tmp_path)])
    finally:
        timer.cancel()
    assert code == 130 and time.monotonic() - start < 10
    assert "interrupted" in capsys.readouterr().err


@pytest.mark.parametrize("address, words", [
    ("ucx://127.0.0.1:8786", "the ucx:// transport is not supported"),
    ("tls://127.0.0.1:8786", "the tls:// transport is not supported"),
    ("tcp://127.0.0.1", "expected tcp://HOST:PORT"),
    ("tcp://127.0.0.1:99999", "expected tcp://HOST:PORT"),
])
def test_unsupported_addresses_are_refused_up_front(address, words, tmp_path, capsys, monkeypatch):
    import rollball.sweeps

    monkeypatch.setattr(rollball.sweeps, "sweep", lambda *a, **k: pytest.fail("the sweep started"))
    from rollball.cli import main

    assert main(["sweep", str(LIFTOFF), "--vary", "start.vx=3:6:4", "--scheduler", address,
                 "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err and list(tmp_path.iterdir()) == []


def test_a_dask_sweep_of_a_scene_that_comes_to_rest_equals_the_local_one(scheduler):
    """Runs through Simulation (a scene that dissipates), their rests and basins: the same table
    on Dask as on one thread and on two."""
    scene = Scene.from_dict({"format": "rollball-scene", "version": 4, "landscape": "(x**2 - 1)**2 + y**2",
                             "contact": {"friction": 0.5, "rolling_resistance": 0.05}, "ball": {"radius": 0.05},
                             "duration": 0.2, "view": {"min": -2.0, "max": 2.0, "step": 0.1}})
    vary = {"start.x": [-1.5, -1.004, 0.0, 0.01, 0.997], "start.y": [0.0, 0.01]}
    remote = sweep(scene, vary, scheduler=scheduler)
    for local in (sweep(scene, vary, workers=1), sweep(scene, vary, workers=2)):
        np.testing.assert_array_equal(remote.codes, local.codes)
        np.testing.assert_array_equal(remote.outcomes, local.outcomes)
        assert remote.minima == local.minima
    assert sorted(set(remote["basin"][np.isfinite(remote["basin"])])) == [0.0, 1.0, 2.0]
