"""Whether a finished run's changes of contact mode are converged: each slip, grip, lift-off and rest the
kernel located is taken again from the last recorded row before it with shorter steps (tighter
tolerances, adaptive), the way the energy check takes an interval again, and its time must move
as the method's order says (docs/design.md §1, "Are the transitions converged?").

A run whose contact changes mode is a sequence of segments; each change's time is located by the
kernel on the method's own step. Where that placement is wrong (a condition that is not smooth, a
change the steps invent), the run still ends ok: this check is what says so, as data
(``TransitionCheck``, ``Trajectory.transition_check``) and as one of ``Trajectory.warnings()``."""

from __future__ import annotations

import math

import numpy as np

from .mode_machine import state_of
from .trajectory import FLYING, RESTING, SLIDING, SLIP_SPEED, T, Status, Transition
from .transition_verdict import (CHANGED, CONVERGED, GROWS, LOOSE, NAMES, NEGLIGIBLE, PLATEAU, TIGHTER, Retake,
                                 TransitionCheck)

# the kernel's changes and the rest (where it comes to rest at the kernel's stop, or after a spin in place
# from there); a landing is a flight's root (exact) and not retaken
RETAKEN = ("slip", "grip", "liftoff", "rest")
MAX_CHECKED = 8        # the first this many of them are checked (the rest are counted)
HALVINGS = 2           # fixed steps: taken again with the run's dt, dt/2 and dt/4 (phase-aligned: on its grid)
SLACK = 1.5            # a halving must shrink the move at least 2^(p - SLACK)-fold (rk4: 5.7; 16 expected)
ADAPTIVE_SHRINK = TIGHTER ** 0.25  # ...and the move must shrink at least 3.2-fold per 100 times (40 to 100 expected)
MIN_TOLERANCE = 1e-15  # (tolerances not below this, as the energy check's)
MOVE_FLOOR = 1e-10     # s: moves below this are round-off (the kernel locates a change to 1e-13 of a step); adaptive,
                       # also below rtol·√(r/g), what the tolerance allows (the error control's time unit)
LOOSE_FACTOR = 100     # adaptive: a first move above this many times that is a time the tolerance does not allow
                       # (dopri5's grip on the tilted bowl, 3.9e-4 s off at rtol 1e-6 and 8.7e-6 s at 1e-8, 3900 and
                       # 8700 times; the hybrid scenes' other adaptive transitions at most 34 times)
REST_FLOOR = 1e-9      # s: a fixed-step run's rest, where a stop pulled sideways is taken by the stiff stretch
                       # (dop853 at 10⁻¹³ from the grid row before it): that places it within ~2·10⁻¹⁰ s (wells),
                       # not 10⁻¹³ of a step
LEAD_STEPS = 64        # a retake starts this many of the run's steps (its average step, adaptive) before the change, or
                       # where its segment starts if that is later...
MARGIN_STEPS = 2       # ...and goes on until it has the change or is this many past it (one moved further is not there)
MAX_STRETCH_STEPS = 4096  # a change whose row to start from lies more steps before it than this is not taken again
TURNED = 1e-3          # a slip turning about must have stopped: its slip speed there at most this share of its largest

def verdict(times, *, shrink: float, floor: float = MOVE_FLOOR, allowed: float = math.inf) -> str:
    """How a ladder of a transition's times (coarse to fine, each level ``shrink`` times finer in
    what the method's accuracy promises: 2^p per halving for order p, less a slack) converges: None
    in ``times`` (a retake without it) is CHANGED; moves all below ``floor`` NEGLIGIBLE; a first
    move (the run's own error, as the finer retakes tell it) above ``allowed`` LOOSE, however the
    moves shrink; a finest move below ``floor`` or each move at least ``shrink`` times the next
    CONVERGED; a move larger than the one before GROWS; else PLATEAU."""
    if any(t is None for t in times):
        return CHANGED
    moves = [abs(b - a) for a, b in zip(times, times[1:])]
    if all(move <= floor for move in moves):
        return NEGLIGIBLE
    if moves[0] > allowed:
        return LOOSE
    if moves[-1] <= floor:
        return CONVERGED
    if any(b > a for a, b in zip(moves, moves[1:])):
        return GROWS
    if all(a >= shrink * b for a, b in zip(moves, moves[1:])):
        return CONVERGED
    return PLATEAU


