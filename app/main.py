"""Start the app: ``rollball-app [SCENE]`` or ``python -m rollball_app [SCENE]`` (``python -m app
[SCENE]`` in a checkout).

Headless (docs/design.md §7): with ``--screenshot PNG`` the app opens the scene, optionally runs it to
``--run-to T`` (as fast as computed), saves a picture of the window and exits; with
``--record VIDEO`` it records the playback. Exit 0, or 2 with a one-line message on stderr:
every refusal comes before a window opens (bad options, a scene that cannot be read, an
output that cannot be written or would replace the scene), and a problem met on the way is
said in that one line too, never in a dialog. Bad options are refused before the core or Qt is
loaded (``formats`` and ``compare_limit`` hold what they are checked against), and a missing package of the app's
(PySide6, pyqtgraph, PyOpenGL) is said in that one line with what to install. SIGTERM, SIGINT or SIGHUP during a
headless run ends it cleanly: nothing half-written stays behind, and the exit code is 128 + the signal.

Shutting down: the window and every Qt object in it are deleted while Python is whole
(``close_down``), not left to the interpreter's finalization, where PySide deletes what is
left in no particular order and a pyqtgraph item's Python override, called during that
teardown, crashed the process (exit by SIGSEGV after the file was written).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

from .formats import DEFAULT_FPS, MAX_FPS, MIN_FPS, format_of
from .opening_notice import OpeningNotice

RUN_TIMEOUT = 600.0   # seconds a --run-to may compute before the screenshot gives up
MIN_SIZE, MAX_SIZE = (320, 240), (7680, 4320)   # --size bounds, width × height
DEFAULT_SIZE = (1280, 860)                      # the window's size for --screenshot
STOPPING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGINT", "SIGHUP") if hasattr(signal, name))
# The modules of the app's own packages (pip install 'rollball[app]') that the window needs at once.
APP_PACKAGES = ("PySide6", "pyqtgraph", "OpenGL")


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


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        """One line (not the usage over several), as every other refusal."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rollball-app", description="RollBall: a ball rolling, sliding and flying on a landscape")
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
                        help=f"frames per simulated second of --record, {MIN_FPS} to {MAX_FPS} (default 30)")
    parser.add_argument("--size", type=_size, metavar="WxH",
                        help=f"the window's size for --screenshot (default {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]}), "
                             "the frames' for --record (default: the 3-D view's size); "
                             f"{MIN_SIZE[0]}x{MIN_SIZE[1]} to {MAX_SIZE[0]}x{MAX_SIZE[1]}")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)

    def fail(message: str):
        parser.exit(2, f"rollball-app: error: {message}\n")

    headless = args.screenshot is not None or args.record is not None   # an empty name counts: refused below
    if args.screenshot is not None and args.record is not None:
        fail("--screenshot or --record, not both")
    if args.run_to is not None and not headless:
        fail("--run-to needs --screenshot or --record")
    if args.record is not None:
        try:
            format_of(args.record)
        except ValueError as error:
            fail(f"--record: {error}")
        args.fps = args.fps or DEFAULT_FPS
        if not MIN_FPS <= args.fps <= MAX_FPS:
            fail(f"--fps: from {MIN_FPS} to {MAX_FPS} frames per simulated second, not {args.fps:g}")
    elif args.fps is not None:
        fail("--fps needs --record")
    missing = missing_package()
    if missing:
        fail(f"the app needs {missing}, which is not installed: pip install 'rollball[app]'")
    specs = None
    if args.compare is not None:
        from rollball.run_specs import parse_runs

        from .compare_limit import MAX_RUNS

        try:
            specs = parse_runs(args.compare)
        except ValueError as error:
            fail(f"--compare: {error}")
        if len(specs) > MAX_RUNS:
            fail(f"--compare: at most {MAX_RUNS} runs, not {len(specs)}")

    opening = None if headless else OpeningNotice().start()   # a first launch imports for many seconds
    try:
        return _open(args, specs, headless, fail, opening)
    finally:
        if opening is not None:
            opening.done()


