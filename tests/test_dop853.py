"""The Dormand–Prince 8(5,3) data: its order conditions hold, and the check is real."""

from decimal import Decimal, localcontext

import numpy as np
import pytest

from rollball import dop853
from rollball.order_conditions import residuals, rooted_trees


def test_the_published_pair_meets_its_conditions():
    pair = dop853.build()
    A, b5 = pair.A, [b - e for b, e in zip(pair.b, pair.e5)]
    with localcontext() as context:
        context.prec = dop853.PRECISION
        # order 8 and not 9; the 5th-order estimate 5 and not 6
        assert max(abs(r) for _, r in residuals(A, pair.b, 8)) < 1e-27
        assert max(abs(r) for _, r in residuals(A, pair.b, 9)) > 1e-6
        assert max(abs(r) for _, r in residuals(A, b5, 5)) < 1e-26
        assert max(abs(r) for _, r in residuals(A, b5, 6)) > 1e-6
        # the dense output at x = 1 is the step's end
        ends = [sum(row) for row in pair.P]
        assert max(abs(e - b) for e, b in zip(ends, pair.b + (0,) * 4)) < 1e-26


def test_the_kernel_rows_are_scipys_coefficients():
    from scipy.integrate._ivp import dop853_coefficients as theirs

    W = dop853.DOP853.matrix()
    assert np.array_equal(W[:16], theirs.A)
    assert np.array_equal(W[16, :12], theirs.B)
    assert np.array_equal(W[17, :13], theirs.E5) and np.abs(W[18, :13] - theirs.E3).max() < 1e-16


def _altered(table, row, col, delta):
    """A copy of a coefficient table (dict of rows or of values) with one entry moved."""
    copy = {i: dict(r) for i, r in table.items()} if row is not None else dict(table)
    target = copy[row] if row is not None else copy
    target[col] = str(Decimal(target.get(col, "0")) + Decimal(delta))
    return copy


@pytest.mark.parametrize("what, change, message", [
    # moved within a row, so the row still sums to c: only the order conditions can tell
    ("a", lambda a: _altered(_altered(a, 8, 5, "1e-12"), 8, 0, "-1e-12"), "b fails the order condition"),
    ("a", lambda a: _altered(a, 7, 6, "1e-12"), "row 8 of A does not sum"),
    ("e5", lambda e5: _altered(e5, None, 9, "1e-12"), "5th-order estimate fails"),
    ("bhh", lambda bhh: _altered(bhh, None, 8, "1e-12"), "3rd-order estimate fails"),
    ("d", lambda d: tuple(_altered(dict(enumerate(d)), 2, 9, "1e-10").values()), "dense output fails"),
])
def test_a_perturbed_coefficient_is_refused(what, change, message):
    table = {"a": dop853.A, "e5": dop853.E5, "bhh": dop853.BHH, "d": dop853.D}[what]
    with pytest.raises(ValueError, match=message):
        dop853.build(**{what: change(table)})


def test_tree_counts():
    assert [len(rooted_trees(p)) for p in range(1, 9)] == [1, 1, 2, 4, 9, 20, 48, 115]
