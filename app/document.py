"""The scene being edited, as a document: where it came from, what was last saved, its title.

No Qt here: the window asks the document and shows what it says.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rollball import Scene


@dataclass
class Document:
    """A scene file (``path``), a shipped example (``example``), or neither (untitled)."""

    path: Path | None = None
    example: str | None = None
    saved_scene: Scene | None = None

    def opened(self, path: Path, scene: Scene, example: bool) -> None:
        """A scene was read from ``path`` (an example is not a file the user saves to)."""
        self.path = None if example else Path(path)
        self.example = Path(path).stem if example else None
        self.saved_scene = scene

    def saved(self, path: Path, scene: Scene) -> None:
        self.path, self.example, self.saved_scene = Path(path), None, scene

    def dirty(self, scene: Scene | None) -> bool:
        """Whether ``scene`` (what the fields hold) differs from what was opened or saved."""
        return scene is not None and scene != self.saved_scene

    @property
    def name(self) -> str:
        """The document's name as a title shows it."""
        if self.path:
            return self.path.name
        return f"{self.example} (example)" if self.example else "untitled"

    @property
    def stem(self) -> str | None:
        """A base name for files made from it (None when untitled)."""
        return self.path.stem if self.path else self.example

    def title(self) -> str:
        """The window title, with Qt's ``[*]`` where the modified mark goes."""
        return f"{self.name}[*] — RollBall"
