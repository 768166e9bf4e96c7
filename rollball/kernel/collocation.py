"""Implicit Gauss–Legendre steps: the stage equations K_i = z'(z + h sum_j a_ij K_j) solved
by fixed-point iteration (the tableaus: implicit.py)."""

from __future__ import annotations

import numpy as np

from .explicit import STEP_NOT_CONVERGED, end_of_step
from .interface import (I_EVALS, I_STEPS, MK_SIZE, MOTION_SIZE, RESISTED_MK_SIZE, SLIDING_MK_SIZE, SLIDING_MOTION_SIZE,
                        SLIDING_RESISTED_MK_SIZE)
from .lowlevel import COLD, JIT
from .physics import STAGE, dexpinv, dynamics, rodrigues, sliding_dynamics


# -- implicit Gauss-Legendre steps (the tableaus: implicit.py) ------------------------------------
#
# An s-stage Gauss method solves K_i = z'(z + h sum_j a_ij K_j) at every step. The iteration
# lives here, beside the explicit stage loop, so that numba's disk cache (which watches only
# the file a function is defined in) recompiles it whenever what it inlines changes.

# The stage iteration is converged once the scaled change of the stage values is at
# round-off (or the error it predicts at the rate seen is below EPSILON), or once it has
# stopped shrinking (no new smallest change in STALL iterations) below NOISE (round-off
# fluctuations); it fails when it stops shrinking above NOISE (it diverges) or has not
# converged after MAX_ITERATIONS.
EPSILON = 2.0 ** -52
ROUND_OFF = 4.0 * EPSILON
NOISE = 1e-13
STALL = 3
MAX_ITERATIONS = 60


