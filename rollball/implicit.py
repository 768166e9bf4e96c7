"""Implicit Gauss–Legendre collocation methods (``gauss4``, ``gauss6``): symmetric, fixed step.

An s-stage Gauss method has order 2s and is symmetric: a step of size h followed by one of
size -h returns to the start. The reduced motion (alpha, v) is reversible under
(alpha, v, t) -> (alpha, -v, -t), so a symmetric method shows no secular drift of the energy
on it; the error stays bounded where every explicit method drifts linearly. The orientation
rides along by Munthe-Kaas: u' = dexp_u^-1(omega) is integrated with (alpha, v) from u = 0,
then R <- exp(u) R.

The stage equations K_i = z'(z + h sum_j a_ij K_j) are solved by fixed-point iteration
inside the compiled kernel (kernel.collocation_step), started from the previous step's
stages, until the change is at round-off. Where the iteration does not contract (a step too large for
the motion) the step fails and the run stops with an honest status; it never takes an
unconverged step. Every iteration costs s right-hand-side evaluations, all counted.

The tableaus are data: the exact coefficients (with sqrt(3), sqrt(15)) evaluated to 60
digits, checked against their order conditions and the symmetry conditions when built.
"""

from __future__ import annotations

from dataclasses import dataclass
from decimal import Decimal, localcontext

import numpy as np

from .kinds import MethodInfo, MethodKind, cubic_hermite
from .order_conditions import residuals, size

PRECISION = 60             # digits of the coefficients and of the checks
RESIDUAL_LIMIT = 1e-50     # the conditions hold to the precision of the arithmetic



@dataclass(frozen=True)
class Collocation(MethodInfo):
    """An implicit symmetric Runge–Kutta method (full stage matrix ``a``), checked when built."""

    kind = MethodKind.IMPLICIT

    name: str
    label: str
    order: int
    c: tuple
    a: tuple
    b: tuple

    def __post_init__(self):
        with localcontext() as context:
            context.prec = PRECISION
            s = len(self.b)
            if len(self.c) != s or len(self.a) != s or any(len(row) != s for row in self.a):
                raise ValueError(f"{self.name}: c, a and b describe different numbers of stages")
            for i, row in enumerate(self.a):
                if abs(sum(row) - self.c[i]) > RESIDUAL_LIMIT:
                    raise ValueError(f"{self.name}: row {i + 1} of a does not sum to c[{i + 1}]")
            # symmetric: c and b mirror, and a_ij + a_(s-1-i)(s-1-j) = b_j
            for i in range(s):
                if abs(self.c[i] + self.c[s - 1 - i] - 1) > RESIDUAL_LIMIT \
                        or self.b[i] != self.b[s - 1 - i] \
                        or any(abs(self.a[i][j] + self.a[s - 1 - i][s - 1 - j] - self.b[j]) > RESIDUAL_LIMIT
                               for j in range(s)):
                    raise ValueError(f"{self.name}: the method is not symmetric (stage {i + 1})")
            worst = {}
            for tree, residual in residuals(self.a, self.b, self.order + 1):
                p = size(tree)
                worst[p] = max(worst.get(p, 0), abs(residual))
                if p <= self.order and abs(residual) > RESIDUAL_LIMIT:
                    raise ValueError(f"{self.name}: fails the order condition of the tree {tree} "
                                     f"(order {p}) by {float(residual):.3g}")
            if worst[self.order + 1] <= RESIDUAL_LIMIT:
                raise ValueError(f"{self.name}: has order above {self.order}")

    @property
    def stages(self) -> int:
        return len(self.b)

    @property
    def last(self) -> int:
        """Index of the derivative at the new state among the kernel's stage derivatives K:
        K_0 = z'(z_n), K_1 .. K_s the stages, K_s+1 .. K_2s their next iterate, then it."""
        return 2 * self.stages + 1

    def extrapolation(self) -> np.ndarray:
        """E with K_i(next step) ~ sum_j E[i, j] K_j(this step) + E[i, s] z'(new state): the
        polynomial through the stage derivatives (at c_j) and the derivative at the step's end
        (at 1), at 1 + c_i; one order better than the collocation polynomial alone."""
        nodes = [float(v) for v in self.c] + [1.0]
        s = self.stages
        E = np.ones((s, s + 1))
        for i in range(s):
            for j in range(s + 1):
                for m in range(s + 1):
                    if m != j:
                        E[i, j] *= (1.0 + nodes[i] - nodes[m]) / (nodes[j] - nodes[m])
        return E

    def dense_output(self) -> tuple[tuple, ...]:
        """The interpolation matrix P over K_0 .. K_last: the cubic Hermite interpolant of the
        step's ends (error O(h^4) inside a step; the collocation polynomial's is O(h^(s+1)))."""
        s = self.stages
        b = [0.0] + [float(v) for v in self.b] + [0.0] * (s + 1)
        return cubic_hermite(b, self.last)

    interpolation_order = 3

    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(W, E, P) as kernel.collocation_step reads them, over K_0 .. K_last: W square, rows
        1 .. s the stage coefficients a (columns 1 .. s), rows s+1 .. 2s the extrapolation of
        the next step's stages (columns 0 .. s: K_0 then holds the new state's derivative),
        row ``last`` the weights b; no error weights E; P the dense output."""
        s, last = self.stages, self.last
        W = np.zeros((last + 1, last + 1))
        W[1:s + 1, 1:s + 1] = [[float(v) for v in row] for row in self.a]
        E = self.extrapolation()
        W[s + 1:2 * s + 1, 1:s + 1] = E[:, :s]
        W[s + 1:2 * s + 1, 0] = E[:, s]
        W[last, 1:s + 1] = [float(v) for v in self.b]
        P = np.array(self.dense_output(), dtype=float)
        return W, np.zeros((0, last + 1)), P


def _gauss4() -> Collocation:
    with localcontext() as context:
        context.prec = PRECISION
        r = Decimal(3).sqrt() / 6
        q = Decimal(1) / 4
        return Collocation("gauss4", "Gauss4", 4, c=(Decimal("0.5") - r, Decimal("0.5") + r),
                           a=((q, q - r), (q + r, q)), b=(Decimal("0.5"), Decimal("0.5")))


def _gauss6() -> Collocation:
    with localcontext() as context:
        context.prec = PRECISION
        w = Decimal(15).sqrt()
        half, f, g = Decimal("0.5"), Decimal(5) / 36, Decimal(2) / 9
        return Collocation(
            "gauss6", "Gauss6", 6, c=(half - w / 10, half, half + w / 10),
            a=((f, g - w / 15, f - w / 30),
               (f + w / 24, g, f - w / 24),
               (f + w / 30, g + w / 15, f)),
            b=(Decimal(5) / 18, Decimal(4) / 9, Decimal(5) / 18))


# E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer 2006,
# §II.1.3 (the Gauss methods) and §VIII.6 (solving their stage equations by fixed-point iteration).
GAUSS4 = _gauss4()
GAUSS6 = _gauss6()
