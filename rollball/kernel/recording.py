"""A run's rows and how it stops: one recorded row (``record``, the columns of
``interface.ROW_FIELDS``), the start check, and a failure's code and facts (``_fail``)."""

from __future__ import annotations

import math

import numpy as np

from .interface import (
    DOES_NOT_FIT, D_SLIP, F_EVENT_T, F_EVENT_X, F_EVENT_Y, F_FAIL_T, F_FAIL_VALUE, F_FAIL_X, F_FAIL_Y, F_LIFTOFF,
    F_LIFT_KINK, F_LIFT_X, F_LIFT_Y, I_DENSE, I_EVALS, I_LAST_RECORDED, I_REASON, I_ROWS, I_STATUS, I_STEPS,
    I_TRANSITION, NONFINITE, PROBE_FIT, PROBE_FORCE, PROBE_HEIGHT, PROBE_NEED, PROBE_OMEGA, PROBE_SIZE, PROBE_SLIP,
    D_SIDE, P_CAUSES, P_DISSIPATED, P_FLY, P_MU, P_TURN, ROW_AIR, ROW_CENTER, ROW_CONTACT, ROW_DISSIPATED,
    ROW_ENERGY, ROW_FORCE, ROW_OMEGA, ROW_R, ROW_ROLLING, ROW_SIZE, ROW_SLIP, ROW_SPIN, ROW_T, ROW_VELOCITY, R_NO_FIT,
    R_START_OVERFLOW, R_START_UNDEFINED, S_DISSIPATED, S_VELOCITY, TRANSITION, T_GRIP, T_LIFTOFF, T_SLIP)
from .lowlevel import COLD, JIT, data_pointer, landscape
from .physics import (FULL, _finite, _finite_row, copy_state, couple_sides, motion_size, rates, resisted_size, shape_of,
                      sliding_size, spin_side)


@JIT
def record(rows, i, t, z, R, probe, p):
    """Write one trajectory row (the CSV columns of docs/design.md §5)."""
    r, m, g0 = p[0], p[1], p[2]
    n1, n2, n3 = probe[0], probe[1], probe[2]
    o1, o2, o3 = probe[3], probe[4], probe[5]
    rows[i, ROW_T] = t
    rows[i, ROW_CONTACT] = z[0]
    rows[i, ROW_CONTACT + 1] = z[1]
    rows[i, ROW_CENTER] = z[0] + r * n1
    rows[i, ROW_CENTER + 1] = z[1] + r * n2
    cz = probe[PROBE_HEIGHT] + r * n3
    rows[i, ROW_CENTER + 2] = cz
    rows[i, ROW_OMEGA], rows[i, ROW_OMEGA + 1], rows[i, ROW_OMEGA + 2] = o1, o2, o3
    for a in range(3):
        for b in range(3):
            rows[i, ROW_R + 3 * a + b] = R[a, b]
    if sliding_size(z.shape[0]):
        c1, c2, c3 = z[S_VELOCITY], z[S_VELOCITY + 1], z[S_VELOCITY + 2]
        rows[i, ROW_VELOCITY], rows[i, ROW_VELOCITY + 1], rows[i, ROW_VELOCITY + 2] = c1, c2, c3
        rows[i, ROW_ENERGY] = (0.5 * m * (c1 * c1 + c2 * c2 + c3 * c3) + 0.2 * m * r * r * (o1 * o1 + o2 * o2 + o3 * o3)
                               + m * g0 * cz)
        u1, u2, u3 = probe[PROBE_SLIP], probe[PROBE_SLIP + 1], probe[PROBE_SLIP + 2]
        rows[i, ROW_SLIP] = math.sqrt(u1 * u1 + u2 * u2 + u3 * u3)
        rows[i, ROW_DISSIPATED] = z[S_DISSIPATED]
    else:
        rows[i, ROW_VELOCITY] = r * (o2 * n3 - o3 * n2)
        rows[i, ROW_VELOCITY + 1] = r * (o3 * n1 - o1 * n3)
        rows[i, ROW_VELOCITY + 2] = r * (o1 * n2 - o2 * n1)
        rows[i, ROW_ENERGY] = 0.5 * (o1 * z[2] + o2 * z[3] + o3 * z[4]) + m * g0 * cz
        rows[i, ROW_SLIP] = 0.0
        rows[i, ROW_DISSIPATED] = p[P_DISSIPATED]
    rows[i, ROW_FORCE] = probe[PROBE_FORCE]
    # the energy rolling resistance, spin friction and air took: before this run (p) and in it (the
    # state's quadratures, part of the total too)
    n = z.shape[0]
    if resisted_size(n):
        q1, q2, q3 = z[n - 3], z[n - 2], z[n - 1]
        rows[i, ROW_DISSIPATED] += q1 + q2 + q3
        rows[i, ROW_ROLLING] = p[P_CAUSES] + q1
        rows[i, ROW_SPIN] = p[P_CAUSES + 1] + q2
        rows[i, ROW_AIR] = p[P_CAUSES + 2] + q3
    else:
        rows[i, ROW_ROLLING], rows[i, ROW_SPIN], rows[i, ROW_AIR] = p[P_CAUSES], p[P_CAUSES + 1], p[P_CAUSES + 2]


