"""The physics of one state: the landscape at the contact point, the reduced equations of
motion (``dynamics``, docs/design.md §1), the exact inverse of dexp on so(3), the principal curvatures,
the Rodrigues formula, and the finiteness checks every step makes."""

from __future__ import annotations

import math

from .interface import (
    D_SIDE, D_SLIP, MK_SIZE, MOTION_SIZE, PROBE_FORCE, PROBE_NEED, PROBE_SIZE, PROBE_SLIP, PROBE_SLIP_PULL,
    PROBE_SPIN_PULL, P_AIR, P_FLY, P_MU, P_RESISTANCE, P_SPIN, P_TURN, P_UNIT, RESISTED_CLASSIC_SIZE, RESISTED_MK_SIZE,
    SLIDING_CLASSIC_SIZE, SLIDING_MK_SIZE, SLIDING_MOTION_SIZE, SLIDING_RESISTED_CLASSIC_SIZE, SLIDING_RESISTED_MK_SIZE)
from .lowlevel import COLD, EXACT, JIT, STEP, data_pointer, landscape


# What ``dynamics`` computes: the stage derivative alone, or also the probe. Floats, like mk
# there (1.0 Munthe-Kaas): numba would compile it anew for every constant bool passed.
STAGE, FULL = 0.0, 1.0


@STEP
def dynamics(fn, d, p, z, mk, K, row, probe, full):
    """K[row] = z'(z); with ``full`` (FULL) also fill ``probe`` (normal, omega, F.N, r*kappa,
    height). Compiled once (numba's inlining copied it into every caller), inlined by LLVM."""
    r, k, mr, mr2, mg = p[0], p[3], p[4], p[5], p[6]
    landscape(fn, z[0], z[1], data_pointer(d))
    fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
    W2 = 1.0 + fx * fx + fy * fy
    iW = 1.0 / math.sqrt(W2)  # one division, then products
    n1, n2, n3 = -fx * iW, -fy * iW, iW
    v1, v2, v3 = z[2], z[3], z[4]
    # omega = T^-1 v, T^-1 = 5/(7 m r^2) (I + 5/2 N N^T)
    nv = 2.5 * (n1 * v1 + n2 * v2 + n3 * v3)
    o1, o2, o3 = k * (v1 + nv * n1), k * (v2 + nv * n2), k * (v3 + nv * n3)
    a1, a2, d1, d2, d3, w1, w2, w3 = rolling_rates(r, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, o1, o2, o3)
    K[row, 0] = a1
    K[row, 1] = a2
    K[row, 2] = -mg * r * n2 + mr2 * (d2 * w3 - d3 * w2)
    K[row, 3] = mg * r * n1 + mr2 * (d3 * w1 - d1 * w3)
    K[row, 4] = mr2 * (d1 * w2 - d2 * w1)
    n = K.shape[1]
    m1, m2, m3 = 0.0, 0.0, 0.0   # the rolling resistance's couple (for the friction rolling needs)
    pull = 0.0   # the pull on v.N (``rolling_couples``)
    if resisted_size(n):
        m1, m2, m3, pull = rolling_losses(p, d, K, row, n, n1, n2, n3, o1, o2, o3, v1, v2, v3, d1, d2, d3, w1, w2, w3)
    if n == MOTION_SIZE:  # no orientation carried
        pass
    elif mk != 0.0 and p[P_TURN] > 0.0:
        # omega' = k (v' + nv' N + nv N'), N' = d: omega carried as a quadrature of the motion
        e1, e2, e3 = K[row, 2], K[row, 3], K[row, 4]
        nve = 2.5 * (d1 * v1 + d2 * v2 + d3 * v3 + n1 * e1 + n2 * e2 + n3 * e3)
        K[row, 5] = k * (e1 + nve * n1 + nv * d1)
        K[row, 6] = k * (e2 + nve * n2 + nv * d2)
        K[row, 7] = k * (e3 + nve * n3 + nv * d3)
    elif mk != 0.0:
        K[row, 5], K[row, 6], K[row, 7] = dexpinv(z[5], z[6], z[7], o1, o2, o3)
    else:
        rotation_rate(z, K, row, 5, o1, o2, o3)
    if full != 0.0:
        probe[0], probe[1], probe[2] = n1, n2, n3
        probe[3], probe[4], probe[5] = o1, o2, o3
        # F.N = m (c'' - g).N with c''.N = r (omega x N').N
        probe[6] = mr * ((o2 * d3 - o3 * d2) * n1 + (o3 * d1 - o1 * d3) * n2
                         + (o1 * d2 - o2 * d1) * n3) + mg * n3
        hi, lo = curvatures(fx, fy, fxx, fxy, fyy, iW)
        probe[7] = r * hi
        probe[8] = d[0]
        probe[9] = r * lo
        need = 0.0
        if p[P_MU] < math.inf:  # (the 2011 model never asks)
            t1, t2, t3 = friction_needed(p, n1, n2, n3, o1, o2, o3, d1, d2, d3, v1, v2, v3, K[row, 2],
                                         K[row, 3], K[row, 4], m1, m2, m3)
            need = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
        probe[PROBE_NEED] = need
        probe[PROBE_SLIP], probe[PROBE_SLIP + 1], probe[PROBE_SLIP + 2] = 0.0, 0.0, 0.0
        probe[PROBE_SPIN_PULL] = pull
        probe[PROBE_SLIP_PULL], probe[PROBE_SLIP_PULL + 1], probe[PROBE_SLIP_PULL + 2] = 0.0, 0.0, 0.0


@JIT
def resisted_size(n):
    """Whether a state of length n carries the quadratures of the dissipation (``interface``)."""
    return (n == RESISTED_MK_SIZE or n == RESISTED_CLASSIC_SIZE or n == SLIDING_RESISTED_MK_SIZE
            or n == SLIDING_RESISTED_CLASSIC_SIZE)


# A couple's side counts as zero at a state (the couple static, ``couple_sides``) where the couple
# would stop it within this fraction of the ball's time unit sqrt(r / g0): far below any step, far
# above what is left of it where a step located its zero (``loops.resume``).
SIDE_ZERO = 1e-9


@JIT
def couple_sides(p, fn_, n1, n2, n3, o1, o2, o3, inertia):
    """The couples' sides at a state with normal N, omega and F.N = fn_: omega's tangential part (3)
    and the sign of omega.N, each zero where its couple would stop it within SIDE_ZERO of the ball's
    time unit (the couple is then static: what holds it at 0, up to its limit). ``inertia``: the
    moment the rolling resistance turns, over m r² (7/5 rolling, about the contact point; 2/5
    sliding). What a step keeps (``loops.couple_reference``), what a run starts with
    (``recording.start``) and what the friction rolling needs is taken with (``rolling_need``)."""
    on = o1 * n1 + o2 * n2 + o3 * n3
    t1, t2, t3 = o1 - on * n1, o2 - on * n2, o3 - on * n3
    force = abs(fn_) * SIDE_ZERO * p[P_UNIT] / p[4]   # r F_n SIDE_ZERO sqrt(r / g0) / (m r^2)
    # (the couples' largest rates of omega: c r F_n / I)
    turning = force * p[P_RESISTANCE] / inertia
    spinning = force * p[P_SPIN] * 2.5   # (I = 0.4 m r^2)
    if not t1 * t1 + t2 * t2 + t3 * t3 > turning * turning:
        t1, t2, t3 = 0.0, 0.0, 0.0
    side = 0.0
    if abs(on) > spinning:
        side = 1.0 if on > 0.0 else -1.0
    return t1, t2, t3, side


