"""Running a scene: initial state, the compiled kernel in chunks, and the trajectory."""

from __future__ import annotations

import decimal
import functools
import math
import numbers
import operator
import os
import dataclasses
import threading

import numpy as np
from scipy.spatial.transform import Rotation

from . import __version__, kernel, machine_code, sliding
from .flight import Flight, FreeState, OffLandscape, Surface, impact, rest_speed, settle
from .geometry import unit_normal
from .landscape import Landscape, landscape_of
from .scene import CONSTRAINTS, Scene, start_slip
from .tableaus import METHODS, MethodKind, get_method
from .transition_check import TransitionCheck, check_transitions
from .trajectory import (CONTACT, DISSIPATED, ENERGY, ENERGY_WARNING, FLIGHT_REASONS, FLYING, NORMAL_FORCE, OMEGA, R,
                         ROLLING, SLIDING, SLIP_SPEED, T, VELOCITY, EnergyCheck, Failure, Liftoff, Reason, Status,
                         Trajectory, Transition)

# kernel.ROW_SIZE (25) doubles a row: 1.0 GB at the limit, handed to the trajectory without a
# copy. A run recording every adaptive step grows its buffer by doubling up to the limit,
# holding the old and the new buffer for a moment (1.5 GB at the last doubling).
MAX_ROWS = 5_000_000
MAX_STEPS = 2 ** 53    # beyond this, step counts and k·dt are no longer exact in a double
CHUNK = 1 << 20        # steps between returns to Python (cancellation, Ctrl-C)
FIRST_ROWS = 4096      # adaptive runs recording every step start with this many rows, then grow
AUTO_ROWS = 200_000    # a run recorded for display keeps at most about this many rows...
ADAPTIVE_ROWS = 10_000  # ...and an adaptive one this many, evenly spaced in time

_STATUS = {code: Status(name) for code, name in enumerate(kernel.KERNEL_STATUSES)
           if code not in (kernel.RUNNING, kernel.TRANSITION)}
# The mode a kernel run's transition leads to (kernel.interface.TRANSITIONS) as a row mode.
_NEXT_MODE = {"liftoff": FLYING, "slip": SLIDING, "grip": ROLLING}
# A friction coefficient above this acts as this one (``_parameters``): "always enough friction"
# as far as a double can tell (μ F_n stays finite for F_n up to 10²⁰⁸ N; a slide on a plane grips
# after 2 v₀/(7 μ g), 10⁻¹⁰⁰ s here), where μ F_n itself overflowed to inf and inf − inf, 0 · inf
# made the friction bound NaN.
FRICTION_CAP = 1e100
MAX_AT_ONCE = 16   # changes of mode at one instant after which a run stops (it would never move on)
# A fixed-step run takes the stretch where a slip's direction is stiff (kernel.T_STIFF: friction
# would stop the slip within a step, at its start or its end) with this adaptive pair at this
# tolerance, far below the fixed steps' own error, to the first step on its grid where it can go
# on (docs/design.md §8); STIFF_WINDOW steps of the grid at a time, twice as many while it cannot.
STIFF_METHOD = "dop853"
STIFF_TOLERANCE = 1e-12
STIFF_WINDOW = 16


def _kernel_arrays(tableau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The method's (W, E, P) (``Tableau.kernel_arrays``): a registered method's made once per
    process and read-only (made from exact fractions, they cost more than a short run's set-up
    otherwise); a tableau passed in itself (not in ``METHODS``) made for its run."""
    if METHODS.get(tableau.name) is tableau:
        return _registered_arrays(tableau.name)
    return tableau.kernel_arrays()


@functools.cache
def _registered_arrays(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    arrays = METHODS[name].kernel_arrays()
    for array in arrays:
        array.setflags(write=False)
    return arrays


def step_count(dt: float, t_end: float) -> int:
    """Steps of size dt to reach t_end; the last one is shortened when dt does not divide t_end.
    Raises ``ValueError`` when there would be more than ``MAX_STEPS``."""
    q = t_end / dt
    if not q <= MAX_STEPS:  # also an overflow to inf
        raise ValueError(f"t_end / dt = {q:.3g} steps is too many (at most {MAX_STEPS:.3g}): "
                         f"use a larger dt or a shorter t_end")
    n = round(q)
    if n >= 1 and abs(q - n) <= 1e-9 * q:
        return n
    return max(1, math.ceil(q))


def recording(scene: Scene, *, method: str | None = None, dt: float | None = None,
              t_end: float | None = None, record_every: int = 0) -> dict:
    """How to record a run to look at it: the ``Simulation`` keyword arguments that keep it to
    about ``AUTO_ROWS`` rows (every N-th fixed step), or ``ADAPTIVE_ROWS`` evenly spaced rows for
    an adaptive method. A ``record_every`` above 0 is the user's choice and kept."""
    t_end = scene.duration if t_end is None else t_end
    if get_method(scene.integrator.method if method is None else method).adaptive:
        return {"record_dt": t_end / ADAPTIVE_ROWS}
    steps = step_count(scene.integrator.dt if dt is None else dt, t_end)
    return {"record_every": record_every or max(1, math.ceil(steps / AUTO_ROWS))}


def _positive(name: str, value, key: str | None = None) -> float:
    """A finite number > 0 (and whatever the scene rule for ``key`` adds) as a float."""
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, decimal.Decimal)):
        raise ValueError(f"{name} must be a number, not {type(value).__name__}")
    try:
        value = float(value)
    except OverflowError:
        raise ValueError(f"{name} is too large") from None
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number greater than 0, not {value!r}")
    problem = CONSTRAINTS[key](value) if key else None
    if problem:
        raise ValueError(f"{name} {problem}, not {value!r}")
    return value


