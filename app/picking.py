"""Where the mouse points in the 3-D view: the ray under a pixel, where it meets the drawn
surface or a plane, and where a point lands on screen. Plain numpy, no widgets: the view
hands over its matrices and its surface's heights.

The start point is dragged over the surface (the ray's first crossing of the drawn surface,
found on samples along the ray and refined by bisection), the start velocity's arrow in the
tangent plane at the ball's centre (the arrow is the centre's velocity, tangent to the surface).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

SAMPLES = 600        # points tried along the ray across the grid
BISECTIONS = 40      # halvings of the bracket around the crossing


def mouse_ray(matrix: np.ndarray, x: float, y: float, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """(origin, unit direction) of the ray under pixel (x, y) of a view ``width`` × ``height``
    whose projection times view matrix is ``matrix`` (4 × 4, acting on column vectors)."""
    nx, ny = 2.0 * x / width - 1.0, 1.0 - 2.0 * y / height
    inverse = np.linalg.inv(matrix)
    near, far = inverse @ np.array([nx, ny, -1.0, 1.0]), inverse @ np.array([nx, ny, 1.0, 1.0])
    near, far = near[:3] / near[3], far[:3] / far[3]
    direction = far - near
    return near, direction / np.linalg.norm(direction)


def on_screen(matrix: np.ndarray, point: np.ndarray, width: float, height: float) -> np.ndarray | None:
    """The pixel (x, y) where ``point`` is drawn, or None behind the camera."""
    p = matrix @ np.array([*point, 1.0])
    if p[3] <= 0:
        return None
    return np.array([(p[0] / p[3] + 1.0) * width / 2, (1.0 - p[1] / p[3]) * height / 2])


def _square(origin: np.ndarray, direction: np.ndarray, lo: float, hi: float) -> tuple[float, float] | None:
    """The ray's parameters where it is above the square [lo, hi]² (None if never)."""
    t0, t1 = 0.0, np.inf
    for k in (0, 1):
        if abs(direction[k]) < 1e-15:
            if not lo <= origin[k] <= hi:
                return None
            continue
        a, b = (lo - origin[k]) / direction[k], (hi - origin[k]) / direction[k]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    return (t0, t1) if t0 < t1 else None


def ray_surface(origin: np.ndarray, direction: np.ndarray, height: Callable, lo: float,
                hi: float) -> np.ndarray | None:
    """The first point where the ray crosses the surface z = height(x, y) over the square
    [lo, hi]² (``height`` vectorised, -inf where nothing is drawn), or None if it misses."""
    span = _square(origin, direction, lo, hi)
    if span is None:
        return None
    t = np.linspace(*span, SAMPLES)

    def above(s):
        p = origin + np.multiply.outer(s, direction)
        return p[..., 2] - height(p[..., 0], p[..., 1])
    side = above(t) > 0      # the surface is a sheet: the ray may pass under its edge
    crossed = np.flatnonzero(side[1:] != side[:-1])
    if not len(crossed):
        return None
    k = crossed[0] + 1
    a, b = t[k - 1], t[k]    # on one side at a, on the other at b
    for _ in range(BISECTIONS):
        m = 0.5 * (a + b)
        if (above(np.array([m]))[0] > 0) == side[k - 1]:
            a = m
        else:
            b = m
    return origin + b * direction


def ray_plane(origin: np.ndarray, direction: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray | None:
    """Where the ray meets the plane through ``point`` with ``normal`` (None: parallel or behind)."""
    across = float(direction @ normal)
    if abs(across) < 1e-9:
        return None
    t = float((point - origin) @ normal) / across
    return origin + t * direction if t > 0 else None


def rounded(value: float, resolution: float) -> float:
    """``value`` to the decimals that ``resolution`` needs (a dragged value reads as a plain
    number: 0.437, not 0.43712873)."""
    digits = max(0, int(np.ceil(-np.log10(resolution)))) if resolution > 0 else 6
    return float(round(value, digits)) + 0.0   # no -0.0