# A rolling ball's omega_t turns its direction at the rate |omega_t'_perp| / |omega_t|, which grows
# without bound as omega_t passes close to 0 at a turning point or a sideways stop (``turning_point``).
# A fixed step's error keeps its order only where that rate is bounded independently of the step:
# a rate above 1 / (TURN_TIME sqrt(r/g)) is stiff for a fixed step, whatever the step.
TURN_TIME = 1.0


@JIT
def turning_point(t1, t2, t3, r1, r2, r3, cap, unit, h):
    """Whether omega_t = t, changing at the rate r, turns its direction too fast for a fixed step of
    h within the step ahead (docs/design.md §1, "Dissipation"): on the line t + r tau the
    direction's rate |r x t| / |t + r tau|^2, at its greatest within the step (where the line comes
    closest to 0), exceeds 1 / (TURN_TIME ``unit``), ``unit`` = sqrt(r / g0) (with no gravity, unit
    is inf: never; nor is there a rolling couple then but on a curve). So it
    does where the ball turns about at a turning point (the pull beats the rolling couple, whose
    rate is ``cap``, C = c_rr r F_n / (7/5 m r^2)) and where it comes to a stop while pulled
    sideways (the path curving ever faster as the speed falls). A line through 0 itself (closer
    than ``couple_sides`` tells from 0) is a stop or a reversal along a line, which the rest's event
    places."""
    rate2 = r1 * r1 + r2 * r2 + r3 * r3
    if not (t1 * t1 + t2 * t2 + t3 * t3 > 0.0 and rate2 > 0.0 and unit < math.inf):
        return False
    tau = min(h, max(0.0, -(t1 * r1 + t2 * r2 + t3 * r3) / rate2))
    m1, m2, m3 = t1 + r1 * tau, t2 + r2 * tau, t3 + r3 * tau
    miss = m1 * m1 + m2 * m2 + m3 * m3
    zero = cap * SIDE_ZERO * unit
    if not zero * zero < miss:
        return False
    c1, c2, c3 = r2 * t3 - r3 * t2, r3 * t1 - r1 * t3, r1 * t2 - r2 * t1
    return math.sqrt(c1 * c1 + c2 * c2 + c3 * c3) * TURN_TIME * unit > miss


@JIT
def rolling_couple(cap, t1, t2, t3, r1, r2, r3, q1, q2, q3, ts):
    """The rolling resistance's couple for omega's tangential part t, at most ``cap`` = c_rr r F_n
    (docs/design.md §1, "Dissipation"): -cap t/|t|, kept on the side of r (omega_t at the step's
    start, ``couple_sides``: past its zero inside the step the couple goes on smoothly, and the zero
    is located on the step's dense output); where r is zero (the ball does not roll at the step's
    start), the static couple -q that holds omega_t at 0 against the pull q (the rate the angular
    momentum's tangential part would have without the couple), or where q exceeds cap the ball starts
    to roll the way it is pulled: -cap q/|q| at omega_t = 0, -cap t/|t| where t (along q) is not.
    ``ts``: |t| where the caller has it (the air's
    speed reads it), else negative (taken here where it is needed)."""
    if r1 != 0.0 or r2 != 0.0 or r3 != 0.0:
        if ts < 0.0:
            ts = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
        if ts == 0.0:
            return 0.0, 0.0, 0.0
        c = -cap / (ts if t1 * r1 + t2 * r2 + t3 * r3 >= 0.0 else -ts)   # (one division)
        return c * t1, c * t2, c * t3
    qs = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
    if qs <= cap:
        return -q1, -q2, -q3
    # the ball starts to turn the way it is pulled: against its own omega_t once that is not 0 (inside
    # the step: its direction relaxes from the pull's, as a starting slip's does), along the pull at 0
    if ts < 0.0:
        ts = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
    if ts > 0.0 and t1 * q1 + t2 * q2 + t3 * q3 > 0.0:
        c = -cap / ts
        return c * t1, c * t2, c * t3
    return -cap * q1 / qs, -cap * q2 / qs, -cap * q3 / qs


@JIT
def spin_couple(cap, side, pull):
    """The spin friction's couple along N, at most ``cap`` = mu_s r F_n: -cap sign(omega.N) with the
    sign ``side`` at the step's start (``couple_sides``, kept through the step like the rolling
    resistance's side); where that is 0 (no spin at the step's start) the static couple -pull that
    holds omega.N at 0, at most cap."""
    if side != 0.0:
        return -cap * side
    return -max(-cap, min(cap, pull))


@JIT
def spin_excess(p, pe):
    """How far the pull on omega.N (probe pe; a rolling ball's on v.N) exceeds what the static spin couple can
    hold, |pull| - mu_s r F_n (``spin_couple``'s cap, F_n as ``rolling_losses`` takes it): where it
    reaches 0 inside a step whose spin couple is static, the couple's law has a kink (static to
    kinetic), which is located on the step's dense output (``events.locate_transition``)."""
    return abs(pe[PROBE_SPIN_PULL]) - spin_limit(p, pe[PROBE_FORCE])


@JIT
def spin_limit(p, fn_):
    """The spin couple's limit mu_s r F_n for F.N = fn_ (|F.N|; F.N where the ball flies, as
    ``rolling_losses`` takes it)."""
    return p[P_SPIN] * p[0] * (fn_ if p[P_FLY] != 0.0 else abs(fn_))


@JIT
def spin_side(p, n, pe, side):
    """The spin couple's side for a step from a state of length n with probe pe: ``side``
    (``couple_sides``'), or, where that is 0 on a ball whose pull on omega.N is at the
    static couple's limit or beyond (``spin_excess``), the pull's sign: the kinetic couple, the
    ball starting to spin the way it is pulled (docs/design.md §1, "Dissipation")."""
    pull = pe[PROBE_SPIN_PULL]
    if side == 0.0 and p[P_SPIN] > 0.0 and pull != 0.0 and spin_excess(p, pe) >= 0.0:
        return 1.0 if pull > 0.0 else -1.0
    return side


@JIT
def rolling_force(mr, mg, n1, n2, n3, o1, o2, o3, d1, d2, d3):
    """F.N of a rolling ball: m (c'' - g).N with c''.N = r (omega x N' alpha').N, N' alpha' = d."""
    return mr * ((o2 * d3 - o3 * d2) * n1 + (o3 * d1 - o1 * d3) * n2 + (o1 * d2 - o2 * d1) * n3) + mg * n3


