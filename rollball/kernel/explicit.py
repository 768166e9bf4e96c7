"""The explicit Runge–Kutta step (one compiled per state layout), the check and full
evaluation of its new state, and the dense-output stages and orientation of the pairs."""

from __future__ import annotations

from .dense import omega_polynomial, turn
from .interface import (
    CLASSIC_SIZE, I_DENSE, I_EVALS, I_STEPS, MK_SIZE, MOTION_SIZE, PROBE_SIZE, P_TURN, QUADRATURES,
    RESISTED_CLASSIC_SIZE, RESISTED_MK_SIZE, SLIDING_CLASSIC_SIZE, SLIDING_MK_SIZE, SLIDING_MOTION_SIZE,
    SLIDING_RESISTED_CLASSIC_SIZE, SLIDING_RESISTED_MK_SIZE, SLIDING_SIZES)
from .lowlevel import COLD, JIT, STEP
from .physics import (FULL, STAGE, _finite, _finite_matrix, _finite_row, dynamics, motion_size, rates,
                      resisted_size, rodrigues, shape_of, sliding_dynamics, sliding_size)


@JIT
def combine(n, z, h, W, row, K, s, out):
    """out = z + h sum_{i<s} W[row, i] K_i, skipping zero weights (row by row: it vectorises)."""
    for q in range(n):
        out[q] = z[q]
    for i in range(s):
        c = h * W[row, i]
        if c != 0.0:
            for q in range(n):
                out[q] += c * K[i, q]


def _trial_step(n: int, mk: bool, defer: bool = False):
    """The explicit step for one state layout: with n and mk constants of the compiled code,
    its stage loops unroll as in hand-written C. ``defer``: carrying omega, leave R to the
    caller (``carry_orientation`` once the step is accepted: a rejected try does not pay
    for the dense-output stages). The layout's length says rolling or sliding (``interface``)."""
    sliding = n in SLIDING_SIZES or n in (SLIDING_RESISTED_MK_SIZE, SLIDING_RESISTED_CLASSIC_SIZE)
    m = SLIDING_MOTION_SIZE if sliding else MOTION_SIZE   # the motion; the orientation after it
    orientation = n > m
    rhs = sliding_dynamics if sliding else dynamics
    # the stages' states: without the dissipation's quadratures, which no rate reads (the step's end has them)
    staged = n - QUADRATURES if resisted_size.py_func(n) else n

    @STEP
    def trial_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
        """One Runge–Kutta step of size h from z (K[0] = z'(z)) to zn, Rn.

        W holds the method (see ``Tableau.kernel_arrays``): rows 1 .. last-1 the stage
        coefficients, row ``last`` the weights b. Stages 1 .. last-1 fill K[1 .. last-1];
        zn = z + h sum b_i K_i; then the full evaluation at zn (before u is reset) goes to
        K[last] and pn. Returns whether the new state is finite: 0 = yes, 1 = the motion is
        not, 2 = only the orientation is not. Counts its evaluations in ints[I_EVALS].
        Carrying omega (p[P_TURN] > 0), Rn follows omega's dense output (P) through the step,
        after the evaluation at zn and the dense-output stages (rows of W after ``last``).
        """
        for i in range(1, last):
            combine(staged, z, h, W, i, K, i, Y)
            rhs(fn, d, p, Y, 1.0 if mk else 0.0, K, i, pn, STAGE)
        ints[I_EVALS] += last - 1
        combine(n, z, h, W, last, K, last, zn)
        carry = orientation and mk and p[P_TURN] > 0.0
        if carry:  # (finite until carried, after the evaluation at zn)
            for a in range(3):
                for c in range(3):
                    Rn[a, c] = R[a, c]
        elif orientation and mk:
            rodrigues(zn[m], zn[m + 1], zn[m + 2], R, Rn)
        elif orientation:
            for a in range(3):
                for c in range(3):
                    Rn[a, c] = zn[m + 3 * a + c]
        code = end_of_step(fn, d, p, mk, n, orientation, zn, Rn, K, last, pn, ints)
        if carry and code == 0 and not defer:
            code = carry_orientation(fn, d, p, W, P, h, z, R, K, last, Y, Rn, pn, ints)
        return code

    return trial_step


