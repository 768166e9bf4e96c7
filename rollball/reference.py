"""An independent reference solution: the equations of docs/design.md §1 written with plain numpy
linear algebra (no closed forms, R as a full matrix) and integrated by scipy's DOP853.

Slow and accurate: for tests and the benchmark, never for normal runs.
"""

from __future__ import annotations

import numpy as np

from .landscape import landscape_of
from .scene import Scene
from .simulation import initial_state


def _skew(u: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])


def reference_rhs(scene: Scene):
    """The right-hand side f(t, y) for y = (alpha, v, R row-major): 14 numbers."""
    landscape = landscape_of(scene)
    values = scene.parameter_values
    r, m = scene.ball.radius, scene.ball.mass
    g = np.array([0.0, 0.0, -scene.gravity])
    eye = np.eye(3)

    def rhs(t, y):
        alpha, v, R = y[:2], y[2:5], y[5:].reshape(3, 3)
        _, fx, fy, fxx, fxy, fyy = landscape.evaluate(alpha[0], alpha[1], values)
        n = np.array([-fx, -fy, 1.0])
        W = np.linalg.norm(n)
        N = n / W
        dn = np.array([[-fxx, -fxy], [-fxy, -fyy], [0.0, 0.0]])
        dN = (eye - np.outer(N, N)) @ dn / W
        dphi = np.array([[1.0, 0.0], [0.0, 1.0], [fx, fy]])
        dC = dphi + r * dN
        T = m * r * r * (0.4 * eye - _skew(N) @ _skew(N))
        omega = np.linalg.solve(T, v)
        dalpha = r * np.linalg.solve(dC.T @ dC, dC.T @ np.cross(omega, N))
        dv = m * r * np.cross(N, g) - m * r * r * np.cross(dN @ dalpha, np.cross(N, omega))
        dR = _skew(omega) @ R
        return np.concatenate([dalpha, dv, dR.ravel()])

    return rhs


def reference_solution(scene: Scene, t_eval, rtol: float = 1e-12, atol: float = 1e-12):
    """(alpha (n, 2), v (n, 3), R (n, 3, 3)) at the times ``t_eval`` (starting at 0)."""
    from scipy.integrate import solve_ivp

    t_eval = np.asarray(t_eval, dtype=float)
    alpha, v = initial_state(landscape_of(scene), scene)
    y0 = np.concatenate([alpha, v, np.eye(3).ravel()])
    sol = solve_ivp(reference_rhs(scene), (0.0, float(t_eval[-1])), y0, method="DOP853",
                    t_eval=t_eval, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"reference solution failed: {sol.message}")
    y = sol.y.T
    return y[:, :2], y[:, 2:5], y[:, 5:].reshape(-1, 3, 3)


def reference_normal_force(scene: Scene):
    """F·N(t, y) of the rolling ball along the state y of ``reference_rhs``: m (c̈ − g)·N with
    c̈·N from the turning normal, m r (ω × Ṅ)·N (docs/design.md §1). Zero where it lifts off."""
    landscape = landscape_of(scene)
    values = scene.parameter_values
    r, m, g0 = scene.ball.radius, scene.ball.mass, scene.gravity
    rhs = reference_rhs(scene)
    eye = np.eye(3)

    def force(t, y):
        alpha, v = y[:2], y[2:5]
        _, fx, fy, fxx, fxy, fyy = landscape.evaluate(alpha[0], alpha[1], values)
        n = np.array([-fx, -fy, 1.0])
        N = n / np.linalg.norm(n)
        omega = 5 / (7 * m * r * r) * (v + 2.5 * N * (N @ v))
        dN = (eye - np.outer(N, N)) @ np.array([[-fxx, -fxy], [-fxy, -fyy], [0.0, 0.0]]) / np.linalg.norm(n)
        return m * r * np.cross(omega, dN @ rhs(t, y)[:2]) @ N + m * g0 * N[2]

    return force


def normal_force_zeros(scene: Scene, t_max: float, first: bool = False) -> np.ndarray:
    """The times F·N crosses 0 up to ``t_max`` (only the first falling through 0 if ``first``),
    by scipy's DOP853 (rtol = atol = 1e-12) with its own event location."""
    from scipy.integrate import solve_ivp

    force = reference_normal_force(scene)
    if first:
        force.terminal, force.direction = True, -1
    alpha, v = initial_state(landscape_of(scene), scene)
    sol = solve_ivp(reference_rhs(scene), (0.0, t_max), np.concatenate([alpha, v, np.eye(3).ravel()]),
                    method="DOP853", rtol=1e-12, atol=1e-12, events=force)
    return sol.t_events[0]
