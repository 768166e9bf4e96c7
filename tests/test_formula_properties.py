"""Property-based: any text is either parsed or refused with a FormulaError, nothing else;
random formulas from the grammar parse, differentiate and evaluate with the right shapes;
random valid scenes survive dumps and loads unchanged."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rollball.formula import FUNCTIONS, FormulaError, parse_formula
from rollball.landscape import Landscape
from rollball.scene import Ball, Integrator, Scene, Start, View
from rollball.tableaus import TABLEAUS

ATOMS = st.sampled_from(["x", "y", "pi", "e", "0", "1", "2.5", "0.1", "3e-2"])
UNARY = sorted(name for name, (_, arity) in FUNCTIONS.items() if arity == 1)


def _combine(children):
    binary = st.tuples(children, st.sampled_from(["+", "-", "*", "/", "^", ".^", ".*", "./", "**"]),
                       children).map(lambda t: f"({t[0]} {t[1]} {t[2]})")
    unary = st.tuples(st.sampled_from(UNARY), children).map(lambda t: f"{t[0]}({t[1]})")
    neg = children.map(lambda c: f"-{c}")
    pair = st.tuples(st.sampled_from(["atan2", "min", "max", "hypot"]), children, children).map(
        lambda t: f"{t[0]}({t[1]}, {t[2]})")
    return binary | unary | neg | pair


FORMULAS = st.recursive(ATOMS, _combine, max_leaves=8)


@settings(max_examples=100, deadline=None)
@given(FORMULAS)
def test_grammar_formulas_parse_or_are_refused_cleanly(text):
    try:
        landscape = Landscape(text)
    except FormulaError as e:
        assert str(e)
        return
    X, Y = np.meshgrid(np.linspace(-2, 2, 5), np.linspace(-2, 2, 3), indexing="ij")
    values = landscape.evaluate(X, Y)
    assert values.shape == (6, 5, 3)
    assert values.dtype == float


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8"), max_size=60)
       | st.text(alphabet="xy+-*/^.()e0123456789 ,sincoqrtlgabmp_", max_size=40))
def test_any_text_is_parsed_or_refused(text):
    try:
        parse_formula(text)
    except FormulaError as e:
        assert str(e) and "\n" not in str(e)


FINITE = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
POSITIVE = st.floats(min_value=1e-6, max_value=1e6)
SCENES = st.builds(
    Scene,
    landscape=st.sampled_from(["0", "x*y", "0.5*sin(x)*cos(y)", "exp(-(x^2 + y^2))", "abs(x) + y^2"]),
    description=st.text(max_size=40),
    gravity=st.floats(min_value=0, max_value=1e3),
    ball=st.builds(Ball, POSITIVE, POSITIVE),
    start=st.builds(Start, FINITE, FINITE, FINITE, FINITE, FINITE),
    integrator=st.builds(Integrator, st.sampled_from(sorted(TABLEAUS)), st.booleans(), POSITIVE),
    duration=POSITIVE,
    view=st.tuples(FINITE, st.floats(min_value=1e-3, max_value=1e6), st.integers(1, 399))  # <= 401 points
           .map(lambda v: View(v[0], v[0] + v[1], v[1] / v[2])),
)


@settings(max_examples=100, deadline=None)
@given(SCENES)
def test_scene_round_trip(scene):
    assert Scene.loads(scene.dumps()) == scene