def _scene(scene) -> Scene:
    """A Scene, or the path of a scene file (loaded)."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return Scene.load(scene)
    raise TypeError(f"pass a Scene (or a scene file's path), not {type(scene).__name__}")


def initial_momentum(d: np.ndarray, vx, vy, spin, r, m) -> np.ndarray:
    """Angular momentum about the contact point, shape (3,) + the shape of the arguments.

    d: the landscape's (f, f_x, f_y, ...) at the contact point (``Landscape.evaluate``);
    vx, vy: horizontal centre velocity (vz follows from tangency); spin: angular velocity
    about the normal; r, m: the ball. Elementwise, so one start or a whole array of starts
    give bit-identical values.
    """
    fx, fy = d[1], d[2]
    n1, n2, n3 = unit_normal(d)
    c1, c2, c3 = vx, vy, fx * vx + fy * vy
    o1 = (n2 * c3 - n3 * c2) / r + spin * n1  # omega = N x c' / r + spin N
    o2 = (n3 * c1 - n1 * c3) / r + spin * n2
    o3 = (n1 * c2 - n2 * c1) / r + spin * n3
    return rolling_momentum(d, o1, o2, o3, r, m)


def rolling_momentum(d: np.ndarray, o1, o2, o3, r, m) -> np.ndarray:
    """The angular momentum about the contact point of a ball rolling with angular velocity
    (o1, o2, o3): v = T ω = m r² (7/5 ω − N (N·ω)) (docs/design.md §1), elementwise."""
    n1, n2, n3 = unit_normal(d)
    no = n1 * o1 + n2 * o2 + n3 * o3
    mr2 = m * r * r
    return np.stack([mr2 * (1.4 * o1 - n1 * no), mr2 * (1.4 * o2 - n2 * no), mr2 * (1.4 * o3 - n3 * no)])


def initial_state(landscape: Landscape, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Contact point and angular momentum about it, from the scene's start values (with
    ``start.omega`` that angular velocity, which the scene checked rolls)."""
    s, r, m = scene.start, scene.ball.radius, scene.ball.mass
    with np.errstate(all="ignore"):  # an overflow is reported by the kernel's start check
        d = landscape.evaluate(s.x, s.y, scene.parameter_values)
        if s.omega is not None:
            return np.array([s.x, s.y]), rolling_momentum(d, *s.omega, r, m)
        v = initial_momentum(d, s.vx, s.vy, s.spin, r, m)
    return np.array([s.x, s.y]), v


