"""The contact's mode machine (docs/design.md §1): a run whose ball can slide, fly and land is a
sequence of kernel runs, each in one mode, and flights between them. The machine holds the rows
they recorded and the mode of each, and decides at every stop of a kernel run what comes next:
a slip or a grip (a kernel run in the new mode from the state where it happened), a lift-off (a
flight, from a kink, a tip, or the tangent plane), a landing (the impact, then a bounce or
contact), a stop (the ball rests, spins in place, or is pulled on: ``resting``) or a stretch
where the slip, or a rolling ball's ω_t near a stop, is too stiff for fixed steps (an adaptive
pair takes it, docs/design.md §8 and §1 "Dissipation").
``Simulation`` runs the kernel and hands each stop to ``ModeMachine.stopped``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from . import kernel, sliding
from .drag_flight import new_flight
from .flight import Flight, FreeState, OffLandscape, Surface, energy, impact, rest_speed
from .geometry import rotation, unit_normal, unit_normal_of
from .modes import AFTER, Change, Mode
from .resting import Spin, holds
from .ridge import END, LIFTOFF, SLIP, TIME, Ridge, edge_force, edge_return, past_edge, turn_over
from .run_size import MAX_ROWS
from .tip import Tip, foot_on_face, onto_face, turn_about
from .trajectory import (CAUSES, CENTER, CONTACT, DISSIPATED, ENERGY, FLIGHT_REASONS, NORMAL_FORCE, OMEGA, R,
                         SLIP_SPEED, T, VELOCITY, Failure, Liftoff, Reason, Status, Transition)

# A friction coefficient above this acts as this one: "always enough friction" as far as a double
# can tell (μ F_n stays finite for F_n up to 10²⁰⁸ N; a slide on a plane grips after 2 v₀/(7 μ g),
# 10⁻¹⁰⁰ s here), where μ F_n itself overflowed to inf and inf − inf, 0 · inf made the friction
# bound NaN.
FRICTION_CAP = 1e100
MAX_AT_ONCE = 16   # changes of mode at one instant after which a run stops (it would never move on)
# A fixed-step run takes its steps where a slip's direction is stiff (friction would stop the
# slip within a step), or a rolling ball's ω_t's (rolling resistance would stop it within a step,
# or it turns faster than the step can follow), with this adaptive pair at this tolerance, far
# below the fixed steps' own error (docs/design.md §8): in the kernel (``kernel.advance``'s pair);
# a classic run stops there instead (kernel.T_STIFF) and takes the stretch here, STIFF_WINDOW steps
# of the grid at a time (twice as many while it cannot go on), to the first step on its grid where
# it can.
STIFF_METHOD = "dop853"
# The tolerance of a run whose couples can bring the ball to rest: a rest after a turning point
# slower than 10⁻⁴ m/s moves 10³ times its error. Without them the stretches are a slip's, whose
# grip moves by less than the tolerance (1.6·10⁻¹³ s on the bench's slipping bowl from 10⁻¹³ to
# 10⁻¹²), at a fifth fewer evaluations; at 10⁻¹¹ gauss6's finest grips in
# tests/test_hybrid_convergence.py stop converging (docs/design.md §8).
STIFF_TOLERANCE = 1e-13
SLIP_TOLERANCE = 1e-12
STIFF_WINDOW = 16

SIDE = 1e-7   # × (1 + |x| + |y|): where the far face of a ridge is evaluated past its edge
RING_COS, RING_SIN = np.cos(np.arange(8) * (np.pi / 4)), np.sin(np.arange(8) * (np.pi / 4))   # (``_at_tip``)
SPIN_ROUND_OFF = 1e-12   # a held ball's r |ω·N| below this share of the run's largest speed (or √(g r)) is no spin
# What ``ModeMachine._bounces`` leaves ``_fly`` to do: nothing (DONE), or search the current
# flight's landing with flight.py's own search (SEARCH)
DONE, SEARCH = object(), object()


def stiff_tolerance(contact) -> float:
    """The stiff stretches' tolerance (rtol and atol) for a run with this ``Contact``: STIFF_TOLERANCE
    where rolling resistance or spin friction can stop the ball, else SLIP_TOLERANCE."""
    return STIFF_TOLERANCE if contact.rolling_resistance or contact.spin_friction else SLIP_TOLERANCE


def friction_of(contact) -> float:
    """The contact's μ as the machine and the kernel use it: a number, inf for "always enough
    friction to roll" (a scene's null), at most FRICTION_CAP where it is finite."""
    return math.inf if contact.friction is None else min(contact.friction, FRICTION_CAP)


def state_of(run, row: np.ndarray) -> sliding.BallState:
    """A recorded row's state, the same in every mode (contact point, ċ, ω, R, D), with ċ in the
    tangent plane at the contact point: a sliding run's ċ drifts off it by the step's error (its
    normal part is not a variable of the motion, only kept at 0 by F_n), and the exact motion
    from a state off it does not keep E + D."""
    x, y = (float(value) for value in row[CONTACT])
    normal = unit_normal(run.landscape.evaluate(x, y, run.scene.parameter_values))
    velocity = row[VELOCITY] - np.dot(row[VELOCITY], normal) * normal
    return sliding.BallState(x, y, velocity, row[OMEGA].copy(), row[R].reshape(3, 3).copy(), float(row[DISSIPATED]),
                             tuple(float(value) for value in row[CAUSES]))


