"""A run's rows and how it stops: one recorded row (``record``, the columns of
``interface.ROW_FIELDS``), the start check, and a failure's code and facts (``_fail``)."""

from __future__ import annotations

import math

import numpy as np

from .interface import (
    DOES_NOT_FIT, F_FAIL_T, F_FAIL_VALUE, F_FAIL_X, F_FAIL_Y, F_LIFTOFF, F_LIFT_KINK, F_LIFT_X, F_LIFT_Y, I_DENSE,
    I_EVALS, I_LAST_RECORDED, I_REASON, I_ROWS, I_STATUS, I_STEPS, NONFINITE, PROBE_FIT, PROBE_FORCE, PROBE_HEIGHT,
    PROBE_OMEGA, PROBE_SIZE, P_TURN, ROW_CENTER, ROW_CONTACT, ROW_ENERGY, ROW_FORCE, ROW_OMEGA, ROW_R, ROW_SIZE,
    ROW_T, ROW_VELOCITY, R_NO_FIT, R_START_OVERFLOW, R_START_UNDEFINED)
from .lowlevel import COLD, JIT, data_pointer, landscape
from .physics import FULL, _finite, _finite_row, dynamics, shape_of


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
    rows[i, ROW_VELOCITY] = r * (o2 * n3 - o3 * n2)
    rows[i, ROW_VELOCITY + 1] = r * (o3 * n1 - o1 * n3)
    rows[i, ROW_VELOCITY + 2] = r * (o1 * n2 - o2 * n1)
    rows[i, ROW_OMEGA], rows[i, ROW_OMEGA + 1], rows[i, ROW_OMEGA + 2] = o1, o2, o3
    for a in range(3):
        for b in range(3):
            rows[i, ROW_R + 3 * a + b] = R[a, b]
    rows[i, ROW_ENERGY] = 0.5 * (o1 * z[2] + o2 * z[3] + o3 * z[4]) + m * g0 * cz
    rows[i, ROW_FORCE] = probe[PROBE_FORCE]


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
def start(fn, d, p, z, R, K, probe, rows, ints, info):
    """Check and record the initial state; K[0] and probe describe it afterwards."""
    n, mk = shape_of(z)
    landscape(fn, z[0], z[1], data_pointer(d))
    if not _finite(d, 0, 6):
        _fail(ints, info, NONFINITE, R_START_UNDEFINED, 0.0, z[0], z[1], math.nan)
        return
    # (np.int64(0): a literal 0 would compile dynamics anew for it)
    dynamics(fn, d, p, z, 1.0 if mk else 0.0, K, np.int64(0), probe, FULL)
    ints[I_EVALS] += 1
    ints[I_DENSE] = -1
    if mk and p[P_TURN] > 0.0:
        for q in range(3):
            z[5 + q] = probe[PROBE_OMEGA + q]
    record(rows, 0, 0.0, z, R, probe, p)
    if not (_finite(z, 0, n) and _finite_row(K, 0, 0, n) and _finite(probe, 0, PROBE_SIZE)
            and _finite_row(rows, 0, 0, ROW_SIZE)):
        _fail(ints, info, NONFINITE, R_START_OVERFLOW, 0.0, z[0], z[1], math.nan)
        return
    ints[I_ROWS] = 1
    if probe[PROBE_FORCE] < 0.0:
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = 0.0, z[0], z[1], 0.0
    if probe[PROBE_FIT] >= 1.0:
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, 0.0, z[0], z[1], probe[PROBE_FIT])
