"""Landscape formulas: untrusted text in, a sympy expression in x and y out.

The text is screened character by character, tokenized and parsed here by a small
recursive-descent parser that builds sympy objects directly from a whitelist. No user
text ever reaches ``eval``, ``sympify`` or ``parse_expr``.

Grammar (MATLAB spellings ``^ .^ .* ./`` are accepted beside Python's)::

    expr  := term (("+" | "-") term)*
    term  := unary (("*" | "/") unary)*
    unary := ("+" | "-") unary | power
    power := atom (("^" | "**") unary)?          # right associative, -x^2 = -(x^2)
    atom  := number | name | name "(" expr ("," expr)* ")" | "(" expr ")"
"""

from __future__ import annotations

import math
import re
from fractions import Fraction
from dataclasses import dataclass

import sympy as sp

X, Y = sp.symbols("x y", real=True)

MAX_LENGTH = 1000
MAX_DEPTH = 40
MAX_ARGUMENTS = 16  # of min and max
LARGEST_CONSTANT = 1e300

CONSTANTS = {"x": X, "y": Y, "pi": sp.pi, "e": sp.E}

# Named parameters (scene version 3): identifiers, at most MAX_PARAMETERS of them; in the
# expression the k-th is the symbol ``parameter_symbol(k)``, whatever its name, so a name never
# reaches generated code.
MAX_PARAMETERS = 32
MAX_PARAMETER_NAME = 32
_PARAMETER_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def parameter_symbol(index: int) -> sp.Symbol:
    return sp.Symbol(f"p_{index}", real=True)


def parameter_problem(name) -> str | None:
    """Why ``name`` cannot name a parameter, or None when it can."""
    if not isinstance(name, str) or not _PARAMETER_NAME.fullmatch(name):
        return "a parameter's name must be an identifier (a letter, then letters, digits or _)"
    if len(name) > MAX_PARAMETER_NAME:
        return f"a parameter's name has at most {MAX_PARAMETER_NAME} characters"
    if name in CONSTANTS:
        return f"{name!r} is taken by the formula's own {'variables' if name in 'xy' else 'constants'}"
    if name in FUNCTIONS:
        return f"{name!r} is the name of a function"
    return None


def check_parameter_names(names) -> tuple[str, ...]:
    """The names, checked (``FormulaError`` for the first bad one, or too many)."""
    names = tuple(names)
    if len(names) > MAX_PARAMETERS:
        raise FormulaError(f"at most {MAX_PARAMETERS} parameters (got {len(names)})")
    for name in names:
        problem = parameter_problem(name)
        if problem:
            raise FormulaError(problem)
    if len(set(names)) != len(names):
        raise FormulaError("a parameter's name appears twice")
    return names


class _RealFunction(sp.Function):
    """A function of one real argument; on a constant it is sympy's own ``constant``."""

    nargs = 1
    constant = None

    @classmethod
    def eval(cls, arg):
        if arg.is_number:
            return cls.constant(arg)


class RealSign(_RealFunction):
    """sign(u) of a real u; its derivative is zero away from the jump."""

    constant = sp.sign

    def fdiff(self, argindex=1):
        return sp.S.Zero


class RealAbs(_RealFunction):
    """|u| of a real u, differentiated as sign(u) u' (sympy's Abs assumes complex u)."""

    constant = sp.Abs

    def fdiff(self, argindex=1):
        return RealSign(self.args[0])


# name: (sympy callable, number of arguments; None for two or more)
FUNCTIONS = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1),
    "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1), "atan2": (sp.atan2, 2),
    "sinh": (sp.sinh, 1), "cosh": (sp.cosh, 1), "tanh": (sp.tanh, 1),
    "asinh": (sp.asinh, 1), "acosh": (sp.acosh, 1), "atanh": (sp.atanh, 1),
    "exp": (sp.exp, 1), "log": (sp.log, 1), "log10": (lambda a: sp.log(a, 10), 1),
    "sqrt": (sp.sqrt, 1), "abs": (RealAbs, 1), "hypot": (lambda a, b: sp.sqrt(a**2 + b**2), 2),
    "min": (sp.Min, None), "max": (sp.Max, None),
}

_ALLOWED_CHARS = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_+-*/^.,() \t")

_TOKEN = re.compile(
    r"(?P<space>[ \t]+)"
    r"|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)"
    r"|(?P<op>\*\*|\.\^|\.\*|\./|[-+*/^(),])"
)
_OPERATOR_SPELLING = {".^": "^", "**": "^", ".*": "*", "./": "/"}


class FormulaError(ValueError):
    """A formula that cannot be accepted; ``position`` is 1-based (0: the whole text)."""

    def __init__(self, reason: str, position: int = 0):
        self.reason = reason
        self.position = position
        super().__init__(f"{reason} at {position}" if position else reason)


