"""Where the ball fits: the unit normal and r·κ_max of a landscape, on arrays of points.

Both take the derivative array ``d`` = (f, f_x, f_y, f_xx, f_xy, f_yy) of
``Landscape.evaluate`` (shape (6,) + grid shape) and work elementwise; they are the
same formulas the kernel evaluates at every step (docs/design.md §1).
"""

from __future__ import annotations

import math

import numpy as np


def cross(a, b) -> np.ndarray:
    """a × b over the last axis (of 3), the products and differences ``np.cross`` takes, in the
    same order (the same numbers), without its setup, which costs more than a flight's few
    vectors; two 3-vectors in Python's floats (a twentieth of np.cross's time)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape == b.shape == (3,):
        a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
        b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def unit_normal(d: np.ndarray) -> np.ndarray:
    """N = (-f_x, -f_y, 1) / sqrt(1 + f_x² + f_y²), shape (3,) + grid shape (one point: in
    Python's floats, the same numbers in a fifth of the time)."""
    if d.ndim == 1:
        return np.array(unit_normal_of(float(d[1]), float(d[2])))
    fx, fy = d[1], d[2]
    W = np.sqrt(1.0 + fx * fx + fy * fy)
    return np.stack([-fx / W, -fy / W, 1.0 / W])


def unit_normal_of(fx: float, fy: float) -> tuple[float, float, float]:
    """``unit_normal`` of one point from its slopes, in Python's floats (the same numbers)."""
    W = math.sqrt(1.0 + fx * fx + fy * fy)
    return -fx / W, -fy / W, 1.0 / W


def rotation(u) -> np.ndarray:
    """The rotation exp([u]×) by the angle θ = |u| about u (3,): Rodrigues' formula
    I + sinc(θ) [u]× + ½ sinc²(θ/2) [u]×² (sinc x = sin x / x: no cancellation as θ → 0); for the few
    rotations Python takes (a flight's state at a time; the kernel's ``physics.rodrigues`` turns the rows)."""
    u1, u2, u3 = (float(c) for c in u)
    theta = math.sqrt(u1 * u1 + u2 * u2 + u3 * u3)
    cross = np.array([[0.0, -u3, u2], [u3, 0.0, -u1], [-u2, u1, 0.0]])
    half = _sinc(0.5 * theta)
    return np.eye(3) + _sinc(theta) * cross + 0.5 * half * half * (cross @ cross)


def _sinc(x: float) -> float:
    return math.sin(x) / x if x != 0.0 else 1.0


def fit_ratio(d: np.ndarray, radius: float) -> np.ndarray:
    """r · κ_max: the ball of this radius fits where this is below 1.

    κ_max is the larger principal curvature, positive where the surface bends up towards
    the ball (a valley); NaN where the landscape cannot be evaluated. Near umbilic points
    (equal curvatures) the square root costs about half the digits, as in the kernel: the
    value serves a threshold at 1.
    """
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):  # NaN marks those points
        fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
        W2 = 1.0 + fx * fx + fy * fy
        W = np.sqrt(W2)
        h11, h12, h22 = fxx / W, fxy / W, fyy / W
        mean = 0.5 * ((1.0 + fx * fx) * h22 + (1.0 + fy * fy) * h11 - 2.0 * fx * fy * h12) / W2
        gauss = (h11 * h22 - h12 * h12) / W2
        ratio = radius * (mean + np.sqrt(np.maximum(mean * mean - gauss, 0.0)))
    return np.where(np.isnan(d).any(axis=0), np.nan, ratio)


def reachable_height(d: np.ndarray, scene) -> float:
    """The highest the centre, and so the contact point, of the scene's ball can ever get:
    its energy at the start as a height, E / (m g) (inf without gravity). ``d`` is the
    derivative array at the start point.

    Rolling, the kinetic energy per mass is ½|ċ|² + ⅕ r²|ω|² with |ω|² = |ċ|²/r² + spin²,
    so E / m = g c_z + 0.7 |ċ|² + 0.2 r² spin².
    """
    s, r = scene.start, scene.ball.radius
    vz = d[1] * s.vx + d[2] * s.vy
    kinetic = 0.7 * (s.vx * s.vx + s.vy * s.vy + vz * vz) + 0.2 * r * r * s.spin * s.spin
    center_z = d[0] + r * unit_normal(d)[2]
    return float(center_z + kinetic / scene.gravity) if scene.gravity > 0 else float("inf")
