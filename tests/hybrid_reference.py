"""An independent reference for the ball's hybrid motion: rolling, sliding, flying and landing
with impacts on a landscape z = f(x, y) (DESIGN §1, §10–§12; docs/design.md "Sliding", "Flight
and landing").

Written from the model's equations, not from RollBall's kernel, and in another formulation:
the state in contact is the centre c, its velocity ċ, the angular velocity ω and the contact
point α = (x, y) (carried along with α′ from ċ = C′ α′), and the contact force F = F_n N + F_t
is a constraint force:

    m c̈ = m g + F,    (2/5) m r² ω̇ = (−r N) × F,
    F_n from d/dt (ċ·N) = 0:  F_n = m (g₀ N_z − ċ·Ṅ),
    rolling: F_t from the tangential part of u̇ = 0, u = ċ + ω × (−r N) the velocity of the
             ball's material point at the contact:  F_t = −(2/7) m B,  B = P (g − r ω × Ṅ)
             (B is u̇ with friction off, P the projection on the tangent plane),
    sliding: F_t = −μ F_n ŝ,  ŝ = u/|u| (ŝ = B̂ from a slip's onset at u = 0 until |u| = 1e-8 m/s).

The landscape's derivatives come from sympy (the formula with the parameters' values put in),
not from RollBall's compiler. Every mode is integrated by scipy's DOP853 at rtol 3e-14, atol 1e-14;
its events (on the dense output) end a mode: a slip where (μ F_n)² = (2/7 m |B|)², a lift-off
where F_n = 0, a grip where |u| falls to 1e-9 m/s (extrapolated linearly to |u| = 0). A flight
is closed form (c a parabola, ω constant); the landing is the first root of the gap
dist(c(t), surface) − r, the distance by Newton's method on the foot, found by brentq. The
impact is an impulse at the contact (normal: u_n → −e u_n; tangential: sticking if
|(2/7) m u_t| ≤ μ J_n, else J_t = −μ J_n û_t); a rebound slower than v_rest = √(2 g₀ 10⁻⁶ r)
stays in contact. A start where F_n < 0 (the surface cannot hold the ball) lifts off at t = 0.

``reference(scene, t_end, times)`` returns a ``HybridReference``; the solution of a scene is
computed once per process (cached by the scene's JSON and t_end). ``python tests/hybrid_reference.py``
prints the reference's transitions for the scenes of tests/test_hybrid_reference.py.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import sympy
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

# DOP853's tolerances (scipy takes rtol >= 2.2e-14): the reference's own error is then about
# 1e-13 m and 1e-13 s (rtol 1e-13 moved positions by up to 5e-13 m, times by 5e-13 s)
RTOL, ATOL = 3e-14, 1e-14
ONSET_SPEED = 1e-8     # m/s: after a slip's onset ŝ = B̂ until |u| reaches this (DESIGN §12)
GRIP_SPEED = 1e-9      # m/s: the grip is located where |u| falls to this, then extrapolated to 0
ROLLING_TOLERANCE = 1e-9   # a start whose slip speed is below this share of its speeds rolls
REST_HEIGHT = 1e-6     # v_rest = sqrt(2 g0 REST_HEIGHT r)

ROLLING, SLIDING, ONSET, FLYING = "rolling", "sliding", "onset", "flying"


# -- the landscape ----------------------------------------------------------------------------

class Landscape:
    """f and its first and second derivatives, from sympy."""

    def __init__(self, formula: str, parameters: dict[str, float]):
        x, y = sympy.symbols("x y", real=True)
        text = formula.replace(".^", "^").replace(".*", "*").replace("./", "/")
        names = {"x": x, "y": y, "e": sympy.E, "pi": sympy.pi, "min": sympy.Min, "max": sympy.Max,
                 "abs": sympy.Abs, "atan2": sympy.atan2}
        names.update({k: sympy.Float(v, 30) for k, v in parameters.items()})
        f = sympy.sympify(text, locals=names, convert_xor=True)
        fx, fy = sympy.diff(f, x), sympy.diff(f, y)
        exprs = [f, fx, fy, sympy.diff(fx, x), sympy.diff(fx, y), sympy.diff(fy, y)]
        self.expr = f
        self.all = sympy.lambdify((x, y), exprs, modules="math", cse=True)
        self.f = sympy.lambdify((x, y), f, modules="math")

    def frame(self, x, y):
        """(f, fx, fy, N, N_x, N_y) at (x, y): N the unit normal, N_x, N_y its derivatives."""
        f, fx, fy, fxx, fxy, fyy = self.all(x, y)
        w = 1.0 / math.sqrt(1.0 + fx * fx + fy * fy)
        n0, n1, n2 = -fx * w, -fy * w, w
        # N = n/|n| with n = (-fx, -fy, 1); dN = (dn - N (N·dn)) / |n|
        dx = -fxx * n0 - fxy * n1
        dy = -fxy * n0 - fyy * n1
        Nx = (w * (-fxx - n0 * dx), w * (-fxy - n1 * dx), w * (-n2 * dx))
        Ny = (w * (-fxy - n0 * dy), w * (-fyy - n1 * dy), w * (-n2 * dy))
        return f, fx, fy, (n0, n1, n2), Nx, Ny, (fxx, fxy, fyy)


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _tangential(a, N):
    """a's part in the tangent plane of the unit normal N."""
    an = _dot(a, N)
    return (a[0] - an * N[0], a[1] - an * N[1], a[2] - an * N[2])


