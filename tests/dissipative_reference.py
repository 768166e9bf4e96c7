"""An independent reference for the hybrid motion with the dissipation of scene version 4: rolling
resistance, spin friction and air (docs/design.md §1, "Dissipation"), in rolling, sliding and
flight, to the rest.

Written from the model's equations, in hybrid_reference.py's formulation (the centre c, ċ, ω and
the contact point α; the contact force F = F_n N + F_t a constraint force), not from RollBall's
kernel, whose rolling state is the angular momentum about the contact point. With F_air = −k|ċ|ċ,
M_rr = −c_rr r |F_n| ω̂_t (ω_t = ω − (ω·N)N) and M_s = −μ_s r |F_n| sign(ω·N) N:

    m c̈ = m g + F + F_air,    (2/5) m r² ω̇ = (−r N) × F + M_rr + M_s,
    F_n from d/dt (ċ·N) = 0:  F_n = m (g₀ N_z − ċ·Ṅ) − F_air·N,
    A = B + P F_air / m + 5/(2 m r) N × M_rr, the slip's acceleration with friction off
    (B = P (g − r ω × Ṅ), P the projection on the tangent plane),
    rolling: F_t = −(2/7) m A;  sliding: F_t = −μ F_n ŝ, ŝ = û (Â from a slip's onset).

The spin couple is static where ω·N is 0: it holds d/dt (ω·N) = 0, M_s = −(2/5) m r² ω·Ṅ (the
pull), while |pull| ≤ μ_s r F_n; beyond, it is kinetic on the pull's side. A sliding ball whose ω_t
is 0 gets the rolling couple against the friction's torque T_f = −r N × F_t (−cap T̂_f where
|T_f| exceeds the cap c_rr r F_n, the ball starting to turn). A rolling ball whose ω_t reaches 0
(|ω_t| r falls to REST_SPEED, extrapolated linearly to 0) stops: held where tan θ ≤ min(c_rr, μ),
it spins in place until spin friction stops that at |ω·N| (2/5) m r² / (μ_s r F_n) later: the
rest. A flight through air is integrated (scipy's DOP853), ω constant; its landing is the first
root of the gap dist(c(t), surface) − r. The state carries the energy each cause took: sliding,
impacts, rolling resistance, spin friction, air.

Every mode is integrated by scipy's DOP853 at hybrid_reference's tolerances, its events on the
dense output. A ball stopped where it is not held, or a sliding ball whose rolling couple would hold
ω_t at 0, is not followed (ValueError): choose scenes without them.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.integrate import solve_ivp

from hybrid_reference import (ATOL, GRIP_SPEED, ONSET_SPEED, ROLLING_TOLERANCE, RTOL, HybridReference, Landscape,
                              Model, Transition, _centre_of, _check_landing, _cross, _dot, _impact, _tangential,
                              AFTER, _Solution, after, first_landing, segment, states)

ROLLING, SLIDING, ONSET, FLYING, RESTING = "rolling", "sliding", "onset", "flying", "resting"
REST_SPEED = 1e-10     # m/s: the stop is located where r |ω_t| falls to this, then extrapolated to 0
TURN_SPEED = 1e-10     # m/s: a sliding ball's r |ω_t| below this turns with the friction's torque
CAUSES = ("sliding", "impacts", "rolling", "spin", "air")   # the quadratures s[11:16]
N_STATE = 16


class DissipativeModel(Model):
    def __init__(self, landscape, radius, mass, gravity, friction, restitution, rolling_resistance, spin_friction,
                 drag):
        super().__init__(landscape, radius, mass, gravity, friction, restitution)
        self.c_rr, self.mu_s, self.k = rolling_resistance, spin_friction, drag

    def terms(self, s):
        """What the right-hand sides need at state s: N, Ṅ, F_n, A without the rolling couple,
        u, α′, ω_t, ω·N, F_air."""
        m, r, g = self.m, self.r, self.g
        v, w, N, Nd, (a1, a2) = self.kinematics(s)
        speed = math.sqrt(_dot(v, v))
        Fa = (-self.k * speed * v[0], -self.k * speed * v[1], -self.k * speed * v[2])
        Fn = m * (g * N[2] - _dot(v, Nd)) - _dot(Fa, N)
        wxNd = _cross(w, Nd)
        q = (-r * wxNd[0] + Fa[0] / m, -r * wxNd[1] + Fa[1] / m, -g - r * wxNd[2] + Fa[2] / m)
        return N, Nd, Fn, _tangential(q, N), self.slip(v, w, N), (a1, a2), _tangential(w, N), _dot(w, N), Fa, speed

    def rolling_couple(self, Fn, wt):
        size = math.sqrt(_dot(wt, wt))
        if size == 0.0:
            return 0.0, 0.0, 0.0
        c = -self.c_rr * self.r * abs(Fn) / size
        return c * wt[0], c * wt[1], c * wt[2]

    def spin_pull(self, w, Nd):
        """The static spin couple's pull: (2/5) m r² ω·Ṅ (d/dt (ω·N) without the couple)."""
        return 0.4 * self.m * self.r * self.r * _dot(w, Nd)

    def rolling_force(self, s, t=None):
        """F_t a rolling ball needs (with the couples), F_n, A with the rolling couple, and that
        couple. Where ω_t is 0 the couple is against the pull, the rate ω_t would have without it
        (−cap along it where it exceeds the cap: the ball starts to turn; a still ball it holds is
        not followed here)."""
        N, Nd, Fn, A, u, _, wt, on, Fa, _ = t or self.terms(s)
        M = self.rolling_couple(Fn, wt)
        if M == (0.0, 0.0, 0.0) and self.c_rr > 0.0:
            f = -2.0 * self.m / 7.0
            F = (Fn * N[0] + f * A[0], Fn * N[1] + f * A[1], Fn * N[2] + f * A[2])
            pull = _cross(N, F)   # ω̇ without the couple is along −N × F; its tangential part
            pn = _dot(pull, N)
            pull = (-(pull[0] - pn * N[0]), -(pull[1] - pn * N[1]), -(pull[2] - pn * N[2]))
            size = math.sqrt(_dot(pull, pull))
            if size > 0.0:
                # |q| = (7/5) m r² |ω̇_t| = (7/5) m r² (5 / (2 m r²)) r |pull| = 3.5 r |pull|
                if 3.5 * self.r * size <= self.c_rr * self.r * abs(Fn):
                    raise ValueError("a still ball held by the rolling couple: not followed here")
                c = -self.c_rr * self.r * abs(Fn) / size
                M = (c * pull[0], c * pull[1], c * pull[2])
        NxM = _cross(N, M)
        k = 2.5 / (self.m * self.r)
        A = (A[0] + k * NxM[0], A[1] + k * NxM[1], A[2] + k * NxM[2])
        f = -2.0 * self.m / 7.0
        return (f * A[0], f * A[1], f * A[2]), Fn, A, M

    def rolling_needs_too_much(self, s):
        Ft, Fn, _, _ = self.rolling_force(s)
        return math.sqrt(_dot(Ft, Ft)) > self.mu * Fn

    def rhs(self, mode, spin, s):
        """mode ROLLING, SLIDING or ONSET; spin: the spin couple's side (±1), or 0 static."""
        m, r = self.m, self.r
        terms = self.terms(s)
        N, Nd, Fn, A, u, (a1, a2), wt, on, Fa, speed = terms
        w = (s[6], s[7], s[8])
        slide = 0.0
        if mode == ROLLING:
            Ft, _, _, M = self.rolling_force(s, terms)
        else:
            if mode == SLIDING:
                d = u
            else:
                M0 = self.rolling_couple(Fn, wt)
                NxM = _cross(N, M0)
                k = 2.5 / (m * r)
                d = (A[0] + k * NxM[0], A[1] + k * NxM[1], A[2] + k * NxM[2])
            size = math.sqrt(_dot(d, d))
            f = -self.mu * Fn / size
            Ft = (f * d[0], f * d[1], f * d[2])
            slide = self.mu * Fn * _dot(u, d) / size
            if r * math.sqrt(_dot(wt, wt)) > TURN_SPEED:
                M = self.rolling_couple(Fn, wt)
            else:   # ω_t at 0: the couple against the friction's torque
                Tf = _cross(N, Ft)
                Tf = (-r * Tf[0], -r * Tf[1], -r * Tf[2])
                size, cap = math.sqrt(_dot(Tf, Tf)), self.c_rr * r * abs(Fn)
                if size <= cap and size > 0.0:
                    raise ValueError("a sliding ball's rolling couple holds ω_t at 0: not followed here")
                M = (-cap * Tf[0] / size, -cap * Tf[1] / size, -cap * Tf[2] / size) if size else (0.0, 0.0, 0.0)
        if spin:
            Ms = -self.mu_s * r * abs(Fn) * spin
        else:
            Ms = -self.spin_pull(w, Nd)
        F = (Fn * N[0] + Ft[0], Fn * N[1] + Ft[1], Fn * N[2] + Ft[2])
        NxF = _cross(N, F)
        kw = 2.5 / (m * r * r)
        wd = [kw * (-r * NxF[q] + M[q] + Ms * N[q]) for q in range(3)]
        return [s[3], s[4], s[5], (F[0] + Fa[0]) / m, (F[1] + Fa[1]) / m, (F[2] + Fa[2]) / m - self.g,
                wd[0], wd[1], wd[2], a1, a2,
                slide, 0.0, -_dot(M, w), -Ms * on, self.k * speed ** 3]

    def spin_side(self, s, at_zero=False):
        """The spin couple's side at s: sign(ω·N), or where that is 0 (``at_zero``: there, up to
        round-off) the pull's sign beyond the static couple's limit, else 0 (static)."""
        N, Nd, Fn, _, _, _, _, on, _, _ = self.terms(s)
        if on != 0.0 and not at_zero:
            return 1.0 if on > 0.0 else -1.0
        pull = self.spin_pull((s[6], s[7], s[8]), Nd)
        if abs(pull) > self.mu_s * self.r * abs(Fn):
            return 1.0 if pull > 0.0 else -1.0
        return 0.0

    def dissipative_events(self, mode, spin):
        r = self.r
        events, names = [], []

        def liftoff(t, s):
            return self.terms(s)[2]
        liftoff.terminal, liftoff.direction = True, -1
        events.append(liftoff), names.append("liftoff")
        if mode == ROLLING:
            def slip(t, s):
                Ft, Fn, _, _ = self.rolling_force(s)
                return (self.mu * Fn) ** 2 - _dot(Ft, Ft)
            slip.terminal, slip.direction = True, -1
            events.append(slip), names.append("slip")
            if self.c_rr > 0.0:
                def stop(t, s):
                    wt = self.terms(s)[6]
                    return r * math.sqrt(_dot(wt, wt)) - REST_SPEED
                stop.terminal, stop.direction = True, -1
                events.append(stop), names.append("stop")
        elif mode == SLIDING:
            def grip(t, s):
                u = self.terms(s)[4]
                return math.sqrt(_dot(u, u)) - GRIP_SPEED
            grip.terminal, grip.direction = True, -1
            events.append(grip), names.append("grip")
        else:
            def onset(t, s):
                u = self.terms(s)[4]
                return math.sqrt(_dot(u, u)) - ONSET_SPEED
            onset.terminal, onset.direction = True, 1
            events.append(onset), names.append("onset")
        if self.mu_s > 0.0:
            if spin:
                def spin_zero(t, s):
                    return self.terms(s)[7]
                spin_zero.terminal, spin_zero.direction = True, -spin
                events.append(spin_zero), names.append("spin_zero")
            else:
                def spin_free(t, s):
                    N, Nd, Fn, _, _, _, _, _, _, _ = self.terms(s)
                    return self.spin_pull((s[6], s[7], s[8]), Nd) ** 2 - (self.mu_s * r * Fn) ** 2
                spin_free.terminal, spin_free.direction = True, 1
                events.append(spin_free), names.append("spin_free")
        return events, names


