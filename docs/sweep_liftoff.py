"""The lift-off map of docs/reference/sweeps.md: the ``liftoff`` example (it flies after its lift-off and lands)
swept over start speed × spin, 400 × 300 = 120 000 runs of 1 s at rk4, dt = 1e-3.

Run from the repository's root (a quarter of an hour or more on 2 shared cores):

    .venv/bin/python docs/sweep_liftoff.py          # writes docs/sweep_liftoff.png, .json and .md

It runs the sweep the manual's command runs (``rollball sweep liftoff --vary start.vx=3:8:400
--vary start.spin=-4:4:300``), on every core, and keeps the map (coloured by the first
lift-off's time) and sweep.json beside it; the CSV (some 30 MB) is left out. sweep_liftoff.md
holds what the manual quotes about the outcomes: how many runs lift off, land, and in which
mode they end, the lowest speed that lifts off, whether the spin changes any outcome, and the
wall time and rate.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))   # this checkout's rollball, whatever is installed (hence E402 below)

from rollball import Scene, sweep  # noqa: E402
from rollball.examples import scene_path  # noqa: E402
from rollball.files import check_outputs, replace_together  # noqa: E402
from rollball.trajectory import MODES  # noqa: E402

VARY = {"start.vx": np.linspace(3.0, 8.0, 400), "start.spin": np.linspace(-4.0, 4.0, 300)}


def summary(table) -> dict:
    ok = table["status"] == "ok"
    lifts = ok & np.isfinite(table["liftoff_time"])
    vx, spin = table["start.vx"], table["start.spin"]
    n_vx, n_spin = (len(values) for values in VARY.values())
    by_spin = {name: table[name].reshape(n_vx, n_spin) for name in
               ("liftoff_time", "landings", "end_mode", "x_end", "t_reached")}
    # the outcomes that do not depend on the spin: equal, to the last bit, across each row of the grid
    spin_free = {name: bool(np.all([np.array_equal(row, np.full_like(row, row[0]), equal_nan=True)
                                    for row in values]))
                 for name, values in by_spin.items()}
    modes, counts = np.unique(table["end_mode"][ok], return_counts=True)
    landings, landing_counts = np.unique(table["landings"][ok], return_counts=True)
    return {
        "runs": len(table), "status": table.counts(),
        "lift_off": int(np.count_nonzero(lifts)),
        "slowest_lifting_off": float(np.min(vx[lifts])) if lifts.any() else None,
        "fastest_staying_on": float(np.max(vx[ok & ~lifts])) if (ok & ~lifts).any() else None,
        "liftoff_time_range": [float(np.min(table["liftoff_time"][lifts])),
                               float(np.max(table["liftoff_time"][lifts]))] if lifts.any() else None,
        "end_modes": {str(mode): int(count) for mode, count in zip(modes, counts)},
        "landings": {str(int(n)): int(count) for n, count in zip(landings, landing_counts)},
        "same_for_every_spin": spin_free,
        "spin_values": [float(np.min(spin)), float(np.max(spin))],
        "seconds": table.seconds, "workers": table.workers,
        "runs_per_second": len(table) / table.seconds,
    }


def markdown(s: dict) -> str:
    lines = ["# The lift-off map's outcomes (docs/sweep_liftoff.py)", "",
             f"- runs: {s['runs']:,}; status: " + ", ".join(f"{k} {v:,}" for k, v in s["status"].items() if v),
             f"- lift off: {s['lift_off']:,} runs; the slowest start that lifts off {s['slowest_lifting_off']!r} m/s, "
             f"the fastest that stays on {s['fastest_staying_on']!r} m/s",
             f"- first lift-off between {s['liftoff_time_range'][0]:.6f} and {s['liftoff_time_range'][1]:.6f} s",
             "- landings: " + ", ".join(f"{n} in {count:,} runs" for n, count in s["landings"].items()),
             "- mode at the end: "
             + ", ".join(f"{MODES[int(float(m))]} {count:,}" for m, count in s["end_modes"].items()),
             "- the same for every spin, to the last bit: "
             + ", ".join(f"{name} {'yes' if same else 'no'}" for name, same in s["same_for_every_spin"].items()),
             f"- wall time {s['seconds']:.1f} s on {s['workers']} threads ({s['runs_per_second']:.0f} runs/s)"]
    return "\n".join(lines) + "\n"


OUTPUTS = ("sweep_liftoff.png", "sweep_liftoff.json", "sweep_liftoff.md")


def main() -> None:
    docs = ROOT / "docs"
    check_outputs(docs, OUTPUTS)   # (before the sweep's forty minutes: each file can be written)
    scene = Scene.load(scene_path("liftoff"))
    started = time.perf_counter()
    table = sweep(scene, VARY)
    print(f"{len(table):,} runs in {time.perf_counter() - started:.1f} s", file=sys.stderr)
    s = summary(table)
    with tempfile.TemporaryDirectory() as folder:
        table.save(folder)
        made = Path(folder)
        # the three together or none; if that fails, the new ones are kept beside them
        replace_together(docs, {"sweep_liftoff.png": (made / "sweep.png").read_bytes(),
                                "sweep_liftoff.json": (made / "sweep.json").read_text(encoding="utf-8"),
                                "sweep_liftoff.md": markdown(s)}, kept_name="sweep_liftoff-unsaved")
    print(json.dumps(s, indent=1))
    print(markdown(s))


if __name__ == "__main__":
    main()