# -- the ball in contact ------------------------------------------------------------------------

class Model:
    def __init__(self, landscape: Landscape, radius, mass, gravity, friction, restitution):
        self.land, self.r, self.m, self.g = landscape, radius, mass, gravity
        self.mu, self.e = friction, restitution

    def kinematics(self, s):
        """At state s = (c, ċ, ω, α): ċ, ω, the unit normal N, Ṅ and α′ (from ċ = C′ α′)."""
        r = self.r
        v, w = (s[3], s[4], s[5]), (s[6], s[7], s[8])
        _, fx, fy, N, Nx, Ny, _ = self.land.frame(s[9], s[10])
        cx = (1.0 + r * Nx[0], r * Nx[1], fx + r * Nx[2])   # C' = phi_alpha + r N_alpha
        cy = (r * Ny[0], 1.0 + r * Ny[1], fy + r * Ny[2])
        e11, e12, e22 = _dot(cx, cx), _dot(cx, cy), _dot(cy, cy)
        b1, b2 = _dot(cx, v), _dot(cy, v)
        det = e11 * e22 - e12 * e12
        a1, a2 = (e22 * b1 - e12 * b2) / det, (e11 * b2 - e12 * b1) / det
        Nd = (Nx[0] * a1 + Ny[0] * a2, Nx[1] * a1 + Ny[1] * a2, Nx[2] * a1 + Ny[2] * a2)
        return v, w, N, Nd, (a1, a2)

    def contact_terms(self, s):
        """Everything the contact's right-hand side needs at state s = (c, ċ, ω, α)."""
        r, g = self.r, self.g
        v, w, N, Nd, (a1, a2) = self.kinematics(s)
        Fn = self.m * (g * N[2] - _dot(v, Nd))
        wxNd = _cross(w, Nd)
        q = (-r * wxNd[0], -r * wxNd[1], -g - r * wxNd[2])     # g - r ω × Ṅ
        return N, Fn, _tangential(q, N), self.slip(v, w, N), (a1, a2)

    def slip(self, v, w, N):
        """The slip velocity u = ċ − r ω × N of the ball's point at the contact, in the tangent plane."""
        wxN = _cross(w, N)
        r = self.r
        return _tangential((v[0] - r * wxN[0], v[1] - r * wxN[1], v[2] - r * wxN[2]), N)

    def rhs(self, mode, s):
        m, r = self.m, self.r
        N, Fn, B, u, (a1, a2) = self.contact_terms(s)
        if mode == ROLLING:
            k = -2.0 * m / 7.0
            Ft = (k * B[0], k * B[1], k * B[2])
        else:
            d = u if mode == SLIDING else B
            size = math.sqrt(_dot(d, d))
            k = -self.mu * Fn / size
            Ft = (k * d[0], k * d[1], k * d[2])
        F = (Fn * N[0] + Ft[0], Fn * N[1] + Ft[1], Fn * N[2] + Ft[2])
        NxF = _cross(N, F)
        kw = -5.0 / (2.0 * m * r)
        return [s[3], s[4], s[5], F[0] / m, F[1] / m, F[2] / m - self.g,
                kw * NxF[0], kw * NxF[1], kw * NxF[2], a1, a2]

    # events: functions of (t, s), their direction, and what they mean
    def events(self, mode):
        m = self.m

        def liftoff(t, s):
            return self.contact_terms(s)[1]
        liftoff.terminal, liftoff.direction = True, -1
        if mode == ROLLING:
            if self.mu is None:
                return [liftoff], ["liftoff"]

            def slip(t, s):
                _, Fn, B, _, _ = self.contact_terms(s)
                return (self.mu * Fn) ** 2 - (2.0 * m / 7.0) ** 2 * _dot(B, B)
            slip.terminal, slip.direction = True, -1
            return [liftoff, slip], ["liftoff", "slip"]
        if mode == SLIDING:
            def grip(t, s):
                u = self.contact_terms(s)[3]
                return math.sqrt(_dot(u, u)) - GRIP_SPEED
            grip.terminal, grip.direction = True, -1
            return [liftoff, grip], ["liftoff", "grip"]

        def onset(t, s):
            u = self.contact_terms(s)[3]
            return math.sqrt(_dot(u, u)) - ONSET_SPEED
        onset.terminal, onset.direction = True, 1
        return [liftoff, onset], ["liftoff", "onset"]

    def rolling_needs_too_much(self, s):
        _, Fn, B, _, _ = self.contact_terms(s)
        return (2.0 * self.m / 7.0) * math.sqrt(_dot(B, B)) > self.mu * Fn

    # -- the foot and the gap ---------------------------------------------------------------

    def foot(self, c, starts):
        """The closest surface point to c: Newton's method on ∇ ½|c − φ(α)|² from each start;
        the nearest converged foot. Returns (x, y, signed distance)."""
        best = None
        for x, y in starts:
            ok = False
            for _ in range(60):
                f, fx, fy, _, _, _, (fxx, fxy, fyy) = self.land.frame(x, y)
                d0, d1, d2 = c[0] - x, c[1] - y, c[2] - f
                g1, g2 = -(d0 + fx * d2), -(d1 + fy * d2)
                h11 = 1.0 + fx * fx - d2 * fxx
                h12 = fx * fy - d2 * fxy
                h22 = 1.0 + fy * fy - d2 * fyy
                det = h11 * h22 - h12 * h12
                if not det > 0:
                    break
                sx, sy = -(h22 * g1 - h12 * g2) / det, -(h11 * g2 - h12 * g1) / det
                x, y = x + sx, y + sy
                if abs(sx) + abs(sy) < 1e-15 * (1.0 + abs(x) + abs(y)):
                    ok = True
                    break
            if not ok:
                # the last step may stall at round-off: accept if the gradient is tiny
                f, fx, fy, _, _, _, _ = self.land.frame(x, y)
                d0, d1, d2 = c[0] - x, c[1] - y, c[2] - f
                ok = abs(d0 + fx * d2) + abs(d1 + fy * d2) < 1e-13
            if not ok:
                continue
            f, fx, fy, N, _, _, _ = self.land.frame(x, y)
            D = (c[0] - x) * N[0] + (c[1] - y) * N[1] + (c[2] - f) * N[2]
            if best is None or abs(D) < abs(best[2]):
                best = (x, y, D)
        if best is None:
            raise RuntimeError(f"no foot found below {c}")
        return best


