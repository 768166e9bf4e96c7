"""Bounds of a landscape over a box, compiled (docs/design.md §1, "Flight"): interval arithmetic
along the landscape's tape (``Landscape.tape``: f's operations in order, interface's TAPE_*).

Each row's interval encloses every value the landscape's own machine code computes for that
operation at any (x, y) in the box, its round-off included, whatever order that code takes the
terms of a sum or the factors of a product in: a sum of n terms is widened by (n + 1) ε times
the sizes of its operands, a product of n factors by (n + 4) ε times its own (ε the double's
machine epsilon; IEEE's +, −, ×, ÷ are off by at most ε/2 each), a function of the math library by
LIBM ε (glibc's are off by at most two units in the last place), every interval by TINY more (an
underflow's round-off). A row that may be NaN, or whose operand's domain the box leaves (log,
sqrt, … of a box partly outside it), is NaN: nothing is certified from it. So f's interval is sound
for the values the track compares (``landing.track_clear``)."""

from __future__ import annotations

import math

from .interface import (
    LANDSCAPE_RECORD_VALUES, TAPE_ABS, TAPE_ACOS, TAPE_ACOSH, TAPE_ADD, TAPE_ASIN, TAPE_ASINH, TAPE_ATAN, TAPE_ATANH,
    TAPE_CONST, TAPE_COS, TAPE_COSH, TAPE_EXP, TAPE_LOG, TAPE_MAX, TAPE_MIN, TAPE_MUL, TAPE_PARAMETER, TAPE_POW,
    TAPE_POWER, TAPE_REAL_POWER, TAPE_SIN, TAPE_SINH, TAPE_SQRT, TAPE_TANH, TAPE_X, TAPE_Y,
)
from .lowlevel import EXACT, JIT, float_pointer

EPS = 2.220446049250313e-16   # (the double's machine epsilon)
TINY = 1e-300
LIBM = 4.0
TWO_PI = 2.0 * math.pi
PERIODIC_MOST = 1e6   # |argument| beyond which sin and cos are bounded by [-1, 1] alone


@JIT
def size(lo, hi):
    return max(abs(lo), abs(hi))


@JIT
def product(alo, ahi, blo, bhi):
    """The interval product (NaN where a product of the ends is: 0 × inf)."""
    p1, p2, p3, p4 = alo * blo, alo * bhi, ahi * blo, ahi * bhi
    if math.isnan(p1) or math.isnan(p2) or math.isnan(p3) or math.isnan(p4):
        return math.nan, math.nan
    return min(min(p1, p2), min(p3, p4)), max(max(p1, p2), max(p3, p4))


@JIT
def passes(lo, hi, offset):
    """Whether offset + 2kπ lies in [lo, hi] for some whole k (taken a little wide: round-off)."""
    slack = 1e-9 * (1.0 + abs(lo) + abs(hi))
    k = math.ceil((lo - slack - offset) / TWO_PI)
    return offset + k * TWO_PI <= hi + slack


@JIT
def power(lo, hi, n):
    """x^n over [lo, hi] for a whole n ≥ 0 (as a float), unwidened."""
    if n == 0.0:
        return 1.0, 1.0
    a, b = math.pow(lo, n), math.pow(hi, n)
    if n % 2.0 == 1.0 or lo >= 0.0:
        return min(a, b), max(a, b)
    if hi <= 0.0:
        return min(a, b), max(a, b)
    return 0.0, max(a, b)


