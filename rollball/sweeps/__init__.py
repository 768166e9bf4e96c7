"""Sweeps: a scene run over a grid of start values or parameters, with one row of outcomes
per run (``rollball sweep``, ``rollball.sweep``)."""

from .grid import KEYS, MAX_RUNS, Grid, parse_vary
from .outcomes import OUTCOMES
from .runner import sweep
from .table import SweepTable

__all__ = ["Grid", "KEYS", "MAX_RUNS", "OUTCOMES", "SweepTable", "parse_vary", "sweep"]
