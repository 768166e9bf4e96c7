"""A landscape's tape: f's operations in order, as data (kernel/interface.py's TAPE_*), from
which the kernel bounds f over a box by interval arithmetic (``kernel.bounds.box_bounds``;
the track under a flight's path certifies stretches of it with those bounds, docs/design.md §1).

A sum or a product of n terms becomes a chain of n − 1 rows that each carry n (the widening of
its round-off covers every order the landscape's code may take them in); a constant is an
interval that holds both its exact value and the double the landscape's code computes for it.
A formula with an operation the bounds do not know (tan, atan2) has no tape: its track takes
every sample."""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from .formula import X, Y, RealAbs
from .kernel import interface as kernel

EPS = 2.220446049250313e-16   # (the double's machine epsilon)

# sympy's functions of one argument, by the operation that bounds them
FUNCTIONS = {sp.exp: kernel.TAPE_EXP, sp.log: kernel.TAPE_LOG, sp.sin: kernel.TAPE_SIN, sp.cos: kernel.TAPE_COS,
             sp.tanh: kernel.TAPE_TANH, sp.atan: kernel.TAPE_ATAN, sp.sinh: kernel.TAPE_SINH,
             sp.asinh: kernel.TAPE_ASINH, sp.cosh: kernel.TAPE_COSH, sp.asin: kernel.TAPE_ASIN,
             sp.acos: kernel.TAPE_ACOS, sp.atanh: kernel.TAPE_ATANH, sp.acosh: kernel.TAPE_ACOSH,
             RealAbs: kernel.TAPE_ABS, sp.Abs: kernel.TAPE_ABS}
# sympy's functions of two or more arguments, taken two at a time
CHAINS = {sp.Add: kernel.TAPE_ADD, sp.Mul: kernel.TAPE_MUL, sp.Min: kernel.TAPE_MIN, sp.Max: kernel.TAPE_MAX}
WHOLE_POWER_MOST = 1 << 20   # |n| of x^n taken as a whole power (beyond: a real one)


class _Unknown(Exception):
    """An operation the bounds do not know."""


def tape(expr: sp.Expr, parameters: int = 0) -> np.ndarray:
    """The tape of ``expr`` (in ``formula.X``, ``formula.Y`` and the parameter symbols p_0 …
    p_{parameters-1}): (n, TAPE_COLUMNS), its last row f; (0, TAPE_COLUMNS) where an operation
    is not known."""
    rows: list[list[float]] = []
    done: dict = {}
    names = {f"p_{k}": k for k in range(parameters)}

    def row(op, a=0, b=0, k=0.0, lo=0.0, hi=0.0) -> int:
        rows.append([float(op), float(a), float(b), float(k), lo, hi])
        return len(rows) - 1

    def constant(value: float) -> int:
        if not math.isfinite(value):
            raise _Unknown
        slack = 2.0 * EPS * abs(value) + 1e-300   # (its double, and the code's division p/q)
        return row(kernel.TAPE_CONST, lo=value - slack, hi=value + slack)

    def visit(e) -> int:
        if e in done:
            return done[e]
        if e == X:
            out = row(kernel.TAPE_X)
        elif e == Y:
            out = row(kernel.TAPE_Y)
        elif e.is_Symbol:
            if e.name not in names:
                raise _Unknown
            out = row(kernel.TAPE_PARAMETER, k=names[e.name])
        elif e.is_Number or e.is_NumberSymbol:
            out = constant(float(e))
        elif type(e) in CHAINS:
            op, args = CHAINS[type(e)], e.args
            out = visit(args[0])
            for arg in args[1:]:
                out = row(op, out, visit(arg), len(args))
        elif e.is_Pow:
            base, exponent = e.args
            if exponent.is_Integer and abs(int(exponent)) <= WHOLE_POWER_MOST:
                out = row(kernel.TAPE_POWER, visit(base), k=int(exponent))
            elif exponent.is_Number:
                value = float(exponent)
                if not math.isfinite(value):
                    raise _Unknown
                out = row(kernel.TAPE_REAL_POWER, visit(base), lo=value, hi=value)
            else:
                out = row(kernel.TAPE_POW, visit(base), visit(exponent))
        elif type(e) in FUNCTIONS and len(e.args) == 1:
            out = row(FUNCTIONS[type(e)], visit(e.args[0]))
        else:
            raise _Unknown
        done[e] = out
        return out

    try:
        visit(expr)
    except (_Unknown, RecursionError, TypeError, ValueError, OverflowError):
        return np.empty((0, kernel.TAPE_COLUMNS))
    return np.array(rows, dtype=float).reshape(-1, kernel.TAPE_COLUMNS)
