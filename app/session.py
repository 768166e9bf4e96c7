"""The scene being worked on, without widgets: the document (where it came from, what was
saved), the scene the view and the run belong to, and the undo history of its changes.

The window shows what the session holds and calls it for every change of the scene; the
session says what a change touches (``changes``) and records it for undo. ``show`` is the one
way back into the window: undo, redo, revert and a loaded run put a scene in the fields and
the view through it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from PySide6 import QtCore, QtGui

from rollball import RunSpec, Scene, get_method

from .document import Document
from .undo import SceneChange


def physics(scene: Scene) -> tuple:
    """What a run depends on (not the drawn grid or the description)."""
    return (scene.landscape, scene.parameters, scene.gravity, scene.ball, scene.start, scene.integrator,
            scene.duration, scene.contact)


def run_spec(scene: Scene) -> RunSpec:
    """The method and orientation update a run of the scene uses."""
    method = get_method(scene.integrator.method)
    return RunSpec(method.name, scene.integrator.munthe_kaas or not method.classic_allowed)


@dataclass(frozen=True)
class Changes:
    """What going from one scene to another touches."""
    grid: bool      # the drawn landscape's formula or grid: redraw it and reset the camera
    surface: bool   # the surface as drawn for this ball (its cut follows the ball's energy), or
                    # with new parameter values (redrawn, the camera kept: a slider is dragged)
    run: bool       # what a run depends on: the run is reset


def changes(old: Scene | None, new: Scene) -> Changes:
    if old is None:
        return Changes(True, True, True)
    grid = old.landscape != new.landscape or old.view != new.view
    surface = (grid or old.parameters != new.parameters or old.ball.radius != new.ball.radius
               or old.start != new.start or old.gravity != new.gravity)
    return Changes(grid, surface, physics(old) != physics(new))


class SceneSession(QtCore.QObject):
    """``show(scene)`` puts a scene into the window (fields and view)."""

    def __init__(self, show: Callable[[Scene], None], parent: QtCore.QObject | None = None):
        super().__init__(parent)
        self.show = show
        self.document = Document()
        self.undo = QtGui.QUndoStack(self)
        self.shown: Scene | None = None   # what the view and the run belong to

    def opened(self, path: Path, scene: Scene, example: bool) -> None:
        """A scene file (or an example) was opened: a new document, no history."""
        self.undo.clear()
        self.document.opened(path, scene, example)

    def edited(self, old: Scene | None, new: Scene, gesture=None) -> None:
        """The fields were changed from ``old`` to ``new`` (already shown): one undo step; the
        changes of one ``gesture`` (a slider's drag) make one step together."""
        if old is not None and old != new:
            self.undo.push(SceneChange(self.show, old, new, gesture=gesture))

    def load(self, current: Scene | None, scene: Scene, text: str) -> bool:
        """Put ``scene`` in place of ``current`` as one undo step named ``text``; False if it is
        the same scene (nothing to do)."""
        if scene == current:
            return False
        self.undo.push(SceneChange(self.show, current, scene, text, applied=False))
        return True

    def revert(self, current: Scene | None) -> bool:
        """Back to the scene as opened or last saved (itself undoable); False if already there."""
        saved = self.document.saved_scene
        if saved is None or not self.document.dirty(current):
            return False
        return self.load(current, saved, "Revert to saved")
