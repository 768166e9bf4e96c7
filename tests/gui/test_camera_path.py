"""The camera is chosen from the path: every example opens with its live path in sight (on
screen, not behind a wall), at 1024×768 and 1400×900; ``valley`` shows its floor."""

import numpy as np
import pytest
from PySide6 import QtGui

from rollball.examples import EXAMPLES_DIR

NAMES = sorted(p.stem for p in EXAMPLES_DIR.glob("*.json"))


def on_screen(view, points) -> np.ndarray:
    """Pixel positions of world points, by Qt's own matrices."""
    w, h = view.width(), view.height()
    m = view.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * view.viewMatrix()
    out = []
    for p in points:
        q = m.map(QtGui.QVector3D(*map(float, p)))
        out.append(((q.x() + 1) * w / 2, (1 - q.y()) * h / 2))
    return np.array(out)


@pytest.mark.parametrize("size", [(1024, 768), (1400, 900)])
def test_every_example_opens_with_its_path_in_sight(qtbot, window, size):
    window.resize(*size)
    view, editing = window.view, window.start_editing
    hidden = {}
    for name in NAMES:
        window.files.open_scene(EXAMPLES_DIR / f"{name}.json", remember=False)
        qtbot.waitUntil(lambda: view.preview.visible() and editing.scene == window.scene
                        and not editing.preview.busy, timeout=30_000)
        path = np.asarray(view.preview.pos)
        samples = path[np.linspace(1, len(path) - 1, 24).astype(int)]
        eye = view.cameraPosition()
        eye = np.array([eye.x(), eye.y(), eye.z()])
        pixels = on_screen(view, samples)
        inside = (pixels[:, 0] >= 0) & (pixels[:, 0] <= view.width()) & (pixels[:, 1] >= 0) \
            & (pixels[:, 1] <= view.height())
        seen = np.array([view.in_sight(p, eye, 2 * window.scene.ball.radius) for p in samples])
        if not (inside.all() and seen.mean() >= 0.9):
            hidden[name] = (int(inside.sum()), int(seen.sum()), len(samples))
    assert not hidden, hidden
