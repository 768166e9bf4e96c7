"""What kind of method a registry entry is, and what follows from its kind."""

from __future__ import annotations

import enum


class MethodKind(str, enum.Enum):
    """How a method steps (scene files, the command line and the app list methods by it)."""

    FIXED = "fixed"        # explicit, fixed step; the orientation classic or Munthe-Kaas
    ADAPTIVE = "adaptive"  # embedded pair with rtol/atol step-size control; Munthe-Kaas only
    IMPLICIT = "implicit"  # implicit, fixed step, symmetric; Munthe-Kaas only

    def __str__(self) -> str:
        return self.value


class MethodInfo:
    """The properties every registry entry derives from its ``kind`` (a base of each entry's
    class: ``Tableau``, ``implicit.Collocation``, ``dop853.DensePair``)."""

    kind: MethodKind

    @property
    def adaptive(self) -> bool:
        return self.kind is MethodKind.ADAPTIVE

    @property
    def fixed_step(self) -> bool:
        """Steps of the size dt (explicit fixed-step and implicit methods)."""
        return self.kind is not MethodKind.ADAPTIVE

    @property
    def classic_allowed(self) -> bool:
        """Whether the orientation may also be integrated as a plain matrix (``munthe_kaas=False``)."""
        return self.kind is MethodKind.FIXED


def cubic_hermite(b, last: int) -> tuple[tuple, ...]:
    """The dense output P (rows K_0 .. K_last, columns theta, theta^2, theta^3) of the cubic
    Hermite interpolant of z_n, K_0 = z'(z_n), z_n+1 = z_n + h sum_i b_i K_i and
    K_last = z'(z_n+1): the coefficients e_0, 3 b - 2 e_0 - e_last and e_0 + e_last - 2 b.
    ``b`` gives a weight for each of the rows 0 .. last (exact or float)."""
    rows = []
    for i in range(last + 1):
        e0, e1 = int(i == 0), int(i == last)
        rows.append((e0 + 0 * b[i], 3 * b[i] - 2 * e0 - e1, e0 + e1 - 2 * b[i]))
    return tuple(rows)
