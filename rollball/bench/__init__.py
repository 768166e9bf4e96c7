"""``rollball bench``: the speed targets and the work-precision report.

``run`` measures (see ``targets`` and ``workprecision``) and writes ``bench.md``,
``bench.png`` (needs matplotlib: ``pip install rollball[bench]``) and ``bench.json``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

from ..files import atomic_write_text
from . import report, targets, workprecision


@dataclass(frozen=True)
class Config:
    scenes: tuple[str, ...]        # example scene names
    t_end: float | None            # None: each scene's own duration
    repeats: int                   # timed runs per point (their median counts)
    quick: bool                    # fewer steps, tolerances and repeats
    targets: bool = True           # also measure the speed targets


FULL = Config(("hills", "bowl", "saddle"), None, 5, quick=False)
QUICK = Config(("hills", "bowl", "saddle"), 2.0, 3, quick=True)


def run(out: Path, config: Config = FULL, log=print) -> str:
    """Measure, write bench.md / bench.png / bench.json into ``out`` and return the Markdown."""
    out.mkdir(parents=True, exist_ok=True)
    measured = None
    if config.targets:
        log("speed targets ...")
        measured = targets.measure(config.quick)
    log("work against precision ...")
    points = workprecision.measure(list(config.scenes), config.t_end, config.quick, config.repeats)
    text = report.markdown(measured, points, config.t_end, config.quick)
    if report.figure(points, out / "bench.png"):
        text += "\n![work-precision](bench.png)\n"
    else:
        text += "\n(no figure: matplotlib is not installed; `pip install rollball[bench]`)\n"
    atomic_write_text(out / "bench.md", text)
    atomic_write_text(out / "bench.json", json.dumps({"targets": measured,
                                                      "points": [asdict(p) for p in points]}, indent=1))
    return text