class ModeMachine:
    """The modes of one run (``Simulation``) whose contact can change mode: its rows, the mode of
    each, its transitions, and what happens at each change (module docstring).

    ``stop_after``: the run ends (ok) once it has this many transitions, before what follows
    them is started (a flight, the next kernel run): a transition's retake looks at no more."""

    def __init__(self, run, mode: Mode, rows: int, *, stop_after: int | None = None):
        self.run = run
        self.mode = mode
        self.starts: list[tuple[int, Mode]] = [(0, mode)]   # (first row, mode) where the mode changes
        self.out = np.empty((rows, kernel.ROW_SIZE))
        self.count = 0              # rows in ``out``
        self.taken = 0              # the current kernel run's rows already moved to ``out``
        self.skip_first = False     # its first row repeats the last one (a slip or a grip)
        self.changes: list[Transition] = []       # every change the kernel runs stopped at
        self.transitions: list[Transition] = []   # the run's transitions (a slip turning about is none)
        # (start, end) s of each turn over a ridge or a tip: its rows are no kernel run's (``_end_turn``)
        self.turns: list[tuple[float, float]] = []
        self.flight: Flight | None = None
        self.spin: Spin | None = None   # a held ball's stay (spinning in place, or still), taken whole
        self.rest: Transition | None = None   # where the ball came to rest
        self.surface = Surface(run.landscape, run.scene.parameter_values)
        self.first_liftoff: Liftoff | None = None
        self.dissipated = 0.0       # J: what a flight carries
        self.causes = (0.0, 0.0, 0.0)   # J: the part of it rolling resistance, spin friction and air took
        self.off: Failure | None = None   # a flight found no surface below the ball, or a tip too slow to leave
        self.stall: str | None = None     # why the contact's modes could not go on
        self.stop_after = stop_after
        # a kernel run writes its rows straight into ``out`` from row ``base`` on (``shared_rows``):
        # no second buffer of them
        self.base = 0
        self.saved: np.ndarray | None = None   # the row its first row lands on, put back (``collect``)

    # -- the rows ---------------------------------------------------------------------------------

    @property
    def rows(self) -> np.ndarray:
        return self.out[: self.count]

    def modes(self, count: int) -> np.ndarray:
        """The mode of each of the first ``count`` rows (positions in ``modes.MODES``)."""
        codes = np.empty(count, dtype=np.int8)
        starts = self.starts + [(count, None)]
        for (first, mode), (end, _) in zip(starts, starts[1:]):
            codes[first:end] = mode
        return codes

    def restart(self, mode: Mode) -> None:
        """Begin anew in ``mode`` (a run from a recorded state: no rows yet, nor a stay its
        scene's start had, ``hold_at_start``)."""
        self.mode, self.starts = Mode(mode), [(0, Mode(mode))]
        self.spin = self.rest = None

    def append(self, rows: np.ndarray) -> None:
        """Add rows to the run's rows (growing the buffer), in the current mode."""
        if not len(rows):
            return
        if self.starts[-1][1] != self.mode:
            self.starts.append((self.count, self.mode))
        need = self.count + len(rows)
        if need > len(self.out):
            if need > MAX_ROWS:
                raise ValueError(f"this run would record more than {MAX_ROWS:,} rows")
            self._grow(self.count, need)
        self.out[self.count: need] = rows
        self.count = need

    def shared_rows(self, repeat: bool, rows: int) -> np.ndarray:
        """The rows a kernel run writes to (``Simulation._room``): ``out`` from the
        run's next row on, room for ``rows`` made (``repeat``: from its last row, which the
        kernel's first row, the same state again, lands on and ``collect`` puts back)."""
        self.base = self.count - (1 if repeat else 0)
        self.saved = self.out[self.base].copy() if repeat else None
        if self.base + rows > len(self.out):
            self._grow(self.count, self.base + rows)
        return self.out[self.base:]

    def grow_shared(self, written: int) -> np.ndarray | None:
        """More room for the kernel run writing into ``out`` (``written`` rows of it so far), as
        its rows from ``base`` on; None at MAX_ROWS."""
        if len(self.out) >= MAX_ROWS:
            return None
        self._grow(self.base + written, 2 * len(self.out))
        return self.out[self.base:]

    def _grow(self, used: int, need: int) -> None:
        grown = np.empty((min(max(2 * len(self.out), need), MAX_ROWS), kernel.ROW_SIZE))
        grown[:used] = self.out[:used]
        self.out = grown

    def collect(self) -> None:
        """Take the current kernel run's new rows as the run's rows, and keep the first lift-off
        it found (where the ball flies, a transition's)."""
        run = self.run
        count = int(run._ints[kernel.I_ROWS])
        start = self.taken
        if self.skip_first and start == 0 and count > 0:
            start = 1
            self.out[self.base] = self.saved
        if count > start:   # (written in place)
            if self.starts[-1][1] != self.mode:
                self.starts.append((self.count, self.mode))
            self.count = self.base + count
        self.taken = count
        info = run._info
        if self.first_liftoff is None and not math.isnan(info[kernel.F_LIFTOFF]):
            self.first_liftoff = Liftoff(float(info[kernel.F_LIFTOFF]), float(info[kernel.F_LIFT_X]),
                                         float(info[kernel.F_LIFT_Y]), bool(info[kernel.F_LIFT_KINK]))

    def new_kernel_run(self, repeat: bool) -> None:
        """A new kernel run's rows begin, written into ``out`` (``shared_rows``; ``repeat``: its first
        row is the run's last row again)."""
        self.taken, self.skip_first = 0, repeat

    # -- a kernel run stopped at a change ------------------------------------------------------

    def stopped(self) -> None:
        """The kernel run stopped where the contact changes mode: go on in the new one."""
        run = self.run
        info = run._info
        stiff = None if run.adaptive else run.stiff_drag_row(run.dt, run._rows[:int(run._ints[kernel.I_ROWS])])
        if stiff is not None:   # (an unstable step's absurd state is no change of mode)
            run._finish_kernel_run()
            self.off, run.status = stiff, Status.NONFINITE
            return
        if int(run._ints[kernel.I_TRANSITION]) == kernel.T_STIFF:
            run._finish_kernel_run()
            self._stiff_stretch()
            return
        kind = Change(kernel.transition_name(int(run._ints[kernel.I_TRANSITION])))
        t = float(info[kernel.F_EVENT_T])
        x, y = float(info[kernel.F_EVENT_X]), float(info[kernel.F_EVENT_Y])
        change = Transition(t, kind, x, y)
        self.changes.append(change)
        if not (kind is Change.SLIP and self.mode is Mode.SLIDING) and kind is not Change.REST:
            # (a slip whose speed fell to zero where rolling needs more friction than μ F·N turns
            # about and goes on: the same slip, no new transition; a stop is a rest only where
            # the ball is held and does not spin, ``stay``)
            self.transitions.append(change)
        run._finish_kernel_run()
        at_once = self.changes[-MAX_AT_ONCE:]
        if len(at_once) == MAX_AT_ONCE and all(change.time == t for change in at_once):
            self.stall = (f"the contact changes mode {MAX_AT_ONCE} times at t = {t:.6g} s, (x, y) = ({x:.6g}, {y:.6g}) "
                          f"({', '.join(sorted({str(change.kind) for change in at_once}))}) without the time moving "
                          f"on: rolling needs more friction than μ F·N there, and sliding stops at once, so the run "
                          f"cannot go on")
            run.status = Status.NONFINITE
            return
        if kind is Change.LIFTOFF:
            self._lift_off(t, x, y)
            if run.status is None:
                self._enough()
            return
        if self._enough():
            return
        if kind is Change.REST and self.hold(self.out[self.count - 1], t):
            return
        state = sliding.stopped_state(run._z, run._R, run._p, run._probe_normal())
        # (a stop where the ball is not held: it rolls on from there, pulled by gravity, no time lost)
        self.mode = Mode.ROLLING if kind is Change.REST else AFTER[kind]
        self.dissipated, self.causes = state.dissipated, state.dissipated_by
        run._start_kernel_run(state, t, slides=kind is Change.SLIP, repeat=True)

    # -- a ball that stops (docs/design.md §1, "Rest") --------------------------------------------

    def hold(self, row: np.ndarray, t: float) -> bool:
        """Whether the ball, still in ``row`` at t (its centre's velocity 0, ω along the normal up
        to the kernel's accuracy), is held there (``resting.holds``): then it stays, spinning in
        place at ω·N, taken whole by ``stay``; False where it is pulled on."""
        run = self.run
        scene = run.scene
        contact, ball = scene.contact, scene.ball
        x, y = (float(value) for value in row[CONTACT])
        normal = unit_normal(run.landscape.evaluate(x, y, scene.parameter_values))
        if not holds(normal, rolling_resistance=contact.rolling_resistance, friction=friction_of(contact)):
            return False
        spin = float(np.dot(row[OMEGA], normal))
        # (a spin the kernel's round-off of ω makes, not the motion: below that of the speeds)
        scale = max(float(np.max(np.linalg.norm(self.rows[:, VELOCITY], axis=1))) if self.count else 0.0,
                    math.sqrt(scene.gravity * ball.radius))
        if abs(spin) * ball.radius <= SPIN_ROUND_OFF * scale:
            spin = 0.0
        self.spin = Spin(t, spin, normal, row[R].reshape(3, 3).copy(), row.copy(), ball.mass, ball.radius,
                         scene.gravity, contact.spin_friction)
        self.mode = Mode.RESTING
        if self.count and self.out[self.count - 1, T] == t:   # the row at the stop is the stay's first
            self._last_row_in(Mode.RESTING)
        return True

    def _last_row_in(self, mode: Mode) -> None:
        """Put the last row recorded in ``mode`` (the rows after it follow in ``self.mode``)."""
        last = self.count - 1
        if self.starts[-1][0] == last:
            self.starts.pop()
        if self.starts[-1][1] != mode:
            self.starts.append((last, mode))

    def hold_at_start(self, x: float, y: float, spin: float) -> None:
        """A run that starts with the ball still at (x, y), spinning at ``spin`` about the normal:
        held there, it stays from t = 0 (``hold``); else the kernel run starts as armed."""
        run = self.run
        scene = run.scene
        d = run.landscape.evaluate(x, y, scene.parameter_values)
        normal = unit_normal(d)
        row = np.zeros(kernel.ROW_SIZE)
        row[CONTACT] = x, y
        row[CENTER] = np.array([x, y, float(d[0])]) + scene.ball.radius * normal
        row[OMEGA] = spin * normal
        row[R] = np.eye(3).ravel()
        if np.isfinite(row).all() and self.hold(row, 0.0):
            self.mode, self.starts = Mode.RESTING, [(0, Mode.RESTING)]

    def stay(self) -> None:
        """Take a held ball's stay whole (``hold``): rows at the run's recording times while it
        spins in place, the rest where its spin reaches 0 (transition "rest"; with the scene's
        ``stop_at_rest`` the run ends there, ok), then still rows to the run's end."""
        run, spin = self.run, self.spin
        self.spin = None
        t_end, t_stop = run.t_end, spin.stop_time
        if not self.count:   # (a run that starts held: its first row)
            self.append(spin.rows(np.array([spin.t0])))
        if t_stop > spin.t0:
            self.append(spin.rows(self.record_times(spin.t0, min(t_stop, t_end))))
        if t_stop > t_end:
            self.append(spin.rows(np.array([t_end])))
            run.status = Status.OK
            return
        if t_stop > spin.t0:
            self.append(spin.rows(np.array([t_stop])))
        if self.rest is None:   # (else it came to rest before, in a stretch taken apart)
            x, y = spin.contact
            self.rest = Transition(t_stop, Change.REST, x, y)
            self.transitions.append(self.rest)
            if self._enough():
                return
        if run.scene.stop_at_rest or not t_end > t_stop:
            run.status = Status.OK
            return
        self.append(spin.rows(np.append(self.record_times(t_stop, t_end), t_end)))
        run.status = Status.OK

    def carry(self, row: np.ndarray) -> None:
        """Carry the energy dissipated in ``row``, and by which cause, into what comes next (a flight)."""
        self.dissipated = float(row[DISSIPATED])
        self.causes = tuple(float(value) for value in row[CAUSES])

    def _carried(self, rows: np.ndarray) -> np.ndarray:
        """A flight's rows with the energy the causes took before it added to what they take in it."""
        if any(self.causes):   # (nothing to add to the rows of a run that has lost nothing to them)
            rows[:, CAUSES] += self.causes
        return rows

    def _enough(self) -> bool:
        """Whether the run has the transitions it was to look for (``stop_after``): it ends ok."""
        if self.stop_after is not None and len(self.transitions) >= self.stop_after:
            self.flight, self.run.status = None, Status.OK
            return True
        return False

    def _lift_off(self, t: float, x: float, y: float) -> None:
        """The ball leaves the surface at (x, y) at t: a flight from the kernel run's last state."""
        run, info = self.run, self.run._info
        last = self.out[self.count - 1]
        self.carry(last)
        before = self.mode
        # the flight leaves along the tangent plane: a sliding state's c'.N is the integrator's
        # drift (0 in the exact motion), and a c' into the surface would land it at once
        start = FreeState.from_row(last)
        if info[kernel.F_LIFT_KINK] == kernel.LIFT_TIP:
            force = self._pivot_force(start, x, y)
            if force > 0.0 and before is Mode.ROLLING and self._turn_about_tip(start, x, y):
                return
            if force > 0.0:   # too slow to leave the tip, and sliding: the ball would slide over it
                self._no_liftoff()
                self.off = Failure(Reason.PIVOT, t, x, y, force)
                run.status = Status.DOES_NOT_FIT
                return
        # a tip left (or one F·N reached 0 within round-off of) is measured directly in the flight's
        # distances too: Newton's method finds no closest point there
        point = np.array([x, y, float(run.landscape.evaluate(x, y, run.scene.parameter_values)[0])])
        if (self._at_tip(x, y) and np.isfinite(point).all()
                and not any(np.array_equal(point, known) for known in self.surface.tips)):
            self.surface.tips.append(point)
        normal = run._probe_normal()
        v, n = start.velocity, normal   # (the sweeps' batch loop's numbers, ``kernel.batch.leave``)
        along = float(v[0]) * float(n[0]) + float(v[1]) * float(n[1]) + float(v[2]) * float(n[2])
        start = dataclasses.replace(start, velocity=v - along * n)
        if info[kernel.F_LIFT_KINK] == 1.0 and t > start.t:
            # a ridge's kink: the run's last state is the last one before it (the kink is located
            # between it and the step's end); the ball is on the surface up to the kink, so it
            # rolls (slides) there along the tangent plane and the flight starts at the kink
            start = self._to_kink(start, t, normal, before)
            found = self._ridge(start, x, y)   # (None: no ridge there to turn over or come down on)
            if found is not None:
                ridge_line, beyond = found
                if before is Mode.ROLLING and self._turn_over(start, x, y, ridge_line, beyond):
                    return
                if before is Mode.SLIDING and self._slides_onto_edge(start, t, x, y, ridge_line):
                    return
                if self._lands_on_edge(start, x, y, ridge_line):
                    return
        self.mode = Mode.FLYING
        self.flight = self._new_flight(start)

    def _no_liftoff(self) -> Transition:
        """The lift-off the kernel run stopped at is none (the ball stays on the surface there)."""
        lift = self.transitions.pop()
        if self.first_liftoff is not None and self.first_liftoff.time == float(self.run._info[kernel.F_LIFTOFF]):
            self.first_liftoff = None
        return lift

    def _turn_over(self, start: FreeState, x: float, y: float, ridge_line: Ridge, beyond: np.ndarray) -> bool:
        """A rolling ball at a ridge's edge (x, y) at ``start``: where it is too slow to leave the
        edge it turns over it (``ridge.turn_over``), and then rolls on the far face, rolls back
        on the near one, flies off the edge, or stops where the friction cannot hold the turn;
        False where it leaves the edge at once (it flies from ``start``). ``ridge_line`` and ``beyond``:
        ``_ridge``'s."""
        run = self.run
        scene = run.scene
        scale = 1.0 + abs(x) + abs(y)
        ball = scene.ball
        turn = turn_over(ridge_line, start, radius=ball.radius, mass=ball.mass, gravity=scene.gravity,
                         friction=friction_of(scene.contact), t_end=run.t_end,
                         times=self.record_times(start.t, run.t_end))
        if turn is None or not self._end_turn(turn, start.t, Reason.RIDGE_SLIP):
            return turn is not None
        # on a face: rolling on from a little past the edge
        face = beyond if turn.how == END else ridge_line.near
        tau = past_edge(turn.state, face, gravity=scene.gravity, scale=scale)
        on = self._to_kink(turn.state, turn.state.t + tau, face, Mode.ROLLING)   # (along the face's plane)
        foot = on.center - ball.radius * face
        state = sliding.BallState(float(foot[0]), float(foot[1]), on.velocity, on.omega, on.R, self.dissipated,
                                  self.causes)
        run._start_kernel_run(state, on.t, slides=False, repeat=False)
        return True

    def _ridge(self, start: FreeState, x: float, y: float) -> tuple[Ridge, np.ndarray] | None:
        """The ridge whose edge the ball at ``start`` reached at (x, y) (``Ridge``: the near face's
        normal along the arm from the edge to the centre), and the far face's unit normal, a little
        past the edge along the ball's heading; None where the two faces make no ridge."""
        run = self.run
        values = run.scene.parameter_values
        point = np.array([x, y, float(run.landscape.evaluate(x, y, values)[0])])
        heading = start.velocity[:2] / max(float(np.linalg.norm(start.velocity[:2])), 1e-300)
        scale = 1.0 + abs(x) + abs(y)
        beyond = unit_normal(run.landscape.evaluate(x + SIDE * scale * heading[0], y + SIDE * scale * heading[1],
                                                    values))
        arm = start.center - point
        ridge_line = Ridge.between(point, arm / float(np.linalg.norm(arm)), beyond)
        if ridge_line is None or not np.isfinite(beyond).all():
            return None
        return ridge_line, beyond

    def _slides_onto_edge(self, start: FreeState, t: float, x: float, y: float, ridge_line: Ridge) -> bool:
        """Whether a sliding ball reaching the edge of ``ridge_line`` at (x, y) at ``start`` is too slow
        to leave it (``ridge.edge_force`` above 0): a real ball would turn over the edge rubbing on it,
        which the model does not follow, and the run stops there (``ridge_pivot``), as at a tip
        (``pivot``); a flight from the edge would land on it at once."""
        ball = self.run.scene.ball
        force = edge_force(ridge_line, start, radius=ball.radius, mass=ball.mass, gravity=self.run.scene.gravity)
        if force is None or not force > 0.0:
            return False
        self._no_liftoff()
        self.off = Failure(Reason.RIDGE_PIVOT, t, x, y, force)
        self.run.status = Status.DOES_NOT_FIT
        return True

    def _lands_on_edge(self, start: FreeState, x: float, y: float, ridge_line: Ridge) -> bool:
        """Whether the ball leaving the edge of ``ridge_line`` at (x, y) at ``start`` comes down on that edge
        again before it is past it (``ridge.edge_return``: it left the edge only just, F·e a little
        below 0): a landing on an edge, which the model does not follow (its flight's landing search
        measures the faces, and found a landing later on the edge that was not one). The run stops at
        the lift-off (``edge_landing``, the flight's time to the edge in the failure's value)."""
        back = edge_return(ridge_line, start, gravity=self.run.scene.gravity)
        if back is None:
            return False
        self.off = Failure(Reason.EDGE_LANDING, start.t, x, y, back)
        self.run.status = Status.DOES_NOT_FIT
        return True

    def _end_turn(self, turn, began: float, slip: Reason) -> bool:
        """A turn over a ridge or a tip (``ridge.Turn``) begun at ``began`` as the run's rows, its
        span among ``turns``, and how it ends: at the run's end, stopped where the friction cannot
        hold it (``slip`` the reason), or off the edge or tip where holding it would need a pull (a
        flight from there); True where it ends on a face (the caller starts the rolling run there)."""
        run = self.run
        lift = self._no_liftoff()
        self.mode = Mode.ROLLING
        self._append_turn(turn)
        self.turns.append((began, turn.state.t))
        t, (cx, cy) = turn.state.t, turn.contact
        if turn.how == TIME:
            run.status = Status.OK
        elif turn.how == SLIP:
            self.off = Failure(slip, t, cx, cy, turn.force)
            run.status = Status.DOES_NOT_FIT
        elif turn.how == LIFTOFF:   # off the edge or tip where holding it would need a pull
            self.transitions.append(dataclasses.replace(lift, time=t, x=cx, y=cy))
            if self.first_liftoff is None:
                self.first_liftoff = Liftoff(t, cx, cy, True)
            self.mode = Mode.FLYING
            self.flight = self._new_flight(turn.state)
        else:
            return True
        return False

    def _turn_about_tip(self, start: FreeState, x: float, y: float) -> bool:
        """A rolling ball at a tip near (x, y) at ``start``, too slow to leave it, turns over it
        (``tip.turn_about``), and then rolls on a face of it, flies off it, or stops where the
        friction cannot hold the turn (docs/design.md §1, "A tip"); False where no tip is found
        there to turn about, or the turn cannot be integrated (the run stops, ``pivot``)."""
        run = self.run
        scene = run.scene
        values = scene.parameter_values
        found = Tip.near(x, y, lambda xs, ys: run.landscape.evaluate(xs, ys, values))
        if found is None:
            return False
        if not any(np.array_equal(found.point, known) for known in self.surface.tips):
            self.surface.tips.append(found.point)
        ball = scene.ball
        turn = turn_about(found, start, run._probe_normal(), radius=ball.radius, mass=ball.mass, gravity=scene.gravity,
                          friction=friction_of(scene.contact), t_end=run.t_end,
                          times=self.record_times(start.t, run.t_end))
        if turn is None or not self._end_turn(turn, start.t, Reason.TIP_SLIP):
            return turn is not None
        tau, face = onto_face(found, turn.state, gravity=scene.gravity)
        on = self._to_kink(turn.state, turn.state.t + tau, face, Mode.ROLLING)   # (along the face's plane)
        x, y = foot_on_face(found, on.center, lambda px, py: run.landscape.evaluate(px, py, values), radius=ball.radius)
        state = sliding.BallState(float(x), float(y), on.velocity, on.omega, on.R, self.dissipated, self.causes)
        run._start_kernel_run(state, on.t, slides=False, repeat=False)
        return True

    def _append_turn(self, turn) -> None:
        """The rows of a turn over a ridge (rolling: no slip, nothing dissipated)."""
        scene = self.run.scene
        m, r, g0 = scene.ball.mass, scene.ball.radius, scene.gravity
        rows = np.zeros((len(turn.states), kernel.ROW_SIZE))
        for row, state, contact, force in zip(rows, turn.states, turn.contacts, turn.forces):
            row[T] = state.t
            row[CONTACT] = contact
            row[CENTER] = state.center
            row[VELOCITY] = state.velocity
            row[OMEGA] = state.omega
            row[R] = state.R.ravel()
            row[ENERGY] = energy(state.velocity, state.omega, state.center[2], m, r, g0)
            row[NORMAL_FORCE] = force
            row[DISSIPATED] = self.dissipated
            row[CAUSES] = self.causes
        self.append(rows)

    def _to_kink(self, start: FreeState, t: float, normal: np.ndarray, mode: Mode) -> FreeState:
        """The state at the kink's time t from ``start`` (the last state before it, τ = t − t₀ earlier),
        moving in the tangent plane of ``normal`` as on that plane: rolling with acceleration
        (5/7) g_t and ω = N × ċ/r plus its spin about N (this keeps E exactly), sliding with
        g_t − μ g₀ N_z û (u the slip velocity) and the torque of that friction. Over the short
        τ the surface's bending moves the centre off the plane by about κ|ċ|²τ²/2. (Also the few
        nanometres from a ridge's edge onto a face after a turn over it, ``ridge.past_edge``.)"""
        scene = self.run.scene
        tau = t - start.t
        r, g0 = scene.ball.radius, scene.gravity
        gravity = np.array([0.0, 0.0, -g0])
        tangential = gravity - float(np.dot(gravity, normal)) * normal
        omega = start.omega
        mu = friction_of(scene.contact)
        sliding_now = mode is Mode.SLIDING and mu < math.inf
        if sliding_now:
            slip = start.velocity + np.cross(omega, -r * normal)
            slip -= float(np.dot(slip, normal)) * normal
            speed = float(np.linalg.norm(slip))
            friction = -mu * g0 * float(normal[2]) * slip / speed if speed > 0.0 else np.zeros(3)
            acceleration = tangential + friction
            omega = omega - (5.0 / (2.0 * r)) * np.cross(normal, friction) * tau
            self.dissipated += scene.ball.mass * mu * g0 * float(normal[2]) * speed * tau
        else:
            acceleration = (5.0 / 7.0) * tangential
        velocity = start.velocity + acceleration * tau
        if not sliding_now:
            omega = np.cross(normal, velocity) / r + float(np.dot(start.omega, normal)) * normal
        center = start.center + start.velocity * tau + 0.5 * acceleration * tau * tau
        R = rotation(0.5 * (start.omega + omega) * tau) @ start.R
        return FreeState(t, center, velocity, omega, R)

    def _at_tip(self, x: float, y: float) -> bool:
        """Whether (x, y) is (within 10⁻⁶ of) a point where the normal turns through a finite angle:
        the unit normals on a ring of that radius about it differ by more than 10⁻² (a smooth
        surface's by about its curvature times 10⁻⁶)."""
        run = self.run
        ring = kernel.TIP_RING * (1.0 + abs(x) + abs(y))
        d = run.landscape.evaluate(x + ring * RING_COS, y + ring * RING_SIN, run.scene.parameter_values)
        # (``unit_normal``'s numbers, in Python's floats; a pair with a normal not finite: a NaN apart, not counted)
        normals = [unit_normal_of(fx, fy) for fx, fy in zip(d[1].tolist(), d[2].tolist())]
        first = normals[0]
        if all(math.dist(first, b) < 0.49e-2 for b in normals[1:]):   # (no pair is 10⁻² apart then)
            return False
        return any(math.dist(a, b) > 1e-2 for i, a in enumerate(normals) for b in normals[i + 1:])

    def _pivot_force(self, start: FreeState, x: float, y: float) -> float:
        """F·N (N) the ball at ``start`` would need to turn about the tip at (x, y): its centre on
        the sphere about the tip, m (g₀ e_z − |ċ_t|² / |c − T|) for e the unit vector from the tip T
        to the centre and ċ_t the velocity across it (docs/design.md §1, "A tip"). At most 0: the
        ball leaves the tip as it reaches it."""
        scene = self.run.scene
        f = float(self.run.landscape.evaluate(x, y, scene.parameter_values)[0])
        arm = start.center - np.array([x, y, f])
        distance = float(np.linalg.norm(arm))
        e = arm / distance
        across = start.velocity - float(np.dot(start.velocity, e)) * e
        return scene.ball.mass * (scene.gravity * e[2] - float(np.dot(across, across)) / distance)

    # -- a stretch where the slip is stiff (docs/design.md §8) ------------------------------------

    def _stiff_stretch(self) -> None:
        """The classic fixed-step kernel run (a Munthe-Kaas one takes these steps with the pair
        itself) stopped before a step where the slip's direction is stiff, or a rolling ball's
        ω_t's against rolling resistance (kernel.T_STIFF): that direction relaxes
        at the rate |B| / |u| (the pull's |G| / |ω_t|) and turns with B (G), which no fixed step can
        follow at its order. That stretch is taken by STIFF_METHOD at ``stiff_tolerance`` (every
        transition in it too, a rest where ω_t reaches 0), recording every step of the run's grid;
        the fixed steps go on from the first grid time where the ball is in another mode, or its
        direction is no longer stiff: its rows and transitions up to there are the run's."""
        run = self.run
        t = float(run._info[kernel.F_EVENT_T])
        state = sliding.stopped_state(run._z, run._R, run._p, run._probe_normal())
        mode, window = self.mode, STIFF_WINDOW
        while True:
            t1 = (kernel.grid_steps_before(t, run.dt) + window) * run.dt
            if not run.t_end - t1 > kernel.GRID_SLIVER * run.dt:
                t1 = run.t_end
            tolerance = stiff_tolerance(run.scene.contact)
            stretch = run.from_state(state, t, mode, t_end=t1, method=STIFF_METHOD, rtol=tolerance,
                                     atol=tolerance, record_dt=run.dt)
            rows, modes = stretch.rows, stretch.modes
            if stretch.status is not Status.OK:   # (its rows and transitions so far are the run's)
                self._adopt(stretch, len(rows) - 1)
                run.status, self.off = stretch.status, stretch.failure
                return
            _, on_grid = self._grid(rows[:, T])
            grid = np.flatnonzero(on_grid)
            turns = self._turns(rows[grid], modes[grid] == int(Mode.SLIDING))
            # (ω_t's rate at each grid row from the next one in the stretch; at the last, from the one before)
            beside = [*range(1, len(grid)), len(grid) - 2 if len(grid) > 1 else None]
            free = next((int(grid[j]) for j in range(len(grid)) if grid[j] > 0 and not self._stiff(
                rows[grid[j]], Mode(int(modes[grid[j]])), turns[j],
                None if beside[j] is None else (rows[grid[beside[j]]], turns[beside[j]]))), None)
            end = free if free is not None else len(rows) - 1
            self._adopt(stretch, end)
            row, mode, t = rows[end], Mode(int(modes[end])), float(rows[end, T])
            if not run.t_end - t > 1e-12 * run.t_end or (self.rest is not None and run.scene.stop_at_rest):
                run.status = Status.OK
                return
            if self._enough():
                return
            if mode is Mode.RESTING or self.rest is not None:   # held in the stretch: the stay goes on
                self.hold(row, t)
                return
            self.mode = mode
            self.carry(row)
            if free is not None and mode is Mode.FLYING:
                self.flight = self._new_flight(FreeState.from_row(row))
                return
            if free is not None:
                run._start_kernel_run(state_of(run, row), t, slides=mode is Mode.SLIDING, repeat=True)
                return
            state, window = state_of(run, row), 2 * window   # still stiff: on from there

    def _grid(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each time's step number k on the run's grid (k·dt) and whether it is on the grid."""
        k = np.round(times / self.run.dt)
        return k, np.abs(times / self.run.dt - k) < 1e-9

    def _stiff(self, row: np.ndarray, mode: Mode, turn: np.ndarray, beside) -> bool:
        """Whether a row's direction is stiff for the fixed steps (``turn``: the slip velocity u
        sliding, ω_t rolling, ``_turns``): sliding, friction would stop its slip within a step (the
        kernel's ``slip_reference``) or the slip changes by as much as itself within SLIP_TIME
        √(r/g); rolling, rolling resistance would stop its ω_t; or the direction turns too fast
        (``turning_point``): as the kernel's ``slip_stiff`` and ``turn_stiff``, with the rate from
        the grid row ``beside`` it and that row's direction, where there is one. Any other mode: not."""
        run = self.run
        ball, force = run.scene.ball, abs(row[NORMAL_FORCE]) * run.dt
        unit = float(run._p[kernel.P_UNIT])   # √(r/g), inf without gravity: the kernel's own
        rate = None if beside is None else (beside[1] - turn) / (beside[0][T] - row[T])
        # (as the kernel's stretch ends: a row the fixed steps go on from is not stiff to them)
        margin = kernel.EXIT_MARGIN
        if mode is Mode.SLIDING:
            cap = 3.5 * float(run._p[kernel.P_MU]) * abs(row[NORMAL_FORCE]) / ball.mass   # the slip's deceleration
            if row[SLIP_SPEED] < cap * run.dt:
                return True
            if (rate is not None and unit < math.inf
                    and np.linalg.norm(rate) * kernel.SLIP_TIME * margin * unit > np.linalg.norm(turn)):
                return True
        elif mode is Mode.ROLLING:
            resistance = float(run._p[kernel.P_RESISTANCE])
            if 0.0 < 1.4 * ball.mass * ball.radius * float(np.linalg.norm(turn)) < resistance * force:
                return True
            if resistance == 0.0:
                return False
            cap = resistance * abs(row[NORMAL_FORCE]) / (1.4 * ball.mass * ball.radius)
        else:
            return False
        if rate is None:
            return False
        return bool(kernel.turning_point.py_func(*turn, *rate, cap, margin * unit, margin * run.dt))

    def _turns(self, rows: np.ndarray, sliding: np.ndarray) -> np.ndarray:
        """The direction whose turning is stiff at each of ``rows`` (n, 3): where ``sliding``, the
        slip velocity u = ċ − r ω × N in the tangent plane; else ω's tangential part ω_t."""
        omega = rows[:, OMEGA]
        normal = unit_normal(self.run.landscape.evaluate(rows[:, CONTACT][:, 0], rows[:, CONTACT][:, 1],
                                                         self.run.scene.parameter_values)).T
        turn = omega - np.sum(omega * normal, axis=1)[:, None] * normal
        slip = rows[:, VELOCITY] - self.run.scene.ball.radius * np.cross(omega, normal)
        slip -= np.sum(slip * normal, axis=1)[:, None] * normal
        return np.where(np.asarray(sliding)[:, None], slip, turn)

    def _adopt(self, stretch, end: int) -> None:
        """A stretch's rows 1 to ``end`` (those at the run's recording times, at its transitions or
        at the end of the run), its transitions up to there and its counts, as the run's own."""
        run = self.run
        rows, modes = stretch.rows[: end + 1], stretch.modes[: end + 1]
        t_end = float(rows[-1, T])
        transitions, changes = {id(c) for c in stretch.transitions}, {id(c) for c in stretch.changes}
        merged = sorted({id(c): c for c in [*stretch.changes, *stretch.transitions] if c.time <= t_end}.values(),
                        key=lambda c: (c.time, c.kind is not Change.LANDING))
        at = {change.time for change in merged}
        k, on_grid = self._grid(rows[:, T])
        kept = [i for i in range(1, len(rows))
                if rows[i, T] in at or rows[i, T] >= run.t_end or (on_grid[i] and k[i] % run.record_every == 0)]
        for i in kept:
            self.mode = Mode(int(modes[i]))
            self.append(rows[i: i + 1].copy())
        self.turns.extend(span for span in stretch.turns if span[0] <= t_end)
        for change in merged:
            if id(change) in changes:
                self.changes.append(change)
            if id(change) in transitions:
                self.transitions.append(change)
                if change.kind is Change.REST:   # (a stop where the ball is pulled on is a change only)
                    self.rest = change
        run._finished[0] += stretch.steps
        run._finished[1] += stretch.rejected
        run._finished[2] += stretch.evaluations
        if self.first_liftoff is None and stretch.liftoff is not None and stretch.liftoff.time <= t_end:
            self.first_liftoff = stretch.liftoff

    # -- a flight and its landing -------------------------------------------------------------------

    def _new_flight(self, start: FreeState) -> Flight:
        scene = self.run.scene
        return new_flight(self.surface, start, radius=scene.ball.radius, mass=scene.ball.mass, gravity=scene.gravity,
                          drag=scene.air.drag_factor(scene.ball.radius))

    def record_spacing(self) -> tuple[int, float]:
        """The run's rows are at every ``every``-th multiple of ``step`` (the kernel's k·dt or
        k·record_dt): fixed steps every record_every-th multiple of dt; adaptive: every multiple
        of record_dt, or of dt."""
        run = self.run
        return (run.record_every, run.dt) if not run.adaptive else (1, run.record_dt or run.dt)

    def record_times(self, t0: float, t1: float) -> np.ndarray:
        """The run's recording times strictly between t0 and t1 (fixed steps: every
        record_every-th multiple of dt; adaptive: the multiples of record_dt, or of dt), each
        computed as the kernel computes its rows' times (k·dt, k·record_dt)."""
        every, step = self.record_spacing()
        spacing = every * step
        k0, k1 = math.floor(t0 / spacing) + 1, math.ceil(t1 / spacing) - 1
        if k1 - k0 + 1 > MAX_ROWS:
            raise ValueError(f"this flight would record more than {MAX_ROWS:,} rows")
        times = (np.arange(k0, k1 + 1) * every) * step
        return times[(times > t0) & (times < t1)]

    def fly(self) -> None:
        """Take the current flight to its landing (or to t_end), then the impact there: in vacuum
        the kernel's (``Surface.bounces``: flight after flight while the ball rebounds), and the
        flight it leaves to flight.py, or one through air, here (``_fly``)."""
        flight = self.flight
        if type(flight) is Flight and flight.compiled:
            landing = self._bounces()
            if landing is not DONE:
                self._fly(landing)
            return
        self._fly(SEARCH)

    def _bounces(self):
        """The kernel's flights from the current one (``Surface.bounces``), their rows, landings and
        losses taken as the run's. Returns DONE, or what ``_fly`` is to finish the current flight
        with: its landing (t, foot), None (flying to t_end) or SEARCH (flight.py's own search)."""
        run, flight = self.run, self.flight
        scene = run.scene
        ball, contact = scene.ball, scene.contact
        every, step = self.record_spacing()
        enough = -1 if self.stop_after is None else self.stop_after - len(self.transitions)
        done = self.surface.bounces(flight.start, gravity=scene.gravity, radius=ball.radius, mass=ball.mass,
                                    restitution=contact.restitution, friction=friction_of(contact),
                                    rest=rest_speed(ball.radius, scene.gravity), t_end=run.t_end, every=every,
                                    step=step, enough=enough, dissipated=self.dissipated,
                                    feet_after=-math.inf if run.flight_contacts else run.t_end)
        self.append(self._carried(done.rows))
        self.dissipated = done.dissipated
        self.transitions.extend(Transition(t, Change.LANDING, x, y, speed, lost)
                                for t, x, y, speed, lost in done.landings.tolist())
        status = done.status
        if status in (kernel.BOUNCES_FLYING, kernel.BOUNCES_DONE, kernel.BOUNCES_ENOUGH):
            self.flight, run.status = None, Status.OK
            return DONE
        if status == kernel.BOUNCES_SETTLED:
            self.flight = None
            self.mode = Mode.ROLLING if done.sticking else Mode.SLIDING
            s = done.state
            state = sliding.BallState(*done.foot, s.velocity, s.omega, s.R, self.dissipated, self.causes)
            run._start_kernel_run(state, s.t, slides=not done.sticking, repeat=False)
            return DONE
        self.flight = self._new_flight(done.state)
        if status == kernel.BOUNCES_CONTINUE:
            return DONE
        if status == kernel.BOUNCES_REFER:   # (the kernel's search just referred this flight)
            self.flight.compiled = False
            return SEARCH
        return done.landing   # BOUNCES_ROOM: its rows recorded here

    def _fly(self, landing) -> None:
        """``fly`` here: the current flight's ``landing`` (SEARCH: flight.py's search, now), its
        rows, the impact there and the next flight or the contact run."""
        run, flight = self.run, self.flight
        scene = run.scene
        ball, contact = scene.ball, scene.contact
        dissipated = self.dissipated
        try:
            if landing is SEARCH:
                landing = flight.landing(run.t_end)
        except FloatingPointError as stiff:   # (a flight through air too thick to integrate)
            self.flight, self.stall, run.status = None, str(stiff), Status.NONFINITE
            return
        except OffLandscape as off:   # nothing to land on: the run ends at the last time there was
            self.append(self._carried(flight.rows(np.append(self.record_times(flight.start.t, off.time), off.time)
                                                  if off.time > flight.start.t else np.empty(0), dissipated)))
            self.flight = None
            self.off = Failure(Reason(off.reason), off.time, *off.point, off.value)
            run.status = Status(FLIGHT_REASONS[off.reason][0]) if off.reason in FLIGHT_REASONS else Status.NONFINITE
            return
        if landing is None:
            times = np.append(self.record_times(flight.start.t, run.t_end), run.t_end)
            self.append(self._carried(flight.rows(times, dissipated)))
            self.flight = None
            run.status = Status.OK
            return
        t, foot = landing
        self.append(self._carried(flight.rows(self.record_times(flight.start.t, t), dissipated)))
        s = flight.state(t)
        hit = impact(s.velocity, s.omega, foot.normal, mass=ball.mass, radius=ball.radius,
                     restitution=contact.restitution, friction=friction_of(contact),
                     rest=rest_speed(ball.radius, scene.gravity))
        bounces = not hit.settled
        air = float(flight.air_dissipated(np.array([t]))[0])
        self.dissipated = dissipated = dissipated + air + hit.energy_lost
        self.causes = (*self.causes[:2], self.causes[2] + air)   # (rolling resistance, spin friction, air)
        self.transitions.append(Transition(t, Change.LANDING, foot.x, foot.y, hit.normal_speed, hit.energy_lost))
        if self._enough():
            return
        if bounces:   # off again: the state just after the impact is a row of the new flight
            self.flight = self._new_flight(FreeState(t, s.center, hit.velocity, hit.omega, s.R))
            self.append(self._carried(self.flight.rows(np.array([t]), dissipated)))
            if t >= run.t_end:
                self.flight, run.status = None, Status.OK
            return
        self.flight = None
        self.mode = Mode.ROLLING if hit.sticking else Mode.SLIDING
        state = sliding.BallState(foot.x, foot.y, hit.velocity, hit.omega, s.R, dissipated, self.causes)
        run._start_kernel_run(state, t, slides=not hit.sticking, repeat=False)
