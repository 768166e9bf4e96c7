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
