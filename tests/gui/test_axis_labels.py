"""The 3-D view's axis numbers and names never overlap: with presentation's large text the short
height axis had its numbers run into each other and into "z (m)"; a small export likewise."""

import pytest
from PySide6 import QtCore, QtGui

from rollball_app.picture import labels_at
from rollball_app.view3d import label_pixels
from rollball.examples import EXAMPLES_DIR


def _boxes(view, size) -> list[tuple[str, QtCore.QRectF]]:
    """Each label shown in a picture of ``size``: its text and the box its letters take."""
    scale = size[0] / max(1, view.width())
    boxes = []
    for x, y, item in labels_at(view, size):
        font = QtGui.QFont(item.font)
        font.setPixelSize(label_pixels(item, scale))
        metrics = QtGui.QFontMetricsF(font)
        boxes.append((item.text, QtCore.QRectF(x, y - metrics.ascent(), metrics.horizontalAdvance(item.text),
                                               metrics.ascent() + metrics.descent())))
    return boxes


def _overlaps(boxes) -> list[tuple[str, str]]:
    return [(a, b) for i, (a, ra) in enumerate(boxes) for b, rb in boxes[i + 1:] if ra.intersects(rb)]


@pytest.mark.parametrize("name", ["hills", "bowl"])
def test_presentation_text_leaves_every_axis_label_clear_of_the_others(qtbot, window, name):
    window.files.open_scene(EXAMPLES_DIR / f"{name}.json", remember=False)
    window.presentation_action.setChecked(True)
    qtbot.waitUntil(window.isFullScreen, timeout=5_000)
    qtbot.wait(300)
    view = window.view
    view.image()   # a frame drawn: the labels are laid out for it
    size = (view.width(), view.height())
    boxes = _boxes(view, size)
    assert not _overlaps(boxes), _overlaps(boxes)
    texts = [text for text, _ in boxes]
    assert {"x (m)", "y (m)", "z (m)"} <= set(texts)   # every axis keeps its name
    assert len(texts) >= 8, texts    # and most numbers stay
    window.presentation_action.setChecked(False)


@pytest.mark.parametrize("size", [(320, 240), (1920, 1080)])
def test_an_exported_picture_leaves_every_axis_label_clear_of_the_others(qtbot, window, size):
    from rollball_app.picture import render_view

    render_view(window.view, size)   # lays the labels out for the picture
    boxes = _boxes(window.view, size)
    assert not _overlaps(boxes), _overlaps(boxes)
    assert "z (m)" in [text for text, _ in boxes]


def _axis_points(view) -> list[tuple[float, float]]:
    """Points along the axes' lines and ticks as drawn on screen (the view's own projection)."""
    w, h = view.width(), view.height()
    matrix = view.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * view.viewMatrix()
    points = []
    pos = view.axes.pos
    for a, b in zip(pos[0::2], pos[1::2]):
        for t in [k / 200 for k in range(201)]:
            p = matrix.map(QtGui.QVector4D(*map(float, a + t * (b - a)), 1.0))
            if p.w() > 0:
                points.append(((p.x() / p.w() + 1) / 2 * w, (1 - p.y() / p.w()) / 2 * h))
    return points


@pytest.mark.parametrize("name", ["hills", "bowl", "incline"])
@pytest.mark.parametrize("presentation", [False, True])
def test_the_closeup_covers_no_axis_label_number_or_line(qtbot, window, name, presentation):
    """In presentation the close-up in the top right corner covered "y (m)" and the top of the y
    axis: it goes to a corner (or shrinks) where every axis and label stays in sight."""
    window.files.open_scene(EXAMPLES_DIR / f"{name}.json", remember=False)
    if presentation:
        window.presentation_action.setChecked(True)
        qtbot.waitUntil(window.isFullScreen, timeout=5_000)
    else:
        window.closeup_action.setChecked(True)
    view, frame = window.view, window.closeup_frame
    for size in ([None] if presentation else [(1024, 700), (1400, 860)]):
        if size is not None:
            window.resize(*size)
        qtbot.wait(300)
        view.image()    # a frame drawn: the labels laid out for the screen again after it
        view.repaint()
        qtbot.wait(100)
        assert frame.isVisible() and view.rect().contains(frame.geometry())
        place = QtCore.QRectF(frame.geometry())
        boxes = _boxes(view, (view.width(), view.height()))
        assert {"x (m)", "y (m)"} <= {text for text, _ in boxes}
        assert [text for text, box in boxes if box.intersects(place)] == []
        assert not [p for p in _axis_points(view) if place.contains(*p)]
        assert frame.width() >= min(160, (view.height() - 16) / 0.75)
    window.presentation_action.setChecked(False)


def test_the_closeup_takes_the_largest_free_corner_stays_put_and_fits_the_view():
    import numpy as np

    from rollball_app.closeup import INSET_MARGIN, inset_place
    none = np.zeros((0, 2, 2))
    top_right = inset_place((1000, 600), [], none)
    assert top_right == QtCore.QRect(1000 - 300 - INSET_MARGIN, INSET_MARGIN, 300, 225)   # 0.3 of the width
    label = [QtCore.QRectF(900, 100, 60, 20)]                                       # a name in the top right
    assert inset_place((1000, 600), label, none).topLeft() == QtCore.QPoint(INSET_MARGIN, INSET_MARGIN)
    line = np.array([[[0.0, 100.0], [1000.0, 100.0]]])                              # across the top: the bottom
    assert inset_place((1000, 600), [], line).bottom() == 600 - INSET_MARGIN - 1
    left = inset_place((1000, 600), [], none, current=QtCore.QRect(INSET_MARGIN, INSET_MARGIN, 300, 225))
    assert left.topLeft() == QtCore.QPoint(INSET_MARGIN, INSET_MARGIN)               # where it was: it stays
    everywhere = [QtCore.QRectF(x, y, 5, 5) for x in range(0, 1000, 120) for y in range(0, 600, 120)]
    crowded = inset_place((1000, 600), everywhere, none)
    assert crowded.width() < 300 and crowded.height() <= 600 - 2 * INSET_MARGIN     # smaller, where least is covered
    low = inset_place((1024, 200), [], none)
    assert low.height() <= 200 - 2 * INSET_MARGIN and low.top() >= 0               # never taller than the view