@dataclass(frozen=True)
class _Token:
    kind: str  # "number", "name", "op", "end"
    text: str
    position: int  # 1-based column


def _tokenize(text: str) -> list[_Token]:
    for i, ch in enumerate(text):
        if ch not in _ALLOWED_CHARS:
            shown = ch if ch.isprintable() else f"U+{ord(ch):04X}"
            raise FormulaError(f"unexpected character {shown!r}", i + 1)
    tokens, i = [], 0
    while i < len(text):
        m = _TOKEN.match(text, i)
        if m is None:
            raise FormulaError(f"unexpected character {text[i]!r}", i + 1)
        kind = m.lastgroup
        if kind != "space":
            tok = m.group()
            tokens.append(_Token(kind, _OPERATOR_SPELLING.get(tok, tok), i + 1))
        i = m.end()
    tokens.append(_Token("end", "", len(text) + 1))
    return tokens


def _number(text: str, position: int) -> sp.Expr:
    value = float(text)
    if not math.isfinite(value) or abs(value) > LARGEST_CONSTANT:
        raise FormulaError(f"number {text} is too large", position)
    digits = text.lower().split("e")[0].replace(".", "").strip("0")
    if len(digits) <= 15 and (value == 0 or 1e-15 <= abs(value) <= 1e15):
        return sp.Rational(text)
    return sp.Float(value)


def _power(base: sp.Expr, exponent: sp.Expr, position: int) -> sp.Expr:
    # Constant ** constant is folded by sympy exactly; refuse what would not fit a float
    # before sympy spends unbounded time on it (9^9^9^9).
    if base.is_number and exponent.is_number:
        try:
            b, p = abs(complex(base)), complex(exponent).real
        except (TypeError, ValueError, OverflowError):
            b, p = math.inf, 1.0
        if b not in (0.0, 1.0) and (not math.isfinite(b) or abs(p * math.log10(b)) > 300):
            raise FormulaError("constant power is too large", position)
    return sp.Pow(base, exponent)


class _Parser:
    def __init__(self, tokens: list[_Token], parameters: dict[str, sp.Symbol] | None = None):
        self.parameters = parameters or {}
        self.tokens = tokens
        self.i = 0
        self.depth = 0

    @property
    def tok(self) -> _Token:
        return self.tokens[self.i]

    def take(self) -> _Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def expect(self, text: str, opened: _Token) -> None:
        if self.tok.text != text:
            if self.tok.kind == "end":
                raise FormulaError("unbalanced parenthesis", opened.position)
            raise FormulaError(f"expected {text!r} but found {self.tok.text!r}", self.tok.position)
        self.take()

    def nest(self, position: int) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise FormulaError(f"formula is nested too deeply (more than {MAX_DEPTH} levels)", position)

    def parse(self) -> sp.Expr:
        if self.tok.kind == "end":
            raise FormulaError("formula is empty")
        expr = self.expr()
        if self.tok.kind != "end":
            tok = self.tok
            if tok.text == ")":
                raise FormulaError("unbalanced parenthesis", tok.position)
            raise FormulaError(f"missing operator before {tok.text!r}", tok.position)
        return expr

    def expr(self) -> sp.Expr:
        terms = [self.term()]
        while self.tok.text in ("+", "-"):
            sign = self.take().text
            term = self.term()
            terms.append(term if sign == "+" else -term)
        return sp.Add(*terms)

    def term(self) -> sp.Expr:
        result = self.unary()
        while self.tok.text in ("*", "/"):
            op = self.take()
            operand = self.unary()
            if op.text == "*":
                result = result * operand
            else:
                if operand == 0:
                    raise FormulaError("division by zero", op.position)
                result = result / operand
        return result

    def unary(self) -> sp.Expr:
        if self.tok.text in ("+", "-"):
            op = self.take()
            self.nest(op.position)
            operand = self.unary()
            self.depth -= 1
            return -operand if op.text == "-" else operand
        return self.power()

    def power(self) -> sp.Expr:
        base = self.atom()
        if self.tok.text == "^":
            op = self.take()
            self.nest(op.position)
            exponent = self.unary()
            self.depth -= 1
            return _power(base, exponent, op.position)
        return base

    def atom(self) -> sp.Expr:
        tok = self.take()
        if tok.kind == "number":
            return _number(tok.text, tok.position)
        if tok.kind == "name":
            return self.name(tok)
        if tok.text == "(":
            self.nest(tok.position)
            inner = self.expr()
            self.expect(")", tok)
            self.depth -= 1
            return inner
        if tok.kind == "end":
            raise FormulaError("formula ends too early", tok.position)
        raise FormulaError(f"unexpected {tok.text!r}", tok.position)

    def name(self, tok: _Token) -> sp.Expr:
        if tok.text in CONSTANTS or tok.text in self.parameters:
            if self.tok.text == "(":
                raise FormulaError(f"{tok.text!r} is not a function", tok.position)
            return CONSTANTS[tok.text] if tok.text in CONSTANTS else self.parameters[tok.text]
        if tok.text not in FUNCTIONS:
            raise FormulaError(f"unknown name {tok.text!r}", tok.position)
        func, arity = FUNCTIONS[tok.text]
        if self.tok.text != "(":
            raise FormulaError(f"function {tok.text!r} needs its arguments in parentheses", tok.position)
        opened = self.take()
        self.nest(opened.position)
        args = [self.expr()]
        while self.tok.text == ",":
            self.take()
            args.append(self.expr())
        self.expect(")", opened)
        self.depth -= 1
        if arity is None and len(args) < 2:
            raise FormulaError(f"{tok.text} takes two or more arguments", tok.position)
        if arity is None and len(args) > MAX_ARGUMENTS:  # sympy compares every pair, and again per derivative
            raise FormulaError(f"{tok.text} takes at most {MAX_ARGUMENTS} arguments", tok.position)
        if arity is not None and len(args) != arity:
            plural = "argument" if arity == 1 else "arguments"
            raise FormulaError(f"{tok.text} takes {arity} {plural}, not {len(args)}", tok.position)
        try:
            result = func(*args)
        except (ValueError, TypeError, ArithmeticError) as e:  # e.g. min of a complex constant
            raise FormulaError(f"{tok.text} cannot be applied here ({e})", tok.position) from None
        if result.is_number:
            # refuse an overflowing constant here, before an enclosing call makes sympy
            # evaluate it to unbounded precision (exp(exp(exp(100))))
            try:
                size = abs(complex(result))   # (the modulus of two finite parts can overflow too)
            except (TypeError, ValueError, OverflowError):
                size = math.inf
            if not math.isfinite(size) or size > LARGEST_CONSTANT:
                raise FormulaError(f"constant value of {tok.text} is too large", tok.position)
        return result


