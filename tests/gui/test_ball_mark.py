"""The ball seen from the back of a lecture room: at the default view the true-size ball is a
few pixels across, so a ring marks it; the ball inside stays drawn to scale."""

import numpy as np
import pytest
from PySide6 import QtCore, QtGui

from rollball_app.modes import DEFAULT_SIZE
from rollball_app.view3d import MARK_FRACTION, MARK_PIXELS, MIN_MARK_PIXELS, mark_pixels

from .guitools import set_field
from .test_compare import compare_to_end
from rollball.examples import EXAMPLES_DIR, example_scenes


def _framed(qtbot, window, name):
    window.files.open_scene(EXAMPLES_DIR / f"{name}.json", remember=False)
    window.resize(QtCore.QSize(*DEFAULT_SIZE))   # the default window on a 1400×900 screen
    qtbot.waitUntil(lambda: window.view.framed)
    window.view.reset_camera()
    window.view.image()   # one frame drawn: the marks are placed when a frame is drawn


def _marked_extent(window) -> tuple[int, int]:
    """Width and height in pixels of what the mark adds to the frame (the frame with the mark
    against the frame without it)."""
    view = window.view
    with_mark = view.image()[..., :3].astype(int)
    window.mark_action.setChecked(False)
    without = view.image()[..., :3].astype(int)
    window.mark_action.setChecked(True)
    rows, cols = np.nonzero(np.abs(with_mark - without).sum(axis=-1) > 30)
    if not len(rows):
        return 0, 0
    return int(cols.max() - cols.min() + 1), int(rows.max() - rows.min() + 1)


@pytest.mark.parametrize("name", [path.stem for path, _ in example_scenes()])
def test_every_example_shows_its_ball_at_least_20_pixels_wide(qtbot, window, name):
    """A ball smaller than MARK_PIXELS is ringed (the ring at least 20 pixels wide); a larger
    one is shown as it is."""
    _framed(qtbot, window, name)
    view = window.view
    true = view.ball_pixels()
    assert true > 1
    if true >= MARK_PIXELS:
        assert not view.marks[0].visible()
        return
    assert view.marks[0].visible()
    width, height = _marked_extent(window)
    assert width >= 20 and height >= 20, (width, height, true)
    assert width <= MARK_PIXELS + 12 and height <= MARK_PIXELS + 12   # a mark around the ball, no more
    assert view.ball_pixels() == pytest.approx(true)   # the mark does not change the ball's drawn size


def test_the_hills_ball_is_a_few_pixels_to_scale_and_ringed(qtbot, window):
    _framed(qtbot, window, "hills")
    assert 4 < window.view.ball_pixels() < 15   # why it needs the ring
    assert window.view.marks[0].visible()


def test_the_ball_stays_drawn_to_scale_inside_the_ring(qtbot, window):
    _framed(qtbot, window, "hills")
    view = window.view
    radius = window.scene.ball.radius
    m = np.array(view.ball.transform().data()).reshape(4, 4).T
    assert np.linalg.norm(m[:3, :3], 2) == pytest.approx(radius)   # the mesh: the ball's own radius
    center = view.ball_center
    assert np.allclose(np.array(view.marks[0].pos)[0], center)


def test_a_ball_large_on_screen_is_not_marked_and_the_mark_can_be_turned_off(qtbot, window):
    _framed(qtbot, window, "hills")
    view = window.view
    window.follow_action.setChecked(True)   # zoomed in to the ball: 25 radii away
    view.image()
    assert view.ball_pixels() >= MARK_PIXELS
    assert not view.marks[0].visible()
    window.follow_action.setChecked(False)
    view.reset_camera()
    view.image()
    assert view.marks[0].visible()
    window.mark_action.setChecked(False)
    view.image()
    assert not view.marks[0].visible()
    assert "to scale" in window.mark_action.statusTip()


def test_compare_mode_marks_every_run_in_its_colour(qtbot, window):
    set_field(qtbot, window, "duration", "0.2")
    window.resize(QtCore.QSize(*DEFAULT_SIZE))
    compare_to_end(qtbot, window, "euler/classic,rk4")
    window.view.reset_camera()
    window.view.image()
    view = window.view
    assert len(view.marks) == len(view.balls) == 2
    assert all(mark.visible() for mark in view.marks)
    edges = [tuple(np.round(mark.color[0, :3], 3)) for mark in view.marks]
    assert edges[0] != edges[1]
    window.compare_action.setChecked(False)
    window.view.image()
    assert len(view.marks) == 1


def _ring_in_picture(window, size) -> tuple[int, int]:
    """Width and height in pixels of what the ring adds to an exported picture of ``size``."""
    from rollball_app.picture import render_view

    def pixels():
        image = render_view(window.view, size).convertToFormat(QtGui.QImage.Format.Format_RGB888)
        array = np.frombuffer(image.constBits(), np.uint8, image.sizeInBytes()).reshape(image.height(), -1)
        return array[:, : 3 * image.width()].reshape(image.height(), image.width(), 3).astype(int)

    with_ring = pixels()
    window.mark_action.setChecked(False)
    without = pixels()
    window.mark_action.setChecked(True)
    rows, cols = np.nonzero(np.abs(with_ring - without).sum(axis=-1) > 30)
    return (int(cols.max() - cols.min() + 1), int(rows.max() - rows.min() + 1)) if len(rows) else (0, 0)


@pytest.mark.parametrize("size", [(320, 240), (1920, 1080)])
def test_an_export_rings_the_ball_in_proportion_to_its_size(qtbot, window, size):
    """The ring is the same share of the picture on screen and in a small or a large export
    (30 pixels in the default view, 504 pixels high): not 30 pixels of a 240-pixel video."""
    _framed(qtbot, window, "hills")
    width, height = _ring_in_picture(window, size)
    share = MARK_FRACTION * min(size)
    assert max(width, height) == pytest.approx(share * 7 / 6, abs=3), (width, height)   # the edge disc
    assert max(width, height) / size[1] < 0.1


def test_the_ring_on_screen_follows_the_view_size(qtbot, window):
    assert mark_pixels((912, 504)) == MARK_PIXELS   # the default window's view
    assert mark_pixels((648, 380)) == 23            # on a 1024×768 screen
    assert mark_pixels((320, 240)) == 14 and mark_pixels((1920, 1080)) == 65
    assert mark_pixels((100, 80)) == MIN_MARK_PIXELS
