"""A landscape z = f(x, y): its formula, derivatives, and their compiled form.

sympy's rules derive f_x, f_y, f_xx, f_xy, f_yy once (``derivative``); common subexpressions are shared and
printed as a small scalar function, compiled as a C callback (landscape_code.py) that the
one stepping kernel calls. A new formula therefore costs a small compile, not a recompile of
the integrator; a formula seen in an earlier run loads its machine code from the cache folder;
and the code of a formula no longer used is freed. ``evaluate`` gives the same six quantities
as numpy arrays for grids (drawing) and for the reference solver, from the same compiled code.
"""

from __future__ import annotations

import hashlib
import math
import re
import sys
import threading
import warnings
import weakref
from functools import cached_property, lru_cache

import numpy as np
import sympy as sp
from sympy.core import cache as sympy_cache
from sympy.core.function import ArgumentIndexError, Function
from sympy.functions.elementary.miscellaneous import MinMaxBase
from sympy.printing.precedence import PRECEDENCE
from sympy.printing.pycode import PythonCodePrinter

from . import landscape_code, landscape_tape
from .cache import cache_dir
from .formula import (X, Y, FormulaError, check_constants, check_parameter_names, code_constant, parameter_symbol,
                      parse_formula)
from .kernel.interface import landscape_record
from .landscape_code import LandscapeCode
from .machine_code import Arguments, call
from .text import shown

# The work budget of a formula: its derivatives may hold about this many nodes (operations,
# functions, numbers, variables), as estimated before each round of differentiation and as
# counted after. Differentiating, simplifying and compiling that much takes a few seconds; a
# product of 17 factors sin(k*x + y) (180 characters) is about this large.
MAX_DERIVATIVE_NODES = 100_000

# An evaluation of this many points or fewer reuses its packed call (``Landscape.evaluate``); the
# packed calls a landscape keeps, per thread (``Landscape.packed``)
PACKED_POINTS, PACKED_CALLS = 64, 32

# sympy's cached results kept at most (about 300 bytes each): see _bound_sympy_cache
SYMPY_CACHE_ENTRIES = 20_000

# Machine code by generated source, while anyone holds it: the same formula is compiled once
# while it is in use, and its code freed when no landscape (and no run) holds it any more.
_COMPILED: weakref.WeakValueDictionary[str, LandscapeCode] = weakref.WeakValueDictionary()
_COMPILE_LOCK = threading.RLock()


class _Printer(PythonCodePrinter):
    def _print_Pow(self, expr, rational=False):
        # numba raises ZeroDivisionError for 0.0 ** -n with an integer n; 1/0.0 is inf
        if expr.exp.is_Integer and expr.exp < -1:
            base = self.parenthesize(expr.base, PRECEDENCE["Pow"])
            return f"(1.0/{base}**{-expr.exp})"
        return super()._print_Pow(expr, rational=rational)

    def _print_Rational(self, expr):  # also Integer: too large for numba's integers -> a float
        return code_constant(expr) or super()._print_Rational(expr)

    def _print_Integer(self, expr):
        return code_constant(expr) or super()._print_Integer(expr)

    def _print_RealAbs(self, expr):
        return f"abs({self._print(expr.args[0])})"

    def _print_RealSign(self, expr):
        u = self._print(expr.args[0])
        return f"(0.0 if ({u}) == 0 else math.copysign(1.0, {u}))"


_PRINTER = _Printer({"standard": "python3", "strict": True})
_GENERATED_NAMES = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")
_SAFE_NAMES = {"def", "landscape", "x", "y", "p", "out", "math", "abs", "min", "max",
               "if", "else", "and", "or", "not"} | {n for n in dir(math) if not n.startswith("_")}


def _without_delta(expr: sp.Expr) -> sp.Expr:
    # The second derivative of a kink (abs, min, max) is a Dirac delta: zero away from the
    # kink, which is where a double can be evaluated.
    return expr.replace(lambda a: isinstance(a, sp.DiracDelta), lambda a: sp.S.Zero)