# -- a solution: segments in time order -----------------------------------------------------

@dataclass(frozen=True)
class Transition:
    time: float
    kind: str      # slip, grip, liftoff, landing
    x: float
    y: float


@dataclass
class HybridReference:
    times: np.ndarray        # (n,)
    center: np.ndarray       # (n, 3)
    contact: np.ndarray      # (n, 2) contact point; in flight the foot of the centre
    velocity: np.ndarray     # (n, 3) centre velocity
    omega: np.ndarray        # (n, 3)
    mode: np.ndarray         # (n,) rolling, sliding or flying
    transitions: tuple       # of Transition
    t_end: float
    drift: float             # largest |c − C(α)| at the segments' ends (a check of the integration)


class _Solution:
    def __init__(self, model: Model):
        self.model = model
        self.segments = []       # (t0, t1, mode, evaluate(t) -> state (11,))
        self.transitions = []
        self.drift = 0.0


def _centre_of(model, x, y):
    f, _, _, N, _, _, _ = model.land.frame(x, y)
    r = model.r
    return (x + r * N[0], y + r * N[1], f + r * N[2])


def _contact_segment(sol: _Solution, mode, t0, s0, t_end):
    model = sol.model
    return segment(sol, mode, lambda t, s: model.rhs(mode, s), model.events(mode), t0, s0, t_end)


