"""What happens inside a step, found on its dense output: lift-off (F.N = 0), the ball no
longer fitting (r·κ = 1), kinks and jumps of the surface, and the edge of the no-fit region
approached in sub-steps (``fold_search``); the last valid state of a stopped run."""

from __future__ import annotations

import math

from .dense import interpolate, state_at
from .explicit import dense_stages
from .interface import (
    DOES_NOT_FIT, F_EVENT_T, F_EVENT_X, F_EVENT_Y, F_FAIL_T, F_FAIL_Y, F_FOLD, F_LIFTOFF, F_LIFT_KINK, F_LIFT_X,
    F_LIFT_Y, F_RATE_FORCE, F_RATE_SLIP, I_DENSE, I_EVALS, I_HELD, I_REASON, I_ROWS, I_STATUS, I_TRANSITION, IMPLICIT,
    D_SIDE, LIFT_TIP, PROBE_FIT, PROBE_FIT_LO, PROBE_FORCE, PROBE_HEIGHT, PROBE_NEED, PROBE_OMEGA, PROBE_SLIP,
    PROBE_SLIP_PULL, PROBE_SPIN_PULL, P_FLY, P_MU, P_RESISTANCE, P_SPIN, P_TURN, R_HEIGHT_JUMP, R_KINK, R_NO_FIT,
    R_SECANT_NO_FIT, R_TIP, SURFACE_SIZE, TRANSITION, T_GRIP, T_LIFTOFF, T_REST, T_SIDE, T_SLIP)
from .lowlevel import COLD, JIT, data_pointer, landscape
from .physics import (copy_state, couple_sides, curvatures, resisted_size, shape_of, sliding_size, slip_deceleration,
                      spin_excess, spin_limit)
from .recording import _fail, hold, record, record_last
from .steps import accept, search_step


# -- dense output and events -----------------------------------------------------------------
#
# After a step from z at t to t + h, z(t + theta h) = z + h sum_i K_i sum_k P[i, k] theta^(k+1)
# (P: ``Tableau.dense_output``), and R(t + theta h) = exp(A(u(theta))) R for Munthe-Kaas.
# Rows at fixed times and the events of a step are read from it. Methods whose dense output
# needs more stages than the step (DOP853: three) give them as rows of W (and K, P) after
# ``last``; ``dense_stages`` computes them once per step, only when the step is interpolated.

ROOT_ITERATIONS = 100  # at most this many evaluations to locate one event
ROOT_TOL = 1e-13       # events are located to this fraction of a step
BREAK_HALVINGS = 48    # bisections that tell a jump or kink of the surface from a smooth bend
KINK_SLACK = 1e-3      # a step whose secant curvature r*|kappa| exceeds twice its ends' plus
                       # this is looked at closer (kinks have no curvature the model can see)
JUMP_SLACK = 0.1       # likewise a height change off the slopes' by this fraction of the step
BREAK_MIN = 1e-6       # a normal turning by more (rad), or a height jumping by more (relative
                       # to 1 + |f|), across 2^-48 of a step is a kink or a jump...
BREAK_SPAN = 1e-9      # ...if that is a stretch of at most this (m): a state racing off to
                       # 1e50 m samples a smooth landscape too coarsely to tell
TIP_MIN = 1e-3        # a stop is put down to a tip where the normal turns by more than this (rad)
                      # over BREAK_SPAN: a finite angle, not a smooth bend however steep
TIP_REACH = 1e-6      # a tip is looked for at least this far (m, relative to 1 + |x| + |y|) around a stop
JOLT_MIN = 1e-6        # a centre jump (``centre_jolted``) shorter than this times r is not looked at
# The edge of the no-fit region is a fold of the centre surface: there the contact point's
# speed grows without bound (as 1 / (1 - r*kappa)) and reaches the edge in finite time, so the
# stages of a step across it are garbage and its ends may both fit. A step whose contact point
# raced (moved more than twice what its ends' speeds explain), whose stages raced (a stage's
# contact velocity off the ends' by more than STAGE_RACE times their size) or that nears the
# edge (the trend of 1 - r*kappa at its or the last step's ends reaches 0 within a step) is
# taken again in sub-steps that approach the edge geometrically (``fold_search``).
STAGE_RACE = 3.0
FOLD_TOL = 1e-13       # sub-steps end here; the edge is then located to this fraction of the step
CHORD_ROUND_OFF = 1e-24  # a step's squared chord below this share of the contact point's squared size is round-off
FOLD_NEAR = 1e-3       # ...where 1 - r*kappa is below this (else a jump of the curvature is
JUMP_TOL = 1e-6        # crossed, at once once a sub-step this short fits and does not race)
FOLD_TRIES = 400       # sub-steps tried at most (then the step is taken as it is)
LINE_SAMPLES = 8       # fit checks on the straight line between a sub-step's contact points
# (kinds as floats: numba would compile a function once per integer constant passed to it)
# FORCE_EVENT: F.N reaches 0; FIT_EVENT: r*kappa reaches 1; SLIP_EVENT: the friction rolling needs
# reaches mu F.N; GRIP_EVENT: the slip velocity's component along the slip at the step's start reaches 0;
# TURN_EVENT: omega's tangential part's along its value at the step's start (s[4:7]) reaches 0 (the
# rolling resistance's side); SPIN_EVENT: omega.N times its sign at the step's start (s[7]) reaches 0;
# LIMIT_EVENT: where that sign is 0 (a static spin couple), the pull on omega.N reaches the couple's limit;
# MISS_EVENT: -|u_slip|^2, never crossing 0: its largest value is where a slip passes closest to 0
FORCE_EVENT, FIT_EVENT, SLIP_EVENT, GRIP_EVENT, TURN_EVENT = 0.0, 1.0, 2.0, 3.0, 4.0
SPIN_EVENT, LIMIT_EVENT, MISS_EVENT = 5.0, 6.0, 7.0
KINK, JUMP, JOLT = 0.0, 1.0, 2.0   # what locate_break bisects towards (JOLT: the centre jumping)


@COLD
def surface_at(fn, d, r, z, h, P, K, theta, Ye, s):
    """The landscape under the dense output's contact point at t + theta h, in s (SURFACE_SIZE)."""
    interpolate(z, h, P, K, theta, Ye)
    landscape(fn, Ye[0], Ye[1], data_pointer(d))
    fx, fy = d[1], d[2]
    iW = 1.0 / math.sqrt(1.0 + fx * fx + fy * fy)
    hi, lo = curvatures(fx, fy, d[3], d[4], d[5], iW)
    s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7] = Ye[0], Ye[1], d[0], -fx * iW, -fy * iW, iW, r * hi, r * lo


@JIT
def condition(kind, p, s, pe):
    """g of a change of contact mode at a state with probe pe, negative before it: -F.N
    (FORCE_EVENT), |F_t| - mu F.N (SLIP_EVENT) or -u_slip . u0 (GRIP_EVENT, u0 in s[0:3])."""
    if kind == FORCE_EVENT:
        return -pe[PROBE_FORCE]
    if kind == SLIP_EVENT:
        return pe[PROBE_NEED] - p[P_MU] * pe[PROBE_FORCE]
    if kind == TURN_EVENT:
        return -turn_along(pe, s[4], s[5], s[6])
    if kind == SPIN_EVENT:
        return -spin_of(pe) * s[7]
    if kind == LIMIT_EVENT:
        return spin_excess(p, pe)
    if kind == MISS_EVENT:
        return -(pe[PROBE_SLIP] ** 2 + pe[PROBE_SLIP + 1] ** 2 + pe[PROBE_SLIP + 2] ** 2)
    return -(pe[PROBE_SLIP] * s[0] + pe[PROBE_SLIP + 1] * s[1] + pe[PROBE_SLIP + 2] * s[2])


@JIT
def spin_of(pe):
    """omega.N of a state with probe pe."""
    return pe[PROBE_OMEGA] * pe[0] + pe[PROBE_OMEGA + 1] * pe[1] + pe[PROBE_OMEGA + 2] * pe[2]


@JIT
def turn_along(pe, r1, r2, r3):
    """omega's tangential part (omega - (omega.N) N) of a state with probe pe, along r."""
    on = spin_of(pe)
    return ((pe[PROBE_OMEGA] - on * pe[0]) * r1 + (pe[PROBE_OMEGA + 1] - on * pe[1]) * r2
            + (pe[PROBE_OMEGA + 2] - on * pe[2]) * r3)


@JIT
def stands(p, pe):
    """Whether a ball with zero slip (probe pe) does not roll either: omega's tangential part is
    zero (``couple_sides``, rolling), so the centre stands still and the rolling resistance's couple
    is static there."""
    t1, t2, t3, _ = couple_sides(p, pe[PROBE_FORCE], pe[0], pe[1], pe[2], pe[PROBE_OMEGA], pe[PROBE_OMEGA + 1],
                                 pe[PROBE_OMEGA + 2], 1.4)
    return t1 == 0.0 and t2 == 0.0 and t3 == 0.0