def _retake(run, row: np.ndarray, t_row: float, mode: int, t_stop: float, wanted: int,
            **options) -> list[Transition] | None:
    """The transitions of the run taken again from ``row`` (at t_row, in ``mode``) on the run's
    clock, so that fixed steps dt / 2^k fall on its grid (``kernel.grid_steps_before``), with
    ``options`` (Simulation's), until it has ``wanted`` of them or reaches t_stop; None where the
    retake cannot be made, or stops short (not ok) before it had ``wanted`` transitions."""
    try:
        redo = run.from_state(state_of(run, row), t_row, mode, t_end=t_stop, stop_after=wanted, **options)
    except ValueError:
        return None
    changes = list(redo.transitions)
    return changes if redo.status is Status.OK or len(changes) >= wanted else None


def _invented(run, rows: np.ndarray, modes: np.ndarray) -> list[str]:
    """Transitions the run's own sequence shows the motion does not have: one at the instant of the
    one before or earlier (a landing may be followed at once: the impact stuck where rolling needs
    more friction than there is; a ball that grips or lands standing still comes to rest at that
    instant), and a slip that turns about (sliding on, no grip between) where
    the slip had not stopped: its slip speed there above TURNED of its largest since it began."""
    notes = []
    changes = run.transitions
    t = rows[:, T]
    for before, change in zip(changes, changes[1:]):
        at_once_ok = before.kind == "landing" or (change.kind == "rest" and change.time == before.time)
        if not at_once_ok and change.time <= before.time:
            when = "at the instant of" if change.time == before.time else "before"
            notes.append(f"the {NAMES.get(change.kind, change.kind)} at {change.time:.6g} s comes {when} "
                         f"the {NAMES.get(before.kind, before.kind)} before it")
    begun = 0.0
    for change in getattr(run, "changes", changes):   # (turns of a slip too, which are no transitions)
        if change.kind != "slip":
            begun = change.time
            continue
        at = np.flatnonzero((t == change.time) & (modes == SLIDING))
        if len(at):   # a slip out of sliding: the slip turns about
            stretch = (t >= begun) & (t <= change.time) & (modes == SLIDING)
            largest = float(np.max(rows[stretch, SLIP_SPEED]))
            speed = float(rows[at[-1], SLIP_SPEED])
            if speed > TURNED * largest:
                share = "its largest" if speed == largest else f"{speed / largest:.2g} of its largest"
                notes.append(f"the slip at {change.time:.6g} s, a turn of the slip, comes where the slip speed is "
                             f"{speed:.2g} m/s, not 0 ({share} since t = {begun:.6g} s)")
        begun = change.time
    return notes