trial_step_mk = _trial_step(MK_SIZE, True)
trial_step_pair = _trial_step(MK_SIZE, True, True)  # the pairs' tries (``advance_adaptive``)
trial_step_classic = _trial_step(CLASSIC_SIZE, False)
trial_step_motion = _trial_step(MOTION_SIZE, False)
sliding_step_mk = _trial_step(SLIDING_MK_SIZE, True)
sliding_step_pair = _trial_step(SLIDING_MK_SIZE, True, True)
sliding_step_classic = _trial_step(SLIDING_CLASSIC_SIZE, False)
# (the same with the dissipation's quadratures)
resisted_step_mk = _trial_step(RESISTED_MK_SIZE, True)
resisted_step_pair = _trial_step(RESISTED_MK_SIZE, True, True)
resisted_step_classic = _trial_step(RESISTED_CLASSIC_SIZE, False)
resisted_sliding_mk = _trial_step(SLIDING_RESISTED_MK_SIZE, True)
resisted_sliding_pair = _trial_step(SLIDING_RESISTED_MK_SIZE, True, True)
resisted_sliding_classic = _trial_step(SLIDING_RESISTED_CLASSIC_SIZE, False)


@JIT
def trial_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """The explicit step (``_trial_step``) for z's layout: MK_SIZE, CLASSIC_SIZE or MOTION_SIZE
    rolling, SLIDING_MK_SIZE or SLIDING_CLASSIC_SIZE sliding, each of the first two with the
    dissipation's quadratures or without."""
    n = z.shape[0]
    if n == MK_SIZE:
        return trial_step_mk(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == CLASSIC_SIZE:
        return trial_step_classic(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == SLIDING_MK_SIZE:
        return sliding_step_mk(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == SLIDING_CLASSIC_SIZE:
        return sliding_step_classic(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == MOTION_SIZE:
        return trial_step_motion(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    return resisted_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)


@JIT
def pair_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """An embedded pair's try (``_trial_step``, R left to ``carry_orientation``) for z's layout:
    MK_SIZE or SLIDING_MK_SIZE, each with the dissipation's quadratures or without."""
    n = z.shape[0]
    if n == MK_SIZE:
        return trial_step_pair(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == SLIDING_MK_SIZE:
        return sliding_step_pair(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == RESISTED_MK_SIZE:
        return resisted_step_pair(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    return resisted_sliding_pair(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)


@JIT
def resisted_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """The explicit step for a layout with the dissipation's quadratures (``trial_step``)."""
    n = z.shape[0]
    if sliding_size(n):
        if n == SLIDING_RESISTED_MK_SIZE:
            return resisted_sliding_mk(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
        return resisted_sliding_classic(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == RESISTED_MK_SIZE:
        return resisted_step_mk(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    return resisted_step_classic(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)


@JIT
def end_of_step(fn, d, p, mk, n, orientation, zn, Rn, K, last, pn, ints):
    """The new state zn, Rn of a step checked, then evaluated in full into K[last] and pn
    (counted in ints[I_EVALS]). Returns the step's report (below): 0, 1 or 2."""
    m = motion_size(n)
    if not _finite(zn, 0, m):
        return 1
    if orientation and not (_finite(zn, m, n) and _finite_matrix(Rn)):
        return 2
    if m == MOTION_SIZE:
        dynamics(fn, d, p, zn, 1.0 if mk else 0.0, K, last, pn, FULL)
    else:
        sliding_dynamics(fn, d, p, zn, 1.0 if mk else 0.0, K, last, pn, FULL)
    ints[I_EVALS] += 1
    if not (_finite_row(K, last, 0, m) and _finite(pn, 0, PROBE_SIZE)):
        return 1
    if not _finite_row(K, last, m, n):
        return 2
    return 0


@COLD
def carry_orientation(fn, d, p, W, P, h, z, R, K, last, Y, Rn, pn, ints):
    """The end of an explicit step carrying omega, once its new state is evaluated: the
    dense-output stages taken, then R carried through the step into Rn (``turn``); returns
    the step's report (0, or 2 where the orientation is not finite)."""
    ints[I_DENSE] = -1  # (this trial's own)
    dense_stages(fn, d, p, W, h, z, K, last, Y, pn, ints)
    omega_polynomial(h, P, K)  # (with the stages: every later turn inside the step reads it)
    turn(p, z, R, h, P, K, 0.0, 1.0, Rn)
    return 0 if _finite_matrix(Rn) else 2


# What a step reports (trial_step and collocation_step alike): 0 done, 1 the motion is not
# finite, 2 only the orientation is not, 3 an implicit step's stage equations did not converge.
STEP_NOT_CONVERGED = 3


@COLD
def dense_stages(fn, d, p, W, h, z, K, last, Y, pe, ints):
    """The extra dense-output stages of the step being taken (rows last+1 .. of W), once."""
    n, mk = shape_of(z)
    if ints[I_DENSE] == ints[I_STEPS] + 1:
        return
    ints[I_DENSE] = ints[I_STEPS] + 1
    for i in range(last + 1, W.shape[0]):
        combine(n, z, h, W, i, K, i, Y)
        rates(fn, d, p, Y, 1.0 if mk else 0.0, K, i, pe, STAGE)
        ints[I_EVALS] += 1
