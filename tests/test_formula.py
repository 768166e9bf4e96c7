"""Formula screening and parsing: what is accepted, what is refused, and where."""

import builtins
import time

import pytest
import sympy as sp

from rollball.formula import MAX_DEPTH, MAX_LENGTH, X, Y, FormulaError, RealAbs, parse_formula


@pytest.mark.parametrize("text, expected", [
    ("0.5*sin(x)*cos(y)", sp.sin(X) * sp.cos(Y) / 2),
    ("x^2 + y.^2", X**2 + Y**2),
    ("x .* y ./ 2", X * Y / 2),
    ("x**2 - y**2", X**2 - Y**2),
    ("-x^2", -X**2),
    ("2^-1*x", X / 2),
    ("x^y^2", X**(Y**2)),
    ("e^x + pi", sp.exp(X) + sp.pi),
    ("exp(-(x^2 + y^2))", sp.exp(-X**2 - Y**2)),
    ("atan2(y, x) + hypot(x, y)", sp.atan2(Y, X) + sp.sqrt(X**2 + Y**2)),
    ("min(x, y, 1) + max(x, 0)", sp.Min(X, Y, 1) + sp.Max(X, 0)),
    ("abs(x) + sqrt(1 + x^2) + log(2 + y) + log10(3 + x)", RealAbs(X) + sp.sqrt(1 + X**2) + sp.log(2 + Y) + sp.log(3 + X, 10)),
    ("tan(x) + asin(x/9) + acos(y/9) + atan(x) + sinh(x) + cosh(y) + tanh(x)",
     sp.tan(X) + sp.asin(X / 9) + sp.acos(Y / 9) + sp.atan(X) + sp.sinh(X) + sp.cosh(Y) + sp.tanh(X)),
    ("1.5e-1 * x", 3 * X / 20),
    ("  3. + .5  ", sp.Rational(7, 2)),
    ("0", sp.S.Zero),
    ("x - x", sp.S.Zero),
])
def test_accepted(text, expected):
    assert sp.simplify(parse_formula(text) - expected) == 0


@pytest.mark.parametrize("text, message", [
    ("z", "unknown name 'z' at 1"),
    ("x + t", "unknown name 't' at 5"),
    ("x + sinx", "unknown name 'sinx' at 5"),
    ("(x + 1", "unbalanced parenthesis at 1"),
    ("x + 1)", "unbalanced parenthesis at 6"),
    ("sin(x", "unbalanced parenthesis at 4"),
    ("x +", "formula ends too early at 4"),
    ("x * * y", "unexpected '*' at 5"),
    ("2 x", "missing operator before 'x' at 3"),
    ("sin x", "function 'sin' needs its arguments in parentheses at 1"),
    ("x(2)", "'x' is not a function at 1"),
    ("atan2(x)", "atan2 takes 2 arguments, not 1 at 1"),
    ("sin(x, y)", "sin takes 1 argument, not 2 at 1"),
    ("max(x)", "max takes two or more arguments at 1"),
    ("1/0", "division by zero at 2"),
    ("x / (y - y)", "division by zero at 3"),
    ("1e999 * x", "number 1e999 is too large at 1"),
    ("9**9**9**9", "constant power is too large"),
    ("log(-1)", "not real"),
    ("", "formula is empty"),
    ("   ", "formula is empty"),
    ("x;y", "unexpected character ';' at 2"),
    ("x\ny", "unexpected character 'U+000A' at 2"),
])
def test_refused_with_position(text, message):
    with pytest.raises(FormulaError) as info:
        parse_formula(text)
    assert message in str(info.value)


INJECTIONS = [
    '__import__("os").system("touch /tmp/rollball-pwned")',
    "__import__('os')",
    "().__class__.__bases__[0].__subclasses__()",
    "x.__class__",
    "x.real",
    "sin.__globals__",
    "lambda: 0",
    "(lambda x: x)(1)",
    "[x for x in (1, 2)]",
    "{x: 1}",
    "'text'",
    '"text"',
    "b'x'",
    "(y := 2)",
    "x if y else 1",
    "eval('1')",
    "exec('1')",
    "open('/etc/passwd')",
    "getattr(x, 'real')",
    "sympify('x')",
    "Symbol('z')",
    "__builtins__",
    "_",
    "x[0]",
    "x; import os",
    "x # comment",
    "`x`",
    "x @ y",
    "x & y",
    "x == y",
    "x % 2",
    "х + 1",            # Cyrillic x
    "x + ｙ",           # full-width y
    "sin(x)\u200b",     # zero-width space
    "x\x00",
]


@pytest.mark.parametrize("text", INJECTIONS)
def test_injection_refused_and_nothing_runs(text, monkeypatch, tmp_path):
    def forbidden(*args, **kwargs):
        raise AssertionError("user text reached an evaluator")

    monkeypatch.setattr(builtins, "eval", forbidden)
    monkeypatch.setattr(builtins, "exec", forbidden)
    monkeypatch.setattr(sp, "sympify", forbidden)
    monkeypatch.setattr(sp, "parse_expr", forbidden, raising=False)
    with pytest.raises(FormulaError) as info:
        parse_formula(text)
    assert str(info.value)
    assert "\n" not in str(info.value)


def test_injection_side_effect_absent():
    import os

    with pytest.raises(FormulaError):
        parse_formula('__import__("os").system("touch /tmp/rollball-pwned")')
    assert not os.path.exists("/tmp/rollball-pwned")


def test_limits_are_fast():
    cases = ["x" * (MAX_LENGTH + 1), "(" * (MAX_DEPTH + 5) + "x" + ")" * (MAX_DEPTH + 5),
             "sin(" * (MAX_DEPTH + 5) + "x" + ")" * (MAX_DEPTH + 5), "-" * 500 + "x",
             "9^9^9^9^9^9", "(1+1e-15)^(10^300)", "2^2^2^2^2^2^2"]
    for text in cases:
        start = time.perf_counter()
        with pytest.raises(FormulaError):
            parse_formula(text)
        assert time.perf_counter() - start < 0.5, text


def test_not_text():
    with pytest.raises(FormulaError, match="must be text"):
        parse_formula(3)
