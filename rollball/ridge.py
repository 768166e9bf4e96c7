"""A rolling ball turning over a ridge (docs/design.md §1, "A ridge"): where the surface has a
convex kink line and the ball reaches it too slowly to leave it, it rolls over the edge, its
contact point on the edge line, its centre on the circle of radius r about it, until it comes
down on the far face (or back on the near one, or leaves the edge where holding it would need a
pull).

The ridge is taken as the straight line where the two faces' tangent planes meet at the point the
ball reached it (``Ridge``). With t̂ along it, e(θ) = cos θ N₁ + sin θ (t̂ × N₁) the direction from
the edge to the centre (θ = 0 on the near face, θ₂ = the angle between the faces' normals on the
far one) and e′ = t̂ × e, the centre is c = P + s t̂ + r e(θ) and rolling without slipping on the
edge point asks ċ = r ω × e: ω = θ̇ t̂ + β e − (ṡ/r) e′, β the spin about e. The contact force F
and I ω̇ = −r e × F (I = 2/5 m r²) give

    s̈ = (5/7) g·t̂ + (2/7) r θ̇ β,   r θ̈ = (5/7) g·e′,   β̇ = −θ̇ ṡ / r,
    F·e = m (g₀ e_z − r θ̇²),   F_t = m ((2/7) (r θ̇ β − g·t̂) t̂ − (2/7) (g·e′) e′),

which keep E = ½ m (7/5) (ṡ² + r² θ̇²) + ⅕ m r² β² + m g₀ c_z (checked in the tests). They are
integrated by DOP853 at rtol 10⁻¹² until θ reaches θ₂ (on the far face) or 0 moving back (on the
near face), F·e reaches 0 (a lift-off from the edge), |F_t| reaches μ F·e (the friction cannot
hold the turn: the run stops, ``ridge_slip``) or the run's end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from .flight import FreeState

TOLERANCE = 1e-12        # DOP853's rtol (and atol in units of r, r/s, rad)
NUDGE = 1e-9             # × (1 + |P|): a face is taken up this far past the edge (its own plane up to there)
MIN_TURN = 1e-6          # rad: faces whose normals differ by less than this are no ridge to turn over
END, BACK, LIFTOFF, SLIP, TIME = "far_face", "near_face", "liftoff", "slip", "end"


@dataclass(frozen=True)
class Ridge:
    """The edge line through ``point`` P along ``along`` t̂, the near face's unit normal ``near``
    N₁ and the angle ``turn`` θ₂ to the far face's normal N₂ (about t̂)."""

    point: np.ndarray
    along: np.ndarray
    near: np.ndarray
    turn: float

    @classmethod
    def between(cls, point, near, far) -> "Ridge | None":
        """The ridge at ``point`` between the faces of unit normals ``near`` and ``far`` (None
        where they are parallel: no ridge)."""
        near, far = np.asarray(near, float), np.asarray(far, float)
        axis = np.cross(near, far)
        size = float(np.linalg.norm(axis))
        turn = math.atan2(size, float(np.dot(near, far)))
        if not turn > MIN_TURN:
            return None
        return cls(np.asarray(point, float), axis / size, near, turn)

    def direction(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        """e(θ) and e′(θ) = t̂ × e(θ)."""
        side = np.cross(self.along, self.near)
        c, s = math.cos(theta), math.sin(theta)
        return c * self.near + s * side, -s * self.near + c * side


@dataclass(frozen=True)
class Turn:
    """How a turn over a ridge ended: ``how`` (END, BACK, LIFTOFF, SLIP or TIME) at ``state``
    (time, centre, velocity, ω, R), the contact point ``contact`` (x, y) on the edge and F·e
    ``force`` there; and the turn at the times asked for before that (``states``, ``contacts``,
    ``forces``), the run's end among them where the turn lasts to it."""

    how: str
    state: FreeState
    contact: tuple[float, float]
    force: float
    states: list[FreeState]
    contacts: list[tuple[float, float]]
    forces: list[float]


def _parts(y, ridge: Ridge, r: float):
    s, ds, theta, dtheta, beta = y[:5]
    e, e1 = ridge.direction(theta)
    omega = dtheta * ridge.along + beta * e - (ds / r) * e1
    return s, ds, theta, dtheta, beta, e, e1, omega


def _turn_rate(ridge: Ridge, start: FreeState, r: float) -> float:
    """θ̇ of the ball at ``start`` on the near face's circle about the edge: its velocity across the
    edge over r."""
    return float(np.dot(start.velocity, ridge.direction(0.0)[1])) / r


def edge_force(ridge: Ridge, start: FreeState, *, radius: float, mass: float, gravity: float) -> float | None:
    """F·e the ball at ``start`` (on the near face's circle about the edge) needs on the edge to turn
    over it as the turn begins, m (g₀ e_z − r θ̇²): above 0 it is too slow to leave the edge, and
    turns over it (``turn_over``; a sliding ball stops the run there, ``ridge_pivot``); None where it
    moves away from the far face (θ̇ ≤ 0: no turn over this edge)."""
    dtheta = _turn_rate(ridge, start, radius)
    if not dtheta > 0.0:
        return None
    return mass * (gravity * ridge.direction(0.0)[0][2] - radius * dtheta * dtheta)


def edge_return(ridge: Ridge, start: FreeState, *, gravity: float) -> float | None:
    """Where the ball at ``start``, leaving the edge on the parabola (F·e ≤ 0, ``edge_force``), comes
    down on the edge again before it is past it: its centre r from the edge line again while the
    edge is the surface's nearest point (the direction from the edge to the centre between the
    faces' normals, 0 < θ < θ₂). With w(τ) = A + B τ + C τ² the centre's offset across the edge line
    (A = r e₀, B ⊥ A its velocity across, C half of gravity across), |w|² − r² = τ² (|C|² τ² + 2 B·C τ
    + |B|² + 2 A·C), the first root τ > 0 of the quadratic: the time after ``start`` it returns in
    (None where the ball clears the edge)."""
    across = np.eye(3) - np.outer(ridge.along, ridge.along)
    A, B = across @ (start.center - ridge.point), across @ start.velocity
    C = 0.5 * (across @ np.array([0.0, 0.0, -gravity]))
    a, b, c = float(C @ C), 2.0 * float(B @ C), float(B @ B) + 2.0 * float(A @ C)
    if not (a > 0.0 and c >= 0.0 and b < 0.0) or b * b < 4.0 * a * c:
        return None
    tau = (-b - math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)   # (the smaller positive root: c >= 0, b < 0)
    if not tau > 0.0:
        return None
    w = A + B * tau + C * tau * tau
    e0, e1 = ridge.direction(0.0)
    theta = math.atan2(float(w @ e1), float(w @ e0))
    return tau if 0.0 < theta < ridge.turn else None


def contact_events(forces, mu: float):
    """The events that end a turn about an edge or a tip, for scipy's solve_ivp: the normal force
    reaching 0 (a lift-off) and the tangential force reaching μ times it (a slip; never with μ
    inf), from ``forces(y)`` = (F·e, |F_t|)."""
    def lifts(_, y):
        return forces(y)[0]
    lifts.terminal, lifts.direction = True, -1.0

    def slips(_, y):
        normal, tangential = forces(y)
        return mu * normal - tangential if mu < math.inf else 1.0
    slips.terminal, slips.direction = True, -1.0
    return lifts, slips


def turn_over(ridge: Ridge, start: FreeState, *, radius: float, mass: float, gravity: float,
              friction: float, t_end: float, times: np.ndarray) -> Turn | None:
    """The ball at ``start`` (on the near face's circle about the edge: c − P along N₁ at distance
    r, rolling) turned over ``ridge`` until the turn ends (``Turn``), with rows at ``times``
    (within it); None where it does not turn over the edge (it moves away from the far face, or
    holding it on the edge needs a pull already: it flies)."""
    from scipy.integrate import solve_ivp   # (scipy loads with a turn, not with the program)

    r, g0, mu = radius, gravity, friction
    g = np.array([0.0, 0.0, -g0])
    arm = start.center - ridge.point
    s0 = float(np.dot(arm, ridge.along))
    force = edge_force(ridge, start, radius=r, mass=mass, gravity=g0)
    if force is None or not force > 0.0:
        return None
    dtheta0 = _turn_rate(ridge, start, r)
    ds0 = float(np.dot(start.velocity, ridge.along))
    beta0 = float(np.dot(start.omega, ridge.direction(0.0)[0]))

    def rates(_, y):
        s, ds, theta, dtheta, beta, e, e1, omega = _parts(y, ridge, r)
        R = y[5:].reshape(3, 3)
        turn = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]], [-omega[1], omega[0], 0.0]])
        return np.concatenate([[ds, (5.0 / 7.0) * float(g @ ridge.along) + (2.0 / 7.0) * r * dtheta * beta,
                                dtheta, (5.0 / 7.0) * float(g @ e1) / r, -dtheta * ds / r], (turn @ R).ravel()])

    def forces(y):
        s, ds, theta, dtheta, beta, e, e1, omega = _parts(y, ridge, r)
        normal = mass * (g0 * e[2] - r * dtheta * dtheta)
        along = (2.0 / 7.0) * (r * dtheta * beta - float(g @ ridge.along))
        across = -(2.0 / 7.0) * float(g @ e1)
        return normal, mass * math.hypot(along, across)

    def far(_, y):
        return y[2] - ridge.turn
    far.terminal, far.direction = True, 1.0

    def back(_, y):
        return y[2]
    back.terminal, back.direction = True, -1.0

    lifts, slips = contact_events(forces, mu)
    y0 = np.concatenate([[s0, ds0, 0.0, dtheta0, beta0], start.R.ravel()])
    if mu < math.inf and slips(start.t, y0) < 0.0:   # (the friction cannot hold the turn from its start)
        return _turn(SLIP, ridge, y0, start.t, r, forces, [], [])
    scale = np.concatenate([[r, r, 1.0, 1.0, 1.0], np.ones(9)])
    asked = np.append(times[(times > start.t) & (times < t_end)], t_end)
    solution = solve_ivp(rates, (start.t, t_end), y0, method="DOP853", rtol=TOLERANCE, atol=TOLERANCE * scale,
                         events=(far, back, lifts, slips), t_eval=asked)
    if solution.status == -1:   # (the integration failed: no turn to follow)
        return None
    ts = np.asarray(solution.t, dtype=float)
    ys = np.asarray(solution.y, dtype=float).reshape(len(y0), len(ts))   # (no column where an event came first)
    how, t, y = TIME, t_end, (ys[:, -1] if len(ts) else None)
    for kind, found, states in zip((END, BACK, LIFTOFF, SLIP), solution.t_events, solution.y_events):
        if len(found) and found[0] < t:
            how, t, y = kind, float(found[0]), states[0]
    keep = np.flatnonzero(ts < t) if how != TIME else np.arange(len(ts))
    return _turn(how, ridge, y, t, r, forces, [ys[:, i] for i in keep], [float(ts[i]) for i in keep])


