"""One run of a sweep, from its initial state to its row of outcomes.

A run of a sweep needs only the motion (contact point and angular momentum): its state has
``MOTION_SIZE`` entries, with no Munthe-Kaas increment, no Rodrigues update and no matrix R.
It is stepped by the kernel's own fixed-step loop, the one ``simulate`` uses
(``kernel.advance``: the same steps, fit checks, search for the edge of the no-fit region and
lift-off detection), so a sweep's runs end exactly where ``simulate`` ends the same scene, and
nothing is compiled for sweeps alone. The loop records every step; each chunk of ``CHUNK``
steps is folded into running outcomes and dropped, so memory does not grow with the number
of steps. The compiled loop releases the GIL: threads run on all cores.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import kernel
from ..trajectory import CENTER, ENERGY, NORMAL_FORCE, VELOCITY

# One row of outcomes per run, in this order (the status is kept apart, as a code).
OUTCOMES = ("t_reached", "liftoff_time", "x_end", "y_end", "energy_drift", "min_normal_force",
            "max_speed", "path_length")
O_T, O_LIFTOFF, O_X, O_Y, O_DRIFT, O_MIN_FORCE, O_MAX_SPEED, O_PATH = range(len(OUTCOMES))

# Status codes beyond the kernel's: a run whose varied scene was refused, and one not run yet.
INVALID, NOT_RUN = 10, 11

CHUNK = 4096  # steps folded into the outcomes at a time

_TINY = float(np.finfo(float).tiny)
# Where _fold finds its quantities in a row, passed to it (a compiled function's cached code is
# renewed only when its own file changes, not when the row layout's does).
_COLUMNS = (CENTER.start, VELOCITY.start, ENERGY, NORMAL_FORCE)


@njit(cache=True, nogil=True)
def _fold(rows, count, first, acc, columns):
    """Fold rows[first:count] into the run's accumulators acc = E0, max |E - E0|, min F.N,
    max speed, path length; rows[first - 1] is the row before them (first = 0 starts them).
    columns: where the centre, its velocity, the energy and the normal force are in a row."""
    _CX, _VX, _ENERGY, _FORCE = columns
    if first == 0:
        acc[0], acc[1], acc[2], acc[3], acc[4] = rows[0, _ENERGY], 0.0, math.inf, 0.0, 0.0
    for i in range(first, count):
        row = rows[i]
        acc[1] = max(acc[1], abs(row[_ENERGY] - acc[0]))
        acc[2] = min(acc[2], row[_FORCE])
        acc[3] = max(acc[3], math.sqrt(row[_VX] ** 2 + row[_VX + 1] ** 2 + row[_VX + 2] ** 2))
        if i > 0:
            acc[4] += math.sqrt((row[_CX] - rows[i - 1, _CX]) ** 2 + (row[_CX + 1] - rows[i - 1, _CX + 1]) ** 2
                                + (row[_CX + 2] - rows[i - 1, _CX + 2]) ** 2)


class Runner:
    """Runs one run after another with the same method, reusing its arrays (one per thread)."""

    def __init__(self, W: np.ndarray, P: np.ndarray):
        n = kernel.MOTION_SIZE
        self.W, self.P = W, P
        self.z = np.zeros(n)
        self.R = np.eye(3)
        self.K = np.zeros((kernel.stage_rows(W.shape[0]), n))
        self.probe = np.zeros(kernel.PROBE_SIZE)
        self.rows = np.empty((CHUNK + 2, kernel.ROW_SIZE))  # the carried last row, the chunk, a stop's row
        self.ints = np.zeros(kernel.INTS_SIZE, dtype=np.int64)
        self.info = np.empty(kernel.INFO_SIZE)
        self.work = np.empty(kernel.work_size(n))
        self.acc = np.empty(5)

    def run(self, fn, z0: np.ndarray, p: np.ndarray, dt: float, t_end: float, n_steps: int,
            out: np.ndarray) -> int:
        """Run from the motion state z0 with kernel parameters p and fixed steps dt to t_end
        (n_steps of them); write the outcomes into ``out`` and return the kernel's status."""
        self.z[:] = z0
        self.ints[:] = 0
        self.info[:] = np.nan
        out[:] = np.nan
        rows, ints, acc = self.rows, self.ints, self.acc
        first = 0  # the first row not folded in yet (after the first chunk, row 0 is the last one folded)
        while ints[kernel.I_STATUS] == kernel.RUNNING:
            kernel.advance(fn, self.W, self.P, p, dt, t_end, n_steps, 1, CHUNK, self.z, self.R, self.K,
                           self.probe, rows, ints, self.info, self.work, kernel.EXPLICIT)
            count = ints[kernel.I_ROWS]
            if count == 0:  # the initial state is not finite: nothing to report
                return int(ints[kernel.I_STATUS])
            _fold(rows, count, first, acc, _COLUMNS)
            rows[0] = rows[count - 1]
            ints[kernel.I_ROWS], first = 1, 1
        last = rows[0]
        out[O_T], out[O_X], out[O_Y] = last[0], last[1], last[2]
        out[O_LIFTOFF] = self.info[kernel.F_LIFTOFF]
        out[O_DRIFT] = acc[1] / max(abs(acc[0]), p[1] * p[2] * p[0], _TINY)
        out[O_MIN_FORCE], out[O_MAX_SPEED], out[O_PATH] = acc[2], acc[3], acc[4]
        return int(ints[kernel.I_STATUS])
