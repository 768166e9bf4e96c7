"""The app's background work: one ``Worker`` runs a function in a thread of its own and reports
to the GUI thread by signals. It serves the runs' row stream (``stream``), the comparison's
reference run, Speed against Error, sweeps and the check of a typed formula.

A worker's thread is a daemon thread, so no work in flight can hold up quitting or abort the
process as a Qt thread destroyed while running would; every wait for it is bounded
(``WAIT_SECONDS``), and the window waits, bounded, for all of them before it goes
(``finish_all``), so no thread is left running the compiled code while Python ends. A
worker is kept (``Worker.running``) from ``start`` until its function has returned and its
thread has ended, whoever started it: closing the window or a dialog drops no worker in flight.

The integrator's warm-up stays apart (``warmup.WarmUp``): it compiles every method for tens of
seconds, which only a process of its own can do without holding the GUI's interpreter, and
can be killed at once when the window closes.
"""

from __future__ import annotations

import threading
import time
import warnings
from typing import Callable

from PySide6 import QtCore

from rollball.comparison import Cancelled, compute_clock
from rollball.warmup import compile_notice

CHUNK_SECONDS = 0.04
MIN_STEPS, MAX_STEPS = 256, 1 << 20
WAIT_SECONDS = 10.0     # the longest any wait for a worker takes (a cancelled one ends within a chunk)
ENDING_SECONDS = 1.0    # for a thread past its last signal: a few instructions


class Worker(QtCore.QObject):
    """``function(progress, cancel)`` in a thread of its own: ``progress(*args)`` reaches the
    GUI thread as ``progressed(args)``; then ``done(result)``, ``cancelled()`` (the function
    raised ``Cancelled``) or ``failed(message)`` (any other exception: one line, never raised
    into Qt); ``ended()`` last, in every case. ``cancel`` is a ``threading.Event`` the function
    checks; ``cancel()`` sets it and calls ``interrupt`` (e.g. to stop a kernel mid-chunk).
    ``describe`` makes the failure's message from the exception (default: its text)."""

    progressed = QtCore.Signal(tuple)
    done = QtCore.Signal(object)
    failed = QtCore.Signal(str)
    cancelled = QtCore.Signal()
    ended = QtCore.Signal()

    running: set[Worker] = set()   # started and not yet let go of

    def __init__(self, function: Callable, describe: Callable[[Exception], str] = str,
                 interrupt: Callable[[], None] | None = None, name: str = "worker"):
        super().__init__()   # no parent: a worker lives until its function returns, not with a window
        self.function, self.describe, self.interrupt, self.name = function, describe, interrupt, name
        self.cancel_event = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        Worker.running.add(self)
        self.ended.connect(self._let_go)   # queued: runs on the GUI thread after the last signal
        self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            result = self.function(lambda *args: self.progressed.emit(args), self.cancel_event)
        except Cancelled:
            self.cancelled.emit()
        except Exception as error:  # noqa: BLE001 - a refusal or a defect is shown, not raised into Qt
            self.failed.emit(self.describe(error))
        else:
            self.done.emit(result)
        finally:
            self.function = self.interrupt = None   # what it computed with is not kept
            self.ended.emit()

    def is_running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def wait(self, seconds: float = WAIT_SECONDS) -> bool:
        """Wait at most ``seconds`` for the thread to end; whether it has."""
        if self._thread is not None:
            self._thread.join(seconds)
        return not self.is_running()

    def cancel(self, wait: bool = True) -> bool:
        """Ask the function to stop; with ``wait``, wait (bounded) until the thread has ended.
        Whether it has ended."""
        self.cancel_event.set()
        interrupt = self.interrupt
        if interrupt is not None:
            interrupt()
        return self.wait() if wait else not self.is_running()

    def _let_go(self) -> None:
        """The function has returned: once the thread is gone, nothing holds the worker (it is
        deleted on the GUI thread, never on its own). Its connections go first: a slot that
        names the worker (``functools.partial``) is held by Qt, out of the garbage collector's
        sight, and would keep it, and what its function computed with, for good."""
        if not self.wait(ENDING_SECONDS):
            return
        for signal in (self.progressed, self.done, self.failed, self.cancelled, self.ended):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)   # a signal nobody listened to
                signal.disconnect()
        Worker.running.discard(self)


