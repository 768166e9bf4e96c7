"""The compiled sweep loop: whole batches of fixed-step runs in one call, without the GIL.

A run of a sweep needs only the motion (contact point and angular momentum): the state has
``MOTION_SIZE`` entries, with no Munthe-Kaas increment, no Rodrigues update and no matrix R.
No rows are kept: after every step the run updates running accumulators for its outcomes,
so memory does not grow with the number of steps. Each step is the main kernel's own:
its trial step, fit checks (the search for the edge of the no-fit region included), lift-off
detection and row formulas (``rollball.kernel``), so a sweep's runs end exactly where
``simulate`` ends the same scene.
"""

from __future__ import annotations

import math

import numpy as np

from .. import kernel
# The narrow seam to the main kernel: these names and nothing else.
from ..kernel import (EXPLICIT, F_LIFTOFF, I_ROWS, I_STATUS, JIT, MOTION_SIZE, NONFINITE, OK, RUNNING,
                      accept, record, record_valid, scratch, start, step_events, trial_step)
from ..trajectory import CENTER, ENERGY, NORMAL_FORCE, VELOCITY

# One row of outcomes per run, in this order (the status is kept apart, as a code).
OUTCOMES = ("t_reached", "liftoff_time", "x_end", "y_end", "energy_drift", "min_normal_force",
            "max_speed", "path_length")
O_T, O_LIFTOFF, O_X, O_Y, O_DRIFT, O_MIN_FORCE, O_MAX_SPEED, O_PATH = range(len(OUTCOMES))

# Status codes beyond the kernel's: a run whose varied scene was refused, and one not run yet.
INVALID, NOT_RUN = 10, 11

# Where the quantities sit in a trajectory row (the core's row layout), as compile-time ints.
_CX, _VX, _ENERGY, _FORCE = CENTER.start, VELOCITY.start, ENERGY, NORMAL_FORCE

_TINY = float(np.finfo(float).tiny)


@JIT
def _take_row(row, first, acc):
    """Fold one recorded state into the run's accumulators: acc = E0, max |E - E0|, the
    previous centre (3), min F.N, max speed, path length; ``first`` starts them."""
    energy = row[_ENERGY]
    speed = math.sqrt(row[_VX] ** 2 + row[_VX + 1] ** 2 + row[_VX + 2] ** 2)
    if first:
        acc[0], acc[1] = energy, 0.0
        acc[5], acc[6], acc[7] = row[_FORCE], speed, 0.0  # min force, max speed, path
    else:
        acc[1] = max(acc[1], abs(energy - acc[0]))
        acc[5] = min(acc[5], row[_FORCE])
        acc[6] = max(acc[6], speed)
        acc[7] += math.sqrt((row[_CX] - acc[2]) ** 2 + (row[_CX + 1] - acc[3]) ** 2
                            + (row[_CX + 2] - acc[4]) ** 2)
    acc[2], acc[3], acc[4] = row[_CX], row[_CX + 1], row[_CX + 2]


@JIT
def run_batch(fn, W, D, Z0, P, DT, T_END, N_STEPS, status, out, K, probe, rows, R, ints, info, acc, work):
    """Run every run of a batch whose status is NOT_RUN; write its status and outcomes.

    fn: the compiled landscape; W, D: the tableau and its dense output (``Tableau.kernel_arrays``,
    W and P there); per run b: Z0[b] the initial
    motion state, P[b] the kernel parameters (``kernel.parameters``), DT[b], T_END[b], N_STEPS[b]
    the fixed steps. K, probe, rows (one row), R (3x3), ints, info, acc (8) and work
    (``kernel.work_size(MOTION_SIZE)``) are scratch.
    """
    n = MOTION_SIZE
    last = W.shape[0] - 1
    z = work[work.shape[0] - n:]  # the current state, at the end of the scratch
    d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm = scratch(work, n)
    row = rows[0]
    for b in range(Z0.shape[0]):
        if status[b] != NOT_RUN:
            continue
        p = P[b]
        for q in range(n):
            z[q] = Z0[b, q]
        for q in range(ints.shape[0]):
            ints[q] = 0
        for q in range(info.shape[0]):
            info[q] = math.nan
        for q in range(out.shape[1]):
            out[b, q] = math.nan
        start(fn, d, p, z, R, K, probe, rows, ints, info)
        if ints[I_ROWS] == 0:  # the initial state is not finite: nothing to report
            status[b] = ints[I_STATUS]
            continue
        _take_row(row, True, acc)
        t_reached = 0.0
        dt, t_end, n_steps = DT[b], T_END[b], N_STEPS[b]
        k = 0
        x_end, y_end = z[0], z[1]
        while ints[I_STATUS] == RUNNING and k < n_steps:
            k += 1
            final = k == n_steps
            t0 = (k - 1) * dt
            h = t_end - t0 if final else dt
            t = t_end if final else k * dt
            bad = trial_step(fn, d, p, W, D, h, z, R, K, last, Y, zn, Rn, pn, ints)
            if bad:
                ints[I_STATUS] = NONFINITE
                break
            valid = step_events(fn, d, p, W, False, n, t0, h, z, R, K, last, D, probe, Y, zn, Rn, pn, ints,
                                info, True, Ye, Re, pe, sa, sb, sm, EXPLICIT)
            if valid >= 0.0:  # the last valid state inside the step, as simulate finds it
                ints[I_ROWS] = 0
                record_valid(fn, d, p, W, t0, h, valid, z, R, K, last, D, probe, rows, ints, info, Y, zn, Rn,
                             pn, Ye, sa, sb, sm, EXPLICIT)
                if ints[I_ROWS] == 1:
                    _take_row(row, False, acc)
                    t_reached, x_end, y_end = row[0], row[1], row[2]
                break
            accept(p, False, n, z, R, K, last, probe, zn, Rn, pn)
            record(rows, 0, t, z, R, probe, p)
            _take_row(row, False, acc)
            t_reached, x_end, y_end = t, z[0], z[1]
        if ints[I_STATUS] == RUNNING:
            ints[I_STATUS] = OK
        status[b] = ints[I_STATUS]
        r, m, g0 = p[0], p[1], p[2]
        o = out[b]
        o[O_T] = t_reached
        o[O_LIFTOFF] = info[F_LIFTOFF]
        o[O_X], o[O_Y] = x_end, y_end
        o[O_DRIFT] = acc[1] / max(abs(acc[0]), m * g0 * r, _TINY)
        o[O_MIN_FORCE], o[O_MAX_SPEED], o[O_PATH] = acc[5], acc[6], acc[7]


def scratch_arrays(stages: int) -> tuple:
    """The scratch arrays ``run_batch`` needs after its outcome arrays (one set per thread);
    stages: the rows of the method's W."""
    n = MOTION_SIZE
    return (np.zeros((kernel.stage_rows(stages), n)), np.zeros(kernel.PROBE_SIZE), np.zeros((1, kernel.ROW_SIZE)),
            np.eye(3), np.zeros(kernel.INTS_SIZE, dtype=np.int64), np.zeros(kernel.INFO_SIZE),
            np.zeros(8), np.zeros(kernel.work_size(n) + n))