def _sizes(exprs, var=None) -> tuple[int, int]:
    """(nodes of the expression trees, estimated nodes of their derivatives by ``var``), without
    building the derivatives: the product rule copies a product once per factor that depends on
    ``var``, the chain rule a function call (or power) once or twice per argument. Generous,
    so the shapes that explode (long products, nested calls) are caught before sympy works."""
    size, dsize, depends = {}, {}, {}
    for expr in exprs:
        for node in sp.postorder_traversal(expr):  # children before their parent
            if node in size:
                continue
            args = node.args
            size[node] = 1 + sum(size[a] for a in args)
            depends[node] = node == var or any(depends[a] for a in args)
            if not depends[node] or not args:
                dsize[node] = int(depends[node])
            elif isinstance(node, sp.Add):
                dsize[node] = 1 + sum(dsize[a] for a in args)
            elif isinstance(node, sp.Mul):
                dsize[node] = 1 + sum(size[node] - size[a] + dsize[a] for a in args if depends[a])
            else:  # powers and functions: f'(args) (about the call's size per argument) times args'
                copies = 2 * len(args)
                dsize[node] = 1 + sum(copies * size[node] + dsize[a] for a in args if depends[a])
    return sum(size[e] for e in exprs), sum(dsize[e] for e in exprs)


_PLAIN_CHAIN_RULE = {Function._eval_derivative, MinMaxBase._eval_derivative}


def derivative(expr: sp.Expr, var: sp.Symbol, done: dict) -> sp.Expr:
    """``sp.diff(expr, var)``, rule for rule and node for node the same expression, about three
    times faster: sympy asks after every node whether its derivative is zero (``is_zero``, an
    assumption query that is two thirds of its time) and then uses it all the same. ``done``
    keeps the derivatives by ``var`` already made, so a subexpression shared by f and f_x (or
    by several terms) is differentiated once. Constructs without a rule here go to sympy."""
    result = done.get(expr)
    if result is not None:
        return result
    if var not in expr.free_symbols:
        result = sp.S.Zero
    elif expr == var:
        result = sp.S.One
    elif isinstance(expr, sp.Add):
        result = sp.Add(*[derivative(a, var, done) for a in expr.args])
    elif isinstance(expr, sp.Mul):   # sympy's Leibniz rule for n = 1
        args = expr.args
        result = sp.Add(*[sp.Mul(*[derivative(a, var, done) if j == i else a for j, a in enumerate(args)])
                          for i in range(len(args))])
    elif isinstance(expr, sp.Pow):
        base, exp = expr.args
        dbase, dexp = derivative(base, var, done), derivative(exp, var, done)
        result = expr * (dexp * sp.log(base) + dbase * exp / base)
    elif isinstance(expr, Function) and type(expr)._eval_derivative in _PLAIN_CHAIN_RULE:
        terms = []
        for i, a in enumerate(expr.args, 1):
            da = derivative(a, var, done)
            if da.is_zero:
                continue
            try:
                df = expr.fdiff(i)
            except ArgumentIndexError:
                df = Function.fdiff(expr, i)
            terms.append(df * da)
        result = sp.Add(*terms)
    else:
        result = sp.diff(expr, var)
    done[expr] = result
    return result