@JIT
def rolling_couples(p, fa, s1, s2, s3, spin_side, n1, n2, n3, o1, o2, o3, v1, v2, v3, d1, d2, d3, w1, w2, w3, e1, e2,
                    e3):
    """A rolling ball's v' = e with the couples of rolling resistance and spin friction and the
    moment r N x F_air of the air's drag about the contact point added (docs/design.md §1,
    "Dissipation"), for |F.N| = fa and the couples' sides s (omega_t's) and ``spin_side``
    (``couple_sides``). Returns that v' (3), the rolling resistance's couple (3), the spin
    friction's (along N), omega.N, the centre's speed (0 without air, whose work alone reads it)
    and the pull on v.N (the rate v.N would have without spin friction, = (2/5) m r² times that of
    omega.N)."""
    r, k = p[0], p[P_AIR]
    on = o1 * n1 + o2 * n2 + o3 * n3
    t1, t2, t3 = o1 - on * n1, o2 - on * n2, o3 - on * n3   # omega's tangential part, N x (omega x N) = N x w
    # the air: F = -k |c'| c', c' = r omega x N = r w; its moment about the contact point r N x F = -k |c'| r² t
    speed, ts = 0.0, -1.0
    if k != 0.0:   # (no air: nothing to add)
        ts = math.sqrt(w1 * w1 + w2 * w2 + w3 * w3)   # |omega x N| = |omega_t|: the rolling couple's too
        speed = r * ts
        a = -k * speed * r * r
        e1, e2, e3 = e1 + a * t1, e2 + a * t2, e3 + a * t3
    # spin friction: the pull on omega.N is that on v.N, (v.N)' = v'.N + v.N'
    pull = e1 * n1 + e2 * n2 + e3 * n3 + v1 * d1 + v2 * d2 + v3 * d3
    ms = spin_couple(p[P_SPIN] * r * fa, spin_side, pull)
    e1, e2, e3 = e1 + ms * n1, e2 + ms * n2, e3 + ms * n3
    # rolling resistance against omega's tangential part, pulled (where it has no side: static) by v''s
    m1, m2, m3 = 0.0, 0.0, 0.0
    if p[P_RESISTANCE] != 0.0:   # (none: a couple of 0)
        cap = p[P_RESISTANCE] * r * fa
        if s1 != 0.0 or s2 != 0.0 or s3 != 0.0:   # (the pull unread: not taken)
            m1, m2, m3 = rolling_couple(cap, t1, t2, t3, s1, s2, s3, 0.0, 0.0, 0.0, ts)
        else:
            en = e1 * n1 + e2 * n2 + e3 * n3
            m1, m2, m3 = rolling_couple(cap, t1, t2, t3, s1, s2, s3, e1 - en * n1, e2 - en * n2, e3 - en * n3, ts)
    return e1 + m1, e2 + m2, e3 + m3, m1, m2, m3, ms, on, speed, pull


@JIT
def rolling_losses(p, d, K, row, n, n1, n2, n3, o1, o2, o3, v1, v2, v3, d1, d2, d3, w1, w2, w3):
    """Add to the rolling ball's v' = K[row, 2:5] the couples of rolling resistance and spin
    friction and the moment of the air's drag (``rolling_couples``, on the sides of the step's start
    in d[D_SIDE:D_SIDE + 4]), and write the rates of the energy each takes into K[row, n - 3:n]:
    -M_rr.omega, -M_s.omega and k |c'|^3 (docs/design.md §1, "Dissipation"). Returns the rolling
    resistance's couple and the pull on v.N."""
    fn_ = rolling_force(p[4], p[6], n1, n2, n3, o1, o2, o3, d1, d2, d3)
    fa = fn_ if p[P_FLY] != 0.0 else abs(fn_)   # (as the sliding friction's: smooth through F.N = 0 where it flies)
    e1, e2, e3, m1, m2, m3, ms, on, speed, pull = rolling_couples(
        p, fa, d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2], d[D_SIDE + 3], n1, n2, n3, o1, o2, o3, v1, v2, v3, d1, d2, d3,
        w1, w2, w3, K[row, 2], K[row, 3], K[row, 4])
    K[row, 2], K[row, 3], K[row, 4] = e1, e2, e3
    K[row, n - 3] = -(m1 * o1 + m2 * o2 + m3 * o3)
    # (a static couple that holds omega.N at 0 does no work: what the integration leaves of omega.N
    # there is its error, on which the couple's work would have either sign)
    K[row, n - 2] = 0.0 if d[D_SIDE + 3] == 0.0 and ms == -pull else -ms * on
    K[row, n - 1] = p[P_AIR] * speed * speed * speed
    return m1, m2, m3, pull


@JIT
def rotation_rate(z, K, row, base, o1, o2, o3):
    """The classic scheme's R' = A(omega) R, column by column, for R carried row-major in
    z[base:base + 9] (rolling and sliding states alike)."""
    for j in range(3):
        q1, q2, q3 = z[base + j], z[base + 3 + j], z[base + 6 + j]
        K[row, base + j] = o2 * q3 - o3 * q2
        K[row, base + 3 + j] = o3 * q1 - o1 * q3
        K[row, base + 6 + j] = o1 * q2 - o2 * q1


@JIT
def copy_state(n, z, R, probe, z_to, R_to, probe_to):
    """z_to[:n], R_to, probe_to = z[:n], R, probe: a state, its orientation and its probe."""
    for q in range(n):
        z_to[q] = z[q]
    for a in range(3):
        for c in range(3):
            R_to[a, c] = R[a, c]
    for q in range(PROBE_SIZE):
        probe_to[q] = probe[q]


@JIT
def frame(r, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3):
    """The surface at a contact point with slopes fx, fy, curvatures fxx, fxy, fyy,
    iW = 1 / sqrt(1 + fx² + fy²) and normal N: the columns of N' (dN/dx, dN/dy) and of the
    centre's Jacobian C' = phi' + r N', and the metric E = C'^T C' with 1 / det E."""
    # N' columns: dN/dx = (n_x - N (N . n_x)) / W with n = (-f_x, -f_y, 1)
    s = n1 * fxx + n2 * fxy
    Nx1, Nx2, Nx3 = (n1 * s - fxx) * iW, (n2 * s - fxy) * iW, n3 * s * iW
    s = n1 * fxy + n2 * fyy
    Ny1, Ny2, Ny3 = (n1 * s - fxy) * iW, (n2 * s - fyy) * iW, n3 * s * iW
    # C' = phi' + r N', E = C'^T C'
    Cx1, Cx2, Cx3 = 1.0 + r * Nx1, r * Nx2, fx + r * Nx3
    Cy1, Cy2, Cy3 = r * Ny1, 1.0 + r * Ny2, fy + r * Ny3
    E11 = Cx1 * Cx1 + Cx2 * Cx2 + Cx3 * Cx3
    E12 = Cx1 * Cy1 + Cx2 * Cy2 + Cx3 * Cy3
    E22 = Cy1 * Cy1 + Cy2 * Cy2 + Cy3 * Cy3
    idet = 1.0 / (E11 * E22 - E12 * E12)
    return Nx1, Nx2, Nx3, Ny1, Ny2, Ny3, Cx1, Cx2, Cx3, Cy1, Cy2, Cy3, E11, E12, E22, idet


