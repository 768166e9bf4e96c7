"""How responsive the window is, for ``rollball bench``: while a long run is computed and played,
and from an edit of the landscape to the landscape drawn (``latency``).

``python -m rollball_app.responsiveness`` opens the main window on the hills example with h = 1e-4 for
100 s (10⁶ steps), plays it as fast as it is computed, and meanwhile lets a 5 ms timer tick on
the GUI thread. It prints one line of JSON: the longest and the median gap between ticks
(painting included: under Xvfb the GL view is rendered in software, on the same cores as the
integrator), and the latencies of ``latency`` (``--latency``: those alone). It needs a display
(or Xvfb) and writes nothing.

The latency is timed from the change to the 3-D view's next frame on screen (``frameSwapped``,
Xvfb's software GL included), on the ripples example (a sin(k x) cos(k y), a 81 × 81 grid):
a parameter's slider moved (the scene made anew, the surface evaluated with the new values
and redrawn, the run reset: nothing compiled), and a formula's last key, counted from the key
(a valid formula is applied as soon as it is checked, without a typing pause) — to a formula
seen before (the app's own part) and to one never seen (parsed, derived and compiled in the
background from the key on). Then the path's preview (``preview``): from a slider moved to the
frame that shows its preview (computed in the background after the landscape is drawn); and a
key typed into the formula field to the field painted (``keystroke``), once with nothing else
to do, once while previews are computed back to back (``keystroke_previewing``: typing must not
wait for them), and while typing on without a pause (``keystroke_typing``: a key every
``TYPING_INTERVAL_MS``, a term of never-seen formulas typed and then deleted again key by key,
each valid text on the way drawn when it is ready, the deleted ones at once as seen before;
``typing_applied``: how many landscapes were drawn meanwhile).
"""

from __future__ import annotations

import dataclasses
import json
import sys
import tempfile
import time

import numpy as np

TICK_MS = 5
LATENCY_GOAL_MS = 150      # from an edit to the landscape drawn, the app's part (issue 25)
TYPING_INTERVAL_MS = 100   # between the keys of ``keystroke_typing``: a fast typist


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
        window.files.open_scene(DEFAULT_EXAMPLE, remember=False)
        window.files.show_scene(scene)
        window.speed.setCurrentIndex(window.speed.count() - 1)  # as fast as computed
        window.show()
        ticks: list[float] = []
        timer = QtCore.QTimer(interval=TICK_MS)
        timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
        window.runs.start()
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


