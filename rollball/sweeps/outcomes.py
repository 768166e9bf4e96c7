"""What a sweep reports per run: its status and a row of outcomes.

The runs of the 2011 model, and of a ball that rolls, slips, grips and flies in vacuum, are the
kernel's (``kernel.batch.advance_batch``: each run stepped by ``simulate``'s own fixed-step loop,
its flights by the mode machine's, in batches without the GIL); a scene whose ball can come to
rest runs each run through ``Simulation`` (``batch.run``). Here are the names of the outcomes and
the statuses a sweep adds to the kernel's.
"""

from __future__ import annotations

from .. import kernel

# The kernel's outcomes, then the contact's: the mode at the end (its position in
# trajectory.MODES: 0 rolling, 1 sliding, 2 flying, 3 resting; the CSV writes its name), the number of
# landings, the time of the first slip (0 for a ball sliding from its start; NaN: none) and of
# the first grip (the first slip's end; NaN: none).
CONTACT_OUTCOMES = ("end_mode", "landings", "first_slip_time", "first_grip_time")
# Then the rest's (scene version 4): where (contact point) and when the ball came to rest, from the
# run's "rest" transition (NaN: it never rests), and its basin: the number of the landscape's
# local minimum that the steepest descent from there reaches (``rollball.basins``; 0: none).
REST_OUTCOMES = ("rest_x", "rest_y", "rest_time", "basin")
OUTCOMES = kernel.OUTCOMES + CONTACT_OUTCOMES + REST_OUTCOMES
O_END_MODE, O_LANDINGS, O_FIRST_SLIP, O_FIRST_GRIP = (OUTCOMES.index(name) for name in CONTACT_OUTCOMES)
O_REST_X, O_REST_Y, O_REST_TIME, O_BASIN = (OUTCOMES.index(name) for name in REST_OUTCOMES)

# Status codes beyond the kernel's: a run whose varied scene was refused, and one not run yet.
INVALID, NOT_RUN = 10, kernel.NOT_RUN