@JIT
def rolling_rates(r, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, o1, o2, o3):
    """The rolling ball's alpha' (2) and N' alpha' (3), and omega x N (3), at a contact point
    (``frame``'s arguments) for the angular velocity omega (docs/design.md §1)."""
    (Nx1, Nx2, Nx3, Ny1, Ny2, Ny3, Cx1, Cx2, Cx3, Cy1, Cy2, Cy3, E11, E12, E22,
     idet) = frame(r, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3)
    # alpha' = r E^-1 C'^T (omega x N)
    w1, w2, w3 = o2 * n3 - o3 * n2, o3 * n1 - o1 * n3, o1 * n2 - o2 * n1
    b1 = r * (Cx1 * w1 + Cx2 * w2 + Cx3 * w3)
    b2 = r * (Cy1 * w1 + Cy2 * w2 + Cy3 * w3)
    a1 = (E22 * b1 - E12 * b2) * idet
    a2 = (E11 * b2 - E12 * b1) * idet
    # N' alpha', then v' = m r (N x g) - m r^2 (N' alpha') x (N x omega), with N x omega = -w
    d1, d2, d3 = Nx1 * a1 + Ny1 * a2, Nx2 * a1 + Ny2 * a2, Nx3 * a1 + Ny3 * a2
    return a1, a2, d1, d2, d3, w1, w2, w3


@JIT
def friction_needed(p, n1, n2, n3, o1, o2, o3, d1, d2, d3, v1, v2, v3, e1, e2, e3, m1, m2, m3):
    """F_t (3), the tangential force the surface must exert for the ball to roll: from the
    torque about the centre, (2/5) m r² omega' = (-r N) x F + M, so F_t = N x ((2/5) m r² omega' - M) / r;
    omega' = T^-1 (v' + 5/2 (N' alpha'.v + N.v') N + 5/2 (N.v) N' alpha'), for the rolling
    state with normal N, omega, N' alpha' = d, angular momentum v, its rate v' = e and the
    rolling resistance's couple M (tangential; the spin friction's, along N, adds nothing)."""
    k, mr = p[3], p[4]
    nv = 2.5 * (n1 * v1 + n2 * v2 + n3 * v3)
    nve = 2.5 * (d1 * v1 + d2 * v2 + d3 * v3 + n1 * e1 + n2 * e2 + n3 * e3)
    q1 = k * (e1 + nve * n1 + nv * d1)
    q2 = k * (e2 + nve * n2 + nv * d2)
    q3 = k * (e3 + nve * n3 + nv * d3)
    c = 0.4 * mr
    if m1 == 0.0 and m2 == 0.0 and m3 == 0.0:
        return c * (n2 * q3 - n3 * q2), c * (n3 * q1 - n1 * q3), c * (n1 * q2 - n2 * q1)
    ir = 1.0 / p[0]
    return (c * (n2 * q3 - n3 * q2) - ir * (n2 * m3 - n3 * m2), c * (n3 * q1 - n1 * q3) - ir * (n3 * m1 - n1 * m3),
            c * (n1 * q2 - n2 * q1) - ir * (n1 * m2 - n2 * m1))


@JIT
def rolling_need(p, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, o1, o2, o3, resisted):
    """F_t (3) a ball rolling at this contact point with angular velocity omega needs
    (``friction_needed``): what a sliding ball whose slip has stopped is held to. Where the scene
    dissipates (``resisted``), with the couples and the air a rolling run started at this state has
    (``rolling_couples`` on the sides ``couple_sides`` gives it, as ``recording.start`` does): the
    same need the rolling run then finds, so that a grip is not undone by a slip at once, nor the
    other way about (docs/design.md §1, "Dissipation")."""
    r, mr, mr2, mg = p[0], p[4], p[5], p[6]
    no = n1 * o1 + n2 * o2 + n3 * o3
    v1, v2, v3 = mr2 * (1.4 * o1 - n1 * no), mr2 * (1.4 * o2 - n2 * no), mr2 * (1.4 * o3 - n3 * no)  # v = T omega
    a1, a2, d1, d2, d3, w1, w2, w3 = rolling_rates(r, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, o1, o2, o3)
    e1 = -mg * r * n2 + mr2 * (d2 * w3 - d3 * w2)
    e2 = mg * r * n1 + mr2 * (d3 * w1 - d1 * w3)
    e3 = mr2 * (d1 * w2 - d2 * w1)
    m1, m2, m3 = 0.0, 0.0, 0.0
    if resisted:
        fn_ = rolling_force(mr, mg, n1, n2, n3, o1, o2, o3, d1, d2, d3)
        s1, s2, s3, side = couple_sides(p, fn_, n1, n2, n3, o1, o2, o3, 1.4)
        e1, e2, e3, m1, m2, m3, _, _, _, _ = rolling_couples(
            p, fn_ if p[P_FLY] != 0.0 else abs(fn_), s1, s2, s3, side, n1, n2, n3, o1, o2, o3, v1, v2, v3, d1, d2,
            d3, w1, w2, w3, e1, e2, e3)
    return friction_needed(p, n1, n2, n3, o1, o2, o3, d1, d2, d3, v1, v2, v3, e1, e2, e3, m1, m2, m3)


@JIT
def slip_deceleration(p, pe):
    """The most a sliding ball's friction decelerates its slip at a state with probe pe:
    (7/2) mu F_n / m (the slip u = c' - r omega x N changes by -(1 + 5/2) mu F_n / m along u/|u|)."""
    return 3.5 * p[P_MU] * abs(pe[PROBE_FORCE]) / p[1]


@JIT
def slow_corrected(p):
    """Whether a growing slip's slow direction is taken to first order in |u| (``slow_direction``),
    its B a function of the state alone: no rolling resistance or spin friction (whose couples
    turn with omega's own direction) and gravity to measure B's rate in. Else B-hat itself."""
    return p[P_RESISTANCE] == 0.0 and p[P_SPIN] == 0.0 and p[P_UNIT] < math.inf


# A slip speed below this fraction of the ball's speeds (|c'|, r |omega|) is zero: the slip of a
# sliding run that starts from rolling, in round-off (its direction is then the one it starts in).
SLIP_ZERO = 1e-12


@JIT
def slow_lag(p, slow, us, lag):
    """Whether a growing slip of speed ``us`` below ``slow`` (``loops.slow_slip``: rtol^(1/4)
    sqrt(g r)) whose slow direction lags B-hat by ``lag`` (rad, ``slow_direction``) is taken on
    the slow motion: below sqrt(rtol g r), where B-hat itself would do, or where the lag is at
    most rtol^LAG_POWER (the first-order direction's error is of the order of its square)."""
    unit = math.sqrt(abs(p[2]) * p[0])
    rtol = (slow / unit) ** (1.0 / SLOW_POWER)
    return us < math.sqrt(rtol) * unit or lag <= rtol ** LAG_POWER


