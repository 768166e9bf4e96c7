"""A rolling ball turning over a tip (docs/design.md §1, "A tip"): where the normal turns through
a finite angle at a point T (the tip of a cone) and the ball reaches it too slowly to leave it, its
contact stays at T and its centre moves on the sphere of radius r about T, until it comes down on a
face of the tip (the far one, or back on the one it came up), or leaves T where holding it would
need a pull.

With ê the unit vector from T to the centre (c = T + r ê), rolling without slipping about T asks
ċ = r ω × ê, so ê̇ = ω × ê. The angular momentum about the fixed point T is L = m r² ℓ with
ℓ = (7/5) ω − ê (ê·ω) (the rolling ball's operator), so ω = (5/7) ℓ + (25/14) ê (ê·ℓ); the contact
force acts at T, and gravity's moment about it gives ℓ̇ = ê × g / r. R′ = A(ω) R. These keep
E = ½ m r² ω·ℓ + m g₀ c_z (checked in the tests). The contact force is F = m (c̈ − g): F·ê is the
normal force, F·ê = m (g₀ ê_z − r |ê̇|²), and F_t = F − (F·ê) ê the friction.

Near T the surface is, to first order, the cone of its generators d(φ) (the unit directions from
T along the surface at azimuth φ). The ball touches the surface only at T while ê·d(φ) < 0 for
every φ (each generator lies below the plane through T normal to ê); where max_φ ê·d(φ) reaches 0
the centre's distance to the surface near T, T excluded, reaches r: ê is then the face's normal
along that generator (its one-sided limit at T) and the ball rolls on from that face. T itself is
taken as the point the tangent planes of the faces about it meet in (least squares over a ring of
radius REACH about the tip the kernel found: exact for a cone, the kernel's tip is known to only
10⁻⁹ m), and d(φ) from the slopes on a ring of radius NEAR about T.

The turn is integrated by DOP853 at rtol 10⁻¹² until max_φ ê·d(φ) reaches 0 (``FACE``), F·ê
reaches 0 (``LIFTOFF``: the ball leaves T), |F_t| reaches μ F·ê (``SLIP``: the friction cannot hold
the turn, the run stops, ``tip_slip``) or the run's end (``TIME``). From a face the rolling run
starts ONTO down it (``onto_face``, ``foot_on_face``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .flight import FreeState
from .ridge import LIFTOFF, SLIP, TIME, TOLERANCE, Turn, contact_events

REACH = 1e-7        # × (1 + |x| + |y|): the ring about the kernel's tip that finds T (its planes)
NEAR = 1e-9         # × (1 + |x| + |y|): the ring about T the generators are sampled on
RING = 64           # points of the ring that finds T
AZIMUTHS = 4096     # generators sampled about T
ONTO = 1e-8         # × (1 + |x| + |y|): a face is taken up this far from T (past the kernel's 4·10⁻⁹ of a tip)
FACE = "face"   # (the other ends as a ridge's: LIFTOFF, SLIP, TIME)


@dataclass(frozen=True)
class Tip:
    """The tip ``point`` T and its unit ``generators`` d(φ) (AZIMUTHS of them, φ evenly spaced)."""

    point: np.ndarray
    generators: np.ndarray

    @classmethod
    def near(cls, x: float, y: float, evaluate) -> "Tip | None":
        """The tip found near (x, y), ``evaluate(xs, ys)`` giving the landscape's f, f_x, f_y (first
        rows) at arrays of points; None where the faces' tangent planes meet in no point near it
        (no tip there) or the landscape cannot be evaluated about it."""
        reach = REACH * (1.0 + abs(x) + abs(y))
        px, py, d = _ring(x, y, reach, RING, evaluate)
        if not np.isfinite(d[:3]).all():
            return None
        f, fx, fy = d[0], d[1], d[2]
        planes = np.column_stack([fx, fy, -np.ones_like(fx)])
        (tx, ty, tz), *_ = np.linalg.lstsq(planes, fx * px + fy * py - f, rcond=None)
        if not math.hypot(tx - x, ty - y) < 0.1 * reach:
            return None
        near = NEAR * (1.0 + abs(x) + abs(y))
        px, py, d = _ring(tx, ty, near, AZIMUTHS, evaluate)
        if not np.isfinite(d[:3]).all():
            return None
        ux, uy = (px - tx) / near, (py - ty) / near
        generators = np.column_stack([ux, uy, d[1] * ux + d[2] * uy])
        generators /= np.linalg.norm(generators, axis=1)[:, None]
        return cls(np.array([tx, ty, tz]), generators)

    def touching(self, e: np.ndarray) -> tuple[float, np.ndarray]:
        """max_φ ê·d(φ) (< 0 while the ball touches the surface near T only at T) and the
        generator d(φ*) where it is largest, both interpolated between the samples by a parabola."""
        dots = self.generators @ e
        k = int(np.argmax(dots))
        before, after = (k - 1) % len(dots), (k + 1) % len(dots)
        a, b, c = dots[before], dots[k], dots[after]
        bend = a - 2.0 * b + c
        shift = 0.5 * (a - c) / bend if bend < 0.0 else 0.0
        value = b - 0.25 * (a - c) * shift
        g0, g1, g2 = self.generators[before], self.generators[k], self.generators[after]
        generator = g1 + 0.5 * shift * (g2 - g0) + 0.5 * shift * shift * (g2 - 2.0 * g1 + g0)
        return float(value), generator / float(np.linalg.norm(generator))


def _ring(x: float, y: float, reach: float, count: int, evaluate):
    phi = np.arange(count) * (2.0 * np.pi / count)
    px, py = x + reach * np.cos(phi), y + reach * np.sin(phi)
    return px, py, np.asarray(evaluate(px, py), dtype=float)


def _omega(e: np.ndarray, ell: np.ndarray) -> np.ndarray:
    return (5.0 / 7.0) * ell + (25.0 / 14.0) * float(np.dot(e, ell)) * e


def turn_about(tip: Tip, start: FreeState, normal: np.ndarray, *, radius: float, mass: float, gravity: float,
               friction: float, t_end: float, times: np.ndarray) -> Turn | None:
    """The ball at ``start`` (rolling on the face of unit ``normal``, its contact point at T: c − T
    of length r) turned over ``tip`` until the turn ends (``ridge.Turn``, its contact T
    throughout), with rows at ``times`` (within it); None where the integration fails."""
    from scipy.integrate import solve_ivp   # (scipy loads with a turn, not with the program)

    r, g0, mu, T = radius, gravity, friction, tip.point
    g = np.array([0.0, 0.0, -g0])
    arm = start.center - T
    e0 = arm / float(np.linalg.norm(arm))
    # the rolling state reached the tip (its contact point within nanometres of T, its normal that
    # close to ê): ċ is taken across ê and ω = ê × ċ / r plus the spin it had about the normal,
    # which keeps E to second order in that distance
    velocity = start.velocity - float(np.dot(start.velocity, e0)) * e0
    omega = np.cross(e0, velocity) / r + float(np.dot(start.omega, normal)) * e0
    ell0 = 1.4 * omega - float(np.dot(e0, omega)) * e0

    def rates(_, y):
        e, ell = y[:3], y[3:6]
        w = _omega(e, ell)
        R = y[6:].reshape(3, 3)
        turn = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
        return np.concatenate([np.cross(w, e), np.cross(e, g) / r, (turn @ R).ravel()])

    def forces(y):
        e = y[:3] / float(np.linalg.norm(y[:3]))
        ell = y[3:6]
        w = _omega(e, ell)
        de, dell = np.cross(w, e), np.cross(e, g) / r
        dw = (5.0 / 7.0) * dell + (25.0 / 14.0) * (float(np.dot(e, ell)) * de + float(np.dot(de, ell)) * e)
        force = mass * (r * (np.cross(dw, e) + np.cross(w, de)) - g)
        normal = float(np.dot(force, e))
        return normal, float(np.linalg.norm(force - normal * e))

    def lands(_, y):
        return tip.touching(y[:3] / float(np.linalg.norm(y[:3])))[0]
    lands.terminal, lands.direction = True, 1.0

    lifts, slips = contact_events(forces, mu)
    y0 = np.concatenate([e0, ell0, start.R.ravel()])
    if not forces(y0)[0] > 0.0:   # (holding it at T needs a pull: it leaves T at once)
        return _turn(LIFTOFF, tip, y0, start.t, r, forces, [], [])
    if slips(start.t, y0) < 0.0:   # (the friction cannot hold the turn from its start)
        return _turn(SLIP, tip, y0, start.t, r, forces, [], [])
    rate = float(np.linalg.norm(ell0)) + math.sqrt(g0 / r)
    scale = np.concatenate([np.ones(3), np.full(3, rate), np.ones(9)])
    asked = np.append(times[(times > start.t) & (times < t_end)], t_end)
    solution = solve_ivp(rates, (start.t, t_end), y0, method="DOP853", rtol=TOLERANCE, atol=TOLERANCE * scale,
                         events=(lands, lifts, slips), t_eval=asked)
    if solution.status == -1:   # (the integration failed: no turn to follow)
        return None
    ts = np.asarray(solution.t, dtype=float)
    ys = np.asarray(solution.y, dtype=float).reshape(len(y0), len(ts))
    how, t, y = TIME, t_end, (ys[:, -1] if len(ts) else None)
    for kind, found, states in zip((FACE, LIFTOFF, SLIP), solution.t_events, solution.y_events):
        if len(found) and found[0] < t:
            how, t, y = kind, float(found[0]), states[0]
    keep = np.flatnonzero(ts < t) if how != TIME else np.arange(len(ts))
    return _turn(how, tip, y, t, r, forces, [ys[:, i] for i in keep], [float(ts[i]) for i in keep])


def _turn(how, tip: Tip, y, t: float, r: float, forces, ys, ts) -> Turn:
    contact = (float(tip.point[0]), float(tip.point[1]))
    return Turn(how, _state(tip, y, t, r), contact, forces(y)[0], [_state(tip, v, s, r) for v, s in zip(ys, ts)],
                [contact] * len(ys), [forces(v)[0] for v in ys])


def _state(tip: Tip, y, t: float, r: float) -> FreeState:
    e = y[:3] / float(np.linalg.norm(y[:3]))
    w = _omega(e, y[3:6])
    u, _, vt = np.linalg.svd(y[6:].reshape(3, 3))   # (the nearest rotation: DOP853 keeps RᵀR = I to its tolerance)
    return FreeState(t, tip.point + r * e, r * np.cross(w, e), w, u @ vt)


def onto_face(tip: Tip, state: FreeState, *, gravity: float) -> tuple[float, np.ndarray]:
    """Where a turn ended on a face (``FACE``): how long the ball at ``state`` takes to roll
    ONTO × (1 + |T|) onto it along the generator it came down on (at its speed along it, or from
    rest at (5/7) g_t), and the face's unit normal there (ê): the rolling run on the face starts
    that far from T (``foot``), beyond where the kernel takes the contact point to be at the tip."""
    T = tip.point
    e = (state.center - T) / float(np.linalg.norm(state.center - T))
    generator = tip.touching(e)[1]
    reach = ONTO * (1.0 + abs(T[0]) + abs(T[1]))
    speed = float(np.dot(state.velocity, generator))
    if speed > 0.0:
        return reach / speed, e
    pull = (5.0 / 7.0) * gravity * math.hypot(e[0], e[1])
    return math.sqrt(2.0 * reach / max(pull, 1e-300)), e


def foot_on_face(tip: Tip, center: np.ndarray, evaluate, *, radius: float) -> tuple[float, float]:
    """The contact point (x, y) of a ball whose centre is just past a face of the tip (off the
    sphere about T), ``evaluate(x, y)`` the landscape's f, f_x, f_y there: first on the generator
    that touches the ball (``Tip.touching``), as far from T as the centre is along it, then moved
    (Newton's method on c = p + r N(p), three times) until its own normal leads to the centre."""
    T = tip.point
    generator = tip.touching((center - T) / float(np.linalg.norm(center - T)))[1]
    x, y = (T + float(np.dot(center - T, generator)) * generator)[:2]
    for _ in range(3):
        f, fx, fy, fxx, fxy, fyy = np.asarray(evaluate(x, y), dtype=float)[:6]
        n = np.array([-fx, -fy, 1.0])
        size = float(np.linalg.norm(n))
        # ∂c/∂x and ∂c/∂y: the surface's tangents plus r ∂N, with ∂n = (−f_xx, −f_xy, 0), (−f_xy, −f_yy, 0)
        columns = [np.array([1.0, 0.0, fx]), np.array([0.0, 1.0, fy])]
        for column, turn in zip(columns, (np.array([-fxx, -fxy, 0.0]), np.array([-fxy, -fyy, 0.0]))):
            column += radius * (turn / size - n * float(n @ turn) / size ** 3)
        jacobian = np.column_stack(columns)
        miss = center - (np.array([x, y, f]) + radius * n / size)
        step = np.linalg.lstsq(jacobian, miss, rcond=None)[0]
        x, y = x + step[0], y + step[1]
    return float(x), float(y)
