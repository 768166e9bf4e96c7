"""Fixtures for driving the real window under Xvfb (pytest-xvfb starts it, with GLX)."""

import pytest
from PySide6 import QtCore, QtWidgets

from rollball_app.garbage import collect_anywhere, collect_on_gui_thread
from rollball_app.main import prepare_qt
from rollball_app.preferences import Preferences
from rollball_app.window import MainWindow
from rollball.examples import EXAMPLES_DIR
from rollball.warmup import warm_up

prepare_qt()  # before pytest-qt creates the QApplication


@pytest.fixture(scope="session", autouse=True)
def compiled_kernel():
    """Compile (or load) the kernel of every method once, before anything in a window is timed:
    with empty caches a method's first run compiles for tens of seconds on a busy machine."""
    warm_up()


@pytest.fixture(scope="package", autouse=True)
def garbage_on_gui_thread(qapp):
    """As in the app: cycles are collected on the GUI thread only (``rollball_app.garbage``); the tests
    outside this folder get Python's automatic collection back."""
    collect_on_gui_thread()
    yield
    collect_anywhere()


@pytest.fixture
def dialogs(monkeypatch):
    """Message boxes are recorded instead of shown: (kind, title, text)."""
    shown = []

    def record(kind, answer):
        def box(parent, title, text, *args, **kwargs):
            shown.append((kind, title, text))
            return answer
        return box

    buttons = QtWidgets.QMessageBox.StandardButton
    monkeypatch.setattr(QtWidgets.QMessageBox, "warning", record("warning", buttons.Ok))
    monkeypatch.setattr(QtWidgets.QMessageBox, "information", record("information", buttons.Ok))
    monkeypatch.setattr(QtWidgets.QMessageBox, "question", record("question", buttons.Discard))
    return shown


@pytest.fixture
def preferences(tmp_path):
    return Preferences(QtCore.QSettings(str(tmp_path / "preferences.ini"), QtCore.QSettings.Format.IniFormat))


@pytest.fixture
def window(qtbot, dialogs, preferences):
    """The main window on the hills example, shown."""
    w = MainWindow(preferences)
    qtbot.addWidget(w)
    w.files.open_scene(EXAMPLES_DIR / "hills.json", remember=False)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.document.saved_scene = w.scene  # nothing to ask about when the test closes it
    w.close()