@COLD  # compiled once (not into each loop): a call costs nothing beside its iterations
def collocation_step(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """One Gauss–Legendre step (``_collocation_step``) for z's layout: rolling or sliding."""
    n = z.shape[0]
    if n == SLIDING_MK_SIZE:
        return sliding_collocation(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == RESISTED_MK_SIZE:
        return resisted_collocation(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == SLIDING_RESISTED_MK_SIZE:
        return resisted_sliding_collocation(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints)
    return rolling_collocation(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints)


def _collocation_step(n: int):
    """The Gauss step for one state layout (MK_SIZE rolling, SLIDING_MK_SIZE sliding): with its
    sizes constants of the compiled code, the loops over the motion unroll."""
    m = SLIDING_MOTION_SIZE if n in (SLIDING_MK_SIZE, SLIDING_RESISTED_MK_SIZE) else MOTION_SIZE

    @JIT
    def step(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints):
        """One Gauss–Legendre step of size h (h < 0 steps backwards) from z to zn, Rn, with the
        arguments and codes of trial_step (the orientation always Munthe-Kaas).

        The stage equations are solved in two parts, since u does not act on the motion (rolling
        (alpha, v), or sliding (alpha, c', omega, D): the state's length says which): first the
        motion, evaluating the right-hand side with u = 0 (so that its u-part is omega), then the
        increments u at the stages from those omegas, which needs no evaluations.

        W (``Collocation.kernel_arrays``) holds a_ij at W[1+i, 1+j], b_i at W[last, 1+i] and the
        extrapolation of the starting values in rows s+1 .. 2s. K[0] holds z'(z); K[1 .. s] hold
        the stage derivatives (on entry those of the previous step, extrapolated with K[0] after
        the first step; on return this step's); K[s+1 .. 2s] is scratch (on return its u-part
        holds omega at the stages); K[last] = K[2s+1] and pn receive the full evaluation at zn.
        Counts its evaluations in ints[I_EVALS]. Returns 0 (done), 1 (the motion is not finite),
        2 (only the orientation is not) or STEP_NOT_CONVERGED.
        """
        s = (last - 1) // 2
        new = s + 1
        # starting values: extrapolated from the previous step's stages and z'(z), or z'(z) throughout
        for i in range(s):
            for q in range(m):
                acc = K[0, q]
                if ints[I_STEPS] > 0:
                    acc *= W[new + i, 0]
                    for j in range(s):
                        acc += W[new + i, 1 + j] * K[1 + j, q]
                K[new + i, q] = acc
        for i in range(s):
            for q in range(m):
                K[1 + i, q] = K[new + i, q]
        for q in range(m, n):
            Y[q] = 0.0
        code = _iterate(s, m, h, z, K, W, ints, fn, d, p, Y, pn)
        if code == 0:
            code = _increments(s, m, h, K, W)
        if code != 0:
            return code
        for i in range(s):   # (the dissipation's quadratures, after u: their rates at the stages)
            for q in range(m + 3, n):
                K[1 + i, q] = K[s + 1 + i, q]
        for q in range(n):
            zn[q] = z[q]
        for i in range(s):
            c = h * W[last, 1 + i]
            for q in range(n):
                zn[q] += c * K[1 + i, q]
        rodrigues(zn[m], zn[m + 1], zn[m + 2], R, Rn)
        return end_of_step(fn, d, p, True, n, True, zn, Rn, K, last, pn, ints)

    return step


rolling_collocation = _collocation_step(MK_SIZE)
sliding_collocation = _collocation_step(SLIDING_MK_SIZE)
resisted_collocation = _collocation_step(RESISTED_MK_SIZE)
resisted_sliding_collocation = _collocation_step(SLIDING_RESISTED_MK_SIZE)


@JIT
def _iterate(s, m, h, z, K, W, ints, fn, d, p, Y, pn):
    """Fixed-point iteration for the motion's parts (the first m) of the stage derivatives
    K[1 .. s]."""
    new = s + 1
    best, stalled, previous = np.inf, 0, np.inf
    for _ in range(MAX_ITERATIONS):
        for i in range(s):
            for q in range(m):
                Y[q] = z[q]
            for j in range(s):
                c = h * W[1 + i, 1 + j]
                for q in range(m):
                    Y[q] += c * K[1 + j, q]
            if m == MOTION_SIZE:   # (m a constant of the caller: one of the two is compiled)
                dynamics(fn, d, p, Y, 1.0, K, new + i, pn, STAGE)
            else:
                sliding_dynamics(fn, d, p, Y, 1.0, K, new + i, pn, STAGE)
        ints[I_EVALS] += s
        # (the parts scaled each by its own size: alpha, then v; sliding alpha, c', omega, D)
        change = max(_scaled_change(s, h, z, K, 0, 2), _scaled_change(s, h, z, K, 2, 5))
        if m != MOTION_SIZE:
            change = max(change, _scaled_change(s, h, z, K, 5, 8), _scaled_change(s, h, z, K, 8, 9))
        for i in range(s):
            for q in range(m):
                K[1 + i, q] = K[new + i, q]
        if change != change:  # the stages left the landscape's domain
            return 1
        # done when the change, or the error it predicts at the rate seen (Hairer, Lubich and
        # Wanner VIII.6: change * rate / (1 - rate)), is at round-off
        rate = change / previous  # (0 at the first iteration, which predicts nothing)
        if change <= ROUND_OFF or (0.0 < rate < 1.0 and change * rate <= EPSILON * (1.0 - rate)):
            return 0
        previous = change
        # a change passes from alpha to v and back, so it need not shrink at every
        # iteration: only STALL iterations without a new smallest change end the iteration
        if change < best:
            best, stalled = change, 0
        else:
            stalled += 1
            if stalled == STALL:  # at round-off, or not contracting
                return 0 if change <= NOISE else STEP_NOT_CONVERGED
    return STEP_NOT_CONVERGED


@JIT
def _increments(s, m, h, K, W):
    """The u-parts of K[1 .. s] (after the motion's m): U_i = h sum_j a_ij dexp^-1_(U_j)(omega_j),
    iterated from U = 0 (omega_j in the u-part of K[s+1+j]); no right-hand-side evaluations."""
    new = s + 1
    for i in range(s):
        for q in range(m, m + 3):
            K[1 + i, q] = K[new + i, q]  # dexp^-1 at U = 0
    best, stalled = np.inf, 0
    for _ in range(MAX_ITERATIONS):
        change, size = 0.0, 0.0
        for i in range(s):
            u1, u2, u3 = 0.0, 0.0, 0.0
            for j in range(s):
                c = h * W[1 + i, 1 + j]
                u1 += c * K[1 + j, m]
                u2 += c * K[1 + j, m + 1]
                u3 += c * K[1 + j, m + 2]
            k1, k2, k3 = dexpinv(u1, u2, u3, K[new + i, m], K[new + i, m + 1], K[new + i, m + 2])
            change = max(change, abs(k1 - K[1 + i, m]), abs(k2 - K[1 + i, m + 1]), abs(k3 - K[1 + i, m + 2]))
            size = max(size, abs(k1), abs(k2), abs(k3))
            # (Gauss-Seidel: later stages see this one's new value at once)
            K[1 + i, m], K[1 + i, m + 1], K[1 + i, m + 2] = k1, k2, k3
        if not change <= size * 1e300:
            return 2
        if change <= ROUND_OFF * size:
            return 0
        if change < best:
            best, stalled = change, 0
        else:
            stalled += 1
            if stalled == STALL:
                return 0 if change <= NOISE * size else STEP_NOT_CONVERGED
    return STEP_NOT_CONVERGED


@JIT
def _scaled_change(s, h, z, K, lo, hi):
    """The largest change h |K_new - K_old| of a stage value in z[lo:hi] (alpha or v), relative
    to the size of that part of the state plus how far the stages move it; nan if an
    iterate is not finite."""
    scale = 0.0
    for q in range(lo, hi):
        scale = max(scale, abs(z[q]))
        for i in range(s):
            scale = max(scale, abs(h * K[s + 1 + i, q]))
    worst = 0.0
    for q in range(lo, hi):
        for i in range(s):
            delta = abs(h * (K[s + 1 + i, q] - K[1 + i, q]))
            if not delta < np.inf:
                return np.nan
            if delta > 0.0:  # (a part at rest whose stages still move: a large change)
                worst = max(worst, delta / scale if scale > 0.0 else 1.0)
    return worst
