"""Sweeps: a scene run over a grid of start values or parameters, with one row of outcomes
per run (``rollball sweep``, ``rollball.sweep``).

The names below are imported when first used (PEP 562): ``rollball.sweeps.options``, which the
command line's help reads, is had without loading the simulation."""

_LAZY = {"Grid": "grid", "KEYS": "options", "MAX_RUNS": "grid", "OUTCOMES": "outcomes", "SweepTable": "table",
         "parse_vary": "grid", "sweep": "runner"}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value   # looked up once
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
