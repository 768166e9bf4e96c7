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
LABELS.update({"landscape": "landscape", "description": "description",
               "integrator.method": "method", "integrator.munthe_kaas": "Munthe-Kaas"})


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
    return [key for key in b if a.get(key) != b[key]]


def describe(old: Scene, new: Scene) -> str:
    keys = changed_keys(old, new)
    if len(keys) == 1:
        return f"Change {LABELS.get(keys[0], keys[0])}"
    return f"Change {len(keys)} fields"


class SceneChange(QtGui.QUndoCommand):
    """From scene ``old`` to ``new`` through ``show(scene)``. ``applied``: the change was already
    made (a field edit), so the first ``redo``, which ``QUndoStack.push`` calls, does nothing."""

    def __init__(self, show: Callable[[Scene], None], old: Scene, new: Scene, text: str | None = None,
                 applied: bool = True):
        super().__init__(text or describe(old, new))
        self.show, self.old, self.new = show, old, new
        self._done = applied

    def redo(self) -> None:
        if self._done:
            self._done = False
            return
        self.show(self.new)

    def undo(self) -> None:
        self.show(self.old)
