"""A landscape z = f(x, y): its formula, derivatives, and their compiled form.

sympy derives f_x, f_y, f_xx, f_xy, f_yy once; common subexpressions are shared and
printed as a small scalar function, compiled by numba as a C callback (``cfunc``) that the
one cached stepping kernel calls. A new formula therefore costs a small compile, not a
recompile of the integrator. ``evaluate`` gives the same six quantities as numpy arrays
for grids (drawing) and for the reference solver, from the same compiled code.
"""

from __future__ import annotations

import math
import re
from functools import lru_cache

import numpy as np
import sympy as sp
from sympy.printing.precedence import PRECEDENCE
from sympy.printing.pycode import PythonCodePrinter

from .formula import X, Y, FormulaError, check_constants, parse_formula

# Compiled callbacks by generated source: the same formula is compiled once per process.
_COMPILED: dict[str, object] = {}


class _Printer(PythonCodePrinter):
    def _print_Pow(self, expr, rational=False):
        # numba raises ZeroDivisionError for 0.0 ** -n with an integer n; 1/0.0 is inf
        if expr.exp.is_Integer and expr.exp < -1:
            base = self.parenthesize(expr.base, PRECEDENCE["Pow"])
            return f"(1.0/{base}**{-expr.exp})"
        return super()._print_Pow(expr, rational=rational)

    def _print_RealAbs(self, expr):
        return f"abs({self._print(expr.args[0])})"

    def _print_RealSign(self, expr):
        u = self._print(expr.args[0])
        return f"(0.0 if ({u}) == 0 else math.copysign(1.0, {u}))"


_PRINTER = _Printer({"standard": "python3", "strict": True})
_GENERATED_NAMES = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")
_SAFE_NAMES = {"def", "landscape", "x", "y", "out", "d", "carray", "math", "abs", "min", "max",
               "if", "else", "float"} | {n for n in dir(math) if not n.startswith("_")}


def _without_delta(expr: sp.Expr) -> sp.Expr:
    # The second derivative of a kink (abs, min, max) is a Dirac delta: zero away from the
    # kink, which is where a double can be evaluated.
    return expr.replace(lambda a: isinstance(a, sp.DiracDelta), lambda a: sp.S.Zero)


class Landscape:
    """A parsed, differentiated landscape formula. Raises ``FormulaError`` for bad text."""

    def __init__(self, text: str):
        self.text = text
        self.expr = parse_formula(text)
        f = self.expr
        try:
            fx, fy = sp.diff(f, X), sp.diff(f, Y)
            exprs = (f, fx, fy, sp.diff(fx, X), sp.diff(fx, Y), sp.diff(fy, Y))
            self.derivatives = tuple(_without_delta(e) for e in exprs)
        except (ValueError, TypeError, ArithmeticError) as e:
            raise FormulaError(f"cannot differentiate the formula ({e})") from None
        for e in self.derivatives:
            check_constants(e)
        self.source = self._generate_source()

    def __repr__(self) -> str:
        return f"Landscape({self.text!r})"

    def _generate_source(self) -> str:
        """Python source of ``landscape(x, y, out)`` filling out[0:6] with f and its derivatives."""
        replacements, reduced = sp.cse(list(self.derivatives), symbols=sp.numbered_symbols("t"))
        lines = ["def landscape(x, y, out):", "    d = carray(out, (6,))", "    d[:] = math.nan"]
        try:
            for sym, value in replacements:
                lines.append(f"    {sym} = {_PRINTER.doprint(value)}")
            for i, value in enumerate(reduced):
                lines.append(f"    d[{i}] = float({_PRINTER.doprint(value)})")
        except (ValueError, TypeError, NotImplementedError) as e:
            raise FormulaError(f"cannot compile the formula ({e})") from None
        source = "\n".join(lines) + "\n"
        unknown = {n for n in _GENERATED_NAMES.findall(source)
                   if n not in _SAFE_NAMES and not re.fullmatch(r"t\d+|e\d*", n)}
        if unknown:  # a construct the printer spelled in a way we did not vouch for
            raise FormulaError(f"cannot compile the formula (uses {', '.join(sorted(unknown))})")
        return source

    @property
    def compiled(self):
        """The numba ``cfunc`` computing f, f_x, f_y, f_xx, f_xy, f_yy at (x, y)."""
        source = self.source
        if source not in _COMPILED:
            from numba import carray, cfunc

            from .kernel import LANDSCAPE_SIGNATURE

            namespace = {"math": math, "carray": carray}
            exec(compile(source, "<landscape>", "exec"), namespace)  # our generated code, not user text
            _COMPILED[source] = cfunc(LANDSCAPE_SIGNATURE, error_model="numpy")(namespace["landscape"])
        return _COMPILED[source]

    def evaluate(self, x, y) -> np.ndarray:
        """f, f_x, f_y, f_xx, f_xy, f_yy at (x, y): an array of shape (6,) + broadcast shape.

        The compiled code the integrator uses; points outside the formula's domain give NaN.
        """
        from .kernel import evaluate_points

        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        out = np.empty((6, x.size))
        evaluate_points(self.compiled, np.ascontiguousarray(x).ravel(), np.ascontiguousarray(y).ravel(), out)
        return out.reshape((6,) + x.shape)

    def height(self, x, y) -> np.ndarray:
        return self.evaluate(x, y)[0]


@lru_cache(maxsize=64)
def landscape_for(text: str) -> Landscape:
    """The (shared, cached) landscape of a formula."""
    return Landscape(text)
