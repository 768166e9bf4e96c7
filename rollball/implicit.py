"""Implicit Gauss–Legendre collocation methods (``gauss4``, ``gauss6``): symmetric, fixed step.

An s-stage Gauss method has order 2s and is symmetric: a step of size h followed by one of
size -h returns to the start. The reduced motion (alpha, v) is reversible under
(alpha, v, t) -> (alpha, -v, -t), so a symmetric method shows no secular drift of the energy
on it; the error stays bounded where every explicit method drifts linearly. The orientation
rides along by Munthe-Kaas: u' = dexp_u^-1(omega) is integrated with (alpha, v) from u = 0,
then R <- exp(u) R.

The stage equations K_i = z'(z + h sum_j a_ij K_j) are solved by fixed-point iteration
inside the compiled kernel, started from the previous step's collocation polynomial, until
the change is at round-off. Where the iteration does not contract (a step too large for
the motion) the step fails and the run stops with an honest status; it never takes an
unconverged step. Every iteration costs s right-hand-side evaluations, all counted.

The tableaus are data: the exact coefficients (with sqrt(3), sqrt(15)) evaluated to 60
digits, checked against their order conditions and the symmetry conditions when built.
"""

from __future__ import annotations

from dataclasses import dataclass
from decimal import Decimal, localcontext

import numpy as np

from . import kernel
from .kernel import JIT
from .order_conditions import residuals, size

PRECISION = 60             # digits of the coefficients and of the checks
RESIDUAL_LIMIT = 1e-50     # the conditions hold to the precision of the arithmetic

# The stage iteration: converged once the scaled change of the stage values is at round-off,
# or once it stops shrinking below NOISE (round-off fluctuations); it fails when it stops
# shrinking above NOISE (it diverges) or has not converged after MAX_ITERATIONS.
ROUND_OFF = 4.0 * 2.0 ** -52
NOISE = 1e-13
MAX_ITERATIONS = 60
NOT_CONVERGED = 3          # the step's code (beside trial_step's 0 ok, 1 motion, 2 orientation)


@dataclass(frozen=True)
class Collocation:
    """An implicit Runge–Kutta method (full stage matrix ``a``), checked when built."""

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

    def extrapolation(self) -> np.ndarray:
        """E with K_i(next step) ~ sum_j E[i, j] K_j(this step): the derivative of this step's
        collocation polynomial (the Lagrange interpolant of K_j at c_j) at 1 + c_i."""
        c = [float(v) for v in self.c]
        s = len(c)
        E = np.ones((s, s))
        for i in range(s):
            for j in range(s):
                for m in range(s):
                    if m != j:
                        E[i, j] *= (1.0 + c[i] - c[m]) / (c[j] - c[m])
        return E

    def matrix(self) -> np.ndarray:
        """What the kernel reads: rows 0 .. s-1 the stage matrix a, row s the weights b,
        rows s+1 .. 2s the extrapolation E of the starting values (s columns each)."""
        a = np.array([[float(v) for v in row] for row in self.a])
        b = np.array([[float(v) for v in self.b]])
        return np.vstack([a, b, self.extrapolation()])


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


def k_rows(stages: int) -> int:
    """Rows of K for an s-stage collocation step: the derivative at the step's start, the
    stage derivatives, the next iterate of them, and the derivative at the new state."""
    return 2 * stages + 2


@JIT
def collocation_step(fn, d, p, W, s, n, h, z, R, K, guess, Y, zn, Rn, pn, ints):
    """One Gauss–Legendre step of size h (h < 0 steps backwards) from z to zn, Rn (Munthe-Kaas).

    K[0] holds z'(z); K[1 .. s] hold the stage derivatives (on entry those of the previous
    step, extrapolated when ``guess``; on return this step's); K[s+1 .. 2s] is scratch;
    K[2s+1] and pn receive the full evaluation at zn, as trial_step's K[last]. Counts its
    evaluations in ints[I_EVALS]. Returns 0 (done), 1 (the motion is not finite), 2 (only
    the orientation is not) or NOT_CONVERGED (the stage iteration does not converge).
    """
    new = s + 1
    # starting values: the previous collocation polynomial extrapolated, or z'(z) throughout
    for i in range(s):
        for q in range(n):
            acc = K[0, q]
            if guess:
                acc = 0.0
                for j in range(s):
                    acc += W[s + 1 + i, j] * K[1 + j, q]
            K[new + i, q] = acc
    for i in range(s):
        for q in range(n):
            K[1 + i, q] = K[new + i, q]
    previous = np.inf
    code = NOT_CONVERGED
    for _ in range(MAX_ITERATIONS):
        for i in range(s):
            for q in range(n):
                Y[q] = z[q]
            for j in range(s):
                c = h * W[i, j]
                for q in range(n):
                    Y[q] += c * K[1 + j, q]
            kernel.dynamics(fn, d, p, Y, True, K, new + i, pn, False)
        ints[kernel.I_EVALS] += s
        change = _scaled_change(s, n, h, z, K)
        for i in range(s):
            for q in range(n):
                K[1 + i, q] = K[new + i, q]
        if not change < np.inf:  # inf or nan: the stages left the landscape's domain
            code = 1 if change != change else NOT_CONVERGED
            break
        if change <= ROUND_OFF:
            code = 0
            break
        if change >= previous:  # no longer shrinking: at round-off, or diverging
            code = 0 if change <= NOISE else NOT_CONVERGED
            break
        previous = change
    if code != 0:
        return code
    for q in range(n):
        zn[q] = z[q]
    for i in range(s):
        c = h * W[s, i]
        for q in range(n):
            zn[q] += c * K[1 + i, q]
    kernel.rodrigues(zn, R, Rn)
    if not kernel._finite(zn, 0, 5):
        return 1
    if not (kernel._finite(zn, 5, n) and kernel._finite_matrix(Rn)):
        return 2
    last = 2 * s + 1
    kernel.dynamics(fn, d, p, zn, True, K, last, pn, True)
    ints[kernel.I_EVALS] += 1
    if not (kernel._finite_row(K, last, 0, 5) and kernel._finite(pn, 0, kernel.PROBE_SIZE)):
        return 1
    if not kernel._finite_row(K, last, 5, n):
        return 2
    return 0


@JIT
def _scaled_change(s, n, h, z, K):
    """The largest change h |K_new - K_old| of a stage value, relative to the size of its part of
    the state (alpha, v or u) plus how far the stages move it; nan if an iterate is not finite."""
    worst = 0.0
    for lo, hi in ((0, 2), (2, 5), (5, n)):
        scale = 0.0
        for q in range(lo, hi):
            scale = max(scale, abs(z[q]))
            for i in range(s):
                scale = max(scale, abs(h * K[s + 1 + i, q]))
        for q in range(lo, hi):
            for i in range(s):
                delta = abs(h * (K[s + 1 + i, q] - K[1 + i, q]))
                if not delta < np.inf:
                    return np.nan
                if delta > 0.0:  # (a part at rest whose stages still move: a large change)
                    worst = max(worst, delta / scale if scale > 0.0 else 1.0)
    return worst
