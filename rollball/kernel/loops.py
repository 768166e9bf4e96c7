"""The stepping loops: fixed steps (``advance``) and an embedded pair with step-size control
(``advance_adaptive``). (A sweep's batch of fixed-step runs: ``batch``.)"""

from __future__ import annotations

import math

import numpy as np

from .dense import state_at
from .events import TIP_REACH, contact_watched, fold_search, looks, record_valid, step_events, tip_liftoff, tip_stop
from .explicit import STEP_NOT_CONVERGED, carry_orientation, dense_stages, pair_step
from .interface import (
    D_SLIP, EXPLICIT, F_EVENT_X, F_EVENT_Y, F_FOLD, F_H, F_TIME, I_LAST_RECORDED, I_NONFINITE, I_REJECTED,
    I_RETRY, I_ROWS, I_STATUS, I_STEPS, MOTION_SIZE, NONFINITE, OK, PROBE_FORCE, PROBE_SLIP, PROBE_SLIP_PULL,
    P_FLY, P_MU, RUNNING, R_NOT_CONVERGED, R_ORIENTATION, R_STEP_UNDERFLOW, R_UNDEFINED, DOES_NOT_FIT, R_NO_FIT,
    PROBE_FIT,
    TRANSITION, T_GRIP, T_STIFF, F_EVENT_T, I_TRANSITION, P_STIFF, D_SIDE, I_DENSE, I_EVALS, I_HELD, PROBE_OMEGA,
    P_RESISTANCE, P_TURN, P_UNIT, T_REST, T_SIDE, MIN_STEP, EXIT_MARGIN, SLIP_TIME, TURN_SHARE, grid_steps_before)
from .lowlevel import COLD, JIT
from .physics import (SLOW_POWER, couple_sides, evaluate, motion_size, resisted_size, shape_of, sliding_size,
                      slip_deceleration, slow_corrected, spin_side, TURN_TIME, turning_point)
from .recording import _fail, hold, record, record_last, start
from .steps import (MAX_FACTOR, MIN_FACTOR, NONFINITE_TRIES, SAFETY, accept, error_norm,
                    next_step_factor, take_step)
from .unpacking import scratch

grid_before = JIT(grid_steps_before)


@JIT
def speed_of(K):
    """The contact point's speed at the step's start (K[0]: the state's derivative there)."""
    return math.sqrt(K[0, 0] * K[0, 0] + K[0, 1] * K[0, 1])


@JIT
def reach_of(K, h, z):
    """How far around the contact point a step of h that cannot pass looks for a tip of the
    surface: twice the step's travel, at least TIP_REACH (relative to 1 + |x| + |y|)."""
    return max(2.0 * h * speed_of(K), TIP_REACH * (1.0 + abs(z[0]) + abs(z[1])))


@JIT
def slip_reference(d, probe, p, h, cap):
    """The slip velocity at the step's start, which a sliding ball's friction keeps its side of
    through the step (``sliding_dynamics``), into d[D_SLIP:D_SLIP + 3] (rolling: 0, never read),
    and into d[D_SLIP + 3] the slip speed below which the slip's direction is stiff (a rate
    |B| / |u|). Fixed steps (``cap`` inf): inf where friction would stop the slip at the step's
    start within the step (|u| < 7/2 mu F_n h / m), and ``advance`` stops there (T_STIFF: the run
    in Python takes that stretch with an adaptive pair), else 0; the adaptive pairs: ``cap``
    (``slow_slip``), below which a growing slip's direction is the slow motion's
    (``sliding_dynamics``), above which the exact equations hold and their error control resolves
    them."""
    u1, u2, u3 = probe[PROBE_SLIP], probe[PROBE_SLIP + 1], probe[PROBE_SLIP + 2]
    d[D_SLIP], d[D_SLIP + 1], d[D_SLIP + 2] = u1, u2, u3
    if cap < math.inf:
        d[D_SLIP + 3] = cap
    else:
        us = math.sqrt(u1 * u1 + u2 * u2 + u3 * u3)
        d[D_SLIP + 3] = math.inf if us * p[1] < 3.5 * p[P_MU] * abs(probe[PROBE_FORCE]) * h else 0.0


@JIT
def slip_stiff(d, p, probe, h, margin):
    """Whether a sliding ball's slip is stiff for a fixed step of h (docs/design.md §8, "the
    slip's direction where it is stiff"): friction would stop it within the step
    (``slip_reference`` has run: d[D_SLIP + 3] inf), or it changes too fast for any step, by a
    bound independent of h. The slip u changes at u' = B - (7/2)(mu F_n / m) u/|u| (probe: B, its
    acceleration with friction off); the friction's direction u/|u| has derivatives that grow as
    powers of |u'|/|u| wherever it turns at all, so the slip is stiff where |u'| SLIP_TIME
    sqrt(r/g) > |u| (just after a slip begins, |u| growing from 0, and before a grip) or where its
    direction turns within the step faster than 1/sqrt(r/g) (``turning_point``: a line through
    nearly 0 within the step). With tests against the step alone (|u| < a h), the fixed steps began
    and ended their stretches where |u'|/|u| grows as the step shrinks, and the grips' times
    converged at order 2-3. (With no gravity, unit = sqrt(r/g) is inf: only the first test.)
    ``margin`` as ``turn_stiff``'s."""
    if d[D_SLIP + 3] == math.inf:
        return True
    u1, u2, u3 = probe[PROBE_SLIP], probe[PROBE_SLIP + 1], probe[PROBE_SLIP + 2]
    us = math.sqrt(u1 * u1 + u2 * u2 + u3 * u3)
    if us == 0.0:
        return False
    a = slip_deceleration(p, probe)
    if not a < math.inf:
        return False
    w = a / us
    b = PROBE_SLIP_PULL
    r1, r2, r3 = probe[b] - w * u1, probe[b + 1] - w * u2, probe[b + 2] - w * u3
    unit = p[P_UNIT]
    if unit < math.inf and math.sqrt(r1 * r1 + r2 * r2 + r3 * r3) * SLIP_TIME * margin * unit > us:
        return True
    return turning_point(u1, u2, u3, r1, r2, r3, a, margin * unit, margin * h)


