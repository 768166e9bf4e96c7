"""Sweeps: a scene run over a grid of start values or parameters, with one row of outcomes
per run (``rollball sweep``, ``rollball.sweep``).

The names below are imported when first used (PEP 562): ``rollball.sweeps.options``, which the
command line's help reads, is had without loading the simulation."""

from ..lazy import lazy_names

_LAZY = {"Grid": "grid", "KEYS": "options", "MAX_RUNS": "grid", "OUTCOMES": "outcomes", "SweepTable": "table",
         "parse_vary": "grid", "sweep": "runner"}

__all__ = sorted(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