def check_transitions(run) -> TransitionCheck | None:
    """The check of a finished run whose contact changed mode (None where it did not, or where the
    run is the 2011 model's). Each of the first MAX_CHECKED slips, grips, lift-offs and rests is taken
    again from a recorded row before it that is not itself at such a change nor in a turn over a
    ridge or a tip (``Simulation.turns``: a retake from there could not follow the turn): the last at least
    LEAD_STEPS of the run's steps before it, or its segment's first where that is later (its
    state by ``mode_machine.state_of``, in that row's mode), until the retake has it or is
    MARGIN_STEPS steps past it, and its time read in each retake: fixed steps with the run's dt,
    dt/2 and dt/4, their steps on the run's grid, the moves to shrink 2^(p − SLACK)-fold per
    halving at least; adaptive with the run's tolerances (its own time) and tolerances TIGHTER
    and TIGHTER² times tighter, ADAPTIVE_SHRINK-fold. A retake whose transitions up to it are of
    other kinds, or that has none there, changed it. The run's errors before the retaken stretch
    are not seen: they are carried into every retake alike."""
    if not run.segmented or not run.transitions:
        return None
    tableau = run.tableau
    rows, modes = run.rows, run.modes
    if not len(rows):
        return None
    t = rows[:, T]
    located = {change.time for change in run.transitions if change.kind in RETAKEN}
    usable = ~np.isin(t, list(located))
    for began, ended in run.turns:   # (a turn's rows, from the last state before it, are no kernel run's)
        usable &= (t < began) | (t > ended)
    # (a run that ended ok before t_end came to rest: its retakes may look past that)
    end = run.t_end if run.status is Status.OK else float(t[-1])
    average = (end / run.steps) if run.adaptive and run.steps else run.dt
    retakes, unchecked, skipped = [], 0, 0
    for index, change in enumerate(run.transitions):
        if change.kind not in RETAKEN:
            continue
        if len(retakes) >= MAX_CHECKED:
            unchecked += 1
            continue
        previous = run.transitions[index - 1].time if index else -math.inf
        before = np.flatnonzero(usable & (t < change.time))
        segment = before[t[before] >= previous]   # (a landing's row is the state after it)
        lead = segment[t[segment] <= change.time - LEAD_STEPS * average]
        i = (int(lead[-1]) if len(lead) else int(segment[0]) if len(segment) else
             int(before[-1]) if len(before) else -1)   # (else from its segment's first row, or the last before it)
        if i < 0 or modes[i] in (FLYING, RESTING) or (change.time - t[i]) > MAX_STRETCH_STEPS * average:
            skipped += 1
            continue
        t_row = float(t[i])
        # the run's changes after the row up to this one (a landing, or one at the same instant, may come first)
        sequence = [c.kind for c in run.transitions[: index + 1] if c.time > t_row]
        k = len(sequence)
        t_stop = min(change.time + MARGIN_STEPS * average, end)
        if t_stop <= change.time:   # (a run that stopped at the change: its retakes look past it, as far as they need)
            t_stop = min(change.time + MARGIN_STEPS * average, run.t_end)
        if run.adaptive:
            steps = tuple(max(run.rtol / TIGHTER ** level, MIN_TOLERANCE) for level in range(3))
            results = [list(run.transitions)] + [
                _retake(run, rows[i], t_row, int(modes[i]), t_stop, k, method=tableau, dt=run.dt,
                        rtol=rtol, atol=max(run.atol / TIGHTER ** level, MIN_TOLERANCE * 1e-3),
                        record_dt=t_stop - t_row)
                for level, rtol in enumerate(steps[1:], start=1)]
            results[0] = [c for c in results[0] if c.time > t_row]
            shrink = ADAPTIVE_SHRINK
            floor = max(MOVE_FLOOR, run.rtol * math.sqrt(run.scene.ball.radius / run.scene.gravity))
            allowed = LOOSE_FACTOR * floor
        else:
            steps = tuple(run.dt / 2 ** level for level in range(HALVINGS + 1))
            results = [_retake(run, rows[i], t_row, int(modes[i]), t_stop, k, method=tableau,
                               munthe_kaas=run.munthe_kaas, dt=h, record_every=2 ** 40) for h in steps]
            shrink, floor = 2.0 ** (tableau.order - SLACK), REST_FLOOR if change.kind == "rest" else MOVE_FLOOR
            allowed = math.inf   # (a fixed step promises no time: its moves' shrinking is the test)
        if any(result is None for result in results):   # a retake that failed says nothing
            skipped += 1
            continue
        times, found = [], []
        for result in results:
            kinds = [c.kind for c in result[:k]]
            found.append(", ".join(f"{NAMES.get(c.kind, c.kind)} at {c.time:.6g} s" for c in result[:k]) or
                         f"no change of mode by {t_stop:.6g} s")
            times.append(result[k - 1].time if kinds == sequence else None)
        retakes.append(Retake(index, change.kind, change.time, t_row, steps, tuple(times), tuple(found),
                              verdict(times, shrink=shrink, floor=floor, allowed=allowed), allowed))
    return TransitionCheck(tableau.name, tableau.order, run.adaptive, tuple(retakes), unchecked,
                           tuple(_invented(run, rows, modes)), skipped)