# Where the rolling couple outweighs the pull (|G| < C), omega_t comes to 0 in about |omega_t| / (C - G.w),
# its direction's derivatives growing as that time shrinks: a stretch of the pair's steps takes the
# last STOP_TIME sqrt(r/g) (C |omega_t| below it) whatever the step, so that the fixed steps before
# it see derivatives bounded independently of h (docs/design.md §1, "Dissipation"). A sliding ball's
# omega_t, starting from 0 or passing it, is the pair's likewise within STOP_TIME sqrt(r/g) of its zero.
STOP_TIME = 0.25


@JIT
def turn_stiff(d, p, probe, K, h, n, margin):
    """Whether a ball's omega_t at the step's start (w0 = d[D_SIDE:D_SIDE + 3],
    ``couple_reference``'s) is stiff for a fixed step of h (docs/design.md §1, "Dissipation"): its
    rolling resistance would stop it within the step, |w0| < C h with C = c_rr r F_n / (7/5 m r^2);
    or its direction would turn within the step faster than a bound independent of h
    (``turning_point``, with w0' = k v'_t from K[0], k = 5/(7 m r^2)): near a stop it relaxes
    towards the pull's at the rate |pull| / |omega_t|, as a starting slip's does
    (``slip_reference``), and at a turning point it turns about within |omega_t,min| / |w0'|, which
    no fixed step follows at its order; or where the couple outweighs the pull, |w0| < C STOP_TIME
    sqrt(r/g): a stop ahead (``STOP_TIME``); or where omega_t is 0 and the ball starts to turn (its
    direction relaxing from the pull's). A sliding ball's omega_t (its rate omega'_t, C = c_rr r F_n /
    (2/5 m r^2)) is judged by the static start, the turn bound, and its nearness to 0: |w0| below
    its rate times STOP_TIME sqrt(r/g) (its direction's derivatives grow as 1 / the time from its zero).
    ``advance`` takes such steps with an embedded pair
    (``stiff_step``). ``margin``: the bound's time and the reach times it (1 to enter a stretch
    of such steps, EXIT_MARGIN to stay in it: a step the fixed steps go on from is not stiff to them)."""
    if p[P_RESISTANCE] == 0.0:
        return False
    sliding = sliding_size(n)
    t1, t2, t3 = d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2]
    ts = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
    if ts == 0.0:   # static: stiff where the ball starts to turn (a rolling ball's run from rest is pulled
        # on; a sliding ball's friction turns it where mu exceeds c_rr): omega_t's direction relaxes from the pull's
        return not sliding or p[P_MU] > p[P_RESISTANCE]
    cap = p[P_RESISTANCE] * abs(probe[PROBE_FORCE]) / ((0.4 if sliding else 1.4) * p[1] * p[0])   # C
    n1, n2, n3 = probe[0], probe[1], probe[2]
    if sliding:   # (a sliding ball's omega_t reaching 0 turns the couple's side, T_SIDE, placed in the step)
        e1, e2, e3 = K[0, 5], K[0, 6], K[0, 7]
        k = 1.0
    else:
        if ts < cap * h:
            return True
        e1, e2, e3 = K[0, 2], K[0, 3], K[0, 4]
        k = p[3]
    en = e1 * n1 + e2 * n2 + e3 * n3
    r1, r2, r3 = k * (e1 - en * n1), k * (e2 - en * n2), k * (e3 - en * n3)
    unit, reach = margin * p[P_UNIT], margin * h
    if sliding and unit < math.inf and ts * ts < (r1 * r1 + r2 * r2 + r3 * r3) * (STOP_TIME * unit) ** 2:
        return True   # (near a zero of omega_t, within STOP_TIME sqrt(r/g) of it at its rate: h aside)
    if not sliding and unit < math.inf and ts < cap * STOP_TIME * unit:   # a stop ahead, h aside
        c = cap / ts
        g1, g2, g3 = r1 + c * t1, r2 + c * t2, r3 + c * t3   # the pull: omega_t' without the couple
        if g1 * g1 + g2 * g2 + g3 * g3 < cap * cap:
            return True
    if far_from_turning(ts * ts, r1 * r1 + r2 * r2 + r3 * r3, unit, reach):
        return False
    return turning_point(t1, t2, t3, r1, r2, r3, cap, unit, reach)


@JIT
def far_from_turning(tt, rate2, unit, h):
    """Whether omega_t (|t|² = tt), changing at a rate of |r|² = rate2, is surely not at a turning
    point (``turning_point`` false) by products alone, as it is at nearly every step: where
    |r| h <= |t| / 3 the line t + r tau stays at least 2|t|/3 from 0 within the step, and where
    also |r| TURN_TIME unit <= |t| / 4 its direction turns at most at |r| |t| / (4 |t|² / 9), under
    1 / (TURN_TIME unit) with room for any rounding (NaN and overflow answer False: then
    ``turning_point`` judges)."""
    return 9.0 * rate2 * h * h <= tt and 16.0 * rate2 * (TURN_TIME * unit) ** 2 <= tt


