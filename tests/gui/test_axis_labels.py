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
