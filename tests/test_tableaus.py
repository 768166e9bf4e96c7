"""The Butcher tableaus satisfy their own order conditions, exactly (rational arithmetic)."""

from fractions import Fraction

import pytest

from rollball.order_conditions import residuals, rooted_trees, size
from rollball.tableaus import DOPRI5, LAWSON5, METHODS, RK4, TABLEAUS, MethodKind, Tableau, get_method


def stage_matrix(tab: Tableau) -> list:
    """A as exact square rows (the tableau lists only the strictly lower triangle)."""
    s = tab.stages
    return [[Fraction(0)] * s] + [list(row) + [Fraction(0)] * (s - len(row)) for row in tab.a]


def test_tree_counts():
    assert [len(rooted_trees(p)) for p in range(1, 7)] == [1, 1, 2, 4, 9, 20]


# the explicit tableaus (the implicit ones and DOP853 check themselves: test_implicit, test_dop853)
ALL = {**{name: m for name, m in METHODS.items() if isinstance(m, Tableau)},
       "dopri5-embedded": DOPRI5.weights(embedded=True)}


@pytest.mark.parametrize("tab", ALL.values(), ids=list(ALL))
def test_declared_order_is_exact(tab):
    found = {}
    for tree, residual in residuals(stage_matrix(tab), tab.b, tab.order + 1):
        found.setdefault(size(tree), []).append(residual == 0)
    assert all(all(found[p]) for p in range(1, tab.order + 1)), tab.name
    assert not all(found[tab.order + 1])  # and not one order more


def test_registry():
    assert list(TABLEAUS) == ["euler", "rk4", "lawson5"]
    assert [name for name in METHODS if name in ("euler", "rk4", "lawson5", "dopri5")] == \
        ["euler", "rk4", "lawson5", "dopri5"]
    assert "adaptive" not in METHODS
    assert get_method("lawson5") is LAWSON5 and get_method("adaptive") is DOPRI5 and get_method(RK4) is RK4
    assert DOPRI5.adaptive and not any(t.adaptive for t in TABLEAUS.values())
    with pytest.raises(ValueError, match="euler, rk4, lawson5, .*dopri5"):
        get_method("rk45")


def test_every_method_says_its_kind():
    for method in METHODS.values():
        assert isinstance(method.kind, MethodKind) and method.label and method.order >= 1
        assert method.fixed_step == (method.kind in (MethodKind.FIXED, MethodKind.IMPLICIT))
        assert method.classic_allowed == (method.kind is MethodKind.FIXED)
    assert RK4.kind == "fixed" and DOPRI5.kind == "adaptive" and str(DOPRI5.kind) == "adaptive"
    assert not DOPRI5.fixed_step and not DOPRI5.classic_allowed and RK4.classic_allowed


def test_step_size_exponent_follows_the_error_estimate():
    assert DOPRI5.error_exponent == -1 / 5  # an estimate of order 4
    with pytest.raises(ValueError, match="no error estimate"):
        RK4.error_exponent


def test_the_pair():
    assert (DOPRI5.order, DOPRI5.order_hat) == (5, 4)
    assert DOPRI5.weights().b == DOPRI5.b and DOPRI5.weights(embedded=True).b == DOPRI5.b_hat
    W, E, P = DOPRI5.kernel_arrays()
    assert W.shape == (7, 7) and E.shape == (1, 7) and P.shape == (7, 4) and DOPRI5.last == 6
    assert (W[6] == [float(v) for v in DOPRI5.b]).all()  # first same as last: the last stage row is b
    assert E[0].sum() == pytest.approx(0, abs=1e-16)  # b - b_hat
    W, E, P = RK4.kernel_arrays()  # the derivative at the new state is one more row
    assert W.shape == (5, 5) and E.shape == (0, 5) and P.shape == (5, 3) and RK4.last == 4
    with pytest.raises(ValueError, match="b_hat"):
        Tableau("bad", "Bad", 1, (Fraction(0), Fraction(1)), ((Fraction(1),),),
                (Fraction(1), Fraction(0)), (Fraction(1, 2), Fraction(1, 3)), 1)
    with pytest.raises(ValueError, match="first same as last"):
        Tableau("bad", "Bad", 1, (Fraction(0), Fraction(1)), ((Fraction(1),),),
                (Fraction(1, 2), Fraction(1, 2)), (Fraction(1), Fraction(0)), 1)


def test_tableau_checks_itself():
    with pytest.raises(ValueError, match="sum to c"):
        Tableau("bad", "Bad", 2, (Fraction(0), Fraction(1, 2)), ((Fraction(1),),), (Fraction(0), Fraction(1)))
    with pytest.raises(ValueError, match="sum to 1"):
        Tableau("bad", "Bad", 1, (Fraction(0),), (), (Fraction(1, 2),))
    A, b, c = RK4.arrays()
    assert A.shape == (4, 4) and (A[0] == 0).all() and A[3, 2] == 1
    assert b.sum() == pytest.approx(1, abs=1e-15) and c[1] == 0.5