SIDE_TURNS = 64   # sides turned in a row at most (in one step; the pairs: since a step ended whole), then static


@JIT
def couple_reference(fn, d, p, z, K, probe, ints, free):
    """The sides of the couples at the step's start (probe: its state's), which the rolling
    resistance and spin friction keep through the step (``rolling_couple``, ``spin_couple``), into
    d[D_SIDE:D_SIDE + 4]: omega's tangential part and the sign of omega.N (``couple_sides``); where
    ``free`` is false the spin's side is zero, and a sliding ball's omega_t's (a rolling ball's omega_t
    reaching 0 is a rest, which ends the run, never a turn in a row: made static while it rolls, the
    couple would push along the motion), and the couple is then static (what holds it at 0, up to its
    limit; a static spin couple whose pull is at its limit or beyond is the kinetic one on the pull's side,
    ``spin_side``). Where that changes a couple's kind of side, K[0] and probe are evaluated anew (the
    step's first stage). Returns whether a rolling ball's omega_t came to 0 (within what
    ``couple_sides`` tells from 0) at the end of the step before without its zero being crossed
    (as where omega_t turns sideways as it stops): that is the rest, at the step's start."""
    n, mk = shape_of(z)
    t1, t2, t3, side = couple_sides(p, probe[PROBE_FORCE], probe[0], probe[1], probe[2], probe[PROBE_OMEGA],
                                    probe[PROBE_OMEGA + 1], probe[PROBE_OMEGA + 2], 0.4 if sliding_size(n) else 1.4)
    if not free:
        side = 0.0
        if sliding_size(n):
            t1, t2, t3 = 0.0, 0.0, 0.0
    side = spin_side(p, n, probe, side)   # (a static spin couple at its limit is kinetic)
    was = d[D_SIDE] != 0.0 or d[D_SIDE + 1] != 0.0 or d[D_SIDE + 2] != 0.0
    now = t1 != 0.0 or t2 != 0.0 or t3 != 0.0
    if was and not now and not sliding_size(n):
        return True
    changed = was != now or side != d[D_SIDE + 3]
    d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2], d[D_SIDE + 3] = t1, t2, t3, side
    if changed:
        evaluate(fn, d, p, z, mk, K, np.int64(0), probe)
        ints[I_EVALS] += 1
    return False


@JIT
def stopped_rolling(rows, ints, info, t, z, R, probe, p):
    """A rolling ball's omega_t came to 0 without crossing it (``couple_reference``): stop the run
    there as a rest (status TRANSITION, T_REST), its state the last row."""
    record_last(rows, ints, t, z, R, probe, p)
    ints[I_STATUS], ints[I_TRANSITION] = TRANSITION, T_REST
    info[F_EVENT_T], info[F_EVENT_X], info[F_EVENT_Y] = t, z[0], z[1]


@COLD
def resume(fn, d, p, h, P, theta, z, R, K, probe, ints, zn, Rn, pn):
    """A couple's side turned at theta inside the step from z of h (a kernel-internal stop,
    T_SIDE, ``events.locate_transition``): make the state there (zn, Rn, pn where the stop holds it
    already, else the step's dense output) the run's, and go on from it."""
    if ints[I_HELD] == 0:
        state_at(fn, d, p, z, R, h, P, K, 0.0, theta, zn, Rn, pn)
    hold(p, z, R, probe, zn, Rn, pn)
    n, mk = shape_of(z)
    evaluate(fn, d, p, z, mk, K, np.int64(0), probe)
    ints[I_EVALS] += 1
    ints[I_HELD], ints[I_STATUS], ints[I_TRANSITION], ints[I_DENSE] = 0, RUNNING, 0, -1


@JIT
def slow_slip(p, rtol):
    """The slip speed below which an adaptive pair takes a slip's direction as the slow
    motion's: rtol^SLOW_POWER sqrt(g r) where it is taken to first order in |u|
    (``physics.slow_corrected``; ``physics.slow_lag`` says how far below), else sqrt(rtol) sqrt(g r)
    (``first_slip``)."""
    if slow_corrected(p):
        return rtol ** SLOW_POWER * math.sqrt(p[2] * p[0])
    return first_slip(p, rtol)


@JIT
def first_slip(p, rtol):
    """sqrt(rtol) sqrt(g r): where the slip's direction taken as B's (its error of order |u| times
    its turning rate over |B|) costs of order rtol in the speeds."""
    return math.sqrt(rtol * p[2] * p[0])


# ``grip_slip``'s share: the slip a grip an embedded pair's step located may leave, in units of rtol sqrt(g r)
GRIP_SLIP = 100.0


@JIT
def grip_slip(p, rtol):
    """The most slip a grip located on an embedded pair's step may leave (``grip_left``): GRIP_SLIP
    rtol sqrt(g r), at most ``first_slip`` (the two meet at rtol 1e-4). Where a slip falls to 0, its
    direction turns towards B's ever faster as |u| falls (with |B| below the friction's rate its
    derivatives grow as powers of 1/|u|), and a step that holds the zero passes it sideways by about
    what the grip leaves; the grip's time is then off by a share of that over the slip's rate. (Left
    up to ``slow_slip``, dop853 at rtol 1e-10 gripped a bowl thrown sideways with 1.6e-6 m/s left,
    4.4e-8 s late, where its tolerance allows about 1e-11 s.)"""
    return min(first_slip(p, rtol), GRIP_SLIP * rtol * math.sqrt(p[2] * p[0]))