# The slip speed below which an adaptive pair's slip may be on the slow motion where its direction is
# taken to first order (``loops.slow_slip``), in units of sqrt(g r): rtol to this power
SLOW_POWER = 0.25
# The lag a slow slip's direction may have (``slow_lag``): rtol to this power
LAG_POWER = 1.0 / 3.0

# The time step (in units of sqrt(r/g)) of the difference that measures B's rate along the slow
# motion (``slow_direction``): B varies on that unit, so its rate is good to about 1e-7 relative.
SLOW_SHIFT = 1e-7


@COLD
def slow_direction(fn, d, p, z, a1, a2, fn_, f, n1, n2, n3, b1, b2, b3, bs, us):
    """The direction of a growing slip of speed ``us`` on the slow motion (docs/design.md §8, "the
    slip's direction where it is stiff"), to first order in us: its direction e relaxes towards B's
    at the rate |B| / us while B turns, so it lags B-hat by the angle us |B-hat'| / (|B| + us'),
    us' = |B| - a: e = B-hat - us P(B') / (|B| (2 |B| - a)), P the projection across B-hat in the
    tangent plane, a = 7/2 f / m. B' is the difference of B (``slow_pull``) over SLOW_SHIFT
    sqrt(r/g) along the motion whose slip points along B-hat. Returns e and the lag's angle.
    Overwrites d's landscape values (the caller's to restore). Where the shifted state gives no
    finite B, B-hat and an infinite lag."""
    m, g0 = p[1], p[2]
    s1, s2, s3 = b1 / bs, b2 / bs, b3 / bs
    e = SLOW_SHIFT * p[P_UNIT]
    q = 2.5 * f / p[4]
    x, y = z[0] + e * a1, z[1] + e * a2
    c1 = z[2] + e * (fn_ * n1 - f * s1) / m
    c2 = z[3] + e * (fn_ * n2 - f * s2) / m
    c3 = z[4] + e * ((fn_ * n3 - f * s3) / m - g0)
    o1 = z[5] + e * q * (n2 * s3 - n3 * s2)
    o2 = z[6] + e * q * (n3 * s1 - n1 * s3)
    o3 = z[7] + e * q * (n1 * s2 - n2 * s1)
    q1, q2, q3 = slow_pull(fn, d, p, x, y, c1, c2, c3, o1, o2, o3)
    q1, q2, q3 = (q1 - b1) / e, (q2 - b2) / e, (q3 - b3) / e
    qn = q1 * n1 + q2 * n2 + q3 * n3
    q1, q2, q3 = q1 - qn * n1, q2 - qn * n2, q3 - qn * n3
    qs = q1 * s1 + q2 * s2 + q3 * s3
    q1, q2, q3 = q1 - qs * s1, q2 - qs * s2, q3 - qs * s3
    k = us / (bs * max(2.0 * bs - 3.5 * f / m, bs))
    t1, t2, t3 = s1 - k * q1, s2 - k * q2, s3 - k * q3
    ts = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
    if not (ts > 0.0 and ts < math.inf):
        return s1, s2, s3, math.inf
    return t1 / ts, t2 / ts, t3 / ts, k * math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)


@JIT
def slow_pull(fn, d, p, x, y, c1, c2, c3, o1, o2, o3):
    """B, a sliding ball's slip acceleration with friction off in the tangent plane, at contact
    point (x, y) with centre velocity c' and angular velocity omega, as ``sliding_dynamics`` has
    it where no rolling couple acts: -r omega x N' alpha' - g z-hat, with the air's drag."""
    r, m, g0 = p[0], p[1], p[2]
    _, _, _, _, _, _, n1, n2, n3, _, _, d1, d2, d3 = sliding_contact(fn, d, r, x, y, c1, c2, c3)
    air = -p[P_AIR] * math.sqrt(c1 * c1 + c2 * c2 + c3 * c3) / m
    b1 = -r * (o2 * d3 - o3 * d2) + air * c1
    b2 = -r * (o3 * d1 - o1 * d3) + air * c2
    b3 = -g0 - r * (o1 * d2 - o2 * d1) + air * c3
    bn = b1 * n1 + b2 * n2 + b3 * n3
    return b1 - bn * n1, b2 - bn * n2, b3 - bn * n3


@JIT
def sliding_contact(fn, d, r, x, y, c1, c2, c3):
    """The landscape at a sliding ball's contact point (x, y) (into d), its slopes and curvatures,
    1 / sqrt(1 + fx² + fy²), the unit normal N, and for the centre velocity c' the contact point's
    alpha' = E^-1 C'^T c' (2) and N' alpha' (3) (``frame``)."""
    landscape(fn, x, y, data_pointer(d))
    fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
    iW = 1.0 / math.sqrt(1.0 + fx * fx + fy * fy)
    n1, n2, n3 = -fx * iW, -fy * iW, iW
    (Nx1, Nx2, Nx3, Ny1, Ny2, Ny3, Cx1, Cx2, Cx3, Cy1, Cy2, Cy3, E11, E12, E22,
     idet) = frame(r, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3)
    # alpha' = E^-1 C'^T c'
    b1 = Cx1 * c1 + Cx2 * c2 + Cx3 * c3
    b2 = Cy1 * c1 + Cy2 * c2 + Cy3 * c3
    a1 = (E22 * b1 - E12 * b2) * idet
    a2 = (E11 * b2 - E12 * b1) * idet
    d1, d2, d3 = Nx1 * a1 + Ny1 * a2, Nx2 * a1 + Ny2 * a2, Nx3 * a1 + Ny3 * a2
    return fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, a1, a2, d1, d2, d3