def _turn(how, ridge: Ridge, y, t: float, r: float, forces, ys, ts) -> Turn:
    contacts = [_contact(ridge, v) for v in ys]
    return Turn(how, _state(ridge, y, t, r), _contact(ridge, y), forces(y)[0],
                [_state(ridge, v, s, r) for v, s in zip(ys, ts)], contacts, [forces(v)[0] for v in ys])


def _contact(ridge: Ridge, y) -> tuple[float, float]:
    point = ridge.point + y[0] * ridge.along
    return float(point[0]), float(point[1])


def _state(ridge: Ridge, y, t: float, r: float) -> FreeState:
    s, ds, theta, dtheta, beta, e, e1, omega = _parts(y, ridge, r)
    center = ridge.point + s * ridge.along + r * e
    velocity = ds * ridge.along + r * dtheta * e1
    R = y[5:].reshape(3, 3)
    u, _, vt = np.linalg.svd(R)   # (the nearest rotation: DOP853 keeps RᵀR = I to its tolerance)
    return FreeState(t, center, velocity, omega, u @ vt)


def past_edge(state: FreeState, normal: np.ndarray, *, gravity: float, scale: float) -> float:
    """How long the ball at ``state`` on the edge takes to roll NUDGE × scale onto the face of unit
    ``normal`` (along that face's plane, accelerating at (5/7) g_t): the rolling run on the face
    starts there, off the edge line, where the face's own normal is the surface's."""
    normal = np.asarray(normal, float)
    g = np.array([0.0, 0.0, -gravity])
    a = (5.0 / 7.0) * (g - float(np.dot(g, normal)) * normal)
    speed = float(np.linalg.norm(state.velocity))
    reach = NUDGE * scale
    return reach / speed if speed > 0.0 else math.sqrt(2.0 * reach / max(float(np.linalg.norm(a)), 1e-300))
