"""The 3-D view: the landscape, the ball showing its orientation, the contact trail, markers,
and before a run the path's preview and the start's handles.

Drawing only: this module receives arrays and never runs the physics. The surface is rebuilt
when the landscape or grid changes; the ball moves by its transform and the trail by
``setData``, so a frame costs little whatever the step rate.

Before a run (``set_start``) the ball can be dragged over the surface to move the start point,
and the head of its velocity arrow (or the ball with Shift) to set the start velocity; the view
says where (``startDragged``, ``velocityDragged``, ``dragFinished``) and the window changes the
scene. Any other drag turns the camera, as before.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
import pyqtgraph.opengl as gl
from OpenGL import GL
from PySide6 import QtCore, QtGui

from rollball.geometry import fit_ratio

from .picking import mouse_ray, on_screen, ray_plane, ray_surface

BACKGROUND = (246, 246, 243)
NO_FIT_COLOR = (0.86, 0.12, 0.20, 1.0)      # where the ball does not fit: r·κ ≥ 1
UNDEFINED_COLOR = (0.55, 0.55, 0.55, 1.0)   # where the formula cannot be evaluated
GRID_COLOR = (0.0, 0.0, 0.0, 0.22)
MAX_GRID_LINES = 30                          # per direction; more would hide the surface
CUT_COLOR = (0.15, 0.15, 0.15, 0.55)        # the edge where unreachable heights are cut away
AXIS_COLOR = (0.30, 0.30, 0.30, 1.0)
TEXT_COLOR = (60, 60, 60, 255)
TRAIL_COLOR = (0.80, 0.10, 0.10, 1.0)
CASING_COLOR = (0.08, 0.08, 0.08, 0.85)   # a dark edge under each trail: readable on every surface colour
CASING_EXTRA = 4.0                        # pixels wider than the trail
# Drawn after the surface (depth 0) and the ball's ring (MARK_DEPTH), before the ball: the casing,
# then its trail over it, both without the depth test, as the trail always was (a line's many
# short antialiased segments would hide each other's pixels in the depth buffer): the whole path
# stays in sight, over the hills too, and a short one (a billiard ball's slide) over the ring.
CASING_DEPTH, TRAIL_DEPTH = 0.52, 0.54
TRAIL_GL = {GL.GL_DEPTH_TEST: False, GL.GL_BLEND: True, GL.GL_CULL_FACE: False,
            "glBlendFunc": (GL.GL_SRC_ALPHA, GL.GL_ONE_MINUS_SRC_ALPHA)}
CASING_GL = TRAIL_GL
LIFTOFF_COLOR = (1.0, 0.55, 0.0, 1.0)
ARROW_COLOR = (0.05, 0.05, 0.05, 0.9)       # the start velocity's arrow
ARROW_SECONDS = 1.0      # the arrow reaches where the centre would be this long after the start
HANDLE_PIXELS = 14       # the arrow head's handle on screen; a press this near grabs it
BALL_STRIPES = np.array([(0.90, 0.20, 0.15), (1.00, 0.80, 0.10), (0.15, 0.45, 0.85),
                         (0.95, 0.55, 0.10), (0.20, 0.65, 0.30), (0.55, 0.25, 0.70)])
HEIGHT_MAP = pg.colormap.get("viridis")
GHOST_ALPHA = 0.3        # the balls of the runs not followed, in compare mode: see-through
TICK = 0.015             # an axis tick's length as a fraction of the landscape's width
LABEL_REACH = 8          # ticks beyond the axes that their labels reach (names at 6, text beyond)
FILL = 0.9               # the framed landscape fills up to this fraction of the view
MARK_FRACTION = 0.06     # a ball drawn smaller than this fraction of the picture's shorter side
MIN_MARK_PIXELS = 12     # (but at least this many pixels) is marked by a ring that wide around it
MARK_PIXELS = 30         # the ring in the default window's view (504 pixels high), for scale
MARK_EDGE = (0.10, 0.10, 0.10, 0.85)   # the ring's edge (a run's own colour in compare mode)
MARK_FILL = (1.0, 1.0, 1.0, 0.55)      # its inside, behind the ball
MARK_GL = {GL.GL_DEPTH_TEST: False, GL.GL_BLEND: True, GL.GL_CULL_FACE: False,   # never hidden by the surface
           "glBlendFuncSeparate": (GL.GL_SRC_ALPHA, GL.GL_ONE_MINUS_SRC_ALPHA, GL.GL_ONE, GL.GL_ONE_MINUS_SRC_ALPHA)}
BALL_DEPTH, MARK_DEPTH, GHOST_DEPTH = 0.6, 0.5, 1.0   # drawing order: surface, marks, ball, ghosts
# before a run, after the marks and before the ball (neither depth-tested): the start velocity's
# arrow, then the preview's casing and line over it (the path it predicts is not hidden by the arrow)
ARROW_DEPTH, PREVIEW_DEPTH = 0.55, 0.58
LABEL_DEPTH = 10.0   # text last: its painter leaves an off-screen rendering's framebuffer unbound
MIN_LABEL_PIXELS = 10      # axis numbers and names in an exported picture are at least this high
LABEL_GAP = 3              # pixels kept free around an axis label (times the picture's scale)
PATH_SAMPLES = 12          # points of the preview's path the camera keeps in sight
# camera directions tried in turn (elevation, azimuth in degrees) until the ball is in sight:
# the usual side from ever higher up, then the other sides
VIEWPOINTS = [(elevation, azimuth) for azimuth in (-60, -30, -90, -120, 0, -150, 30, 180, 60, 150, 90, 120)
              for elevation in (30, 45, 60, 75)] + [(90, -90)]


def mark_pixels(size: tuple[int, int]) -> int:
    """The ball's ring in a picture of ``size`` (width, height): the same share of the picture
    on screen, in a small video and in a large one."""
    return max(MIN_MARK_PIXELS, round(MARK_FRACTION * min(size)))


def ring_sizes(ring: float, k: int = 0) -> np.ndarray:
    """The two discs drawing run k's ring ``ring`` pixels wide: its edge, then its inside."""
    step = ring / 5
    return np.array([ring + step * (5 / 6), ring]) + step * k


def label_pixels(item: gl.GLTextItem, scale: float = 1.0) -> int:
    """An axis label's text height in pixels in a picture ``scale`` times as wide as the view
    (at least ``MIN_LABEL_PIXELS``, so a small video keeps it legible)."""
    return max(MIN_LABEL_PIXELS, round(QtGui.QFontInfo(item.font).pixelSize() * scale))


def ball_mesh(stripes: np.ndarray = BALL_STRIPES, cap=(0.97, 0.97, 0.97), rows: int = 24,
              cols: int = 48) -> gl.MeshData:
    """A unit beach ball: six coloured segments around the body z axis, caps of one colour.

    Its pattern makes every rotation visible, and a non-orthogonal R visibly deforms it.
    """
    mesh = gl.MeshData.sphere(rows=rows, cols=cols, radius=1.0)
    centres = mesh.vertexes(indexed="faces").mean(axis=1)
    segment = ((np.arctan2(centres[:, 1], centres[:, 0]) + np.pi) / (2 * np.pi) * 6).astype(int) % 6
    colors = np.ones((len(centres), 4))
    colors[:, :3] = np.asarray(stripes)[segment]
    colors[np.abs(centres[:, 2]) > 0.88, :3] = cap
    mesh.setFaceColors(colors)
    return mesh


