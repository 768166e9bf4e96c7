"""Cycles holding Qt objects are freed on the GUI thread, never on a worker thread that
happens to allocate (there, freeing a QObject deadlocks against the GUI thread)."""

import gc
import threading

from PySide6 import QtWidgets

from rollball_app.garbage import INTERVAL


class Cycle:
    """A cycle (it refers to itself) holding a widget with a child menu; records the thread
    that frees it."""

    freed_on: list[str] = []

    def __init__(self):
        self.me = self
        self.widget = QtWidgets.QWidget()
        QtWidgets.QMenu(self.widget).addAction("an action")

    def __del__(self):
        Cycle.freed_on.append(threading.current_thread().name)


def test_cycles_are_freed_on_the_gui_thread_while_a_worker_allocates(qtbot):
    assert not gc.isenabled()
    Cycle.freed_on.clear()
    for _ in range(20):
        Cycle()

    def allocate():   # far past every threshold: with automatic collection this collects here
        junk = [[] for _ in range(100_000)]
        for item in junk:
            item.append(item)

    worker = threading.Thread(target=allocate, name="worker")
    worker.start()
    worker.join()
    assert Cycle.freed_on == []                       # not on the worker
    qtbot.waitUntil(lambda: len(Cycle.freed_on) == 20, timeout=int(10_000 * INTERVAL))
    assert set(Cycle.freed_on) == {threading.main_thread().name}
