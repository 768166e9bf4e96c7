"""What the probes share that drive the real window in a process of their own under a window
manager (``probe_modes``, ``probe_layout``), and how a test runs one: on a virtual screen of the
size asked for, with openbox, its report the last line it prints (JSON)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from PySide6 import QtWidgets

ROOT = Path(__file__).resolve().parents[2]


def settle(seconds: float = 0.5) -> None:
    """Let the window and the window manager do what is pending for ``seconds``."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        QtWidgets.QApplication.processEvents()
        time.sleep(0.01)


def wait_until(condition, seconds: float = 120.0) -> bool:
    """Process events until ``condition()`` holds (True) or ``seconds`` have passed (False)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        QtWidgets.QApplication.processEvents()
        if condition():
            return True
        time.sleep(0.01)
    return False


def run_probe(module: str, screen: str, *args: str, timeout: float) -> dict:
    """Run ``python -m tests.gui.MODULE ARGS`` on a new virtual screen ``screen`` (WxH) with
    openbox as its window manager; the report it printed last."""
    command = f"openbox >/dev/null 2>&1 & sleep 1; {sys.executable} -m tests.gui.{module} {' '.join(args)}"
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    done = subprocess.run(["xvfb-run", "-a", "-s", f"-screen 0 {screen}x24 +extension GLX +render",
                           "bash", "-c", command], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=timeout)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])
