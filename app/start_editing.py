"""Editing the start in the 3-D view before a run: the path's preview drawn ahead of the ball,
and the ball and its velocity arrow dragged there.

``StartEditing`` ties the view's handles (``view3d.SceneView``: ``startDragged``,
``velocityDragged``, ``dragFinished``) to the Scene panel's start fields and keeps the preview
(``preview.PathPreview``) up to date with the scene shown. The window calls ``show`` where it
draws the ball at its start and ``hide`` when a run is shown instead.
"""

from __future__ import annotations

import numpy as np
from PySide6 import QtCore

from rollball import Scene

from .picking import rounded
from .contact_view import trail_colors
from .preview import PathPreview, Preview
from .view3d import ARROW_SECONDS

DRAG_RESOLUTION = 1e-3   # a dragged start is rounded to this fraction of the drawn grid's width


class StartEditing(QtCore.QObject):
    """``show(scene, center, normal)``: the ball stands at its start: handles and a preview;
    ``hide()``: a run is shown (no handles, no preview)."""

    def __init__(self, view, panel, parent=None):
        super().__init__(parent)
        self.view, self.panel = view, panel
        self.preview = PathPreview(self)
        self.preview.ready.connect(self._preview_ready)
        self.preview.failed.connect(lambda _message: self.view.set_preview(None))
        self.scene: Scene | None = None     # the scene whose start is shown (None: hidden)
        self.drags = 0                      # counts drags: one undo step each
        view.startDragged.connect(self._point_dragged)
        view.velocityDragged.connect(self._velocity_dragged)
        view.dragFinished.connect(self._finished)

    def show(self, scene: Scene, center: np.ndarray, normal: np.ndarray, slope: np.ndarray) -> None:
        """The ball at the start ``center`` with the surface's ``normal`` and ``slope`` (f_x,
        f_y) there: the handles, and the preview asked for (the old one stays until it comes)."""
        s = scene.start
        velocity = np.array([s.vx, s.vy, slope[0] * s.vx + slope[1] * s.vy])   # tangent to the surface
        # with a start.omega of its own, the velocity goes with it (the app has no field for ω): not dragged
        self.view.set_start(center, normal, velocity, velocity_fixed=s.omega is not None)
        if scene != self.scene:   # (the same scene drawn again: its preview is there or coming)
            self.scene = scene
            self.preview.request(scene)

    def hide(self) -> None:
        self.scene = None
        self.preview.clear()
        self.view.set_start(None)
        self.view.set_preview(None)

    def shutdown(self) -> None:
        self.preview.shutdown()

    def _preview_ready(self, preview: Preview) -> None:
        if preview.scene == self.scene:
            self.view.set_preview(preview.points, trail_colors(preview.modes))

    def _resolution(self) -> float:
        view = self.panel.scene().view
        return DRAG_RESOLUTION * (view.max - view.min)

    def _point_dragged(self, x: float, y: float) -> None:
        step = self._resolution()
        self.panel.put({"start.x": rounded(x, step), "start.y": rounded(y, step)}, ("start", self.drags))

    def _velocity_dragged(self, vx: float, vy: float) -> None:
        step = self._resolution() / ARROW_SECONDS
        self.panel.put({"start.vx": rounded(vx, step), "start.vy": rounded(vy, step)}, ("start", self.drags))

    def _finished(self) -> None:
        self.drags += 1