def segment(sol: _Solution, mode, rhs, events, t0, s0, t_end):
    """A stretch of the solution in a contact ``mode`` from s0 at t0, by DOP853 on ``rhs`` (t, s)
    to the first of ``events`` (functions, names) or t_end; returns (t, state there, event name or
    None)."""
    model = sol.model
    funcs, names = events
    res = solve_ivp(rhs, (t0, t_end), s0, method="DOP853", rtol=RTOL, atol=ATOL, dense_output=True, events=funcs)
    if res.status < 0:
        raise RuntimeError(f"{mode} from t = {t0}: {res.message}")
    t1, event = res.t[-1], None
    for name, te in zip(names, res.t_events):
        if len(te) and te[0] <= t1:
            t1, event = te[0], name
    s1 = res.sol(t1) if event else res.y[:, -1]
    dense = res.sol
    sol.segments.append((t0, t1, SLIDING if mode == ONSET else mode, dense))
    c = _centre_of(model, s1[9], s1[10])
    sol.drift = max(sol.drift, math.dist(c, s1[:3]))
    return t1, np.array(s1), event


def _flight(sol: _Solution, t0, s0, t_end):
    """Fly from (c, ċ, ω) at t0; returns (t, state with its foot in s[9:11], landed)."""
    model = sol.model
    g, r = model.g, model.r
    c0, v0, w0 = np.array(s0[:3]), np.array(s0[3:6]), np.array(s0[6:9])
    gvec = np.array([0.0, 0.0, -g])

    def centre(t):
        tau = t - t0
        return c0 + v0 * tau + 0.5 * gvec * tau * tau

    last = [(s0[9], s0[10])]

    def gap(t):
        c = centre(t)
        x, y, D = model.foot(c, [last[0], (c[0], c[1])])
        last[0] = (x, y)
        return D - r

    def state(t):
        tau = t - t0
        c = centre(t)
        x, y, _ = model.foot(c, [last[0], (c[0], c[1])])
        last[0] = (x, y)
        return np.concatenate([c, v0 + gvec * tau, w0, [x, y]])

    landed = first_landing(gap, lambda t: np.linalg.norm(v0 + gvec * (t - t0)), t0, t_end, r, g)
    if landed is not None:
        _check_landing(model, centre(landed), last[0])
    t1 = landed if landed is not None else t_end
    dense = _FlightDense(model, t0, c0, v0, w0, (s0[9], s0[10]))
    sol.segments.append((t0, t1, FLYING, dense))
    s1 = state(t1)
    return t1, s1, landed is not None


def first_landing(gap, speed, t0, t_end, r, g):
    """The first root of a flight's ``gap`` (t) after t0, by brentq, the gap sampled in steps of half
    the gap over the centre's ``speed`` (t); None where there is none before t_end."""
    # clear the surface: the gap grows from 0 (like τ³ after a lift-off, τ after a rebound)
    tau = 1e-6
    while gap(t0 + tau) < 1e-9 * r:
        tau *= 2.0
        if tau > 0.05:
            raise RuntimeError(f"the ball does not leave the surface at t = {t0}")
    t = t0 + tau
    h = gap(t)
    while t < t_end:
        dt = min(max(0.5 * h / (speed(t) + g * 5e-3), 1e-6), 5e-3, t_end - t)
        h1 = gap(t + dt)
        if h1 <= 0.0:
            return brentq(gap, t, t + dt, xtol=1e-16, rtol=1e-15, maxiter=200)
        t, h = t + dt, h1
    return None


