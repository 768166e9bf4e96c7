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
    parser.add_argument("scene", nargs="?", help="scene file to open (default: the hills example)")
    args = parser.parse_args(argv)

    from PySide6 import QtWidgets

    prepare_qt()
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setOrganizationName("RollBall")
    app.setApplicationName("RollBall")

    from rollball.examples import DEFAULT_EXAMPLE

    from .window import MainWindow

    window = MainWindow()
    window.open_scene(args.scene or DEFAULT_EXAMPLE, remember=args.scene is not None)
    window.show()
    return app.exec()
