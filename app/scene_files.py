"""The window's scene commands: opening a scene (a file, a recent one, an example), saving it,
reverting it, asking before unsaved changes are lost, and showing a scene in the fields and
the view (the landscape drawn, the run reset when what it depends on changed).

The scene's document and undo history are the widget-free ``session.SceneSession``'s; this
module is what the window does with them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PySide6 import QtWidgets

from rollball import Scene, SceneError
from rollball.geometry import reachable_height
from rollball.text import shown

from .controller import PAUSED, RUNNING
from .inputs import compile_reason
from .parameters import valued
from .session import changes

SCENE_FILTER = "RollBall scenes (*.json);;All files (*)"


class SceneFiles:
    """The scene commands of ``window`` (a ``MainWindow``: its session, panel, view, close-up,
    plots, preferences and run commands)."""

    def __init__(self, window):
        self.window = window

    @property
    def dirty(self) -> bool:
        w = self.window
        return w.document.dirty(w.scene)

    # -- opening ---------------------------------------------------------------------

    def open_scene(self, path, remember: bool = True) -> bool:
        """Load a scene file; on failure say why and keep the current scene."""
        w = self.window
        path = Path(path)
        try:  # a named pipe or a device is refused before it is opened (it would block)
            scene = Scene.load(path)
        except (SceneError, OSError) as error:
            reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
            w._warn("Cannot open scene", f"{shown(path.name)}: {reason}")
            if remember:
                w.preferences.remove_recent(str(path.resolve()))
            return False
        if not self.may_discard():
            return False
        w.runs.reset()
        w.session.opened(path, scene, example=not remember)
        if remember:
            w.preferences.add_recent(path)
            w.preferences.set_last_folder(path)
        w.panel.set_scene(scene)
        notes = self.use_scene(scene, redraw_camera=True)
        w.show_message(f"Opened {path.name}" + (f": {scene.description}" if scene.description else "")
                       + "".join(f" ({note})" for note in notes))
        return True

    def open_dialog(self) -> None:
        w = self.window
        path, _ = QtWidgets.QFileDialog.getOpenFileName(w, "Open scene", w.preferences.last_folder(), SCENE_FILTER)
        if path:
            self.open_scene(path)

    def fill_recent(self, menu: QtWidgets.QMenu) -> None:
        """File → Open Recent, as it is shown."""
        menu.clear()
        preferences = self.window.preferences
        files = preferences.recent_files()
        for path in files:
            action = menu.addAction(Path(path).name)
            action.setToolTip(path)
            action.setStatusTip(path)
            action.triggered.connect(lambda _=False, p=path: self.open_scene(p))
        if not files:
            menu.addAction("(none)").setEnabled(False)
        menu.addSeparator()
        menu.addAction("Clear Recent", preferences.clear_recent).setEnabled(bool(files))

    # -- changes ---------------------------------------------------------------------

    def scene_edited(self, scene: Scene) -> None:
        """The fields make a new scene: shown, and one undo step."""
        session = self.window.session
        old = session.shown
        self.use_scene(scene)
        session.edited(old, scene, self.window.panel.gesture)

    def show_scene(self, scene: Scene) -> None:
        """Put a scene into the fields and the view (undo, redo, revert)."""
        self.window.panel.set_scene(scene)
        self.use_scene(scene)

    def revert(self) -> None:
        """Back to the scene as opened or last saved (itself undoable)."""
        w = self.window
        if not w.session.revert(w.scene):
            return
        w.show_message(f"Reverted to {w.document.name}")

    def use_scene(self, scene: Scene, redraw_camera: bool = False) -> list[str]:
        """Show a valid scene; a change to what a run depends on resets the run. Returns notes
        on what the drawn landscape shows (no-fit and undefined regions)."""
        w = self.window
        old = w.session.shown
        landscape = valued(scene)   # with the parameters' values: new values compile nothing
        try:
            landscape.compiled  # noqa: B018 - compile now, so a run starts at once
        except Exception as error:  # numba refused generated code: keep what is shown
            w._warn("Cannot use this landscape", compile_reason(error))
            return []
        notes = []
        changed = changes(old, scene)
        if changed.surface:
            w.landscape = landscape
            start = landscape.evaluate(scene.start.x, scene.start.y)
            reachable = reachable_height(start, scene) if np.all(np.isfinite(start)) else np.inf
            facts = w.view.set_landscape(landscape, scene.view, scene.ball.radius, reachable)
            w.closeup.set_landscape(landscape, scene.ball.radius, w.view.z_span)
            if facts["no_fit"]:
                notes.append("red: the ball does not fit there")
            if facts["undefined"]:
                notes.append("grey: the landscape is undefined there")
            if facts["cut"]:
                notes.append("cut level where the ball's energy cannot take it")
            if facts["coarse"]:
                notes.append("the grid spacing is too coarse for this landscape, the drawing is misleading: "
                             "choose a smaller area or spacing")
            w.show_message("; ".join(notes).capitalize())
        w.plots.set_duration(scene.duration)
        if changed.run:
            if w.controller.state in (RUNNING, PAUSED):
                w.show_message("Scene changed: the run was reset")
            w.runs.reset()
        if redraw_camera or changed.grid:
            w.view.reset_camera()   # after the reset, so the ball stands at the start
        elif changed.surface:
            w.view.refresh_axes()   # new heights (a slider): the camera stays
        w.session.shown = scene
        w.compare.scene_changed(scene)
        w.measured.scene_changed(scene)
        self.update_title()
        return notes

    def update_title(self) -> None:
        w = self.window
        dirty, title = self.dirty, w.document.title()
        if w.isWindowModified() != dirty or w.windowTitle() != title:   # (setting them costs ms: the
            w.setWindowModified(dirty)                                   # window system is told)
            w.setWindowTitle(title)
        w.revert_action.setEnabled(dirty)

    def may_discard(self) -> bool:
        """Ask before unsaved scene changes are lost; True to go on."""
        if not self.dirty:
            return True
        answer = self.ask_unsaved()
        if answer == QtWidgets.QMessageBox.StandardButton.Save:
            return self.save()
        return answer == QtWidgets.QMessageBox.StandardButton.Discard

    def ask_unsaved(self) -> QtWidgets.QMessageBox.StandardButton:
        buttons = QtWidgets.QMessageBox.StandardButton
        return QtWidgets.QMessageBox.question(self.window, "Unsaved changes",
                                              "The scene has unsaved changes. Save them?",
                                              buttons.Save | buttons.Discard | buttons.Cancel, buttons.Save)

    # -- saving ----------------------------------------------------------------------

    def save(self) -> bool:
        document = self.window.document
        if document.path is None:
            return self.save_as()
        return self.save_to(document.path)

    def save_as(self) -> bool:
        w = self.window
        suggestion = str(Path(w.preferences.last_folder()) / f"{w.document.stem or 'scene'}.json")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(w, "Save scene", suggestion, SCENE_FILTER)
        return bool(path) and self.save_to(Path(path))

    def save_to(self, path: Path) -> bool:
        w = self.window
        scene = w.panel.apply() or w.scene
        if w.panel.error_text:
            w.show_message(f"Saving the last valid scene ({w.panel.error_text})")
        if not self.write("save scene", path, scene.save):
            return False
        w.document.saved(path, scene)
        w.preferences.add_recent(path)
        self.update_title()
        w.show_message(f"Saved {Path(path).name}")
        return True

    def write(self, what: str, path: Path, write) -> bool:
        """``write(path)`` (atomic); a failure is reported and leaves any old file as it was."""
        w = self.window
        try:
            write(path)
        except OSError as error:
            w._warn(f"Cannot {what}", f"{shown(path)}: {error.strerror or error}. Nothing was changed.")
            return False
        w.preferences.set_last_folder(path)
        return True
