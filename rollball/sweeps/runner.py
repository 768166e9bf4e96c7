"""Running a sweep: the grid cut into batches, run on local threads or a Dask cluster.

Locally, a pool of threads runs the batches: the compiled loop releases the GIL, so the
threads run on all cores at once, sharing one compiled landscape. Runs whose contact can slip
or come to rest go through ``Simulation``, whose Python holds the GIL: their batches run in
worker processes (``processes``), each compiling the landscape once. With a scheduler
address the batches go to a Dask distributed cluster (``client.map`` over the batches,
results taken ``as_completed``); each worker process compiles the landscape on its first
batch. A batch is sized to take a few tenths of a second (Dask's advice: tasks of 100 ms or
more), and there are at least four per worker so that the load evens out.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Callable

import numpy as np

from ..basins import Basins
from ..scene import Scene
from ..run_size import MAX_STEPS, step_count
from . import batch, processes
from .grid import PARAMETER_PREFIX, Grid, check_keys
from .options import CONNECT_TIMEOUT, WORKER_TIMEOUT
from .outcomes import NOT_RUN, O_BASIN, O_REST_X, O_REST_Y, OUTCOMES
from .table import SweepTable

# Landscape evaluations per batch: about 0.2 s on a 2020s core for a small formula.
BATCH_EVALUATIONS = 3_000_000
BATCHES_PER_WORKER = 4
IN_FLIGHT = 2            # batches sent to a worker at a time (one running, one waiting)
# A sweep whose runs hold the GIL goes to worker processes from this many evaluations (counted
# as ``run_evaluations`` does: 100 runs of liftoff, about 0.1 s of them on one core). A smaller
# one takes no longer on threads, where processes could save hundredths of a second and cost a
# second where they have yet to start.
PROCESS_EVALUATIONS = 400_000
POLL = 0.2               # seconds between looks at the cancel event while waiting on a cluster
SCHEMES = ("tcp",)       # the Dask transports a sweep connects by (inproc too, in-process)

Progress = Callable[[int, int, str], None]


def local_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def run_evaluations(scene: Scene, grid: Grid) -> int:
    """The landscape evaluations of the grid's longest run, as its fixed steps count them
    (a run that changes mode takes more: its flights' and stiff stretches')."""
    def extreme(key, pick, smallest=0.0):
        if key in grid.keys:
            values = grid.axes[grid.keys.index(key)]
            values = values[values > smallest]
            return float(pick(values)) if values.size else None
        return None
    t_end = extreme("duration", np.max) or scene.duration
    # steps too small for the longest run are refused run by run (status invalid), not sized for
    dt = extreme("integrator.dt", np.min, t_end / MAX_STEPS) or scene.integrator.dt
    try:
        return step_count(dt, t_end) * batch.sweep_method(scene).stages
    except ValueError:
        return BATCH_EVALUATIONS


def batch_size(scene: Scene, grid: Grid, workers: int) -> int:
    """Runs per batch: about BATCH_EVALUATIONS landscape evaluations for the longest run,
    and at least BATCHES_PER_WORKER batches per worker."""
    runs = max(1, BATCH_EVALUATIONS // run_evaluations(scene, grid))
    return max(1, min(runs, math.ceil(grid.size / (BATCHES_PER_WORKER * workers))))


def check_address(address: str) -> str:
    """A Dask scheduler address a sweep can connect to, as ``tcp://host:port`` (a bare
    ``host:port`` is tcp); ValueError naming the problem for anything else (tls:// needs
    certificates, ucx:// a library; neither is set up by this program)."""
    text = str(address).strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    scheme = scheme.lower()
    if scheme == "inproc":  # a cluster in this very process (tests, notebooks)
        return text
    if scheme not in SCHEMES:
        raise ValueError(f"scheduler {address!r}: the {scheme}:// transport is not supported; "
                         f"give a tcp://HOST:PORT address")
    host, colon, port = rest.rpartition(":")
    host = host.strip("[]")
    if not colon or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"scheduler {address!r}: expected tcp://HOST:PORT (a port from 1 to 65535)")
    return f"tcp://{rest}"


