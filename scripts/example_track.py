"""Write resources/examples/billiard_track.csv: a synthetic measured track for the billiard example.

Not a measurement: the exact motion of a billiard shot (closed form, tests/exact_tracks.py) with
μ = 0.25 and v₀ = 2.2 m/s, where the billiard example's scene has 0.2 and 2.0, seen from above at
60 frames a second for 1.2 s, with Gaussian noise of 1 mm on x and y (seed 33) and three frames
where the ball was not found. ``rollball fit billiard billiard_track.csv --fit
contact.friction,start.vx`` finds the values back. Run from the checkout's root:
``python scripts/example_track.py``.
"""

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from exact_tracks import billiard, noisy  # noqa: E402 (tests/ is on the path only from here)

from rollball.files import atomic_write_text  # noqa: E402 (the checkout's, ahead of an installed one)

MU, V0, SIGMA, SEED, FPS, SECONDS = 0.25, 2.2, 1e-3, 33, 60, 1.2
LOST = (17, 18, 40)   # frames where the ball was not found: written as empty cells


def main() -> None:
    times = np.arange(1, round(FPS * SECONDS) + 1) / FPS
    track = noisy(times, billiard(times, MU, V0), ("x", "y"), SIGMA, SEED)
    lines = track.to_text((
        f"Synthetic, not a measurement: the billiard example's shot in closed form with mu = {MU} and v0 = {V0} m/s,",
        (f"seen from above at {FPS} frames/s, with Gaussian noise of {SIGMA * 1000:g} mm "
         f"(seed {SEED}); frames {', '.join(map(str, LOST))} lost."),
        "Made by scripts/example_track.py; "
        "try: rollball fit billiard billiard_track.csv --fit contact.friction,start.vx",
    )).splitlines()
    header = sum(line.startswith("#") for line in lines) + 1
    for frame in LOST:
        lines[header + frame] = lines[header + frame].split(",")[0] + ",,"
    atomic_write_text(ROOT / "resources" / "examples" / "billiard_track.csv", "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