@JIT
def sides_turn(p, d, n, pn):
    """Which couple's side the end of a step (probe pn) says turned inside it, for a state of
    length n carrying the dissipation (``couple_reference``'s sides in d): T_REST where a rolling
    ball's omega_t, against its rolling resistance (c_rr > 0), reached 0; T_SIDE where a sliding
    ball's did, or the spin omega.N against a spin friction (mu_s > 0), or where the spin couple is
    static the pull on omega.N reached its limit (``spin_excess``); 0 for none."""
    if p[P_RESISTANCE] > 0.0 and (d[D_SIDE] != 0.0 or d[D_SIDE + 1] != 0.0 or d[D_SIDE + 2] != 0.0):
        if turn_along(pn, d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2]) <= 0.0:
            return T_SIDE if sliding_size(n) else T_REST
    if p[P_SPIN] > 0.0 and d[D_SIDE + 3] != 0.0 and spin_of(pn) * d[D_SIDE + 3] <= 0.0:
        return T_SIDE
    if p[P_SPIN] > 0.0 and d[D_SIDE + 3] == 0.0 and spin_excess(p, pn) >= 0.0:
        return T_SIDE
    return 0


@COLD
def event_value(kind, fn, d, p, z, R, h, P, K, theta, Ye, Re, pe, s):
    """g(theta) of an event, negative before it: -F.N (lift-off), r*kappa - 1 (no fit),
    |F_t| - mu F.N (slip: the friction rolling needs beyond what the contact gives) or
    -u_slip . u0 (grip; s[0:3] holds u0, the slip velocity at the step's start); +inf where
    the state is not finite (past any event)."""
    if kind != FIT_EVENT:
        ok = state_at(fn, d, p, z, R, h, P, K, 0.0, theta, Ye, Re, pe)
        g = condition(kind, p, s, pe)
    else:
        surface_at(fn, d, p[0], z, h, P, K, theta, Ye, s)
        ok = True
        g = s[6] - 1.0
    return g if ok and math.isfinite(g) else math.inf


@COLD
def locate(kind, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, a, ga, b, gb, ints):
    """Shrink [a, b], g(a) < 0 <= g(b), around the event to ROOT_TOL (Illinois, every third
    try a bisection, so that it never stalls); returns (a, b)."""
    side = 0
    for it in range(ROOT_ITERATIONS):
        if b - a <= ROOT_TOL:
            break
        m = 0.5 * (a + b)
        if it % 3 != 2:
            secant = (a * gb - b * ga) / (gb - ga)
            if a < secant < b:
                m = secant
        g = event_value(kind, fn, d, p, z, R, h, P, K, m, Ye, Re, pe, s)
        if kind != FIT_EVENT:
            ints[I_EVALS] += 1
        if g >= 0.0:
            b, gb = m, g
            if side == 1:
                ga *= 0.5
            side = 1
        else:
            a, ga = m, g
            if side == -1:
                gb *= 0.5
            side = -1
    return a, b


@JIT
def centre_moved(r, sa, sb):
    """How far the centre moves between two surface points (squared)."""
    return ((sb[0] - sa[0] + r * (sb[3] - sa[3])) ** 2 + (sb[1] - sa[1] + r * (sb[4] - sa[4])) ** 2
            + (sb[2] - sa[2] + r * (sb[5] - sa[5])) ** 2)


@JIT
def break_measure(kind, r, sa, sb):
    """How much of a break of the surface lies between two surface points: the angle the
    normal turns (KINK), the height change beyond the slopes' trapezoid (JUMP), or how far the
    centre moves (JOLT, squared: the tip of a cone)."""
    if kind == JOLT:
        return centre_moved(r, sa, sb)
    if kind == KINK:
        return math.sqrt((sb[3] - sa[3]) ** 2 + (sb[4] - sa[4]) ** 2 + (sb[5] - sa[5]) ** 2)
    dx, dy = sb[0] - sa[0], sb[1] - sa[1]
    slope = ((sa[3] / sa[5] + sb[3] / sb[5]) * dx + (sa[4] / sa[5] + sb[4] / sb[5]) * dy) * 0.5
    return abs(sb[2] - sa[2] + slope)  # grad f = -(N1, N2) / N3


@COLD
def locate_break(kind, fn, d, r, z, h, P, K, Ye, sa, sb, sm, a, b):
    """Halve [a, b] (fractions of the step) BREAK_HALVINGS times towards the half holding more
    of the break; returns (a, b, the measure over [a, b]), sa and sb the surface at a and b.
    A smooth surface's measure vanishes with the interval; a kink's or jump's does not."""
    surface_at(fn, d, r, z, h, P, K, a, Ye, sa)
    surface_at(fn, d, r, z, h, P, K, b, Ye, sb)
    for _ in range(BREAK_HALVINGS):
        m = 0.5 * (a + b)
        surface_at(fn, d, r, z, h, P, K, m, Ye, sm)
        if break_measure(kind, r, sa, sm) >= break_measure(kind, r, sm, sb):
            b = m
            for q in range(SURFACE_SIZE):
                sb[q] = sm[q]
        else:
            a = m
            for q in range(SURFACE_SIZE):
                sa[q] = sm[q]
    if (sb[0] - sa[0]) ** 2 + (sb[1] - sa[1]) ** 2 > BREAK_SPAN * BREAK_SPAN:
        return a, b, 0.0
    return a, b, break_measure(kind, r, sa, sb)


@COLD
def normal_at(fn, d, x, y):
    """The unit upward normal of the surface at (x, y) (nan where it is not finite)."""
    landscape(fn, x, y, data_pointer(d))
    iW = 1.0 / math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
    return -d[1] * iW, -d[2] * iW, iW


@JIT
def chord(ax, ay, az, bx, by, bz):
    """The squared distance between two unit normals (0 where either is not finite)."""
    g = (ax - bx) ** 2 + (ay - by) ** 2 + (az - bz) ** 2
    return g if math.isfinite(g) else 0.0


@COLD
def normal_spread(fn, d, x0, y0, side):
    """The largest distance between the unit normals at the corners of the square of this side
    whose lower left corner is (x0, y0) (corners where the landscape is not finite left out)."""
    ax, ay, az = normal_at(fn, d, x0, y0)
    bx, by, bz = normal_at(fn, d, x0 + side, y0)
    cx, cy, cz = normal_at(fn, d, x0, y0 + side)
    ex, ey, ez = normal_at(fn, d, x0 + side, y0 + side)
    worst = max(chord(ax, ay, az, bx, by, bz), chord(ax, ay, az, cx, cy, cz), chord(ax, ay, az, ex, ey, ez),
                chord(bx, by, bz, cx, cy, cz), chord(bx, by, bz, ex, ey, ez), chord(cx, cy, cz, ex, ey, ez))
    return math.sqrt(worst)


@COLD
def find_tip(fn, d, x, y, half):
    """Look for a tip or kink of the surface in the square of half-width ``half`` around
    (x, y): a point where the normal turns through a finite angle over a vanishing span.
    The square is halved, keeping of its nine overlapping half-size squares the one whose
    corners' normals spread most, until it
    is at most BREAK_SPAN wide; a smooth surface's spread vanishes with the square, a tip's or
    kink's does not. Returns (the spread there, its centre x, y, whether the surface is convex
    there: higher than the mean of a ring around it); spread 0 where the landscape is not finite
    on that ring (the edge of its domain, which is not a tip)."""
    cx, cy, spread = x, y, 0.0
    for _ in range(200):
        if not 2.0 * half > BREAK_SPAN:
            break
        spread, bi, bj = -1.0, 0, 0
        for i in range(3):  # (overlapping halves: a tip lies at least a quarter inside one of them)
            for j in range(3):
                g = normal_spread(fn, d, cx + (0.5 * i - 1.0) * half, cy + (0.5 * j - 1.0) * half, half)
                if g > spread:
                    spread, bi, bj = g, i, j
        cx += 0.5 * (bi - 1) * half
        cy += 0.5 * (bj - 1) * half
        half *= 0.5
    # convex (a ridge or the tip of a cone pointing up) where the surface stands above a ring
    landscape(fn, cx, cy, data_pointer(d))
    f0, ring = d[0], 0.0
    rho = 16.0 * BREAK_SPAN
    for k in range(8):
        landscape(fn, cx + rho * math.cos(k * math.pi / 4.0), cy + rho * math.sin(k * math.pi / 4.0),
                  data_pointer(d))
        ring += (d[0] + 0.0 * (d[1] + d[2])) / 8.0
    if not math.isfinite(ring + f0):  # the landscape ends there (a domain's edge): no tip
        return 0.0, cx, cy, False
    return spread, cx, cy, f0 > ring


