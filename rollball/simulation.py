"""Running a scene: initial state, the compiled kernel in chunks, and the trajectory."""

from __future__ import annotations

import decimal
import functools
import math
import numbers
import operator
import os
import threading

import numpy as np

from . import __version__, kernel, machine_code, sliding
from .run_size import MAX_ROWS, MAX_STEPS, step_count
from .energy_check import energy_check
from .geometry import unit_normal, unit_normal_of
from .landscape import Landscape, landscape_of
from .mode_machine import STIFF_METHOD, ModeMachine, friction_of, stiff_tolerance
from .modes import Mode
from .scene import CONSTRAINTS, Scene, start_slip
from .tableaus import METHODS, MethodKind, get_method
from .transition_check import check_transitions
from .trajectory import (CONTACT, FLIGHT_REASONS, T, VELOCITY, EnergyCheck, Failure, Liftoff, Reason, Status,
                         Trajectory, Transition)
from .transition_verdict import TransitionCheck

CHUNK = 1 << 20        # steps between returns to Python (cancellation, Ctrl-C)
FIRST_ROWS = 4096      # adaptive runs recording every step start with this many rows, then grow
AUTO_ROWS = 200_000    # a run recorded for display keeps at most about this many rows...
ADAPTIVE_ROWS = 10_000  # ...and an adaptive one this many, evenly spaced in time
# A non-finite stop is the air's where its drag's rate k|ċ|/m times the step exceeds this: beyond the
# stability interval of every explicit method here on the negative axis (Euler's 2, rk4's 2.8, the
# pairs' ≲ 6), where Gauss's stage iteration (a contraction for a rate times step below about 1) fails too
DRAG_STIFF = 10.0
# the kernel's reasons an unstable step through such air shows as (its state or rotation blowing up, no
# stage iteration converging, no adaptive step small enough)
STIFF_DRAG_SIGNS = (Reason.UNDEFINED, Reason.ORIENTATION_OVERFLOW, Reason.NOT_CONVERGED, Reason.STEP_UNDERFLOW)
SHARED_ROWS = 4        # rows a kernel run writing into the mode machine's rows finds free at its start (it grows them)
# rows beyond the grid's a run whose contact changes mode has room for before its rows grow (a copy of
# them all): a change's own row, and the row a flight's landing adds, a few each
CHANGE_ROWS = 64

