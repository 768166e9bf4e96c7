"""The app's one worker for background functions: progress, a result, a failure in one line,
a cancel, bounded waits, and a worker kept until its thread has ended, whoever started it."""

import functools
import gc
import time
import weakref

import numpy as np

from PySide6 import QtCore

from rollball.comparison import Cancelled
from rollball_app.worker import Worker, finish_all, one_line


def _run(qtbot, worker, signal):
    with qtbot.waitSignal(signal, timeout=10_000) as blocker:
        worker.start()
    qtbot.waitUntil(lambda: worker not in Worker.running, timeout=10_000)   # it let go of itself
    assert not worker.is_running()
    return blocker.args


def test_the_result_and_the_progress_reach_the_gui_thread(qtbot):
    seen = []

    def work(progress, cancel):
        for k in range(3):
            progress(k, 3, f"step {k}")
        return "result"

    worker = Worker(work)
    worker.progressed.connect(seen.append)
    assert _run(qtbot, worker, worker.done) == ["result"]
    qtbot.waitUntil(lambda: len(seen) == 3)
    assert seen == [(0, 3, "step 0"), (1, 3, "step 1"), (2, 3, "step 2")]


def test_a_failure_is_one_line_and_never_raised(qtbot):
    worker = Worker(lambda progress, cancel: 1 / 0)
    assert _run(qtbot, worker, worker.failed) == ["division by zero"]
    typed = Worker(lambda progress, cancel: {}["x"], describe=one_line)
    assert _run(qtbot, typed, typed.failed) == ["KeyError: 'x'"]


def test_cancel_stops_the_function_and_waits_for_the_thread(qtbot):
    interrupted = []

    def work(progress, cancel):
        while not cancel.is_set():
            time.sleep(0.01)
        raise Cancelled()

    worker = Worker(work, interrupt=lambda: interrupted.append(True))
    with qtbot.waitSignal(worker.cancelled, timeout=10_000):
        worker.start()
        time.sleep(0.05)
        assert worker.cancel()
        assert not worker.is_running() and interrupted == [True]   # cancel() waited for the thread's end
    qtbot.waitUntil(lambda: worker not in Worker.running, timeout=10_000)


def test_closing_waits_for_work_in_flight_at_most_as_long_as_it_is_told(qtbot):
    """A step that cannot be interrupted (a formula's compile) holds up closing only for the
    bound given; one that can is cancelled and ends within it."""
    def stubborn(progress, cancel):
        time.sleep(1.5)

    def willing(progress, cancel):
        while not cancel.is_set():
            time.sleep(0.01)

    workers = [Worker(stubborn, name="stubborn"), Worker(willing, name="willing")]
    for worker in workers:
        worker.start()
    started = time.perf_counter()
    assert finish_all(0.3) == ["stubborn"]
    assert time.perf_counter() - started < 1.0
    assert not workers[1].is_running() and workers[1] not in Worker.running
    assert finish_all(10) == [] and not Worker.running


def test_a_worker_outlives_the_window_that_started_it(qtbot):
    """What a worker says after its receiver is deleted goes nowhere: no error, no crash, and
    the worker lets go of itself."""
    class Owner(QtCore.QObject):
        def __init__(self):
            super().__init__()
            self.seen = []

        def take(self, result):
            self.seen.append(result)

    owner = Owner()
    worker = Worker(lambda progress, cancel: time.sleep(0.2) or "late")
    worker.done.connect(owner.take)
    worker.start()
    owner.deleteLater()
    qtbot.wait(10)   # the owner is deleted while the worker computes
    qtbot.waitUntil(lambda: worker not in Worker.running, timeout=10_000)


def test_a_worker_let_go_of_is_freed_with_what_it_computed_with(qtbot):
    """A slot naming its worker (as the run controller's do) keeps nothing once it has ended:
    100 runs must not keep 100 runs' arrays."""
    big = np.ones(10**6)
    worker = Worker(lambda progress, cancel, big=big: float(big.sum()))
    worker.done.connect(functools.partial(lambda w, result: None, worker))
    freed, kept = weakref.ref(worker), weakref.ref(big)
    worker.start()
    del worker, big
    qtbot.waitUntil(lambda: not Worker.running, timeout=10_000)
    gc.collect()
    assert freed() is None and kept() is None
