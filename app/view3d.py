"""The 3-D view: the landscape, the ball showing its orientation, the contact trail, markers.

Drawing only: this module receives arrays and never runs the physics. The surface is rebuilt
when the landscape or grid changes; the ball moves by its transform and the trail by
``setData``, so a frame costs little whatever the step rate.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
import pyqtgraph.opengl as gl
from PySide6 import QtGui

from rollball.geometry import fit_ratio

BACKGROUND = (246, 246, 243)
NO_FIT_COLOR = (0.86, 0.12, 0.20, 1.0)      # where the ball does not fit: r·κ ≥ 1
UNDEFINED_COLOR = (0.55, 0.55, 0.55, 1.0)   # where the formula cannot be evaluated
GRID_COLOR = (0.0, 0.0, 0.0, 0.22)
MAX_GRID_LINES = 30                          # per direction; more would hide the surface
TRAIL_COLOR = (0.80, 0.10, 0.10, 1.0)
LIFTOFF_COLOR = (1.0, 0.55, 0.0, 1.0)
BALL_STRIPES = np.array([(0.90, 0.20, 0.15), (1.00, 0.80, 0.10), (0.15, 0.45, 0.85),
                         (0.95, 0.55, 0.10), (0.20, 0.65, 0.30), (0.55, 0.25, 0.70)])
HEIGHT_MAP = pg.colormap.get("viridis")


def ball_mesh(rows: int = 24, cols: int = 48) -> gl.MeshData:
    """A unit beach ball: six coloured segments around the body z axis, white caps.

    Its pattern makes every rotation visible, and a non-orthogonal R visibly deforms it.
    """
    mesh = gl.MeshData.sphere(rows=rows, cols=cols, radius=1.0)
    centres = mesh.vertexes(indexed="faces").mean(axis=1)
    segment = ((np.arctan2(centres[:, 1], centres[:, 0]) + np.pi) / (2 * np.pi) * 6).astype(int) % 6
    colors = np.ones((len(centres), 4))
    colors[:, :3] = BALL_STRIPES[segment]
    colors[np.abs(centres[:, 2]) > 0.88, :3] = 0.97
    mesh.setFaceColors(colors)
    return mesh


def ball_transform(center: np.ndarray, R: np.ndarray, radius: float) -> pg.Transform3D:
    """The unit ball mesh placed at ``center`` and turned by R; a matrix R that is no rotation
    deforms it (one that grows is drawn no larger than the ball, so its shape stays visible)."""
    m = np.eye(4)
    m[:3, :3] = R * (radius / max(1.0, float(np.linalg.norm(R, 2))))
    m[:3, 3] = center
    return pg.Transform3D(*m.ravel())


def height_span(z: np.ndarray) -> tuple[float, float]:
    """The heights the colour map spans: those of the finite points."""
    finite = np.isfinite(z)
    return (float(np.min(z[finite])), float(np.max(z[finite]))) if finite.any() else (0.0, 1.0)


def surface_colors(z: np.ndarray, fit: np.ndarray, span: tuple[float, float] | None = None) -> np.ndarray:
    """Vertex colours: height by colour map over ``span`` (default: z's own), the no-fit region
    and undefined points apart."""
    finite = np.isfinite(z)
    lo, hi = span or height_span(z)
    level = np.clip((np.where(finite, z, lo) - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.full(z.shape, 0.5)
    colors = HEIGHT_MAP.map(level.ravel(), mode="float").reshape(z.shape + (4,))
    colors[fit >= 1.0] = NO_FIT_COLOR
    colors[~finite] = UNDEFINED_COLOR
    return colors


def grid_lines(axis: np.ndarray, z: np.ndarray, lift: float) -> np.ndarray:
    """Segments (pairs of points) along every k-th grid line of the surface, raised by ``lift``."""
    n = len(axis)
    k = max(1, -(-n // MAX_GRID_LINES))
    picked = np.arange(0, n, k)
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    points = np.stack([xs, ys, z + lift], axis=-1)
    along_y = points[picked]                   # lines of constant x
    along_x = points[:, picked].swapaxes(0, 1)  # lines of constant y
    lines = np.concatenate([along_y, along_x])
    return np.stack([lines[:, :-1], lines[:, 1:]], axis=2).reshape(-1, 3)


class SceneView(gl.GLViewWidget):
    """Landscape, ball, trail and lift-off marker, with a camera that can follow the ball."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setBackgroundColor(BACKGROUND)
        self.setMinimumSize(480, 360)
        self.follow = False
        self.surface: gl.GLSurfacePlotItem | None = None
        self.extent = 6.0
        self.z_span = (0.0, 1.0)   # heights the colour map spans
        self.grid_lines = gl.GLLinePlotItem(color=GRID_COLOR, width=1.0, antialias=True, mode="lines")
        self.grid_lines.setGLOptions("translucent")
        self.addItem(self.grid_lines)
        self.ball = gl.GLMeshItem(meshdata=ball_mesh(), smooth=False, shader="shaded", glOptions="opaque")
        self.trail = gl.GLLinePlotItem(color=TRAIL_COLOR, width=3.0, antialias=True, mode="line_strip")
        self.liftoff = gl.GLScatterPlotItem(color=LIFTOFF_COLOR, size=16.0, pxMode=True)
        self.liftoff.setGLOptions("translucent")
        for item in (self.ball, self.trail, self.liftoff):
            self.addItem(item)
        self.liftoff.setVisible(False)
        self.ball_center = np.zeros(3)

    # -- landscape -------------------------------------------------------------------

    def set_landscape(self, landscape, view, radius: float) -> dict:
        """Draw the landscape on the scene's grid; returns what the grid showed (for the status)."""
        n = int(round((view.max - view.min) / view.step)) + 1
        axis = np.linspace(view.min, view.min + (n - 1) * view.step, n)
        xs, ys = np.meshgrid(axis, axis, indexing="ij")
        d = landscape.evaluate(xs, ys)
        z = d[0]
        fit = np.nan_to_num(fit_ratio(d, radius), nan=0.0)
        self.extent = float(axis[-1] - axis[0])
        finite = np.isfinite(z)
        lowest = z[finite].min() if finite.any() else 0.0
        # undefined points sit at the lowest height (drawn grey); walls are cut at twice the grid
        shown = np.clip(np.where(finite, z, lowest), -2 * self.extent, 2 * self.extent)
        self.z_span = height_span(z)
        colors = surface_colors(z, fit, self.z_span)
        if self.surface is not None:
            self.removeItem(self.surface)
        self.surface = gl.GLSurfacePlotItem(x=axis, y=axis, z=shown, colors=colors, shader="shaded",
                                            smooth=True, drawEdges=False,
                                            edgeColor=(0.0, 0.0, 0.0, 0.18))
        self.surface.setGLOptions("opaque")
        self.addItem(self.surface)
        self.grid_lines.setData(pos=grid_lines(axis, shown, lift=0.002 * self.extent))
        for item in (self.grid_lines, self.trail, self.liftoff):   # drawn after the surface, on top of it
            self.removeItem(item)
            self.addItem(item)
        return {"no_fit": bool((fit >= 1.0).any()), "undefined": bool((~np.isfinite(z)).any())}

    def reset_camera(self) -> None:
        self.setCameraPosition(distance=1.25 * self.extent, elevation=30, azimuth=-60)
        c = self.ball_center if self.follow else np.zeros(3)
        self.opts["center"] = QtGui.QVector3D(*map(float, c))
        self.update()

    # -- ball, trail, markers ---------------------------------------------------------

    def set_ball(self, center: np.ndarray, R: np.ndarray, radius: float) -> None:
        """Place the ball (see ``ball_transform``)."""
        self.ball.setTransform(ball_transform(center, R, radius))
        self.ball_center = np.asarray(center, dtype=float)
        if self.follow:
            self.opts["center"] = QtGui.QVector3D(*map(float, center))
        self.update()

    def set_trail(self, points: np.ndarray) -> None:
        self.trail.setData(pos=points if len(points) >= 2 else np.zeros((0, 3)))

    def set_liftoff(self, point: np.ndarray | None) -> None:
        self.liftoff.setVisible(point is not None)
        if point is not None:
            self.liftoff.setData(pos=np.asarray(point, dtype=float).reshape(1, 3))

    def set_follow(self, follow: bool, radius: float | None = None) -> None:
        """Keep the ball in the centre of the view; zoom in to it when a radius is given."""
        self.follow = follow
        if follow:
            self.opts["center"] = QtGui.QVector3D(*map(float, self.ball_center))
            if radius is not None:
                self.opts["distance"] = 25.0 * radius
            self.update()

    def image(self, size: tuple[int, int] | None = None) -> np.ndarray:
        """The rendered view as an RGBA array (height, width, 4)."""
        qimage = self.grabFramebuffer().convertToFormat(QtGui.QImage.Format.Format_RGBA8888)
        if size is not None:
            qimage = qimage.scaled(*size)
        ptr = qimage.constBits()
        array = np.frombuffer(ptr, dtype=np.uint8, count=qimage.sizeInBytes())
        return array.reshape(qimage.height(), qimage.bytesPerLine() // 4, 4)[:, : qimage.width()].copy()
