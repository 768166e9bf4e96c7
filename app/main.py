"""Start the app: ``python -m app [SCENE.json]`` or the installed ``rollball-app``."""

from __future__ import annotations

import argparse
import sys


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
    args = parser.parse_args(argv)

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
    window.open_scene(path, remember=named_file)
    window.show()
    return app.exec()
