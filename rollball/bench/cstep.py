"""The C yardstick: ``step.c`` (the kernel's RK4 Munthe-Kaas step on the hills, by hand)
compiled with ``gcc -O3 -march=native`` at run time and timed in its own process."""

from __future__ import annotations

import atexit
import shutil
import subprocess
import tempfile
from importlib import resources
from pathlib import Path


class CStep:
    """The compiled C step; ``None`` from ``build`` where there is no gcc."""

    def __init__(self, executable: Path):
        self.executable = executable

    @classmethod
    def build(cls, directory: Path | None = None) -> "CStep | None":
        gcc = shutil.which("gcc")
        if gcc is None:
            return None
        if directory is None:   # a folder of this process's own, removed when it ends
            directory = tempfile.mkdtemp(prefix="rollball-cstep-")
            atexit.register(shutil.rmtree, directory, True)
        directory = Path(directory)
        executable = directory / "step"
        with resources.as_file(resources.files(__package__) / "step.c") as source:
            subprocess.run([gcc, "-O3", "-march=native", "-o", str(executable), str(source), "-lm"],
                           check=True, capture_output=True)
        return cls(executable)

    def run(self, radius: float, mass: float, gravity: float, x: float, y: float, dt: float,
            steps: int) -> tuple[float, float, float]:
        """ns per step and the final contact point of a run from rest at (x, y)."""
        args = [radius, mass, gravity, x, y, dt, steps]
        out = subprocess.run([str(self.executable), *map(repr, args)], check=True,
                             capture_output=True, text=True).stdout.split()
        return float(out[0]), float(out[1]), float(out[2])