@COLD
def tip_stop(fn, d, ints, info, t, x, y, half, speed, fly):
    """Before a run stops because its step cannot pass (the adaptive step underflows, the
    implicit stage equations do not converge, a step's secant says the ball does not fit):
    whether a tip or kink of the surface lies within ``half`` of the contact point (x, y),
    where the normal turns by more than TIP_MIN over a vanishing span. A convex one is the
    real ball's lift-off (reported, at the time the contact point at ``speed`` would reach it
    from t) and the stop's reason (R_TIP); where the ball flies (``fly``, p[P_FLY]) it is a
    lift-off at a tip instead (``tip_liftoff``), from the run's state. A valley's is a kink
    where the ball does not fit. Returns whether one was found (the stop is then set)."""
    turn, tx, ty, convex = find_tip(fn, d, x, y, half)
    if not turn > TIP_MIN:
        return False
    reach = math.sqrt((tx - x) ** 2 + (ty - y) ** 2)
    when = t + reach / speed if speed > 0.0 else t
    if convex and fly != 0.0:
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = when, tx, ty, LIFT_TIP
        ints[I_STATUS] = TRANSITION
        ints[I_TRANSITION] = T_LIFTOFF
        info[F_EVENT_T], info[F_EVENT_X], info[F_EVENT_Y] = when, tx, ty
    elif convex:
        if math.isnan(info[F_LIFTOFF]):
            info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = when, tx, ty, 1.0
        _fail(ints, info, DOES_NOT_FIT, R_TIP, when, tx, ty, turn)
    else:
        _fail(ints, info, DOES_NOT_FIT, R_KINK, when, tx, ty, turn)
    return True


@JIT
def looks(r, z, probe, zn, pn):
    """The cheap looks at a step from (z, probe) to (zn, pn), from what its ends know: whether
    the ball does not fit at the end; whether the step bends sharper than the curvatures at
    its ends explain (``sharp``: a kink, or a secant curvature with r*kappa >= 1); whether the
    height changed off the slopes' trapezoid (``jumpy``). Returns them with the bend
    -(N1 - N0).(phi1 - phi0) and the squared chord |phi1 - phi0|^2."""
    f0 = probe[PROBE_HEIGHT]
    dx, dy, df = zn[0] - z[0], zn[1] - z[1], pn[PROBE_HEIGHT] - f0
    bend = -((pn[0] - probe[0]) * dx + (pn[1] - probe[1]) * dy + (pn[2] - probe[2]) * df)
    chord2 = dx * dx + dy * dy + df * df
    worst = max(probe[PROBE_FIT], pn[PROBE_FIT], -probe[PROBE_FIT_LO], -pn[PROBE_FIT_LO])
    fit_end = pn[PROBE_FIT] >= 1.0
    sharp = chord2 > 0.0 and (r * bend >= chord2 or r * abs(bend) > chord2 * (2.0 * worst + KINK_SLACK))
    # the height change against the slopes' trapezoid, grad f = -(N1, N2) / N3; 1 / N3 bounds
    # 1 and |grad f| (squares: no root per step)
    w0, w1 = 1.0 / probe[2], 1.0 / pn[2]
    off = df + 0.5 * ((probe[0] * w0 + pn[0] * w1) * dx + (probe[1] * w0 + pn[1] * w1) * dy)
    jumpy = off * off > JUMP_SLACK * JUMP_SLACK * (dx * dx + dy * dy) * (w0 + w1) ** 2 + 1e-24 * (1.0 + f0 * f0)
    return fit_end, sharp, jumpy, bend, chord2


@JIT
def step_events(fn, d, p, W, mk, n, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, segment, Ye,
                Re, pe, sa, sb, sm, stepping, watch):
    """The validity checks and events of a finished step from t to t + h, located on its dense
    output. Returns -1 while the run may go on; otherwise the run stops (status and reason
    set) and the result is theta, the last valid point of the step (0 <= theta < 1).

    Stops: r*kappa reaches 1 (at the step's end, or inside a step that raced or nears the
    edge of the no-fit region, where ``fold_search`` takes it again in sub-steps; ``segment``:
    fixed steps, whose contact point may race); a kink or cusp of a valley; a jump in height. A convex
    kink (a ridge) is a lift-off there, and F.N turning negative is one: the first is kept.
    A step bending more sharply than the curvatures at its ends explain is searched for a
    kink; one whose secant curvature says r*kappa >= 1 stops the run even where smooth.
    """
    fit_end, sharp, jumpy, bend, chord2 = looks(p[0], z, probe, zn, pn)
    raced = segment and contact_raced(h, z, zn, K, 0, last)
    raced |= stages_raced(K, last)
    # nearing: the edge is less than a step ahead of this step's end, or of the last step's
    fold = fold_ahead(t, h, probe, pn)
    raced |= fold < t + 2.0 * h or info[F_FOLD] < t + 2.0 * h  # (nan before the first step)
    info[F_FOLD] = fold
    force_end = pn[PROBE_FORCE] < 0.0 and math.isnan(info[F_LIFTOFF])
    jolted = math.isnan(info[F_LIFTOFF]) and centre_jolted(p[0], h, z, probe, zn, pn)
    turned = watch and (mode_changes(p, n, probe, pn) != 0 or (resisted_size(n) and sides_turn(p, d, n, pn) != 0)
                        or (not segment and passed_beside(p, n, probe, pn)))
    # (watch: ``contact_watched``)
    dips = dipping(p, n, h, probe, pn, info) if watch else 0
    if watch and resisted_size(n) and spin_stops(p, d, n, h, probe):
        dips += 4
    turned |= dips != 0
    if not (fit_end or sharp or jumpy or raced or force_end or jolted or turned):
        return -1.0  # the usual step: nothing to look at closer
    valid = -1.0
    if fit_end or sharp or jumpy or raced or force_end or jolted:
        valid = examine_step(fn, d, p, W, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe,
                             sa, sb, sm, fit_end, sharp, jumpy, raced, force_end, jolted, bend, chord2, stepping)
    if turned and valid < 0.0:
        # (refine as a float: the loops pass segment as a constant, and a constant bool would
        # compile locate_transition once for each value)
        valid = locate_transition(fn, d, p, W, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, Ye, Re,
                                  pe, sa, sb, dips, stepping, 1.0 if segment else 0.0)
    return valid


@JIT
def contact_watched(p, n):
    """Whether a run can change contact mode (a slip, grip, lift-off or rest stop): a sliding ball,
    a finite mu, a ball that flies or one that carries the dissipation. False for the 2011 model,
    whose loops then skip the looks (decided once per call of a loop: a condition that does not
    change inside it)."""
    return p[P_FLY] != 0.0 or p[P_MU] < math.inf or sliding_size(n) or resisted_size(n)


@JIT
def mode_changes(p, n, probe, pn):
    """Which change of contact mode the ends of a step (probes probe and pn) say happens
    inside it, for a state of length n: T_LIFTOFF (F.N < 0 at the end, where the ball flies:
    p[P_FLY]), T_SLIP (rolling with a finite mu: the friction rolling needs exceeds mu F.N at
    the end), T_GRIP (sliding: the slip velocity at the end points against the one at the
    start); 0 for none (always, in the 2011 model: mu inf and glued). The first found; the
    earliest inside the step is ``locate_transition``'s."""
    if p[P_FLY] != 0.0 and pn[PROBE_FORCE] < 0.0:
        return T_LIFTOFF
    if sliding_size(n):
        u0 = probe[PROBE_SLIP] ** 2 + probe[PROBE_SLIP + 1] ** 2 + probe[PROBE_SLIP + 2] ** 2
        dot = (probe[PROBE_SLIP] * pn[PROBE_SLIP] + probe[PROBE_SLIP + 1] * pn[PROBE_SLIP + 1]
               + probe[PROBE_SLIP + 2] * pn[PROBE_SLIP + 2])
        return T_GRIP if u0 > 0.0 and dot <= 0.0 else 0
    if p[P_MU] < math.inf and pn[PROBE_NEED] > p[P_MU] * pn[PROBE_FORCE]:
        return T_SLIP
    return 0


@JIT
def passed_beside(p, n, probe, pn):
    """Whether a sliding step of an embedded pair passed its slip's zero beside it (docs/design.md
    §8, "grips"): the slip speed |u| rose from the step's start (not 0) to its end while the
    friction could hold the slip at both ends, |B| < (7/2) mu F_n / m (B: the slip's acceleration
    with friction off). There the exact slip falls at a rate of at least that difference all along
    and reaches 0 in finite time (a grip); a rise is the step's own error carrying u past 0 on one
    side of it (u.u0 still positive, so ``mode_changes`` sees no grip), and the pair's next steps
    would chatter about 0 until one of them crossed it. ``locate_transition`` grips where the slip
    at the step's start reaches 0 at its relaxed rate (``grip_ahead``), or, where that reaches past
    the step, where the step's dense output passes closest to 0 (``dip_bracket`` on MISS_EVENT)."""
    if not sliding_size(n):
        return False
    u0 = probe[PROBE_SLIP] ** 2 + probe[PROBE_SLIP + 1] ** 2 + probe[PROBE_SLIP + 2] ** 2
    u1 = pn[PROBE_SLIP] ** 2 + pn[PROBE_SLIP + 1] ** 2 + pn[PROBE_SLIP + 2] ** 2
    if not 0.0 < u0 < u1:
        return False
    return holds(p, probe) and holds(p, pn)


