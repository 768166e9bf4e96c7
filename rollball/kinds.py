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

    @property
    def adaptive(self) -> bool:
        return self is MethodKind.ADAPTIVE

    @property
    def fixed_step(self) -> bool:
        """Steps of the size dt (explicit fixed-step and implicit methods)."""
        return self is not MethodKind.ADAPTIVE

    @property
    def classic_allowed(self) -> bool:
        """Whether the orientation may also be integrated as a plain matrix (``munthe_kaas=False``)."""
        return self is MethodKind.FIXED


# Every method's name and kind, in the order they are listed. The registry (``tableaus.METHODS``)
# holds exactly these, checked when it is built; the command line reads the names here, without
# building a tableau (numpy, exact order conditions), so that its help and its refusals are instant.
KINDS: dict[str, MethodKind] = {
    "euler": MethodKind.FIXED, "rk4": MethodKind.FIXED, "lawson5": MethodKind.FIXED,
    "gauss4": MethodKind.IMPLICIT, "gauss6": MethodKind.IMPLICIT,
    "dopri5": MethodKind.ADAPTIVE, "dop853": MethodKind.ADAPTIVE,
}
# Older names still read (scene files of version 1, the command line, the API).
ALIASES: dict[str, str] = {"adaptive": "dopri5"}


def method_name(name) -> str:
    """The registry's name for ``name`` (one of ``KINDS`` or an alias); a ``ValueError`` listing
    the valid names for anything else."""
    try:
        found = ALIASES.get(name, name)
        if found in KINDS:
            return found
    except TypeError:   # unhashable
        pass
    raise ValueError(f"unknown method {name!r}; valid methods: {', '.join(KINDS)}")


class MethodInfo:
    """The properties every registry entry derives from its ``kind`` (a base of each entry's
    class: ``Tableau``, ``implicit.Collocation``, ``dop853.DensePair``)."""

    kind: MethodKind

    @property
    def adaptive(self) -> bool:
        return self.kind.adaptive

    @property
    def fixed_step(self) -> bool:
        return self.kind.fixed_step

    @property
    def classic_allowed(self) -> bool:
        return self.kind.classic_allowed


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
