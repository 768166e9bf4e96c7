"""Preferences kept in QSettings, apart from scenes: window geometry, recent files, last folder,
text size, whether future events are shown."""

from __future__ import annotations

import os
import stat
import sys
from pathlib import Path

from PySide6 import QtCore

MAX_RECENT = 8


class SessionSettings:
    """Preferences kept for this session only (what QSettings offers the app), where the
    preferences file cannot be used."""

    def __init__(self):
        self._values: dict = {}

    def value(self, key: str, default=None):
        return self._values.get(key, default)

    def setValue(self, key: str, value) -> None:
        self._values[key] = value

    def sync(self) -> None:
        pass


def settings_files() -> list[Path]:
    """The files QSettings reads the app's preferences from (Unix: the user's
    ``$XDG_CONFIG_HOME/RollBall/RollBall.conf`` and ``RollBall.conf`` beside it, then the same
    in each system folder)."""
    if sys.platform in ("win32", "darwin"):   # the registry, property lists: not checked here
        return []
    org, app = QtCore.QCoreApplication.organizationName(), QtCore.QCoreApplication.applicationName()
    folders = [QtCore.QStandardPaths.writableLocation(QtCore.QStandardPaths.StandardLocation.GenericConfigLocation),
               *(os.environ.get("XDG_CONFIG_DIRS") or "/etc/xdg").split(os.pathsep),
               QtCore.QLibraryInfo.path(QtCore.QLibraryInfo.LibraryPath.SettingsPath)]
    files = []
    for folder in dict.fromkeys(f for f in folders if f):
        files += [Path(folder) / org / f"{app}.conf", Path(folder) / f"{org}.conf"]
    return files


def unusable_settings_file() -> tuple[Path, str] | None:
    """A preferences file QSettings would hang on or fail with (a named pipe, a device, a
    folder): QSettings opens it as soon as it is made, and a FIFO blocks there for good.
    Returns (path, what it is) or None."""
    for path in settings_files():
        try:
            mode = os.stat(path).st_mode
        except OSError:
            continue   # missing (or unreadable: QSettings copes)
        if not stat.S_ISREG(mode):
            kind = ("a named pipe (FIFO)" if stat.S_ISFIFO(mode) else "a folder" if stat.S_ISDIR(mode)
                    else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "not a regular file")
            return path, kind
    return None


def default_settings():
    """QSettings on the app's preferences file, or, where that file is not a regular file,
    preferences for this session only (said on stderr once)."""
    unusable = unusable_settings_file()
    if unusable is None:
        return QtCore.QSettings()
    path, kind = unusable
    print(f"rollball: warning: the preferences file {path} is {kind}, not a regular file: ignored "
          f"(preferences are kept for this session only)", file=sys.stderr)
    return SessionSettings()


class Preferences:
    def __init__(self, settings: QtCore.QSettings | None = None):
        self.settings = settings if settings is not None else default_settings()

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

    def show_future_events(self) -> bool:
        """Whether events are marked before playback reaches them (View ▸ Show Future Events)."""
        value = self.settings.value("showFutureEvents", False)
        return value is True or (isinstance(value, str) and value.lower() == "true")

    def set_show_future_events(self, on: bool) -> None:
        self.settings.setValue("showFutureEvents", bool(on))

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