@JIT
def grip_ahead(p, probe, h, closest):
    """Where in a step of h that passed its slip's zero beside it (``passed_beside``) the slip
    reaches 0: at the rate (7/2) mu F_n / m - |B| from the step's start (probe), the rate at which the
    exact slip falls once its direction has relaxed to B's (its part across B relaxes at the rate
    (7/2) mu F_n / (m |u|), fast near 0: within a step there, the pair's stages follow it only
    roughly and carry u round 0, so the dense output's closest approach, ``closest``, can come early
    by a share of the step); ``closest`` where that rate is not positive or reaches past the step."""
    u = math.sqrt(probe[PROBE_SLIP] ** 2 + probe[PROBE_SLIP + 1] ** 2 + probe[PROBE_SLIP + 2] ** 2)
    b = math.sqrt(probe[PROBE_SLIP_PULL] ** 2 + probe[PROBE_SLIP_PULL + 1] ** 2 + probe[PROBE_SLIP_PULL + 2] ** 2)
    rate = slip_deceleration(p, probe) - b
    if rate > 0.0 and u < rate * h:
        return u / (rate * h)
    return closest


@JIT
def holds(p, pe):
    """Whether friction can hold a sliding ball's slip at a state with probe pe: its largest
    deceleration of the slip (``slip_deceleration``) exceeds B, the slip's acceleration without it."""
    a = slip_deceleration(p, pe)
    b = pe[PROBE_SLIP_PULL] ** 2 + pe[PROBE_SLIP_PULL + 1] ** 2 + pe[PROBE_SLIP_PULL + 2] ** 2
    return b < a * a


# A change of contact mode that begins and ends inside one step (F.N dipping below 0 and back, or
# the friction rolling needs rising past mu F.N and back) leaves both ends of the step on the same
# side. Where a condition at the step's ends is within DIP_REACH times what it changed by over this
# step or the last (per step) of 0, the step's dense output is searched for it: the condition at
# DIP_SAMPLES - 1 evenly spaced points, then, where none has crossed, a golden-section search for
# the condition's largest value (DIP_ITERATIONS at most) around the largest sample. A quadratic
# dip whose ends are both on one side reaches at most a quarter of what the step before changed
# by: DIP_REACH 1 leaves a margin of four. The first step of a run (no step before) is searched.
DIP_REACH = 1.0
DIP_SAMPLES = 8
DIP_ITERATIONS = 40
GOLDEN = 0.6180339887498949
REFINE_TRIES = 16   # the method's own steps tried to place a change of mode (``refine_transition``)
REFINE_SPAN = 1e-3  # the dense output's slope of the condition is taken over this much of the step


@JIT
def near_zero(g0, g1, h, info, slot):
    """Whether a condition negative at both ends of a step of h (g0, g1) comes near enough to 0
    that it may cross inside (DIP_REACH); info[slot] holds its rate over the last step, and then
    this step's."""
    rate = (g1 - g0) / h
    before = info[slot]
    info[slot] = rate
    if not (g0 < 0.0 and g1 < 0.0):   # (a crossing at the ends is ``mode_changes``'s)
        return False
    if math.isnan(before):   # the run's first step
        return True
    return max(g0, g1) >= -DIP_REACH * h * max(abs(rate), abs(before))


@JIT
def dipping(p, n, h, probe, pn, info):
    """The changes of contact mode that may begin and end inside a step (``near_zero``) for a
    state of length n: 1 lift-off (where the ball flies), 2 slip (rolling with a finite mu), or
    both (3); 0 none."""
    dips = 0
    if p[P_FLY] != 0.0 and near_zero(-probe[PROBE_FORCE], -pn[PROBE_FORCE], h, info, F_RATE_FORCE):
        dips += 1
    mu = p[P_MU]
    if mu < math.inf and not sliding_size(n) and near_zero(
            probe[PROBE_NEED] - mu * probe[PROBE_FORCE], pn[PROBE_NEED] - mu * pn[PROBE_FORCE], h, info, F_RATE_SLIP):
        dips += 2
    return dips


@JIT
def spin_stops(p, d, n, h, probe):
    """Whether a kinetic spin couple (its side d[D_SIDE + 3]) would, at the rate omega.N
    has at the step's start (probe), take omega.N to 0 within the step of h: the pull may then turn
    it back inside the step, both ends on the side of the start, past a zero the ends do not show
    (``locate_transition`` searches the dense output for it, ``dip_bracket``; bit 4 of ``dipping``'s)."""
    side = d[D_SIDE + 3]
    if side == 0.0 or p[P_SPIN] == 0.0:
        return False
    rate = probe[PROBE_SPIN_PULL] - side * spin_limit(p, probe[PROBE_FORCE])
    return rate * side < 0.0 and 0.4 * p[5] * abs(spin_of(probe)) < h * abs(rate)


@COLD
def dip_bracket(kind, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, ga, ints, out):
    """Search the step's dense output for a change of mode whose condition g is ga < 0 at the
    step's start and negative at its end (see DIP_REACH): out = (a, g(a), b, g(b)) with
    g(a) < 0 <= g(b) around the first crossing found; returns whether one was found. Where none
    is, out[0:2] = (theta, g(theta)) at the condition's largest value found (``MISS_EVENT``: where
    the slip passes closest to 0)."""
    a, g_a, top, g_top = 0.0, ga, 0.0, ga
    for j in range(1, DIP_SAMPLES):
        x = j / DIP_SAMPLES
        g = event_value(kind, fn, d, p, z, R, h, P, K, x, Ye, Re, pe, s)
        ints[I_EVALS] += 1
        if g >= 0.0:
            out[0], out[1], out[2], out[3] = a, g_a, x, g
            return True
        if g > g_top:
            top, g_top = x, g
        a, g_a = x, g
    # none of the samples crossed: the condition's largest value near the largest sample
    lo = max(top - 1.0 / DIP_SAMPLES, 0.0)
    hi = min(top + 1.0 / DIP_SAMPLES, 1.0)
    g_lo = event_value(kind, fn, d, p, z, R, h, P, K, lo, Ye, Re, pe, s)
    c, e = hi - GOLDEN * (hi - lo), lo + GOLDEN * (hi - lo)
    gc = event_value(kind, fn, d, p, z, R, h, P, K, c, Ye, Re, pe, s)
    ge = event_value(kind, fn, d, p, z, R, h, P, K, e, Ye, Re, pe, s)
    ints[I_EVALS] += 3
    for _ in range(DIP_ITERATIONS):
        if gc >= 0.0 or ge >= 0.0:
            if gc >= 0.0:
                out[0], out[1], out[2], out[3] = lo, g_lo, c, gc
            else:
                out[0], out[1], out[2], out[3] = c, gc, e, ge
            return True
        if gc > ge:   # the largest value lies in [lo, e]
            hi, e, ge = e, c, gc
            c = hi - GOLDEN * (hi - lo)
            gc = event_value(kind, fn, d, p, z, R, h, P, K, c, Ye, Re, pe, s)
        else:         # in [c, hi]
            lo, g_lo, c, gc = c, gc, e, ge
            e = lo + GOLDEN * (hi - lo)
            ge = event_value(kind, fn, d, p, z, R, h, P, K, e, Ye, Re, pe, s)
        ints[I_EVALS] += 1
    out[0], out[1] = (c, gc) if gc > ge else (e, ge)
    return False


@COLD
def step_condition(kind, stepping, fn, d, p, W, P, h, theta, z, R, K, last, Y, zn, Rn, pn, ints, s):
    """g of a change of mode (``condition``) at the end of the method's own step from the step's
    start to theta (zn, Rn, pn then hold that state); +inf where the step fails."""
    bad = search_step(stepping, fn, d, p, W, P, theta * h, z, R, K, last, Y, zn, Rn, pn, ints)
    g = condition(kind, p, s, pn)
    return g if bad == 0 and math.isfinite(g) else math.inf


@COLD
def refine_transition(kind, stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints, s, Ye, Re, pe,
                      theta, b, gb):
    """Place a change of mode located at theta on the step's dense output to the method's own
    accuracy. The dense output's order may be below the method's (the cubic Hermite of Lawson5,
    the collocation polynomial of the Gauss methods: an error O(h^4) inside the step), and a
    change of mode placed on it carries that error into everything after; here the change is
    the root of g at the end of the method's own step from the step's start (a step of theta h,
    ``step_condition``), found by a Newton step with the dense output's slope from theta, then
    by the secant through the last two tries, bisecting where it leaves the bracket.

    b, gb: the end of the bracket on the dense output (g < 0 at the step's start), gb the
    method's g there if known (the step's end), else nan. Returns the fraction of the step, on
    the side where the change has happened (g >= 0), with zn, Rn, pn the state there; -1 where
    none is found within REFINE_TRIES (the step's buffers are then spoilt: take it again)."""
    lo, hi = max(theta - REFINE_SPAN, 0.0), min(theta + REFINE_SPAN, 1.0)
    slope = (event_value(kind, fn, d, p, z, R, h, P, K, hi, Ye, Re, pe, s)
             - event_value(kind, fn, d, p, z, R, h, P, K, lo, Ye, Re, pe, s)) / (hi - lo)
    a, bracketed = 0.0, not math.isnan(gb)
    x, x_old, g_old, reached, found = theta, math.nan, math.nan, -1.0, False
    for it in range(REFINE_TRIES):
        g = step_condition(kind, stepping, fn, d, p, W, P, h, x, z, R, K, last, Y, zn, Rn, pn, ints, s)
        reached = x
        if g >= 0.0:
            b, bracketed = x, True
        else:
            a = x
        if bracketed and b - a <= ROOT_TOL:
            found = True
            break
        # Newton with the dense output's slope first, then the secant through the last two tries
        rate = slope if it == 0 else (g - g_old) / (x - x_old)
        move = -g / rate
        if math.isfinite(move) and abs(move) < 0.5 * ROOT_TOL:   # converged: step across the root
            move = 0.5 * ROOT_TOL if g < 0.0 else -0.5 * ROOT_TOL
        x_old, g_old = x, g
        x += move
        if bracketed and not a < x < b:   # (also a move that is not finite)
            x = 0.5 * (a + b)
        elif not 0.0 < x <= 1.0:
            return -1.0
    if not found:
        return -1.0
    if reached != b and not step_condition(kind, stepping, fn, d, p, W, P, h, b, z, R, K, last, Y, zn, Rn, pn,
                                           ints, s) >= 0.0:
        return -1.0
    return b


