"""The integrator's warm-up: every method compiled in a process of its own from launch
(``python -m rollball.warmup``), its machine code kept on disk where a run finds it.

The process says ``ready METHOD mk|classic`` as each variant is ready; the window's Start waits
for its variant (``must_wait``) and goes when it is ready or the process has ended.
"""

from __future__ import annotations

import sys

from PySide6 import QtCore

from rollball import RunSpec


class WarmUp(QtCore.QObject):
    """One warm-up process at a time. ``readied``: a variant is ready; ``ended``: the process
    has ended (or could not start) and is let go."""

    readied = QtCore.Signal()
    ended = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.process: QtCore.QProcess | None = None   # compiling in the background
        self.ready: set[RunSpec] = set()               # what it has compiled so far

    @staticmethod
    def command(first: RunSpec | None = None) -> list[str]:
        """The warm-up's command line, ``first`` compiled first."""
        return [sys.executable, "-m", "rollball.warmup", *([] if first is None else [str(first)])]

    def start(self, command: list[str]) -> None:
        process = QtCore.QProcess(self)
        process.setProcessChannelMode(QtCore.QProcess.ProcessChannelMode.ForwardedErrorChannel)
        process.readyReadStandardOutput.connect(self._read)
        process.finished.connect(self._ended)
        process.errorOccurred.connect(lambda _error: self._ended())
        self.process, self.ready = process, set()
        process.start(command[0], command[1:])

    def must_wait(self, spec: RunSpec | None) -> bool:
        """Whether a run of ``spec`` (None: several, or not known) started now would compile
        what the process is compiling."""
        return self.process is not None and (spec is None or spec not in self.ready)

    def _read(self) -> None:
        if self.process is None:
            return
        for line in bytes(self.process.readAllStandardOutput()).decode(errors="replace").splitlines():
            words = line.split()
            if len(words) == 3 and words[0] == "ready":
                self.ready.add(RunSpec(words[1], words[2] == "mk"))
        self.readied.emit()

    def _ended(self) -> None:
        if self.process is None:
            return
        self.process.deleteLater()
        self.process = None
        self.ended.emit()

    def stop(self) -> None:
        """Kill the process (closing): disconnected first, so that nothing it says or its end
        reaches the window, then waited for and deleted."""
        process, self.process = self.process, None
        if process is None:
            return
        for signal in (process.readyReadStandardOutput, process.finished, process.errorOccurred):
            signal.disconnect()
        process.kill()
        process.waitForFinished(5000)
        process.deleteLater()
