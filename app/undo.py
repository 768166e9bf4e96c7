"""Undo and redo over scene changes: every valid change of the fields is one ``SceneChange`` on a
``QUndoStack``; undoing it puts the previous scene back into the fields and the view.

What changed is named from the scenes themselves (``changed_keys``), so the Edit menu reads
"Undo Change radius" without the panel telling.
"""

from __future__ import annotations

from typing import Callable

from PySide6 import QtGui

from rollball import Scene

from .inputs import NUMBER_FIELDS

LABELS = {key: f"{group.lower()} {label}" if group in ("Start", "Grid") else label.lower()
          for group, fields in NUMBER_FIELDS.items() for key, label, _, _ in fields}
LABELS.update({"landscape": "landscape", "description": "description", "parameters": "parameters",
               "integrator.method": "method", "integrator.munthe_kaas": "Munthe-Kaas",
               "contact.friction": "friction", "contact.restitution": "restitution",
               "contact.after_liftoff": "after lift-off", "start.omega": "start ω",
               "contact.rolling_resistance": "rolling resistance", "contact.spin_friction": "spin friction",
               "air.density": "air density", "air.drag_coefficient": "drag coefficient",
               "stop_at_rest": "stop at rest"})


def _flat(data: dict, prefix: str = "") -> dict:
    out = {}
    for key, value in data.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def changed_keys(old: Scene, new: Scene) -> list[str]:
    """The dotted scene keys whose values differ, in the scene file's order."""
    a, b = _flat(old.to_dict()), _flat(new.to_dict())
    return [key for key in {**b, **a} if a.get(key) != b.get(key)]   # (a key one of them leaves out: start.omega)


def describe(old: Scene, new: Scene) -> str:
    added = [n for n in new.parameter_names if n not in old.parameter_names]
    removed = [n for n in old.parameter_names if n not in new.parameter_names]
    if len(added) + len(removed) == 1:   # (with the formula changed, or not)
        return f"Add parameter {added[0]}" if added else f"Remove parameter {removed[0]}"
    keys = changed_keys(old, new)
    if keys in (["start.x", "start.y"], ["start.vx", "start.vy"]):   # a handle dragged in the view
        return "Move start point" if keys[0] == "start.x" else "Change start velocity"
    if keys == ["air.density", "air.drag_coefficient"]:   # the air's choice fills both
        return "Change air"
    if len(keys) == 1:
        key = keys[0]
        if key.startswith("parameters.") and key not in LABELS:   # parameters.k or parameters.k.value
            return f"Change parameter {key.split('.')[1]}"
        return f"Change {LABELS.get(key, key)}"
    return f"Change {len(keys)} fields"


GESTURE_ID = 1   # QUndoCommand.id of changes that merge with the previous one of their gesture


class SceneChange(QtGui.QUndoCommand):
    """From scene ``old`` to ``new`` through ``show(scene)``. ``applied``: the change was already
    made (a field edit), so the first ``redo``, which ``QUndoStack.push`` calls, does nothing.
    Changes of the same ``gesture`` (a slider's drag) merge into one step, from the scene before
    the drag to the scene after it."""

    def __init__(self, show: Callable[[Scene], None], old: Scene, new: Scene, text: str | None = None,
                 applied: bool = True, gesture=None):
        super().__init__(text or describe(old, new))
        self.show, self.old, self.new = show, old, new
        self._done = applied
        self.gesture = gesture

    def id(self) -> int:
        return GESTURE_ID if self.gesture is not None else -1

    def mergeWith(self, other) -> bool:
        if not isinstance(other, SceneChange) or other.gesture != self.gesture or self.gesture is None:
            return False
        self.new = other.new
        if self.old == self.new:
            self.setObsolete(True)   # dragged back to where it was: no step
        else:
            self.setText(describe(self.old, self.new))
        return True

    def redo(self) -> None:
        if self._done:
            self._done = False
            return
        self.show(self.new)

    def undo(self) -> None:
        self.show(self.old)