class Simulation:
    """One run of a scene, advanced in chunks: ``advance`` until ``done``, then ``trajectory``.

    Keyword arguments override the scene's integrator settings and duration. With an
    adaptive method (``dopri5``) the step size follows the tolerances ``rtol``/``atol`` (``dt`` is the
    first step tried, the orientation always Munthe-Kaas); rows are recorded at multiples
    of ``record_dt`` and at ``t_end``, or at every accepted step when ``record_dt`` is None.
    Fixed-step methods record every ``record_every``-th step instead.

    ``scene`` may also be a scene file's path. One thread at a time may call ``advance``: a
    second thread calling it meanwhile gets a ``RuntimeError`` (``cancel`` and the read-only
    properties are safe from any thread).
    """

    def __init__(self, scene: Scene, *, method: str | None = None, munthe_kaas: bool | None = None,
                 dt: float | None = None, t_end: float | None = None, record_every: int = 1,
                 rtol: float | None = None, atol: float | None = None, record_dt: float | None = None):
        self.scene = scene = _scene(scene)
        self.tableau = get_method(scene.integrator.method if method is None else method)
        self.adaptive = self.tableau.adaptive
        classic_allowed = self.tableau.classic_allowed
        mk = (scene.integrator.munthe_kaas or not classic_allowed) if munthe_kaas is None else munthe_kaas
        if not isinstance(mk, bool):
            raise ValueError(f"munthe_kaas must be True or False, not {mk!r}")
        if not (mk or classic_allowed):
            raise ValueError(f"{self.tableau.name} always advances the orientation by Munthe-Kaas; "
                             "munthe_kaas cannot be False")
        self.munthe_kaas = mk
        self.dt = _positive("dt", scene.integrator.dt if dt is None else dt)
        self.t_end = _positive("t_end", scene.duration if t_end is None else t_end)
        if not self.adaptive and (rtol is not None or atol is not None):
            raise ValueError("rtol and atol are for the adaptive method; fixed steps use dt")
        self.rtol = _positive("rtol", scene.integrator.rtol if rtol is None else rtol, "integrator.rtol")
        self.atol = _positive("atol", scene.integrator.atol if atol is None else atol, "integrator.atol")
        try:
            every = operator.index(record_every)
        except TypeError:
            raise ValueError(f"record_every must be a whole number, not {type(record_every).__name__}") from None
        if isinstance(record_every, bool) or not 1 <= every <= MAX_STEPS:
            raise ValueError(f"record_every must be from 1 to {MAX_STEPS:.3g}")
        if self.adaptive and every != 1:
            raise ValueError("record_every counts fixed steps; with an adaptive method use record_dt")
        if record_dt is not None and not self.adaptive:
            raise ValueError("record_dt is for the adaptive methods; fixed steps use record_every")
        self.record_every = every
        self.record_dt = None if record_dt is None else _positive("record_dt", record_dt)
        if self.adaptive:
            if self.dt <= kernel.MIN_STEP:
                raise ValueError(f"dt (the first step tried) must be greater than {kernel.MIN_STEP:g} s: "
                                 f"smaller steps are lost in round-off")
            self.n_steps = None  # not known in advance: see ``progress``
            rows = FIRST_ROWS if self.record_dt is None else 2 + self.t_end / self.record_dt * (1 + 1e-12)
        else:
            self.n_steps = step_count(self.dt, self.t_end)
            rows = 1 + self.n_steps // every + (1 if self.n_steps % every else 0)
        if not rows <= MAX_ROWS:  # also an overflow to inf
            raise ValueError(f"this run would record {rows:,.0f} rows (at most {MAX_ROWS:,}): "
                             + ("use a larger record_dt" if self.adaptive
                                else "record every N-th step with a larger N"))
        n_rows = math.ceil(rows)
        self._busy = threading.Lock()

        self.landscape = landscape_of(scene)
        self._landscape_record = self.landscape.record(scene.parameter_values)   # held while the kernel runs
        self._fn = self._landscape_record.ctypes.data
        self._W, self._E, self._P = _kernel_arrays(self.tableau)
        self._error_kind = max(len(self._E) - 1, 0)  # kernel.steps.error_norm: 1 or 2 estimates
        # The 2011 model (friction null, glued after a lift-off) is one kernel run, as before scene
        # version 3; any other contact is a sequence of runs, each in one mode (``_advance``).
        contact = scene.contact
        self.segmented = not (contact.friction is None and contact.after_liftoff == "glued")
        self._p = self._parameters(0.0)
        slip = start_slip(scene)
        slips = slip is not None and bool(np.any(slip != 0.0)) and contact.friction is not None
        if slips:   # a start.omega that does not roll: the ball starts sliding
            s = scene.start
            d = self.landscape.evaluate(s.x, s.y, scene.parameter_values)
            velocity = np.array([s.vx, s.vy, d[1] * s.vx + d[2] * s.vy])
            state = sliding.BallState(s.x, s.y, velocity, np.array(s.omega), np.eye(3), 0.0)
            arrays = sliding.start_arrays(state, d, sliding=True, munthe_kaas=mk, stages=len(self._W), rows=n_rows,
                                          radius=scene.ball.radius, mass=scene.ball.mass)
        else:
            arrays = kernel.run_arrays(kernel.state_size(mk), len(self._W), n_rows)
            alpha, v = initial_state(self.landscape, scene)
            arrays["z"][:2], arrays["z"][2:5] = alpha, v
            if not mk:
                arrays["z"][5:] = arrays["R"].ravel()
        arrays["info"][kernel.F_H] = self.dt
        self._arm(arrays, 0.0)
        # the runs after the first, where the contact changes mode
        self._taken = 0            # its rows already moved to _out
        self._skip_first = False   # its first row repeats the last one (a slip or a grip)
        self._out = np.empty((n_rows if self.segmented else 0, kernel.ROW_SIZE))
        self._count = 0            # rows in _out
        self._mode = SLIDING if slips else ROLLING
        self._mode_starts = [(0, self._mode)]   # (first row, mode) where the mode changes
        self.changes: list[Transition] = []   # every change the kernel runs stopped at
        self.transitions: list[Transition] = []
        self._flight: Flight | None = None
        self._surface = Surface(self.landscape, scene.parameter_values)
        self._finished = [0, 0, 0]   # steps, rejected tries and evaluations of the finished kernel runs
        self._first_liftoff: Liftoff | None = None
        self._dissipated_now = 0.0   # J: what a flight carries
        self._off: Failure | None = None   # a flight found no surface below the ball, or a tip too slow to leave
        self._stall: str | None = None     # why the contact's modes could not go on
        self.status: Status | None = None
        self._energy_check: EnergyCheck | None = None
        self._transition_check: TransitionCheck | None = None
        self.judge_energy = True  # whether the finished run looks at whose its energy error is (and its transitions)

    def _parameters(self, dissipated: float) -> np.ndarray:
        scene = self.scene
        turn = kernel.TURN_SHARE * self.rtol if self.adaptive else 0.0
        if not self.segmented:
            return kernel.parameters(scene.ball.radius, scene.ball.mass, scene.gravity, turn)
        contact = scene.contact
        friction = None if contact.friction is None else min(contact.friction, FRICTION_CAP)
        return kernel.parameters(scene.ball.radius, scene.ball.mass, scene.gravity, turn, friction=friction,
                                 fly=contact.after_liftoff == "fly", dissipated=dissipated, stiff=True)

    def _arm(self, arrays: dict, t_start: float) -> None:
        """Make ``arrays`` the current kernel run, from t_start to t_end on the run's one clock (its
        fixed steps and rows on the grid of a run from t = 0: ``kernel.grid_steps_before``)."""
        t_end, n_steps = self.t_end, self.n_steps
        self._run_start = t_start
        if not self.adaptive:   # this kernel run's steps
            before = kernel.grid_steps_before(t_start, self.dt)
            self._run_before, self._run_steps = before, max(1, n_steps - before)
        self._z, self._R, self._K, self._rows = arrays["z"], arrays["R"], arrays["K"], arrays["rows"]
        self._ints, self._info, self._probe = arrays["ints"], arrays["info"], arrays["probe"]
        if self.adaptive:
            self._kernel = machine_code.Arguments(
                "advance_adaptive", fn=self._fn, W=self._W, E=self._E, P=self._P, p=self._p, err_kind=self._error_kind,
                err_exp=self.tableau.error_exponent, t_start=t_start, t_end=t_end, record_dt=self.record_dt or 0.0,
                rtol=self.rtol, atol=self.atol, max_steps=1, **arrays)
        else:
            self._kernel = machine_code.Arguments(
                "advance", fn=self._fn, W=self._W, P=self._P, p=self._p, dt=self.dt, t_start=t_start, t_end=t_end,
                n_steps=n_steps, every=self.record_every, max_steps=1, **arrays,
                stepping=kernel.IMPLICIT if self.tableau.kind is MethodKind.IMPLICIT else kernel.EXPLICIT)

    @property
    def done(self) -> bool:
        return self.status is not None

    @property
    def steps(self) -> int:
        return self._finished[0] + int(self._ints[kernel.I_STEPS])

    @property
    def rejected(self) -> int:
        """Steps tried and rejected by the adaptive method's error control (0 for fixed steps)."""
        return self._finished[1] + int(self._ints[kernel.I_REJECTED])

    @property
    def evaluations(self) -> int:
        """Right-hand-side evaluations so far, rejected tries included."""
        return self._finished[2] + int(self._ints[kernel.I_EVALS])

    @property
    def failure(self) -> Failure | None:
        """Why and where the physics stopped the run (None while it has not)."""
        if self._off is not None:
            return self._off
        reason = kernel.reason_name(int(self._ints[kernel.I_REASON]))
        if reason is None:
            return None
        info = self._info
        return Failure(Reason(reason), float(info[kernel.F_FAIL_T]), float(info[kernel.F_FAIL_X]),
                       float(info[kernel.F_FAIL_Y]), float(info[kernel.F_FAIL_VALUE]))

    @property
    def time(self) -> float:
        """Simulated time reached so far."""
        if self.segmented:
            if self.status is Status.OK:
                return self.t_end
            if self._flight is not None:
                return self._flight.start.t
        if self.adaptive:
            t = self._info[kernel.F_TIME]
            return self._run_start if math.isnan(t) else float(t)
        k = int(self._ints[kernel.I_STEPS])
        if k == 0:
            return self._run_start
        return self.t_end if k == self._run_steps else (self._run_before + k) * self.dt

    @property
    def progress(self) -> float:
        """Fraction of the run done, 0 to 1 (``time / t_end``), for every method."""
        return self.time / self.t_end

    @property
    def row_capacity(self) -> int:
        """Rows reserved so far: all a fixed-step run will record; an adaptive run grows as needed
        (and so does a run whose contact changes mode)."""
        return len(self._out) if self.segmented else len(self._rows)

    @property
    def rows(self) -> np.ndarray:
        """The rows recorded so far (a view: copy what you keep)."""
        if self.segmented:
            return self._out[: self._count]
        return self._rows[: self._ints[kernel.I_ROWS]]

    def _row_count(self) -> int:
        return self._count if self.segmented else int(self._ints[kernel.I_ROWS])

    @property
    def modes(self) -> np.ndarray:
        """The contact's mode of each row so far (positions in ``trajectory.MODES``)."""
        codes = np.empty(self._row_count(), dtype=np.int8)
        starts = self._mode_starts + [(len(codes), None)]
        for (first, mode), (end, _) in zip(starts, starts[1:]):
            codes[first:end] = mode
        return codes

    def advance(self, max_steps: int | None = None) -> np.ndarray:
        """Run up to ``max_steps`` more steps (a whole number >= 1; all remaining if None);
        return the new rows. Raises ``RuntimeError`` if another thread is advancing this run."""
        if max_steps is not None:
            if isinstance(max_steps, bool) or not isinstance(max_steps, numbers.Integral) or max_steps < 1:
                raise ValueError(f"max_steps must be a whole number of 1 or more, not {max_steps!r}")
            max_steps = int(max_steps)
        if not self._busy.acquire(blocking=False):
            raise RuntimeError("this Simulation is being advanced by another thread; "
                               "advance one Simulation from one thread at a time")
        try:
            return self._advance(max_steps)
        finally:
            self._busy.release()

    def _advance(self, max_steps: int | None) -> np.ndarray:
        if self.done:
            return self.rows[:0]
        first = self._row_count()
        if max_steps is not None:
            remaining = max_steps
        else:
            remaining = math.inf if self.adaptive or self.segmented else self.n_steps - self.steps
        while (remaining > 0 or self._row_count() == 0) and not self.done:
            if self._flight is not None:   # a flight is taken whole, as one step
                self._fly()
                remaining -= 1
                continue
            chunk = int(min(remaining, CHUNK))
            if self.adaptive:
                if self._ints[kernel.I_ROWS] >= len(self._rows) - 2:
                    if len(self._rows) >= MAX_ROWS:  # stop rather than fill the memory
                        self.status = Status.ROW_LIMIT
                        break
                    grown = np.empty((min(2 * len(self._rows), MAX_ROWS), kernel.ROW_SIZE))
                    grown[: len(self._rows)] = self._rows
                    self._rows = grown
                    self._kernel.set("rows", grown)
                before = self.steps + self.rejected
                self._kernel.set("max_steps", chunk)
                self._kernel()
                chunk = self.steps + self.rejected - before
            else:
                self._kernel.set("max_steps", chunk)
                self._kernel()
            remaining -= chunk
            if self.segmented:
                self._collect()
                self._note_liftoff()
            code = int(self._ints[kernel.I_STATUS])
            if code == kernel.TRANSITION:
                self._transition()
            elif code != kernel.RUNNING:
                self.status = _STATUS[code]
                break
        if self.judge_energy and self.status in (Status.OK, Status.DOES_NOT_FIT, Status.NONFINITE):
            # (here, where the run runs: never in the thread that reads the trajectory)
            self._energy_check = energy_check(self)
            self._transition_check = check_transitions(self)
        return self.rows[first:].copy()

    # -- the runs after the first, where the contact changes mode (docs/design.md §1) ----------

    def _append(self, rows: np.ndarray) -> None:
        """Add rows to the run's rows (growing the buffer), in the current mode."""
        if not len(rows):
            return
        if self._mode_starts[-1][1] != self._mode:
            self._mode_starts.append((self._count, self._mode))
        need = self._count + len(rows)
        if need > len(self._out):
            if need > MAX_ROWS:
                raise ValueError(f"this run would record more than {MAX_ROWS:,} rows")
            grown = np.empty((min(max(2 * len(self._out), need), MAX_ROWS), kernel.ROW_SIZE))
            grown[: self._count] = self._out[: self._count]
            self._out = grown
        self._out[self._count: need] = rows
        self._count = need

    def _collect(self) -> None:
        """Move the current kernel run's new rows to the run's rows."""
        count = int(self._ints[kernel.I_ROWS])
        start = self._taken
        if self._skip_first and start == 0 and count > 0:
            start = 1
        rows = self._rows[start:count].copy()
        self._taken = count
        self._append(rows)

    def _note_liftoff(self) -> None:
        """Keep the first lift-off a kernel run found (where the ball flies, a transition's)."""
        info = self._info
        if self._first_liftoff is None and not math.isnan(info[kernel.F_LIFTOFF]):
            self._first_liftoff = Liftoff(float(info[kernel.F_LIFTOFF]), float(info[kernel.F_LIFT_X]),
                                          float(info[kernel.F_LIFT_Y]), bool(info[kernel.F_LIFT_KINK]))

    def _finish_kernel_run(self) -> None:
        self._finished[0] += int(self._ints[kernel.I_STEPS])
        self._finished[1] += int(self._ints[kernel.I_REJECTED])
        self._finished[2] += int(self._ints[kernel.I_EVALS])

    def _transition(self) -> None:
        """The kernel run stopped where the contact changes mode: go on in the new one."""
        info = self._info
        if int(self._ints[kernel.I_TRANSITION]) == kernel.T_STIFF:
            self._finish_kernel_run()
            self._stiff_stretch()
            return
        kind = kernel.transition_name(int(self._ints[kernel.I_TRANSITION]))
        t = float(info[kernel.F_EVENT_T])
        x, y = float(info[kernel.F_EVENT_X]), float(info[kernel.F_EVENT_Y])
        change = Transition(t, kind, x, y)
        self.changes.append(change)
        if not (kind == "slip" and self._mode == SLIDING):
            # (a slip whose speed fell to zero where rolling needs more friction than μ F·N turns
            # about and goes on: the same slip, no new transition)
            self.transitions.append(change)
        self._finish_kernel_run()
        at_once = self.changes[-MAX_AT_ONCE:]
        if len(at_once) == MAX_AT_ONCE and all(change.time == t for change in at_once):
            self._stall = (f"the contact changes mode {MAX_AT_ONCE} times at t = {t:.6g} s, (x, y) = ({x:.6g}, {y:.6g}) "
                           f"({', '.join(sorted({change.kind for change in at_once}))}) without the time moving on: "
                           f"rolling needs more friction than μ F·N there, and sliding stops at once, so the run "
                           f"cannot go on")
            self.status = Status.NONFINITE
            return
        last = self._out[self._count - 1]
        if kind == "liftoff":
            self._dissipated_now = float(last[DISSIPATED])
            self._mode = FLYING
            # the flight leaves along the tangent plane: a sliding state's c'.N is the integrator's
            # drift (0 in the exact motion), and a c' into the surface would land it at once
            start = FreeState.from_row(last)
            if info[kernel.F_LIFT_KINK] == kernel.LIFT_TIP:
                force = self._pivot_force(start, x, y)
                if force > 0.0:   # too slow to leave the tip: the ball would roll over it, pivoting
                    self.transitions.pop()
                    if self._first_liftoff is not None and self._first_liftoff.time == float(info[kernel.F_LIFTOFF]):
                        self._first_liftoff = None
                    self._off = Failure(Reason.PIVOT, t, x, y, force)
                    self.status = Status.DOES_NOT_FIT
                    return
            # a tip left (or one F·N reached 0 within round-off of) is measured directly in the flight's
            # distances too: Newton's method finds no closest point there
            point = np.array([x, y, float(self.landscape.evaluate(x, y, self.scene.parameter_values)[0])])
            if (self._at_tip(x, y) and np.isfinite(point).all()
                    and not any(np.array_equal(point, known) for known in self._surface.tips)):
                self._surface.tips.append(point)
            normal = self._probe_normal()
            velocity = start.velocity - float(np.dot(start.velocity, normal)) * normal
            start = dataclasses.replace(start, velocity=velocity)
            if info[kernel.F_LIFT_KINK] == 1.0 and t > start.t:
                # a ridge's kink: the run's last state is the last one before it (the kink is located
                # between it and the step's end); the ball is on the surface up to the kink, so it
                # rolls (slides) there along the tangent plane and the flight starts at the kink
                start = self._to_kink(start, t, normal)
            self._flight = self._new_flight(start)
            return
        normal = self._probe_normal()
        state = sliding.stopped_state(self._z, self._R, self._p, normal)
        self._mode = _NEXT_MODE[kind]
        self._dissipated_now = state.dissipated
        self._start_kernel_run(state, t, slides=kind == "slip", repeat=True)

    def _to_kink(self, start: FreeState, t: float, normal: np.ndarray) -> FreeState:
        """The state at the kink's time t from ``start`` (the last state before it, τ = t − t₀ earlier),
        moving in the tangent plane of ``normal`` as on that plane: rolling with acceleration
        (5/7) g_t and ω = N × ċ/r plus its spin about N (this keeps E exactly), sliding with
        g_t − μ g₀ N_z û (u the slip velocity) and the torque of that friction. Over the short
        τ the surface's bending moves the centre off the plane by about κ|ċ|²τ²/2."""
        tau = t - start.t
        r, g0 = self.scene.ball.radius, self.scene.gravity
        gravity = np.array([0.0, 0.0, -g0])
        tangential = gravity - float(np.dot(gravity, normal)) * normal
        omega = start.omega
        if self._mode == SLIDING and self.scene.contact.friction is not None:
            slip = start.velocity + np.cross(omega, -r * normal)
            slip -= float(np.dot(slip, normal)) * normal
            speed = float(np.linalg.norm(slip))
            mu = min(self.scene.contact.friction, FRICTION_CAP)
            friction = -mu * g0 * float(normal[2]) * slip / speed if speed > 0.0 else np.zeros(3)
            acceleration = tangential + friction
            omega = omega - (5.0 / (2.0 * r)) * np.cross(normal, friction) * tau
            self._dissipated_now += self.scene.ball.mass * mu * g0 * float(normal[2]) * speed * tau
        else:
            acceleration = (5.0 / 7.0) * tangential
        velocity = start.velocity + acceleration * tau
        if self._mode != SLIDING or self.scene.contact.friction is None:
            omega = np.cross(normal, velocity) / r + float(np.dot(start.omega, normal)) * normal
        center = start.center + start.velocity * tau + 0.5 * acceleration * tau * tau
        R = Rotation.from_rotvec(0.5 * (start.omega + omega) * tau).as_matrix() @ start.R
        return FreeState(t, center, velocity, omega, R)

    def _stiff_stretch(self) -> None:
        """The fixed-step kernel run stopped before a step where the slip's direction is stiff
        (kernel.T_STIFF): its direction relaxes at the rate |B| / |u| and turns with B, which no
        fixed step can follow at its order. That stretch is taken by STIFF_METHOD at
        STIFF_TOLERANCE (every transition in it too), recording every step of the run's grid; the
        fixed steps go on from the first grid time where the ball no longer slides, or its slip
        is no longer stiff: its rows and transitions up to there are the run's."""
        t = float(self._info[kernel.F_EVENT_T])
        state = sliding.stopped_state(self._z, self._R, self._p, self._probe_normal())
        mode, window = SLIDING, STIFF_WINDOW
        while True:
            t1 = (kernel.grid_steps_before(t, self.dt) + window) * self.dt
            if not self.t_end - t1 > kernel.GRID_SLIVER * self.dt:
                t1 = self.t_end
            run = self._stretch_run(state, t, t1, mode)
            rows, modes = run.rows, run.modes
            if run.status is not Status.OK:   # (its rows and transitions so far are the run's)
                self._adopt(run, len(rows) - 1)
                self.status, self._off = run.status, run.failure
                return
            _, on_grid = self._grid(rows[:, T])
            free = [i for i in range(1, len(rows))
                    if on_grid[i] and (modes[i] != SLIDING or not self._stiff(rows[i]))]
            end = free[0] if free else len(rows) - 1
            self._adopt(run, end)
            row, mode, t = rows[end], int(modes[end]), float(rows[end, T])
            if not self.t_end - t > 1e-12 * self.t_end:
                self.status = Status.OK
                return
            self._mode, self._dissipated_now = mode, float(row[DISSIPATED])
            if free and mode == FLYING:
                self._flight = self._new_flight(FreeState.from_row(row))
                return
            if free:
                self._start_kernel_run(_state_of(self, row), t, slides=mode == SLIDING, repeat=True)
                return
            state, window = _state_of(self, row), 2 * window   # still stiff: on from there

    def _grid(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each time's step number k on the run's grid (k·dt) and whether it is on the grid."""
        k = np.round(times / self.dt)
        return k, np.abs(times / self.dt - k) < 1e-9

    def _stiff(self, row: np.ndarray) -> bool:
        """Whether a sliding row's slip is stiff for the fixed steps: friction would stop it within
        a step (the kernel's ``slip_reference``)."""
        ball = self.scene.ball
        return (row[SLIP_SPEED] * ball.mass
                < 3.5 * float(self._p[kernel.P_MU]) * abs(row[NORMAL_FORCE]) * self.dt)

    def _stretch_run(self, state, t0: float, t1: float, mode: int) -> "Simulation":
        """STIFF_METHOD's run from ``state`` in ``mode`` at t0 to t1, a row at every step of the grid."""
        run = Simulation(dataclasses.replace(self.scene, duration=t1), method=STIFF_METHOD, rtol=STIFF_TOLERANCE,
                         atol=STIFF_TOLERANCE, record_dt=self.dt)
        run.judge_energy = False
        run._mode, run._mode_starts = mode, [(0, mode)]
        run._start_kernel_run(state, t0, slides=mode == SLIDING, repeat=False)
        run.advance()
        return run

    def _adopt(self, run: "Simulation", end: int) -> None:
        """A stretch's rows 1 to ``end`` (those at the run's recording times, at its transitions or
        at the end of the run), its transitions up to there and its counts, as the run's own."""
        rows, modes = run.rows[: end + 1], run.modes[: end + 1]
        t_end = float(rows[-1, T])
        transitions, changes = {id(c) for c in run.transitions}, {id(c) for c in run.changes}
        merged = sorted({id(c): c for c in [*run.changes, *run.transitions] if c.time <= t_end}.values(),
                        key=lambda c: (c.time, c.kind != "landing"))
        at = {change.time for change in merged}
        k, on_grid = self._grid(rows[:, T])
        kept = [i for i in range(1, len(rows))
                if rows[i, T] in at or rows[i, T] >= self.t_end or (on_grid[i] and k[i] % self.record_every == 0)]
        for i in kept:
            self._mode = int(modes[i])
            self._append(rows[i: i + 1].copy())
        for change in merged:
            if id(change) in changes:
                self.changes.append(change)
            if id(change) in transitions:
                self.transitions.append(change)
        self._finished[0] += run.steps
        self._finished[1] += run.rejected
        self._finished[2] += run.evaluations
        if self._first_liftoff is None and run.liftoff is not None and run.liftoff.time <= t_end:
            self._first_liftoff = run.liftoff

    def _at_tip(self, x: float, y: float) -> bool:
        """Whether (x, y) is (within 10⁻⁶ of) a point where the normal turns through a finite angle:
        the unit normals on a ring of that radius about it differ by more than 10⁻² (a smooth
        surface's by about its curvature times 10⁻⁶)."""
        ring = 1e-6 * (1.0 + abs(x) + abs(y))
        angles = np.arange(8) * (np.pi / 4)
        d = self.landscape.evaluate(x + ring * np.cos(angles), y + ring * np.sin(angles), self.scene.parameter_values)
        normals = unit_normal(d).T
        spread = np.linalg.norm(normals[:, None, :] - normals[None, :, :], axis=2)
        return bool(np.nanmax(spread) > 1e-2) if np.isfinite(spread).any() else False

    def _pivot_force(self, start: FreeState, x: float, y: float) -> float:
        """F·N (N) the ball at ``start`` would need to turn about the tip at (x, y): its centre on
        the sphere about the tip, m (g₀ e_z − |ċ_t|² / |c − T|) for e the unit vector from the tip T
        to the centre and ċ_t the velocity across it (docs/design.md §1, "A tip"). At most 0: the
        ball leaves the tip as it reaches it."""
        f = float(self.landscape.evaluate(x, y, self.scene.parameter_values)[0])
        arm = start.center - np.array([x, y, f])
        distance = float(np.linalg.norm(arm))
        e = arm / distance
        across = start.velocity - float(np.dot(start.velocity, e)) * e
        return self.scene.ball.mass * (self.scene.gravity * e[2] - float(np.dot(across, across)) / distance)

    def _probe_normal(self) -> np.ndarray:
        return self._probe[kernel.PROBE_N: kernel.PROBE_N + 3].copy()


    def _new_flight(self, start: FreeState) -> Flight:
        ball = self.scene.ball
        return Flight(self._surface, start, radius=ball.radius, mass=ball.mass, gravity=self.scene.gravity)

    def _start_kernel_run(self, state, t: float, *, slides: bool, repeat: bool) -> None:
        """A kernel run from ``state`` at time t in the given mode; ``repeat``: its first row
        repeats the run's last row (the state where a slip or grip happened) and is left out."""
        left = self.t_end - t
        if not left > 1e-12 * self.t_end:
            self.status = Status.OK
            return
        if self.adaptive:
            rows = FIRST_ROWS if self.record_dt is None else 3 + left / self.record_dt * (1 + 1e-12)
        else:   # (the start, every record_every-th step on the grid from t = 0, the end)
            own = max(1, self.n_steps - kernel.grid_steps_before(t, self.dt))
            rows = 1 + own // self.record_every + 2
        d = self.landscape.evaluate(state.x, state.y, self.scene.parameter_values)
        h = float(self._info[kernel.F_H]) if self.adaptive and math.isfinite(self._info[kernel.F_H]) else self.dt
        arrays = sliding.start_arrays(state, d, sliding=slides, munthe_kaas=self.munthe_kaas, stages=len(self._W),
                               rows=math.ceil(rows), radius=self.scene.ball.radius, mass=self.scene.ball.mass)
        arrays["info"][kernel.F_H] = h
        self._p = self._parameters(state.dissipated)
        self._arm(arrays, t)
        self._taken, self._skip_first = 0, repeat

    def _record_times(self, t0: float, t1: float) -> np.ndarray:
        """The run's recording times strictly between t0 and t1 (fixed steps: every
        record_every-th multiple of dt; adaptive: the multiples of record_dt, or of dt), each
        computed as the kernel computes its rows' times (k·dt, k·record_dt)."""
        every, step = (self.record_every, self.dt) if not self.adaptive else (1, self.record_dt or self.dt)
        spacing = every * step
        k0, k1 = math.floor(t0 / spacing) + 1, math.ceil(t1 / spacing) - 1
        if k1 - k0 + 1 > MAX_ROWS:
            raise ValueError(f"this flight would record more than {MAX_ROWS:,} rows")
        times = (np.arange(k0, k1 + 1) * every) * step
        return times[(times > t0) & (times < t1)]

    def _fly(self) -> None:
        """Take the current flight to its landing (or to t_end), then the impact there."""
        flight, ball, contact = self._flight, self.scene.ball, self.scene.contact
        dissipated = self._dissipated_now
        try:
            landing = flight.landing(self.t_end)
        except OffLandscape as off:   # nothing to land on: the run ends at the last time there was
            self._append(flight.rows(np.append(self._record_times(flight.start.t, off.time), off.time)
                                     if off.time > flight.start.t else np.empty(0), dissipated))
            self._flight = None
            self._off = Failure(Reason(off.reason), off.time, *off.point, off.value)
            self.status = Status(FLIGHT_REASONS[off.reason][0]) if off.reason in FLIGHT_REASONS else Status.NONFINITE
            return
        if landing is None:
            times = np.append(self._record_times(flight.start.t, self.t_end), self.t_end)
            self._append(flight.rows(times, dissipated))
            self._flight = None
            self.status = Status.OK
            return
        t, foot = landing
        self._append(flight.rows(self._record_times(flight.start.t, t), dissipated))
        s = flight.state(t)
        hit = impact(s.velocity, s.omega, foot.normal, mass=ball.mass, radius=ball.radius,
                     restitution=contact.restitution, friction=contact.friction)
        bounces = hit.rebound > rest_speed(ball.radius, self.scene.gravity)
        if not bounces:
            hit = settle(hit, foot.normal, mass=ball.mass, radius=ball.radius)
        self._dissipated_now = dissipated = dissipated + hit.energy_lost
        self.transitions.append(Transition(t, "landing", foot.x, foot.y, hit.normal_speed, hit.energy_lost))
        if bounces:   # off again: the state just after the impact is a row of the new flight
            self._flight = self._new_flight(FreeState(t, s.center, hit.velocity, hit.omega, s.R))
            self._append(self._flight.rows(np.array([t]), dissipated))
            if t >= self.t_end:
                self._flight, self.status = None, Status.OK
            return
        self._flight = None
        self._mode = ROLLING if hit.sticking else SLIDING
        state = sliding.BallState(foot.x, foot.y, hit.velocity, hit.omega, s.R, dissipated)
        self._start_kernel_run(state, t, slides=not hit.sticking, repeat=False)

    def cancel(self) -> None:
        """Stop the run where it is (status ``aborted``); the rows so far are kept.

        Safe to call from another thread: a running ``advance`` returns after its current chunk.
        """
        if not self.done:
            self.status = Status.ABORTED

    @property
    def transition_check(self) -> TransitionCheck | None:
        """Whether the finished run's transitions are converged (``transition_check``; None before)."""
        return self._transition_check

    @property
    def liftoff_time(self) -> float | None:
        liftoff = self.liftoff
        return None if liftoff is None else liftoff.time

    @property
    def liftoff(self) -> Liftoff | None:
        """The first lift-off, as soon as the kernel has found it (None before)."""
        if self.segmented:
            return self._first_liftoff
        info = self._info
        if math.isnan(info[kernel.F_LIFTOFF]):
            return None
        return Liftoff(float(info[kernel.F_LIFTOFF]), float(info[kernel.F_LIFT_X]), float(info[kernel.F_LIFT_Y]),
                       bool(info[kernel.F_LIFT_KINK]))

    def message(self, status: Status | None = None) -> str:
        """How the run ended (or stands), in words."""
        status = status or self.status
        failure = self.failure
        if self._stall is not None and status is Status.NONFINITE:
            return self._stall
        if failure is not None and status in (Status.DOES_NOT_FIT, Status.NONFINITE):
            return describe(failure, self.scene.ball.radius)
        if status is Status.OK:
            rejected = f" ({self.rejected} rejected)" if self.adaptive else ""
            flew = any(change.kind == "landing" for change in self.transitions)
            where = " on the surface (a flight is exact: no steps)" if flew else ""
            return f"reached t = {self.t_end:g} s in {self.steps} steps{where}{rejected}"
        if status is Status.ABORTED:
            return f"stopped at t = {self.time:.6g} s after {self.steps} steps"
        if status is Status.ROW_LIMIT:
            return (f"row limit reached: {len(self.rows):,} rows (every step) by t = {self.time:.6g} s of "
                    f"{self.t_end:g} s; use record_dt to record at fixed times instead")
        return f"running: t = {self.time:.6g} s"

    def trajectory(self) -> Trajectory:
        """The rows so far and how the run ended (a run not yet done counts as aborted)."""
        scene, s = self.scene, self.scene.start
        status = self.status or Status.ABORTED
        message = self.message(status)
        provenance = {
            "program": f"rollball {__version__}",
            "landscape": scene.landscape,
            "ball": f"radius {scene.ball.radius!r} m, mass {scene.ball.mass!r} kg",
            "gravity": f"{scene.gravity!r} m/s^2",
            "start": f"x {s.x!r}, y {s.y!r}, vx {s.vx!r}, vy {s.vy!r}, spin {s.spin!r}",
            "method": (f"{self.tableau.name}, Munthe-Kaas, rtol {self.rtol!r}, atol {self.atol!r}, "
                       f"t_end {self.t_end!r} s, record_dt {self.record_dt!r}" if self.adaptive else
                       f"{self.tableau.name}, {'Munthe-Kaas' if self.munthe_kaas else 'classic'}, "
                       f"dt {self.dt!r} s, t_end {self.t_end!r} s, every {self.record_every}"),
            "status": f"{status}: {message}",
        }
        if self.segmented:
            c = scene.contact
            friction = "none (it always rolls)" if c.friction is None else repr(c.friction)
            provenance["contact"] = (f"friction {friction}, restitution {c.restitution!r}, "
                                     f"after_liftoff {c.after_liftoff}")
        # rows are only ever appended: the trajectory can share them instead of copying
        return Trajectory(self.rows, status=status, message=message,
                          liftoff=self.liftoff, steps=self.steps, rejected=self.rejected,
                          evaluations=self.evaluations, failure=self.failure, mass=scene.ball.mass,
                          radius=scene.ball.radius, gravity=scene.gravity, provenance=provenance,
                          energy_check=self._energy_check, modes=self.modes if self.segmented else None,
                          transitions=tuple(self.transitions), transition_check=self._transition_check)


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


def _start_of(run: Simulation, row: np.ndarray):
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


def _state_of(run: Simulation, row: np.ndarray) -> sliding.BallState:
    """A recorded row's state, the same in every mode (contact point, ċ, ω, R, D), with ċ in the
    tangent plane at the contact point: a sliding run's ċ drifts off it by the step's error (its
    normal part is not a variable of the motion, only kept at 0 by F_n), and the exact motion
    from a state off it does not keep E + D."""
    x, y = (float(value) for value in row[CONTACT])
    normal = unit_normal(run.landscape.evaluate(x, y, run.scene.parameter_values))
    velocity = row[VELOCITY] - np.dot(row[VELOCITY], normal) * normal
    return sliding.BallState(x, y, velocity, row[OMEGA].copy(), row[R].reshape(3, 3).copy(), float(row[DISSIPATED]))


def _run_from(run: Simulation, row: np.ndarray, mode: int, duration: float, **options) -> Simulation | None:
    """The scene run for ``duration`` from a recorded row's state with ``options`` (Simulation's),
    finished; None where it does not end ok. A run that only ever rolls (the 2011 model) starts
    from the row as a scene's start (``_start_of``); one whose contact can change mode from the
    row's whole state (``_state_of``, its dissipated energy too) in ``mode`` (ROLLING or SLIDING)
    on a clock from 0, where it may change mode again as the run did."""
    start = _start_of(run, row) if not run.segmented else run.scene.start
    if start is None:
        return None
    try:
        redo = Simulation(dataclasses.replace(run.scene, start=start, duration=duration), **options)
    except ValueError:   # (a SceneError too: an interval shorter than its first step's delay)
        return None
    redo.judge_energy = False  # (the check's own runs are not checked)
    if run.segmented:
        redo._mode, redo._mode_starts = mode, [(0, mode)]
        redo._start_kernel_run(_state_of(run, row), 0.0, slides=mode == SLIDING, repeat=False)
    redo.advance()
    return redo if redo.status is Status.OK and len(redo.rows) >= 2 else None


def _interval_change(run: Simulation, row: np.ndarray, mode: int, duration: float, delay: float = 0.0,
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
        row, mode = lead.rows[-1], int(lead.modes[-1]) if run.segmented else ROLLING
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


def _judged(run: Simulation, rows: np.ndarray) -> np.ndarray:
    """Which recorded intervals (rows i to i + 1) the energy check may take again: those the
    contact integrated in one mode, rolling or sliding. A flight is exact, so an interval that
    ends in one, or that holds a landing (its impact is counted in D), is not the step's."""
    if not run.segmented:
        return np.ones(len(rows) - 1, dtype=bool)
    contact = run.modes[1: len(rows)] != FLYING
    t = rows[:, T]
    for change in run.transitions:
        if change.kind == "landing":
            contact &= ~((t[:-1] < change.time) & (change.time <= t[1:]))
    return contact


def energy_check(run: Simulation) -> EnergyCheck | None:
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
    SHORTER^ROUGH_ORDER (adaptive: the change shrank by less than the square root of TIGHTER). A method of order below PROBE_ORDER (euler) cannot
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
    mode = int(run.modes[i + 1]) if run.segmented else ROLLING   # (the mode that integrated the interval)
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


def describe(failure: Failure, radius: float) -> str:
    """The sentence for a failure, made from its fields (``kernel.interface.REASONS``, or a flight's
    ``trajectory.FLIGHT_REASONS``)."""
    reason = str(failure.reason)
    if reason in FLIGHT_REASONS:
        where = f"t = {failure.time:.6g} s, (x, y) = ({failure.x:.6g}, {failure.y:.6g})"
        return FLIGHT_REASONS[reason][2].format(where=where, value=failure.value, radius=radius)
    return kernel.sentence(reason, failure.value, failure.time, failure.x, failure.y, radius)


def simulate(scene: Scene | str | os.PathLike, *, method: str | None = None, munthe_kaas: bool | None = None,
             dt: float | None = None, t_end: float | None = None, record_every: int = 1,
             rtol: float | None = None, atol: float | None = None,
             record_dt: float | None = None) -> Trajectory:
    """Run a scene to its end (or until the physics stops it) and return the trajectory.

    Keyword arguments override the scene's values: ``method`` (a name in ``METHODS``:
    euler, rk4, lawson5, dopri5, …), ``munthe_kaas``, ``dt`` (s; for adaptive the first
    step tried), ``t_end`` (s), ``rtol``/``atol`` (adaptive). Fixed steps: ``record_every``
    keeps every N-th step; adaptive: rows at multiples of ``record_dt`` (s) or, if None,
    at every accepted step. Row 0 is the initial state and the last row the end of the run.
    ``scene`` may also be a scene file's path.
    """
    run = Simulation(scene, method=method, munthe_kaas=munthe_kaas, dt=dt, t_end=t_end,
                     record_every=record_every, rtol=rtol, atol=atol, record_dt=record_dt)
    run.advance()
    return run.trajectory()