@COLD
def locate_transition(fn, d, p, W, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe, s, out,
                      dips, stepping, refine):
    """A step whose ends say the contact changes mode (``mode_changes``), or inside which it may
    (``dipping``: dips, whose dense output is searched, ``dip_bracket``; bit 4: a spin's zero,
    ``spin_stops``): locate the earliest
    change on the step's dense output to ROOT_TOL of the step, and where ``refine`` (1.0: fixed
    steps) or the run goes on from it (T_SIDE) to the method's own accuracy (``refine_transition``:
    K then holds the stages of the method's step from z to there); stop the run there (status
    TRANSITION, its kind, time and contact point in ints and info) and return the fraction of
    the step where it happens (``record_valid`` then records the state there, the one zn, Rn,
    pn hold where ints[I_HELD] is set); -1 when the dense output shows none after all.

    A slip that stops where rolling would need more friction than mu F.N is not a grip: the
    slip turns about, and the run stops as a slip (the next run slides on from zero slip)."""
    n, mk = shape_of(z)
    dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)
    mu = p[P_MU]
    best, kind, event = 2.0, 0, FORCE_EVENT
    b_end, g_end = 1.0, math.nan   # the chosen change's bracket's end on the dense output (g there)
    if p[P_FLY] != 0.0:
        ga, gb = -probe[PROBE_FORCE], -pn[PROBE_FORCE]
        found = ga < 0.0 < gb
        if not found and dips % 2 == 1:
            found = dip_bracket(FORCE_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, ga, ints, out)
        if found:
            a, hi = 0.0, 1.0
            if not gb > 0.0:   # (inside the step)
                a, ga, hi, gb = out[0], out[1], out[2], out[3]
            a, b = locate(FORCE_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, a, ga, hi, gb, ints)
            best, kind, event = b, T_LIFTOFF, FORCE_EVENT
            b_end, g_end = hi, -pn[PROBE_FORCE] if hi == 1.0 else math.nan
    if sliding_size(n):
        s[0], s[1], s[2] = probe[PROBE_SLIP], probe[PROBE_SLIP + 1], probe[PROBE_SLIP + 2]
        ga = -(s[0] * s[0] + s[1] * s[1] + s[2] * s[2])
        gb = -(s[0] * pn[PROBE_SLIP] + s[1] * pn[PROBE_SLIP + 1] + s[2] * pn[PROBE_SLIP + 2])
        if ga < 0.0 <= gb:
            a, b = locate(GRIP_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, 0.0, ga, 1.0, gb, ints)
            if refine == 0.0 and (pe[PROBE_SLIP] ** 2 + pe[PROBE_SLIP + 1] ** 2 + pe[PROBE_SLIP + 2] ** 2) > 1e-4 * -ga:
                # (a pair's slip crossed the plane of its start beside 0, above a hundredth of |u0|: carried round)
                b = grip_ahead(p, probe, h, b)
            if b < best:
                best, kind, event = b, T_GRIP, GRIP_EVENT
                b_end, g_end = 1.0, gb
        elif refine == 0.0 and passed_beside(p, n, probe, pn):   # (an embedded pair's step)
            zero = dip_bracket(MISS_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, ga, ints, out)
            b = out[2] if zero else grip_ahead(p, probe, h, out[0])
            if b < best:
                best, kind, event = b, T_GRIP, GRIP_EVENT
    elif mu < math.inf:
        ga = probe[PROBE_NEED] - mu * probe[PROBE_FORCE]
        gb = pn[PROBE_NEED] - mu * pn[PROBE_FORCE]
        found = ga < 0.0 < gb
        if not found and ga < 0.0 and dips & 2 != 0:
            found = dip_bracket(SLIP_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, ga, ints, out)
        if found:
            a, hi = 0.0, 1.0
            if not gb > 0.0:
                a, ga, hi, gb = out[0], out[1], out[2], out[3]
            a, b = locate(SLIP_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, a, ga, hi, gb, ints)
            if b < best:
                best, kind, event = b, T_SLIP, SLIP_EVENT
                b_end, g_end = hi, pn[PROBE_NEED] - mu * pn[PROBE_FORCE] if hi == 1.0 else math.nan
        elif 0.0 < gb:   # at the limit already at the step's start (a grip there, within round-off)
            best, kind = 0.0, T_SLIP
    if resisted_size(n):   # a couple's side turning (``sides_turn``): s[4:8] the sides at the step's start
        s[4], s[5], s[6], s[7] = d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2], d[D_SIDE + 3]
        if p[P_RESISTANCE] > 0.0 and (s[4] != 0.0 or s[5] != 0.0 or s[6] != 0.0):
            ga, gb = -turn_along(probe, s[4], s[5], s[6]), -turn_along(pn, s[4], s[5], s[6])
            if ga < 0.0 <= gb:
                a, b = locate(TURN_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, 0.0, ga, 1.0, gb, ints)
                if b < best:
                    best, kind, event = b, T_SIDE if sliding_size(n) else T_REST, TURN_EVENT
                    b_end, g_end = 1.0, gb
        if p[P_SPIN] > 0.0:
            spin = SPIN_EVENT if s[7] != 0.0 else LIMIT_EVENT   # (a static couple: its limit)
            ga, gb = condition(spin, p, s, probe), condition(spin, p, s, pn)
            found = ga < 0.0 <= gb
            if not found and ga < 0.0 and dips & 4 != 0:   # (``spin_stops``)
                found = dip_bracket(spin, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, ga, ints, out)
            if found:
                a, hi = 0.0, 1.0
                if not gb >= 0.0:   # (inside the step)
                    a, ga, hi, gb = out[0], out[1], out[2], out[3]
                a, b = locate(spin, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, a, ga, hi, gb, ints)
                if b < best:
                    best, kind, event = b, T_SIDE, spin
                    b_end, g_end = hi, gb if hi == 1.0 else math.nan
    if kind == 0:
        return -1.0
    held = False
    if (refine != 0.0 or kind == T_SIDE) and best > 0.0:   # (the pairs too where the run goes on from it)
        # (a grip's reference slip u0 is s[0:3], set above)
        theta = refine_transition(event, stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints, s, Ye,
                                  Re, pe, best, b_end, g_end)
        ints[I_DENSE] = -1
        if theta >= 0.0:
            best, held = theta, True
            copy_state(n, zn, Rn, pn, Ye, Re, pe)
        else:   # not found: the dense output's place stands (the step taken again)
            retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
            dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)
    if not held:
        state_at(fn, d, p, z, R, h, P, K, 0.0, best, Ye, Re, pe)
    if kind == T_GRIP and pe[PROBE_NEED] > mu * pe[PROBE_FORCE]:
        kind = T_SLIP
    elif kind == T_GRIP and p[P_RESISTANCE] > 0.0 and resisted_size(n) and stands(p, pe):
        kind = T_REST   # the slip and the rolling stop at once: the rolling resistance holds omega_t at 0
    # (the first lift-off, or this step's, which ``examine_step`` put on the dense output)
    if kind == T_LIFTOFF and (math.isnan(info[F_LIFTOFF]) or (info[F_LIFTOFF] >= t and info[F_LIFT_KINK] == 0.0)):
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + best * h, Ye[0], Ye[1], 0.0
    if held:
        ints[I_HELD] = 1
    ints[I_STATUS] = TRANSITION
    ints[I_TRANSITION] = kind
    info[F_EVENT_T], info[F_EVENT_X], info[F_EVENT_Y] = t + best * h, Ye[0], Ye[1]
    return best