@COLD  # (called, not inlined: the sliding steps are rarer than rolling's, and the kernel's code stays smaller)
def sliding_dynamics(fn, d, p, z, mk, K, row, probe, full):
    """``dynamics`` of a sliding ball, z = (x, y, c' (3), omega (3), D, orientation): the ball
    keeps contact, F_n from the constraint N.c'' = -(N' alpha').c', kinetic friction -mu F_n s
    along the unit slip velocity s of the material point at the contact (docs/design.md §1, "Sliding"):
    alpha' = E^-1 C'^T c', m c'' = m g + F_n N - mu |F_n| s, (2/5) m r² omega' = (-r N) x F,
    D' = mu |F_n| |u_slip|. Where the slip is zero (SLIP_ZERO: a slip starting), or grows while
    its direction is stiff (below d[D_SLIP + 3], ``loops.slip_reference``), s is the direction of B,
    the slip's acceleration with friction off, at this state; where it is exactly zero the probe's
    slip velocity is 0.

    Inside a step the friction stays on its side of the slip velocity at the step's start,
    d[D_SLIP:D_SLIP + 3] (s = -u/|u| where u points against it, and D' < 0): the equations go on
    smoothly through a slip speed of 0 instead of turning the friction about, so that the
    step's stages and dense output stay those of a smooth motion and the grip (u.u0 = 0) is
    located on them to the method's order (the run stops there)."""
    r, m, g0, mr, mu = p[0], p[1], p[2], p[4], p[P_MU]
    c1, c2, c3 = z[2], z[3], z[4]
    o1, o2, o3 = z[5], z[6], z[7]
    fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, a1, a2, d1, d2, d3 = sliding_contact(fn, d, r, z[0], z[1], c1, c2, c3)
    fn_ = m * (g0 * n3 - (d1 * c1 + d2 * c2 + d3 * c3))   # F_n = m (-(N' alpha').c' - N.g)
    n = K.shape[1]
    resisted = resisted_size(n)
    air = 0.0   # the air's drag F_air = air c' (docs/design.md §1, "Dissipation")
    if resisted:
        cs = math.sqrt(c1 * c1 + c2 * c2 + c3 * c3)
        air = -p[P_AIR] * cs
        fn_ -= air * (c1 * n1 + c2 * n2 + c3 * n3)   # (F_n = m (-(N' alpha').c' - N.g) - F_air.N)
    # the slip velocity u = c' + omega x (-r N)
    u1 = c1 - r * (o2 * n3 - o3 * n2)
    u2 = c2 - r * (o3 * n1 - o1 * n3)
    u3 = c3 - r * (o1 * n2 - o2 * n1)
    # its part in the tangent plane: u.N = c'.N is 0 in the exact motion and only the integrator's
    # drift here; left in, it would turn the friction off the plane and, while |u| is small, drive
    # that drift at the stiff rate mu F_n / (m |u|) (docs/design.md §1, "Sliding")
    un = u1 * n1 + u2 * n2 + u3 * n3
    u1, u2, u3 = u1 - un * n1, u2 - un * n2, u3 - un * n3
    us = math.sqrt(u1 * u1 + u2 * u2 + u3 * u3)
    speeds = c1 * c1 + c2 * c2 + c3 * c3 + r * r * (o1 * o1 + o2 * o2 + o3 * o3)
    zero = not us * us > SLIP_ZERO * SLIP_ZERO * speeds
    if zero:
        u1, u2, u3, us = 0.0, 0.0, 0.0, 0.0
    # where the ball flies the run stops where F_n reaches 0: mu F_n, smooth through that zero, keeps
    # the stages of the step across it (and its dense output, on which the lift-off is located)
    # those of a smooth motion; glued, a pulling F_n < 0 rubs too
    f = mu * (fn_ if p[P_FLY] != 0.0 else abs(fn_))
    # B, the slip's acceleration with friction off: c'' - r omega x N' alpha' in the tangent plane
    b1 = -r * (o2 * d3 - o3 * d2)
    b2 = -r * (o3 * d1 - o1 * d3)
    b3 = -g0 - r * (o1 * d2 - o2 * d1)
    fa = fn_ if p[P_FLY] != 0.0 else abs(fn_)
    on = o1 * n1 + o2 * n2 + o3 * n3
    if resisted:   # B with the air's drag and the rolling resistance where it keeps its side (its part - r omega' x N)
        b1, b2, b3 = b1 + air * c1 / m, b2 + air * c2 / m, b3 + air * c3 / m
        if d[D_SIDE] != 0.0 or d[D_SIDE + 1] != 0.0 or d[D_SIDE + 2] != 0.0:
            m1, m2, m3 = rolling_couple(p[P_RESISTANCE] * r * fa, o1 - on * n1, o2 - on * n2, o3 - on * n3,
                                        d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2], 0.0, 0.0, 0.0, -1.0)
            w = 2.5 * r / p[5]
            b1 -= w * (m2 * n3 - m3 * n2)
            b2 -= w * (m3 * n1 - m1 * n3)
            b3 -= w * (m1 * n2 - m2 * n1)
    bn = b1 * n1 + b2 * n2 + b3 * n3
    b1, b2, b3 = b1 - bn * n1, b2 - bn * n2, b3 - bn * n3
    bs = math.sqrt(b1 * b1 + b2 * b2 + b3 * b3)
    slow = d[D_SLIP + 3]   # below this slip speed the slip's direction is stiff (``slip_reference``)
    r1, r2, r3 = d[D_SLIP], d[D_SLIP + 1], d[D_SLIP + 2]
    rn = r1 * n1 + r2 * n2 + r3 * n3   # (held in the tangent plane here, which turns within the step)
    r1, r2, r3 = r1 - rn * n1, r2 - rn * n2, r3 - rn * n3
    rn = math.sqrt(r1 * r1 + r2 * r2 + r3 * r3)
    slows = (zero or (us < slow and (rn == 0.0 or bs * m > 3.5 * f))) and bs > 0.0
    s1, s2, s3 = 0.0, 0.0, 0.0
    if slows and not zero and slow < math.inf and slow_corrected(p):
        # to first order in |u|, where its lag behind B-hat is small enough (``slow_lag``)
        h0 = d[0]
        s1, s2, s3, lag = slow_direction(fn, d, p, z, a1, a2, fn_, f, n1, n2, n3, b1, b2, b3, bs, us)
        d[0], d[1], d[2], d[3], d[4], d[5] = h0, fx, fy, fxx, fxy, fyy
        slows = slow_lag(p, slow, us, lag)
    elif slows:
        s1, s2, s3 = b1 / bs, b2 / bs, b3 / bs
    if slows:
        # a slip starting (zero at the step's start, or growing while its direction is stiff, the
        # adaptive pairs): its direction relaxes towards B's at the rate |B| / |u| and then turns
        # with it; taken as the slow motion's the exact one follows (B's direction at this state,
        # or ``slow_direction``), smooth through the step (docs/design.md §8, "the slip's direction
        # where it is stiff")
        us = u1 * s1 + u2 * s2 + u3 * s3
    elif not zero:
        side = us
        if u1 * r1 + u2 * r2 + u3 * r3 < 0.0:
            side = -us   # past the slip's zero: the friction keeps its side (above)
        s1, s2, s3 = u1 / side, u2 / side, u3 / side
        us = side
    else:   # (no slip and no pull: nothing for friction to act along)
        s1, s2, s3, us = 0.0, 0.0, 0.0, 0.0
    K[row, 0] = a1
    K[row, 1] = a2
    K[row, 2] = (fn_ * n1 - f * s1) / m
    K[row, 3] = (fn_ * n2 - f * s2) / m
    K[row, 4] = (fn_ * n3 - f * s3) / m - g0
    q = 2.5 * f / mr   # omega' = 5 / (2 m r²) (-r N) x (-f s)
    K[row, 5] = q * (n2 * s3 - n3 * s2)
    K[row, 6] = q * (n3 * s1 - n1 * s3)
    K[row, 7] = q * (n1 * s2 - n2 * s1)
    K[row, 8] = f * us
    pull = 0.0   # the pull on omega.N, times (2/5) m r² (``sliding_losses``)
    if resisted:
        pull = sliding_losses(p, d, K, row, n, fa, air, c1, c2, c3, o1, o2, o3, on, n1, n2, n3, d1, d2, d3,
                              f * r * (n2 * s3 - n3 * s2), f * r * (n3 * s1 - n1 * s3), f * r * (n1 * s2 - n2 * s1))
    if n == SLIDING_MOTION_SIZE:  # no orientation carried
        pass
    elif mk != 0.0 and p[P_TURN] > 0.0:  # the pairs: omega is the motion's, R follows it (``turn``)
        K[row, 9], K[row, 10], K[row, 11] = 0.0, 0.0, 0.0
    elif mk != 0.0:
        K[row, 9], K[row, 10], K[row, 11] = dexpinv(z[9], z[10], z[11], o1, o2, o3)
    else:
        rotation_rate(z, K, row, 9, o1, o2, o3)
    if full != 0.0:
        probe[0], probe[1], probe[2] = n1, n2, n3
        probe[3], probe[4], probe[5] = o1, o2, o3
        probe[6] = fn_
        hi, lo = curvatures(fx, fy, fxx, fxy, fyy, iW)
        probe[7] = r * hi
        probe[8] = d[0]
        probe[9] = r * lo
        t1, t2, t3 = rolling_need(p, fx, fy, fxx, fxy, fyy, iW, n1, n2, n3, o1, o2, o3, resisted)
        probe[PROBE_NEED] = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
        probe[PROBE_SLIP], probe[PROBE_SLIP + 1], probe[PROBE_SLIP + 2] = u1, u2, u3
        probe[PROBE_SPIN_PULL] = pull
        probe[PROBE_SLIP_PULL], probe[PROBE_SLIP_PULL + 1], probe[PROBE_SLIP_PULL + 2] = b1, b2, b3


