"""Regenerate the pictures in docs/: the README's and the manual's screenshot (hills, run to t = 4 s) and a
contact sheet of every example as it opens (docs/examples.png, the 3-D view of each).

Run under a display with OpenGL, e.g. ``xvfb-run -a -s "-screen 0 1400x900x24 +extension GLX
+render" .venv/bin/python scripts/pictures.py`` (``scripts/pictures`` does that).
"""

import sys
import tempfile
from pathlib import Path

from PySide6 import QtCore, QtGui

from rollball_app.main import application, screenshot
from rollball_app.preferences import Preferences
from rollball_app.window import MainWindow
from rollball.examples import example_scenes, scene_path
from rollball.files import atomic_write_bytes

DOCS = Path(__file__).resolve().parent.parent / "docs"
COLUMNS, CELL = 2, (640, 430)   # the sheet: views scaled to this size, two per row
TITLE = 24                       # pixels above each view for its name and description


def png(image: QtGui.QImage) -> bytes:
    data = QtCore.QByteArray()
    buffer = QtCore.QBuffer(data)
    buffer.open(QtCore.QIODevice.OpenModeFlag.WriteOnly)
    image.save(buffer, "PNG")
    return bytes(data)


def main() -> int:
    app = application()
    with tempfile.TemporaryDirectory() as folder:
        settings = QtCore.QSettings(str(Path(folder) / "preferences.ini"), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(Preferences(settings))
        error = screenshot(window, scene_path("hills"), DOCS / "screenshot.png", 4.0, (1280, 860))
        if error:
            print(f"pictures: {error}", file=sys.stderr)
            return 1
        examples = example_scenes()
        rows = -(-len(examples) // COLUMNS)
        sheet = QtGui.QImage(COLUMNS * CELL[0], rows * (CELL[1] + TITLE), QtGui.QImage.Format.Format_RGB32)
        sheet.fill(QtGui.QColor("white"))
        painter = QtGui.QPainter(sheet)
        for k, (path, scene) in enumerate(examples):
            error = screenshot(window, path, Path(folder) / "example.png", None, (1280, 860))
            if error:
                print(f"pictures: {path.stem}: {error}", file=sys.stderr)
                return 1
            view = window.view.grabFramebuffer().scaled(*CELL, QtCore.Qt.AspectRatioMode.KeepAspectRatio,
                                                        QtCore.Qt.TransformationMode.SmoothTransformation)
            x, y = (k % COLUMNS) * CELL[0], (k // COLUMNS) * (CELL[1] + TITLE)
            painter.drawText(QtCore.QRect(x + 6, y + 4, CELL[0] - 12, TITLE - 4),
                             QtCore.Qt.AlignmentFlag.AlignLeft | QtCore.Qt.TextFlag.TextSingleLine,
                             f"{path.stem}: {scene.description}")
            painter.drawImage(x + (CELL[0] - view.width()) // 2, y + TITLE, view)
        painter.end()
        atomic_write_bytes(DOCS / "examples.png", png(sheet))
        window.document.saved_scene = window.scene
        window.close()
    del app
    print(f"wrote {DOCS / 'screenshot.png'} and {DOCS / 'examples.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
