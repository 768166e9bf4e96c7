"""Worker processes for the sweeps whose runs hold the interpreter's lock.

A run whose contact can slip or come to rest goes through ``Simulation``, whose Python holds
the GIL between its kernel calls (a quarter to a half of a run that flies, when flights went
that way too): on threads such runs wait on each other (a sweep on two cores ran 1.2–1.3 times
as fast as on one). Those sweeps run their batches in worker processes
instead: a loky process pool, one per worker count, shared by the sweeps of this process
whatever thread runs them. Its workers are started afresh (fork and exec: nothing of this
process, its threads or its Qt, is copied, and a script's main module is not run again); each
one ends after ``IDLE`` seconds without a batch and is started again when needed, so sweeps in
a row (the app's, a bench's) do not start them again and keep the landscapes they compiled. A
worker never sees the terminal's Ctrl-C (``held_interrupts``: the sweep's own process decides
what an interrupt stops) and loads the kernel's machine code when it starts.
"""

from __future__ import annotations

import contextlib
import signal
import threading

IDLE = 300   # seconds an idle worker is kept

_lock = threading.Lock()
_pools: dict = {}   # worker count -> loky's ProcessPoolExecutor


def start_worker() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from .. import machine_code
    machine_code.entries()


def pool(workers: int):
    """The shared pool of ``workers`` processes. Raises OSError (or ImportError,
    NotImplementedError) where this system cannot make one."""
    from loky import ProcessPoolExecutor

    with _lock:
        if workers not in _pools:
            _pools[workers] = ProcessPoolExecutor(max_workers=workers, timeout=IDLE, initializer=start_worker)
        return _pools[workers]


def discard(executor) -> None:
    """Stop using a pool whose worker died (``BrokenProcessPool``): the next sweep makes another."""
    with _lock:
        for workers, kept in list(_pools.items()):
            if kept is executor:
                del _pools[workers]
    executor.shutdown(wait=False)


def close() -> None:
    """Shut every pool down (their workers end after their batches); later sweeps make new ones."""
    with _lock:
        pools = list(_pools.values())
        _pools.clear()
    for executor in pools:
        executor.shutdown(wait=True)


@contextlib.contextmanager
def held_interrupts():
    """Ctrl-C (SIGINT) blocked in this thread while it starts worker processes (a submit starts
    them, and loky's threads that may start more later): a process inherits the blocked signal
    through exec, so a terminal's interrupt, which goes to every process of its group, never
    reaches a worker, not even while it starts up. An interrupt meanwhile goes to another thread
    of this process, or waits for this one: none is lost."""
    if not hasattr(signal, "pthread_sigmask"):   # (Windows: no process groups to interrupt)
        yield
        return
    import multiprocessing.resource_tracker

    from loky.backend import resource_tracker

    # the resource trackers a pool needs, started first: starting one unblocks SIGINT
    resource_tracker.ensure_running()
    multiprocessing.resource_tracker.ensure_running()
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
