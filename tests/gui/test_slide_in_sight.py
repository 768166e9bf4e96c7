"""A short slide is seen while it happens: the trail is drawn over the ball's ring (which marks a
ball drawn small), not hidden under it, and the ring is tinted in the sliding colour. On the
closed-form billiard shot (``scripted``): the ball slides until T1."""

import numpy as np
import pytest

from rollball_app import contact_view
from rollball_app.controller import FINISHED, Run
from rollball_app.view3d import MARK_FILL
from rollball.trajectory import SLIDING

from .guitools import FASTEST
from .scripted import SCENE, T1, T2, ScriptedSimulation


def near(image: np.ndarray, color: str, tolerance: int = 30) -> int:
    """How many pixels of ``image`` are within ``tolerance`` (sum over r, g, b) of ``color``."""
    rgb = np.round(255 * contact_view.rgba(color)[:3])
    return int((np.abs(image[..., :3].astype(int) - rgb).sum(axis=-1) < tolerance).sum())


@pytest.mark.parametrize("size", [(1024, 768), (1400, 900)])
def test_the_slide_shows_while_the_ball_slides(qtbot, window, tmp_path, size):
    window.resize(*size)
    SCENE.save(tmp_path / "billiard.json")
    window.files.open_scene(tmp_path / "billiard.json", remember=False)
    window.speed.setCurrentIndex(FASTEST)
    window.timeline.set_span(1.0)
    window.controller.start([Run(ScriptedSimulation(), window.landscape)])
    qtbot.waitUntil(lambda: window.controller.state == FINISHED, timeout=20_000)
    view = window.view
    view.setCameraPosition(distance=1.5 * view.opts["distance"])   # from further: the ball drawn small
    window.runs.seek(T1 / 3)   # a third of the way through the slide: a few pixels of trail
    assert window.controller.buffer.mode[window.controller.buffer.index_at(T1 / 3)] == SLIDING
    image = view.image()
    assert view.marks[0].visible()   # a ring marks the ball
    sky = near(image, contact_view.MODE_COLORS[SLIDING])
    assert sky >= 10, sky   # the sliding trail's colour is on screen
    sliding = contact_view.rgba(contact_view.MODE_COLORS[SLIDING])
    assert np.allclose(view.marks[0].fill[:3], sliding[:3])   # and the ring is tinted in it
    window.runs.seek((T1 + T2) / 2)   # rolling: the ring as always
    assert view.marks[0].fill == MARK_FILL
