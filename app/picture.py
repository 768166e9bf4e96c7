"""Pictures of a run for slides: the 3-D view rendered at any size (not only the window's),
with the close-up in its corner, an optional caption (formula, method, step, time) and,
optionally, the plots below it. Used by Save Image and by animation export alike.
"""

from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball import METHODS, Scene

from .contact_view import KIND_COLORS, MODE_COLORS, rgba
from .view3d import BALL_STRIPES, LIFTOFF_COLOR, NO_FIT_COLOR, TRAIL_COLOR, label_pixels

# colours of the view that must stay recognisable in a GIF's palette (the trail's by mode and the
# transitions' markers among them)
ACCENTS = (TRAIL_COLOR[:3], LIFTOFF_COLOR[:3], NO_FIT_COLOR[:3], *BALL_STRIPES, (0.97, 0.97, 0.97),
           *(tuple(rgba(color)[:3]) for color in (*MODE_COLORS.values(), *KIND_COLORS.values())))
MAX_TEXTURE = 4096          # pixels per side of one off-screen rendering pass
INSET_FRACTION = 0.3       # the close-up's width as a fraction of the picture's
CAPTION_FRACTION = 0.028   # caption text height as a fraction of the picture's width (at least 11 px)


def caption_text(scene: Scene, t: float, methods: list[str] | None = None) -> str:
    """One line saying what is shown: formula, method and step (or tolerance) — or the labels of
    the runs compared — and the time."""
    method = METHODS[scene.integrator.method]
    if methods:
        stepping = "; ".join(methods)
    elif method.adaptive:
        stepping = f"{method.label}, rtol {scene.integrator.rtol:g}"
    else:
        orientation = "Munthe-Kaas" if scene.integrator.munthe_kaas else "classic"
        stepping = f"{method.label}, {orientation}, h = {scene.integrator.dt:g} s"
    return f"z = {scene.landscape}   ·   {stepping}   ·   t = {t:.3f} s"


def caption_pixels(width: int) -> int:
    return max(11, round(CAPTION_FRACTION * width))


def caption_height(width: int) -> int:
    """The height of the caption bar under a picture ``width`` pixels wide."""
    return 2 * caption_pixels(width)


def render_view(view, size: tuple[int, int]) -> QtGui.QImage:
    """A GL view rendered off screen at ``size`` (width, height) with its current camera."""
    width, height = int(size[0]), int(size[1])
    side = max(width, height) + 2
    # one off-screen pass when it fits in a texture (pyqtgraph's default tiles 1024-pixel squares)
    tiles = {"textureSize": side, "padding": 1} if side <= MAX_TEXTURE else {"textureSize": MAX_TEXTURE}
    bgra = view.renderToArray((width, height), **tiles)
    rgb = np.ascontiguousarray(bgra[..., 2::-1])
    image = QtGui.QImage(rgb.data, rgb.shape[1], rgb.shape[0], rgb.strides[0], QtGui.QImage.Format.Format_RGB888)
    return image.copy()   # owns its pixels once rgb is gone


def labels_at(view, size: tuple[int, int]) -> list[tuple[float, float, object]]:
    """The view's text items (axis numbers and names: ``view.axis_labels``) shown, as (x, y,
    item): where each one's anchor falls in a picture of ``size`` taken with the view's
    camera. GL draws this text on the widget with a painter, so an off-screen rendering
    (``renderToArray``) has none of it: ``compose`` draws it."""
    width, height = int(size[0]), int(size[1])
    matrix = view.projectionMatrix((0, 0, width, height), (0, 0, width, height)) * view.viewMatrix()
    placed = []
    for item in getattr(view, "axis_labels", ()):
        if not (item.visible() and item.text):
            continue
        p = matrix.map(QtGui.QVector4D(*map(float, item.pos), 1.0))
        if p.w() <= 0:
            continue   # behind the camera
        placed.append(((p.x() / p.w() + 1) / 2 * width, (1 - p.y() / p.w()) / 2 * height, item))
    return placed


