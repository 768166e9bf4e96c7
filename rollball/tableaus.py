"""Runge–Kutta methods, declared as Butcher tableaus.

A tableau is data: exact fractions that check themselves when built. The registry
``METHODS`` maps every method name used in scene files, on the command line and in the
app to its tableau, and each entry says what kind of method it is (``MethodKind``): an
explicit fixed-step method (``TABLEAUS``; classic or Munthe-Kaas), an embedded pair with
step-size control, or an implicit symmetric one. ``get_method`` resolves names and the
aliases of older scene files and turns an unknown name into a clear ``ValueError``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction

import numpy as np

from .dop853 import DOP853, DensePair
from .implicit import GAUSS4, GAUSS6, Collocation
from .kinds import ALIASES, KINDS, MethodInfo, MethodKind, cubic_hermite, method_name  # noqa: F401 (ALIASES)


def _fractions(values) -> tuple[Fraction, ...]:
    return tuple(Fraction(v) for v in values)


@dataclass(frozen=True)
class Tableau(MethodInfo):
    """An explicit Runge–Kutta method: nodes ``c``, stage rows ``a`` and weights ``b``.

    ``a`` lists the strictly-lower-triangular rows, one per stage after the first,
    so stage i (counting from 0) has i coefficients. An embedded pair also has weights
    ``b_hat`` of a lower order ``order_hat``: their difference estimates the error of a
    step. The pairs here are "first same as last": the last row of ``a`` is ``b``, so the
    last stage is the derivative at the new state.

    Dense output: ``dense`` holds a continuous extension of order ``dense_order`` as scipy's
    ``P``: row i for stage derivative K_i (the derivative at the new state included as one
    more row for methods that are not first same as last), column k the coefficient of
    theta^(k+1), so that z(t + theta h) = z + h sum_i K_i sum_k P[i, k] theta^(k+1). Without it
    the method gets the cubic Hermite interpolant of the step's end values and derivatives
    (``dense_output``).
    """

    name: str
    label: str
    order: int
    c: tuple[Fraction, ...]
    a: tuple[tuple[Fraction, ...], ...]
    b: tuple[Fraction, ...]
    b_hat: tuple[Fraction, ...] | None = None
    order_hat: int | None = None
    dense: tuple[tuple[Fraction, ...], ...] | None = None
    dense_order: int | None = None

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
        if self.b_hat is not None:
            if len(self.b_hat) != s or sum(self.b_hat) != 1 or self.order_hat is None:
                raise ValueError(f"{self.name}: b_hat must have {s} weights summing to 1, with order_hat")
            if self.a[-1] + (0,) != self.b:
                raise ValueError(f"{self.name}: the last row of a must be b (first same as last)")
        if self.dense is not None:
            rows = s if self.first_same_as_last else s + 1
            if len(self.dense) != rows or self.dense_order is None:
                raise ValueError(f"{self.name}: dense must have {rows} rows, with dense_order")
            b = self.b + (0,) * (rows - s)
            if any(sum(row) != bi for row, bi in zip(self.dense, b)):
                raise ValueError(f"{self.name}: the dense output at theta = 1 must be the step (rows sum to b)")

    @property
    def kind(self) -> MethodKind:
        return MethodKind.ADAPTIVE if self.b_hat is not None else MethodKind.FIXED

    @property
    def error_exponent(self) -> float:
        """-1 / (q + 1) for an embedded error estimate of order q: the step-size rule's exponent."""
        if self.order_hat is None:
            raise ValueError(f"{self.name} has no error estimate")
        return -1.0 / (self.order_hat + 1)

    def weights(self, embedded: bool = False) -> "Tableau":
        """The method with the pair's main weights b (or, embedded, b_hat) as a plain
        fixed-step tableau: for measuring the pair's two orders."""
        b, order = (self.b_hat, self.order_hat) if embedded else (self.b, self.order)
        suffix = "-embedded" if embedded else "-main"
        return replace(self, name=self.name + suffix, b=b, order=order, b_hat=None, order_hat=None,
                       dense=None, dense_order=None)

    @property
    def stages(self) -> int:
        return len(self.b)

    @property
    def first_same_as_last(self) -> bool:
        """The last stage is the derivative at the new state (the pairs here)."""
        return self.b_hat is not None

    @property
    def last(self) -> int:
        """Index of the derivative at the new state among the stage derivatives K."""
        return self.stages - 1 if self.first_same_as_last else self.stages

    def dense_output(self) -> tuple[tuple[Fraction, ...], ...]:
        """The interpolation matrix P (see the class docstring), exact: the declared one, or
        the cubic Hermite interpolant of z_n, K_0 = z'(z_n), z_n+1 = z_n + h sum b_i K_i and
        K_last = z'(z_n+1), whose coefficients of theta, theta^2, theta^3 are
        e_0, 3 b - 2 e_0 - e_last and e_0 + e_last - 2 b."""
        if self.dense is not None:
            return self.dense
        return cubic_hermite(self.b + (Fraction(0),) * (self.last + 1 - self.stages), self.last)

    @property
    def interpolation_order(self) -> int:
        """Order of the dense output: the declared one, or for the cubic Hermite interpolant
        3 (error O(h^4) inside a step), and never above the method's order."""
        return self.dense_order if self.dense is not None else min(3, self.order)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tableau as float arrays (A square, strictly lower triangular; b; c)."""
        s = self.stages
        A = np.zeros((s, s))
        for i, row in enumerate(self.a, start=1):
            A[i, :i] = [float(v) for v in row]
        return A, np.array([float(v) for v in self.b]), np.array([float(v) for v in self.c])

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The method as the kernel reads it: (W, E, P) over the stage derivatives K_0 .. K_last
        (K_last the derivative at the new state, ``last``). W is square and strictly lower
        triangular: rows 1 .. last-1 the stage coefficients, row ``last`` the weights b.
        E holds the error weights b - b_hat (no rows for fixed-step methods). P is the dense
        output. (Extra dense-output stages would be further rows of W, K and P after ``last``.)
        """
        A, b, _ = self.arrays()
        size = self.last + 1
        W = np.zeros((size, size))
        W[: self.stages, : self.stages] = A
        W[self.last, : self.stages] = b
        E = np.zeros((0, size))
        if self.adaptive:
            E = (b - np.array([float(v) for v in self.b_hat]))[None, :]
        P = np.array([[float(v) for v in row] for row in self.dense_output()])
        return W, E, P