def run_ball_mesh(color, alpha: float = 1.0) -> gl.MeshData:
    """A beach ball in one run's colour: its segments alternate the colour and a pale tint of
    it, with dark caps, so rotation and deformation stay as visible as on the striped ball.
    With ``alpha`` < 1 a see-through ghost of it."""
    c = np.asarray(pg.mkColor(color).getRgbF()[:3])
    pale = 0.35 * c + 0.65
    mesh = ball_mesh(np.array([c, pale] * 3), cap=0.45 * c)
    if alpha < 1.0:
        colors = mesh.faceColors()
        colors[:, 3] = alpha
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


def grid_lines(axis: np.ndarray, z: np.ndarray, lift: float, cap: float = np.inf) -> np.ndarray:
    """Segments (pairs of points) along every k-th grid line of the surface, raised by ``lift``;
    none reaching above ``cap`` (where the surface is cut away)."""
    n = len(axis)
    k = max(1, -(-n // MAX_GRID_LINES))
    picked = np.arange(0, n, k)
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    points = np.stack([xs, ys, z], axis=-1)
    along_y = points[picked]                   # lines of constant x
    along_x = points[:, picked].swapaxes(0, 1)  # lines of constant y
    lines = np.concatenate([along_y, along_x])
    pairs = np.stack([lines[:, :-1], lines[:, 1:]], axis=2).reshape(-1, 2, 3)
    pairs = pairs[pairs[:, :, 2].max(axis=1) <= cap]
    pairs[:, :, 2] += lift
    return pairs.reshape(-1, 3)


def too_coarse(landscape, axis: np.ndarray, z: np.ndarray) -> bool:
    """Whether the grid is too coarse to show the landscape: in the middle of many cells (a
    tenth of them) the landscape differs from what the drawing shows there by more than 5 % of
    its height range (hills narrower than the spacing come out as noise; a few cells at a
    singular edge do not count)."""
    mid = (axis[:-1] + axis[1:]) / 2
    xs, ys = np.meshgrid(mid, mid, indexing="ij")
    between = landscape.evaluate(xs, ys)[0]
    drawn = (z[:-1, :-1] + z[1:, :-1] + z[:-1, 1:] + z[1:, 1:]) / 4
    with np.errstate(invalid="ignore"):
        error = np.abs(between - drawn)
    finite = np.isfinite(error) & np.isfinite(z[:-1, :-1])
    span = np.ptp(z[np.isfinite(z)]) if np.isfinite(z).any() else 0.0
    return bool(finite.any() and span > 0 and np.percentile(error[finite], 90) > 0.05 * span)


def height_cap(lowest: float, reachable: float, radius: float) -> float:
    """Heights above this are not drawn: the ball's energy never takes it up there
    (``reachable``, E / (m g)); the margin keeps a little of every wall in sight."""
    return reachable + 2.0 * radius + 0.1 * max(reachable - lowest, 0.0)


def lidded(z: np.ndarray, cap: float) -> np.ndarray:
    """The grid points above ``cap`` that are closed by a flat lid at the cap: those of hilltops
    (regions above the cap that do not reach the grid's edge). A wall reaching the edge stays
    open, cut: the view looks over it into the landscape."""
    above = z > cap
    reached = np.zeros_like(above)   # above the cap and joined to the edge (4-connected: a
    reached[[0, -1], :] = above[[0, -1], :]   # triangle's corners above are joined)
    reached[:, [0, -1]] |= above[:, [0, -1]]
    while True:   # grown into the neighbours above until it no longer grows
        grown = reached.copy()
        grown[1:] |= reached[:-1]
        grown[:-1] |= reached[1:]
        grown[:, 1:] |= reached[:, :-1]
        grown[:, :-1] |= reached[:, 1:]
        grown &= above
        if (grown == reached).all():
            return above & ~reached
        reached = grown


def surface_mesh(axis: np.ndarray, z: np.ndarray, colors: np.ndarray, cap: float) -> gl.MeshData:
    """The grid as triangles, without those wholly above ``cap``, so the surface ends in a level
    cut: a point above it slides towards its lowest neighbour (of eight) to where the surface
    crosses the cap (or, with no neighbour below, is lowered onto it). A hilltop cut away is
    closed by a flat lid at the cap (``lidded``): no hole shows the background through the hill."""
    n = len(axis)
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    vertexes = np.stack([xs, ys, np.minimum(z, cap)], axis=-1)
    padded = np.pad(z, 1, constant_values=np.inf)
    steps = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1) if i or j])   # the eight neighbours
    neighbours = np.stack([padded[1 + i:n + 1 + i, 1 + j:n + 1 + j] for i, j in steps])
    lowest = np.argmin(neighbours, axis=0)
    low = np.take_along_axis(neighbours, lowest[None], axis=0)[0]
    slide = (z > cap) & (low < cap)
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(slide, (z - cap) / (z - low), 0.0)
    step = axis[1] - axis[0] if n > 1 else 0.0
    vertexes[..., 0] += w * steps[lowest, 0] * step
    vertexes[..., 1] += w * steps[lowest, 1] * step
    vertexes = vertexes.reshape(-1, 3)
    index = np.arange(n * n).reshape(n, n)
    a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[:-1, 1:].ravel(), index[1:, 1:].ravel()
    # wound as GLSurfacePlotItem winds them
    faces = np.concatenate([np.stack([a, d, b], axis=1), np.stack([a, c, d], axis=1)])
    faces = faces[(z.ravel()[faces] <= cap).any(axis=1) | lidded(z, cap).ravel()[faces].all(axis=1)]
    mesh = gl.MeshData(vertexes=vertexes, faces=faces, vertexColors=colors.reshape(-1, 4))
    mesh._vertexNormals = vertex_normals(vertexes, faces)   # pyqtgraph's loop takes ~0.3 s a redraw
    return mesh


