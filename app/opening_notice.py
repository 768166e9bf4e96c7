"""Never silent while the app opens: the first launch after an install imports (and compiles to
bytecode) sympy, numba, scipy, Qt and pyqtgraph for many seconds before the window shows; the
terminal that started it hears every ``EVERY`` seconds that the app is still opening."""

from __future__ import annotations

import sys
import threading
import time

EVERY = 5.0   # seconds between lines (the setup's heartbeat says the same every 5 s)


class OpeningNotice:
    """``start()`` from the launch on, ``done()`` once the window is up: meanwhile a line on
    ``stream`` (stderr) every ``every`` seconds, "rollball: still opening the app (N s)"."""

    def __init__(self, every: float = EVERY, stream=None):
        self.every = every
        self.stream = stream if stream is not None else sys.stderr
        self._done = threading.Event()
        self._started = time.monotonic()
        self._thread = threading.Thread(target=self._say, name="opening notice", daemon=True)

    def start(self) -> OpeningNotice:
        self._started = time.monotonic()
        self._thread.start()
        return self

    def done(self) -> None:
        self._done.set()

    def _say(self) -> None:
        while not self._done.wait(self.every):
            try:
                print(f"rollball: still opening the app ({time.monotonic() - self._started:.0f} s)",
                      file=self.stream, flush=True)
            except (OSError, ValueError):   # the terminal has gone: nothing to say it to
                return