def _segment(sol, mode, spin, t0, s0, t_end):
    model = sol.model
    return segment(sol, mode, lambda t, s: model.rhs(mode, spin, s), model.dissipative_events(mode, spin), t0, s0,
                   t_end)


class _Still:
    """A ball held where it stopped, spinning down in place: its state at t."""

    def __init__(self, model, t0, s0, rate):
        self.model, self.t0, self.s0, self.rate = model, t0, s0, rate

    def __call__(self, t):
        s = self.s0.copy()
        N = np.array(self.model.land.frame(s[9], s[10])[3])
        on = float(s[6:9] @ N)
        left = max(0.0, abs(on) - self.rate * (t - self.t0))
        s[6:9] = math.copysign(left, on) * N
        s[14] += 0.2 * self.model.m * self.model.r ** 2 * (on * on - left * left)
        return s


def _flight(sol, t0, s0, t_end):
    """Fly from s0 at t0 through air (k > 0) or vacuum; returns (t, state with its foot, landed)."""
    model = sol.model
    g, r, m, k = model.g, model.r, model.m, model.k

    def motion(t, y):
        v = y[3:6]
        speed = math.sqrt(float(v @ v))
        a = -k * speed * v / m
        return [v[0], v[1], v[2], a[0], a[1], a[2] - g, k * speed ** 3]

    y0 = np.concatenate([s0[:6], [s0[15]]])
    horizon = t_end
    res = solve_ivp(motion, (t0, horizon), y0, method="DOP853", rtol=RTOL, atol=ATOL, dense_output=True)
    path = res.sol
    last = [(s0[9], s0[10])]

    def gap(t):
        c = path(t)[:3]
        x, y, D = model.foot(c, [last[0], (c[0], c[1])])
        last[0] = (x, y)
        return D - r

    def state(t):
        y = path(t)
        c = y[:3]
        x, yy, _ = model.foot(c, [last[0], (c[0], c[1])])
        last[0] = (x, yy)
        s = s0.copy()
        s[:6], s[9], s[10], s[15] = y[:6], x, yy, y[6]
        return s

    landed = first_landing(gap, lambda t: np.linalg.norm(path(t)[3:6]), t0, t_end, r, g)
    if landed is not None:
        _check_landing(model, path(landed)[:3], last[0])
    t1 = landed if landed is not None else t_end
    sol.segments.append((t0, t1, FLYING, state))
    return t1, state(t1), landed is not None