def sweep(scene: Scene, vary, *, workers: int | None = None, scheduler: str | None = None,
          progress: Progress | None = None, cancel: threading.Event | None = None,
          connect_timeout: float = CONNECT_TIMEOUT, worker_timeout: float = WORKER_TIMEOUT) -> SweepTable:
    """Run the scene once for every combination of the varied values; return the table.

    vary: a mapping from dotted scene keys (``start.vx``, ``ball.radius``, ... see
    ``grid.KEYS``) to their values; the runs are the full grid, the last key varying
    fastest. Local by default, on ``workers`` threads or processes (default: every core); with
    ``scheduler`` (a Dask address, ``tcp://host:8786``) on that cluster instead: the scheduler
    must answer within ``connect_timeout`` seconds and have a worker within ``worker_timeout``
    (and get one back within that time if all leave), else ValueError saying which; setting
    ``cancel`` while waiting for them raises ``KeyboardInterrupt``.
    progress(done, total, text) is called as batches finish; setting ``cancel`` stops the
    sweep after the batches under way, and the table is then ``partial``; so is a sweep whose
    batch failed on a cluster (``table.error`` says why). Raises
    ValueError for a bad grid, a method a sweep cannot run, or bad ``workers``.
    """
    grid = Grid.of(vary)
    check_keys(scene, grid.keys)
    batch.sweep_method(scene)
    if scheduler is not None:
        scheduler = check_address(scheduler)
        for name, value in (("connect_timeout", connect_timeout), ("worker_timeout", worker_timeout)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < math.inf:
                raise ValueError(f"{name} must be a number of seconds greater than 0, not {value!r}")
    if scheduler is not None and workers is not None:
        raise ValueError("give workers (local threads) or scheduler (a Dask cluster), not both")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers must be a whole number of 1 or more, not {workers!r}")
    table = SweepTable(scene, grid, np.full(grid.size, NOT_RUN, dtype=np.int8),
                       np.full((grid.size, len(OUTCOMES)), np.nan))
    cancel = cancel or threading.Event()
    done = 0

    def take(result: batch.Result) -> None:
        nonlocal done
        hi = result.lo + len(result.status)
        table.codes[result.lo:hi] = result.status
        table.outcomes[result.lo:hi] = result.outcomes
        table.messages.update(result.messages)
        done += len(result.status)
        if progress is not None:
            progress(done, grid.size, f"{done:,} of {grid.size:,} runs")

    started = time.perf_counter()
    if scheduler is None:
        table.workers = workers or local_workers()
        hold_lock = (not batch.compiled(scene, grid.keys)
                     and grid.size * run_evaluations(scene, grid) >= PROCESS_EVALUATIONS)
        table.processes, table.error = _run_local(_tasks(scene, grid, table.workers), table.workers, take,
                                                  cancel, hold_lock)
    else:
        table.scheduler = str(scheduler)
        table.workers, table.error = _run_dask(scene, grid, str(scheduler), take, cancel,
                                               float(connect_timeout), float(worker_timeout))
    _give_basins(scene, grid, table)
    table.seconds = time.perf_counter() - started
    from ..comparison import machine
    table.machine = machine()
    return table


def _give_basins(scene: Scene, grid: Grid, table: SweepTable) -> None:
    """The basin of every run that came to rest, and the minima they are numbered by
    (``table.minima``): those of the scene's landscape over its view square. A sweep over a
    parameter of the landscape moves its minima from run to run: its basins are left empty."""
    rested = np.isfinite(table.outcomes[:, O_REST_X])
    if not rested.any() or any(key.startswith(PARAMETER_PREFIX) for key in grid.keys):
        return
    basins = Basins.of(scene)
    table.minima = basins.minima
    table.outcomes[rested, O_BASIN] = basins.basin(table.outcomes[rested, O_REST_X], table.outcomes[rested, O_REST_Y])


def _tasks(scene: Scene, grid: Grid, workers: int) -> list[batch.Task]:
    size = batch_size(scene, grid, workers)
    return [batch.Task(scene, grid, lo, min(lo + size, grid.size)) for lo in range(0, grid.size, size)]


def _run_local(tasks, workers: int, take, cancel: threading.Event, hold_lock: bool) -> tuple[bool, str | None]:
    """Run the batches on ``workers`` threads, or processes if their runs hold the GIL
    (``hold_lock``, for a sweep worth starting them; ``processes``) and there are two workers
    and two batches or more: where this system cannot start processes, on threads. Returns
    whether they ran on processes, and why the sweep stopped early if a worker process died
    (the batches finished before are kept), else None."""
    if hold_lock and workers > 1 and len(tasks) > 1:
        try:
            pool = processes.pool(workers)
        except (OSError, ImportError, NotImplementedError):
            pass
        else:
            return True, _drain(pool, tasks, workers, take, cancel, processes.held_interrupts)
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="rollball-sweep") as pool:
        return False, _drain(pool, tasks, workers, take, cancel, contextlib.nullcontext)


def _drain(pool, tasks, workers: int, take, cancel: threading.Event, sending) -> str | None:
    """Send the batches to ``pool``, at most ``IN_FLIGHT`` per worker at a time, within the
    context ``sending`` (a process pool's starts its workers), and ``take`` their results as they
    come; on ``cancel`` the batches not started are dropped, those under way taken. (A process
    pool's batches sent are run even when this process exits: the few in flight, not the whole
    sweep.)"""
    waiting, pending = list(reversed(tasks)), set()

    def send() -> None:
        if not waiting or cancel.is_set() or len(pending) >= IN_FLIGHT * workers:
            return   # (nothing to send: ``sending`` not entered, a process pool's trackers not asked)
        with sending():
            while waiting and len(pending) < IN_FLIGHT * workers and not cancel.is_set():
                pending.add(pool.submit(batch.run, waiting.pop()))

    try:
        send()
        while pending:
            finished, pending = wait(pending, timeout=0.1, return_when=FIRST_COMPLETED)
            if cancel.is_set():
                for future in pending:
                    future.cancel()  # those not started; the running ones finish
                finished |= wait(pending).done
                pending = set()
            for future in sorted(finished, key=lambda f: f.cancelled() or f.exception() is not None):
                if not future.cancelled():   # (the batches that ran first: an error after them)
                    take(future.result())
            send()
    except BrokenProcessPool as error:
        processes.discard(pool)
        for future in pending:   # (those finished before it that were not taken above)
            if future.done() and not future.cancelled() and future.exception() is None:
                take(future.result())
        return f"a sweep's worker process ended unexpectedly ({error or 'it was killed'})"
    finally:  # an error in a batch: do not start the rest
        for future in pending:
            future.cancel()
    return None


