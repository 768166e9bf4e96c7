"""The app's background work: one ``Worker`` runs a function in a thread of its own, and
``SimulationThread`` hands over the integrators' recorded rows chunk by chunk.

``Worker`` (a function run in a QThread: progress, a result or a failure, a cancel flag) serves
the comparison's reference run, Speed against Error and sweeps. ``SimulationThread`` streams
rows while it computes: the compiled kernel releases the GIL, so the GUI thread keeps serving
events while a chunk is computed. Chunks are sized to take about ``CHUNK_SECONDS`` each, so a
stop request is answered within that time. Several runs share the thread: the one furthest
behind in simulated time goes next, so they are computed in step with each other.

Two kinds of background work stay apart on purpose: the integrator's warm-up is a process of
its own (``warmup.WarmUp``: it compiles and caches every method while the window is used), and
a formula's check is a daemon thread (``inputs.ScenePanel``: a compile cannot be interrupted
and must never hold up quitting).

Every thread is let go of with ``retire`` once its work has ended.
"""

from __future__ import annotations

import threading
import time
from typing import Callable

from PySide6 import QtCore

from rollball.comparison import Cancelled, compute_clock
from rollball.warmup import compile_notice

CHUNK_SECONDS = 0.04
MIN_STEPS, MAX_STEPS = 256, 1 << 20


class SimulationThread(QtCore.QThread):
    """Runs each simulation's ``advance`` in chunks until all are done or stopped.

    ``rowsReady`` carries the ``token`` the thread was made with (whose runs these are), a run's
    index, its chunk's new rows passed through that run's
    ``derive`` (an owned array, or None when the chunk has none) and whether the run has
    ended with it (its last rows: the GUI knows a run has ended only when they are there); ``failed`` a one-line message if the core raised (the GUI
    stays up). ``seconds[i]`` is the processor time this thread spent in run i's ``advance``
    so far (its compute time: ``rollball.comparison.compute_clock``, as the command line
    measures it; wall-clock time would count whatever else the machine does meanwhile);
    the ``warm_ups`` (tiny runs of the same methods) are run first, untimed, so that loading or
    compiling a method's kernel does not count.
    """

    rowsReady = QtCore.Signal(object, int, object, bool)
    failed = QtCore.Signal(str)
    compiling = QtCore.Signal()      # the kernel is being compiled (first run on this machine)

    def __init__(self, simulations, derives, parent=None, warm_ups=(), token=None):
        super().__init__(parent)
        self.token = token
        self.simulations = list(simulations)
        self.derives = list(derives)
        self.warm_ups = list(warm_ups)
        self.seconds = [0.0] * len(self.simulations)

    def run(self) -> None:
        try:
            with compile_notice(self.compiling.emit):
                self._compute()
        except Exception as error:  # a defect in the core must not take the window down
            self.failed.emit(f"{type(error).__name__}: {error}")

    def _compute(self) -> None:
        sims = self.simulations
        steps = [4096] * len(sims)
        for warm_up in self.warm_ups:
            warm_up.advance()
        while not self.isInterruptionRequested():
            pending = [i for i, sim in enumerate(sims) if not sim.done]
            if not pending:
                break
            i = min(pending, key=lambda k: sims[k].progress)
            started, cpu = time.perf_counter(), compute_clock()
            rows = sims[i].advance(steps[i])
            elapsed = time.perf_counter() - started   # sizes the chunks: a stop is answered in time
            self.seconds[i] += compute_clock() - cpu    # the run's own processor time, as on the command line
            ended = sims[i].done
            if len(rows) or ended:
                self.rowsReady.emit(self.token, i, self.derives[i](rows) if len(rows) else None, ended)
            scale = CHUNK_SECONDS / max(elapsed, 1e-6)
            steps[i] = int(min(MAX_STEPS, max(MIN_STEPS, steps[i] * min(4.0, max(0.25, scale)))))

    def stop(self) -> None:
        """Cancel the runs and wait for the thread to end (at most about one chunk)."""
        self.requestInterruption()
        for sim in self.simulations:
            sim.cancel()
        self.wait()


def retire(thread: QtCore.QThread) -> None:
    """Let go of a worker thread whose work has ended. ``finished`` is emitted from inside the
    thread, just before it ends: the object may be deleted (its last Python reference dropped)
    only once the thread has really ended, else Qt aborts the process ("QThread: Destroyed
    while thread is still running"). The wait is for the few instructions after ``finished``."""
    thread.wait()
    thread.deleteLater()


class Worker(QtCore.QThread):
    """``function(progress, cancel)`` in a thread of its own: ``progress(*args)`` reaches the
    GUI thread as ``progressed(args)``; then ``done(result)``, ``cancelled()`` (the function
    raised ``Cancelled``) or ``failed(message)`` (any other exception: one line, never raised
    into Qt). ``cancel`` is a ``threading.Event`` the function checks; ``cancel()`` sets it.
    ``describe`` makes the failure's message from the exception (default: its text)."""

    progressed = QtCore.Signal(tuple)
    done = QtCore.Signal(object)
    failed = QtCore.Signal(str)
    cancelled = QtCore.Signal()

    def __init__(self, function: Callable, parent=None, describe: Callable[[Exception], str] = str):
        super().__init__(parent)
        self.function, self.describe = function, describe
        self.cancel_event = threading.Event()

    def run(self) -> None:
        try:
            result = self.function(lambda *args: self.progressed.emit(args), self.cancel_event)
        except Cancelled:
            self.cancelled.emit()
        except Exception as error:  # noqa: BLE001 - a refusal or a defect is shown, not raised into Qt
            self.failed.emit(self.describe(error))
        else:
            self.done.emit(result)

    def cancel(self, wait: bool = True) -> None:
        """Ask the function to stop; with ``wait``, wait until the thread has ended."""
        self.cancel_event.set()
        if wait:
            self.wait()


def one_line(error: Exception) -> str:
    """An unexpected exception as a one-line message: its type and text."""
    return f"{type(error).__name__}: {error}"


def reference_worker(scene, t_end: float, record_dt: float, parent=None) -> Worker:
    """The reference run of a comparison (``rollball.comparison.reference_run``): ``done``
    carries (trajectory, its own error estimate). It cannot be cancelled (it takes seconds): a
    reference no longer wanted is left to finish, and its result is ignored."""
    from rollball.comparison import reference_run

    return Worker(lambda _progress, _cancel: reference_run(scene, t_end, record_dt), parent, describe=one_line)
