"""Runge–Kutta order conditions (Butcher's rooted trees), for tableaus that check themselves.

A method with stage matrix A (any s x s, explicit or implicit) and weights b has order p
when b . Phi(t) = 1 / gamma(t) for every rooted tree t with at most p nodes, where
Phi_i(t) = prod over the subtrees t' of t of (A Phi(t'))_i and gamma is the tree's density.
Exact with ``Fraction`` entries; with decimal coefficients the residuals show how far the
published digits are from the exact method.
"""

from __future__ import annotations

from functools import lru_cache


@lru_cache(maxsize=None)
def rooted_trees(order: int) -> tuple[tuple, ...]:
    """All rooted trees with ``order`` nodes, each a sorted tuple of its subtrees."""
    if order == 1:
        return ((),)
    trees = set()

    def partitions(n, largest):  # sizes of the subtrees, largest first
        if n == 0:
            yield []
            return
        for k in range(min(n, largest), 0, -1):
            for rest in partitions(n - k, k):
                yield [k] + rest

    def build(sizes, chosen):
        if not sizes:
            trees.add(tuple(sorted(chosen)))
            return
        for t in rooted_trees(sizes[0]):
            build(sizes[1:], chosen + [t])

    for sizes in partitions(order - 1, order - 1):
        build(sizes, [])
    return tuple(sorted(trees))


def size(tree) -> int:
    return 1 + sum(size(t) for t in tree)


def density(tree) -> int:
    """gamma(t): the tree's size times the densities of its subtrees."""
    result = size(tree)
    for t in tree:
        result *= density(t)
    return result


class ElementaryWeights:
    """Phi(t) over the stages of a stage matrix ``A`` (rows of numbers), memoised per tree."""

    def __init__(self, A):
        self.A = [list(row) for row in A]
        self.s = len(self.A)
        self._memo = {}

    def __call__(self, tree) -> list:
        if tree not in self._memo:
            s, A = self.s, self.A
            g = [1] * s
            for child in tree:
                h = self(child)
                g = [g[i] * sum(A[i][j] * h[j] for j in range(s) if A[i][j]) for i in range(s)]
            self._memo[tree] = g
        return self._memo[tree]


def residuals(A, b, order: int, phi: ElementaryWeights | None = None, power: int | None = None):
    """(tree, b . Phi(t) - 1/gamma(t)) for every tree with at most ``order`` nodes; b may be
    shorter than A (the weights of the first len(b) stages). Exact for ``Fraction`` entries,
    as precise as the context for ``Decimal`` ones. ``phi``: the elementary weights of A, if
    already at hand. With ``power`` k, the conditions on the coefficient of x^k of a
    continuous extension b(x): b_k . Phi(t) = 1/gamma(t) if t has k nodes, else 0."""
    phi = phi or ElementaryWeights(A)
    for p in range(1, order + 1):
        target = 1 if power is None or power == p else 0
        for tree in rooted_trees(p):
            weights, gamma = phi(tree), density(tree)
            total = sum(bi * weights[i] for i, bi in enumerate(b) if bi)
            yield tree, (total * gamma - target) / gamma