def _probe(address: str, timeout: float, cancel: threading.Event | None = None) -> None:
    """Ask the scheduler who it is, in a thread of its own, all within ``timeout`` seconds:
    ValueError for no answer (a port that accepts and never answers), an answer that is not a
    Dask scheduler's (a port answering garbage), or no connection at all."""
    import asyncio

    from distributed.comm import connect

    outcome: list = []

    async def ask():
        comm = await connect(address, timeout=0.8 * timeout)  # its own error first: refused, ...
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    def run():
        try:
            outcome.append(asyncio.run(asyncio.wait_for(ask(), timeout)))
        except BaseException as error:  # noqa: BLE001 - reported below, in one line
            outcome.append(error)

    thread = threading.Thread(target=run, name="rollball-dask-probe", daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout + 5.0  # wait_for ends it by then; one that hangs anyway is left
    while thread.is_alive() and time.monotonic() < deadline:
        thread.join(POLL)
        if cancel is not None and cancel.is_set():
            raise KeyboardInterrupt
    answer = outcome[0] if outcome else TimeoutError()
    if isinstance(answer, (TimeoutError, asyncio.TimeoutError)):
        raise ValueError(f"no answer from the Dask scheduler at {address} within {timeout:g} s "
                         f"(--connect-timeout)")
    if isinstance(answer, OSError):
        raise ValueError(f"cannot reach the Dask scheduler at {address}: {' '.join(str(answer).split())[:200]}")
    if isinstance(answer, BaseException) or not isinstance(answer, dict) or answer.get("type") != "Scheduler":
        what = type(answer).__name__ if isinstance(answer, BaseException) else "an answer"
        raise ValueError(f"{address} did not answer as a Dask scheduler does ({what})")


def _wait_until(condition, seconds: float, cancel: threading.Event) -> bool:
    """Poll ``condition`` until it holds (True), ``seconds`` pass (False) or ``cancel`` is set
    (KeyboardInterrupt: the caller's Ctrl-C)."""
    deadline = time.monotonic() + seconds
    while not condition():
        if cancel.is_set():
            raise KeyboardInterrupt
        if time.monotonic() >= deadline:
            return False
        time.sleep(min(POLL, max(0.0, deadline - time.monotonic())))
    return True


def _run_dask(scene: Scene, grid: Grid, address: str, take, cancel: threading.Event,
              connect_timeout: float = CONNECT_TIMEOUT, worker_timeout: float = WORKER_TIMEOUT):
    try:
        from distributed import Client, wait as dask_wait
    except ImportError:
        raise ValueError("a sweep on a Dask cluster needs Dask distributed: "
                         "pip install 'rollball[dask]'") from None
    if not address.startswith("inproc://"):
        _probe(address, connect_timeout, cancel)
    try:
        client = Client(address, timeout=f"{connect_timeout}s")
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"cannot reach the Dask scheduler at {address}: {e}") from None
    with client:
        def worker_count() -> int:
            return len(client.scheduler_info().get("workers", {}))

        if not _wait_until(lambda: worker_count() > 0, worker_timeout, cancel):
            raise ValueError(f"the Dask scheduler at {address} has no workers: none joined within "
                             f"{worker_timeout:g} s (--worker-timeout)")
        workers = worker_count()
        threads = sum(client.nthreads().values()) or 1
        futures = client.map(batch.run, _tasks(scene, grid, threads), pure=False)
        pending, alone_since = set(futures), None
        while pending:
            try:
                finished, pending = dask_wait(pending, timeout=POLL, return_when="FIRST_COMPLETED")
            except TimeoutError:
                finished = set()
            for future in finished:
                try:
                    take(future.result())
                except Exception as error:  # e.g. KilledWorker: the batch took down workers repeatedly
                    client.cancel(futures)
                    return workers, f"a batch failed on the cluster ({type(error).__name__}: {error})"
            if cancel.is_set():
                client.cancel(futures)
                break
            if worker_count():
                alone_since = None
            elif alone_since is None:
                alone_since = time.monotonic()
            elif time.monotonic() - alone_since > worker_timeout:
                client.cancel(futures)
                return workers, f"the cluster lost its workers: none for {worker_timeout:g} s (--worker-timeout)"
    return workers, None