@JIT
def sliding_losses(p, d, K, row, n, fa, air, c1, c2, c3, o1, o2, o3, on, n1, n2, n3, d1, d2, d3, f1, f2, f3):
    """Add to the sliding ball's rates K[row] the air's drag F_air = air c' (on c'') and the couples
    of rolling resistance and spin friction (on omega', ``rolling_couple`` and ``spin_couple``, F.N
    as ``fa``; f = (2/5) m r² omega' of the sliding friction), and write the rates of the energy each
    takes into K[row, n - 3:n] (docs/design.md §1, "Dissipation"). A static couple holds its part of
    omega at 0 in the turning tangent plane (N' = d): the spin's pull is (2/5) m r² omega.N' (the
    friction's and the rolling couple's moments lie in the plane), the rolling couple's
    f - (2/5) m r² (omega.N) N' (omega_t' = omega'_t - (omega.N) N' where omega_t is 0). Returns the
    spin's pull."""
    r, m, mr2 = p[0], p[1], p[5]
    pull = 0.4 * mr2 * (o1 * d1 + o2 * d2 + o3 * d3)
    ms = spin_couple(p[P_SPIN] * r * fa, d[D_SIDE + 3], pull)
    q = 0.4 * mr2 * on
    m1, m2, m3 = rolling_couple(p[P_RESISTANCE] * r * fa, o1 - on * n1, o2 - on * n2, o3 - on * n3, d[D_SIDE],
                                d[D_SIDE + 1], d[D_SIDE + 2], f1 - q * d1, f2 - q * d2, f3 - q * d3, -1.0)
    a = air / m
    K[row, 2] += a * c1
    K[row, 3] += a * c2
    K[row, 4] += a * c3
    q = 2.5 / mr2
    K[row, 5] += q * (m1 + ms * n1)
    K[row, 6] += q * (m2 + ms * n2)
    K[row, 7] += q * (m3 + ms * n3)
    K[row, n - 3] = -(m1 * o1 + m2 * o2 + m3 * o3)
    K[row, n - 2] = 0.0 if d[D_SIDE + 3] == 0.0 and ms == -pull else -ms * on   # (as ``rolling_losses``)
    K[row, n - 1] = -air * (c1 * c1 + c2 * c2 + c3 * c3)
    return pull


@JIT
def sliding_size(n):
    """Whether a state of length n is a sliding ball's."""
    return (n == SLIDING_MOTION_SIZE or n == SLIDING_MK_SIZE or n == SLIDING_CLASSIC_SIZE
            or n == SLIDING_RESISTED_MK_SIZE or n == SLIDING_RESISTED_CLASSIC_SIZE)


@JIT
def motion_size(n):
    """The motion's part of a state of length n (its orientation follows it)."""
    return SLIDING_MOTION_SIZE if sliding_size(n) else MOTION_SIZE


@JIT
def rates(fn, d, p, z, mk, K, row, probe, full):
    """``dynamics`` or ``sliding_dynamics``, by the state's length."""
    if sliding_size(K.shape[1]):
        sliding_dynamics(fn, d, p, z, mk, K, row, probe, full)
    else:
        dynamics(fn, d, p, z, mk, K, row, probe, full)


# Below this |u|^2 the coefficient of dexp^-1 is its series (to round-off for |u| < 0.1).
DEXPINV_SERIES = 1e-2


@JIT
def dexpinv(u1, u2, u3, o1, o2, o3):
    """dexp_u^-1(omega) = omega - 1/2 u x omega + c(theta) u x (u x omega) on so(3), exact:
    c = (1 - (theta/2) cot(theta/2)) / theta^2, theta = |u|, with its series
    1/12 + theta^2/720 + theta^4/30240 + theta^6/1209600 for small theta. (The truncation
    after 1/12 limits Munthe-Kaas to order 5; the exact inverse to none.)"""
    th2 = u1 * u1 + u2 * u2 + u3 * u3
    if th2 < DEXPINV_SERIES:
        c = 1.0 / 12.0 + th2 * (1.0 / 720.0 + th2 * (1.0 / 30240.0 + th2 * (1.0 / 1209600.0)))
    else:
        x = 0.5 * math.sqrt(th2)
        c = (1.0 - x * math.cos(x) / math.sin(x)) / th2
    c1, c2, c3 = u2 * o3 - u3 * o2, u3 * o1 - u1 * o3, u1 * o2 - u2 * o1
    return (o1 - 0.5 * c1 + c * (u2 * c3 - u3 * c2),
            o2 - 0.5 * c2 + c * (u3 * c1 - u1 * c3),
            o3 - 0.5 * c3 + c * (u1 * c2 - u2 * c1))


@JIT
def curvatures(fx, fy, fxx, fxy, fyy, iW):
    """The largest and smallest principal curvature (> 0 bending up towards the ball),
    iW = 1 / sqrt(1 + f_x² + f_y²)."""
    # roots of det(II - kappa G) = 0, G first, II second fundamental form
    G11, G12, G22 = 1.0 + fx * fx, fx * fy, 1.0 + fy * fy
    h11, h12, h22 = fxx * iW, fxy * iW, fyy * iW
    iW2 = iW * iW
    mean = 0.5 * (G11 * h22 + G22 * h11 - 2.0 * G12 * h12) * iW2
    gauss = (h11 * h22 - h12 * h12) * iW2
    root = math.sqrt(max(mean * mean - gauss, 0.0))
    return mean + root, mean - root