def _open(args, specs, headless: bool, fail, opening: OpeningNotice | None) -> int:
    """The app, from the scene named on the command line (``main``'s arguments checked)."""
    from rollball import Scene, SceneError
    from rollball.examples import DEFAULT_EXAMPLE, scene_path

    try:
        path = scene_path(args.scene) if args.scene else DEFAULT_EXAMPLE
    except FileNotFoundError as error:
        fail(str(error))
    if headless:
        from rollball.files import write_target

        try:
            Scene.load(path)   # refuse a bad scene here, in one line, not in a dialog
        except (SceneError, OSError) as error:
            fail(f"{path}: {_reason(error)}")
        output = args.screenshot if args.screenshot is not None else args.record
        try:   # before anything runs: an empty name, a folder, a FIFO, a read-only file, the scene itself
            target = write_target(output, keep=[path])
        except OSError as error:
            fail(f"{output or repr(output)}: {_reason(error)}")
        if not target.parent.is_dir():
            fail(f"cannot write {output}: no such folder {target.parent}")
        if sys.platform.startswith("linux") and not (
                os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.environ.get("QT_QPA_PLATFORM")):
            fail("no display to draw on: run under xvfb-run, or set DISPLAY")

    app = application()
    app.setOrganizationName("RollBall")
    app.setApplicationName("RollBall")

    if headless:
        with stopped_by_signals() as stopped:
            error = run_headless(app, args, path, specs, stopped)
        if stopped:
            print(f"rollball-app: stopped by {signal.Signals(stopped[0]).name}", file=sys.stderr)
            return 128 + stopped[0]
        if error:
            print(f"rollball-app: error: {error}", file=sys.stderr)
            return 2
        return 0

    from PySide6 import QtCore

    from .window import MainWindow

    window = MainWindow()
    named_file = args.scene is not None and str(path) == args.scene   # not an example's name
    window.files.open_scene(path, remember=named_file)
    window.runs.prepare_integrator()   # compiled in the background while the user looks around
    if specs is not None:
        from .compare_runs import CompareRun

        window.compare.enter([CompareRun.of(spec, window.scene) for spec in specs])
    window.show()
    QtCore.QTimer.singleShot(0, opening.done)   # the window is up once the event loop turns
    code = app.exec()
    close_down(app, window)
    return code


def missing_package() -> str | None:
    """The first of ``APP_PACKAGES`` that cannot be imported, found without importing it (Qt is
    set up by ``prepare_qt`` first), or None."""
    from importlib.util import find_spec

    for name in APP_PACKAGES:
        try:
            if find_spec(name) is None:
                return name
        except (ImportError, ValueError):   # ValueError: a module without a spec in sys.modules
            return name
    return None


def _reason(error: Exception) -> str:
    return error.strerror if isinstance(error, OSError) and error.strerror else str(error)


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
    if not (width.isdigit() and height.isdigit()):
        raise argparse.ArgumentTypeError(f"size as WIDTHxHEIGHT in pixels (e.g. 1280x720), not {text!r}")
    w, h = int(width), int(height)
    if not (MIN_SIZE[0] <= w <= MAX_SIZE[0] and MIN_SIZE[1] <= h <= MAX_SIZE[1]):
        raise argparse.ArgumentTypeError(
            f"WIDTHxHEIGHT from {MIN_SIZE[0]}x{MIN_SIZE[1]} to {MAX_SIZE[0]}x{MAX_SIZE[1]} pixels, not {text!r}")
    return w, h


