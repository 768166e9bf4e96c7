"""Start the app: ``rollball-app [SCENE]`` or ``python -m rollball_app [SCENE]`` (``python -m app
[SCENE]`` in a checkout).

Headless (docs/design.md §7): with ``--screenshot PNG`` the app opens the scene, optionally runs it to
``--run-to T`` (as fast as computed), saves a picture of the window and exits; with
``--record VIDEO`` it records the playback. Exit 0, or non-zero with a one-line message.
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


def application():
    """The QApplication (made once, after ``prepare_qt``), collecting garbage on its own thread."""
    from PySide6 import QtWidgets

    from .garbage import collect_on_gui_thread

    prepare_qt()
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    collect_on_gui_thread()
    return app


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rollball-app", description="RollBall: a ball rolling on a landscape")
    parser.add_argument("scene", nargs="?", help="scene file or example name to open (default: hills)")
    parser.add_argument("--compare", metavar="SPECS",
                        help="open in compare mode with these runs, e.g. euler/classic,rk4/classic,rk4")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="save a picture of the window to PNG and exit (needs a display, e.g. xvfb-run)")
    parser.add_argument("--run-to", type=_positive, metavar="T",
                        help="with --screenshot: the picture at time T (run as fast as computed); "
                             "with --record: record from 0 to T")
    parser.add_argument("--record", metavar="VIDEO", help="record the playback from 0 to T as .mp4 or .gif "
                        "and exit")
    parser.add_argument("--fps", type=_positive, default=None, metavar="N",
                        help="frames per simulated second of --record (default 30)")
    parser.add_argument("--size", type=_size, metavar="WxH", help="the window's size for --screenshot "
                        "(default 1280x860), the frames' for --record (default: the 3-D view's size)")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    fail = lambda message: parser.exit(2, f"rollball-app: error: {message}\n")  # noqa: E731
    if args.screenshot and args.record:
        fail("--screenshot or --record, not both")
    if args.run_to is not None and not (args.screenshot or args.record):
        fail("--run-to needs --screenshot or --record")
    if args.record is not None:
        from .animation import DEFAULT_FPS, MAX_FPS, format_of

        try:
            format_of(args.record)
        except ValueError as error:
            parser.error(str(error))
        args.fps = args.fps or DEFAULT_FPS
        if args.fps > MAX_FPS:
            parser.error(f"--fps: at most {MAX_FPS}")
    elif args.fps is not None:
        parser.error("--fps needs --record")
    if args.compare is not None:
        from rollball import parse_runs

        from .compare_runs import MAX_RUNS

        try:
            specs = parse_runs(args.compare)
        except ValueError as error:
            parser.exit(2, f"rollball-app: error: --compare: {error}\n")
        if len(specs) > MAX_RUNS:
            parser.exit(2, f"rollball-app: error: --compare: at most {MAX_RUNS} runs, not {len(specs)}\n")

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
        if sys.platform.startswith("linux") and not (
                os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.environ.get("QT_QPA_PLATFORM")):
            fail("no display to draw on: run under xvfb-run, or set DISPLAY")

    from PySide6 import QtCore

    app = application()
    app.setOrganizationName("RollBall")
    app.setApplicationName("RollBall")

    from .preferences import Preferences
    from .window import MainWindow

    if args.screenshot:
        with tempfile.TemporaryDirectory(prefix="rollball-app-") as folder:   # the user's preferences stay
            settings = QtCore.QSettings(str(Path(folder) / "preferences.ini"), QtCore.QSettings.Format.IniFormat)
            window = MainWindow(Preferences(settings))
            error = screenshot(window, path, Path(args.screenshot), args.run_to, args.size or (1280, 860),
                               compare=specs if args.compare is not None else None)
            window.document.saved_scene = window.scene   # nothing to ask on closing
            window.close()
        if error:
            fail(error)
        return 0

    window = MainWindow()
    named_file = args.scene is not None and str(path) == args.scene   # not an example's name
    window.open_scene(path, remember=named_file and args.record is None)
    if args.record is None:
        window.prepare_integrator()   # compiled in the background while the user looks around
    if args.compare is not None:
        from .compare_runs import CompareRun

        window.compare.enter([CompareRun.of(spec, window.scene) for spec in specs])
    window.show()
    if args.record is not None:
        return record(app, window, args)
    return app.exec()


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number, not {text!r}")
    return value


def _size(text: str) -> tuple[int, int]:
    width, _, height = text.lower().partition("x")
    if not (width.isdigit() and height.isdigit() and 16 <= int(width) <= 8192 and 16 <= int(height) <= 8192):
        raise argparse.ArgumentTypeError(f"size as WIDTHxHEIGHT in pixels, 16 to 8192 each, not {text!r}")
    return int(width), int(height)


def wait_until(app, done) -> None:
    """Serve events until ``done()`` holds."""
    while not done():
        app.processEvents()
        time.sleep(0.005)


def record(app, window, args) -> int:
    """Headless: run the scene (to --run-to T), record its playback from 0 to T, exit."""
    from dataclasses import replace

    from .controller import FINISHED

    scene = window.scene
    if scene is None:
        print("rollball-app: error: no scene to record", file=sys.stderr)
        return 1
    if args.run_to is not None and args.run_to != scene.duration:
        window.show_scene(replace(scene, duration=args.run_to))
    window.speed.setCurrentIndex(window.speed.count() - 1)   # as fast as computed
    window.start()
    wait_until(app, lambda: window.controller.state == FINISHED)
    try:
        window.export_animation(Path(args.record), fps=args.fps, size=args.size)
    except (OSError, ValueError) as error:
        print(f"rollball-app: error: {args.record}: {getattr(error, 'strerror', None) or error}", file=sys.stderr)
        return 1
    print(window.message.text())
    window.document.saved_scene = window.scene   # nothing to ask on the way out
    return 0


def screenshot(window, scene: Path, out: Path, run_to: float | None, size: tuple[int, int],
               compare=None) -> str | None:
    """Open ``scene`` in the window (in compare mode with these run specs), run it to ``run_to``
    if given, save a PNG of the window to ``out`` atomically; returns None, or why it could not."""
    from PySide6 import QtCore, QtGui, QtWidgets

    from rollball.files import atomic_write_bytes

    from .controller import READY, RUNNING

    problems: list[str] = []
    window._warn = lambda title, text: problems.append(f"{title.lower()}: {text}")   # no dialogs
    app = QtWidgets.QApplication.instance()
    window.resize(*size)
    if not window.open_scene(scene, remember=False):
        return problems[0] if problems else f"cannot open {scene}"
    if compare is not None:
        from .compare_runs import CompareRun

        window.compare.enter([CompareRun.of(spec, window.scene) for spec in compare])
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
            wait_until(app, lambda: controller.state != RUNNING)
        else:
            controller.play_time = run_to
            window.stop()
        if compare is not None:   # the true errors need the reference
            started = time.monotonic()
            while controller.reference is None and not problems and time.monotonic() - started < RUN_TIMEOUT:
                app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
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