def _check_landing(model, c, foot):
    """At a landing the centre is r from the surface, and no surface point is nearer: no point
    of a 41 x 41 grid of surface points around the foot (±2r) is inside the ball."""
    r = model.r
    x, y, D = model.foot(c, [foot, (c[0], c[1])])
    if abs(D - r) > 1e-12 * r:
        raise RuntimeError(f"landing at {c}: the centre is {D} from the surface, not r = {r}")
    grid = np.linspace(-2.0 * r, 2.0 * r, 41)
    for gx in grid:
        for gy in grid:
            px, py = x + gx, y + gy
            d = math.dist(c, (px, py, model.land.f(px, py)))
            if d < r - 1e-9:
                raise RuntimeError(f"landing at {c}: the surface at ({px}, {py}) is nearer ({d}) than r")


class _FlightDense:
    def __init__(self, model, t0, c0, v0, w0, foot):
        self.model, self.t0, self.c0, self.v0, self.w0, self.foot = model, t0, c0, v0, w0, foot

    def __call__(self, t):
        tau = t - self.t0
        gvec = np.array([0.0, 0.0, -self.model.g])
        c = self.c0 + self.v0 * tau + 0.5 * gvec * tau * tau
        x, y, _ = self.model.foot(c, [self.foot, (c[0], c[1])])
        self.foot = (x, y)
        return np.concatenate([c, self.v0 + gvec * tau, self.w0, [x, y]])


def _impact(model: Model, s):
    """The impulse at the contact; returns (state after, stuck, rebounds)."""
    m, r, mu, e = model.m, model.r, model.mu, model.e
    _, _, _, N, _, _, _ = model.land.frame(s[9], s[10])
    N = np.array(N)
    v, w = s[3:6].copy(), s[6:9].copy()
    u = v - r * np.cross(w, N)
    un = float(u @ N)
    ut = u - un * N
    Jn = (1.0 + e) * m * abs(un)
    Jt = -(2.0 / 7.0) * m * ut
    stuck = mu is None or np.linalg.norm(Jt) <= mu * Jn
    if not stuck:
        Jt = -mu * Jn * ut / np.linalg.norm(ut)
    J = Jn * N + Jt
    v = v + J / m
    w = w + (5.0 / (2.0 * m * r * r)) * np.cross(-r * N, J)
    rebounds = e * abs(un) >= math.sqrt(2.0 * model.g * REST_HEIGHT * r)
    if not rebounds:
        v = v - float(v @ N) * N
    out = s.copy()
    out[3:6], out[6:9] = v, w
    return out, stuck, rebounds


# A contact segment's event that changes the mode and nothing else: the mode after it
AFTER = {"liftoff": FLYING, "slip": ONSET, "onset": SLIDING}
RECORDED = ("liftoff", "slip")   # (a slip's onset ends a stretch of the solution, not a transition)


def after(sol: _Solution, event: str, t: float, s) -> str:
    """The mode after ``event`` (one of AFTER's) at t in state s, the transition recorded."""
    if event in RECORDED:
        sol.transitions.append(Transition(t, event, s[9], s[10]))
    return AFTER[event]


