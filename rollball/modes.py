"""The contact's modes and the changes between them (docs/design.md §1), as named values.

A recorded row is in one ``Mode``; a ``Change`` of mode is a transition. Both compare equal to
what they were as bare values (a mode to its position in ``MODES``, a change to its name), so a
trajectory's arrays and files keep their numbers and words.
"""

from __future__ import annotations

import enum

import numpy as np


class Mode(enum.IntEnum):
    """The contact's mode: on the surface without slipping, slipping on it, off it, or still on
    it (resting: its centre does not move; it may still spin in place about the normal)."""

    ROLLING = 0
    SLIDING = 1
    FLYING = 2
    RESTING = 3

    def __str__(self) -> str:
        return self.name.lower()


class Change(str, enum.Enum):
    """A change of mode: rolling turns into sliding (slip), sliding into rolling (grip), the ball
    leaves the surface (liftoff) or comes back to it (landing), or it comes to rest (rest: speed
    and spin 0, and the couples and friction hold it there, docs/design.md §1, "Rest")."""

    SLIP = "slip"
    GRIP = "grip"
    LIFTOFF = "liftoff"
    LANDING = "landing"
    REST = "rest"

    def __str__(self) -> str:
        return self.value


MODES = tuple(str(mode) for mode in Mode)   # the names a CSV writes, at their modes' positions
ROLLING, SLIDING, FLYING, RESTING = Mode
TRANSITION_KINDS = tuple(str(change) for change in Change)
# The mode a change leads to (a landing leads to rolling or sliding, as its impact decides).
AFTER = {Change.SLIP: Mode.SLIDING, Change.GRIP: Mode.ROLLING, Change.LIFTOFF: Mode.FLYING,
         Change.REST: Mode.RESTING}


def interval_modes(codes: np.ndarray) -> np.ndarray:
    """The mode of the motion over each recorded interval (rows i − 1 to i), given at the row i it
    ends in, from the rows' modes ``codes`` (positions in MODES; the first row's is its own): the
    mode of that row, but the row where a moving ball comes to be held (a resting row after one
    that is not, the first of its stay) ends the motion that stopped there, the mode of the row
    before."""
    codes = np.array(codes, dtype=np.int8)
    held = np.flatnonzero((codes[1:] == Mode.RESTING) & (codes[:-1] != Mode.RESTING)) + 1
    codes[held] = codes[held - 1]
    return codes
