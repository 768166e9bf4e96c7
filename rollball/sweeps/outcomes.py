"""What a sweep reports per run: its status and a row of outcomes.

The runs themselves are the kernel's (``kernel.loops.advance_batch``: each run stepped by
``simulate``'s own fixed-step loop, in batches without the GIL); here are the
names of the outcomes and the statuses a sweep adds to the kernel's.
"""

from __future__ import annotations

from .. import kernel

OUTCOMES = kernel.OUTCOMES

# Status codes beyond the kernel's: a run whose varied scene was refused, and one not run yet.
INVALID, NOT_RUN = 10, kernel.NOT_RUN