def solve(scene_json: str, t_end: float) -> _Solution:
    from rollball import Scene
    scene = Scene.loads(scene_json)
    params = {p.name: p.value for p in scene.parameters}
    land = Landscape(scene.landscape, params)
    ct = scene.contact
    if ct.after_liftoff != "fly":
        raise ValueError("the reference follows after_liftoff 'fly' only")
    model = Model(land, scene.ball.radius, scene.ball.mass, scene.gravity, ct.friction, ct.restitution)
    sol = _Solution(model)
    st, r = scene.start, model.r
    _, fx, fy, N, _, _, _ = land.frame(st.x, st.y)
    v = np.array([st.vx, st.vy, fx * st.vx + fy * st.vy])
    N = np.array(N)
    if st.omega is None:
        w = np.cross(N, v) / r + st.spin * N
    else:
        w = np.array(st.omega, dtype=float)
    s = np.concatenate([_centre_of(model, st.x, st.y), v, w, [st.x, st.y]])
    u = v - r * np.cross(w, N)
    scale = max(np.linalg.norm(v), r * np.linalg.norm(w))
    if model.mu is None or np.linalg.norm(u) <= ROLLING_TOLERANCE * scale:
        mode = ROLLING
        if model.mu is not None and model.rolling_needs_too_much(s):
            mode = ONSET
    else:
        mode = SLIDING
    if model.contact_terms(s)[1] < 0.0:   # F_n < 0: the surface cannot hold the ball, which leaves it at once
        sol.transitions.append(Transition(0.0, "liftoff", st.x, st.y))
        mode = FLYING
    t = 0.0
    while t < t_end:
        if mode == FLYING:
            t, s, landed = _flight(sol, t, s, t_end)
            if not landed:
                break
            sol.transitions.append(Transition(t, "landing", s[9], s[10]))
            s, stuck, rebounds = _impact(model, s)
            if rebounds:
                mode = FLYING
            else:
                s[:3] = _centre_of(model, s[9], s[10])
                mode = ROLLING if stuck else SLIDING
            continue
        t, s, event = _contact_segment(sol, mode, t, s, t_end)
        if event is None:
            break
        if event in AFTER:
            mode = after(sol, event, t, s)
        elif event == "grip":
            # |u| = GRIP_SPEED: extrapolate linearly to |u| = 0 (an error of order GRIP_SPEED²)
            d = np.array(model.rhs(SLIDING, s))
            _, Fn, B, u, _ = model.contact_terms(s)
            size = math.sqrt(_dot(u, u))
            # d|u|/dt = û·u̇, u̇ = B − (7/2) μ (F_n/m) û in the tangent plane
            rate = 3.5 * model.mu * Fn / model.m - _dot(u, B) / size
            delta = size / rate
            s = s + delta * d
            t = t + delta
            if model.rolling_needs_too_much(s):
                mode = ONSET     # the slip turns about and goes on
            else:
                N, _, _, u, _ = model.contact_terms(s)
                s[6:9] += np.cross(N, u) / r   # u = 0 exactly
                sol.transitions.append(Transition(t, "grip", s[9], s[10]))
                mode = ROLLING
    return sol


@functools.lru_cache(maxsize=None)
def _solved(scene_json: str, t_end: float) -> _Solution:
    return solve(scene_json, t_end)


def reference(scene, t_end: float, times) -> HybridReference:
    """The reference motion of ``scene`` (a rollball Scene or its JSON) until ``t_end``, at
    ``times`` (s, within [0, t_end]). At a transition's own time the state before it is given."""
    text = scene if isinstance(scene, str) else scene.dumps()
    return evaluate(_solved(text, float(t_end)), t_end, times)


def states(sol: _Solution, times: np.ndarray) -> tuple[np.ndarray, list]:
    """A solution's states at ``times`` (a row each) and its modes there."""
    rows, modes = [], []
    for t in times:
        for t0, t1, mode, dense in sol.segments:
            if t0 <= t <= t1:
                rows.append(dense(t))
                modes.append(mode)
                break
        else:
            raise ValueError(f"time {t} is outside the reference's run [0, {sol.segments[-1][1]}]")
    return np.array(rows), modes


def evaluate(sol: _Solution, t_end, times) -> HybridReference:
    """A solution (``solve``'s, uncached) at ``times``."""
    times = np.asarray(times, dtype=float)
    rows, modes = states(sol, times)
    return HybridReference(times, rows[:, :3], rows[:, 9:11], rows[:, 3:6], rows[:, 6:9],
                           np.array(modes), tuple(sol.transitions), float(t_end), sol.drift)


if __name__ == "__main__":
    import time
    import sys
    here = __file__.rsplit("/", 1)[0] or "."
    sys.path[:0] = [here + "/..", here]   # this checkout's rollball, and the tests
    from test_hybrid_reference import SCENES
    for name, (scene, t_end) in SCENES.items():
        t0 = time.process_time()
        ref = reference(scene, t_end, [0.0, t_end])
        print(f"{name}: {time.process_time() - t0:.2f} s CPU, drift {ref.drift:.1e} m")
        for tr in ref.transitions:
            print(f"   {tr.kind:8s} t = {tr.time:.15f}  ({tr.x:.12f}, {tr.y:.12f})")