@COLD
def evaluate_points(fn, xs, ys, out, d):
    """out[:, i] = f, f_x, f_y, f_xx, f_xy, f_yy at (xs[i], ys[i]); d (6): scratch."""
    for i in range(xs.shape[0]):
        landscape(fn, xs[i], ys[i], data_pointer(d))
        for k in range(6):
            out[k, i] = d[k]


@EXACT
def closest_points(fn, centers, feet, normals, distances, iterations, d):
    """The closest surface point (foot) of each centre (n, 3) by Newton's method from the first
    guesses in feet (n, 2), which are replaced by the feet; normals (n, 3) the unit normals there,
    distances (n) the centre's signed distance along them; NaN feet and distances where Newton's
    method does not converge within ``iterations`` or ends where c − φ is not along N
    (``flight.Surface.feet`` says why the method works). Each point stops when its step is
    round-off (converged) or its foot is no longer finite (it left the landscape's domain: no
    foot from that start; the others go on). Without fused multiply-adds (EXACT), the feet and
    normals are bit for bit those of the same iteration written in numpy; the distance may
    differ in its last bit (numpy's einsum sums three products in an order that depends on the
    arrays' shapes). d (6): scratch."""
    n = centers.shape[0]
    done = distances   # (whether a point is done, as 1.0, until the distances are written)
    for i in range(n):
        done[i] = 0.0
    for _ in range(iterations):
        for i in range(n):
            if done[i] != 0.0:
                continue
            ax, ay = feet[i, 0], feet[i, 1]
            landscape(fn, ax, ay, data_pointer(d))
            f, fx, fy, fxx, fxy, fyy = d[0], d[1], d[2], d[3], d[4], d[5]
            dx, dy, dz = centers[i, 0] - ax, centers[i, 1] - ay, centers[i, 2] - f
            b1, b2 = dx + dz * fx, dy + dz * fy
            h11, h12, h22 = 1.0 + fx * fx - dz * fxx, fx * fy - dz * fxy, 1.0 + fy * fy - dz * fyy
            det = h11 * h22 - h12 * h12
            s1, s2 = (h22 * b1 - h12 * b2) / det, (h11 * b2 - h12 * b1) / det
            ax, ay = ax + s1, ay + s2
            feet[i, 0], feet[i, 1] = ax, ay
            # |step|_max <= 4e-16 (1 + |α|_max), false where anything is NaN
            scale = 1.0 + (abs(ax) if abs(ax) >= abs(ay) else abs(ay))
            if math.isnan(ax) or math.isnan(ay):
                scale = math.nan
            if abs(s1) <= 4e-16 * scale and abs(s2) <= 4e-16 * scale:
                done[i] = 1.0
            elif not (math.isfinite(ax) and math.isfinite(ay)):
                done[i] = -1.0   # this start left the landscape: it finds no foot, the others go on
        finished = True
        for i in range(n):
            finished = finished and done[i] != 0.0
        if finished:
            break
    for i in range(n):
        ax, ay = feet[i, 0], feet[i, 1]
        landscape(fn, ax, ay, data_pointer(d))
        fx, fy = d[1], d[2]
        w = math.sqrt(1.0 + fx * fx + fy * fy)
        n1, n2, n3 = -fx / w, -fy / w, 1.0 / w
        normals[i, 0], normals[i, 1], normals[i, 2] = n1, n2, n3
        g1, g2, g3 = centers[i, 0] - ax, centers[i, 1] - ay, centers[i, 2] - d[0]
        distance = g1 * n1 + g2 * n2 + g3 * n3
        o1, o2, o3 = g1 - distance * n1, g2 - distance * n2, g3 - distance * n3
        off = math.sqrt(o1 * o1 + o2 * o2 + o3 * o3)
        # a converged foot has c − φ along N; anything else (a saddle of the distance, no
        # convergence) is not a closest point
        if done[i] != 1.0 or not off <= 1e-6 * (1.0 + abs(distance)):
            feet[i, 0], feet[i, 1], distance = math.nan, math.nan, math.nan
        distances[i] = distance


@JIT
def rodrigues(u1, u2, u3, R, out):
    """out = exp(A(u)) R, exact at any angle, with a series for small |u| (out may be R)."""
    th2 = u1 * u1 + u2 * u2 + u3 * u3
    th = math.sqrt(th2)
    if th < 1e-4:
        a = 1.0 - th2 / 6.0 * (1.0 - th2 / 20.0)
        b = 0.5 - th2 / 24.0 * (1.0 - th2 / 30.0)
    else:
        a = math.sin(th) / th
        h = math.sin(0.5 * th) / th
        b = 2.0 * h * h
    # Q = I + a A + b A^2, A^2 = u u^T - |u|^2 I
    q11, q22, q33 = 1.0 + b * (u1 * u1 - th2), 1.0 + b * (u2 * u2 - th2), 1.0 + b * (u3 * u3 - th2)
    q12, q21 = -a * u3 + b * u1 * u2, a * u3 + b * u1 * u2
    q13, q31 = a * u2 + b * u1 * u3, -a * u2 + b * u1 * u3
    q23, q32 = -a * u1 + b * u2 * u3, a * u1 + b * u2 * u3
    for j in range(3):
        r1, r2, r3 = R[0, j], R[1, j], R[2, j]
        out[0, j] = q11 * r1 + q12 * r2 + q13 * r3
        out[1, j] = q21 * r1 + q22 * r2 + q23 * r3
        out[2, j] = q31 * r1 + q32 * r2 + q33 * r3


@JIT
def shape_of(z):
    """(n, munthe_kaas) read from the state's length at run time: the functions compiled once
    (COLD) take them so, not as the constants of the loops, which would compile them anew
    for every loop."""
    n = z.shape[0]
    return n, n == MK_SIZE or n == SLIDING_MK_SIZE or n == RESISTED_MK_SIZE or n == SLIDING_RESISTED_MK_SIZE


@JIT
def _finite(a, lo, hi):
    """a[lo:hi] all finite: a chain of cheap ands, no early exit and no floating-point chain."""
    ok = True
    for q in range(lo, hi):
        ok &= math.isfinite(a[q])
    return ok


@JIT
def _finite_row(K, row, lo, hi):
    ok = True
    for q in range(lo, hi):
        ok &= math.isfinite(K[row, q])
    return ok


@JIT
def _finite_matrix(R):
    ok = True
    for a in range(3):
        for c in range(3):
            ok &= math.isfinite(R[a, c])
    return ok


@COLD
def evaluate(fn, d, p, z, mk, K, row, probe):
    rates(fn, d, p, z, 1.0 if mk else 0.0, K, row, probe, FULL)