def finish_all(seconds: float = WAIT_SECONDS) -> list[str]:
    """Cancel every worker in flight and wait for them, ``seconds`` in all (closing the app); the
    names of those still running after that (an uninterruptible step: they are left to the
    process's end)."""
    workers = list(Worker.running)
    for worker in workers:
        worker.cancel(wait=False)
    deadline = time.monotonic() + seconds
    for worker in workers:
        if worker.wait(max(0.0, deadline - time.monotonic())):
            Worker.running.discard(worker)
    return sorted(worker.name for worker in workers if worker.is_running())


def one_line(error: Exception) -> str:
    """An unexpected exception as a one-line message: its type and text."""
    return f"{type(error).__name__}: {error}"


# -- the runs' row stream --------------------------------------------------------------

ROWS, COMPILING = "rows", "compiling"   # what a stream's progress says


def stream(simulations, derives, warm_ups=(), seconds: list | None = None) -> Callable:
    """A worker's function that runs each simulation's ``advance`` in chunks until all are done
    or it is cancelled, saying ``progress(ROWS, i, block, ended)`` for run i's new rows passed
    through ``derives[i]`` (an owned array, or None when the chunk has none; ``ended``: its last
    rows, the GUI knows a run has ended only when they are there) and ``progress(COMPILING)``
    while a method's kernel is being compiled (first run on this machine).

    The compiled kernel releases the GIL, so the GUI thread keeps serving events while a chunk
    is computed. Chunks are sized to take about ``CHUNK_SECONDS`` each, so a cancel is
    answered within that time (``interrupt`` cancels the simulations mid-chunk). Several runs
    share the thread: the one furthest behind in simulated time goes next, so they are computed
    in step with each other. ``seconds[i]`` is the processor time spent in run i's ``advance``
    so far (its compute time: ``rollball.comparison.compute_clock``, as the command line
    measures it; wall-clock time would count whatever else the machine does meanwhile); the
    ``warm_ups`` (tiny runs of the same methods) are run first, untimed, so that loading or
    compiling a method's kernel does not count."""
    sims = list(simulations)

    def compute(progress, cancel) -> None:
        with compile_notice(lambda: progress(COMPILING)):
            for warm_up in warm_ups:
                warm_up.advance(rows=False)
            steps = [4096] * len(sims)
            while not cancel.is_set():
                pending = [i for i, sim in enumerate(sims) if not sim.done]
                if not pending:
                    break
                i = min(pending, key=lambda k: sims[k].progress)
                started, cpu = time.perf_counter(), compute_clock()
                rows = sims[i].advance(steps[i])
                elapsed = time.perf_counter() - started   # sizes the chunks: a stop is answered in time
                if seconds is not None:
                    seconds[i] += compute_clock() - cpu    # the run's own processor time
                ended = sims[i].done
                if len(rows) or ended:
                    progress(ROWS, i, derives[i](rows) if len(rows) else None, ended)
                scale = CHUNK_SECONDS / max(elapsed, 1e-6)
                steps[i] = int(min(MAX_STEPS, max(MIN_STEPS, steps[i] * min(4.0, max(0.25, scale)))))

    return compute


def stream_worker(simulations, derives, warm_ups=(), seconds: list | None = None) -> Worker:
    """The worker computing these simulations (``stream``); cancelling it cancels them."""
    sims = list(simulations)

    def interrupt() -> None:
        for sim in sims:
            sim.cancel()

    return Worker(stream(sims, derives, warm_ups, seconds), describe=one_line, interrupt=interrupt,
                  name="runs")


def reference_worker(scene, t_end: float, record_dt: float) -> Worker:
    """The reference run of a comparison (``rollball.comparison.reference_run``): ``done``
    carries (trajectory, its own error estimate); cancelling it stops it within a chunk."""
    from rollball.comparison import reference_run

    return Worker(lambda _progress, cancel: reference_run(scene, t_end, record_dt, cancel=cancel),
                  describe=one_line, name="reference")