@JIT
def slip_left(pe):
    """|u|² at a state with probe pe: what a grip located there leaves of the slip."""
    return pe[PROBE_SLIP] ** 2 + pe[PROBE_SLIP + 1] ** 2 + pe[PROBE_SLIP + 2] ** 2


@JIT
def grip_left(pe, most, before):
    """Whether a grip located on an embedded pair's step (pe: the grip's state) left a slip the step
    did not resolve, to be taken again with a step half as long: more than ``most`` (``grip_slip``),
    and at most half what the last grip taken again in this call of the loop left (``before``, squared;
    inf for none). The grip is where the slip's component along
    its start's reaches 0; a step that crossed the slip's zero with the friction's direction turning
    within it unresolved ends with u sideways to u0 and large (dop853 at rtol 1e-4 took the tilted
    bowl's last 50 ms of sliding in one step and "gripped" at its end with 0.039 m/s left of 0.105,
    1e-2 s late), and a shorter step leaves less. A slip that does not shrink as the step does is the
    run's own error, not the step's: the grip stays."""
    ub = slip_left(pe)
    return ub > most * most and ub <= 0.25 * before


# A step that fell below round-off where the ball all but does not fit (r·κ within this of 1 at the
# step's start: the equations are singular at r·κ = 1) met that edge, and the run stops as past it
FIT_NEAR = 1e-4


@JIT
def underflow(fn, d, p, ints, info, t, z, K, hs, h, probe):
    """Stop a run whose step fell below round-off at t (``hs`` the step tried, ``h`` the one it came
    to; probe: the state at t): at a tip or kink there (``tip_stop``); where r·κ there is within
    FIT_NEAR of 1, as the ball's not fitting (R_NO_FIT, as a step's end past that edge says: the
    pairs shrank their steps to nothing against it, where a fixed step or a longer one lands past it);
    else R_STEP_UNDERFLOW."""
    if tip_stop(fn, d, ints, info, t, z[0], z[1], reach_of(K, hs, z), speed_of(K), p[P_FLY]):
        return
    if probe[PROBE_FIT] >= 1.0 - FIT_NEAR:
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t, z[0], z[1], probe[PROBE_FIT])
    else:
        _fail(ints, info, NONFINITE, R_STEP_UNDERFLOW, t, z[0], z[1], h)


@JIT
def crossed_unseen(p, z, probe, zn, pn):
    """Whether an embedded pair's step from (z, probe) to (zn, pn), which its events let stand,
    crossed a feature of the surface it did not see: its height changed off what the slopes at its
    ends explain (``events.looks``' jumpy: no jump in height was found in it, so the change is
    smooth, and steep somewhere between the ends) while its contact point travelled more than the
    ball's radius. Its stages and error estimate sample the surface only at their own points: on
    the flat approach to a smooth drop dopri5's steps grew to 0.3 s, 1.2 m of travel, and one passed
    a drop 3 m deep without a stage on it, the ball carried on along the lower level without
    flying. Taken again a quarter as long; a step that travels less than r is the events' to judge."""
    dx, dy = zn[0] - z[0], zn[1] - z[1]
    if not dx * dx + dy * dy > p[0] * p[0]:
        return False
    return looks(p[0], z, probe, zn, pn)[2]


@JIT
def pair_try(fn, d, p, W, E, P, err_kind, err_exp, rtol, atol, t, hs, cap, free, z, R, K, last, probe, rows, ints, info,
             Y, zn, Rn, pn, watch):
    """One try of an embedded pair's step of hs from t (``advance_adaptive``, ``stiff_step``): the
    couples' sides (``free``: ``couple_reference``'s) and the slip's reference (``cap``:
    ``slip_reference``'s) at its start, the step, its error in units of the tolerance and, accepted
    (<= 1), R carried through it. Returns (err, h): accepted, h = hs; rejected, h the step to try
    next; -1 where the run stopped (status set, its last row recorded: a rest at t, a step
    that cannot be made small enough or finite)."""
    n = z.shape[0]
    if resisted_size(n) and couple_reference(fn, d, p, z, K, probe, ints, free):
        stopped_rolling(rows, ints, info, t, z, R, probe, p)
        return math.inf, -1.0
    if watch:
        slip_reference(d, probe, p, hs, cap)
    bad = pair_step(fn, d, p, W, P, hs, z, R, K, last, Y, zn, Rn, pn, ints)
    err = math.inf if bad else error_norm(E, err_kind, K, last, motion_size(n), z, zn, hs, rtol, atol, p)
    if err <= 1.0:  # accepted: R carried through the step (its dense-output stages only now)
        bad = carry_orientation(fn, d, p, W, P, hs, z, R, K, last, Y, Rn, pn, ints)
        err = math.inf if bad else err
    if err <= 1.0:
        return err, hs
    ints[I_REJECTED] += 1
    h = hs * max(MIN_FACTOR, SAFETY * err ** err_exp) if err < math.inf else MIN_FACTOR * hs
    ints[I_NONFINITE] += 1 if bad else 0
    if ints[I_NONFINITE] >= NONFINITE_TRIES:
        _fail(ints, info, NONFINITE, R_ORIENTATION if bad == 2 else R_UNDEFINED, t, z[0], z[1], 0.0)
    elif h <= MIN_STEP * max(1.0, abs(t)):
        underflow(fn, d, p, ints, info, t, z, K, hs, h, probe)
    else:
        return err, h
    record_last(rows, ints, t, z, R, probe, p)
    return err, -1.0


