"""The basin map of the README and docs/reference/sweeps.md: the ``wells`` example (three wells in
a shallow bowl, a little rolling resistance) swept over the start position, balls released at rest,
each run coloured by the well it comes to rest in.

Run from the repository's root (a few minutes on 2 shared cores):

    .venv/bin/python docs/sweep_basins.py          # writes docs/sweep_basins.png, .json and .md

It runs the sweep the manual's command runs (``rollball sweep wells --vary start.x=-2.5:2.5:121 --vary
start.y=-2.5:2.5:121 --color basin``) on every core, then the same sweep again on a Dask cluster of one
worker process per core on this machine, and checks that the two tables are equal to the last bit.
It keeps the map, and sweep.json with what the manual quotes (sweep_basins.json's ``summary``:
how many runs rest, in which well, how soon, the wall times, whether Dask's table is the same);
sweep_basins.md says the same in words. The CSV is left out.
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
from rollball.sweeps.runner import local_workers  # noqa: E402

N = 121
VARY = {"start.x": np.linspace(-2.5, 2.5, N), "start.y": np.linspace(-2.5, 2.5, N)}
OUTPUTS = ("sweep_basins.png", "sweep_basins.json", "sweep_basins.md")


def on_dask(scene, vary, workers: int):
    """The sweep on a Dask cluster of ``workers`` processes of one thread each, on this machine."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=":0", worker_dashboard_address=":0") as cluster:
        return sweep(scene, vary, scheduler=cluster.scheduler_address)


def summary(table, remote) -> dict:
    ok = table["status"] == "ok"
    rested = ok & np.isfinite(table["rest_time"])
    basins, counts = np.unique(table["basin"][rested], return_counts=True)
    rest_time = table["rest_time"][rested]
    return {
        "runs": len(table), "status": table.counts(), "rested": int(np.count_nonzero(rested)),
        "minima": [m.to_dict() for m in table.minima or ()],
        "basins": {str(int(b)): int(n) for b, n in zip(basins, counts)},
        "rest_time": {"min": float(np.min(rest_time)), "median": float(np.median(rest_time)),
                      "max": float(np.max(rest_time))} if rested.any() else None,
        "seconds": table.seconds, "workers": table.workers,
        "local": "worker processes" if table.processes else "threads",
        "runs_per_second": len(table) / table.seconds,
        "dask_seconds": remote.seconds, "dask_workers": remote.workers,
        "dask_same_table": bool(np.array_equal(table.codes, remote.codes)
                                and np.array_equal(table.outcomes, remote.outcomes, equal_nan=True)
                                and table.minima == remote.minima),
    }


def markdown(s: dict) -> str:
    lines = ["# The basin map's outcomes (docs/sweep_basins.py)", "",
             f"- runs: {s['runs']:,}; status: " + ", ".join(f"{k} {v:,}" for k, v in s["status"].items() if v),
             f"- come to rest: {s['rested']:,} runs, between {s['rest_time']['min']:.2f} and "
             f"{s['rest_time']['max']:.2f} s (median {s['rest_time']['median']:.2f} s)",
             "- the minima: " + "; ".join(f"{m['number']} at ({m['x']:.4f}, {m['y']:.4f}), f = {m['f']:.4f}"
                                          for m in s["minima"]),
             "- runs per basin: " + ", ".join(f"{b}: {n:,}" for b, n in s["basins"].items()),
             f"- wall time {s['seconds']:.1f} s on {s['workers']} local {s['local']} "
             f"({s['runs_per_second']:.0f} runs/s); "
             f"on Dask ({s['dask_workers']} worker processes on this machine) {s['dask_seconds']:.1f} s, "
             f"{'the same table to the last bit' if s['dask_same_table'] else 'A DIFFERENT TABLE'}"]
    return "\n".join(lines) + "\n"


def main() -> None:
    docs = ROOT / "docs"
    check_outputs(docs, OUTPUTS)   # (before the sweeps' minutes: each file can be written)
    scene = Scene.load(scene_path("wells"))
    started = time.perf_counter()
    table = sweep(scene, VARY)
    print(f"{len(table):,} runs in {time.perf_counter() - started:.1f} s on {table.workers} "
          f"{'worker processes' if table.processes else 'threads'}", file=sys.stderr)
    remote = on_dask(scene, VARY, local_workers())
    print(f"the same on Dask in {remote.seconds:.1f} s", file=sys.stderr)
    s = summary(table, remote)
    with tempfile.TemporaryDirectory() as folder:
        table.save(folder, color="basin")
        made = Path(folder)
        info = {**json.loads((made / "sweep.json").read_text(encoding="utf-8")), "summary": s}
        # the three together or none; if that fails, the new ones are kept beside them
        replace_together(docs, {"sweep_basins.png": (made / "sweep.png").read_bytes(),
                                "sweep_basins.json": json.dumps(info, indent=2, allow_nan=False) + "\n",
                                "sweep_basins.md": markdown(s)}, kept_name="sweep_basins-unsaved")
    print(markdown(s))


if __name__ == "__main__":
    main()