def draw_labels(painter: QtGui.QPainter, view, size: tuple[int, int]) -> None:
    """The view's axis numbers and names on a picture of it at ``size``, as on screen: anchored
    at their points (left, baseline), their text scaled with the picture (``label_pixels``);
    those the view left out so as not to overlap others (``SceneView._thin_labels``) stay out."""
    scale = size[0] / max(1, view.width())
    for x, y, item in labels_at(view, size):
        font = QtGui.QFont(item.font)
        font.setPixelSize(label_pixels(item, scale))
        painter.setFont(font)
        painter.setPen(item.color)
        painter.drawText(QtCore.QPointF(x, y), item.text)


def inset_corner(view, inset) -> tuple[bool, bool]:
    """(right, top): the corner of the view the close-up ``inset`` is in on screen, where it
    covers none of the axes (``closeup.inset_place``); a picture puts it in the same corner."""
    centre = inset.mapToGlobal(QtCore.QPoint(inset.width() // 2, inset.height() // 2))
    origin = view.mapToGlobal(QtCore.QPoint(0, 0))
    return centre.x() - origin.x() >= view.width() / 2, centre.y() - origin.y() < view.height() / 2


def compose(view, size: tuple[int, int], inset=None, caption: str | None = None,
            plots: QtWidgets.QWidget | None = None) -> QtGui.QImage:
    """The view at ``size``; ``inset`` (a GL view, e.g. the close-up) drawn in the corner it
    takes on screen (``inset_corner``); a caption bar under it; the plots widget rendered below at the same width."""
    width, height = map(int, size)
    picture = render_view(view, (width, height))
    text_px = caption_pixels(width)
    caption_h = caption_height(width) if caption else 0
    plots_h = round(plots.height() * width / max(1, plots.width())) if plots is not None else 0
    out = QtGui.QImage(width, height + caption_h + plots_h, QtGui.QImage.Format.Format_RGB888)
    out.fill(QtGui.QColor("white"))
    painter = QtGui.QPainter(out)
    painter.setRenderHint(QtGui.QPainter.RenderHint.Antialiasing)
    painter.setRenderHint(QtGui.QPainter.RenderHint.TextAntialiasing)
    painter.drawImage(0, 0, picture)
    draw_labels(painter, view, (width, height))
    if inset is not None:
        w = round(INSET_FRACTION * width)
        h = round(w * inset.height() / max(1, inset.width()))
        margin = max(4, width // 100)
        right, top = inset_corner(view, inset)
        x = width - w - margin if right else margin
        y = margin if top else height - h - margin
        painter.drawImage(x, y, render_view(inset, (w, h)))
        painter.setPen(QtGui.QPen(QtGui.QColor("#333333"), max(1, width // 600)))
        painter.drawRect(x, y, w, h)
    if caption:
        font = QtGui.QFont(QtWidgets.QApplication.font())
        font.setPixelSize(text_px)
        while text_px > 7 and QtGui.QFontMetrics(font).horizontalAdvance(caption) > width - text_px:
            text_px -= 1   # a narrow picture: a smaller caption rather than a cut one
            font.setPixelSize(text_px)
        painter.setFont(font)
        painter.setPen(QtGui.QColor("#222222"))
        painter.fillRect(0, height, width, caption_h, QtGui.QColor("#f3f1ea"))
        painter.drawText(QtCore.QRect(text_px // 2, height, width - text_px, caption_h),
                         QtCore.Qt.AlignmentFlag.AlignVCenter | QtCore.Qt.AlignmentFlag.AlignLeft, caption)
    if plots is not None:
        painter.save()
        painter.translate(0, height + caption_h)
        painter.scale(width / max(1, plots.width()), width / max(1, plots.width()))
        plots.render(painter, QtCore.QPoint(0, 0), QtGui.QRegion(),
                     QtWidgets.QWidget.RenderFlag.DrawChildren | QtWidgets.QWidget.RenderFlag.DrawWindowBackground)
        painter.restore()
    painter.end()
    return out


def rgb_array(image: QtGui.QImage) -> np.ndarray:
    """An image's pixels as an (height, width, 3) uint8 array (a copy)."""
    image = image.convertToFormat(QtGui.QImage.Format.Format_RGB888)
    view = np.frombuffer(image.constBits(), dtype=np.uint8, count=image.sizeInBytes())
    return view.reshape(image.height(), image.bytesPerLine())[:, : 3 * image.width()].reshape(
        image.height(), image.width(), 3).copy()
