"""The landscape's local minima over the scene's view square, and the basin a point belongs to.

A sweep's ``basin`` outcome says in which well a ball came to rest (docs/design.md §13). The
minima are found on the compiled landscape: a grid of ``GRID_POINTS`` × ``GRID_POINTS`` heights
over [view.min, view.max]², each grid point no higher than its eight neighbours a seed, Newton's
method on ∇f = 0 from each seed, a point kept where it converged inside the square with a
positive-definite Hessian (f_xx > 0, f_xx f_yy − f_xy² > 0: a strict local minimum; a flat
bottom, as of x⁴ or a ring, has none), and points closer than ``MERGE`` × the square's side taken
as one. They are numbered 1..K by height, the lowest first (equal heights: by x, then y).

A point's basin is the minimum its steepest descent on f reaches: the curve along −∇f, followed
in steps of ``DESCENT_STEP`` × the grid's spacing (the midpoint rule along the unit direction),
finished by Newton's steps once they are shorter than that and the Hessian is positive definite.
A point whose descent leaves the square, stops on a flat or does not arrive is in basin 0. A
resting ball is not at its minimum in general (rolling resistance holds it on a slope with
tan θ ≤ c_rr), hence the descent rather than the nearest minimum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

GRID_POINTS = 401        # heights per side of the view square searched for minima
NEWTON_STEPS = 40        # Newton's steps from a seed (it converges in a handful)
CONVERGED = 1e-11        # a Newton step this small (× the square's side): converged
MERGE = 1e-6             # minima closer than this (× the square's side) are one
DESCENT_STEP = 0.25      # the descent's step, a share of the grid's spacing
DESCENT_LENGTH = 8.0     # longest descent followed, in sides of the square


@dataclass(frozen=True)
class Minimum:
    """A strict local minimum of the landscape: its number (1 the lowest), where it is, its height."""

    number: int
    x: float
    y: float
    f: float

    def to_dict(self) -> dict:
        return {"number": self.number, "x": self.x, "y": self.y, "f": self.f}


class Basins:
    """The minima of a landscape over the square [lo, hi]², and the basin of any point in it.

    ``landscape``: a ``Landscape`` (its compiled code is used); ``values``: its parameters' values.
    """

    def __init__(self, landscape, values=(), lo: float = -3.0, hi: float = 3.0, points: int = GRID_POINTS):
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"the square of the minima needs finite lo < hi, not {lo!r}, {hi!r}")
        if points < 3:
            raise ValueError(f"the grid of the minima needs 3 points a side or more, not {points}")
        self.landscape, self.values = landscape, tuple(float(v) for v in values)
        self.lo, self.hi, self.points = float(lo), float(hi), int(points)
        self.side = self.hi - self.lo
        self.spacing = self.side / (self.points - 1)
        self.minima = self._find()

    @classmethod
    def of(cls, scene) -> "Basins":
        """The minima of a scene's landscape (its parameters' values) over its view square."""
        from .landscape import landscape_of

        return cls(landscape_of(scene), scene.parameter_values, scene.view.min, scene.view.max)

    # -- minima ------------------------------------------------------------------------------

    def _derivatives(self, p: np.ndarray) -> np.ndarray:
        """f, f_x, f_y, f_xx, f_xy, f_yy at the points p (n, 2): shape (6, n)."""
        return self.landscape.evaluate(p[:, 0], p[:, 1], self.values)

    @staticmethod
    def _newton_step(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The Newton step on ∇f = 0 at each point (n, 2), and whether the Hessian there is
        positive definite."""
        fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
        det = fxx * fyy - fxy * fxy
        with np.errstate(all="ignore"):
            step = np.stack([-(fyy * fx - fxy * fy) / det, -(fxx * fy - fxy * fx) / det], axis=1)
        return step, (fxx > 0) & (det > 0)

    def _inside(self, p: np.ndarray) -> np.ndarray:
        return np.all((p >= self.lo) & (p <= self.hi), axis=1)

    def _seeds(self) -> np.ndarray:
        """The grid points no higher than any of their eight neighbours (outside the square: +∞)."""
        axis = np.linspace(self.lo, self.hi, self.points)
        x, y = np.meshgrid(axis, axis, indexing="ij")
        f = self.landscape.evaluate(x, y, self.values)[0]
        padded = np.pad(f, 1, constant_values=np.inf)
        lowest = np.isfinite(f)
        n = self.points
        for i in (0, 1, 2):
            for j in (0, 1, 2):
                if (i, j) != (1, 1):
                    lowest &= f <= padded[i:i + n, j:j + n]
        return np.stack([x[lowest], y[lowest]], axis=1)

    def _find(self) -> tuple[Minimum, ...]:
        p = self._seeds()
        step = np.zeros_like(p)
        for _ in range(NEWTON_STEPS):
            if not len(p):
                break
            step, _ = self._newton_step(self._derivatives(p))
            p = p + step
        d = self._derivatives(p)
        _, definite = self._newton_step(d)
        with np.errstate(invalid="ignore"):
            ok = (definite & self._inside(p) & np.all(np.isfinite(p), axis=1)
                  & (np.linalg.norm(step, axis=1) <= CONVERGED * self.side))
        found = sorted(zip(d[0][ok], p[ok, 0], p[ok, 1]))
        kept: list[tuple[float, float, float]] = []
        for f, x, y in found:   # the lowest first: a duplicate is dropped for the one kept
            if all(math.hypot(x - kx, y - ky) > MERGE * self.side for _, kx, ky in kept):
                kept.append((float(f), float(x), float(y)))
        return tuple(Minimum(k + 1, x, y, f) for k, (f, x, y) in enumerate(kept))

    # -- basins ------------------------------------------------------------------------------

    def basin(self, x, y) -> np.ndarray:
        """The number of the minimum each point's steepest descent reaches (float array as x):
        0 where it leaves the square, stops or arrives nowhere, NaN where x or y is NaN."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        shape = x.shape
        p = np.stack([x.ravel(), y.ravel()], axis=1)
        result = np.where(np.isnan(p).any(axis=1), np.nan, 0.0)
        active = np.flatnonzero(~np.isnan(p).any(axis=1) & self._inside(p)) if self.minima else np.array([], int)
        h = DESCENT_STEP * self.spacing
        centres = np.array([[m.x, m.y] for m in self.minima]).reshape(-1, 2)
        for _ in range(math.ceil(DESCENT_LENGTH * self.side / h)):
            if not len(active):
                break
            q = p[active]
            d = self._derivatives(q)
            newton, definite = self._newton_step(d)
            length = np.linalg.norm(newton, axis=1)
            arrived = definite & (length <= CONVERGED * self.side)
            if arrived.any():
                distance = np.linalg.norm(q[arrived, None, :] - centres[None, :, :], axis=2)
                nearest = np.argmin(distance, axis=1)
                close = distance[np.arange(len(nearest)), nearest] <= MERGE * self.side
                result[active[arrived]] = np.where(close, nearest + 1.0, 0.0)
            by_newton = definite & (length <= h) & ~arrived
            downhill = ~definite | (length > h)
            q_next = q.copy()
            q_next[by_newton] = q[by_newton] + newton[by_newton]
            q_next[downhill] = self._descend(q[downhill], d[:, downhill], h)
            p[active] = q_next
            moving = ~arrived & np.all(np.isfinite(q_next), axis=1) & self._inside(q_next)
            active = active[moving]
        return result.reshape(shape)

    def _descend(self, q: np.ndarray, d: np.ndarray, h: float) -> np.ndarray:
        """A step of length h along the steepest descent (the midpoint rule on the unit direction
        −∇f/|∇f|); NaN where the slope is 0 (a flat: the descent stops there)."""
        def direction(g):
            with np.errstate(all="ignore"):
                norm = np.hypot(g[0], g[1])
                return np.stack([-g[0] / norm, -g[1] / norm], axis=1) * np.where(norm > 0, 1.0, np.nan)[:, None]

        mid = q + 0.5 * h * direction(d[1:3])
        return q + h * direction(self._derivatives(mid)[1:3])