@EXACT
def box_bounds(fn, tape, work, xlo, xhi, ylo, yhi):
    """(lo, hi) enclosing f over [xlo, xhi] × [ylo, yhi] as the landscape ``fn`` computes it (the
    record's parameter values read from it), by its ``tape`` (n, TAPE_COLUMNS; n ≥ 1); work: (n, 2)
    scratch. NaN where nothing is known."""
    values = float_pointer(fn)
    n = tape.shape[0]
    for i in range(n):
        op, a, b = int(tape[i, 0]), int(tape[i, 1]), int(tape[i, 2])
        k = tape[i, 3]
        alo, ahi = work[a, 0], work[a, 1]
        lo, hi, e = math.nan, math.nan, 0.0
        if op == TAPE_CONST:
            lo, hi = tape[i, 4], tape[i, 5]
        elif op == TAPE_X:
            lo, hi = xlo, xhi
        elif op == TAPE_Y:
            lo, hi = ylo, yhi
        elif op == TAPE_PARAMETER:
            lo = hi = values[LANDSCAPE_RECORD_VALUES + int(k)]
        elif math.isnan(alo) or math.isnan(ahi):
            pass
        elif op == TAPE_ADD or op == TAPE_MUL or op == TAPE_MIN or op == TAPE_MAX or op == TAPE_POW:
            blo, bhi = work[b, 0], work[b, 1]
            if math.isnan(blo) or math.isnan(bhi):
                pass
            elif op == TAPE_ADD:
                lo, hi = alo + blo, ahi + bhi
                e = (k + 1.0) * EPS * (size(alo, ahi) + size(blo, bhi))
            elif op == TAPE_MUL:
                lo, hi = product(alo, ahi, blo, bhi)
                e = (k + LIBM) * EPS * size(lo, hi)
            elif op == TAPE_MIN:
                lo, hi = min(alo, blo), min(ahi, bhi)
            elif op == TAPE_MAX:
                lo, hi = max(alo, blo), max(ahi, bhi)
            elif alo > 0.0:   # TAPE_POW: a^b = exp(b log a), each step widened
                llo, lhi = math.log(alo), math.log(ahi)
                w = LIBM * EPS * size(llo, lhi) + TINY
                plo, phi = product(llo - w, lhi + w, blo, bhi)
                w = LIBM * EPS * size(plo, phi) + TINY
                lo, hi = math.exp(plo - w), math.exp(phi + w)
                e = 2.0 * LIBM * EPS * size(lo, hi)
        elif op == TAPE_POWER:
            if k >= 0.0:
                lo, hi = power(alo, ahi, k)
            elif alo > 0.0 or ahi < 0.0:   # (0 inside: unbounded)
                plo, phi = power(alo, ahi, -k)
                lo, hi = 1.0 / phi, 1.0 / plo
            e = (abs(k) + LIBM) * EPS * size(lo, hi)
        elif op == TAPE_REAL_POWER:
            c = tape[i, 4]
            if alo >= 0.0:
                p, q = math.pow(alo, c), math.pow(ahi, c)
                lo, hi = min(p, q), max(p, q)
                e = LIBM * EPS * size(lo, hi)
        else:   # a function of one argument
            if op == TAPE_EXP:
                lo, hi = math.exp(alo), math.exp(ahi)
            elif op == TAPE_LOG:
                if alo > 0.0:
                    lo, hi = math.log(alo), math.log(ahi)
            elif op == TAPE_SQRT:
                if alo >= 0.0:
                    lo, hi = math.sqrt(alo), math.sqrt(ahi)
            elif op == TAPE_TANH:
                lo, hi = math.tanh(alo), math.tanh(ahi)
            elif op == TAPE_ATAN:
                lo, hi = math.atan(alo), math.atan(ahi)
            elif op == TAPE_SINH:
                lo, hi = math.sinh(alo), math.sinh(ahi)
            elif op == TAPE_ASINH:
                lo, hi = math.asinh(alo), math.asinh(ahi)
            elif op == TAPE_COSH:
                far = size(alo, ahi)
                near = 0.0 if alo <= 0.0 <= ahi else min(abs(alo), abs(ahi))
                lo, hi = math.cosh(near), math.cosh(far)
            elif op == TAPE_ABS:
                far = size(alo, ahi)
                lo, hi = (0.0 if alo <= 0.0 <= ahi else min(abs(alo), abs(ahi))), far
            elif op == TAPE_ASIN:
                if -1.0 <= alo and ahi <= 1.0:
                    lo, hi = math.asin(alo), math.asin(ahi)
            elif op == TAPE_ACOS:
                if -1.0 <= alo and ahi <= 1.0:
                    lo, hi = math.acos(ahi), math.acos(alo)
            elif op == TAPE_ATANH:
                if -1.0 < alo and ahi < 1.0:
                    lo, hi = math.atanh(alo), math.atanh(ahi)
            elif op == TAPE_ACOSH:
                if alo >= 1.0:
                    lo, hi = math.acosh(alo), math.acosh(ahi)
            elif op == TAPE_SIN or op == TAPE_COS:
                lo, hi = -1.0, 1.0
                if ahi - alo < TWO_PI and size(alo, ahi) < PERIODIC_MOST:
                    if op == TAPE_SIN:
                        p, q, peak = math.sin(alo), math.sin(ahi), 0.5 * math.pi
                    else:
                        p, q, peak = math.cos(alo), math.cos(ahi), 0.0
                    w = LIBM * EPS + TINY
                    lo, hi = min(p, q) - w, max(p, q) + w
                    if passes(alo, ahi, peak) or hi > 1.0:
                        hi = 1.0
                    if passes(alo, ahi, peak + math.pi) or lo < -1.0:
                        lo = -1.0
            if op != TAPE_SIN and op != TAPE_COS and op != TAPE_ABS:
                e = LIBM * EPS * size(lo, hi)
        if math.isnan(lo) or math.isnan(hi):
            lo = hi = math.nan
        else:
            lo, hi = lo - (e + TINY), hi + (e + TINY)
        work[i, 0], work[i, 1] = lo, hi
    return work[n - 1, 0], work[n - 1, 1]


@EXACT
def bound_boxes(fn, tape, boxes, out, work):
    """``box_bounds`` of each box (m, 4: x_lo, x_hi, y_lo, y_hi) into out (m, 2); NaN where the
    tape is empty."""
    for i in range(boxes.shape[0]):
        if tape.shape[0] == 0:
            out[i, 0] = out[i, 1] = math.nan
        else:
            out[i, 0], out[i, 1] = box_bounds(fn, tape, work, boxes[i, 0], boxes[i, 1], boxes[i, 2], boxes[i, 3])
