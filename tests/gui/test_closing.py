"""Closing the window with every kind of background work in flight: a comparison (its runs and
its reference), Speed against Error, a sweep and a formula being checked. It neither hangs
(every wait is bounded) nor raises, and the process exits 0."""

import os
import subprocess
import sys
import time

import pytest
from rollball_app.worker import WAIT_SECONDS, Worker

from .guitools import set_field


def _busy(qtbot, window) -> None:
    """Start every kind of background work the window has, on a long comparison."""
    set_field(qtbot, window, "duration", "200")
    window.compare_action.setChecked(True)
    window.runs.start()
    window.show_speed_against_error()
    window.open_sweep().run()
    window.panel.formula.setText("0.4*sin(1.3*x)*cos(0.7*y) + 0.05*x*y")
    window.panel.apply()   # checked in the background: "checking…" meanwhile
    assert window.panel.checking


def test_closing_with_every_kind_of_work_in_flight_neither_hangs_nor_raises(qtbot, window):
    _busy(qtbot, window)
    names = {worker.name for worker in Worker.running}
    assert {"runs", "reference", "speed against error", "sweep", "formula check"} <= names, names
    window.document.saved_scene = window.scene   # nothing to ask about
    started = time.perf_counter()
    assert window.close()   # pytest-qt fails the test on any exception raised in a Qt callback
    took = time.perf_counter() - started
    print(f"\nclosing with {len(names)} kinds of work in flight took {took:.2f} s")
    assert took < WAIT_SECONDS
    qtbot.waitUntil(lambda: not Worker.running, timeout=5_000)
    qtbot.wait(100)   # what the workers said last is delivered to nobody


SCRIPT = """
import sys
from PySide6 import QtCore
from rollball_app.main import application, close_down
from rollball_app.preferences import Preferences
from rollball_app.window import MainWindow
from rollball.examples import EXAMPLES_DIR

app = application()
window = MainWindow(Preferences(QtCore.QSettings(sys.argv[1], QtCore.QSettings.Format.IniFormat)))
window.files.open_scene(EXAMPLES_DIR / sys.argv[2], remember=False)
window.show()
window.compare_action.setChecked(True)
window.runs.start()
window.show_speed_against_error()
window.open_sweep().run()
window.panel.formula.setText("0.3*sin(2.1*x)*cos(0.9*y)")
window.panel.apply()


def close():
    window.document.saved_scene = window.scene   # nothing to ask about
    window.close()


QtCore.QTimer.singleShot(300, close)
code = app.exec()
close_down(app, window)
print("closed", code)
"""


@pytest.mark.parametrize("example", ["hills.json", "liftoff.json"])   # (liftoff's sweep: worker processes)
def test_the_app_closed_with_work_in_flight_exits_0(tmp_path, example):
    result = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path / "preferences.ini"), example],
                            capture_output=True, text=True, timeout=120, env=dict(os.environ))
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["closed", "0"]
    assert "Traceback" not in result.stderr and "QThread" not in result.stderr, result.stderr
