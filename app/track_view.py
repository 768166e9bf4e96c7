"""A measured track in the window: File → Import Measured Track… and Close Track, its points over
the 3-D view, and the residual of the scene against it in the status bar (docs/design.md §10).

The points are yellow dots with a dark rim (a colour none of the path's modes, events or the
preview uses), on the surface and under the trail: the model's path runs over the measured
points, which show beside it wherever the two part; as the trail, no hill hides them. Those up to
the playback time are drawn full, the ones ahead faint: where the real ball was by the time shown
and where it went next, beside the model's ball. A track of x and y lies on the surface (its
height the landscape's there); one with z is drawn as measured, a side view (x, z) in the
plane of the scene's start.

Each scene shown (an edit, an undo, another scene opened) is run to the track's last time in
the background and compared with it (``rollball.residuals``): the status bar's right says the
residual RMS against the track's noise and whether the model explains it; its tooltip says
all of it. The track is not remembered with the session (nor is any run or file but the scene).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pyqtgraph.opengl as gl
from OpenGL import GL
from PySide6 import QtCore, QtWidgets

from rollball import Fit, Scene, Track
from rollball.sweeps.grid import with_values
from rollball.text import shown
from rollball.track import TrackError
from rollball.track_check import ROUGH, residuals

from .controller import READY
from .fit_dialog import FitDialog
from .modes import place_over
from .track_import import TrackImportDialog, TrackReading
from .worker import Worker, one_line

TRACK_FILTER = "Measured tracks (*.csv *.tsv *.txt);;All files (*)"
# Yellow (Okabe–Ito's, which no mode, event or the preview uses) with a dark rim: seen on every
# height colour. Under the trail: the model's path runs over the measured points, which show beside
# it wherever the two part.
SEEN_COLOR = (0.94, 0.89, 0.26, 1.0)     # the points up to the playback time
AHEAD_COLOR = (0.94, 0.89, 0.26, 0.5)    # the points the playback has not reached: faint
RIM_COLOR = (0.1, 0.1, 0.1, 0.8)
POINT_PIXELS, RIM_PIXELS, AHEAD_PIXELS = 9.0, 12.0, 8.0
TRACK_DEPTH = 0.005                      # drawn after the surface (0), before the trail's casing (0.01)
POINTS_GL = {GL.GL_DEPTH_TEST: False, GL.GL_BLEND: True, GL.GL_CULL_FACE: False,
             "glBlendFunc": (GL.GL_SRC_ALPHA, GL.GL_ONE_MINUS_SRC_ALPHA)}
LIFT = 0.003                             # points on the surface sit this fraction of the view's extent above it
FIT_NOTE = "Fitted to"                   # how the note a fit adds to the description begins
RECHECK_MS = 200                         # a scene changing on and on (a slider) is compared once it rests


class MeasuredTrack(QtCore.QObject):
    """The window's measured track (``track``, None when there is none) and what shows it.
    ``residuals``: the shown scene against it, once computed (None before)."""

    changed = QtCore.Signal()   # a track imported or closed

    def __init__(self, window):
        super().__init__(window)
        self.window = window
        self.track: Track | None = None
        self.point = "center"
        self.residuals = None
        self._points = np.zeros((0, 3))
        self._token: object | None = None   # the comparison under way or last made
        self._announce = False      # say the verdict in the status message (a track just imported)
        self._drawn: tuple | None = None   # (points, how many full) as last drawn
        self.ahead = self._scatter(AHEAD_COLOR, AHEAD_PIXELS, "ahead")
        self.rims = self._scatter(RIM_COLOR, RIM_PIXELS, "rims")
        self.seen = self._scatter(SEEN_COLOR, POINT_PIXELS, "seen")
        self.label = QtWidgets.QLabel(objectName="trackResidual")
        self.label.hide()
        window.statusBar().addPermanentWidget(self.label)
        self._recheck = QtCore.QTimer(self, singleShot=True, interval=RECHECK_MS)
        self._recheck.timeout.connect(self._compare)
        window.controller.frameReady.connect(lambda _force: self.show_time())
        window.controller.stateChanged.connect(lambda _state: self.show_time())
        self.import_action = window._action("&Import Measured Track…", self.import_dialog, "Ctrl+Shift+T",
                                            "Read a measured track (CSV, TSV, Tracker's export) and show it "
                                            "over the view", name="import_track")
        self.close_action = window._action("Close &Track", self.close_track, None,
                                           "Take the measured track away", name="close_track")
        self.close_action.setEnabled(False)
        self.fit_action = window._action("&Fit to Track…", self.open_fit, None,
                                         "Fit scene values (start, friction, restitution, parameters) to the "
                                         "measured track", name="fit_to_track")

    def _scatter(self, color, size: float, name: str) -> gl.GLScatterPlotItem:
        item = gl.GLScatterPlotItem(pos=np.zeros((0, 3)), color=color, size=size, pxMode=True)
        item.setGLOptions(POINTS_GL)
        item.setDepthValue(TRACK_DEPTH + {"ahead": 0.0, "rims": 0.001, "seen": 0.002}[name])   # (< 0.01)
        item.setObjectName(f"track.{name}")
        item.setVisible(False)
        self.window.view.addItem(item)
        return item

    # -- importing and closing ---------------------------------------------------------

    def import_dialog(self) -> bool:
        """File → Import Measured Track…: a file, then how to read it; False if none was imported."""
        w = self.window
        path, _ = QtWidgets.QFileDialog.getOpenFileName(w, "Import measured track", w.preferences.last_folder(),
                                                        TRACK_FILTER)
        if not path:
            return False
        dialog = TrackImportDialog(Path(path), w)
        if dialog.exec() != QtWidgets.QDialog.DialogCode.Accepted:
            return False
        return self.load(path, dialog.reading())

    def load(self, path, reading: TrackReading | None = None) -> bool:
        """Read the track at ``path`` and show it; on failure say why in one line and keep what
        was shown (the track before, if any)."""
        w = self.window
        path, reading = Path(path), reading or TrackReading()
        try:
            track = Track.load(path, columns=reading.columns, length_unit=reading.length_unit,
                               time_unit=reading.time_unit)
        except OSError as error:
            w._warn("Cannot import track", f"{shown(path.name)}: {error.strerror or error}")
            return False
        except TrackError as error:   # it names the file by its path: the file's name, as a scene's
            w._warn("Cannot import track", f"{shown(path.name)}{str(error).removeprefix(shown(str(path)))}")
            return False
        self.track, self.point, self.residuals = track, reading.point, None
        self._announce = True
        w.preferences.set_last_folder(path)
        self.close_action.setEnabled(True)
        skipped = f"; {track.skipped} frames without a position skipped" if track.skipped else ""
        w.show_message(f"Imported {path.name}: {len(track)} positions ({', '.join(track.axes)}) from "
                       f"t = {track.t[0]:.4g} to {track.t[-1]:.4g} s{skipped}")
        self.scene_changed(w.scene)
        w.plots.set_track(track, reading.point)
        self.changed.emit()
        return True

    def close_track(self) -> None:
        """File → Close Track: the points and the residual go."""
        self.track, self.residuals, self._points, self._drawn = None, None, np.zeros((0, 3)), None
        self._recheck.stop()
        self._token = None   # what a comparison under way says is dropped
        for item in (self.ahead, self.rims, self.seen):
            item.setData(pos=np.zeros((0, 3)))
            item.setVisible(False)
        self.label.hide()
        self.close_action.setEnabled(False)
        self.window.plots.set_track(None)
        self.changed.emit()

    # -- fitting -----------------------------------------------------------------------

    def open_fit(self) -> FitDialog | None:
        """Analysis → Fit to Track…: a fit of the current scene to the track (imported first if
        there is none)."""
        w = self.window
        w.panel.apply()
        if (self.track is None and not self.import_dialog()) or w.scene is None:
            return None
        dialog = FitDialog(w.scene, self.track, self.point, w)
        dialog.setAttribute(QtCore.Qt.WidgetAttribute.WA_DeleteOnClose)
        dialog.applied.connect(self.apply_fit)
        self.changed.connect(dialog.close)   # another track, or none: the fit is of the old one
        place_over(dialog, w)
        dialog.show()
        return dialog

    def apply_fit(self, result: Fit) -> None:
        """The fit's estimates into the scene shown (its other values as they are now), with the
        fit's note in its description: one undo step."""
        w = self.window
        scene = w.scene
        fitted = with_values(scene, result.keys, result.values)
        description = result.scene.description
        note = description[description.rfind(FIT_NOTE):] if FIT_NOTE in description else ""
        fitted = dataclasses.replace(fitted, description=f"{scene.description} {note}".strip())
        if w.session.load(scene, fitted, "Apply Fit to Track"):
            w.show_message("Fitted values applied: " + ", ".join(
                f"{k} = {v:.6g}" for k, v in zip(result.keys, result.values)) + " (Edit → Undo puts the old ones back)")

    # -- drawing -----------------------------------------------------------------------

    def scene_changed(self, scene: Scene | None) -> None:
        """A scene is shown: the points placed on its surface, its residual computed (soon)."""
        if self.track is None or scene is None:
            return
        self._points, self.residuals = self.points_3d(scene), None
        for dialog in self.window.findChildren(FitDialog):
            dialog.set_scene(scene)   # the next fit starts from the scene shown
        self.show_time()
        self.label.setText("Track: comparing…")
        self.label.setToolTip("")
        self.label.show()
        self._recheck.start()

    def points_3d(self, scene: Scene) -> np.ndarray:
        """(n, 3) where each measured position is drawn: as measured where the track has z,
        on the surface where it has only x and y, in the start's plane where one of those lacks."""
        track, w = self.track, self.window
        columns = dict(zip(track.axes, track.positions.T))
        x = columns.get("x", np.full(len(track), scene.start.x))
        y = columns.get("y", np.full(len(track), scene.start.y))
        if "z" in columns:
            z = columns["z"]
        else:
            landscape = w.landscape
            z = np.asarray(landscape.evaluate(x, y)[0], dtype=float) + LIFT * w.view.extent
            z = np.where(np.isfinite(z), z, w.view.bounds[0, 2])   # undefined there: drawn at the lowest
        return np.column_stack([x, y, z])

    def show_time(self) -> None:
        """The points up to the playback time full, the rest faint (before a run: all full)."""
        if self.track is None:
            return
        controller = self.window.controller
        seen = np.ones(len(self.track), dtype=bool) if controller.state == READY or not controller.runs else \
            self.track.t <= controller.play_time + 1e-9
        drawn = (self._points, int(seen.sum()))
        if self._drawn is not None and self._drawn[0] is drawn[0] and self._drawn[1] == drawn[1]:
            return   # (called every frame: the same points are not sent to the GPU again)
        self._drawn = drawn
        for item, points in ((self.ahead, self._points[~seen]), (self.rims, self._points[seen]),
                             (self.seen, self._points[seen])):
            item.setData(pos=points)
            item.setVisible(len(points) > 0)

    def seen_count(self) -> int:
        """How many points are drawn full (up to the playback time)."""
        return len(self.seen.pos) if self.seen.visible() and self.seen.pos is not None else 0

    # -- the residual ------------------------------------------------------------------

    def _compare(self) -> None:
        scene, track, point = self.window.scene, self.track, self.point
        if scene is None or track is None:
            return
        token = self._token = object()   # names this comparison: an answer to an older one is dropped

        def compare(_progress, _cancel):
            try:
                return token, residuals(scene, track, point)
            except ValueError as error:   # a run too short to compare (the physics stopped it at once)
                return token, str(error)

        worker = Worker(compare, describe=one_line, name="track residual")
        # to methods of this object: what the worker says after the window has gone is dropped
        worker.done.connect(self._compared)
        worker.start()

    def _compared(self, answer: tuple) -> None:
        token, result = answer
        if token is not self._token:
            return   # a scene or track since replaced
        if isinstance(result, str):
            self.label.setText("Track: cannot compare")
            self.label.setToolTip(result)
            return
        self.residuals = result
        verdict = result.verdict()
        word = "explained" if result.explained else ("roughly" if result.covered and result.ratio <= ROUGH else
                                                      "not explained")
        self.label.setText(f"Track: RMS {result.rms * 1000:.3g} mm, {result.ratio:.3g}× noise — {word}")
        self.label.setToolTip("\n".join(result.lines()))
        self.label.setStyleSheet("" if result.explained else "color: #b03a00;")
        if self._announce:   # said once, for the track just imported; the label keeps it after
            self._announce = False
            self.window.show_message(f"{Path(result.track.source).name}: {verdict}")