def _kinetic(model, s):
    N = np.array(model.land.frame(s[9], s[10])[3])
    return 0.5 * model.m * float(s[3:6] @ s[3:6]) + 0.2 * model.m * model.r ** 2 * float(s[6:9] @ s[6:9]), N


def solve(scene_json: str, t_end: float) -> _Solution:
    from rollball import Scene
    scene = Scene.loads(scene_json)
    params = {p.name: p.value for p in scene.parameters}
    land = Landscape(scene.landscape, params)
    ct, r = scene.contact, scene.ball.radius
    if ct.after_liftoff != "fly" or ct.friction is None:
        raise ValueError("the reference follows a finite friction and after_liftoff 'fly' only")
    model = DissipativeModel(land, r, scene.ball.mass, scene.gravity, ct.friction, ct.restitution,
                             ct.rolling_resistance, ct.spin_friction, scene.air.drag_factor(r))
    sol = _Solution(model)
    st = scene.start
    _, fx, fy, N, _, _, _ = land.frame(st.x, st.y)
    v = np.array([st.vx, st.vy, fx * st.vx + fy * st.vy])
    N = np.array(N)
    w = np.cross(N, v) / r + st.spin * N if st.omega is None else np.array(st.omega, dtype=float)
    s = np.concatenate([_centre_of(model, st.x, st.y), v, w, [st.x, st.y], np.zeros(5)])
    u = v - r * np.cross(w, N)
    scale = max(np.linalg.norm(v), r * np.linalg.norm(w))
    if np.linalg.norm(u) <= ROLLING_TOLERANCE * scale:
        mode = ONSET if model.rolling_needs_too_much(s) else ROLLING
    else:
        mode = SLIDING
    if abs(float(w @ N)) * r <= 1e-13 * max(scale, math.sqrt(model.g * r)):
        s[6:9] -= float(w @ N) * N   # no spin: the static spin couple's
    t, spin = 0.0, None
    while t < t_end:
        if mode == FLYING:
            t, s, landed = _flight(sol, t, s, t_end)
            if not landed:
                break
            sol.transitions.append(Transition(t, "landing", s[9], s[10]))
            before, _ = _kinetic(model, s)
            s, stuck, rebounds = _impact(model, s)
            s[12] += before - _kinetic(model, s)[0]
            spin = None
            if not rebounds:
                s[:3] = _centre_of(model, s[9], s[10])
                mode = ROLLING if stuck else SLIDING
            continue
        if spin is None:
            spin = model.spin_side(s)
        t, s, event = _segment(sol, mode, spin, t, s, t_end)
        if event is None:
            break
        N = np.array(model.land.frame(s[9], s[10])[3])
        if event in AFTER:
            mode = after(sol, event, t, s)
        elif event == "spin_zero":
            s[6:9] -= float(s[6:9] @ N) * N    # ω·N = 0: the side is decided anew, by the pull
            spin = model.spin_side(s, at_zero=True)
        elif event == "spin_free":   # the pull at the static couple's limit: kinetic on its side
            spin = math.copysign(1.0, model.spin_pull(s[6:9], model.terms(s)[1]))
        elif event == "grip":
            d = np.array(model.rhs(SLIDING, spin, s))
            _, _, Fn, A, u, _, wt, _, _, _ = model.terms(s)
            M = model.rolling_couple(Fn, wt)
            NxM = _cross(N, M)
            A = np.array(A) + 2.5 / (model.m * r) * np.array(NxM)
            size = math.sqrt(_dot(u, u))
            rate = 3.5 * model.mu * Fn / model.m - float(np.dot(u, A)) / size
            delta = size / rate
            s, t = s + delta * d, t + delta
            if model.rolling_needs_too_much(s):
                mode = ONSET
            else:
                u = np.array(model.terms(s)[4])
                s[6:9] += np.cross(N, u) / r
                sol.transitions.append(Transition(t, "grip", s[9], s[10]))
                mode = ROLLING
        elif event == "stop":
            d = np.array(model.rhs(ROLLING, spin, s))
            wt = np.array(model.terms(s)[6])
            size = float(np.linalg.norm(wt))
            rate = -float(wt @ model.terms(s + 1e-9 * d)[6] - wt @ wt) / (1e-9 * size)   # −d|ω_t|/dt
            delta = size / rate if rate > 0.0 else 0.0
            s, t = s + delta * d, t + delta
            s[6:9] = float(s[6:9] @ N) * N
            s[3:6] = 0.0
            tan = math.hypot(N[0], N[1]) / N[2]
            if not tan <= min(model.c_rr, model.mu):
                raise ValueError(f"the ball stops at t = {t} where it is not held: not followed here")
            on = float(s[6:9] @ N)
            Fn = model.m * model.g * N[2]
            rate = 2.5 * model.mu_s * Fn / (model.m * r)
            stop = t + (abs(on) / rate if on else 0.0) if rate > 0.0 or not on else math.inf
            sol.segments.append((t, max(t_end, stop), RESTING, _Still(model, t, s, rate)))
            if stop <= t_end:
                sol.transitions.append(Transition(stop, "rest", s[9], s[10]))
            break
    return sol


@functools.lru_cache(maxsize=None)
def _solved(scene_json: str, t_end: float) -> _Solution:
    return solve(scene_json, t_end)


def reference(scene, t_end: float, times) -> tuple[HybridReference, np.ndarray]:
    """The reference motion of ``scene`` until ``t_end`` (or its rest) at ``times``, and the energy
    each cause took (len(times), 5: CAUSES)."""
    text = scene if isinstance(scene, str) else scene.dumps()
    sol = _solved(text, float(t_end))
    times = np.asarray(times, dtype=float)
    rows, modes = states(sol, times)
    ref = HybridReference(times, rows[:, :3], rows[:, 9:11], rows[:, 3:6], rows[:, 6:9], np.array(modes),
                          tuple(sol.transitions), float(t_end), sol.drift)
    return ref, rows[:, 11:16]
