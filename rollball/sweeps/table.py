"""A sweep's result: one row per run (the varied values, a status, the outcomes), and its files."""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import __version__, kernel
from ..files import atomic_write, check_outputs, replace_together
from ..scene import Scene
from ..trajectory import MODES, Status
from .grid import Grid
from .outcomes import INVALID, NOT_RUN, O_BASIN, O_END_MODE, OUTCOMES

# Status codes by name, as the CSV writes them.
STATUS_NAMES = {kernel.OK: str(Status.OK), kernel.DOES_NOT_FIT: str(Status.DOES_NOT_FIT),
                kernel.NONFINITE: str(Status.NONFINITE), INVALID: "invalid", NOT_RUN: "not_run"}
FORMAT = "rollball-sweep"
FILES = ("sweep.csv", "sweep.json", "sweep.png")
KEPT_NAME = "sweep-unsaved"   # where a sweep's files that could not replace the old ones are kept


def check(directory, keep=()) -> None:
    """Before the first run: the folder and each of a sweep's files may be written (OSError if not)."""
    check_outputs(directory, FILES, keep)
VERSION = 1


@dataclass
class SweepTable:
    """The runs of a sweep in grid order (row-major over the varied keys, the last fastest).

    ``table["start.vx"]``, ``table["status"]``, ``table["liftoff_time"]``: a column as an
    array (NaN where a run has no such value: no lift-off, a refused scene, a run not done).
    ``partial`` says the sweep was stopped early; its unfinished runs have status "not_run".
    """

    scene: Scene
    grid: Grid
    codes: np.ndarray                  # (runs,) status codes
    outcomes: np.ndarray               # (runs, len(OUTCOMES))
    messages: dict[int, str] = field(default_factory=dict)   # why a run's scene was refused
    seconds: float = 0.0               # wall time of the sweep
    workers: int | None = None         # local threads or processes, or the cluster's workers
    processes: bool = False            # the local workers were processes (runs that hold the GIL)
    scheduler: str | None = None       # Dask scheduler address, or None for a local sweep
    machine: str = ""
    error: str | None = None           # why a sweep stopped early: its cluster or a worker process failed
    minima: tuple | None = None        # the landscape's minima the basins are numbered by (basins.Minimum)

    @property
    def keys(self) -> tuple[str, ...]:
        return self.grid.keys

    @property
    def columns(self) -> tuple[str, ...]:
        return self.grid.keys + ("status",) + OUTCOMES

    @property
    def done(self) -> np.ndarray:
        return self.codes != NOT_RUN

    @property
    def partial(self) -> bool:
        return not bool(np.all(self.done))

    def __len__(self) -> int:
        return self.grid.size

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self.grid.keys:
            return self.grid.values()[:, self.grid.keys.index(name)]
        if name == "status":
            names = np.array([STATUS_NAMES.get(c, "") for c in range(max(STATUS_NAMES) + 1)], dtype=object)
            return names[self.codes]
        if name in OUTCOMES:
            return self.outcomes[:, OUTCOMES.index(name)]
        raise KeyError(f"no column {name!r}; the columns: {', '.join(self.columns)}")

    def counts(self) -> dict[str, int]:
        """Runs per status."""
        codes, counts = np.unique(self.codes, return_counts=True)
        return {STATUS_NAMES[int(c)]: int(n) for c, n in zip(codes, counts)}

    # -- files ---------------------------------------------------------------------------

    def write_csv(self, stream) -> None:
        """The finished runs: varied keys, status, outcomes (full precision, empty where a run
        has no value; the mode at the end by name, the basin by number), and a message for refused scenes."""
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(self.columns + ("message",))
        values = self.grid.values()
        status = self["status"]
        for i in np.flatnonzero(self.done):
            cells = ["" if math.isnan(v) else repr(float(v)) for v in self.outcomes[i]]
            mode, basin = self.outcomes[i, O_END_MODE], self.outcomes[i, O_BASIN]
            cells[O_END_MODE] = "" if math.isnan(mode) else MODES[int(mode)]
            cells[O_BASIN] = "" if math.isnan(basin) else str(int(basin))
            writer.writerow([repr(float(v)) for v in values[i]] + [status[i]] + cells
                            + [self.messages.get(int(i), "")])

    def to_csv(self, path) -> None:
        atomic_write(path, self.write_csv)

    def to_dict(self) -> dict:
        done = int(np.count_nonzero(self.done))
        return {
            "format": FORMAT, "version": VERSION, "program": f"rollball {__version__}",
            "scene": self.scene.to_dict(),
            "grid": [{"key": k, "n": len(a), "values": a.tolist()} for k, a in zip(self.grid.keys, self.grid.axes)],
            "runs": len(self), "finished": done, "partial": self.partial, "error": self.error,
            "outcomes": list(OUTCOMES), "status": self.counts(),
            "method": self.scene.integrator.method,
            "machine": self.machine, "workers": self.workers,
            "processes": self.processes, "scheduler": self.scheduler,
            "seconds": self.seconds,
            "runs_per_second": done / self.seconds if self.seconds > 0 else None,
            **({} if self.minima is None else {"minima": [m.to_dict() for m in self.minima]}),
        }

    def save(self, directory, color: str = "liftoff_time") -> list[Path]:
        """Write sweep.csv, sweep.json and (one or two varied keys, with matplotlib) sweep.png
        into ``directory`` (created if missing), replaced together or not at all
        (``files.replace_together``; an old sweep.png is removed when there is no figure, so it
        cannot pass for this sweep's). ``files.NotReplaced`` when none was: the new files are
        then kept in a folder of their own, named in its message. Returns the files written."""
        from .plot import figure_png

        csv_text = io.StringIO()
        self.write_csv(csv_text)
        files = {"sweep.csv": csv_text.getvalue(),
                 "sweep.json": json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n",
                 "sweep.png": figure_png(self, color)}
        return replace_together(directory, files, kept_name=KEPT_NAME)
