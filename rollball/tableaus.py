"""Explicit Runge–Kutta methods, declared as Butcher tableaus.

A tableau is data: exact fractions that check themselves when built. The registry
``TABLEAUS`` maps the names used in scene files, on the command line and in the app
to the tableaus; ``get_tableau`` turns an unknown name into a clear ``ValueError``.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np


def _fractions(values) -> tuple[Fraction, ...]:
    return tuple(Fraction(v) for v in values)


@dataclass(frozen=True)
class Tableau:
    """An explicit Runge–Kutta method: nodes ``c``, stage rows ``a`` and weights ``b``.

    ``a`` lists the strictly-lower-triangular rows, one per stage after the first,
    so stage i (counting from 0) has i coefficients.
    """

    name: str
    label: str
    order: int
    c: tuple[Fraction, ...]
    a: tuple[tuple[Fraction, ...], ...]
    b: tuple[Fraction, ...]

    def __post_init__(self):
        s = len(self.b)
        if len(self.c) != s or len(self.a) != s - 1:
            raise ValueError(f"{self.name}: c, a and b describe different numbers of stages")
        if self.c[0] != 0:
            raise ValueError(f"{self.name}: an explicit method starts with c = 0")
        for i, row in enumerate(self.a, start=1):
            if len(row) != i:
                raise ValueError(f"{self.name}: row {i} of a must have {i} entries")
            if sum(row) != self.c[i]:
                raise ValueError(f"{self.name}: row {i} of a does not sum to c[{i}]")
        if sum(self.b) != 1:
            raise ValueError(f"{self.name}: the weights b do not sum to 1")

    @property
    def stages(self) -> int:
        return len(self.b)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tableau as float arrays (A square, strictly lower triangular; b; c)."""
        s = self.stages
        A = np.zeros((s, s))
        for i, row in enumerate(self.a, start=1):
            A[i, :i] = [float(v) for v in row]
        return A, np.array([float(v) for v in self.b]), np.array([float(v) for v in self.c])

    def matrix(self) -> np.ndarray:
        """A with the weights b as one more row: the (s + 1) x s array the kernel reads."""
        A, b, _ = self.arrays()
        return np.vstack([A, b])


def tableau(name: str, label: str, order: int, c, a, b) -> Tableau:
    return Tableau(name, label, order, _fractions(c), tuple(_fractions(r) for r in a), _fractions(b))


EULER = tableau("euler", "Euler", 1, c=[0], a=[], b=[1])

RK4 = tableau(
    "rk4", "RK4", 4,
    c=[0, "1/2", "1/2", 1],
    a=[["1/2"], [0, "1/2"], [0, 0, 1]],
    b=["1/6", "1/3", "1/3", "1/6"],
)

# J. D. Lawson, "An order five Runge-Kutta process with extended region of stability",
# SIAM J. Numer. Anal. 3(4), 1966.
LAWSON5 = tableau(
    "lawson5", "Lawson5", 5,
    c=[0, "1/12", "1/4", "1/2", "3/4", 1],
    a=[
        ["1/12"],
        ["-1/8", "3/8"],
        ["3/5", "-9/10", "4/5"],
        ["39/80", "-9/20", "3/20", "9/16"],
        ["-59/35", "66/35", "48/35", "-12/7", "8/7"],
    ],
    b=["7/90", 0, "16/45", "2/15", "16/45", "7/90"],
)

TABLEAUS: dict[str, Tableau] = {t.name: t for t in (EULER, RK4, LAWSON5)}


def get_tableau(name: str) -> Tableau:
    try:
        return TABLEAUS[name]
    except (KeyError, TypeError):
        valid = ", ".join(TABLEAUS)
        raise ValueError(f"unknown method {name!r}; valid methods: {valid}") from None
