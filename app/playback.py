"""What the app has received of a run, and what it derives once per row for drawing.

Rows arrive in chunks from the worker thread, which also derives the contact point's
height (for the trail), the relative energy error (what friction and landings dissipated
counted as accounted for) and ‖RᵀR − I‖ (for the plots), and takes each row's contact mode
(rolling, sliding, flying), slip speed and energy dissipated from the run, so the GUI thread
only stores blocks and a frame only looks values up.
"""

from __future__ import annotations

import numpy as np

from rollball import Trajectory
from rollball.kernel.interface import ROW_SIZE
from rollball.trajectory import CENTER, CONTACT, FLYING, T

ROW = ROW_SIZE   # a recorded row as the run hands it over
# the derived columns after it
HEIGHT, ENERGY_ERROR, ORTHOGONALITY, MODE, SLIP, DISSIPATED = range(ROW, ROW + 6)
EXTRA = 6


class RunBuffer:
    """A growing table of recorded rows plus derived columns."""

    def __init__(self, landscape, mass: float, radius: float, gravity: float, capacity: int = 1024,
                 modes=None):
        """``modes()``: the run's mode code of every row so far (``Simulation.modes``), called in
        the worker thread as each chunk is derived; None: every row rolls."""
        self.landscape = landscape
        self.modes = modes
        self._derived = 0   # rows derived so far (worker thread)
        self.mass, self.radius, self.gravity = mass, radius, gravity
        # reserved, not touched: memory is paid for as rows arrive, and nothing is copied
        self._data = np.empty((capacity, ROW + EXTRA))
        self.n = 0
        self.e0: float | None = None     # energy (and dissipated) of the first row, set by derive
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
    def energy_error(self) -> np.ndarray:
        return self._data[: self.n, ENERGY_ERROR]

    @property
    def orthogonality_error(self) -> np.ndarray:
        return self._data[: self.n, ORTHOGONALITY]

    @property
    def mode(self) -> np.ndarray:
        """Each row's mode, as its position in ``trajectory.MODES`` (int)."""
        return self._data[: self.n, MODE].astype(np.int8)

    @property
    def slip_speed(self) -> np.ndarray:
        return self._data[: self.n, SLIP]

    @property
    def dissipated(self) -> np.ndarray:
        return self._data[: self.n, DISSIPATED]

    @property
    def end_time(self) -> float:
        return float(self._data[self.n - 1, T]) if self.n else 0.0

    def derive(self, rows: np.ndarray) -> np.ndarray:
        """Rows with the derived columns appended. Runs in the worker thread, chunk by chunk."""
        part = Trajectory(rows, mass=self.mass, radius=self.radius, gravity=self.gravity)
        total = part.energy + part.dissipated   # what friction and landings took, accounted for
        if self.e0 is None:
            self.e0, self.scale = float(total[0]), part.energy_scale
        block = np.empty((len(rows), ROW + EXTRA))
        block[:, :ROW] = rows
        block[:, HEIGHT] = self.landscape.height(*rows[:, CONTACT].T)
        block[:, ENERGY_ERROR] = (total - self.e0) / self.scale
        block[:, ORTHOGONALITY] = part.orthogonality_error()
        first, self._derived = self._derived, self._derived + len(rows)
        codes = self.modes() if self.modes is not None else None
        block[:, MODE] = 0 if codes is None or len(codes) < self._derived else codes[first: self._derived]
        block[:, SLIP] = part.slip_speed
        block[:, DISSIPATED] = part.dissipated
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

    def trail_rows(self, index: int, max_points: int = 20_000) -> np.ndarray:
        """The rows of 0..index a trail is drawn through (thinned to about max_points)."""
        stride = max(1, -(-(index + 1) // max_points))
        return np.r_[np.arange(0, index + 1, stride), index] if self.n else np.zeros(0, dtype=int)

    def trail(self, index: int, max_points: int = 20_000, lift: float = 0.0, picked=None) -> np.ndarray:
        """Contact points of rows 0..index (thinned to about max_points; or the rows
        ``picked``), raised along the normal by ``lift`` times the radius: the drawn surface,
        flat between its grid points, lies above the true one in valleys, and would hide a
        trail drawn on the true one. In flight the trail goes through the ball's point nearest
        the surface (raised the same way): the lowest point of the ball's path, which is the
        contact point where it touches."""
        if picked is None:
            picked = self.trail_rows(index, max_points)
        points = np.empty((len(picked), 3))
        points[:, :2] = self._data[picked, CONTACT]
        points[:, 2] = self._data[picked, HEIGHT]
        center = self._data[picked, CENTER]
        trail = points + lift * (center - points)
        flying = self._data[picked, MODE] == FLYING
        if flying.any():
            away = center[flying] - points[flying]   # from the centre's nearest surface point
            length = np.linalg.norm(away, axis=1, keepdims=True)
            with np.errstate(invalid="ignore", divide="ignore"):
                unit = np.where(length > 0, away / length, [0.0, 0.0, 1.0])
            trail[flying] = center[flying] - (1.0 - lift) * self.radius * unit
        return trail

    def point_at(self, t: float) -> np.ndarray:
        """The contact point at time t, interpolated between recorded rows."""
        i = self.index_at(t)
        j = min(i + 1, self.n - 1)
        t0, t1 = self._data[i, T], self._data[j, T]
        w = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
        x, y = (1 - w) * self._data[i, CONTACT] + w * self._data[j, CONTACT]
        return np.array([x, y, float(self.landscape.height(x, y))])

    def mode_of(self, i: int) -> int:
        """Row i's mode (its position in ``trajectory.MODES``)."""
        return int(self._data[i, MODE])
