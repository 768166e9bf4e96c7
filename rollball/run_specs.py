"""Run specs: a method and how it advances the orientation, ``"rk4"`` (Munthe-Kaas) or
``"rk4/classic"``, read from text by the method's name and kind alone (``kinds``), without
building a tableau: so that the command line and the app refuse a bad spec at once, before the
numerical modules load."""

from __future__ import annotations

from dataclasses import dataclass

from .kinds import ALIASES, KINDS, MethodInfo, MethodKind, method_name


@dataclass(frozen=True)
class RunSpec:
    """A method and how it advances the orientation: ``"rk4"`` (Munthe-Kaas) or ``"rk4/classic"``."""

    method: str
    munthe_kaas: bool = True

    def __post_init__(self):
        method = self.method.name if isinstance(self.method, MethodInfo) else self.method   # a registry entry
        name = method_name(method)  # ValueError listing the valid names
        object.__setattr__(self, "method", name)
        if not isinstance(self.munthe_kaas, bool):
            raise ValueError(f"munthe_kaas must be True or False, not {self.munthe_kaas!r}")
        if not self.munthe_kaas and not self.kind.classic_allowed:
            raise ValueError(f"{name} always advances the orientation by Munthe-Kaas: "
                             f"{name}/classic is not a run; valid runs: {', '.join(valid_specs())}")

    def __str__(self) -> str:
        return self.method if self.munthe_kaas else f"{self.method}/classic"

    @property
    def kind(self) -> MethodKind:
        return KINDS[self.method]

    @property
    def fixed_step(self) -> bool:
        return self.kind.fixed_step

    @property
    def label(self) -> str:
        """For legends and tables: the method's label and, for fixed steps, the scheme."""
        from .tableaus import METHODS

        method = METHODS[self.method]
        if not method.classic_allowed:
            return method.label
        return f"{method.label} {'Munthe-Kaas' if self.munthe_kaas else 'classic'}"


def default_runs() -> list[RunSpec]:
    """Every method in ``KINDS`` (the registry's order), the explicit fixed-step ones both ways."""
    return [RunSpec(name, mk) for name, kind in KINDS.items()
            for mk in ((True, False) if kind.classic_allowed else (True,))]


def valid_specs() -> list[str]:
    return [str(spec) for spec in default_runs()]


def parse_runs(text: str) -> list[RunSpec]:
    """``"euler/classic,rk4,dopri5"`` -> run specs (duplicates dropped); ValueError listing
    the valid specs for anything else."""
    specs = []
    for part in str(text).split(","):
        part = part.strip()
        name, slash, scheme = part.partition("/")
        if name in KINDS or name in ALIASES:
            if slash and scheme != "classic":
                raise ValueError(f"unknown run {part!r}: only /classic may follow a method; "
                                 f"valid runs: {', '.join(valid_specs())}")
            spec = RunSpec(name, not slash)  # ValueError when the method has no classic scheme
        else:
            raise ValueError(f"unknown run {part!r}; valid runs: {', '.join(valid_specs())} "
                             f"(comma-separated)")
        if spec not in specs:
            specs.append(spec)
    return specs
