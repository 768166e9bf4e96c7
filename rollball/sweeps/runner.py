"""Running a sweep: the grid cut into batches, run on local threads or a Dask cluster.

Locally, a pool of threads runs the batches: the compiled loop releases the GIL, so the
threads run on all cores at once, sharing one compiled landscape. With a scheduler
address the batches go to a Dask distributed cluster (``client.map`` over the batches,
results taken ``as_completed``); each worker process compiles the landscape on its first
batch. A batch is sized to take a few tenths of a second (Dask's advice: tasks of 100 ms or
more), and there are at least four per worker so that the load evens out.
"""

from __future__ import annotations

import math
import os
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from typing import Callable

import numpy as np

from ..scene import Scene
from ..simulation import MAX_STEPS, step_count
from . import batch
from .grid import Grid
from .outcomes import NOT_RUN, OUTCOMES
from .table import SweepTable

# Landscape evaluations per batch: about 0.2 s on a 2020s core for a small formula.
BATCH_EVALUATIONS = 3_000_000
BATCHES_PER_WORKER = 4
CONNECT_TIMEOUT = "10s"  # to reach a Dask scheduler

Progress = Callable[[int, int, str], None]


def local_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def batch_size(scene: Scene, grid: Grid, workers: int) -> int:
    """Runs per batch: about BATCH_EVALUATIONS landscape evaluations for the longest run,
    and at least BATCHES_PER_WORKER batches per worker."""
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
        evaluations = step_count(dt, t_end) * batch.sweep_method(scene).stages
    except ValueError:
        evaluations = BATCH_EVALUATIONS
    runs = max(1, BATCH_EVALUATIONS // evaluations)
    return max(1, min(runs, math.ceil(grid.size / (BATCHES_PER_WORKER * workers))))


def sweep(scene: Scene, vary, *, workers: int | None = None, scheduler: str | None = None,
          progress: Progress | None = None, cancel: threading.Event | None = None) -> SweepTable:
    """Run the scene once for every combination of the varied values; return the table.

    vary: a mapping from dotted scene keys (``start.vx``, ``ball.radius``, ... see
    ``grid.KEYS``) to their values; the runs are the full grid, the last key varying
    fastest. Local by default, on ``workers`` threads (default: every core); with
    ``scheduler`` (a Dask address, ``tcp://host:8786``) on that cluster instead.
    progress(done, total, text) is called as batches finish; setting ``cancel`` stops the
    sweep after the batches under way, and the table is then ``partial``; so is a sweep whose
    batch failed on a cluster (``table.error`` says why). Raises
    ValueError for a bad grid, a method a sweep cannot run, or bad ``workers``.
    """
    grid = Grid.of(vary)
    batch.sweep_method(scene)
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
        _run_local(_tasks(scene, grid, table.workers), table.workers, take, cancel)
    else:
        table.scheduler = str(scheduler)
        table.workers, table.error = _run_dask(scene, grid, str(scheduler), take, cancel)
    table.seconds = time.perf_counter() - started
    from ..bench.report import machine
    table.machine = machine()
    return table


def _tasks(scene: Scene, grid: Grid, workers: int) -> list[batch.Task]:
    size = batch_size(scene, grid, workers)
    return [batch.Task(scene, grid, lo, min(lo + size, grid.size)) for lo in range(0, grid.size, size)]


def _run_local(tasks, workers: int, take, cancel: threading.Event) -> None:
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="rollball-sweep") as pool:
        pending = {pool.submit(batch.run, task) for task in tasks}
        try:
            while pending:
                finished, pending = wait(pending, timeout=0.1, return_when=FIRST_COMPLETED)
                for future in finished:
                    if not future.cancelled():
                        take(future.result())
                if cancel.is_set():
                    for future in pending:
                        future.cancel()  # those not started; the running ones finish
                    for future in wait(pending).done:
                        if not future.cancelled():
                            take(future.result())
                    break
        finally:  # an error in a batch: do not start the rest
            for future in pending:
                future.cancel()


def _run_dask(scene: Scene, grid: Grid, address: str, take, cancel: threading.Event) -> int:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ValueError("a sweep on a Dask cluster needs Dask distributed: "
                         "pip install 'rollball[dask]'") from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"cannot reach the Dask scheduler at {address}: {e}") from None
    with client:
        workers = len(client.scheduler_info()["workers"])
        threads = sum(client.nthreads().values()) or 1
        futures = client.map(batch.run, _tasks(scene, grid, threads), pure=False)
        for future in as_completed(futures):
            try:
                take(future.result())
            except Exception as error:  # e.g. KilledWorker: the batch took down workers repeatedly
                client.cancel(futures)
                return workers, f"a batch failed on the cluster ({type(error).__name__}: {error})"
            if cancel.is_set():
                client.cancel(futures)
                break
    return workers, None
