"""The integrator in a worker thread, handing over chunks of recorded rows.

The compiled kernel releases the GIL, so the GUI thread keeps serving events while a chunk
is computed. Chunks are sized to take about ``CHUNK_SECONDS`` each, so a stop request is
answered within that time.
"""

from __future__ import annotations

import time

from PySide6 import QtCore

CHUNK_SECONDS = 0.04
MIN_STEPS, MAX_STEPS = 256, 1 << 20


class SimulationThread(QtCore.QThread):
    """Runs ``simulation.advance`` in chunks until it is done or stopped.

    ``rowsReady`` carries each chunk's new rows passed through ``derive`` (an owned array);
    ``failed`` a one-line message if the core raised (the GUI stays up).
    """

    rowsReady = QtCore.Signal(object)
    failed = QtCore.Signal(str)

    def __init__(self, simulation, derive, parent=None):
        super().__init__(parent)
        self.simulation = simulation
        self.derive = derive

    def run(self) -> None:
        sim, steps = self.simulation, 4096
        try:
            while not sim.done and not self.isInterruptionRequested():
                started = time.perf_counter()
                rows = sim.advance(steps)
                if len(rows):
                    self.rowsReady.emit(self.derive(rows))
                elapsed = time.perf_counter() - started
                scale = CHUNK_SECONDS / max(elapsed, 1e-6)
                steps = int(min(MAX_STEPS, max(MIN_STEPS, steps * min(4.0, max(0.25, scale)))))
        except Exception as error:  # a defect in the core must not take the window down
            self.failed.emit(f"{type(error).__name__}: {error}")

    def stop(self) -> None:
        """Cancel the run and wait for the thread to end (at most about one chunk)."""
        self.requestInterruption()
        self.simulation.cancel()
        self.wait()
