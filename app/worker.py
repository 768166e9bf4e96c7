"""The integrators in a worker thread, handing over chunks of recorded rows.

The compiled kernel releases the GIL, so the GUI thread keeps serving events while a chunk
is computed. Chunks are sized to take about ``CHUNK_SECONDS`` each, so a stop request is
answered within that time. Several runs share the thread: the one furthest behind in
simulated time goes next, so they are computed in step with each other.
"""

from __future__ import annotations

import time

from PySide6 import QtCore

from rollball.comparison import compute_clock
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


class ReferenceThread(QtCore.QThread):
    """Computes the reference run of a comparison (``rollball.comparison.reference_run``).

    ``done`` carries the reference trajectory and its own error estimate; ``failed`` a
    one-line message. It cannot be interrupted (it takes seconds): a reference no longer
    wanted is left to finish, and its result is ignored.
    """

    done = QtCore.Signal(object, float)
    failed = QtCore.Signal(str)

    def __init__(self, scene, t_end: float, record_dt: float, parent=None):
        super().__init__(parent)
        self.scene, self.t_end, self.record_dt = scene, t_end, record_dt

    def run(self) -> None:
        from rollball.comparison import reference_run

        try:
            trajectory, estimate = reference_run(self.scene, self.t_end, self.record_dt)
        except Exception as error:  # noqa: BLE001 - shown, never raised into Qt
            self.failed.emit(f"{type(error).__name__}: {error}")
            return
        self.done.emit(trajectory, estimate)
