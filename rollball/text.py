"""User-controlled text inside messages: shown so that it cannot act on a terminal or a window."""

from __future__ import annotations

import os


def shown(text) -> str:
    """``text`` as it may appear in a one-line message: unchanged when it is plain printable
    text, else quoted and escaped as Python writes it (``'a\\nb'``, ``'\\x1b[2J'``), so a
    newline, an escape sequence or a direction override in a file name or a JSON key cannot
    fake a line, clear the screen or retitle the terminal."""
    text = os.fsdecode(text) if isinstance(text, (bytes, os.PathLike)) else str(text)
    return text if text.isprintable() else repr(text)
