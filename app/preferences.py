"""Preferences kept in QSettings, apart from scenes: window geometry, recent files, last folder,
text size."""

from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore

MAX_RECENT = 8


class Preferences:
    def __init__(self, settings: QtCore.QSettings | None = None):
        self.settings = settings or QtCore.QSettings()

    def recent_files(self) -> list[str]:
        value = self.settings.value("recentFiles", [])
        files = [value] if isinstance(value, str) else list(value or [])
        return [f for f in files if isinstance(f, str)][:MAX_RECENT]

    def add_recent(self, path: str | Path) -> None:
        path = str(Path(path).resolve())
        files = [path] + [f for f in self.recent_files() if f != path]
        self.settings.setValue("recentFiles", files[:MAX_RECENT])

    def remove_recent(self, path: str) -> None:
        self.settings.setValue("recentFiles", [f for f in self.recent_files() if f != path])

    def clear_recent(self) -> None:
        self.settings.setValue("recentFiles", [])

    def last_folder(self) -> str:
        folder = self.settings.value("lastFolder", "")
        return folder if isinstance(folder, str) and Path(folder).is_dir() else str(Path.home())

    def set_last_folder(self, path: str | Path) -> None:
        self.settings.setValue("lastFolder", str(Path(path).resolve().parent))

    def font_scale(self) -> float:
        """The text size of readouts, status and plots, as a factor (1: normal)."""
        try:
            value = float(self.settings.value("fontScale", 1.0))
        except (TypeError, ValueError):
            return 1.0
        return value if 0.5 <= value <= 4.0 else 1.0

    def set_font_scale(self, scale: float) -> None:
        self.settings.setValue("fontScale", float(scale))

    def restore(self, window) -> None:
        geometry, state = self.settings.value("geometry"), self.settings.value("windowState")
        if isinstance(geometry, QtCore.QByteArray):
            window.restoreGeometry(geometry)
        if isinstance(state, QtCore.QByteArray):
            window.restoreState(state)

    def save(self, window) -> None:
        self.settings.setValue("geometry", window.saveGeometry())
        self.settings.setValue("windowState", window.saveState())
        self.settings.sync()
