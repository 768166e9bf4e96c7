"""How big a run may be: its fixed steps, counted exactly, and the rows it holds."""

from __future__ import annotations

import math

MAX_STEPS = 2 ** 53    # beyond this, step counts and k·dt are no longer exact in a double
# kernel.ROW_SIZE (28) doubles a row: 1.1 GB at the limit, handed to the trajectory without a
# copy. A run recording every adaptive step grows its buffer by doubling up to the limit,
# holding the old and the new buffer for a moment (1.7 GB at the last doubling).
MAX_ROWS = 5_000_000


def step_count(dt: float, t_end: float) -> int:
    """Steps of size dt to reach t_end; the last one is shortened when dt does not divide t_end.
    Raises ``ValueError`` when there would be more than ``MAX_STEPS``."""
    q = t_end / dt
    if not q <= MAX_STEPS:  # also an overflow to inf
        raise ValueError(f"t_end / dt = {q:.3g} steps is too many (at most {MAX_STEPS:.3g}): "
                         f"use a larger dt or a shorter t_end")
    n = round(q)
    if n >= 1 and abs(q - n) <= 1e-9 * q:
        return n
    return max(1, math.ceil(q))
