"""Start the app: ``python -m app [SCENE]`` or the installed ``rollball-app``.

With ``--screenshot PNG`` the app opens the scene, optionally runs it to ``--run-to T`` (as
fast as computed), saves a picture of the window and exits: 0, or 2 with a one-line message
when it cannot (DESIGN §9).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

RUN_TIMEOUT = 600.0   # seconds a --run-to may compute before the screenshot gives up


def prepare_qt() -> None:
    """OpenGL settings that must be made before the QApplication exists."""
    from PySide6 import QtCore, QtGui

    # GL views share one set of shader programs and buffers, whichever window made them
    QtCore.QCoreApplication.setAttribute(QtCore.Qt.ApplicationAttribute.AA_ShareOpenGLContexts)
    if sys.platform == "darwin":  # a core profile is what macOS offers
        fmt = QtGui.QSurfaceFormat()
        fmt.setVersion(4, 1)
        fmt.setProfile(QtGui.QSurfaceFormat.OpenGLContextProfile.CoreProfile)
        fmt.setDepthBufferSize(24)
        QtGui.QSurfaceFormat.setDefaultFormat(fmt)


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a size like 1280x860: {text!r}") from None
    if not (320 <= width <= 8192 and 240 <= height <= 8192):
        raise argparse.ArgumentTypeError(f"width 320 to 8192 and height 240 to 8192 pixels: {text!r}")
    return width, height


def _time(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite time greater than 0: {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rollball-app", description="RollBall: a ball rolling on a landscape")
    parser.add_argument("scene", nargs="?", help="scene file or example name to open (default: hills)")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="save a picture of the window to PNG and exit (needs a display, e.g. xvfb-run)")
    parser.add_argument("--run-to", type=_time, metavar="T",
                        help="with --screenshot: first run the scene to time T (as fast as computed)")
    parser.add_argument("--size", type=_size, metavar="WxH", help="window size in pixels, e.g. 1280x860")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    fail = lambda message: parser.exit(2, f"rollball-app: error: {message}\n")  # noqa: E731
    if args.run_to is not None and not args.screenshot:
        fail("--run-to needs --screenshot")

    from rollball import Scene, SceneError
    from rollball.examples import DEFAULT_EXAMPLE, scene_path

    try:
        path = scene_path(args.scene) if args.scene else DEFAULT_EXAMPLE
    except FileNotFoundError as error:
        fail(str(error))
    if args.screenshot:
        try:
            Scene.load(path)   # refuse a bad scene here, in one line, not in a dialog
        except (SceneError, OSError) as error:
            fail(f"{path}: {error.strerror if isinstance(error, OSError) and error.strerror else error}")
    if args.screenshot and sys.platform.startswith("linux") and not (
            os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.environ.get("QT_QPA_PLATFORM")):
        fail("no display to draw on: run under xvfb-run, or set DISPLAY")

    from PySide6 import QtCore, QtWidgets

    prepare_qt()
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setOrganizationName("RollBall")
    app.setApplicationName("RollBall")

    from .preferences import Preferences
    from .window import MainWindow

    if not args.screenshot:
        window = MainWindow()
        if args.size:
            window.resize(*args.size)
        named_file = args.scene is not None and str(path) == args.scene   # not an example's name
        window.open_scene(path, remember=named_file)
        window.show()
        return app.exec()

    with tempfile.TemporaryDirectory(prefix="rollball-app-") as folder:   # the user's preferences stay
        settings = QtCore.QSettings(str(Path(folder) / "preferences.ini"), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(Preferences(settings))
        error = screenshot(window, path, Path(args.screenshot), args.run_to, args.size or (1280, 860))
        window.document.saved_scene = window.scene   # nothing to ask on closing
        window.close()
    if error:
        fail(error)
    return 0


def screenshot(window, scene: Path, out: Path, run_to: float | None, size: tuple[int, int]) -> str | None:
    """Open ``scene`` in the window, run it to ``run_to`` if given, save a PNG of the window to
    ``out`` atomically; returns None, or why it could not."""
    from PySide6 import QtCore, QtGui, QtWidgets

    from rollball.files import atomic_write_bytes

    from .controller import READY, RUNNING

    problems: list[str] = []
    window._warn = lambda title, text: problems.append(f"{title.lower()}: {text}")   # no dialogs
    app = QtWidgets.QApplication.instance()
    window.resize(*size)
    if not window.open_scene(scene, remember=False):
        return problems[0] if problems else f"cannot open {scene}"
    window.show()
    window.view.reset_camera()   # framed for the final size of the view
    if run_to is not None:
        controller = window.controller
        window.speed.setCurrentIndex(window.speed.count() - 1)   # as fast as computed
        window.start()
        controller.pause()   # the worker computes on; the picture is taken at run_to
        started = time.monotonic()
        while not (controller.computed or controller.end_time >= run_to or problems):
            app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
            if controller.state == READY:
                return problems[0] if problems else "the run did not start"
            if time.monotonic() - started > RUN_TIMEOUT:
                return f"the run did not reach t = {run_to:g} s within {RUN_TIMEOUT:g} s"
        if problems:
            return problems[0]
        if controller.computed and run_to >= controller.end_time:   # the run ends first: its end
            controller.toggle_pause()
            while controller.state == RUNNING:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
        else:
            controller.play_time = run_to
            window.stop()
    for _ in range(5):   # let the last frame be laid out and painted
        app.processEvents()
        time.sleep(0.02)
    image = window.grab().toImage()
    painter = QtGui.QPainter(image)   # the window's picture of the GL view lacks its text (axis labels)
    painter.drawImage(window.view.mapTo(window, QtCore.QPoint(0, 0)), window.view.grabFramebuffer())
    painter.end()
    data = QtCore.QByteArray()
    buffer = QtCore.QBuffer(data)
    buffer.open(QtCore.QIODevice.OpenModeFlag.WriteOnly)
    if not image.save(buffer, "PNG"):
        return "cannot render the window"
    try:
        atomic_write_bytes(out, bytes(data))
    except OSError as error:
        return f"cannot write {out}: {error.strerror or error}"
    return None