@JIT
def row_due(ints, k, every, phase):
    """Whether the end of this run's grid step k is a recorded row (``advance``'s rows: every
    ``every``-th time of the whole run's grid, the first after the start at step every - phase)."""
    done = ints[I_LAST_RECORDED]
    return k - done == (every if done > 0 else every - phase)


@JIT
def record_due(rows, ints, k, t, z, R, probe, p):
    """The row at the end of this run's grid step k (time t): recorded, counted, and marked as the
    last recorded step (which ``row_due`` counts from)."""
    record(rows, ints[I_ROWS], t, z, R, probe, p)
    ints[I_ROWS] += 1
    ints[I_LAST_RECORDED] = k


@JIT
def rows_inside(fn, d, p, P, t, hs, theta, z, R, K, rows, ints, Ye, Re, pe, dt, before, kk, k_end, every, phase):
    """The rows due (``row_due``) at the ends of this run's grid steps kk, kk + 1, ... before k_end
    that a stiff pair's step from t of hs passed strictly before t + theta hs, from its dense output
    (one evaluation each; Ye, Re, pe: scratch). Returns the first of those steps it did not pass."""
    stop = t + theta * hs
    while kk < k_end:
        tk = (before + kk) * dt
        if not tk < stop:
            break
        if row_due(ints, kk, every, phase):
            state_at(fn, d, p, z, R, hs, P, K, 0.0, (tk - t) / hs, Ye, Re, pe)
            ints[I_EVALS] += 1
            record_due(rows, ints, kk, tk, Ye, Re, pe, p)
        kk += 1
    return kk


@JIT
def row_at_end(rows, ints, t, z, R, probe, p, dt, before, kk, k_end, every, phase):
    """A stiff pair's step whose state z (at t) ended exactly at the end of this run's grid step
    kk (before k_end): its row where due, and the step counted. Returns the first step ahead."""
    if kk < k_end and (before + kk) * dt == t:
        if row_due(ints, kk, every, phase):
            record_due(rows, ints, kk, t, z, R, probe, p)
        ints[I_STEPS] = kk
        return kk + 1
    return kk


@JIT
def stiff_step(fn, S, SE, SP, s_kind, s_exp, tol, p, t0, h, hp, z, R, K, probe, rows, ints, info, work, watch, dt,
               before, kk, k_end, every, phase):
    """The fixed steps kk .. k_end of this run (``advance``), from t0 to t0 + h, where the slip's
    direction, or a rolling ball's omega_t's, is stiff (``slip_reference``, ``turn_stiff``: no fixed
    step follows it at its order), taken by the embedded pair S, SE, SP (as ``advance_adaptive``'s
    W, E, P; s_kind, s_exp its err_kind, err_exp) at the tolerance ``tol``, in as many of its steps
    as its error control takes, the first tried at ``hp``; the rows due at the grid times inside
    (dt, before, every, phase: ``advance``'s) from its dense output (``rows_inside``); each step
    with its events: a transition inside stops the run there as a fixed step's does, a rest where
    omega_t reaches 0 included. Returns the pair's next step, or -1 where the run stopped (status
    set, its last row recorded). A Munthe-Kaas state only, in the pair's layout (``pair_layout``)
    at both ends."""
    n = z.shape[0]
    last = SE.shape[1] - 1
    d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm = scratch(work, n)
    cap = slow_slip(p, tol)
    t, t_end, turns, retry, out = t0, t0 + h, 0, False, -1.0
    while True:
        land = t + 1.1 * hp >= t_end
        hs = t_end - t if land else hp
        err, tried = pair_try(fn, d, p, S, SE, SP, s_kind, s_exp, tol, tol, t, hs, cap, turns < SIDE_TURNS, z, R, K,
                              last, probe, rows, ints, info, Y, zn, Rn, pn, watch)
        if tried < 0.0:
            break
        if not err <= 1.0:
            retry, hp = True, tried
            continue
        valid = step_events(fn, d, p, S, True, n, t, hs, z, R, K, last, SP, probe, Y, zn, Rn, pn, ints, info,
                            False, Ye, Re, pe, sa, sb, sm, EXPLICIT, watch)
        # (rows before a side's turn placed by the method's own step to it: that step's dense output)
        hd = valid * hs if valid >= 0.0 and ints[I_TRANSITION] == T_SIDE and ints[I_HELD] == 1 else hs
        kk = rows_inside(fn, d, p, SP, t, hd, 1.0 if hd != hs else valid if valid >= 0.0 else 1.0, z, R, K, rows,
                         ints, Ye, Re, pe, dt, before, kk, k_end, every, phase)
        if valid >= 0.0 and ints[I_TRANSITION] == T_SIDE:   # on from the state there
            resume(fn, d, p, hs, SP, valid, z, R, K, probe, ints, zn, Rn, pn)
            turns += 1
            t += valid * hs
            kk = row_at_end(rows, ints, t, z, R, probe, p, dt, before, kk, k_end, every, phase)
            continue
        if valid >= 0.0:
            record_valid(fn, d, p, S, t, hs, valid, z, R, K, last, SP, probe, rows, ints, info, Y, zn,
                         Rn, pn, Ye, sa, sb, sm, EXPLICIT)
            break
        t = t_end if land else t + hs
        accept(p, True, n, z, R, K, last, probe, zn, Rn, pn)
        kk = row_at_end(rows, ints, t, z, R, probe, p, dt, before, kk, k_end, every, phase)
        turns = 0
        grown = hs * min(1.0 if retry else MAX_FACTOR, next_step_factor(err, s_kind, s_exp, info))
        hp = max(hp, grown) if land else grown
        retry = False
        if t == t_end:
            out = hp
            break
        if hp <= MIN_STEP * max(1.0, abs(t)):
            underflow(fn, d, p, ints, info, t, z, K, hs, hp, probe)
            record_last(rows, ints, t, z, R, probe, p)
            break
    return out


