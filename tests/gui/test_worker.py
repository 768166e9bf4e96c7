"""The app's one worker for background functions: progress, a result, a failure in one line,
a cancel, and a thread let go of only once it has ended."""

import time

from rollball.comparison import Cancelled
from rollball_app.worker import Worker, one_line, retire


def _run(qtbot, worker, signal):
    with qtbot.waitSignal(signal, timeout=10_000) as blocker:
        worker.start()
    qtbot.waitUntil(worker.isFinished, timeout=10_000)
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
    retire(worker)


def test_a_failure_is_one_line_and_never_raised(qtbot):
    worker = Worker(lambda progress, cancel: 1 / 0)
    assert _run(qtbot, worker, worker.failed) == ["division by zero"]
    typed = Worker(lambda progress, cancel: {}["x"], describe=one_line)
    assert _run(qtbot, typed, typed.failed) == ["KeyError: 'x'"]
    retire(worker)
    retire(typed)


def test_cancel_stops_the_function_and_waits_for_the_thread(qtbot):
    def work(progress, cancel):
        while not cancel.is_set():
            time.sleep(0.01)
        raise Cancelled()

    worker = Worker(work)
    with qtbot.waitSignal(worker.cancelled, timeout=10_000):
        worker.start()
        time.sleep(0.05)
        worker.cancel()
        assert worker.isFinished()   # cancel() waited for the thread's end
    retire(worker)
