"""How long the landing search takes per flight on the examples that fly: each example is run
(its own method and step) with ``Flight.landing`` and ``Flight.gap`` counted and timed, with the
kernel's search (``kernel.landing``) and with flight.py's own (``Flight.compiled`` off), which
takes the same looks; prints flights, gap evaluations per flight (counted on flight.py's) and CPU
ms per flight of each (the median of ROUNDS runs, the two in turn).

    python docs/flight_timing.py
"""

from __future__ import annotations

import statistics
import sys
import time

from rollball import flight
from rollball.examples import example_scenes
from rollball.simulation import Simulation

EXAMPLES = ("liftoff", "cylinder", "bump", "ridge_jump", "billiard")
ROUNDS = 5


def measure(scene, compiled: bool = True) -> tuple[int, int, float]:
    """Flights, gap evaluations (flight.py's: none are counted in the kernel) and CPU seconds spent
    finding landings in one run of ``scene``."""
    counts, spent = [0, 0], [0.0]
    landing, gap = flight.Flight.landing, flight.Flight.gap
    many = getattr(flight.Flight, "gaps", None)   # (looks taken together, where the search has them)

    def timed_landing(self, *args, **kwargs):
        counts[0] += 1
        start = time.process_time()
        try:
            return landing(self, *args, **kwargs)
        finally:
            spent[0] += time.process_time() - start

    def counted_gap(self, *args, **kwargs):
        counts[1] += 1
        return gap(self, *args, **kwargs)

    def counted_gaps(self, times, *args, **kwargs):
        counts[1] += len(times)
        return many(self, times, *args, **kwargs)

    flight.Flight.landing, flight.Flight.gap = timed_landing, counted_gap
    flight.Flight.compiled = compiled
    if many is not None:
        flight.Flight.gaps = counted_gaps
    try:
        run = Simulation(scene)
        run.judge_energy = False
        run.advance()
    finally:
        flight.Flight.landing, flight.Flight.gap = landing, gap
        flight.Flight.compiled = True
        if many is not None:
            flight.Flight.gaps = many
    return counts[0], counts[1], spent[0]


def main() -> None:
    scenes = {path.stem: scene for path, scene in example_scenes()}
    for name in EXAMPLES:
        measure(scenes[name]), measure(scenes[name], compiled=False)   # (compiled, warm)
        pairs = [(measure(scenes[name]), measure(scenes[name], compiled=False)) for _ in range(ROUNDS)]
        flights, gaps = pairs[0][1][:2]
        if not flights:
            print(f"{name:11s} no flight")
            continue
        kernel, own = (statistics.median(run[k][2] for run in pairs) * 1e3 / flights for k in (0, 1))
        print(f"{name:11s} {flights:3d} flights  {gaps / flights:6.1f} gaps looked at  {kernel:6.2f} ms per flight "
              f"(flight.py's own search: {own:6.2f} ms)")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