@JIT
def hold(p, z, R, probe, zn, Rn, pn):
    """Make zn, Rn, pn (a state inside a step) the run's state z, R, probe, as a step's start:
    the Munthe-Kaas increment u zero (R holds the orientation), a rolling pair's omega exact."""
    n, mk = shape_of(z)
    m = motion_size(n)
    copy_state(n, zn, Rn, pn, z, R, probe)
    if mk and p[P_TURN] > 0.0 and m == 5:
        for q in range(3):
            z[5 + q] = pn[PROBE_OMEGA + q]
    elif mk and n > m:
        for q in range(3):
            z[m + q] = 0.0


@COLD
def record_last(rows, ints, t, z, R, probe, p):
    """A run stopped by the physics: its last valid state (the current one) is the last row."""
    if ints[I_LAST_RECORDED] != ints[I_STEPS]:
        record(rows, ints[I_ROWS], t, z, R, probe, p)
        ints[I_ROWS] += 1
        ints[I_LAST_RECORDED] = ints[I_STEPS]


@JIT
def _fail(ints, info, status, reason, t, x, y, value):
    ints[I_STATUS] = status
    ints[I_REASON] = reason
    info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y], info[F_FAIL_VALUE] = t, x, y, value


@COLD
def start(fn, d, p, z, R, K, probe, rows, ints, info, t_start):
    """Check and record the initial state, at time t_start; K[0] and probe describe it afterwards.
    A start that changes contact mode at once stops the run there (status TRANSITION, ``start_mode``)."""
    n, mk = shape_of(z)
    landscape(fn, z[0], z[1], data_pointer(d))
    if not _finite(d, 0, 6):
        _fail(ints, info, NONFINITE, R_START_UNDEFINED, t_start, z[0], z[1], math.nan)
        return
    sliding = sliding_size(n)
    d[D_SLIP], d[D_SLIP + 1], d[D_SLIP + 2], d[D_SLIP + 3] = 0.0, 0.0, 0.0, 0.0   # (no step yet)
    d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2], d[D_SIDE + 3] = 0.0, 0.0, 0.0, 0.0
    # (np.int64(0): a literal 0 would compile dynamics anew for it)
    rates(fn, d, p, z, 1.0 if mk else 0.0, K, np.int64(0), probe, FULL)
    ints[I_EVALS] += 1
    if resisted_size(n):   # the couples' sides at the start (``couple_sides``), as its first step takes them
        t1, t2, t3, side = couple_sides(p, probe[PROBE_FORCE], probe[0], probe[1], probe[2], probe[PROBE_OMEGA],
                                        probe[PROBE_OMEGA + 1], probe[PROBE_OMEGA + 2], 0.4 if sliding else 1.4)
        side = spin_side(p, n, probe, side)
        if t1 != 0.0 or t2 != 0.0 or t3 != 0.0 or side != 0.0:
            d[D_SIDE], d[D_SIDE + 1], d[D_SIDE + 2], d[D_SIDE + 3] = t1, t2, t3, side
            rates(fn, d, p, z, 1.0 if mk else 0.0, K, np.int64(0), probe, FULL)
            ints[I_EVALS] += 1
    ints[I_DENSE] = -1
    if mk and p[P_TURN] > 0.0 and not sliding:
        for q in range(3):
            z[5 + q] = probe[PROBE_OMEGA + q]
    record(rows, 0, t_start, z, R, probe, p)
    if not (_finite(z, 0, n) and _finite_row(K, 0, 0, n) and _finite(probe, 0, PROBE_SIZE)
            and _finite_row(rows, 0, 0, ROW_SIZE)):
        _fail(ints, info, NONFINITE, R_START_OVERFLOW, t_start, z[0], z[1], math.nan)
        return
    ints[I_ROWS] = 1
    if probe[PROBE_FORCE] < 0.0:
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t_start, z[0], z[1], 0.0
    if probe[PROBE_FIT] >= 1.0:
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t_start, z[0], z[1], probe[PROBE_FIT])
        return
    kind = start_mode(p, sliding, probe)
    if kind != 0:
        ints[I_STATUS] = TRANSITION
        ints[I_TRANSITION] = kind
        info[F_EVENT_T], info[F_EVENT_X], info[F_EVENT_Y] = t_start, z[0], z[1]


# A sliding start with zero slip grips only where rolling needs less than mu F.N by this share of
# it: at a slip the two are equal to round-off, and the slip must not turn into a grip at once.
GRIP_MARGIN = 1e-9


@JIT
def start_mode(p, sliding, probe):
    """The change of contact mode a run's start makes at once (probe: its state's), or 0:
    a lift-off where F.N < 0 and the ball flies (p[P_FLY]); rolling, a slip where the friction
    it needs exceeds mu F.N; sliding with zero slip, a grip where it needs less (GRIP_MARGIN)."""
    force, need, mu = probe[PROBE_FORCE], probe[PROBE_NEED], p[P_MU]
    if p[P_FLY] != 0.0 and force < 0.0:
        return T_LIFTOFF
    if sliding:
        slip = probe[PROBE_SLIP] ** 2 + probe[PROBE_SLIP + 1] ** 2 + probe[PROBE_SLIP + 2] ** 2
        return T_GRIP if slip == 0.0 and need <= mu * force * (1.0 - GRIP_MARGIN) else 0
    if mu < math.inf and need > mu * force:
        return T_SLIP
    return 0
