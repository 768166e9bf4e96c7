"""A picture-in-picture close-up that follows the ball, so its rotation and any deformation
of a classic R can be seen whatever the main camera's zoom.

It draws its own fine patch of the landscape around the contact point (resampled as the ball
moves, with darker lines fixed in the world one ball radius apart, so the ground visibly passes
under the ball), the ball, and the trail; its camera looks from the main view's direction.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
import pyqtgraph.opengl as gl
from PySide6 import QtCore, QtGui

from rollball.geometry import fit_ratio

from .view3d import BACKGROUND, TRAIL_COLOR, ball_mesh, ball_transform, run_ball_mesh, surface_colors

PATCH_RADII = 5.0      # the patch reaches this many ball radii either side of the contact point
PATCH_CELLS = 40       # grid cells per side of the patch
DISTANCE_RADII = 9.0   # camera distance from the ball's centre
LINE_EVERY = 5         # a darker grid line every this many cells (a ball radius apart)


INSET_WIDTH = 0.3      # the close-up's width on screen as a fraction of the view's, at most
INSET_SMALLEST = 160   # and at least, in pixels
INSET_RATIO = 0.75     # its height over its width
INSET_MARGIN = 8       # pixels from the view's edges


def inset_corners(size: tuple[int, int], width: int) -> list[QtCore.QRect]:
    """The close-up ``width`` wide in the corners of a view of ``size``: top right (first: where
    it always was), top left, bottom right, bottom left."""
    w, h = size
    iw, ih = width, round(INSET_RATIO * width)
    left, right, top, bottom = INSET_MARGIN, w - iw - INSET_MARGIN, INSET_MARGIN, h - ih - INSET_MARGIN
    return [QtCore.QRect(x, y, iw, ih) for x, y in ((right, top), (left, top), (right, bottom), (left, bottom))]


def covered(rect: QtCore.QRect, labels, lines: np.ndarray) -> int:
    """How many of the axis ``labels`` (rectangles) and ``lines`` ((m, 2, 2): ends on screen) the
    close-up at ``rect`` would cover (a line: any part of it)."""
    box = QtCore.QRectF(rect).adjusted(-2, -2, 2, 2)   # its frame and a hair
    count = sum(1 for label in labels if box.intersects(label))
    if len(lines):
        x0, y0, x1, y1 = box.left(), box.top(), box.right(), box.bottom()
        a, b = lines[:, 0], lines[:, 1]
        t = np.linspace(0.0, 1.0, 65)[None, :, None]   # along each line: a point every few pixels
        points = a[:, None] + t * (b - a)[:, None]
        inside = ((points[..., 0] >= x0) & (points[..., 0] <= x1) & (points[..., 1] >= y0) & (points[..., 1] <= y1))
        count += int(inside.any(axis=1).sum())
    return count


def inset_place(size: tuple[int, int], labels, lines: np.ndarray, current: QtCore.QRect | None = None) -> QtCore.QRect:
    """Where the close-up goes in a view of ``size`` whose axes take ``labels`` and ``lines``
    (``SceneView.taken``): the largest size from ``INSET_WIDTH`` of the view (as tall as the
    view at most) down to ``INSET_SMALLEST`` pixels at which a corner leaves every axis label, number and line in
    sight (the corner it is in, ``current``, first: it does not jump about while the camera
    turns); failing that, the smallest, in the corner covering least."""
    w, h = size
    tallest = int((h - 2 * INSET_MARGIN) / INSET_RATIO)   # (never taller than the view)
    smallest = min(INSET_SMALLEST, tallest)
    widest = max(smallest, min(round(INSET_WIDTH * w), tallest))
    widths = [widest]
    while widths[-1] > smallest:
        widths.append(max(smallest, round(widths[-1] * 0.9)))
    order = [0, 1, 2, 3]
    if current is not None:
        for k, rect in enumerate(inset_corners(size, current.width())):
            if rect.topLeft() == current.topLeft():
                order = [k] + [i for i in order if i != k]
                break
    for width in widths:
        corners = inset_corners(size, width)
        for k in order:
            if covered(corners[k], labels, lines) == 0:
                return corners[k]
    corners = inset_corners(size, widths[-1])
    return min((corners[k] for k in order), key=lambda rect: covered(rect, labels, lines))


class CloseUp(gl.GLViewWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.setBackgroundColor(BACKGROUND)
        self.setObjectName("closeup")
        self.landscape = None
        self.color: str | None = None   # the run's colour, None: the striped ball
        self.radius = 0.1
        self.z_span = (0.0, 1.0)
        self.patch = gl.GLSurfacePlotItem(shader="shaded", smooth=True, glOptions="opaque")
        self.ball = gl.GLMeshItem(meshdata=ball_mesh(), smooth=False, shader="shaded", glOptions="opaque")
        self.trail = gl.GLLinePlotItem(color=TRAIL_COLOR, width=4.0, antialias=True, mode="line_strip")
        self._trail_color = np.asarray(TRAIL_COLOR)
        for item in (self.patch, self.ball, self.trail):
            self.addItem(item)
        self.patch.setVisible(False)   # until it has been sampled
        self._patch_origin = None
        self.setAttribute(QtCore.Qt.WidgetAttribute.WA_TransparentForMouseEvents)  # the main view keeps the mouse

    def set_landscape(self, landscape, radius: float, z_span: tuple[float, float]) -> None:
        """The landscape to sample, the ball's radius, and the heights the colour map spans
        (the main view's, so colours match)."""
        self.landscape, self.radius, self.z_span = landscape, radius, z_span
        self._patch_origin = None

    def set_color(self, color: str | None) -> None:
        """The ball and trail in a run's colour (compare mode), or None: the striped ball."""
        if color == self.color:
            return
        self.color = color
        self.ball.setMeshData(meshdata=ball_mesh() if color is None else run_ball_mesh(color))
        self.trail.setData(pos=np.zeros((0, 3)), color=np.zeros((0, 4)))   # (colours per point from now on)
        self._trail_color = np.asarray(TRAIL_COLOR if color is None else pg.mkColor(color).getRgbF(), dtype=float)

    def show_ball(self, center: np.ndarray, R: np.ndarray, contact: np.ndarray, trail: np.ndarray,
                  azimuth: float, elevation: float, color: str | None = None,
                  trail_colors: np.ndarray | None = None) -> None:
        """Draw the ball at ``center`` turned by R, touching at ``contact`` (x, y), with the trail
        points (n, 3), seen from the main camera's direction; ``color``: the run's (see
        ``set_color``); ``trail_colors``: one per trail point (the contact's modes), else the
        run's colour."""
        if self.landscape is None:
            return
        self.set_color(color)
        self._update_patch(contact)
        self.ball.setTransform(ball_transform(center, R, self.radius))
        near = np.max(np.abs(trail[:, :2] - contact[:2]), axis=1) <= PATCH_RADII * self.radius if len(trail) else []
        shown = np.count_nonzero(near) >= 2
        colors = np.tile(self._trail_color, (len(trail), 1)) if trail_colors is None else trail_colors
        self.trail.setData(pos=trail[near] if shown else np.zeros((0, 3)),
                           color=colors[near] if shown else np.zeros((0, 4)))
        self.opts["center"] = QtGui.QVector3D(*map(float, center))
        self.opts["distance"] = DISTANCE_RADII * self.radius
        self.opts["azimuth"], self.opts["elevation"] = azimuth, elevation
        self.update()

    def _update_patch(self, contact) -> None:
        step = 2 * PATCH_RADII * self.radius / PATCH_CELLS
        origin = tuple(np.floor((np.asarray(contact[:2]) - PATCH_RADII * self.radius) / step).astype(int))
        if origin == self._patch_origin:
            return  # the ball has not crossed a grid line: the same patch
        self._patch_origin = origin
        x = (origin[0] + np.arange(PATCH_CELLS + 1)) * step
        y = (origin[1] + np.arange(PATCH_CELLS + 1)) * step
        xs, ys = np.meshgrid(x, y, indexing="ij")
        d = self.landscape.evaluate(xs, ys)
        z = d[0]
        colors = surface_colors(z, np.nan_to_num(fit_ratio(d, self.radius), nan=0.0), self.z_span)
        # darker lines fixed in the world, every LINE_EVERY cells: the ground visibly passes by
        ix, iy = np.meshgrid(origin[0] + np.arange(PATCH_CELLS + 1), origin[1] + np.arange(PATCH_CELLS + 1),
                             indexing="ij")
        colors[(ix % LINE_EVERY == 0) | (iy % LINE_EVERY == 0), :3] *= 0.55
        finite = np.isfinite(z)
        self.patch.setData(x=x, y=y, z=np.where(finite, z, z[finite].min() if finite.any() else 0.0), colors=colors)
        self.patch.setVisible(True)