def parse_formula(text: str, parameters=()) -> sp.Expr:
    """Parse a landscape formula z = f(x, y) into a sympy expression in ``X`` and ``Y`` (and
    ``parameter_symbol(k)`` for the k-th of the names ``parameters``).

    Raises ``FormulaError`` (a ``ValueError``) naming the position and the reason.
    """
    names = check_parameter_names(parameters)
    if not isinstance(text, str):
        raise FormulaError("formula must be text")
    if len(text) > MAX_LENGTH:
        raise FormulaError(f"formula is too long ({len(text)} characters, at most {MAX_LENGTH})")
    expr = _Parser(_tokenize(text), {n: parameter_symbol(k) for k, n in enumerate(names)}).parse()
    check_constants(expr)
    return expr


# numba types an integer literal in generated code as a 64-bit integer and refuses a larger
# one ("Int value is too large"): 1e10*1e10*x folds to the exact 100000000000000000000*x, and
# the second derivative of sin(1e15*x) holds 10^30. Beyond 2^53 a double holds the number no
# less exactly than the arithmetic it feeds (which is in doubles), so such constants are
# spelled as float literals.
LARGEST_CODE_INTEGER = 2**53


def code_constant(number: sp.Rational) -> str | None:
    """How generated code spells a rational constant whose numerator or denominator numba
    cannot take as an integer: the correctly rounded float literal (in parentheses); None
    when the ordinary spelling compiles."""
    p, q = int(number.p), int(number.q)
    if abs(p) <= LARGEST_CODE_INTEGER and q <= LARGEST_CODE_INTEGER:
        return None
    value = float(Fraction(p, q))  # correctly rounded; constants over 1e300 were refused earlier
    if not math.isfinite(value):
        raise FormulaError("a constant in the formula is too large")
    return f"({value!r})"


def check_constants(expr: sp.Expr) -> None:
    """Refuse expressions holding numbers a double cannot represent (or complex ones)."""
    if expr.has(sp.zoo, sp.oo, sp.nan, sp.I):
        raise FormulaError("formula is undefined or not real")
    if expr.is_number:
        try:
            value = complex(expr)
        except (TypeError, ValueError, OverflowError):
            value = complex("nan")
        if value.imag != 0 or not math.isfinite(value.real):
            raise FormulaError("formula is undefined or not real")
    for number in expr.atoms(sp.Number):
        try:
            too_large = abs(float(number)) > LARGEST_CONSTANT
        except OverflowError:
            too_large = True
        if too_large:
            raise FormulaError("a constant in the formula is too large")