@JIT
def pair_layout(fn, d, p, z, K, probe, ints, tol):
    """A Munthe-Kaas state at a step's start made the stiff pair's (``stiff_step``): the pair
    carries omega (p[P_TURN] > 0: rolling, in u's place; sliding, omega is the motion's and u
    stays 0), and K[0] is evaluated anew."""
    n, mk = shape_of(z)
    p[P_TURN] = TURN_SHARE * tol
    if motion_size(n) == MOTION_SIZE:
        for q in range(3):
            z[5 + q] = probe[PROBE_OMEGA + q]
    evaluate(fn, d, p, z, mk, K, np.int64(0), probe)
    ints[I_EVALS] += 1


@JIT
def fixed_layout(p, z, K, probe):
    """The stiff pair's state (``pair_layout``) made the fixed steps' again: u zero, K[0]'s
    u-part omega (as ``accept`` leaves it), p[P_TURN] 0."""
    m = motion_size(z.shape[0])
    p[P_TURN] = 0.0
    for q in range(3):
        z[m + q] = 0.0
        K[0, m + q] = probe[PROBE_OMEGA + q]


@COLD  # called by its entry point (simulate) and by the sweeps' batch loop: compiled once
def advance(fn, W, P, p, dt, t_start, t_end, n_steps, every, max_steps, z, R, K, probe, rows, ints, info, work,
            stepping, S, SE, SP, s_kind, s_exp, s_tol):
    """Run up to ``max_steps`` further fixed steps; all run state lives in the arrays passed in.

    W, P: the method (``Tableau.kernel_arrays``); K has ``stage_rows`` of the larger of W's and S's
    rows (``Simulation``; S's only where p[P_STIFF] is set).
    ``stepping``: IMPLICIT for collocation_step's steps (the
    Gauss methods, Munthe-Kaas only), EXPLICIT for trial_step's. One compiled loop serves every
    fixed-step method and both orientation schemes (read from the state's length). On the first
    call (no rows yet) the initial state is checked and recorded. The run stops early, with
    ints[I_STATUS] set, where the state turns non-finite or a check fails; the last valid state
    is then the last row.

    Where the slip's direction, or a rolling ball's omega_t's, is stiff for the steps, a stretch
    of steps is the embedded pair's S, SE, SP at s_tol (``stiff_step``; a classic run stops there
    instead, T_STIFF, for the caller to take that stretch), in the pair's own steps: where its next
    step reaches past the grid step's end, as many of the grid's steps at once as it reaches (the
    stiffness judged again at the end of the last, the rows between from the pair's dense output).

    The run's clock is the whole run's (``interface.grid_steps_before``): it starts at t_start
    (0, or where the contact changed mode) and its steps end at the multiples k·dt of the grid, the
    first one at the first grid time after t_start, the last at t_end; n_steps counts the grid's
    steps to t_end, those before t_start too. Rows: the start (at t_start), the steps whose k is
    a multiple of ``every``, and the last. ints[I_STEPS] counts this run's steps.
    """
    n, mk = shape_of(z)
    last = W.shape[0] - 1
    d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm = scratch(work, n)

    if ints[I_ROWS] == 0:
        for a in range(3):   # (a state without orientation never writes these: they are checked as R)
            for c in range(3):
                Rn[a, c] = Re[a, c] = R[a, c]
        start(fn, d, p, z, R, K, probe, rows, ints, info, t_start)
        if ints[I_STATUS] != RUNNING:
            return

    watch = contact_watched(p, n)
    resists = resisted_size(n)
    before = grid_before(t_start, dt)   # the grid's steps before this run (0 from t = 0)
    own = max(1, n_steps - before)      # this run's steps
    phase = before % every              # the first row after the start: at the step every - phase
    k = ints[I_STEPS]
    k_stop = min(own, k + max_steps)
    stretch, hp = False, dt   # in a stretch of stiff steps (its state in the pair's layout); the pair's next step
    while k < k_stop:
        k += 1
        final = k == own
        g = before + k
        t0 = (g - 1) * dt if k > 1 else t_start
        h = t_end - t0 if final else dt if k > 1 else g * dt - t0
        t = t_end if final else g * dt
        turns = 0
        while True:   # (again from where a couple's side turned inside the step, ``resume``)
            if resists and couple_reference(fn, d, p, z, K, probe, ints, turns < SIDE_TURNS):
                if stretch:
                    fixed_layout(p, z, K, probe)
                stopped_rolling(rows, ints, info, t0, z, R, probe, p)
                return
            stiff = False
            if watch:
                slip_reference(d, probe, p, h, math.inf)
                margin = EXIT_MARGIN if stretch else 1.0
                stiff = p[P_STIFF] != 0.0 and (sliding_size(n) and slip_stiff(d, p, probe, h, margin)
                                               or resists and turn_stiff(d, p, probe, K, h, n, margin))
            if stiff and not mk:   # (the caller's: T_STIFF)
                ints[I_STATUS], ints[I_TRANSITION] = TRANSITION, T_STIFF
                info[F_EVENT_T], info[F_EVENT_X], info[F_EVENT_Y] = t0, z[0], z[1]
                return
            if stiff and not stretch:
                pair_layout(fn, d, p, z, K, probe, ints, s_tol)
            elif stretch and not stiff:
                fixed_layout(p, z, K, probe)
            stretch = stiff
            if stiff:
                # the pair's next step reaching past this step's end: the stretch on to the last end
                # of a grid step it reaches (at most k_stop's), the rows between from its dense output
                k_end = k
                if hp > h and not final:
                    k_end += int(min(float(k_stop - k), (t0 + hp - t) / dt))
                t_span = t_end if k_end == own else (before + k_end) * dt
                hp = stiff_step(fn, S, SE, SP, s_kind, s_exp, s_tol, p, t0, t_span - t0, min(hp, t_span - t0), z, R,
                                K, probe, rows, ints, info, work, watch, dt, before, k, k_end, every, phase)
                if hp < 0.0:
                    fixed_layout(p, z, K, probe)
                    return
                k, t, final = k_end, t_span, k_end == own
                valid = -1.0
                break
            bad = take_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
            if bad and info[F_FOLD] < t0 + 2.0 * h:  # a step failing at the edge of the no-fit region
                valid = fold_search(fn, d, p, W, P, t0, h, z, R, K, last, probe, Y, zn, Rn, pn, ints, info, Ye, Re,
                                    pe, stepping)
                if valid >= 0.0:
                    record_valid(fn, d, p, W, t0, h, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                                 Rn, pn, Ye, sa, sb, sm, stepping)
                    return
            if bad:
                if bad == STEP_NOT_CONVERGED:
                    # (unless the step would pass a tip of the surface: that is the landscape's)
                    if not tip_stop(fn, d, ints, info, t0, z[0], z[1], reach_of(K, h, z), speed_of(K), p[P_FLY]):
                        _fail(ints, info, NONFINITE, R_NOT_CONVERGED, t, z[0], z[1], h)
                    elif ints[I_STATUS] == TRANSITION:   # the ball flies off the tip: from the state there
                        valid = tip_liftoff(fn, d, p, W, t0, h, 0.5, z, R, K, last, P, probe, ints, Y, zn, Rn, pn,
                                            info, info[F_EVENT_X], info[F_EVENT_Y], stepping)
                        record_valid(fn, d, p, W, t0, h, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                                     Rn, pn, Ye, sa, sb, sm, stepping)
                        return
                else:
                    _fail(ints, info, NONFINITE, R_ORIENTATION if bad == 2 else R_UNDEFINED, t, z[0], z[1],
                          0.0 if mk else 1.0)
                record_last(rows, ints, t0, z, R, probe, p)
                return
            valid = step_events(fn, d, p, W, mk, n, t0, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info,
                                True, Ye, Re, pe, sa, sb, sm, stepping, watch)
            if not (valid >= 0.0 and ints[I_TRANSITION] == T_SIDE):
                break
            resume(fn, d, p, h, P, valid, z, R, K, probe, ints, zn, Rn, pn)
            turns += 1
            t0 += valid * h
            h = t - t0
        if valid >= 0.0:
            record_valid(fn, d, p, W, t0, h, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                         Rn, pn, Ye, sa, sb, sm, stepping)
            return
        if not stretch:   # (a stiff step's state is the run's already)
            accept(p, mk, n, z, R, K, last, probe, zn, Rn, pn)
        ints[I_STEPS] = k
        if row_due(ints, k, every, phase) or final:   # (no division in the loop)
            record_due(rows, ints, k, t, z, R, probe, p)
    if stretch:
        fixed_layout(p, z, K, probe)
    if ints[I_STEPS] == own:
        ints[I_STATUS] = OK