def tableau(name: str, label: str, order: int, c, a, b, b_hat=None, order_hat=None, dense=None,
            dense_order=None) -> Tableau:
    return Tableau(name, label, order, _fractions(c), tuple(_fractions(r) for r in a), _fractions(b),
                   None if b_hat is None else _fractions(b_hat), order_hat,
                   None if dense is None else tuple(_fractions(r) for r in dense), dense_order)


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

# J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae",
# J. Comput. Appl. Math. 6(1), 1980: orders 5 and 4, first same as last.
DOPRI5 = tableau(
    "dopri5", "DOPRI5", 5,
    c=[0, "1/5", "3/10", "4/5", "8/9", 1, 1],
    a=[
        ["1/5"],
        ["3/40", "9/40"],
        ["44/45", "-56/15", "32/9"],
        ["19372/6561", "-25360/2187", "64448/6561", "-212/729"],
        ["9017/3168", "-355/33", "46732/5247", "49/176", "-5103/18656"],
        ["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84"],
    ],
    b=["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0],
    b_hat=["5179/57600", 0, "7571/16695", "393/640", "-92097/339200", "187/2100", "1/40"],
    order_hat=4,
    # the continuous extension of order 4 (L. F. Shampine, "Some practical Runge-Kutta
    # formulas", Math. Comp. 46, 1986), in the form of scipy's RK45.P
    dense=[
        [1, "-8048581381/2820520608", "8663915743/2820520608", "-12715105075/11282082432"],
        [0, 0, 0, 0],
        [0, "131558114200/32700410799", "-68118460800/10900136933", "87487479700/32700410799"],
        [0, "-1754552775/470086768", "14199869525/1410260304", "-10690763975/1880347072"],
        [0, "127303824393/49829197408", "-318862633887/49829197408", "701980252875/199316789632"],
        [0, "-282668133/205662961", "2019193451/616988883", "-1453857185/822651844"],
        [0, "40617522/29380423", "-110615467/29380423", "69997945/29380423"],
    ],
    dense_order=4,
)

# Every registry entry is a tableau; ``Method`` names that role in signatures.
# A registry entry: an explicit tableau, an implicit collocation method or DOP853's pair,
# each with name, label, order, kind (and what follows from it) and ``kernel_arrays``.
Method = Tableau | Collocation | DensePair

# Every method by the name scene files, the command line and the app use, in the order
# they are listed.
METHODS: dict[str, Method] = {t.name: t for t in (EULER, RK4, LAWSON5, GAUSS4, GAUSS6, DOPRI5, DOP853)}
if [(name, m.kind) for name, m in METHODS.items()] != list(KINDS.items()):
    raise RuntimeError("kinds.KINDS must list the methods of METHODS, in its order and with their kinds")
# The explicit fixed-step ones (each also runs classic or Munthe-Kaas).
TABLEAUS: dict[str, Tableau] = {name: t for name, t in METHODS.items() if t.classic_allowed}


def get_method(name) -> Method:
    """The method of a name in ``METHODS`` or ``ALIASES`` (a method itself is passed through)."""
    if isinstance(name, MethodInfo):
        return name
    return METHODS[method_name(name)]