_STATUS = {code: Status(name) for code, name in enumerate(kernel.KERNEL_STATUSES)
           if code not in (kernel.RUNNING, kernel.TRANSITION)}


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
    if type(value) is float and 0.0 < value < math.inf and not key:   # (a scene's own values: at once)
        return value
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
    give bit-identical values (one start in Python's floats: the same numbers, sooner).
    """
    n1, n2, n3 = _normal(d)
    if d.ndim == 1:
        d, vx, vy, spin, r, m = d.tolist(), float(vx), float(vy), float(spin), float(r), float(m)
    fx, fy = d[1], d[2]
    c1, c2, c3 = vx, vy, fx * vx + fy * vy
    o1 = (n2 * c3 - n3 * c2) / r + spin * n1  # omega = N x c' / r + spin N
    o2 = (n3 * c1 - n1 * c3) / r + spin * n2
    o3 = (n1 * c2 - n2 * c1) / r + spin * n3
    return _momentum(n1, n2, n3, o1, o2, o3, r, m)


def rolling_momentum(d: np.ndarray, o1, o2, o3, r, m) -> np.ndarray:
    """The angular momentum about the contact point of a ball rolling with angular velocity
    (o1, o2, o3): v = T ω = m r² (7/5 ω − N (N·ω)) (docs/design.md §1), elementwise."""
    if d.ndim == 1:
        o1, o2, o3, r, m = float(o1), float(o2), float(o3), float(r), float(m)
    return _momentum(*_normal(d), o1, o2, o3, r, m)


def _normal(d: np.ndarray):
    """The unit normal's three components: Python's floats for one point, else arrays."""
    return unit_normal_of(float(d[1]), float(d[2])) if d.ndim == 1 else unit_normal(d)


def _momentum(n1, n2, n3, o1, o2, o3, r, m) -> np.ndarray:
    no = n1 * o1 + n2 * o2 + n3 * o3
    mr2 = m * r * r
    v = mr2 * (1.4 * o1 - n1 * no), mr2 * (1.4 * o2 - n2 * no), mr2 * (1.4 * o3 - n3 * no)
    return np.array(v) if isinstance(no, float) else np.stack(v)


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
                 rtol: float | None = None, atol: float | None = None, record_dt: float | None = None,
                 stop_after: int | None = None):
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
        # (fixed steps: the pair that takes their stiff steps, ``kernel.advance``; K holds its stages too)
        self._S, self._SE, self._SP = _registered_arrays(STIFF_METHOD)
        self._stages = len(self._W) if self.adaptive else max(len(self._W), len(self._S))
        # The 2011 model (friction null, glued after a lift-off) is one kernel run, as before scene
        # version 3; any other contact is a sequence of runs, each in one mode (``_advance``).
        contact = scene.contact
        self.segmented = not (contact.friction is None and contact.after_liftoff == "glued" and not scene.dissipates)
        self._p = self._parameters(0.0)
        slip = start_slip(scene)
        slips = slip is not None and bool(np.any(slip != 0.0)) and contact.friction is not None
        # (a run whose contact changes mode writes its rows into the mode machine's, ``_room``: none of its own)
        own_rows = 0 if self.segmented else n_rows
        if slips:   # a start.omega that does not roll: the ball starts sliding
            s = scene.start
            d = self.landscape.evaluate(s.x, s.y, scene.parameter_values)
            velocity = np.array([s.vx, s.vy, d[1] * s.vx + d[2] * s.vy])
            state = sliding.BallState(s.x, s.y, velocity, np.array(s.omega), np.eye(3), 0.0)
            arrays = sliding.start_arrays(state, d, sliding=True, munthe_kaas=mk, stages=self._stages, rows=own_rows,
                                          radius=scene.ball.radius, mass=scene.ball.mass, resisted=scene.dissipates)
        else:
            arrays = kernel.run_arrays(kernel.state_size(mk, resisted=scene.dissipates), self._stages, own_rows)
            alpha, v = initial_state(self.landscape, scene)
            arrays["z"][:2], arrays["z"][2:5] = alpha, v
            if not mk:
                arrays["z"][5:14] = arrays["R"].ravel()
        arrays["info"][kernel.F_H] = self.dt
        self._finished = [0, 0, 0]   # steps, rejected tries and evaluations of the finished kernel runs
        # the runs after the first, where the contact changes mode (``stop_after``: the run ends
        # once it has this many transitions, ``ModeMachine``)
        self.machine = ModeMachine(self, Mode.SLIDING if slips else Mode.ROLLING,
                                   min(n_rows + CHANGE_ROWS, MAX_ROWS) if self.segmented else 0, stop_after=stop_after)
        if self.segmented:
            arrays["rows"] = self.machine.shared_rows(False, self._room(n_rows))
            self.machine.new_kernel_run(False)
        self._kernel: machine_code.Arguments | None = None   # the kernel call of the current kernel run
        self._arm(arrays, 0.0)
        self.status: Status | None = None
        s = scene.start
        if self.segmented and scene.dissipates and not slips and s.vx == 0.0 and s.vy == 0.0:
            # (a ball that starts still may be held where it is: it then stays, ``ModeMachine.hold``)
            spin = s.spin if s.omega is None else float(np.dot(s.omega, unit_normal(
                self.landscape.evaluate(s.x, s.y, scene.parameter_values))))
            self.machine.hold_at_start(s.x, s.y, spin)
        self._energy_check: EnergyCheck | None = None
        self._transition_check: TransitionCheck | None = None
        self.judge_energy = True  # whether the finished run looks at whose its energy error is (and its transitions)
        # whether the rows of a flight the kernel takes (in vacuum) hold their contact point; a
        # sweep's runs read only their last row's (``sweeps.batch.run_one``), and leave the others
        # NaN (their contact and slip speed), for the feet searched no more
        self.flight_contacts = True

    def _room(self, rows: float) -> int:
        """The rows a kernel run of a run whose contact changes mode finds free in the mode machine's,
        which it writes to (``ModeMachine.shared_rows``; a buffer of its own would hold the rows twice,
        millions recording every adaptive step, and first touching its pages took 1.2 ms of a
        fixed-step wells run's 5.1 ms): all it can write (``rows``), or SHARED_ROWS for an adaptive
        run recording every step, grown as it goes."""
        return SHARED_ROWS if self.adaptive and self.record_dt is None else math.ceil(rows)

    def _parameters(self, dissipated: float, dissipated_by=(0.0, 0.0, 0.0)) -> np.ndarray:
        """The kernel's parameters for a run that starts with ``dissipated`` J lost, ``dissipated_by``
        of it to rolling resistance, spin friction and air (``sliding.BallState``)."""
        scene = self.scene
        turn = kernel.TURN_SHARE * self.rtol if self.adaptive else 0.0
        if not self.segmented:
            return kernel.parameters(scene.ball.radius, scene.ball.mass, scene.gravity, turn)
        contact = scene.contact
        return kernel.parameters(scene.ball.radius, scene.ball.mass, scene.gravity, turn, friction=friction_of(contact),
                                 fly=contact.after_liftoff == "fly", dissipated=dissipated, stiff=True,
                                 rolling_resistance=contact.rolling_resistance, spin_friction=contact.spin_friction,
                                 air=scene.air.drag_factor(scene.ball.radius), causes=dissipated_by)

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
        if self._kernel is not None:   # (a later kernel run of this run: its own arrays, state and start)
            for key, value in arrays.items():
                self._kernel.set(key, value)
            self._kernel.set("p", self._p)
            self._kernel.set("t_start", t_start)
        elif self.adaptive:
            self._kernel = machine_code.Arguments(
                "advance_adaptive", fn=self._fn, W=self._W, E=self._E, P=self._P, p=self._p, err_kind=self._error_kind,
                err_exp=self.tableau.error_exponent, t_start=t_start, t_end=t_end, record_dt=self.record_dt or 0.0,
                rtol=self.rtol, atol=self.atol, max_steps=1, **arrays)
        else:
            self._kernel = machine_code.Arguments(
                "advance", fn=self._fn, W=self._W, P=self._P, p=self._p, dt=self.dt, t_start=t_start, t_end=t_end,
                n_steps=n_steps, every=self.record_every, max_steps=1, **arrays,
                stepping=kernel.IMPLICIT if self.tableau.kind is MethodKind.IMPLICIT else kernel.EXPLICIT,
                S=self._S, SE=self._SE, SP=self._SP, s_kind=len(self._SE) - 1,
                s_exp=METHODS[STIFF_METHOD].error_exponent, s_tol=stiff_tolerance(self.scene.contact))

    @property
    def done(self) -> bool:
        return self.status is not None

    @property
    def steps(self) -> int:
        return self._finished[0] + int(self._ints[kernel.I_STEPS])

    @property
    def rejected(self) -> int:
        """Steps tried and rejected by the adaptive method's error control (fixed steps: by their
        stiff pair's, ``kernel.advance``)."""
        return self._finished[1] + int(self._ints[kernel.I_REJECTED])

    @property
    def evaluations(self) -> int:
        """Right-hand-side evaluations so far, rejected tries included."""
        return self._finished[2] + int(self._ints[kernel.I_EVALS])

    @property
    def failure(self) -> Failure | None:
        """Why and where the physics stopped the run (None while it has not)."""
        if self.machine.off is not None:
            return self.machine.off
        reason = kernel.reason_name(int(self._ints[kernel.I_REASON]))
        if reason is None:
            return None
        info = self._info
        failure = Failure(Reason(reason), float(info[kernel.F_FAIL_T]), float(info[kernel.F_FAIL_X]),
                          float(info[kernel.F_FAIL_Y]), float(info[kernel.F_FAIL_VALUE]))
        return self._stiff_drag(failure) or failure

    def _stiff_drag(self, failure: Failure) -> Failure | None:
        """A kernel run's non-finite stop put down to the air where its drag is stiff beyond what
        the steps can take (``stiff_drag_row``; adaptive: the step that failed). None otherwise."""
        if failure.reason not in STIFF_DRAG_SIGNS:
            return None
        return self.stiff_drag_row(failure.value if self.adaptive else self.dt)

    def stiff_drag_row(self, step: float, rows: np.ndarray | None = None) -> Failure | None:
        """The first of ``rows`` (default: the run's) where the drag's rate k|ċ|/m times ``step`` is
        above DRAG_STIFF, where no explicit method is stable and an implicit one's stage equations
        do not converge: a failure there (the rows after it are the unstable steps' own); None if
        there is none. Asked where a fixed-step kernel run stops, however it stops (of that kernel
        run's rows): an unstable first step may blow up into a state that is finite but absurd (a
        lift-off with the centre 10⁴⁷ m away)."""
        rows = self.rows if rows is None else rows
        scene = self.scene
        drag = scene.air.drag_factor(scene.ball.radius)
        if not (drag > 0.0 and len(rows)):
            return None
        with np.errstate(all="ignore"):
            stiffness = drag / scene.ball.mass * step * np.linalg.norm(rows[:, VELOCITY], axis=1)
        beyond = np.flatnonzero(stiffness > DRAG_STIFF)
        if not len(beyond):
            return None
        row = rows[beyond[0]]
        return Failure(Reason.STIFF_DRAG, float(row[T]), float(row[CONTACT][0]), float(row[CONTACT][1]),
                       float(stiffness[beyond[0]]))

    @property
    def time(self) -> float:
        """Simulated time reached so far."""
        if self.segmented:
            if self.status is Status.OK:
                return self.t_end
            if self.machine.flight is not None:
                return self.machine.flight.start.t
            if self.machine.spin is not None:
                return self.machine.spin.t0
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
        return len(self.machine.out) if self.segmented else len(self._rows)

    @property
    def rows(self) -> np.ndarray:
        """The rows recorded so far (a view: copy what you keep)."""
        if self.segmented:
            return self.machine.rows
        return self._rows[: self._ints[kernel.I_ROWS]]

    def _row_count(self) -> int:
        return self.machine.count if self.segmented else int(self._ints[kernel.I_ROWS])

    @property
    def modes(self) -> np.ndarray:
        """The contact's mode of each row so far (positions in ``modes.MODES``)."""
        return self.machine.modes(self._row_count())

    @property
    def transitions(self) -> list[Transition]:
        """The run's transitions so far, in time order."""
        return self.machine.transitions

    @property
    def changes(self) -> list[Transition]:
        """Every change of mode the kernel runs stopped at (a slip that turns about too)."""
        return self.machine.changes

    @property
    def turns(self) -> list[tuple[float, float]]:
        """The (start, end) times (s) of the run's turns over a ridge or a tip so far: rows in them
        are the turn's (integrated apart from the kernel, rolling about the edge or tip)."""
        return self.machine.turns

    def advance(self, max_steps: int | None = None, *, rows: bool = True) -> np.ndarray | None:
        """Run up to ``max_steps`` more steps (a whole number >= 1; all remaining if None);
        return the new rows (a copy), or with ``rows=False`` nothing (for a caller that reads the
        trajectory at the end, or nothing: a whole run's copy of its rows is saved). Raises
        ``RuntimeError`` if another thread is advancing this run."""
        if max_steps is not None:
            if isinstance(max_steps, bool) or not isinstance(max_steps, numbers.Integral) or max_steps < 1:
                raise ValueError(f"max_steps must be a whole number of 1 or more, not {max_steps!r}")
            max_steps = int(max_steps)
        if not self._busy.acquire(blocking=False):
            raise RuntimeError("this Simulation is being advanced by another thread; "
                               "advance one Simulation from one thread at a time")
        try:
            first = self._advance(max_steps)
            return self.rows[first:].copy() if rows else None
        finally:
            self._busy.release()

    def _advance(self, max_steps: int | None) -> int:
        """Run as ``advance`` says; returns the number of rows before (the new rows' first)."""
        first = self._row_count()
        if self.done:
            return first
        if max_steps is not None:
            remaining = max_steps
        else:
            remaining = math.inf if self.adaptive or self.segmented else self.n_steps - self.steps
        while (remaining > 0 or self._row_count() == 0) and not self.done:
            if self.machine.flight is not None:   # a flight is taken whole, as one step
                self.machine.fly()
                remaining -= 1
                continue
            if self.machine.spin is not None:   # and so is a held ball's stay
                self.machine.stay()
                remaining -= 1
                continue
            chunk = int(min(remaining, CHUNK))
            if self.adaptive:
                if self._ints[kernel.I_ROWS] >= len(self._rows) - 2:
                    if self.segmented:
                        grown = self.machine.grow_shared(int(self._ints[kernel.I_ROWS]))
                    elif len(self._rows) < MAX_ROWS:
                        grown = np.empty((min(2 * len(self._rows), MAX_ROWS), kernel.ROW_SIZE))
                        grown[: len(self._rows)] = self._rows
                    else:
                        grown = None
                    if grown is None:  # stop rather than fill the memory
                        self.status = Status.ROW_LIMIT
                        break
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
                self.machine.collect()
            code = int(self._ints[kernel.I_STATUS])
            if code == kernel.TRANSITION:
                self.machine.stopped()
            elif code != kernel.RUNNING:
                self.status = _STATUS[code]
                break
        if self.judge_energy and self.status in (Status.OK, Status.DOES_NOT_FIT, Status.NONFINITE):
            # (here, where the run runs: never in the thread that reads the trajectory)
            self._energy_check = energy_check(self)
            self._transition_check = check_transitions(self)
        return first

    # -- the kernel runs of a run whose contact changes mode (mode_machine) -------------------

    def _probe_normal(self) -> np.ndarray:
        return self._probe[kernel.PROBE_N: kernel.PROBE_N + 3].copy()

    def _finish_kernel_run(self) -> None:
        self._finished[0] += int(self._ints[kernel.I_STEPS])
        self._finished[1] += int(self._ints[kernel.I_REJECTED])
        self._finished[2] += int(self._ints[kernel.I_EVALS])

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
        arrays = sliding.start_arrays(state, d, sliding=slides, munthe_kaas=self.munthe_kaas, stages=self._stages,
                                      rows=0, radius=self.scene.ball.radius, mass=self.scene.ball.mass,
                                      resisted=self.scene.dissipates)
        arrays["info"][kernel.F_H] = h
        arrays["rows"] = self.machine.shared_rows(repeat, self._room(rows))   # (only a segmented run has these)
        self.machine.new_kernel_run(repeat)
        self._p = self._parameters(state.dissipated, state.dissipated_by)
        self._arm(arrays, t)

    def from_state(self, state: sliding.BallState, t: float, mode: Mode, *, t_end: float, **options) -> "Simulation":
        """A run of this scene from ``state`` at time t in ``mode`` (ROLLING or SLIDING) to t_end,
        on the clock of a run from t = 0, with ``options`` (Simulation's), finished and not
        judged: a stretch taken again (the energy and transition checks, a stiff slip)."""
        run = type(self)(self.scene, t_end=t_end, **options)
        run.judge_energy = False
        run.machine.restart(mode)
        run._start_kernel_run(state, t, slides=mode == Mode.SLIDING, repeat=False)
        run.advance(rows=False)
        return run

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
            return self.machine.first_liftoff
        info = self._info
        if math.isnan(info[kernel.F_LIFTOFF]):
            return None
        return Liftoff(float(info[kernel.F_LIFTOFF]), float(info[kernel.F_LIFT_X]), float(info[kernel.F_LIFT_Y]),
                       bool(info[kernel.F_LIFT_KINK]))

    def message(self, status: Status | None = None) -> str:
        """How the run ended (or stands), in words."""
        status = status or self.status
        failure = self.failure
        if self.machine.stall is not None and status is Status.NONFINITE:
            return self.machine.stall
        if failure is not None and status in (Status.DOES_NOT_FIT, Status.NONFINITE):
            return describe(failure, self.scene.ball.radius)
        rest = self.machine.rest
        if status is Status.OK and rest is not None and self.scene.stop_at_rest:
            return kernel.transition_sentence("rest", rest.time, rest.x, rest.y)
        if status is Status.OK:
            rejected = f" ({self.rejected} rejected)" if self.adaptive else ""
            flew = any(change.kind == "landing" for change in self.transitions)
            through_air = self.scene.air.drag_factor(self.scene.ball.radius) > 0.0
            where = ("" if not flew else " on the surface (a flight is exact: no steps)" if not through_air else
                     " on the surface (a flight through air is integrated apart, to 10⁻¹³: its steps are not counted)")
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
        if scene.dissipates:
            c, air = scene.contact, scene.air
            provenance["dissipation"] = (f"rolling_resistance {c.rolling_resistance!r}, spin_friction "
                                         f"{c.spin_friction!r}, air density {air.density!r} kg/m^3, drag_coefficient "
                                         f"{air.drag_coefficient!r}, stop_at_rest {scene.stop_at_rest}")
        # rows are only ever appended: the trajectory can share them instead of copying
        return Trajectory(self.rows, status=status, message=message,
                          liftoff=self.liftoff, steps=self.steps, rejected=self.rejected,
                          evaluations=self.evaluations, failure=self.failure, mass=scene.ball.mass,
                          radius=scene.ball.radius, gravity=scene.gravity, provenance=provenance,
                          energy_check=self._energy_check, modes=self.modes if self.segmented else None,
                          transitions=tuple(self.transitions), transition_check=self._transition_check,
                          dissipates=scene.dissipates)


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
    run.advance(rows=False)
    return run.trajectory()