@JIT
def centre_jolted(r, h, z, probe, zn, pn):
    """The ball's centre moved from the step's start to its end by more than twice what its
    speeds there explain. The centre's speed is continuous and bounded by the energy, so the
    exact motion cannot do that: the contact point passed (within round-off of the step) a
    point where the normal turns through a finite angle, as beside the tip of a cone, where
    the model's centre jumps across however short the step."""
    # the centre's velocity r omega x N + the slip velocity (0 rolling)
    c0 = r * (probe[PROBE_OMEGA + 1] * probe[2] - probe[PROBE_OMEGA + 2] * probe[1]) + probe[PROBE_SLIP]
    c1 = r * (probe[PROBE_OMEGA + 2] * probe[0] - probe[PROBE_OMEGA] * probe[2]) + probe[PROBE_SLIP + 1]
    c2 = r * (probe[PROBE_OMEGA] * probe[1] - probe[PROBE_OMEGA + 1] * probe[0]) + probe[PROBE_SLIP + 2]
    s0 = c0 * c0 + c1 * c1 + c2 * c2
    c0 = r * (pn[PROBE_OMEGA + 1] * pn[2] - pn[PROBE_OMEGA + 2] * pn[1]) + pn[PROBE_SLIP]
    c1 = r * (pn[PROBE_OMEGA + 2] * pn[0] - pn[PROBE_OMEGA] * pn[2]) + pn[PROBE_SLIP + 1]
    c2 = r * (pn[PROBE_OMEGA] * pn[1] - pn[PROBE_OMEGA + 1] * pn[0]) + pn[PROBE_SLIP + 2]
    s1 = c0 * c0 + c1 * c1 + c2 * c2
    dx = zn[0] - z[0] + r * (pn[0] - probe[0])
    dy = zn[1] - z[1] + r * (pn[1] - probe[1])
    dz = pn[PROBE_HEIGHT] - probe[PROBE_HEIGHT] + r * (pn[2] - probe[2])
    moved = dx * dx + dy * dy + dz * dz
    return moved > 4.0 * h * h * max(s0, s1) and moved > (JOLT_MIN * r) ** 2


@COLD
def examine_step(fn, d, p, W, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe, sa, sb, sm,
                 fit_end, sharp, jumpy, raced, force_end, jolted, bend, chord2, stepping):
    """``step_events`` for a step its cheap looks have flagged: locate what happens in it."""
    n, mk = shape_of(z)
    r = p[0]
    dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)

    stop, valid = 2.0, 0.0
    # the ball no longer fits: where along the step r*kappa reached 1. The step is taken again
    # in sub-steps (its own stages may have jumped the edge, its dense output bent around it)
    if raced or fit_end:
        edge = fold_search(fn, d, p, W, P, t, h, z, R, K, last, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe,
                           stepping)
        if edge >= 0.0:
            stop, valid = edge, edge
        else:  # no edge: the step stands, taken again (the search used its buffers)
            retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
            dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)
    if fit_end and stop > 1.0:  # the sub-steps all fit: locate the edge on the step's dense output
        gb = event_value(FIT_EVENT, fn, d, p, z, R, h, P, K, 1.0, Ye, Re, pe, sa)
        a, b = 0.0, 1.0
        if gb >= 0.0:  # the dense output agrees: locate the edge on it
            a, b = locate(FIT_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, sa, 0.0,
                          probe[PROBE_FIT] - 1.0, 1.0, gb, ints)
        surface_at(fn, d, r, z, h, P, K, b, Ye, sa)
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t + b * h, sa[0], sa[1], max(sa[6], 1.0))
        stop, valid = b, a
    # a bend sharper than the step's ends explain: a kink, or a bend tighter than the ball
    if sharp and stop > 1.0:
        a, b, turn = locate_break(KINK, fn, d, r, z, h, P, K, Ye, sa, sb, sm, 0.0, 1.0)
        if turn > BREAK_MIN:
            # (a backslash, not parentheses: the shipped code's stamp is made from the tokens)
            phi = (sb[0] - sa[0]) * (sb[3] - sa[3]) + (sb[1] - sa[1]) * (sb[4] - sa[4]) \
                + (sb[2] - sa[2]) * (sb[5] - sa[5])
            if phi < 0.0:  # the normal turns towards the motion: a valley, where the ball cannot fit
                _fail(ints, info, DOES_NOT_FIT, R_KINK, t + b * h, sb[0], sb[1], turn)
                stop, valid = b, a
            elif math.isnan(info[F_LIFTOFF]):  # a ridge: the real ball flies off it
                info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + a * h, sa[0], sa[1], 1.0
                edge = edge_line(K, sa, sb) if p[P_FLY] != 0.0 else NO_LINE
                clean = approach(KINK, fn, d, p, W, t, h, a, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, Ye, sa,
                                 sb, sm, info[F_LIFTOFF:F_LIFT_Y + 1], edge, stepping)
                if p[P_FLY] != 0.0:  # the ball flies: the run stops at the last state before the ridge
                    stop, valid = clean, clean
                    kink_liftoff(p, z, R, probe, zn, Rn, pn, ints, info, clean)
                else:  # the run goes on with the whole step, taken again (the approach used its buffers)
                    retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
                    dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)
        elif r * bend >= chord2 and chord2 > CHORD_ROUND_OFF * (1.0 + z[0] * z[0] + z[1] * z[1]
                                                            + probe[PROBE_HEIGHT] * probe[PROBE_HEIGHT]):
            # (a chord within round-off of the contact point's coordinates has no secant to judge: a step
            # ending at a ball's rest moves it 10^-15 m, and the normal's round-off over that bends like anything)
            # a step passing a tip of the surface within round-off of its stages bends like that too
            # (the normal turns through a finite angle over a span the dense output cannot resolve)
            turn, tx, ty, convex = find_tip(fn, d, sb[0], sb[1], max(math.sqrt(chord2), BREAK_SPAN))
            if turn > TIP_MIN and convex and p[P_FLY] != 0.0:   # the ball flies: from the state before the tip
                stop = valid = tip_liftoff(fn, d, p, W, t, h, a, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, info,
                                           tx, ty, stepping)
            elif turn > TIP_MIN and convex:  # the real ball leaves the surface there: a lift-off and a stop
                if math.isnan(info[F_LIFTOFF]):
                    info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + b * h, tx, ty, 1.0
                _fail(ints, info, DOES_NOT_FIT, R_TIP, t + b * h, tx, ty, turn)
                stop, valid = b, a
            elif turn > TIP_MIN:
                _fail(ints, info, DOES_NOT_FIT, R_KINK, t + b * h, tx, ty, turn)
                stop, valid = b, a
            else:
                _fail(ints, info, DOES_NOT_FIT, R_SECANT_NO_FIT, t + b * h, sb[0], sb[1], r * bend / chord2)
                stop, valid = b, a
    # a jump in height
    if jumpy and stop > 1.0:
        a, b, jump = locate_break(JUMP, fn, d, r, z, h, P, K, Ye, sa, sb, sm, 0.0, 1.0)
        if jump > BREAK_MIN * (1.0 + abs(sa[2])):
            _fail(ints, info, DOES_NOT_FIT, R_HEIGHT_JUMP, t + b * h, sb[0], sb[1], sb[2] - sa[2])
            stop, valid = b, a
    # the centre jumped: the contact point passed the tip of a cone or a like point where the
    # normal turns through a finite angle. Where the ball fits, such a point is convex: the real
    # ball leaves the surface there (a lift-off at a kink); the step stands
    if jolted and stop > 1.0 and math.isnan(info[F_LIFTOFF]):
        a, b, _ = locate_break(JOLT, fn, d, r, z, h, P, K, Ye, sa, sb, sm, 0.0, 1.0)
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + a * h, sb[0], sb[1], 1.0
        if p[P_FLY] != 0.0:   # the ball flies: from the state before the tip the contact point jumped over
            # (within the step's travel: a step may pass beside the tip the exact motion reaches)
            travel = math.sqrt((zn[0] - z[0]) ** 2 + (zn[1] - z[1]) ** 2 + (sb[0] - sa[0]) ** 2 + (sb[1] - sa[1]) ** 2)
            turn, tx, ty, convex = find_tip(fn, d, sb[0], sb[1], travel + BREAK_SPAN)
            if turn > TIP_MIN and convex:
                stop = valid = tip_liftoff(fn, d, p, W, t, h, a, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, info,
                                           tx, ty, stepping)
    # lift-off: F.N turns negative (first time only, before any stop)
    if force_end and stop > 1.0 and math.isnan(info[F_LIFTOFF]):
        a, b = locate(FORCE_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, sa, 0.0,
                      -probe[PROBE_FORCE], 1.0, -pn[PROBE_FORCE], ints)
        interpolate(z, h, P, K, b, Ye)
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + b * h, Ye[0], Ye[1], 0.0
    return valid if stop <= 1.0 else -1.0


@COLD
def kink_liftoff(p, z, R, probe, zn, Rn, pn, ints, info, clean):
    """Where the ball flies (p[P_FLY]), a lift-off at a ridge's kink (info[F_LIFTOFF ...]) stops
    the run as a transition whose state is the last one before the kink: zn, Rn, pn where the
    ``approach`` reached one (clean > 0), else the step's start."""
    if not clean > 0.0:
        copy_state(z.shape[0], z, R, probe, zn, Rn, pn)
    ints[I_HELD] = 1
    ints[I_STATUS] = TRANSITION
    ints[I_TRANSITION] = T_LIFTOFF
    info[F_EVENT_T], info[F_EVENT_X], info[F_EVENT_Y] = info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y]


