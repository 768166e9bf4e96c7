"""The integrators in a worker thread, handing over chunks of recorded rows.

The compiled kernel releases the GIL, so the GUI thread keeps serving events while a chunk
is computed. Chunks are sized to take about ``CHUNK_SECONDS`` each, so a stop request is
answered within that time. Several runs share the thread: the one furthest behind in
simulated time goes next, so they are computed in step with each other.
"""

from __future__ import annotations

import time

from PySide6 import QtCore

CHUNK_SECONDS = 0.04
MIN_STEPS, MAX_STEPS = 256, 1 << 20


class SimulationThread(QtCore.QThread):
    """Runs each simulation's ``advance`` in chunks until all are done or stopped.

    ``rowsReady`` carries a run's index and its chunk's new rows passed through that run's
    ``derive`` (an owned array); ``failed`` a one-line message if the core raised (the GUI
    stays up).
    """

    rowsReady = QtCore.Signal(int, object)
    failed = QtCore.Signal(str)

    def __init__(self, simulations, derives, parent=None):
        super().__init__(parent)
        self.simulations = list(simulations)
        self.derives = list(derives)

    def run(self) -> None:
        sims = self.simulations
        steps = [4096] * len(sims)
        try:
            while not self.isInterruptionRequested():
                pending = [i for i, sim in enumerate(sims) if not sim.done]
                if not pending:
                    break
                i = min(pending, key=lambda k: sims[k].progress)
                started = time.perf_counter()
                rows = sims[i].advance(steps[i])
                if len(rows):
                    self.rowsReady.emit(i, self.derives[i](rows))
                elapsed = time.perf_counter() - started
                scale = CHUNK_SECONDS / max(elapsed, 1e-6)
                steps[i] = int(min(MAX_STEPS, max(MIN_STEPS, steps[i] * min(4.0, max(0.25, scale)))))
        except Exception as error:  # a defect in the core must not take the window down
            self.failed.emit(f"{type(error).__name__}: {error}")

    def stop(self) -> None:
        """Cancel the runs and wait for the thread to end (at most about one chunk)."""
        self.requestInterruption()
        for sim in self.simulations:
            sim.cancel()
        self.wait()
