"""``rollball bench``: the speed targets and the work-precision report.

``run`` measures (see ``targets`` and ``workprecision``, which runs ``rollball.compare`` on
each scene) and writes ``bench.md``, ``bench.png`` and ``bench.json``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

from ..files import atomic_write_bytes, atomic_write_text
from . import report, targets, workprecision


@dataclass(frozen=True)
class Config:
    scenes: tuple[str, ...]        # example scene names
    t_end: float | None            # None: each scene's own duration
    quick: bool                    # shorter ladders, fewer tolerances and repeats
    targets: bool = True           # also measure the speed targets


FULL = Config(("hills", "bowl", "saddle"), None, quick=False)
QUICK = Config(("hills", "bowl", "saddle"), 2.0, quick=True)


def run(out: Path, config: Config = FULL, log=print) -> str:
    """Measure, write bench.md / bench.png / bench.json into ``out`` and return the Markdown."""
    out.mkdir(parents=True, exist_ok=True)
    measured = None
    if config.targets:
        log("speed targets ...")
        measured = targets.measure(config.quick)
    log("work against precision ...")
    results = workprecision.measure(list(config.scenes), config.t_end, config.quick, log)
    text = report.markdown(measured, results, config.t_end, config.quick) + "\n![work-precision](bench.png)\n"
    image = report.figure(results)
    scenes = {r.name: {**r.comparison.to_dict(), "scipy_dop853": [asdict(b) for b in r.scipy]} for r in results}
    atomic_write_bytes(out / "bench.png", image)
    atomic_write_text(out / "bench.md", text)
    atomic_write_text(out / "bench.json", json.dumps({"targets": measured, "scenes": scenes}, indent=1,
                                                     allow_nan=False))
    return text