@contextlib.contextmanager
def stopped_by_signals():
    """While the block runs, SIGTERM, SIGINT and SIGHUP only note themselves in the list
    yielded: the headless loops look at it between events and frames and stop there, so that
    the ordinary way out (an export cancelled, temporary files removed, the window closed)
    is taken. Python runs the handler on the main thread between two bytecodes, never inside
    Qt or the encoder."""
    stopped: list[int] = []

    def note(signum, _frame):
        stopped.append(signum)

    previous = {}
    for s in STOPPING:
        with contextlib.suppress(ValueError, OSError):   # not the main thread: nothing to install
            previous[s] = signal.signal(s, note)
    try:
        yield stopped
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def run_headless(app, args, path: Path, specs, stopped: list) -> str | None:
    """--screenshot or --record in a window with preferences of its own (the user's stay as they
    are), dialogs said as the one-line answer instead; returns None or why it could not."""
    from PySide6 import QtCore

    from .preferences import Preferences
    from .window import MainWindow

    with tempfile.TemporaryDirectory(prefix="rollball-app-") as folder:
        settings = QtCore.QSettings(str(Path(folder) / "preferences.ini"), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(Preferences(settings))
        problems: list[str] = []
        window._warn = lambda title, text: problems.append(f"{title.lower()}: {text}")   # no dialogs
        try:
            if args.screenshot is not None:
                return screenshot(window, path, Path(args.screenshot), args.run_to, args.size or DEFAULT_SIZE,
                                  compare=specs, stopped=stopped)
            return record(app, window, path, args, specs, problems, stopped)
        finally:
            window.document.saved_scene = window.scene   # nothing to ask on closing
            close_down(app, window)


def close_down(app, window) -> None:
    """Close the window and delete it, and every Qt object it holds, now: the worker and
    reference threads are stopped and waited for, the integrator's warm-up process killed
    (``closeEvent``), then the deletion is carried out by sending the deferred deletes and
    Python's cycles are collected on this thread. What is left for the interpreter's
    finalization holds no widget, so no Python override (pyqtgraph's resize handlers) can be
    called while Python is being torn down."""
    from PySide6 import QtCore

    from .garbage import collect_anywhere

    if window.isVisible():
        window.close()   # an interactive window closed by the user has had its closeEvent
    window.controller.shutdown()
    window.runs.stop_preparing()
    app.processEvents()   # what is queued runs while every object it may touch is whole
    for widget in [window, *app.topLevelWidgets()]:
        widget.hide()
        widget.deleteLater()
    for _ in range(3):   # deletions may queue more deletions (deleteLater in destructors)
        app.sendPostedEvents(None, QtCore.QEvent.Type.DeferredDelete)
    collect_anywhere()   # the GUI thread is the only one left: automatic collection is safe again


def wait_until(app, done, stopped=(), timeout: float = RUN_TIMEOUT) -> bool:
    """Serve events until ``done()`` holds (True), a signal came or ``timeout`` s passed (False)."""
    from PySide6 import QtCore

    deadline = time.monotonic() + timeout
    while not done():
        if stopped or time.monotonic() > deadline:
            return False
        app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
        time.sleep(0.005)
    return True


def record(app, window, path: Path, args, specs, problems: list, stopped: list) -> str | None:
    """Headless: run the scene (to --run-to T), record its playback from 0 to T; returns None or
    why it could not."""
    from dataclasses import replace

    from .controller import FINISHED, READY

    if not window.files.open_scene(path, remember=False):
        return problems[0] if problems else f"cannot open {path}"
    if specs is not None:
        from .compare_runs import CompareRun

        window.compare.enter([CompareRun.of(spec, window.scene) for spec in specs])
    window.show()
    scene = window.scene
    if args.run_to is not None and args.run_to != scene.duration:
        window.files.show_scene(replace(scene, duration=args.run_to))
    window.speed.setCurrentIndex(window.speed.count() - 1)   # as fast as computed
    window.runs.start()
    if window.runs.state == READY:
        return problems[0] if problems else "the run did not start"
    if not wait_until(app, lambda: window.controller.state == FINISHED or problems, stopped):
        return None if stopped else f"the run did not end within {RUN_TIMEOUT:g} s"
    if problems:
        return problems[0]
    try:
        done = window.exports.export_animation(Path(args.record), fps=args.fps, size=args.size,
                                       progress=lambda _done, _total: not stopped)
    except (OSError, ValueError) as error:
        return f"{args.record}: {_reason(error)}"
    if problems:
        return problems[0]
    if done:
        print(window.message.text())
    return None


def screenshot(window, scene: Path, out: Path, run_to: float | None, size: tuple[int, int],
               compare=None, stopped=()) -> str | None:
    """Open ``scene`` in the window (in compare mode with these run specs), run it to ``run_to``
    if given, save a PNG of the window to ``out`` atomically; returns None, or why it could not."""
    from PySide6 import QtCore, QtGui, QtWidgets

    from rollball.files import atomic_write_bytes

    from .controller import READY, RUNNING

    problems: list[str] = []
    window._warn = lambda title, text: problems.append(f"{title.lower()}: {text}")   # no dialogs
    app = QtWidgets.QApplication.instance()
    window.resize(*size)
    if not window.files.open_scene(scene, remember=False):
        return problems[0] if problems else f"cannot open {scene}"
    if compare is not None:
        from .compare_runs import CompareRun

        window.compare.enter([CompareRun.of(spec, window.scene) for spec in compare])
    window.show()
    window.view.reset_camera()   # framed for the final size of the view
    if run_to is None:   # the picture before a run shows the live path (the camera framed with it)
        wait_until(app, lambda: not window.start_editing.preview.busy, stopped)
    else:
        controller = window.controller
        window.speed.setCurrentIndex(window.speed.count() - 1)   # as fast as computed
        window.runs.start()
        controller.pause()   # the worker computes on; the picture is taken at run_to
        started = time.monotonic()
        while not (controller.computed or controller.end_time >= run_to or problems):
            app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
            if stopped:
                return None
            if controller.state == READY:
                return problems[0] if problems else "the run did not start"
            if time.monotonic() - started > RUN_TIMEOUT:
                return f"the run did not reach t = {run_to:g} s within {RUN_TIMEOUT:g} s"
        if problems:
            return problems[0]
        if controller.computed and run_to >= controller.end_time:   # the run ends first: its end
            controller.toggle_pause()
            wait_until(app, lambda: controller.state != RUNNING, stopped)
        else:
            controller.play_time = run_to
            window.runs.stop()
        if compare is not None:   # the true errors need the reference
            wait_until(app, lambda: controller.reference is not None or problems, stopped)
        if stopped:
            return None
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
    if stopped:
        return None
    try:
        atomic_write_bytes(out, bytes(data), keep=[scene])
    except OSError as error:
        return f"cannot write {out}: {_reason(error)}"
    return None
