"""Formula screening and parsing: what is accepted, what is refused, and where."""

import pytest
import sympy as sp

from rollball.formula import X, Y, FormulaError, RealAbs, parse_formula


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
    ("abs(x) + sqrt(1 + x^2) + log(2 + y) + log10(3 + x)",
     RealAbs(X) + sp.sqrt(1 + X**2) + sp.log(2 + Y) + sp.log(3 + X, 10)),
    ("tan(x) + asin(x/9) + acos(y/9) + atan(x) + sinh(x) + cosh(y) + tanh(x)",
     sp.tan(X) + sp.asin(X / 9) + sp.acos(Y / 9) + sp.atan(X) + sp.sinh(X) + sp.cosh(Y) + sp.tanh(X)),
    ("1.5e-1 * x", 3 * X / 20),
    ("  3. + .5  ", sp.Rational(7, 2)),
    ("0", sp.S.Zero),
    ("x - x", sp.S.Zero),
])
def test_accepted(text, expected):
    assert sp.simplify(parse_formula(text) - expected) == 0


# Refused formulas, with their messages, are the corpus in tests/hostile_corpus.py.


def test_not_text():
    with pytest.raises(FormulaError, match="must be text"):
        parse_formula(3)


@pytest.mark.parametrize("text, at, expected", [
    # folded exactly by sympy to integers numba's 64-bit literals cannot hold
    ("1e10*1e10*x", 0.5, [5e19, 1e20, 0, 0, 0, 0]),
    ("0.1*sin(1e15*x)", 0.25, None),          # f_xx holds 10^29
    ("1e20/3*x + x/(1e10*1e10)", 1.0, [1e20 / 3 + 1e-20, 1e20 / 3 + 1e-20, 0, 0, 0, 0]),
])
def test_constants_too_large_for_machine_integers_compile(text, at, expected):
    import math

    import numpy as np

    from rollball.landscape import Landscape

    values = Landscape(text).evaluate(at, 0.0)
    if expected is None:
        expected = [0.1 * math.sin(1e15 * at), 1e14 * math.cos(1e15 * at), 0, -1e29 * math.sin(1e15 * at), 0, 0]
    np.testing.assert_allclose(values, expected, rtol=1e-12)


@pytest.mark.parametrize("text", ["1e10*1e10*x", "0.1*sin(1e15*x)"])
def test_they_run_from_the_command_line(text, tmp_path, capsys):
    import json

    from rollball.cli import main

    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({"format": "rollball-scene", "version": 2, "landscape": text, "duration": 0.05}))
    assert main(["simulate", str(scene)]) == 0
    out = capsys.readouterr()
    assert "status ok" in out.out and "Traceback" not in out.err
