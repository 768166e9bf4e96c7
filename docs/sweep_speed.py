"""Runs per second of sweeps over contact scenes (the figures of docs/reference/sweeps.md), one thread.

Run from the repository's root (a minute or two):

    .venv/bin/python docs/sweep_speed.py            # prints a table (markdown)

Two sweeps over the start speed, each run through ``Simulation`` (sweeps/batch.run_one):
``liftoff`` from 4.5 to 6 m/s (every run lifts off, flies and lands once; 1 s at rk4, dt 1e-3) and
``billiard`` from 0.5 to 4 m/s (every run slides, then grips and rolls; 2 s). Each is timed
REPEATS times with ``workers=1`` after one small warm-up sweep; the table gives the median of the
wall-clock rate and of the rate per CPU second of this process (which counts only the work
done for it, so it varies less on a shared machine). With ``PYTHONPATH`` pointing at another
checkout it measures that code instead (the figures before a change).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from rollball import Scene, sweep
from rollball.examples import scene_path

SWEEPS = (("liftoff", "start.vx", 4.5, 6.0, 200), ("billiard", "start.vx", 0.5, 4.0, 400))
REPEATS = 5


def rates(name: str, key: str, lo: float, hi: float, runs: int) -> tuple[float, float, dict]:
    scene = Scene.load(scene_path(name))
    sweep(scene, {key: np.linspace(lo, hi, 4)}, workers=1)   # warm-up: the landscape compiled
    wall, cpu = [], []
    for _ in range(REPEATS):
        started, used = time.perf_counter(), time.process_time()
        table = sweep(scene, {key: np.linspace(lo, hi, runs)}, workers=1)
        wall.append(runs / (time.perf_counter() - started))
        cpu.append(runs / (time.process_time() - used))
    landings = int(np.nansum(table["landings"]))
    return statistics.median(wall), statistics.median(cpu), {"landings": landings, "status": table.counts()}


def main() -> None:
    print(f"| sweep | runs | runs/s (wall, median of {REPEATS}) | runs per CPU second | landings |")
    print("|---|---:|---:|---:|---:|")
    for name, key, lo, hi, runs in SWEEPS:
        wall, cpu, facts = rates(name, key, lo, hi, runs)
        print(f"| {name}, {key} {lo:g}…{hi:g} | {runs} | {wall:.0f} | {cpu:.0f} | {facts['landings']} |")


if __name__ == "__main__":
    main()
