"""Exact motions of the ball's centre, in closed form, for the tests of measured tracks and fits,
and synthetic tracks made from them with Gaussian noise.

- a billiard shot on a flat table z = 0 (docs/design.md "Sliding"): struck at speed v₀ along x
  without spin, the ball slides with deceleration μ g until t* = 2 v₀ / (7 μ g), then rolls at
  (5/7) v₀; its centre stays at height r.
- rolling on an inclined plane z = −a x: the centre accelerates at (5/7) g sin θ down the slope,
  c̈ = (5/7) g a / (1 + a²) · (1, 0, −a); it starts at the contact point plus r N,
  N = (a, 0, 1) / √(1 + a²), with the horizontal velocity (vx, vy) and vz = −a vx (tangency).
"""

from __future__ import annotations

import math

import numpy as np

from rollball.track import Track


def billiard(t, mu: float, v0: float, x0: float = -2.5, r: float = 0.1, g: float = 9.81) -> np.ndarray:
    """The centre (n, 3) of the billiard shot at the times t."""
    t = np.asarray(t, dtype=float)
    grip = 2 * v0 / (7 * mu * g)
    at_grip = x0 + v0 * grip - 0.5 * mu * g * grip ** 2
    x = np.where(t < grip, x0 + v0 * t - 0.5 * mu * g * t * t, at_grip + 5 / 7 * v0 * (t - grip))
    return np.column_stack([x, np.zeros_like(t), np.full_like(t, r)])


def incline(t, a: float, vx: float, vy: float, x0: float, y0: float, r: float = 0.1,
            g: float = 9.81) -> np.ndarray:
    """The centre (n, 3) of a ball rolling on z = −a x at the times t."""
    t = np.asarray(t, dtype=float)[:, None]
    w = math.sqrt(1 + a * a)
    c0 = np.array([x0 + r * a / w, y0, -a * x0 + r / w])
    v0 = np.array([vx, vy, -a * vx])
    acc = 5 / 7 * g * a / (1 + a * a) * np.array([1.0, 0.0, -a])
    return c0 + v0 * t + 0.5 * acc * t * t


def noisy(times, centre: np.ndarray, axes: tuple[str, ...], sigma: float, seed: int) -> Track:
    """A track of the centre on ``axes`` with independent Gaussian noise of ``sigma`` metres."""
    columns = ["xyz".index(axis) for axis in axes]
    rng = np.random.default_rng(seed)
    return Track(times, axes, centre[:, columns] + rng.normal(0.0, sigma, (len(times), len(axes))))