NO_LINE = (0.0, 0.0, 0.0, 0.0, 0.0)   # (``past``: no line, nothing past it)
TIP_HALVINGS = 60   # sub-steps that bisect the time the contact point reaches a tip (``tip_liftoff``)...
TIP_RESTARTS = 30   # ...from the last clean one again, at most this many times


@COLD
def tip_liftoff(fn, d, p, W, t, h, theta, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, info, tx, ty, stepping):
    """Where the ball flies, the contact point reaching a convex tip at (tx, ty) (a point where the
    normal turns through a finite angle: the tip of a cone) stops the run as a lift-off
    (``kink_liftoff``) at the last state before it, marked info[F_LIFT_KINK] = LIFT_TIP: the ball
    then leaves the tip or would pivot about it (docs/design.md §1, "A tip"). That state is the
    end of the longest sub-step, from a first guess theta (a fraction of the step), that stays
    before the tip (``clean_fraction``: its end and its stages short of the line through the tip
    across the way to it, by 4 BREAK_SPAN, and its centre not jolted; in the model's motion the
    contact point may creep into the tip while the centre turns about it); then again from the
    state reached (z, R, probe move on to it), whose shorter sub-steps resolve the last stretch
    better, until the contact point is within twice that of the tip or no sub-step gets nearer. The lift-off's place is
    the tip. Returns the fraction of the step where the run stops."""
    n, mk = shape_of(z)
    done, m = 0.0, theta    # (the fraction of the step the state has moved on by)
    near = 4.0 * BREAK_SPAN * (1.0 + abs(tx) + abs(ty))   # (the tip is found to BREAK_SPAN)
    for _ in range(TIP_RESTARTS):
        span = (1.0 - done) * h
        gap = math.sqrt((tx - z[0]) ** 2 + (ty - z[1]) ** 2)
        if not gap > 0.0:
            break
        line = (tx, ty, (tx - z[0]) / gap, (ty - z[1]) / gap, near)
        lo = clean_fraction(stepping, fn, d, p, W, P, t, span, m, z, R, K, last, probe, Y, zn, Rn, pn, ints, line,
                            1.0)
        if not lo > 0.0:
            break
        search_step(stepping, fn, d, p, W, P, lo * span, z, R, K, last, Y, zn, Rn, pn, ints)   # (the clean one)
        accept(p, mk, n, z, R, K, last, probe, zn, Rn, pn)
        done += lo * (1.0 - done)
        m = 0.5
        if (z[0] - tx) ** 2 + (z[1] - ty) ** 2 <= 4.0 * near * near:
            break
    info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + done * h, tx, ty, LIFT_TIP
    kink_liftoff(p, z, R, probe, zn, Rn, pn, ints, info, 0.0)   # (the state reached: z, R, probe)
    return done


@COLD
def clean_fraction(stepping, fn, d, p, W, P, t, span, m, z, R, K, last, probe, Y, zn, Rn, pn, ints, line, tip):
    """The longest sub-step from z, as a fraction of ``span`` (bisected from a first guess m to
    round-off of the time, 0 where none is), that stays before a break of the surface: it is
    finite and neither its end nor any of its stages (``stages_past``) lies past ``line`` (a tip
    or a ridge's edge), nor (``tip``) does the ball's centre jump. A stage past it samples the far
    face, whose rates differ from the near one's by a finite amount however short the step: a
    step whose end still falls short of the break errs by O(h) (fixed steps would reach it at
    order 1). (``tip`` a float, 1.0 or 0.0, as the flags of COLD functions are.)"""
    r = p[0]
    lo, hi = 0.0, 1.0
    for _ in range(TIP_HALVINGS):
        if not lo < m < hi:
            m = 0.5 * (lo + hi)
        crossed = search_step(stepping, fn, d, p, W, P, m * span, z, R, K, last, Y, zn, Rn, pn, ints) != 0
        if not crossed:
            crossed = (past(zn[0], zn[1], line) or stages_past(stepping, W, m * span, z, K, last, line)
                       or (tip != 0.0 and centre_jolted(r, m * span, z, probe, zn, pn)))
        if crossed:
            hi = m
        else:
            lo = m
        if not (hi - lo) * span > 4e-16 * (1.0 + abs(t)):
            break
        m = 0.5 * (lo + hi)
    return lo


@JIT
def past(x, y, line):
    """Whether the point (x, y) lies past ``line`` = (x₀, y₀, m_x, m_y, near), or within near
    before it: (x − x₀, y − y₀)·m > −near, m its unit normal pointing across it (NO_LINE: no
    point does)."""
    return (x - line[0]) * line[2] + (y - line[1]) * line[3] > -line[4]


@JIT
def stages_past(stepping, W, h, z, K, last, line):
    """Whether a stage of the step of size h just taken from z (its stage derivatives in K) put
    its contact point past ``line`` (``past``)."""
    stages = (last - 1) // 2 if stepping == IMPLICIT else last - 1   # (Gauss: W rows 1 .. s hold a)
    for i in range(1, stages + 1):
        x, y = z[0], z[1]
        for j in range(last):
            c = h * W[i, j]
            if c != 0.0:
                x += c * K[j, 0]
                y += c * K[j, 1]
        if past(x, y, line):
            return True
    return False


@JIT
def edge_line(K, sa, sb):
    """The line of a ridge's edge in the plane, as ``past`` reads it, from the surface just before
    it (sa) and just after it (sb): through sa's contact point, along the horizontal part of the
    faces' normals' cross product, its normal pointing the way the contact point moves (K[0]),
    near 4 BREAK_SPAN. NO_LINE where the normals give none."""
    ax, ay = sa[4] * sb[5] - sa[5] * sb[4], sa[5] * sb[3] - sa[3] * sb[5]
    size = math.sqrt(ax * ax + ay * ay)
    if not size > 0.0:
        return NO_LINE
    mx, my = -ay / size, ax / size
    if mx * K[0, 0] + my * K[0, 1] < 0.0:
        mx, my = -mx, -my
    return sa[0], sa[1], mx, my, 4.0 * BREAK_SPAN * (1.0 + abs(sa[0]) + abs(sa[1]))


@JIT
def contact_raced(h, z, zn, K, first, last):
    """The contact point moved from z to zn by more than twice what its speeds at the step's
    ends (K[first], K[last]) explain."""
    dx, dy = zn[0] - z[0], zn[1] - z[1]
    speed = max(K[first, 0] ** 2 + K[first, 1] ** 2, K[last, 0] ** 2 + K[last, 1] ** 2)
    return dx * dx + dy * dy > 4.0 * h * h * speed


@JIT
def fold_ahead(t, h, probe, pn):
    """When the contact point, from t to t + h with probes probe and pn, reaches the edge of the
    no-fit region if 1 - r*kappa goes on falling: the earlier of the straight extrapolations
    of 1 - r*kappa and of its square (the square falls linearly near the edge); inf when it
    does not fall."""
    u0, u1 = 1.0 - probe[PROBE_FIT], 1.0 - pn[PROBE_FIT]
    if not u1 < u0:
        return math.inf
    return t + h + h * min(u1 / (u0 - u1), u1 * u1 / (u0 * u0 - u1 * u1))


@JIT
def stages_raced(K, last):
    """A stage's contact velocity is off the step's start's by more than STAGE_RACE times the
    larger of the ends' (the stages felt a fold of the centre surface the ends do not show)."""
    speed = max(K[0, 0] ** 2 + K[0, 1] ** 2, K[last, 0] ** 2 + K[last, 1] ** 2)
    spread = 0.0
    for i in range(1, last):
        spread = max(spread, (K[i, 0] - K[0, 0]) ** 2 + (K[i, 1] - K[0, 1]) ** 2)
    return spread > STAGE_RACE * STAGE_RACE * speed


@COLD
def line_fits(fn, d, r, z0, z1):
    """The ball fits at LINE_SAMPLES points evenly inside the straight line between the contact
    points of z0 and z1 (a sub-step may jump a thin no-fit region with both ends fitting)."""
    for j in range(1, LINE_SAMPLES + 1):
        theta = j / (LINE_SAMPLES + 1.0)
        landscape(fn, z0[0] + theta * (z1[0] - z0[0]), z0[1] + theta * (z1[1] - z0[1]), data_pointer(d))
        iW = 1.0 / math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
        if not r * curvatures(d[1], d[2], d[3], d[4], d[5], iW)[0] < 1.0:
            return False
    return True


@COLD
def retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """Take the step from z again (after a search inside it used the step's buffers)."""
    search_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if p[P_TURN] == 0.0:  # (carrying omega, the step has taken its dense-output stages again)
        ints[I_DENSE] = -1


