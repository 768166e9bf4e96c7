"""Start the app: ``python -m app [SCENE.json]`` or the installed ``rollball-app``."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path


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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rollball-app", description="RollBall: a ball rolling on a landscape")
    parser.add_argument("scene", nargs="?", help="scene file or example name to open (default: hills)")
    parser.add_argument("--run-to", type=_positive, metavar="T", help="run the scene to time T (seconds)")
    parser.add_argument("--record", metavar="VIDEO", help="record the playback from 0 to T as .mp4 or .gif "
                        "and exit")
    parser.add_argument("--fps", type=_positive, default=None, metavar="N",
                        help="frames per simulated second of --record (default 30)")
    parser.add_argument("--size", type=_size, metavar="WxH", help="frame size of --record in pixels "
                        "(default: the 3-D view's size)")
    args = parser.parse_args(argv)
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

    from rollball.examples import DEFAULT_EXAMPLE, scene_path

    try:
        path = scene_path(args.scene) if args.scene else DEFAULT_EXAMPLE
    except FileNotFoundError as error:
        parser.exit(2, f"rollball-app: error: {error}\n")

    from PySide6 import QtWidgets

    prepare_qt()
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setOrganizationName("RollBall")
    app.setApplicationName("RollBall")

    from .window import MainWindow

    window = MainWindow()
    named_file = args.scene is not None and str(path) == args.scene   # not an example's name
    window.open_scene(path, remember=named_file and args.record is None)
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