@JIT
def advance_adaptive(fn, W, E, P, p, err_kind, err_exp, t_start, t_end, record_dt, rtol, atol, max_steps, z, R,
                     K, probe, rows, ints, info, work):
    """Run up to ``max_steps`` further trial steps of an embedded pair with step-size control
    (carrying omega, p[P_TURN] > 0); info[F_TIME] is the time reached and info[F_H] the next
    step to try. The error is controlled on the motion (rolling or sliding, by z's length);
    R follows omega (``turn``).

    The loop is generic over the pair; its plug-in points are data (``Tableau.kernel_arrays``):
    - W, square: rows 1 .. last-1 the stage coefficients, row ``last`` the weights b (the
      evaluation at the new state is K[last]; first same as last or not);
    - E, (estimates x (last + 1)): the error weights; ``last`` is E.shape[1] - 1;
    - err_kind: how ``error_norm`` combines E's rows (0: one estimate; 1: DOP853's estimates
      of orders 5 and 3); err_exp = -1/(q + 1) for an estimate of order q;
    - P, (rows of W x degree): the continuous extension, as scipy's ``P``;
    - extra dense-output stages (DOP853's three): rows of W and P after ``last``, evaluated by
      ``dense_stages`` only for steps that are interpolated (a row or an event inside them).
    K has ``stage_rows(W.shape[0])`` rows.

    The run's clock is the whole run's: time starts at t_start (0, or where the contact changed
    mode). Steps are cut only to land on t_end. Rows at the multiples of record_dt after t_start
    (``interface.grid_steps_before``) are the dense output at those times (record_dt 0: every
    accepted step is a row). Events are located on
    the dense output (``step_events``). Returns early, still running, when ``rows`` has fewer
    than two free rows while recording every step: the caller grows it and calls again.
    """
    n = z.shape[0]   # MK_SIZE, or SLIDING_MK_SIZE
    last = E.shape[1] - 1
    d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm = scratch(work, n)
    if ints[I_ROWS] == 0:
        start(fn, d, p, z, R, K, probe, rows, ints, info, t_start)
        info[F_TIME] = t_start
        if ints[I_STATUS] != RUNNING:
            return
    watch = contact_watched(p, n)
    turns = 0   # (the couples' sides turned since the last step that ended whole: SIDE_TURNS at most, ``resume``)
    cap, most = slow_slip(p, rtol), grip_slip(p, rtol)
    before = math.inf   # the slip the last grip taken again in this call left, squared (``grip_left``)
    skipped = grid_before(t_start, record_dt) if record_dt > 0.0 else 0   # row i >= 1 at (i + skipped) record_dt
    t, h = info[F_TIME], info[F_H]
    retry = ints[I_RETRY] == 1  # right after a rejection the step may shrink but not grow (Hairer's rule)
    for _ in range(max_steps):
        if record_dt == 0.0 and ints[I_ROWS] >= rows.shape[0] - 2:
            break
        land = t + 1.1 * h >= t_end  # stretch a little rather than leave a sliver
        hs = t_end - t if land else h
        err, tried = pair_try(fn, d, p, W, E, P, err_kind, err_exp, rtol, atol, t, hs, cap, turns < SIDE_TURNS, z, R,
                              K, last, probe, rows, ints, info, Y, zn, Rn, pn, watch)
        if tried < 0.0:
            break
        if not err <= 1.0:  # rejected (or not finite): try again with a smaller step
            retry, h = True, tried
            continue
        t_new = t_end if land else t + hs
        valid = step_events(fn, d, p, W, True, n, t, hs, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info,
                            False, Ye, Re, pe, sa, sb, sm, EXPLICIT, watch)
        if valid < 0.0 and crossed_unseen(p, z, probe, zn, pn):   # taken again, shorter
            ints[I_REJECTED] += 1
            ints[I_DENSE], info[F_FOLD] = -1, math.nan   # (the step's dense stages and edge estimate: none)
            retry, h = True, 0.25 * hs
            continue
        if valid >= 0.0 and ints[I_TRANSITION] == T_GRIP and grip_left(pe, most, before):   # taken again, shorter
            before = slip_left(pe)
            ints[I_STATUS], ints[I_TRANSITION], ints[I_HELD], ints[I_DENSE] = RUNNING, 0, 0, -1
            ints[I_REJECTED] += 1
            retry, h = True, 0.5 * hs
            continue
        t_stop = t + valid * hs if valid >= 0.0 else t_new
        # the rows before a side's turn placed by the method's own step to it: that step's dense output
        # (``locate_transition``; the whole step's crosses the turn, a kink of a couple's law)
        hd = valid * hs if valid >= 0.0 and ints[I_TRANSITION] == T_SIDE and ints[I_HELD] == 1 else hs
        theta = 0.0  # Re: the orientation there (the rows' orientations follow on from each other)
        for a in range(3):
            for c in range(3):
                Re[a, c] = R[a, c]
        while record_dt > 0.0:  # the rows inside the step, from its dense output
            t_row = (ints[I_ROWS] + skipped) * record_dt
            if t_end - t_row < 1e-9 * record_dt:
                t_row = t_end
            if t_row > t_new or (valid >= 0.0 and t_row >= t_stop) or t_row <= rows[ints[I_ROWS] - 1, 0]:
                break
            if t_row == t_new:
                record(rows, ints[I_ROWS], t_new, zn, Rn, pn, p)
                ints[I_LAST_RECORDED] = ints[I_STEPS] + 1
            else:
                dense_stages(fn, d, p, W, hd, z, K, last, Ye, pe, ints)
                state_at(fn, d, p, z, Re, hd, P, K, theta, (t_row - t) / hd, Ye, Re, pe)
                theta = (t_row - t) / hd
                record(rows, ints[I_ROWS], t_row, Ye, Re, pe, p)
            ints[I_ROWS] += 1
        if valid >= 0.0 and ints[I_TRANSITION] == T_SIDE:   # on from the state there (its rows are recorded)
            resume(fn, d, p, hs, P, valid, z, R, K, probe, ints, zn, Rn, pn)
            turns += 1
            t = t_stop
            continue
        if valid >= 0.0:
            record_valid(fn, d, p, W, t, hs, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                         Rn, pn, Ye, sa, sb, sm, EXPLICIT)
            break
        if record_dt == 0.0:
            record(rows, ints[I_ROWS], t_new, zn, Rn, pn, p)
            ints[I_ROWS] += 1
            ints[I_LAST_RECORDED] = ints[I_STEPS] + 1
        t = t_new
        accept(p, True, n, z, R, K, last, probe, zn, Rn, pn)
        ints[I_STEPS] += 1
        turns = 0   # (a count per call made the couples static for the rest of it: energy gained, docs/design.md §1)
        grown = hs * min(1.0 if retry else MAX_FACTOR, next_step_factor(err, err_kind, err_exp, info))
        h = max(h, grown) if land else grown
        retry = False
        if h <= MIN_STEP * max(1.0, abs(t)):  # creeping up to a singularity (Zeno)
            underflow(fn, d, p, ints, info, t, z, K, hs, h, probe)
            record_last(rows, ints, t, z, R, probe, p)
            break
        if t == t_end:
            ints[I_STATUS] = OK
            break
    info[F_TIME], info[F_H] = t, h
    ints[I_RETRY] = 1 if retry else 0