def latency(repeats: int = 9) -> dict:
    """Milliseconds from an edit to the landscape drawn (medians and longest of ``repeats``), and
    how many landscapes were compiled while the sliders moved (none is right)."""
    import random

    from PySide6 import QtCore, QtTest

    from rollball import landscape as core
    from rollball.examples import scene_path

    from .inputs import DEBOUNCE_MS
    from .main import application
    from .preferences import Preferences
    from .window import MainWindow

    app = application()
    with tempfile.TemporaryDirectory() as folder:
        settings = QtCore.QSettings(f"{folder}/preferences.ini", QtCore.QSettings.Format.IniFormat)
        window = MainWindow(Preferences(settings))
        window.files.open_scene(scene_path("ripples"), remember=False)
        window.show()
        frames = [0]
        window.view.frameSwapped.connect(lambda: frames.__setitem__(0, frames[0] + 1))

        def settle(seconds: float = 0.3) -> None:
            end = time.perf_counter() + seconds
            while time.perf_counter() < end:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 20)

        def drawn_after(change, done=lambda: True, since=None, drawn_at=None) -> float:
            """Seconds from ``change()`` (or from ``since()``, once ``done()``) to the view's next
            frame on screen once ``done()`` (``drawn_at()``: the frames swapped when what is
            waited for was drawn, if a frame may have followed before ``done()`` is seen)."""
            settle()
            started = time.perf_counter()
            change()
            deadline = started + 120
            while not done() and time.perf_counter() < deadline:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 5)
            seen = frames[0] if drawn_at is None else drawn_at()
            while frames[0] == seen and time.perf_counter() < deadline:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 5)
            return time.perf_counter() - (started if since is None else since())

        settle(1.0)
        compiles = []
        real = core._compile
        core._compile = lambda source: compiles.append(source) or real(source)
        try:
            slider = window.panel.parameter_rows.rows["a"].slider
            slider_s = [drawn_after(lambda p=p: slider.setValue(p)) for p in
                        (100 + 800 * (i % 2) + 10 * i for i in range(repeats))]
            slider_compiles = len(compiles)
            field, panel = window.panel.formula, window.panel
            base = window.scene.landscape
            seen = [f"{base}+0.1*x", f"{base}-0.1*x"]
            for text in seen:   # compiled once, beforehand
                field.setText(text)
                panel.apply()
                while panel.checking:
                    app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 5)

            def keystroke(text: str) -> None:   # the formula's last key
                field.setText(text[:-1])
                field.setCursorPosition(len(text) - 1)
                QtTest.QTest.keyClicks(field, text[-1])
            fresh = [f"{base}+{random.randrange(10**8, 10**9)}e-10*x" for _ in range(repeats)]   # never seen
            seen_s, new_s = [], []
            for i in range(repeats):   # in turns, so that the machine's load weighs on both alike
                seen_s.append(drawn_after(lambda t=seen[i % 2]: keystroke(t),
                                          lambda t=seen[i % 2]: window.scene.landscape == t))
                new_s.append(drawn_after(lambda t=fresh[i]: keystroke(t),
                                         lambda t=fresh[i]: window.scene.landscape == t))
        finally:
            core._compile = real
        editing = window.start_editing

        preview_drawn = [None]   # the frames swapped when the shown scene's preview was drawn
        editing.preview.ready.connect(lambda preview: preview_drawn.__setitem__(0, frames[0])
                                      if preview.scene == window.scene else None)

        def move(position: int) -> None:
            preview_drawn[0] = None
            slider.setValue(position)
        preview_s = [drawn_after(lambda p=p: move(p), lambda: preview_drawn[0] is not None,
                                 drawn_at=lambda: preview_drawn[0])
                     for p in (150 + 700 * (i % 2) + 10 * i for i in range(repeats))]
        painted = [0]

        class Paints(QtCore.QObject):
            def eventFilter(self, watched, event):
                if event.type() == QtCore.QEvent.Type.Paint:
                    painted[0] += 1
                return False
        paints = Paints()
        field.installEventFilter(paints)

        def typed() -> float:   # a key into the formula field, to the field painted
            settle(0.05)
            seen, started = painted[0], time.perf_counter()
            QtTest.QTest.keyClick(field, "1")
            while painted[0] == seen and time.perf_counter() < started + 10:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 1)
            elapsed = time.perf_counter() - started
            panel._timer.stop()   # the typing pause never ends: the key is not applied
            return elapsed
        field.setText(base)
        keys_s = [typed() for _ in range(repeats)]

        applied = []
        panel.sceneChanged.connect(applied.append)

        def typing_on(key) -> float:   # keys at a typist's pace, each to the field painted
            seen, started = painted[0], time.perf_counter()
            QtTest.QTest.keyClick(field, key)
            while painted[0] == seen and time.perf_counter() < started + 10:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 1)
            elapsed = time.perf_counter() - started
            while time.perf_counter() < started + TYPING_INTERVAL_MS / 1e3:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 1)
            return elapsed
        field.setText(base)
        field.setCursorPosition(len(base))
        settle()
        term = f"+0.{random.randrange(10**6, 10**7)}*x"   # never seen, valid from "+0" on
        typing_s = [typing_on(char) for char in term] + [typing_on(QtCore.Qt.Key.Key_Backspace) for _ in term]
        panel.sceneChanged.disconnect(applied.append)
        panel._timer.stop()
        scenes = [dataclasses.replace(window.scene, start=dataclasses.replace(window.scene.start, x=x))
                  for x in (0.3, 0.35)]
        busy = []

        def keep_busy():   # previews back to back, as while a slider is dragged
            if not editing.preview.busy:
                editing.preview.request(scenes[len(busy) % 2])
                busy.append(1)
        feeder = QtCore.QTimer(interval=0)
        feeder.timeout.connect(keep_busy)
        feeder.start()
        field.setText(base)
        busy_at_key = []

        def typed_previewing() -> float:
            settle(0.05)
            busy_at_key.append(editing.preview.busy)
            return typed()
        previewing_s = [typed_previewing() for _ in range(repeats)]
        feeder.stop()
        field.removeEventFilter(paints)
        window.document.saved_scene = window.scene  # nothing to ask when it closes
        window.close()

    def ms(values):
        return {"median_ms": float(1e3 * np.median(values)), "longest_ms": float(1e3 * np.max(values))}
    return {"slider": ms(slider_s), "slider_compiles": slider_compiles, "formula_seen": ms(seen_s),
            "formula_new": ms(new_s), "preview": ms(preview_s), "keystroke": ms(keys_s),
            "keystroke_previewing": ms(previewing_s), "keystroke_typing": ms(typing_s), "typing_applied": len(applied),
            "typing_keys": len(typing_s), "typing_interval_ms": TYPING_INTERVAL_MS, "previews_during_keys": len(busy),
            "preview_busy_at_key": int(sum(busy_at_key)), "debounce_ms": DEBOUNCE_MS, "goal_ms": LATENCY_GOAL_MS,
            "repeats": repeats}


if __name__ == "__main__":
    if "--latency" in sys.argv[1:]:
        print(json.dumps(latency()))
    else:
        print(json.dumps({**measure(), "latency": latency()}))
