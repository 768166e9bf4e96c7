"""The kernel's entry points: what Python calls (by address, through ``machine_code``), one per
function in ``interface.ENTRIES``, each generated from that declaration (``unpacking``).
They are plain functions here: machine_code.py compiles them, so importing the kernel
compiles nothing."""

from __future__ import annotations

from .batch import advance_batch
from .bounces import bounces, impact
from .bounds import bound_boxes
from .feet import nearest_feet
from .flight_rows import flight_rows
from .landing import land
from .loops import advance, advance_adaptive
from .physics import closest_points, evaluate_points
from .unpacking import ENTRY_SIGNATURE, make_entry

FUNCTIONS = {"advance": advance, "advance_adaptive": advance_adaptive, "advance_batch": advance_batch,
             "evaluate_points": evaluate_points, "closest_points": closest_points,
             "nearest_feet": nearest_feet, "land": land, "flight_rows": flight_rows,
             "impact": impact, "bounces": bounces, "bound_boxes": bound_boxes}
ENTRIES = {name: make_entry(name, function) for name, function in FUNCTIONS.items()}

__all__ = ["ENTRIES", "ENTRY_SIGNATURE", "FUNCTIONS"]
