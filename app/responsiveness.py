"""How responsive the window stays while a long run is computed and played, for ``rollball bench``.

``python -m rollball_app.responsiveness`` opens the main window on the hills example with h = 1e-4 for
100 s (10⁶ steps), plays it as fast as it is computed, and meanwhile lets a 5 ms timer tick on
the GUI thread. It prints one line of JSON: the longest and the median gap between ticks
(painting included: under Xvfb the GL view is rendered in software, on the same cores as the
integrator). It needs a display (or Xvfb) and writes nothing.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import tempfile
import time

import numpy as np

TICK_MS = 5


def measure() -> dict:
    from PySide6 import QtCore

    from rollball import Scene
    from rollball.examples import DEFAULT_EXAMPLE

    from .main import application
    from .preferences import Preferences
    from .window import MainWindow

    app = application()
    with tempfile.TemporaryDirectory() as folder:  # the user's preferences are not touched
        settings = QtCore.QSettings(f"{folder}/preferences.ini", QtCore.QSettings.Format.IniFormat)
        window = MainWindow(Preferences(settings))
        scene = Scene.load(DEFAULT_EXAMPLE)
        scene = dataclasses.replace(scene, duration=100.0,
                                    integrator=dataclasses.replace(scene.integrator, method="rk4", dt=1e-4))
        window.open_scene(DEFAULT_EXAMPLE, remember=False)
        window.show_scene(scene)
        window.speed.setCurrentIndex(window.speed.count() - 1)  # as fast as computed
        window.show()
        ticks: list[float] = []
        timer = QtCore.QTimer(interval=TICK_MS)
        timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
        window.start()
        controller = window.controller
        deadline = time.monotonic() + 600
        while not (controller.buffer is not None and len(controller.buffer) > 0) and time.monotonic() < deadline:
            app.processEvents()
        timer.start()  # from the first chunk on: the run is under way
        # until computed, and ticking again: on a loaded machine the whole run's rows can arrive
        # in the one batch of events that brought the first chunk, and that stall is a gap too
        while not (controller.computed and len(ticks) >= 2) and time.monotonic() < deadline:
            app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 50)
        timer.stop()
        steps = controller.simulation.steps
        window.document.saved_scene = window.scene  # nothing to ask when it closes
        window.close()
    gaps = np.diff(ticks) if len(ticks) > 1 else np.array([np.nan])
    return {"steps": steps, "ticks": len(ticks), "longest_gap_ms": float(1e3 * gaps.max()),
            "median_gap_ms": float(1e3 * np.median(gaps))}


if __name__ == "__main__":
    print(json.dumps(measure()))
