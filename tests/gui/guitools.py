"""Steps a user takes, shared by the GUI tests."""

from app.controller import FINISHED
from app.window import SPEEDS

FASTEST = len(SPEEDS) - 1


def run_to_end(qtbot, window, timeout=30_000):
    """Start (at the fastest playback) and wait until the run has played to its end."""
    window.speed.setCurrentIndex(FASTEST)
    window.start()
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=timeout)


def set_field(qtbot, window, key, text):
    """Type into a scene field as a user would and let the typing pause pass."""
    edit = window.panel.formula if key == "landscape" else window.panel.numbers[key]
    edit.selectAll()
    qtbot.keyClicks(edit, text)
    apply_fields(qtbot, window)


def apply_fields(qtbot, window):
    """End the typing pause now and wait for a formula's background check, if any."""
    window.panel.apply()
    qtbot.waitUntil(lambda: not window.panel.checking, timeout=60_000)