def vertex_normals(vertexes: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each vertex's normal as pyqtgraph's ``MeshData.vertexNormals`` makes it (the sum of its
    faces' cross-product normals, normalised), in numpy at once rather than vertex by vertex."""
    v = vertexes[faces]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    sums = np.stack([sum(np.bincount(faces[:, k], normals[:, i], minlength=len(vertexes)) for k in range(3))
                     for i in range(3)], axis=1)
    length = np.sqrt((sums ** 2).sum(axis=1, keepdims=True))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(length > 0, sums / length, 0.0).astype(np.float32)


def level_segments(axis: np.ndarray, z: np.ndarray, level: float) -> np.ndarray:
    """Where the surface crosses the height ``level``: segments (pairs of points) through the
    grid cells (marching squares, crossings placed linearly along the cell edges)."""
    xs, ys = np.meshgrid(axis, axis, indexing="ij")
    corners = [(slice(None, -1), slice(None, -1)), (slice(1, None), slice(None, -1)),
               (slice(1, None), slice(1, None)), (slice(None, -1), slice(1, None))]
    points, crossed = [], []
    for k in range(4):  # the cell's four edges, corner k to corner k + 1
        i, j = corners[k], corners[(k + 1) % 4]
        za, zb = z[i], z[j]
        hit = (za - level) * (zb - level) < 0
        with np.errstate(invalid="ignore", divide="ignore"):
            w = np.where(hit, (level - za) / (zb - za), 0.0)
        points.append(np.stack([xs[i] + w * (xs[j] - xs[i]), ys[i] + w * (ys[j] - ys[i]),
                                np.full(za.shape, level)], axis=-1))
        crossed.append(hit)
    points, crossed = np.stack(points).reshape(4, -1, 3), np.stack(crossed).reshape(4, -1)
    count, cells = crossed.sum(axis=0), np.arange(crossed.shape[1])
    edges = np.argsort(~crossed, axis=0, kind="stable")   # each cell's crossed edges first
    two, four = count == 2, count == 4   # a saddle cell crossed on all four edges: 0-1 and 2-3
    pairs = [(points[edges[0, two], cells[two]], points[edges[1, two], cells[two]]),
             (points[0, four], points[1, four]), (points[2, four], points[3, four])]
    return np.concatenate([np.stack(pair, axis=1) for pair in pairs]).reshape(-1, 3)


def nice_step(span: float, ticks: int = 5) -> float:
    """A round tick spacing (1, 2 or 5 times a power of ten) giving about ``ticks`` ticks."""
    raw = span / ticks
    power = 10.0 ** np.floor(np.log10(raw))
    return float(min((m * power for m in (1, 2, 5, 10) if m * power >= raw), default=10 * power))


def look(center: np.ndarray, distance: float, elevation: float, azimuth: float) -> np.ndarray:
    """The camera's position, as pyqtgraph places it (angles in degrees)."""
    el, az = np.radians(elevation), np.radians(azimuth)
    return center + distance * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


def camera_axes(forward: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The view's right and up directions for a camera looking along ``forward`` with z up:
    right = forward × z normalised (x when looking straight down), up = right × forward,
    written out (numpy's cross costs more than the rest of a camera fit together)."""
    fx, fy, fz = map(float, forward)
    norm = (fx * fx + fy * fy) ** 0.5
    rx, ry = (fy / norm, -fx / norm) if norm > 1e-9 else (1.0, 0.0)
    return np.array([rx, ry, 0.0]), np.array([ry * fz, -rx * fz, rx * fy - ry * fx])


def project(points: np.ndarray, eye: np.ndarray, center: np.ndarray, fov: float, aspect: float) -> np.ndarray:
    """Normalised view coordinates (-1 to 1 across the view) of points seen from ``eye``
    looking at ``center`` with z up, ``fov`` the horizontal field of view in degrees and
    ``aspect`` = height / width; points behind the camera come out as inf."""
    forward = (center - eye) / np.linalg.norm(center - eye)
    right, up = camera_axes(forward)
    rel = np.atleast_2d(points) - eye
    depth = rel @ forward
    half = np.tan(np.radians(fov) / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.stack([(rel @ right) / (depth * half), (rel @ up) / (depth * half * aspect)], axis=-1)
    out[depth <= 0] = np.inf
    return out


def _labelled(corners: np.ndarray, box: np.ndarray, center: np.ndarray, elevation: float, azimuth: float,
              reach: float) -> np.ndarray:
    """The box's corners and those of its floor moved ``reach`` out towards the camera in x
    and in y: the axes' numbers and names stand there (``_draw_axes``), and framing them too
    keeps them in the picture."""
    eye = look(center, 1.0, elevation, azimuth)
    out = np.array([np.sign(eye[0] - center[0]) or 1.0, np.sign(eye[1] - center[1]) or 1.0, 0.0]) * reach
    floor = corners[corners[:, 2] == box[0, 2]]
    return np.vstack([corners, floor + out * [1, 0, 0], floor + out * [0, 1, 0]])


class SceneView(gl.GLViewWidget):
    """Landscape, ball, trail and lift-off marker, with a camera that can follow the ball;
    before a run, the path's preview and the start's handles (dragged: the signals).

    The surface is drawn up to the height the ball's energy can reach (plus a margin) and cut
    level there, with a faint line along the cut; axes with ticks in metres give the scale.
    The camera frames the drawn landscape, heights included, from a side where the ball is
    in sight, and keeps that framing when the view is resized until the user turns or zooms.
    """

    startDragged = QtCore.Signal(float, float)      # the start contact point dragged to (x, y)
    velocityDragged = QtCore.Signal(float, float)   # the start velocity's arrow dragged to (vx, vy)
    dragFinished = QtCore.Signal()                  # the button let go: the drag is over
    axesPlaced = QtCore.Signal()                    # the axes moved on screen (``taken``)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setBackgroundColor(BACKGROUND)
        self.setMinimumSize(440, 280)   # the window fits 1024x700 with a two-line message
        self.follow = False
        self.framed = False                   # the camera is as reset_camera left it
        self.surface: gl.GLMeshItem | None = None
        self.extent = 6.0
        self.z_span = (0.0, 1.0)   # heights the colour map spans
        self.bounds = np.array([[-3.0, -3.0, 0.0], [3.0, 3.0, 0.0]])  # drawn box: lowest, highest corner
        self.no_fit_points = np.zeros((0, 3))  # some drawn points where the ball does not fit
        self.lowest_point = np.zeros(3)         # where the ball is heading, shown if possible
        self.path: np.ndarray | None = None     # the preview's points on this landscape, once come
        self.awaiting_path = False              # framed before the path came: framed again then
        self.cap = np.inf                     # heights above this are cut away
        self._axis = np.linspace(-3.0, 3.0, 2)
        self._drawn = np.zeros((2, 2))        # drawn heights on the grid (-inf where cut away)
        self._top = self._drawn               # the same with the hilltops' lids (what hides what)
        self.grid_lines = gl.GLLinePlotItem(color=GRID_COLOR, width=1.0, antialias=True, mode="lines")
        self.grid_lines.setGLOptions("translucent")
        self.cut_edge = gl.GLLinePlotItem(color=CUT_COLOR, width=1.5, antialias=True, mode="lines")
        self.cut_edge.setGLOptions("translucent")
        self.axes = gl.GLLinePlotItem(color=AXIS_COLOR, width=1.5, antialias=True, mode="lines")
        self.axis_labels: list[gl.GLTextItem] = []
        self._thinned_for = None   # what the labels were last thinned for (_thin_labels)
        self._kept: tuple = (None, [])   # (size, the shown labels' rectangles) as last thinned
        # where the axes are on screen: the shown labels' rectangles and the axes' lines (m, 2, 2), in
        # the widget's pixels, as last painted (the close-up keeps out of them: ``drawing.place_closeup``)
        self.taken: tuple[list[QtCore.QRectF], np.ndarray] = ([], np.zeros((0, 2, 2)))
        self._taken_for = None
        self.ball = gl.GLMeshItem(meshdata=ball_mesh(), smooth=False, shader="shaded", glOptions="opaque")
        self.trail = self._trail_items(TRAIL_COLOR)
        self.casing = self.trail.casing
        self.liftoff = gl.GLScatterPlotItem(color=LIFTOFF_COLOR, size=16.0, pxMode=True)
        self.liftoff.setGLOptions("translucent")
        self.liftoff.setDepthValue(BALL_DEPTH + 0.1)   # over the ball's mark
        self.ball.setDepthValue(BALL_DEPTH)
        for item in (self.grid_lines, self.cut_edge, self.axes, self.ball, self.trail, self.liftoff):
            self.addItem(item)
        self.liftoff.setVisible(False)
        self._trail_colors = [np.asarray(TRAIL_COLOR)]   # each run's own
        self.addItem(self.casing)
        self.ball_radius = 0.1
        self.balls, self.trails = [self.ball], [self.trail]   # one per run (compare mode: several)
        self.centers = [np.zeros(3)]
        self.followed = 0                                      # the run the camera follows
        self.trails_shown = True
        self.label_scale = 1.0   # the axis labels' text size, times 8 pt
        self.colors: list | None = None   # the runs' colours in compare mode
        self.marks_shown = True   # a ring around a ball too small to be seen from afar
        self.marks = [self._mark(MARK_EDGE)]   # one per ball
        # the path's preview before a run, drawn as a trail is, in the colours of the modes it predicts
        self.preview = self._trail_items(TRAIL_COLOR)
        self.preview.setDepthValue(PREVIEW_DEPTH)
        self.preview.casing.setDepthValue(PREVIEW_DEPTH - 0.01)
        self.arrow = gl.GLLinePlotItem(color=ARROW_COLOR, width=2.5, antialias=True, mode="lines")
        self.arrow.setGLOptions(MARK_GL)          # over the surface, as the ball's ring
        self.arrow_head = gl.GLScatterPlotItem(pos=np.zeros((1, 3)), size=HANDLE_PIXELS, pxMode=True,
                                               color=(0.05, 0.05, 0.05, 0.35))
        self.arrow_head.setGLOptions(MARK_GL)
        for item in (self.arrow, self.arrow_head):
            item.setDepthValue(ARROW_DEPTH)
        for item in (self.preview.casing, self.preview, self.arrow, self.arrow_head):
            item.setVisible(False)
            self.addItem(item)
        self.start: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None   # centre, normal, velocity
        self.velocity_fixed = False
        self._drag: tuple[str, np.ndarray] | None = None   # what is dragged, and the grab's offset
        self.setMouseTracking(True)               # the cursor shows what can be dragged

    @property
    def ball_center(self) -> np.ndarray:
        return self.centers[self.followed]

    # -- landscape -------------------------------------------------------------------

    def set_landscape(self, landscape, view, radius: float, reachable: float = np.inf) -> dict:
        """Draw the landscape on the scene's grid, cut above what the ball can reach (its
        energy as a height, ``reachable``); returns what the grid showed (for the status)."""
        n = int(round((view.max - view.min) / view.step)) + 1
        axis = np.linspace(view.min, view.min + (n - 1) * view.step, n)
        xs, ys = np.meshgrid(axis, axis, indexing="ij")
        d = landscape.evaluate(xs, ys)
        z = d[0]
        fit = np.nan_to_num(fit_ratio(d, radius), nan=0.0)
        self.extent = float(axis[-1] - axis[0])
        self.path = None   # the preview on the landscape before is not this one's
        finite = np.isfinite(z)
        lowest = z[finite].min() if finite.any() else 0.0
        # undefined points sit at the lowest height (drawn grey); walls are cut at twice the grid
        shown = np.clip(np.where(finite, z, lowest), -2 * self.extent, 2 * self.extent)
        self.cap = min(height_cap(lowest, reachable, radius), 2 * self.extent)
        self.z_span = height_span(np.minimum(z, self.cap))   # the colours span what is drawn
        colors = surface_colors(np.minimum(z, self.cap), fit, self.z_span)
        if self.surface is not None:
            self.removeItem(self.surface)
        self.surface = gl.GLMeshItem(meshdata=surface_mesh(axis, shown, colors, self.cap), smooth=True,
                                     shader="shaded", glOptions="opaque")
        self.addItem(self.surface)
        lift = 0.002 * self.extent
        self.grid_lines.setData(pos=grid_lines(axis, shown, lift=lift, cap=self.cap))
        cut = level_segments(axis, shown, self.cap) if shown.max() > self.cap else np.zeros((0, 3))
        self.cut_edge.setData(pos=cut + [0.0, 0.0, lift])
        self._axis, self._drawn = axis, np.where(shown <= self.cap, shown, -np.inf)
        self._top = np.where(lidded(shown, self.cap), self.cap, self._drawn)   # and the hilltops' lids
        red = np.flatnonzero(((fit >= 1.0) & (shown <= self.cap)).ravel())   # a few no-fit points to show
        picked = red[np.linspace(0, len(red) - 1, min(len(red), 5)).astype(int)] if len(red) else red
        low = np.unravel_index(np.argmin(np.where(finite, shown, np.inf)), shown.shape)
        self.lowest_point = np.array([axis[low[0]], axis[low[1]], shown[low]])
        self.no_fit_points = np.stack([xs.ravel()[picked], ys.ravel()[picked], shown.ravel()[picked]], axis=-1)
        kept = shown <= self.cap   # the box around what is drawn (a cell beyond, where it is cut)
        near = kept | np.roll(kept, 1, 0) | np.roll(kept, -1, 0) | np.roll(kept, 1, 1) | np.roll(kept, -1, 1)
        xs_kept, ys_kept = xs[near], ys[near]
        self.bounds = np.array([[xs_kept.min(), ys_kept.min(), float(shown.min())],
                                [xs_kept.max(), ys_kept.max(), float(min(shown.max(), self.cap))]])
        for item in (self.grid_lines, self.cut_edge, *self.trails, self.liftoff, self.preview.casing,
                     self.preview):   # after the surface
            self.removeItem(item)
            self.addItem(item)
        return {"no_fit": bool((fit >= 1.0).any()), "undefined": bool((~np.isfinite(z)).any()),
                "cut": bool(shown.max() > self.cap), "coarse": too_coarse(landscape, axis, z)}

    def height_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The drawn surface's height at points, a hilltop's lid included, interpolated
        bilinearly on the grid (-inf outside the grid or where the surface is cut away)."""
        axis, n = self._axis, len(self._axis)
        step = (axis[-1] - axis[0]) / max(n - 1, 1)
        u, v = (np.asarray(x) - axis[0]) / step, (np.asarray(y) - axis[0]) / step
        inside = (u >= 0) & (u <= n - 1) & (v >= 0) & (v <= n - 1)
        i, j = np.clip(np.floor(u).astype(int), 0, n - 2), np.clip(np.floor(v).astype(int), 0, n - 2)
        a, b = np.clip(u - i, 0, 1), np.clip(v - j, 0, 1)
        z = self._top
        with np.errstate(invalid="ignore"):   # -inf corners stay -inf
            h = ((1 - a) * (1 - b) * z[i, j] + a * (1 - b) * z[i + 1, j] + (1 - a) * b * z[i, j + 1]
                 + a * b * z[i + 1, j + 1])
        return np.where(inside & np.isfinite(h), h, -np.inf)

    def in_sight(self, point: np.ndarray, eye: np.ndarray, clearance: float) -> bool:
        """Whether the straight line from ``eye`` to ``point`` passes above the drawn surface
        by at least a quarter of ``clearance`` (from ``clearance`` away from the point on, so
        that the ball itself does not count)."""
        length = float(np.linalg.norm(eye - point))
        t = np.linspace(min(clearance / length, 1.0), 1.0, 400)[:, None]
        samples = point + t * (eye - point)
        return bool(np.all(samples[:, 2] >= self.height_at(samples[:, 0], samples[:, 1]) + clearance / 4))

    # -- camera ----------------------------------------------------------------------

    def reset_camera(self, include: np.ndarray | None = None, aspect: float | None = None) -> None:
        """Frame the drawn landscape, its heights included, from the first viewpoint of
        ``VIEWPOINTS`` where the ball, some of the region where it does not fit, the path
        (``PATH_SAMPLES`` of the preview's points, once it has come: ``set_preview``) and the
        lowest point are in sight (not behind a wall); failing that, without the lowest point,
        then without the path. ``include``: more points (n, 3) the ball's centre passes (an export
        frames the whole path, also where it leaves the drawn grid; default: the preview's path);
        ``aspect``: the framed picture's height over its width (default: the view's)."""
        r = self.ball_radius
        path = self.path[np.linspace(1, len(self.path) - 1, min(PATH_SAMPLES, len(self.path) - 1)).astype(int)] \
            if self.path is not None else np.zeros((0, 3))
        self.awaiting_path = self.path is None   # framed again when it comes
        box = self._box(include if include is not None else self.path)
        center = box.mean(axis=0)
        corners = np.array([[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        aspect = aspect or self.height() / max(self.width(), 1)
        fov = self.opts["fov"]
        reach = LABEL_REACH * TICK * float(max(box[1, 0] - box[0, 0], box[1, 1] - box[0, 1]))
        fitted = {}   # (distance, elevation, azimuth) of the viewpoints tried: most scenes need one

        def view(elevation, azimuth):
            if (elevation, azimuth) not in fitted:
                fitted[elevation, azimuth] = (self._fit_distance(
                    _labelled(corners, box, center, elevation, azimuth, reach), center, elevation, azimuth,
                    fov, aspect), elevation, azimuth)
            return fitted[elevation, azimuth]
        must = (self.ball_center, *self.no_fit_points)
        tried = ((*must, self.lowest_point, *path), (*must, *path), (*must, self.lowest_point), must)
        chosen = next((view(*v) for wanted in tried for v in VIEWPOINTS
                       if all(self.in_sight(point, look(center, *view(*v)), 2 * r) for point in wanted)),
                      None) or view(*VIEWPOINTS[0])   # the landscape framed, should no side show the ball
        distance, elevation, azimuth = chosen
        axes_eye = look(center, distance, elevation, azimuth)
        if not self.follow:   # the picture's middle on what is framed, not on the box's centre
            center, distance = self._centred(_labelled(corners, box, center, elevation, azimuth, reach), center,
                                             distance, elevation, azimuth, fov, aspect)
        self.setCameraPosition(distance=distance, elevation=elevation, azimuth=azimuth)
        focus = self.ball_center if self.follow else center
        self.opts["center"] = QtGui.QVector3D(*map(float, focus))
        self._draw_axes(box, axes_eye)
        self.framed = True
        self.update()

    def _box(self, include: np.ndarray | None = None) -> np.ndarray:
        """The box framed: the drawn landscape, the ball and ``include`` (n, 3)."""
        r = self.ball_radius
        points = np.vstack([self.ball_center.reshape(1, 3)] + ([] if include is None else
                                                                [np.asarray(include, dtype=float).reshape(-1, 3)]))
        points = points[np.all(np.isfinite(points), axis=1)]
        return np.array([np.minimum(self.bounds[0], points.min(axis=0) - r),
                         np.maximum(self.bounds[1], points.max(axis=0) + r)])

    def refresh_axes(self) -> None:
        """The axes around the landscape as now drawn, the camera left where it is (a slider
        reshaping the landscape: its heights change, the view does not jump)."""
        if self.axis_labels:   # the axes were drawn (by reset_camera) before
            eye = self.cameraPosition()
            self._draw_axes(self._box(), np.array([eye.x(), eye.y(), eye.z()]))

    @classmethod
    def _centred(cls, corners, center, distance, elevation, azimuth, fov, aspect) -> tuple[np.ndarray, float]:
        """The focus and distance at which the framed ``corners`` stand in the middle of the view:
        seen in perspective, the near half of a box looks larger than the far half, so a camera
        aimed at the box's centre leaves a band empty above it (a fifth of a saved picture's
        height). The camera is moved across its line of sight, focus and eye together, until the
        corners' projected extents are even about the middle (three rounds; the move shrinks by
        the depth's spread each round), then brought as near as ``_fit_distance`` allows."""
        for _ in range(3):
            eye = look(center, distance, elevation, azimuth)
            forward = (center - eye) / distance
            right, up = camera_axes(forward)
            rel = np.atleast_2d(corners) - eye
            depth = rel @ forward
            across, upward = (rel @ right) / depth, (rel @ up) / depth
            center = center + distance * (0.5 * (across.max() + across.min()) * right
                                          + 0.5 * (upward.max() + upward.min()) * up)
            distance = cls._fit_distance(corners, center, elevation, azimuth, fov, aspect)
        return center, distance

    @staticmethod
    def _fit_distance(corners, center, elevation, azimuth, fov, aspect) -> float:
        """The camera distance at which every corner lies within FILL of the view."""
        near, far = 1e-3, 1e3 * float(np.ptp(corners, axis=0).max() + 1.0)
        # as ``project`` sees them from eye = center + d·u (u the unit vector to the camera): the
        # view's axes do not depend on d and a corner's depth is q + d, so it is within FILL
        # from d = |its sideways offset| / (FILL · tan(fov/2) · (1 or aspect)) − q on
        eye = look(center, 1.0, elevation, azimuth)
        forward = center - eye
        right, up = camera_axes(forward)
        rel = np.atleast_2d(corners) - center
        half = FILL * np.tan(np.radians(fov) / 2)
        needed = np.maximum(np.abs(rel @ right) / half, np.abs(rel @ up) / (half * aspect)) - rel @ forward
        return float(min(max(needed.max(), near), far))

    def _draw_axes(self, box: np.ndarray, eye: np.ndarray) -> None:
        """Axes with ticks and labels in metres along the box's lower edges nearest the eye,
        and a height axis at their corner."""
        (x0, y0, z0), (x1, y1, z1) = box
        ox = x1 if eye[0] > (x0 + x1) / 2 else x0     # the corner nearest the camera
        oy = y1 if eye[1] > (y0 + y1) / 2 else y0
        horizontal = max(x1 - x0, y1 - y0)
        tick = TICK * horizontal
        away = np.array([1.0 if ox == x1 else -1.0, 1.0 if oy == y1 else -1.0, 0.0]) * tick
        segments, labels = [], []
        for k, (lo, hi) in enumerate(((x0, x1), (y0, y1), (z0, z1))):
            start = np.array([ox, oy, z0])
            start[k] = lo
            end = start.copy()
            end[k] = hi
            segments += [start, end]
            out = away * ([0.0, 1.0, 0.0] if k == 0 else [1.0, 0.0, 0.0])   # ticks point outwards
            if k == 2 and hi - lo < 0.05 * horizontal:
                break   # a flat landscape: no height axis
            step = nice_step(hi - lo, 6 if k < 2 else 5)
            corner = (ox, oy)[k] if k < 2 else None
            numbers = []
            for value in np.arange(np.ceil(lo / step) * step, hi + 1e-9 * step, step):
                at = start.copy()
                at[k] = value
                segments += [at, at + out]
                if corner is None or abs(value - corner) > 0.5 * step:   # the corner is the height axis's
                    numbers.append((at + 2.5 * out, f"{value if abs(value) > 1e-9 * step else 0.0:g}", k))
            # the first and last numbers before those between (they are kept first where crowded)
            labels += numbers[:1] + numbers[-1:] + numbers[1:-1] if len(numbers) > 1 else numbers
            # the height axis's name beside its top number (as far out as that number is wide:
            # ``_place_name``), the others' beyond their ends
            labels.append((end + 6 * out, "xyz"[k] + " (m)", (end, out) if k == 2 else None))
        self.axes.setData(pos=np.array(segments))
        for item in self.axis_labels:
            self.removeItem(item)
        font = QtGui.QFont()
        font.setPointSizeF(8 * self.label_scale)
        self.axis_labels = [gl.GLTextItem(pos=np.asarray(pos, dtype=float), text=text, color=TEXT_COLOR,
                                          font=font, glOptions="translucent") for pos, text, _ in labels]
        for item, (_, _, about) in zip(self.axis_labels, labels):
            item.setDepthValue(LABEL_DEPTH)
            item.is_name = item.text.endswith(" (m)")
            item.axis = about if not item.is_name else None              # a number's axis (0, 1, 2)
            item.beside = about if item.is_name else None               # the height axis's (top, out)
            self.addItem(item)
        self._thinned_for = None

    def _thin_labels(self, size: tuple[int, int]) -> None:
        """In a picture of ``size`` (the screen's or an export's), an axis number that would
        overlap an axis name or a number shown before it is left out: the names first, then
        each axis's numbers in order. (The height axis is short beside the others: with large
        text its numbers would run into each other and into "z (m)".) Worked out again only when
        the size, the camera or the labels change."""
        w, h = size
        matrix = self.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * self.viewMatrix()
        key = (w, h, self.width(), tuple(matrix.data()), id(self.axis_labels), self.label_scale)
        if key == self._thinned_for:
            return
        self._thinned_for = key
        scale = w / max(1, self.width())
        gap = LABEL_GAP * scale

        def screen(point) -> tuple[float, float] | None:
            p = matrix.map(QtGui.QVector4D(*map(float, point), 1.0))
            return None if p.w() <= 0 else ((p.x() / p.w() + 1) / 2 * w, (1 - p.y() / p.w()) / 2 * h)

        kept: list[QtCore.QRectF] = []
        font = QtGui.QFont(self.axis_labels[0].font) if self.axis_labels else QtGui.QFont()
        font.setPixelSize(label_pixels(self.axis_labels[0], scale) if self.axis_labels else MIN_LABEL_PIXELS)
        metrics = QtGui.QFontMetricsF(font)   # every label has the same font
        widest = max((metrics.horizontalAdvance(item.text) for item in self.axis_labels if item.axis == 2),
                     default=0.0)
        for item in sorted(self.axis_labels, key=lambda item: not item.is_name):
            if item.beside is not None:
                self._place_name(item, screen, widest, metrics.horizontalAdvance(item.text), gap)
            xy = screen(item.pos)
            show = xy is not None
            if show:
                x, y = xy
                rect = QtCore.QRectF(x, y - metrics.ascent(), metrics.horizontalAdvance(item.text),
                                     metrics.ascent() + metrics.descent()).adjusted(-gap, -gap, gap, gap)
                show = not any(rect.intersects(other) for other in kept)
                if show:
                    kept.append(rect)
            if item.visible() != show:
                item.setVisible(show)
        self._kept = ((w, h), [QtCore.QRectF(r.x() / scale, r.y() / scale, r.width() / scale, r.height() / scale)
                               for r in kept])

    @staticmethod
    def _place_name(item: gl.GLTextItem, screen, numbers: float, name: float, gap: float) -> None:
        """The height axis's name at its top, out beyond its numbers (``numbers`` pixels wide at
        most, 2.5 ticks out) on the picture: they are drawn rightwards from their anchors, so
        where the ticks point right the name starts past the widest number, where they point left
        it ends before the numbers start."""
        top, out = item.beside
        a, b = screen(top), screen(np.asarray(top) + out)
        if a is None or b is None or abs(b[0] - a[0]) < 1e-6:
            return
        reach = 2.5 + ((numbers if b[0] > a[0] else name) + 2 * gap) / abs(b[0] - a[0])   # in ticks
        pos = np.asarray(top, dtype=float) + reach * np.asarray(out)
        if not np.allclose(pos, item.pos):
            item.setData(pos=pos)

    def paintGL(self) -> None:
        super().paintGL()
        self._note_taken()

    def _note_taken(self) -> None:
        """``taken`` for the picture on screen as just painted; ``axesPlaced`` when it changed."""
        w, h = self.width(), self.height()
        size, rects = self._kept
        if size != (w, h) or self._thinned_for == self._taken_for:
            return
        self._taken_for = self._thinned_for
        matrix = np.array(self.projectionMatrix((0, 0, w, h), (0, 0, w, h)).data()).reshape(4, 4).T @ \
            np.array(self.viewMatrix().data()).reshape(4, 4).T
        pos = np.asarray(self.axes.pos if self.axes.pos is not None else np.zeros((0, 3)), dtype=float)
        pairs = pos[: len(pos) // 2 * 2].reshape(-1, 2, 3)
        clip = np.concatenate([pairs, np.ones(pairs.shape[:2] + (1,))], axis=2) @ matrix.T
        ahead = (clip[:, :, 3] > 0).all(axis=1)   # (a line reaching behind the camera: left out)
        clip = clip[ahead]
        ndc = clip[:, :, :2] / clip[:, :, 3:]
        lines = np.stack([(ndc[:, :, 0] + 1) / 2 * w, (1 - ndc[:, :, 1]) / 2 * h], axis=-1)
        self.taken = (rects, lines)
        self.axesPlaced.emit()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        if self.framed:
            self.reset_camera()

    def mousePressEvent(self, event) -> None:
        grab = self._grab(event)
        if grab is not None:
            self._drag = grab
            event.accept()
            return
        self.framed = False   # the user takes the camera
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event) -> None:
        if self._drag is not None:
            self._dragged(event.position())
            event.accept()
            return
        if event.buttons() == QtCore.Qt.MouseButton.NoButton:
            self._hover(event)
        super().mouseMoveEvent(event)

    def mouseReleaseEvent(self, event) -> None:
        if self._drag is not None:
            self._drag = None
            if self.follow:   # the camera stood still under the mouse while it dragged: it follows again
                self.opts["center"] = QtGui.QVector3D(*map(float, self.ball_center))
                self.update()
            self.dragFinished.emit()
            event.accept()
            return
        super().mouseReleaseEvent(event)

    # -- the start's handles --------------------------------------------------------------

    def set_start(self, center: np.ndarray | None, normal: np.ndarray | None = None,
                  velocity: np.ndarray | None = None, velocity_fixed: bool = False) -> None:
        """The start's handles at the ball's ``center`` (``normal``: the surface's there;
        ``velocity``: the centre's, tangent to the surface), the arrow drawn to where the centre
        would be ARROW_SECONDS later; None: no handles (a run is shown). ``velocity_fixed``: the
        arrow is shown but not dragged (a scene with a ``start.omega`` that goes with it)."""
        self.start = None if center is None else tuple(np.asarray(a, dtype=float) for a in (center, normal, velocity))
        self.velocity_fixed = velocity_fixed
        shown = self.start is not None and bool(np.any(self.start[2]))
        self.arrow.setVisible(shown)
        self.arrow_head.setVisible(shown)
        if not shown:
            if self.start is None:
                self._drag = None
            return
        center, normal, velocity = self.start
        tip = center + ARROW_SECONDS * velocity
        length = float(np.linalg.norm(tip - center))
        back = (center - tip) / length * min(0.25 * length, 3.0 * self.ball_radius)   # the head's barbs
        side = np.cross(normal, back) * 0.5
        self.arrow.setData(pos=np.array([center, tip, tip, tip + back + side, tip, tip + back - side]))
        self.arrow_head.setData(pos=tip.reshape(1, 3))

    def set_preview(self, points: np.ndarray | None, colors: np.ndarray | None = None) -> None:
        """The path's preview (None or fewer than two points: none), ``colors`` one (r, g, b, a)
        per point: the mode it predicts there (``contact_view.trail_colors``)."""
        shown = points is not None and len(points) >= 2
        self.preview.setVisible(shown)
        self.preview.casing.setVisible(shown)
        if shown:
            points = np.asarray(points, dtype=float)
            self.preview.setData(pos=points, color=np.asarray(colors, dtype=float))
            self.preview.casing.setData(pos=points, width=self.preview.width + CASING_EXTRA)
            self.path = points
            if self.framed and self.awaiting_path:   # the camera was chosen without it (just opened)
                self.reset_camera()

    def _matrix(self) -> np.ndarray:
        w, h = self.width(), self.height()
        return np.array((self.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * self.viewMatrix()).data()).reshape(4, 4).T

    def _ray(self, pos) -> tuple[np.ndarray, np.ndarray]:
        return mouse_ray(self._matrix(), pos.x(), pos.y(), self.width(), self.height())

    def _handle_at(self, pos, shift: bool = False) -> str | None:
        """"velocity" over the arrow's head, "point" over the ball (Shift: "velocity"), or None."""
        if self.start is None:
            return None
        center, _, velocity = self.start
        m, w, h = self._matrix(), self.width(), self.height()
        mouse = np.array([pos.x(), pos.y()])
        shift = shift and not self.velocity_fixed
        if np.any(velocity) and not self.velocity_fixed:
            tip = on_screen(m, center + ARROW_SECONDS * velocity, w, h)
            if tip is not None and np.linalg.norm(tip - mouse) <= HANDLE_PIXELS:
                return "velocity"
        ball = on_screen(m, center, w, h)
        reach = max(self.ball_pixels() / 2, MARK_PIXELS / 2)
        if ball is not None and np.linalg.norm(ball - mouse) <= reach:
            return "velocity" if shift else "point"
        return None

    def _grab(self, event) -> tuple[str, np.ndarray] | None:
        if event.button() != QtCore.Qt.MouseButton.LeftButton:
            return None
        shift = bool(event.modifiers() & QtCore.Qt.KeyboardModifier.ShiftModifier)
        handle = self._handle_at(event.position(), shift)
        if handle is None:
            return None
        offset = np.zeros(2)
        if handle == "point":   # the contact point keeps its offset from the point grabbed
            hit = ray_surface(*self._ray(event.position()), self.height_at, self._axis[0], self._axis[-1])
            contact = self.start[0] - self.ball_radius * self.start[1]
            offset = (contact - hit)[:2] if hit is not None else offset
        return handle, offset

    def _dragged(self, pos) -> None:
        kind, offset = self._drag
        origin, direction = self._ray(pos)
        if kind == "point":
            hit = ray_surface(origin, direction, self.height_at, self._axis[0], self._axis[-1])
            if hit is not None:
                self.startDragged.emit(*map(float, hit[:2] + offset))
            return
        center, normal, _ = self.start
        hit = ray_plane(origin, direction, center, normal)   # the tangent plane at the centre
        if hit is not None:
            self.velocityDragged.emit(*map(float, (hit - center)[:2] / ARROW_SECONDS))

    def _hover(self, event) -> None:
        shift = bool(event.modifiers() & QtCore.Qt.KeyboardModifier.ShiftModifier)
        handle = self._handle_at(event.position(), shift)
        cursors = {"point": QtCore.Qt.CursorShape.OpenHandCursor, "velocity": QtCore.Qt.CursorShape.SizeAllCursor}
        if handle is None:
            self.unsetCursor()
        else:
            self.setCursor(cursors[handle])
        self.setToolTip({"point": "Drag to move the start point over the surface (Shift: set the velocity)",
                         "velocity": "Drag to set the start velocity (the arrow: where the ball is "
                                     f"{ARROW_SECONDS:g} s later)"}.get(handle, ""))

    def wheelEvent(self, event) -> None:
        self.framed = False
        super().wheelEvent(event)

    # -- ball, trail, markers ---------------------------------------------------------

    def set_runs(self, colors: list | None) -> None:
        """One ball and trail per colour (compare mode), or None: the single striped ball."""
        for item in self.balls[1:] + self.trails[1:] + [t.casing for t in self.trails[1:]] + self.marks[1:]:
            self.removeItem(item)
        self.balls, self.trails, self.marks = [self.ball], [self.trail], self.marks[:1]
        self._color_mark(self.marks[0], MARK_EDGE if colors is None else colors[0])
        self.ball.setMeshData(meshdata=ball_mesh() if colors is None else run_ball_mesh(colors[0]))
        # the trails' colours are given per point (``set_trail``): a single colour set after
        # per-point ones would reach the GL buffer as a tuple
        self._trail_colors = [np.asarray(pg.mkColor(c).getRgbF(), dtype=float) for c in colors] if colors \
            else [np.asarray(TRAIL_COLOR)]
        self.trail.setData(pos=np.zeros((0, 3)), color=np.zeros((0, 4)))
        self.casing.setData(pos=np.zeros((0, 3)))
        for color in (colors or [])[1:]:
            ball = gl.GLMeshItem(meshdata=run_ball_mesh(color), smooth=False, shader="shaded",
                                 glOptions="opaque")
            ball.setTransform(self.ball.transform())   # at the start until its run's first row
            ball.setDepthValue(BALL_DEPTH)
            mark = self._mark(color, len(self.marks))
            mark.setData(pos=self.marks[0].pos)
            self.marks.append(mark)
            trail = self._trail_items(pg.mkColor(color).getRgbF())
            self.addItem(ball)
            self.addItem(trail.casing)
            self.addItem(trail)
            self.balls.append(ball)
            self.trails.append(trail)
        self.removeItem(self.liftoff)  # the marker stays on top
        self.addItem(self.liftoff)
        for ball, trail in zip(self.balls, self.trails):
            ball.setVisible(True)
            trail.setVisible(self.trails_shown)
            trail.casing.setVisible(self.trails_shown)
        self.centers = [self.centers[0]] * len(self.balls)
        self.colors = list(colors) if colors else None
        self.followed = 0
        self._ghosts()

    def _ghosts(self) -> None:
        """With several runs, the followed run's ball is solid and the others are see-through
        ghosts drawn after it: a ball deformed by a classic update stays in sight where the
        other runs' balls stand in the same place."""
        if not self.colors or len(self.balls) < 2:
            return
        for k, (ball, color) in enumerate(zip(self.balls, self.colors)):
            ghost = k != self.followed
            ball.setMeshData(meshdata=run_ball_mesh(color, GHOST_ALPHA if ghost else 1.0))
            ball.setGLOptions("translucent" if ghost else "opaque")
            ball.setDepthValue(GHOST_DEPTH if ghost else BALL_DEPTH)

    def set_run_visible(self, index: int, visible: bool) -> None:
        self.balls[index].setVisible(visible)
        self.trails[index].setVisible(visible and self.trails_shown)
        self.trails[index].casing.setVisible(visible and self.trails_shown)

    # -- the ball's mark: seen from the back of the room, the ball itself drawn to scale ----

    def _mark(self, edge, k: int = 0) -> gl.GLScatterPlotItem:
        """A ring ``mark_pixels`` wide around a ball's centre, drawn over the surface and under
        the ball: a dark (or the run's) edge, a pale inside. Run k's ring is wider by k fifths of
        its width and drawn before those of the runs before it, so where balls stand together
        every ring shows."""
        mark = gl.GLScatterPlotItem(pos=np.zeros((2, 3)), size=ring_sizes(MARK_PIXELS, k), pxMode=True)
        mark.ring = (MARK_PIXELS, k)   # the ring's width and the run's index it is drawn for
        self._color_mark(mark, edge)
        mark.setGLOptions(MARK_GL)
        mark.setDepthValue(MARK_DEPTH - 0.01 * k)
        mark.setVisible(False)
        self.addItem(mark)
        return mark

    @staticmethod
    def _color_mark(mark: gl.GLScatterPlotItem, edge, fill=MARK_FILL) -> None:
        edge = np.asarray(pg.mkColor(edge).getRgbF() if isinstance(edge, str) else edge, dtype=float)
        edge[3] = MARK_EDGE[3]
        mark.fill = tuple(fill)
        mark.setData(color=np.array([edge, fill]))

    def set_mark_fill(self, fill=MARK_FILL, index: int = 0) -> None:
        """The inside of a ball's ring: pale white, or tinted (the contact's mode while it slides:
        a slip seen from afar while it happens, however short its trail)."""
        mark = self.marks[index]
        if mark.fill != tuple(fill):
            self._color_mark(mark, mark.color[0], fill)

    def ball_pixels(self, index: int = 0, size: tuple[int, int] | None = None) -> float:
        """A ball's diameter in pixels, true to scale, on screen or in a picture of ``size``
        taken with the same camera: its centre and a point one radius from it across the line
        of sight, projected with the view's own matrices."""
        w, h = size or (self.width(), self.height())
        m = np.array((self.projectionMatrix((0, 0, w, h), (0, 0, w, h)) * self.viewMatrix()).data()).reshape(4, 4).T
        right = np.array(self.viewMatrix().row(0).toVector3D().toTuple())   # the camera's x axis in the world
        center = self.centers[index]
        points = np.array([[*center, 1.0], [*(center + self.ball_radius * right), 1.0]]) @ m.T
        if np.any(points[:, 3] <= 0):
            return 0.0   # behind the camera
        ndc = points[:, :2] / points[:, 3:]
        return float(np.linalg.norm((ndc[1] - ndc[0]) * [w / 2, h / 2])) * 2

    def set_marks_visible(self, on: bool) -> None:
        self.marks_shown = on
        self.update()

    def _place_marks(self, size: tuple[int, int]) -> None:
        """For a picture of ``size`` (the screen's or an export's): a ball is marked while it is
        drawn smaller than ``mark_pixels(size)``, by a ring that wide (changed only when it
        changes: a change asks for one more frame)."""
        ring = mark_pixels(size)
        for k, (ball, mark) in enumerate(zip(self.balls, self.marks)):
            wanted = self.marks_shown and ball.visible() and self.ball_pixels(k, size) < ring
            if mark.visible() != wanted:
                mark.setVisible(wanted)
            if wanted and mark.ring != (ring, k):
                mark.ring = (ring, k)
                mark.setData(size=ring_sizes(ring, k))

    def paint(self, *, region, viewport, useItemNames=False) -> None:
        """On screen (``paintGL``) and off screen (``renderToArray``, an export at any size)."""
        self._place_marks((int(viewport[2]), int(viewport[3])))
        self._thin_labels((int(viewport[2]), int(viewport[3])))
        super().paint(region=region, viewport=viewport, useItemNames=useItemNames)

    def set_label_scale(self, scale: float) -> None:
        """The axis labels at ``scale`` times their normal size."""
        if scale == self.label_scale:
            return
        self.label_scale = scale
        for item in self.axis_labels:
            font = QtGui.QFont(item.font)
            font.setPointSizeF(8 * scale)
            item.setData(font=font)

    def set_trails_visible(self, on: bool) -> None:
        self.trails_shown = on
        for ball, trail in zip(self.balls, self.trails):
            trail.setVisible(on and ball.visible())
            trail.casing.setVisible(on and ball.visible())

    def set_ball(self, center: np.ndarray, R: np.ndarray, radius: float, index: int = 0) -> None:
        """Place a run's ball (see ``ball_transform``)."""
        self.balls[index].setTransform(ball_transform(center, R, radius))
        self.centers[index] = np.asarray(center, dtype=float)
        self.marks[index].setData(pos=np.tile(self.centers[index], (2, 1)))
        self.ball_radius = radius
        if self.follow and index == self.followed and self._drag is None:   # (a dragged start: after the drag)
            self.opts["center"] = QtGui.QVector3D(*map(float, center))
        self.update()

    @staticmethod
    def _trail_items(color) -> gl.GLLinePlotItem:
        """A run's trail, with its dark casing as ``trail.casing`` (both to be added to the view)."""
        trail = gl.GLLinePlotItem(color=color, width=3.0, antialias=False, mode="line_strip", glOptions=TRAIL_GL)
        trail.casing = gl.GLLinePlotItem(color=CASING_COLOR, width=3.0 + CASING_EXTRA, antialias=True,
                                         mode="line_strip", glOptions=CASING_GL)
        trail.setDepthValue(TRAIL_DEPTH)
        trail.casing.setDepthValue(CASING_DEPTH)
        return trail

    def set_trail(self, points: np.ndarray, index: int = 0, colors: np.ndarray | None = None) -> None:
        """A run's trail through ``points``; ``colors``: one (r, g, b, a) per point (the contact's
        modes), else the run's own colour."""
        enough = len(points) >= 2
        if colors is None:
            colors = np.tile(self._trail_colors[index], (len(points), 1))
        trail = self.trails[index]
        trail.setData(pos=points if enough else np.zeros((0, 3)), color=colors if enough else np.zeros((0, 4)))
        trail.casing.setData(pos=points if enough else np.zeros((0, 3)), width=trail.width + CASING_EXTRA)

    def set_marked(self, points: np.ndarray, colors: np.ndarray) -> None:
        """The marked points (n, 3), each in its colour (n, 4): lift-offs and the other changes of
        the contact's mode, those playback has reached (none: the marker hidden)."""
        shown = len(points) > 0
        self.liftoff.setVisible(shown)
        if shown:
            self.liftoff.setData(pos=np.asarray(points, dtype=float).reshape(-1, 3),
                                 color=np.asarray(colors, dtype=float).reshape(-1, 4))

    def set_follow(self, follow: bool, radius: float | None = None, index: int | None = None) -> None:
        """Keep a run's ball (``index``, or the one followed so far) in the centre of the view;
        zoom in to it when a radius is given."""
        self.follow = follow
        if index is not None and index != self.followed:
            self.followed = index
            self._ghosts()
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
