"""Whose a finished run's energy error is (docs/design.md §1): the recorded interval that holds
most of it is taken again with shorter steps (tighter tolerances), and the way its change of
energy shrinks tells the method's error from the landscape's (a jump of the curvature, a kink).
It looks at a run from outside: ``energy_check(run)`` takes a finished ``Simulation`` and makes
runs of its own from the interval's first row (``Simulation.from_state``)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .geometry import unit_normal
from .mode_machine import state_of
from .modes import FLYING, RESTING, ROLLING, Change, Mode, interval_modes
from .run_size import MAX_STEPS
from .tableaus import get_method
from .trajectory import CONTACT, DISSIPATED, ENERGY, ENERGY_WARNING, OMEGA, T, VELOCITY, EnergyCheck, Status


SHORTER = 4            # energy_check takes the interval again with steps 4, 16, 64, 256 times shorter...
LEVELS = 4             # (down to FLOOR)
PHASES = 8             # ...each starting 0, 1/8, ..., 7/8 of such a step late, the largest change counting
FLOOR = 1e-10          # (relative energy changes below this are not used: round-off)
MAX_CHECK_STEPS = 4096  # (nor levels of more steps than this over the interval: a long one is judged coarser)
TIGHTER = 1e4          # ...or, adaptive, with tolerances this many times tighter
MIN_TOLERANCE = 1e-15  # (not below this)
PROBE_ORDER = 3        # methods of lower order (euler) are judged by rk4's changes over the interval
ROUGH_ORDER = 2        # the energy error of a step across a jump of the curvature goes as h^2


def _accounted(rows: np.ndarray) -> np.ndarray:
    """The energy plus what friction and landings dissipated so far, per row (``Trajectory.energy_error``)."""
    return rows[:, ENERGY] + rows[:, DISSIPATED]


def _start_of(run, row: np.ndarray):
    """A recorded row's state as a scene's start (a rolling state is its contact point, its
    centre's horizontal velocity and its spin about the normal), or None where it is not one."""
    x, y = (float(value) for value in row[CONTACT])
    d = run.landscape.evaluate(x, y, run.scene.parameter_values)
    spin = float(np.dot(row[OMEGA], unit_normal(d)))
    vx, vy = (float(value) for value in row[VELOCITY][:2])
    try:
        return dataclasses.replace(run.scene.start, x=x, y=y, vx=vx, vy=vy, spin=spin)
    except ValueError:
        return None


def _run_from(run, row: np.ndarray, mode: Mode, duration: float, **options):
    """The scene run for ``duration`` from a recorded row's state with ``options`` (Simulation's),
    finished; None where it does not end ok. A run that only ever rolls (the 2011 model) starts
    from the row as a scene's start (``_start_of``); one whose contact can change mode from the
    row's whole state (``mode_machine.state_of``, its dissipated energy too) in ``mode`` (ROLLING
    or SLIDING) on a clock from 0, where it may change mode again as the run did."""
    try:
        if run.segmented:
            redo = run.from_state(state_of(run, row), 0.0, mode, t_end=duration, **options)
        else:
            start = _start_of(run, row)
            if start is None:
                return None
            redo = type(run)(dataclasses.replace(run.scene, start=start, duration=duration), **options)
            redo.judge_energy = False  # (the check's own runs are not checked)
            redo.advance(rows=False)
    except ValueError:   # (a SceneError too: an interval shorter than its first step's delay)
        return None
    return redo if redo.status is Status.OK and len(redo.rows) >= 2 else None


def _interval_change(run, row: np.ndarray, mode: Mode, duration: float, delay: float = 0.0,
                     **options) -> float | None:
    """How much E + D (D is 0 where the ball only rolls) changes over the interval of
    ``duration`` taken again from ``row`` in ``mode`` with ``options`` (Simulation's), its first
    step ``delay`` long where ``delay`` > 0 (so that the steps after it fall elsewhere), from the
    state it starts from (``_run_from``); None where a run does not end ok."""
    e0 = None
    if delay > 0.0:
        lead = _run_from(run, row, mode, delay, **{**options, "dt": delay})
        if lead is None or (run.segmented and lead.modes[-1] == FLYING):
            return None
        e0 = float(_accounted(lead.rows[:1])[0])
        row, mode = lead.rows[-1], Mode(int(lead.modes[-1])) if run.segmented else ROLLING
        duration -= delay
    redo = _run_from(run, row, mode, duration, **options)
    if redo is None:
        return None
    energy = _accounted(redo.rows)
    if e0 is None:
        e0 = float(energy[0])
    elif not run.segmented:   # (a run from a scene's start counts D from 0: carry the lead's)
        energy = energy + float(row[DISSIPATED])
    return abs(float(energy[-1]) - e0)


def _judged(run, rows: np.ndarray) -> np.ndarray:
    """Which recorded intervals (rows i to i + 1) the energy check may take again: those the
    contact integrated in one mode, rolling or sliding. A flight and a held ball's stay are
    exact, so an interval in one (``modes.interval_modes``: the stop that begins a stay ends the
    motion before it), or that holds a landing (its impact is counted in D), is not the step's."""
    if not run.segmented:
        return np.ones(len(rows) - 1, dtype=bool)
    contact = ~np.isin(interval_modes(run.modes[: len(rows)])[1:], (FLYING, RESTING))
    t = rows[:, T]
    for change in run.transitions:
        if change.kind is Change.LANDING:
            contact &= ~((t[:-1] < change.time) & (change.time <= t[1:]))
    return contact


def energy_check(run) -> EnergyCheck | None:
    """Whose a finished run's energy error is, where one recorded interval holds most of it
    (at least half; None otherwise, or where the error is below the warning).

    The interval is taken again from its first row's state (``_start_of``) with the same method
    and step, then with steps SHORTER, SHORTER^2, ... (LEVELS of them) times shorter (adaptive:
    once, with tolerances TIGHTER times tighter). On a smooth landscape the energy's change
    shrinks as the method's order p predicts, SHORTER^p per level (TIGHTER) once the steps
    resolve the landscape. Across a jump of the curvature a step's energy error goes as h^2 (its
    error in the state, of order h, is along the flow, where the energy does not change), across
    a kink not at all: however short the steps, the change shrinks by at most SHORTER^2 per
    level. How much it is depends on where in a step the jump falls, so each shorter step is
    taken PHASES times, each starting a fraction of a step later, and the largest change counts.
    The two finest levels whose changes are above FLOOR judge, by the shrink per level between
    them (coarse steps may not yet resolve a smooth landscape, nor show the jump's rate under the
    step's own error; over two levels, one whose phases all fell lucky counts once too high and
    once too low): the landscape's where it is less than the geometric mean of SHORTER^p and
    SHORTER^ROUGH_ORDER (adaptive: the change shrank by less than the square root of TIGHTER).
    A method of order below PROBE_ORDER (euler) cannot
    tell a jump of the curvature so (its own error shrinks more slowly than the jump's), so rk4
    takes the interval again for it."""
    rows = run.rows
    if len(rows) < 2:
        return None
    scene = run.scene
    energy = _accounted(rows)
    scale = max(abs(rows[0, ENERGY]), scene.ball.mass * scene.gravity * scene.ball.radius, np.finfo(float).tiny)
    error = (energy - energy[0]) / scale
    with np.errstate(invalid="ignore"):
        drift = float(np.nanmax(np.abs(error)))
        jumps = np.abs(np.diff(error))
    jumps[~_judged(run, rows)] = np.nan
    if not (drift > ENERGY_WARNING and np.isfinite(jumps).any()):
        return None
    i = int(np.nanargmax(jumps))
    if not jumps[i] >= 0.5 * drift:
        return None
    row, t0, t1 = rows[i], float(rows[i][T]), float(rows[i + 1][T])
    mode = Mode(int(run.modes[i + 1])) if run.segmented else ROLLING   # (the mode that integrated the interval)
    if run.adaptive:
        changes = [_interval_change(run, row, mode, t1 - t0, method=run.tableau.name, dt=run.dt,
                                    rtol=max(run.rtol / tighter, MIN_TOLERANCE),
                                    atol=max(run.atol / tighter, MIN_TOLERANCE * 1e-3), record_dt=t1 - t0)
                   for tighter in (1.0, TIGHTER)]
        if None in changes:
            return None
        expected, threshold = TIGHTER, math.sqrt(TIGHTER)
        finer = "its tolerances and ones 10⁴ times tighter, the tighter"
    else:
        probe = run.tableau if run.tableau.order >= PROBE_ORDER else get_method("rk4")
        same = dict(method=probe.name, munthe_kaas=run.munthe_kaas, record_every=MAX_STEPS)
        changes = [_interval_change(run, row, mode, t1 - t0, dt=run.dt, **same)]
        level = 0
        while (level < LEVELS and changes[-1] is not None and (level == 0 or changes[-1] >= FLOOR * scale)
               and (level == 0 or (t1 - t0) * SHORTER ** (level + 1) <= run.dt * MAX_CHECK_STEPS)):
            level += 1
            h = run.dt / SHORTER ** level
            phases = [_interval_change(run, row, mode, t1 - t0, k * h / PHASES, dt=h, **same) for k in range(PHASES)]
            changes.append(None if None in phases else max(phases))
        if None in changes:
            return None
        if level > 1 and changes[-1] < FLOOR * scale:  # judged by the finest levels above round-off
            level -= 1
        first = max(level - 2, 0)  # over the two finest levels, where there are two
        changes = [changes[first], changes[level]]
        expected = float(SHORTER ** probe.order)
        threshold = SHORTER ** ((probe.order + ROUGH_ORDER) / 2)
        steps = [SHORTER ** k for k in range(first, level + 1)]
        finer = (f"the run's step and one {SHORTER} times shorter, the shorter" if level == 1 else
                 f"steps {', '.join(map(str, steps[:-1]))} and {steps[-1]} times shorter than the run's, each "
                 f"{SHORTER} times shorter" if first > 0 else
                 f"the run's step and ones {', '.join(map(str, steps[1:-1]))} and {steps[-1]} times shorter, each "
                 f"{SHORTER} times shorter")
        if probe is not run.tableau:
            finer = f"{probe.name}, at {finer}"
        if changes[0] < FLOOR * scale:  # the probe's change at the run's step is round-off: smooth to it
            changes = [1.0, 0.0]
    shrink = changes[0] / changes[1] if changes[1] > 0.0 else math.inf
    if not run.adaptive:  # per level: steps SHORTER times shorter
        shrink **= 1 / (level - first)
    x, y = (float(value) for value in row[CONTACT])
    return EnergyCheck(t0, t1, x, y, float(jumps[i]), float(shrink), expected, not shrink >= threshold, finer)