@COLD
def fold_time(fn, d, r, Zs, K, ps):
    """How long until the contact point, at Zs with velocity K[0] and probe ps, reaches the edge
    of the no-fit region, if 1 - r*kappa keeps falling as the square root it is near there:
    (1 - r*kappa) / (2 d(r*kappa)/dt), the rate from a difference along the velocity; inf
    when r*kappa is not growing."""
    k1, k2 = K[0, 0], K[0, 1]
    speed = math.sqrt(k1 * k1 + k2 * k2)
    if not speed > 0.0:
        return math.inf
    delta = 1e-7 * (1.0 + max(abs(Zs[0]), abs(Zs[1])))
    landscape(fn, Zs[0] + delta * k1 / speed, Zs[1] + delta * k2 / speed, data_pointer(d))
    iW = 1.0 / math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
    rate = (r * curvatures(d[1], d[2], d[3], d[4], d[5], iW)[0] - ps[PROBE_FIT]) / delta * speed
    return (1.0 - ps[PROBE_FIT]) / (2.0 * rate) if rate > 0.0 else math.inf


@COLD
def fold_search(fn, d, p, W, P, t, h, z, R, K, last, probe, Y, zn, Rn, pn, ints, info, Zs, Rs, ps, stepping):
    """Take the step from t to t + h again in sub-steps that each stay within half the time
    ``fold_time`` gives to the edge of the no-fit region (a fold of the centre surface, which
    the contact point reaches at unbounded speed) and are accepted only where they are
    finite, their contact point does not race and they keep at least half of 1 - r*kappa.
    Towards the edge the sub-steps shrink geometrically; the edge is where they fall below
    FOLD_TOL of the step.

    Returns -1 when the sub-steps reach the step's end (no edge; zn, Rn, pn, K spoilt: take
    the step again). Otherwise the run stops (DOES_NOT_FIT at the edge, ints[I_HELD] set)
    and the result is the fraction of the step of the last valid sub-state, which zn, Rn,
    pn hold. Zs, Rs, ps: scratch for the sub-state.
    """
    n, mk = shape_of(z)
    r = p[0]
    spare = K.shape[0] - 1
    copy_state(n, z, R, probe, Zs, Rs, ps)
    for q in range(n):
        K[spare, q] = K[0, q]
    ts, grow, edge = 0.0, 0.25, -1.0
    for _ in range(FOLD_TRIES):
        reach = fold_time(fn, d, r, Zs, K, ps) / h
        if 0.5 * reach <= FOLD_TOL:  # at the edge
            edge = min(ts + reach, 1.0)
            break
        hs = min(grow, 0.5 * reach, 1.0 - ts)
        bad = search_step(stepping, fn, d, p, W, P, hs * h, Zs, Rs, K, last, Y, zn, Rn, pn, ints)
        u0, u1 = 1.0 - ps[PROBE_FIT], 1.0 - pn[PROBE_FIT]
        steady = bad == 0 and not (contact_raced(hs * h, Zs, zn, K, 0, last) or stages_raced(K, last))
        across = bad == 0 and (u1 <= 0.0 or not line_fits(fn, d, r, Zs, zn))
        if not (steady and u1 >= 0.5 * u0) or across:
            near = u0 < FOLD_NEAR or across
            if hs > (JUMP_TOL if steady and not near else FOLD_TOL):
                grow = 0.1 * hs
                continue
            if near:
                edge = min(ts + hs, 1.0)
                break
            if bad != 0:  # not finite however short, away from the edge: the step stands
                break
            # (else a jump of the curvature, where the ball still fits, is crossed)
        # the sub-step is taken: its end is the new sub-state (u = 0 again for Munthe-Kaas)
        ts += hs
        grow = 2.0 * hs
        accept(p, mk, n, Zs, Rs, K, last, ps, zn, Rn, pn)
        if ts >= 1.0 - FOLD_TOL:
            break
    for q in range(n):
        K[0, q] = K[spare, q]
    ints[I_DENSE] = -1
    if edge < 0.0:
        return -1.0
    copy_state(n, Zs, Rs, ps, zn, Rn, pn)
    ints[I_HELD] = 1
    _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t + edge * h, Zs[0], Zs[1], max(ps[PROBE_FIT], 1.0))
    return ts


REFINE_STEPS = 6  # shorter steps tried to reach the last valid state before a stop


@COLD
def approach(kind, fn, d, p, W, t, h, theta, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, Ye, sa, sb, sm,
             event, line, stepping):
    """Reach the last valid state before a break inside a step from t to t + h, first guessed
    at theta (a fraction of the step) from the step's dense output.

    The dense output of a step across a kink, a jump or the edge of the no-fit region (kind
    KINK, JUMP or FIT_EVENT) is spoiled by the stages beyond it, so the state is computed by a
    step of theta h from the step's start instead; while such a step still crosses (its ends'
    looks say so), the break is located again on its own, less spoiled, dense output and the
    step shortened to before it; a clean step's dense output, continued a little past its end,
    times a kink or jump. event = (time, x, y) of the break is updated on the way. Where ``line``
    is a ridge's edge (``edge_line``; NO_LINE: none), the clean step is the longest whose end and
    stages stay before it (``clean_fraction``): its stages must not sample the far face, and its
    end is within 4 BREAK_SPAN of the edge, from where the flight or the turn over the edge is
    carried to the kink along the tangent plane (a clean step ending earlier, as the dense output
    of the step across it may say, left that an O(τ²) error in the surface's bending). Returns
    the theta of the clean step (zn, Rn, pn hold its end), or 0 when none was found.
    """
    n, mk = shape_of(z)
    r = p[0]
    for _ in range(REFINE_STEPS):
        hs = theta * h
        if not hs > 0.0:
            break
        bad = search_step(stepping, fn, d, p, W, P, hs, z, R, K, last, Y, zn, Rn, pn, ints)
        if bad != 0:
            break
        fit_end, sharp, jumpy, bend, chord2 = looks(r, z, probe, zn, pn)
        if not (fit_end or sharp or jumpy):
            if line[4] > 0.0:   # (a ridge's edge: the longest step before it, its stages too)
                theta = clean_fraction(stepping, fn, d, p, W, P, t, h, theta, z, R, K, last, probe, Y, zn, Rn, pn,
                                       ints, line, 0.0)
                hs = theta * h
                if not hs > 0.0 or search_step(stepping, fn, d, p, W, P, hs, z, R, K, last, Y, zn, Rn, pn, ints) != 0:
                    break
            if kind != FIT_EVENT and theta < 1.0:
                a, b, size = locate_break(kind, fn, d, r, z, hs, P, K, Ye, sa, sb, sm, 1.0, min(1.0 / theta, 2.0))
                if size > 0.0:
                    event[0], event[1], event[2] = t + b * hs, sb[0], sb[1]
            return theta
        a, b, size = 0.0, 0.0, 0.0
        if kind == FIT_EVENT:
            if fit_end:
                a, b = locate(FIT_EVENT, fn, d, p, z, R, hs, P, K, Ye, Rn, pn, sa, 0.0,
                              probe[PROBE_FIT] - 1.0, 1.0, pn[PROBE_FIT] - 1.0, ints)
                surface_at(fn, d, r, z, hs, P, K, b, Ye, sa)
                event[0], event[1], event[2] = t + b * hs, sa[0], sa[1]
        elif sharp or jumpy:
            a, b, size = locate_break(kind, fn, d, r, z, hs, P, K, Ye, sa, sb, sm, 0.0, 1.0)
            if size > 0.0:
                event[0], event[1], event[2] = t + b * hs, sb[0], sb[1]
        theta *= a if a > 0.0 else 0.5
    return 0.0


@COLD
def record_valid(fn, d, p, W, t, h, theta, z, R, K, last, P, probe, rows, ints, info, Y, zn, Rn, pn,
                 Ye, sa, sb, sm, stepping):
    """A run stopped inside a step: its last valid state, reached by ``approach`` (or else the
    step's start), is the last row; the stop's time and place are refined on the way. A run
    stopped at a change of contact mode: the state there on the step's dense output is the
    last row and the run's state (z, R, probe)."""
    if ints[I_STATUS] == TRANSITION:  # the state at the change of mode, from the dense output
        if ints[I_HELD] == 0:  # (held: the last state before a ridge, ``kink_liftoff``)
            state_at(fn, d, p, z, R, h, P, K, 0.0, theta, zn, Rn, pn)
        record(rows, ints[I_ROWS], t + theta * h, zn, Rn, pn, p)
        ints[I_ROWS] += 1
        hold(p, z, R, probe, zn, Rn, pn)
        return
    if ints[I_HELD] == 1:  # the last valid state is known already (``fold_search``)
        record(rows, ints[I_ROWS], t + theta * h, zn, Rn, pn, p)
        ints[I_ROWS] += 1
        return
    reason = ints[I_REASON]
    kind = JUMP if reason == R_HEIGHT_JUMP else FIT_EVENT if reason == R_NO_FIT else KINK
    event = info[F_FAIL_T:F_FAIL_Y + 1]
    theta = approach(kind, fn, d, p, W, t, h, theta, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, Ye, sa, sb,
                     sm, event, NO_LINE, stepping)
    if theta > 0.0:
        record(rows, ints[I_ROWS], t + theta * h, zn, Rn, pn, p)
        ints[I_ROWS] += 1
    else:
        record_last(rows, ints, t, z, R, probe, p)
