"""Python's cycle collector runs on the GUI thread only.

A collection frees whatever Qt objects sit in unreachable cycles (a closed dialog, a finished
window). Left automatic, it runs on whichever thread happens to allocate, a run's or a sweep's
worker thread too; freeing a QObject there takes Qt's connection lock and then waits for the
GIL, while the GUI thread, holding the GIL, waits for that lock: both stop for good. So the app
switches automatic collection off and collects on a timer of the GUI thread instead
(pyqtgraph's ``GarbageCollector``: every generation when its count is over the threshold).
"""

from __future__ import annotations

import gc

from pyqtgraph.util.garbage_collector import GarbageCollector

INTERVAL = 1.0   # seconds between checks

_collector: GarbageCollector | None = None


def collect_on_gui_thread() -> None:
    """From now on collect only on this (the GUI) thread; once per process. Needs the
    QApplication."""
    global _collector
    if _collector is None:
        _collector = GarbageCollector(interval=INTERVAL)


def collect_anywhere() -> None:
    """Back to Python's automatic collection (for a test session that goes on without Qt)."""
    global _collector
    if _collector is not None:
        _collector.timer.stop()
        _collector = None
        gc.collect()
        gc.enable()
