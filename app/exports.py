"""What the window writes besides the scene: the trajectory as CSV, the view as a PNG, the run's
playback as an MP4 or GIF, with their dialogs.

Every file is written whole or not at all, and never over the open scene's file. The window
only wires its actions to these methods; what is drawn comes from its view, close-up, plots and
run controller.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from rollball.files import atomic_write_bytes, write_target
from rollball.trajectory import CENTER

from .animation import frame_times, record
from .controller import RUNNING, STOPPED
from .dialogs import AnimationDialog, ImageDialog
from .formats import DEFAULT_FPS
from .picture import ACCENTS, caption_height, caption_text, compose, rgb_array

CSV_FILTER = "CSV files (*.csv);;All files (*)"


class Exports:
    """The window's exports (``window``: a ``MainWindow``; its ``_write`` writes a file
    atomically and reports a failure)."""

    def __init__(self, window):
        self.window = window

    def _keep(self) -> list[Path]:
        """Files an export may never replace: the open scene's."""
        path = self.window.document.path
        return [path] if path else []

    # -- trajectory ------------------------------------------------------------------

    def export_dialog(self) -> None:
        w = self.window
        suggestion = str(Path(w.preferences.last_folder()) / f"{w.document.stem or 'trajectory'}.csv")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(w, "Export trajectory", suggestion, CSV_FILTER)
        if path:
            self.export_csv(Path(path))

    def export_csv(self, path: Path) -> bool:
        w = self.window
        simulation = w.controller.simulation
        if simulation is None or not (w.controller.computed or w.runs.state == STOPPED):
            return False   # what a stopped run computed is exported as it stands
        trajectory = simulation.trajectory()
        keep = self._keep()
        if not w.files.write("export trajectory", path, lambda target: trajectory.to_csv(target, keep=keep)):
            return False
        w.show_message(f"Exported {len(trajectory):,} rows to {Path(path).name}")
        return True

    # -- image -----------------------------------------------------------------------

    def suggest(self, suffix: str) -> Path:
        """A file name saying the scene and the time shown, in the last folder used."""
        w = self.window
        t = w.controller.play_time if w.controller.runs else 0.0
        return Path(w.preferences.last_folder()) / f"{w.document.stem or 'rollball'}-t{t:.2f}s{suffix}"

    def save_image_dialog(self) -> None:
        dialog = ImageDialog(self.suggest(".png"), self.window)
        if dialog.exec() == QtWidgets.QDialog.DialogCode.Accepted:
            self.save_image(dialog.path, **dialog.options())

    def picture(self, size: tuple[int, int], caption: bool = False, plots: bool = False) -> QtGui.QImage:
        """The 3-D view at ``size`` as shown (with the close-up when it is on), optionally with a
        caption and the plots."""
        w = self.window
        return compose(w.view, size, inset=w.closeup if w.closeup.isVisible() else None,
                       caption=self.caption() if caption else None,
                       plots=w.bottom.currentWidget() if plots and w.bottom.isVisible() else None)   # (not folded away)

    def caption(self) -> str | None:
        """What is shown, in one line: formula, method(s) and step, time."""
        w = self.window
        runs = w.controller.runs
        scene = runs[0].simulation.scene if runs else w.scene
        methods = [run.label for run in runs] if w.compare.active and runs else None
        return caption_text(scene, w.controller.play_time, methods) if scene else None

    def save_image(self, path: Path, scale: int = 1, caption: bool = False, plots: bool = False) -> bool:
        """The 3-D view as a PNG at ``scale`` times its size on screen, written atomically."""
        w = self.window
        image = self.picture((scale * w.view.width(), scale * w.view.height()), caption, plots)
        data = QtCore.QByteArray()
        buffer = QtCore.QBuffer(data)
        buffer.open(QtCore.QIODevice.OpenModeFlag.WriteOnly)
        image.save(buffer, "PNG")
        keep = self._keep()
        if not w.files.write("save image", path, lambda target: atomic_write_bytes(target, bytes(data), keep=keep)):
            return False
        w.show_message(f"Saved {path.name} ({image.width()}×{image.height()})")
        return True

    # -- animation -------------------------------------------------------------------

    def export_animation_dialog(self) -> None:
        w = self.window
        if not w.controller.runs:
            return
        size = (w.view.width() - w.view.width() % 2, w.view.height() - w.view.height() % 2)
        dialog = AnimationDialog(self.suggest(".mp4").with_name(f"{w.document.stem or 'rollball'}.mp4"),
                                 size, w.controller.end_time, w)
        if dialog.exec() != QtWidgets.QDialog.DialogCode.Accepted:
            return
        options = dialog.options()
        progress = QtWidgets.QProgressDialog("Exporting animation…", "Cancel", 0, 100, w)
        progress.setWindowModality(QtCore.Qt.WindowModality.WindowModal)
        progress.setMinimumDuration(300)

        def report(done: int, total: int) -> bool:
            progress.setMaximum(total)
            progress.setValue(done)
            return not progress.wasCanceled()
        try:
            self.export_animation(dialog.path, progress=report, **options)
        except (OSError, ValueError) as error:
            w._warn("Cannot export animation", f"{dialog.path}: {getattr(error, 'strerror', None) or error}. "
                                               "Nothing was changed.")
        finally:
            progress.close()

    def export_animation(self, path: Path, fps: float = DEFAULT_FPS, t0: float = 0.0, t1: float | None = None,
                         size: tuple[int, int] | None = None, caption: bool = True, progress=None) -> bool:
        """Play the computed run from t0 to t1 into an MP4 or GIF, ``fps`` frames per simulated
        second, each frame the 3-D view at ``size`` (default: as on screen); the moment shown
        before, and playback if it was playing, come back after it. False if there is
        no run or it was cancelled; OSError or ValueError if it cannot be written. Either way a
        file is written whole or not at all."""
        w = self.window
        if not w.controller.runs:
            return False
        end = w.controller.end_time
        t1 = end if t1 is None else min(t1, end)
        size = size or (w.view.width(), w.view.height())
        times = frame_times(t0, t1, fps)
        keep = self._keep()
        write_target(path, keep)   # refused before a frame is drawn
        shown, started = w.controller.play_time, QtCore.QElapsedTimer()
        playing = w.controller.state == RUNNING
        started.start()
        w.controller.pause()
        view_size = (size[0], size[1] - caption_height(size[0])) if caption else size   # caption inside
        # a camera as framed on opening frames the whole path in the video (the ball may leave
        # the drawn grid); one the user turned, zoomed or set to follow the ball is kept
        reframe = w.view.framed and not w.view.follow
        if reframe:
            w.view.reset_camera(include=self.path(t0, t1), aspect=view_size[1] / max(1, view_size[0]))
        try:
            done = record(path, times, fps, size, w.runs.seek, lambda: rgb_array(self.picture(view_size, caption)),
                          progress, ACCENTS, keep=keep)
        finally:
            if reframe:
                w.view.reset_camera()
            w.runs.seek(shown)
            if playing:
                w.controller.toggle_pause()   # playback goes on from where it was
        if not done:
            w.show_message("Export cancelled; nothing was written")
            return False
        w.preferences.set_last_folder(path)
        w.show_message(f"Exported {len(times)} frames ({times[-1] - times[0]:.3g} s at {fps:g} per second) "
                       f"to {Path(path).name} in {started.elapsed() / 1000:.1f} s")
        return True

    def path(self, t0: float, t1: float) -> np.ndarray:
        """The balls' centres from t0 to t1, every run's (an export frames them all)."""
        paths = [run.buffer.rows[(run.buffer.t >= t0) & (run.buffer.t <= t1)][:, CENTER]
                 for run in self.window.controller.runs if len(run.buffer)]
        return np.vstack(paths) if paths else np.zeros((0, 3))
