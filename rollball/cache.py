"""Where RollBall keeps compiled code between runs: the landscapes' generated modules and
their compiled form, and the kernel's machine code (machine_code.py)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

_CACHE_DIR: Path | None = None


def cache_dir() -> Path:
    """The cache folder: $ROLLBALL_CACHE_DIR, else $XDG_CACHE_HOME/rollball (~/.cache/rollball), else, where
    that cannot be written, a temporary directory for this process only."""
    global _CACHE_DIR
    if _CACHE_DIR is None:
        base = os.environ.get("ROLLBALL_CACHE_DIR") or os.path.join(
            os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "rollball")
        try:
            os.makedirs(base, exist_ok=True)
            if not os.access(base, os.W_OK):
                raise PermissionError(base)
            _CACHE_DIR = Path(base)
        except OSError:
            _CACHE_DIR = Path(tempfile.mkdtemp(prefix="rollball-"))
    return _CACHE_DIR
