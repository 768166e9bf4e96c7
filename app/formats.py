"""The animation files the app writes and their frame rates: plain values, without numpy or Qt,
so that ``rollball-app`` refuses a bad ``--record`` or ``--fps`` at once (``main.py``)."""

from __future__ import annotations

import os
from pathlib import Path

FORMATS = {".mp4": "MP4 video", ".gif": "GIF animation"}
MIN_FPS = 1
DEFAULT_FPS = 30
MAX_FPS = 120


def format_of(path: str | os.PathLike) -> str:
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{Path(path).name}: an animation is .mp4 or .gif")
    return suffix
