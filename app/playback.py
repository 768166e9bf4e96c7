"""What the app has received of a run, and what it derives once per row for drawing.

Rows arrive in chunks from the worker thread, which also derives the contact point's
height (for the trail), the relative energy error and ‖RᵀR − I‖ (for the plots), so the
GUI thread only stores blocks and a frame only looks values up.
"""

from __future__ import annotations

import numpy as np

from rollball import COLUMNS, Trajectory
from rollball.trajectory import CENTER, CONTACT, T

ROW = len(COLUMNS)
EXTRA = 3   # contact height, relative energy error, orthogonality error


class RunBuffer:
    """A growing table of recorded rows plus derived columns."""

    def __init__(self, landscape, mass: float, radius: float, gravity: float, capacity: int = 1024):
        self.landscape = landscape
        self.mass, self.radius, self.gravity = mass, radius, gravity
        # reserved, not touched: memory is paid for as rows arrive, and nothing is copied
        self._data = np.empty((capacity, ROW + EXTRA))
        self.n = 0
        self.e0: float | None = None     # energy of the first row, set by derive
        self.scale = 1.0

    def __len__(self) -> int:
        return self.n

    @property
    def rows(self) -> np.ndarray:
        return self._data[: self.n, :ROW]

    @property
    def t(self) -> np.ndarray:
        return self._data[: self.n, T]

    @property
    def contact_height(self) -> np.ndarray:
        return self._data[: self.n, ROW]

    @property
    def energy_error(self) -> np.ndarray:
        return self._data[: self.n, ROW + 1]

    @property
    def orthogonality_error(self) -> np.ndarray:
        return self._data[: self.n, ROW + 2]

    @property
    def end_time(self) -> float:
        return float(self._data[self.n - 1, T]) if self.n else 0.0

    def derive(self, rows: np.ndarray) -> np.ndarray:
        """Rows with the derived columns appended. Runs in the worker thread, chunk by chunk."""
        part = Trajectory(rows, mass=self.mass, radius=self.radius, gravity=self.gravity)
        if self.e0 is None:
            self.e0, self.scale = float(part.energy[0]), part.energy_scale
        block = np.empty((len(rows), ROW + EXTRA))
        block[:, :ROW] = rows
        block[:, ROW] = self.landscape.height(*rows[:, CONTACT].T)
        block[:, ROW + 1] = (part.energy - self.e0) / self.scale
        block[:, ROW + 2] = part.orthogonality_error()
        return block

    def append(self, block: np.ndarray) -> None:
        """Keep a block made by ``derive`` (GUI thread)."""
        k = len(block)
        if self.n + k > len(self._data):
            grown = np.empty((max(2 * len(self._data), self.n + k, 1024), ROW + EXTRA))
            grown[: self.n] = self._data[: self.n]
            self._data = grown
        self._data[self.n: self.n + k] = block
        self.n += k

    def index_at(self, t: float) -> int:
        """The last row at or before time t (0 when empty)."""
        if self.n == 0:
            return 0
        return max(0, int(np.searchsorted(self.t, t, side="right")) - 1)

    def trail(self, index: int, max_points: int = 20_000, lift: float = 0.0) -> np.ndarray:
        """Contact points of rows 0..index (thinned to about max_points), raised along the
        normal by ``lift`` times the radius: the drawn surface, flat between its grid points,
        lies above the true one in valleys, and would hide a trail drawn on the true one."""
        stride = max(1, -(-(index + 1) // max_points))
        picked = np.r_[np.arange(0, index + 1, stride), index] if self.n else np.zeros(0, dtype=int)
        points = np.empty((len(picked), 3))
        points[:, :2] = self._data[picked, CONTACT]
        points[:, 2] = self._data[picked, ROW]
        return points + lift * (self._data[picked, CENTER] - points)

    def point_at(self, t: float) -> np.ndarray:
        """The contact point at time t, interpolated between recorded rows."""
        i = self.index_at(t)
        j = min(i + 1, self.n - 1)
        t0, t1 = self._data[i, T], self._data[j, T]
        w = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
        x, y = (1 - w) * self._data[i, CONTACT] + w * self._data[j, CONTACT]
        return np.array([x, y, float(self.landscape.height(x, y))])