class Landscape:
    """A parsed, differentiated landscape formula, with the names of its parameters (scene
    version 3: their values are arguments of the compiled code, so new values compile nothing).
    Raises ``FormulaError`` for bad text or names, or for a formula whose derivatives would
    exceed ``MAX_DERIVATIVE_NODES`` (checked before each round of differentiation, so a refusal
    comes within a second or two)."""

    def __init__(self, text: str, parameters: tuple[str, ...] = ()):
        self.text = text
        self.parameters = check_parameter_names(parameters)
        self.expr = parse_formula(text, self.parameters)
        f = self.expr
        try:
            # sympy builds first derivatives slowest, node by node: a tenth of the budget
            self._within_budget(_sizes([f], X)[1] + _sizes([f], Y)[1], MAX_DERIVATIVE_NODES // 10)
            by_x, by_y = {}, {}   # each subexpression differentiated once by x and once by y
            fx, fy = derivative(f, X, by_x), derivative(f, Y, by_y)
            self._within_budget(_sizes([fx], X)[1] + _sizes([fx, fy], Y)[1])
            exprs = (f, fx, fy, derivative(fx, X, by_x), derivative(fx, Y, by_y), derivative(fy, Y, by_y))
            self.derivatives = tuple(_without_delta(e) for e in exprs)
            self._within_budget(_sizes(self.derivatives[3:])[0])
        except FormulaError:
            raise
        except (ValueError, TypeError, ArithmeticError) as e:
            raise FormulaError(f"cannot differentiate the formula ({e})") from None
        for e in self.derivatives:
            check_constants(e)
        self.source = self._generate_source()
        self._compiled: LandscapeCode | None = None
        self._packed = threading.local()   # .calls: (values, key) -> a packed call, its record (``packed``)
        _bound_sympy_cache()

    def __repr__(self) -> str:
        return f"Landscape({self.text!r}{f', {self.parameters!r}' if self.parameters else ''})"

    @staticmethod
    def _within_budget(nodes: int, budget: int = MAX_DERIVATIVE_NODES) -> None:
        if nodes > budget:
            raise FormulaError(f"formula too complex to differentiate (its derivatives would have about "
                               f"{nodes:,} operations, at most {budget:,})")

    def _generate_source(self) -> str:
        """Python source of ``landscape(x, y, p, out)`` filling out[0:6] with f and its
        derivatives, the parameters' values read from p[0], p[1], ... (kernel/interface.py)."""
        replacements, reduced = sp.cse(list(self.derivatives), symbols=sp.numbered_symbols("t"))
        # plain pointer stores (no carray, no slices, no conversions): numba types and
        # compiles this in about half the time; NaN first, in case an evaluation raises
        lines = (["def landscape(x, y, p, out):"] + [f"    out[{i}] = math.nan" for i in range(6)]
                 + [f"    {parameter_symbol(k)} = p[{k}]" for k in range(len(self.parameters))])
        try:
            for sym, value in replacements:
                lines.append(f"    {sym} = {_PRINTER.doprint(value)}")
            for i, value in enumerate(reduced):
                lines.append(f"    out[{i}] = {_PRINTER.doprint(value)}")
        except (ValueError, TypeError, NotImplementedError) as e:
            raise FormulaError(f"cannot compile the formula ({e})") from None
        source = "\n".join(lines) + "\n"
        unknown = {n for n in _GENERATED_NAMES.findall(source)
                   if n not in _SAFE_NAMES and not re.fullmatch(r"t\d+|e\d*|p_\d+", n)}
        if unknown:  # a construct the printer spelled in a way we did not vouch for
            raise FormulaError(f"cannot compile the formula (uses {', '.join(sorted(unknown))})")
        return source

    @property
    def compiled(self) -> LandscapeCode:
        """The machine code computing f, f_x, f_y, f_xx, f_xy, f_yy at (x, y) (``address``,
        ``ctypes``): made once and kept while this landscape (or anyone else) holds it."""
        code = self._compiled
        if code is None:
            with _COMPILE_LOCK:
                code = _COMPILED.get(self.source)
                if code is None:
                    code = _compile_or_refuse(self.source)
                code = self._compiled = _COMPILED[self.source] = code
        return code

    @cached_property
    def tape(self) -> np.ndarray:
        """f's operations as the kernel bounds f over a box by them (landscape_tape.py; no rows
        where an operation is not known)."""
        return landscape_tape.tape(self.derivatives[0], len(self.parameters))

    def bounds(self, boxes, values=()) -> np.ndarray:
        """Bounds of f over each box (m, 4: x_lo, x_hi, y_lo, y_hi), as (m, 2): the interval the
        kernel computes from ``tape`` (``kernel.bounds``), which holds every value the compiled code
        gives in the box; NaN where nothing is known (no tape, a box partly outside f's domain)."""
        boxes = np.ascontiguousarray(boxes, dtype=float).reshape(-1, 4)
        out, record = np.empty((len(boxes), 2)), self.record(values)   # (the record held while the kernel reads it)
        call("bound_boxes", fn=record.ctypes.data, tape=self.tape, boxes=boxes, out=out,
             work=np.empty((max(len(self.tape), 1), 2)))
        return out

    def record(self, values=()) -> np.ndarray:
        """What the kernel takes as the landscape (``fn`` is its address): the compiled code's
        address and the parameters' ``values`` (kernel/interface.py). The caller keeps this
        landscape (its code) and the record alive while the kernel runs."""
        values = np.asarray(values, dtype=float).ravel()
        if values.size != len(self.parameters):
            raise ValueError(f"{self!r} takes {len(self.parameters)} parameter values, not {values.size}")
        return landscape_record(self.compiled.address, values)

    def packed(self, values, key, make):
        """A kernel call on this landscape with the parameters' ``values``, packed once (``make(fn)``,
        fn the address of the landscape's record, made here and kept with it) and kept for this
        thread under ``key`` (the entry point and the sizes of its arrays), so that the runs of
        a sweep, or the flights of one, do not pack it anew: the caller writes its inputs into
        the call's arrays, runs it and copies its outputs before the thread calls again. Each
        thread keeps its own calls (at most PACKED_CALLS, then all are dropped): the record a
        call reads lives until its own thread drops it, never while another thread runs it."""
        values = np.asarray(values, dtype=float).ravel()
        calls = getattr(self._packed, "calls", None)
        if calls is None:
            calls = self._packed.calls = {}
        full = (tuple(values.tolist()), key)
        entry = calls.get(full)
        if entry is None:
            if len(calls) >= PACKED_CALLS:
                calls.clear()
            record = self.record(values)
            entry = calls[full] = (make(record.ctypes.data), record)   # (the record kept while its address is)
        return entry[0]

    def evaluate(self, x, y, values=()) -> np.ndarray:
        """f, f_x, f_y, f_xx, f_xy, f_yy at (x, y) (with the parameters' ``values``): an array of
        shape (6,) + broadcast shape.

        The compiled code the integrator uses; points outside the formula's domain give NaN.
        An evaluation of at most PACKED_POINTS points reuses its call's packed arguments
        (``packed``): packing costs ten times the evaluation of a point.
        """
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if x.shape != y.shape:   # (broadcast_arrays costs more than a few points' evaluation)
            x, y = np.broadcast_arrays(x, y)
        n = x.size
        if n > PACKED_POINTS:
            out = np.empty((6, n))
            record = self.record(values)
            call("evaluate_points", fn=record.ctypes.data, xs=np.ascontiguousarray(x).ravel(),
                 ys=np.ascontiguousarray(y).ravel(), out=out, d=np.empty(6))
            return out.reshape((6,) + x.shape)

        def make(fn):
            xs, ys, out = np.empty(n), np.empty(n), np.empty((6, n))
            return Arguments("evaluate_points", fn=fn, xs=xs, ys=ys, out=out, d=np.empty(6)), xs, ys, out

        packed = self.packed(values, ("evaluate_points", n), make)
        arguments, xs, ys, out = packed
        xs[:], ys[:] = x.ravel(), y.ravel()
        arguments()
        return out.reshape((6,) + x.shape).copy()

    def height(self, x, y, values=()) -> np.ndarray:
        return self.evaluate(x, y, values)[0]


def _bound_sympy_cache() -> None:
    """sympy keeps what it derives in caches of its own, each bounded but not all of them
    together: about 80 entries (25 kB) a new formula, for good. Past ``SYMPY_CACHE_ENTRIES``
    they start again empty, so a long session of new formulas stays within a few MB."""
    functions = getattr(sympy_cache, "CACHE", [])
    if sum(f.cache_info().currsize for f in functions if hasattr(f, "cache_info")) > SYMPY_CACHE_ENTRIES:
        sympy_cache.clear_cache()


class CacheWarning(UserWarning):
    """The cache folder cannot be written; formulas are compiled without keeping their code."""


_CACHE_BROKEN = False  # the cache failed once: this process compiles without it (and said so)


def _compile(source: str) -> LandscapeCode:
    """The machine code of generated source (landscape_code.py), kept in the cache folder
    under a name made from its hash and the machine, so a formula seen in an earlier run loads
    in milliseconds. The cache is only an optimisation: where it cannot be written (full disk,
    no permission) the formula is compiled in memory, and a ``CacheWarning`` says so once."""
    global _CACHE_BROKEN
    text = "import math\n\n\n" + source
    name = "rollball_landscape_" + hashlib.sha256(text.encode()).hexdigest()[:24]
    code = landscape_code.load(text, name, cached=not _CACHE_BROKEN)
    if code.unwritten and not _CACHE_BROKEN:
        _CACHE_BROKEN = True
        warnings.warn(f"the cache folder {shown(str(cache_dir()))} cannot be used ({code.unwritten}); "
                      f"formulas are compiled without it from now on", CacheWarning, stacklevel=3)
    return code


def _compile_or_refuse(source: str) -> LandscapeCode:
    """``_compile``, with a construct numba refuses (where it lowers what the translation does
    not know) as one line, not its coloured traceback."""
    try:
        return _compile(source)
    except Exception as e:
        errors = sys.modules.get("numba.core.errors")   # (numba is imported only when it compiles)
        if errors is None or not isinstance(e, errors.NumbaError):
            raise
        text = re.sub(r"\x1b\[[0-9;]*m", "", str(e))  # numba colours its messages
        first = next((line.strip() for line in text.splitlines() if line.strip()), "")
        raise FormulaError(f"cannot compile the formula ({first})") from None


def landscape_of(scene) -> Landscape:
    """The (shared, cached) landscape of a scene: its formula with its parameters' names."""
    return landscape_for(scene.landscape, scene.parameter_names)


def landscape_for(text: str, parameters: tuple[str, ...] = ()) -> Landscape:
    """The (shared, cached) landscape of a formula with the parameters of these names."""
    return _landscape_for(text, tuple(parameters))


@lru_cache(maxsize=64)
def _landscape_for(text: str, parameters: tuple[str, ...]) -> Landscape:
    return Landscape(text, parameters)


landscape_for.cache_clear = _landscape_for.cache_clear   # (as before, for tests and the app)
landscape_for.cache_info = _landscape_for.cache_info
