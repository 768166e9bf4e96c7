"""One batch of a sweep: runs lo .. hi-1 of the grid, from scene values to outcomes.

``run(task)`` is what a local thread or a Dask worker executes: it validates the varied
scenes, computes the initial states for the whole batch at once and runs them all in one
call of the compiled batch loop (``kernel.batch.advance_batch``, which releases the GIL): the
2011 model's runs, and those of a ball that rolls, slips, grips and flies in vacuum; a run the
loop leaves to the mode machine, and every run of a scene whose ball can come to rest (or starts
with an omega that slips), goes through ``Simulation`` (``run_one``). The same
batch gives the same numbers bit for bit wherever it runs. A process compiles the landscape once, on its
first batch, and keeps it for the rest.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .. import kernel, machine_code
from ..landscape import landscape_of
from ..flight import KEPT_ROWS, bounce_scratch, rest_speed
from ..modes import FLYING, ROLLING, SLIDING, Change
from ..run_size import step_count
from ..scene import Scene, SceneError
from ..mode_machine import FRICTION_CAP, STIFF_METHOD, stiff_tolerance
from ..simulation import Simulation, initial_momentum
from ..tableaus import METHODS, MethodKind, get_method
from ..trajectory import CENTER, VELOCITY, Status
from .grid import KEYS, PARAMETER_PREFIX, Grid, value_of, with_values
from .outcomes import (INVALID, NOT_RUN, O_END_MODE, O_FIRST_GRIP, O_FIRST_SLIP, O_LANDINGS, O_REST_TIME, O_REST_X,
                       O_REST_Y, OUTCOMES)

_COMPILE_LOCK = threading.Lock()  # threads of one process compile a landscape once


def sweep_method(scene: Scene):
    """The scene's method if a sweep can run it (the explicit fixed-step ones), else ValueError."""
    method = get_method(scene.integrator.method)
    if method.kind is not MethodKind.FIXED:
        fixed = ", ".join(m.name for m in METHODS.values() if m.kind is MethodKind.FIXED)
        raise ValueError(f"sweeps run the explicit fixed-step methods ({fixed}); "
                         f"this scene's integrator.method is {method.name}")
    return method


@dataclass(frozen=True)
class Task:
    """Everything a batch needs, small enough to send to another machine."""

    scene: Scene
    grid: Grid
    lo: int
    hi: int


@dataclass
class Result:
    lo: int
    status: np.ndarray      # (runs,) int8 status codes (kernel codes, INVALID)
    outcomes: np.ndarray    # (runs, len(OUTCOMES))
    messages: dict          # run index (in the grid) -> why its scene was refused


def _columns(scene: Scene, grid: Grid, values: np.ndarray) -> dict[str, np.ndarray]:
    """Every key's value per run the batch loop reads: the varied column or the scene's own value
    (a null friction inf)."""
    keys = [key for key in KEYS if not key.startswith(CONTACT_PREFIX) and key not in DISSIPATION_KEYS]
    keys += [RESTITUTION, FRICTION]
    keys += [PARAMETER_PREFIX + name for name in scene.parameter_names]
    return {key: values[:, grid.keys.index(key)] if key in grid.keys else np.full(len(values), value_of(scene, key))
            for key in keys}


def validate(scene: Scene, grid: Grid, values: np.ndarray) -> dict[int, str]:
    """Row -> message for the runs whose varied scene is refused, each checked like a scene file.

    Scene constraints tie no start value to another key, so each varied start key is checked
    value by value, and the other varied keys together, once per distinct combination.
    """
    groups = [[k] for k in grid.keys if k.startswith("start.")]
    rest = [k for k in grid.keys if not k.startswith("start.")]
    groups += [rest] if rest else []
    messages: dict[int, str] = {}
    for group in groups:
        columns = values[:, [grid.keys.index(k) for k in group]]
        combos, inverse = np.unique(columns, axis=0, return_inverse=True)
        for i, combo in enumerate(combos):
            refusal = _refusal(scene, tuple(group), tuple(float(v) for v in combo))
            if refusal:  # the key and value named, whatever the message says
                refusal = f"{refusal} ({', '.join(f'{k} = {float(v)!r}' for k, v in zip(group, combo))})"
                for row in np.flatnonzero(inverse.ravel() == i):
                    messages.setdefault(int(row), refusal)
    return messages


@lru_cache(maxsize=1 << 16)  # batches of a grid share most values: each is checked once per process
def _refusal(scene: Scene, keys: tuple, values: tuple) -> str | None:
    varied = _varied(scene, keys, values)
    return varied if isinstance(varied, str) else None


@lru_cache(maxsize=1 << 12)  # (more than a batch's runs: a run's scene made by validate is reused)
def _varied(scene: Scene, keys: tuple, values: tuple) -> Scene | str:
    """The scene with these values (``with_values``), or why it is refused. (In a sweep of one
    key, or of keys checked together, each run's scene is made and checked once.)"""
    try:
        varied = with_values(scene, keys, values)
        step_count(varied.integrator.dt, varied.duration)  # a dt of 1e-300: too many steps
    except (SceneError, ValueError) as e:
        return str(e)
    return varied


def _landscape(scene: Scene):
    """The scene's landscape, its machine code made: one compile for every run of a sweep
    (parameters' values are arguments). The caller holds it while the kernel runs it."""
    with _COMPILE_LOCK:
        landscape = landscape_of(scene)
        landscape.compiled  # noqa: B018 - made now, under the lock
        return landscape


CONTACT_PREFIX = "contact."
RESTITUTION, FRICTION = "contact.restitution", "contact.friction"   # (the contact keys the batch loop reads)


# Keys that give a rolling ball a loss of energy, and so a rest (scene version 4).
DISSIPATION_KEYS = ("contact.rolling_resistance", "contact.spin_friction", "air.density", "air.drag_coefficient")


def _slips_or_rests(scene: Scene, keys=()) -> bool:
    """Whether the runs' ball can slip (``_slips``) or come to rest (``_rests``)."""
    return _slips(scene, keys) or _rests(scene, keys)


def _slips(scene: Scene, keys=()) -> bool:
    """Whether the runs' ball can slip: a friction, or one varied."""
    return scene.contact.friction is not None or FRICTION in keys


def _rests(scene: Scene, keys=()) -> bool:
    """Whether the runs' ball can come to rest: a dissipation, or one varied."""
    return scene.dissipates or any(key in DISSIPATION_KEYS for key in keys)


def changes_mode(scene: Scene, keys=()) -> bool:
    """Whether the runs' contact can change mode (the 2011 model's ball rolls for ever): it can
    fly, or slip, or it dissipates (it may come to rest), or a sweep varying ``keys`` gives it a
    friction or a dissipation."""
    return scene.contact.after_liftoff != "glued" or _slips_or_rests(scene, keys)


def compiled(scene: Scene, keys=()) -> bool:
    """Whether the batch loop runs the runs itself (``kernel.batch``): the 2011 model, or a ball
    that rolls, slips, grips and flies in vacuum (no dissipation, a start that rolls); else each run
    goes through ``Simulation``. (The loop leaves a run it cannot finish so to ``Simulation`` too:
    REFERRED.)"""
    return not _rests(scene, keys) and (scene.start.omega is None or not _slips(scene, keys))


_CODES = {Status.OK: kernel.OK, Status.DOES_NOT_FIT: kernel.DOES_NOT_FIT, Status.NONFINITE: kernel.NONFINITE}


def run_one(scene: Scene) -> tuple[int, np.ndarray]:
    """A run of a scene whose contact changes mode, through ``Simulation`` (every step a row; a
    flight's rows in vacuum without their contact point but the last, which the outcomes read),
    and its status code and outcomes: those of the batch loop, from the rows, then the contact's
    and where and when it came to rest (the basin is left NaN: ``runner.sweep`` gives it)."""
    simulation = Simulation(scene, record_every=1)
    simulation.judge_energy = simulation.flight_contacts = False
    simulation.advance(rows=False)
    traj = simulation.trajectory()
    out = np.full(len(OUTCOMES), np.nan)
    rows = len(traj)
    if rows:
        # the centre's and the velocity's columns, each made contiguous at once (one pass over the rows)
        cx, cy, cz, vx, vy, vz = traj.data[:, CENTER.start:VELOCITY.stop].T.copy()
        dx, dy, dz = np.diff(cx), np.diff(cy), np.diff(cz)
        # (the squares summed as np.linalg.norm does; the steps in order, as the batch loop sums them)
        path = float(np.cumsum(np.sqrt(dx * dx + dy * dy + dz * dz))[-1]) if rows > 1 else 0.0
        out[:len(kernel.OUTCOMES)] = (traj.t[-1], np.nan if traj.liftoff_time is None else traj.liftoff_time,
                                      traj.contact[-1, 0], traj.contact[-1, 1], traj.energy_drift,
                                      float(np.min(traj.normal_force)),
                                      math.sqrt(float(np.max(vx * vx + vy * vy + vz * vz))), path)
        out[O_END_MODE] = ROLLING if traj.modes is None else traj.modes[rows - 1]   # (no modes: it rolls)
    out[O_LANDINGS] = traj.landings
    # a ball that slides from its start (a start.omega that does not roll) slips at t = 0
    slides = rows and traj.modes is not None and traj.modes[0] == SLIDING
    slips = [float(traj.t[0])] if slides else []
    slips += [change.time for change in traj.transitions if change.kind is Change.SLIP]
    out[O_FIRST_SLIP] = slips[0] if slips else np.nan
    grips = [change.time for change in traj.transitions if change.kind is Change.GRIP]
    out[O_FIRST_GRIP] = grips[0] if grips else np.nan
    rest = next((change for change in traj.transitions if change.kind == Change.REST), None)
    if rest is not None:   # (the basin is the sweep's: from every run's resting point at once)
        out[[O_REST_X, O_REST_Y, O_REST_TIME]] = rest.x, rest.y, rest.time
    return _CODES[traj.status], out


def run(task: Task) -> Result:
    scene, grid = task.scene, task.grid
    values = grid.values(task.lo, task.hi)
    runs = len(values)
    method = sweep_method(scene)
    messages = validate(scene, grid, values)
    status = np.full(runs, NOT_RUN, dtype=np.int64)
    status[list(messages)] = INVALID
    if not compiled(scene, grid.keys):
        outcomes = np.full((runs, len(OUTCOMES)), np.nan)
        _run_each(scene, grid, values, np.flatnonzero(status != INVALID), status, outcomes)
        return Result(task.lo, status.astype(np.int8), outcomes,
                      {task.lo + i: text for i, text in messages.items()})
    c = _columns(scene, grid, values)
    landscape = _landscape(scene)   # held while the kernel runs it: its machine code lives as long
    names = [PARAMETER_PREFIX + name for name in scene.parameter_names]
    parameter_values = np.stack([c[key] for key in names], axis=1) if names else np.empty((runs, 0))
    # the runs of one set of parameter values share a landscape record: a kernel call each
    sets, of_set = np.unique(parameter_values, axis=0, return_inverse=True)
    of_set = of_set.ravel()
    r, m = c["ball.radius"], c["ball.mass"]
    # (a ball that can slip: Munthe-Kaas states, as ``Simulation``'s, whose stiff stretches the pair takes)
    slips = _slips(scene, grid.keys)
    size = kernel.MK_SIZE if slips else kernel.MOTION_SIZE
    with np.errstate(all="ignore"):  # refused runs may hold any value; they are not run
        z0 = np.zeros((runs, size))
        z0[:, 0], z0[:, 1] = c["start.x"], c["start.y"]
        for k, values_k in enumerate(sets):
            these = of_set == k
            d = landscape.evaluate(c["start.x"][these], c["start.y"][these], values_k)
            z0[these, 2:5] = initial_momentum(d, c["start.vx"][these], c["start.vy"][these], c["start.spin"][these],
                                              r[these], m[these]).T
        # (as ``Simulation._parameters`` gives a run whose contact changes mode)
        segmented, flies = changes_mode(scene, grid.keys), scene.contact.after_liftoff == "fly"
        mu = c[FRICTION]   # (``mode_machine.friction_of``: inf, or at most FRICTION_CAP)
        friction = np.where(mu < np.inf, np.minimum(mu, FRICTION_CAP), np.inf)
        p = np.ascontiguousarray(kernel.parameters(r, m, c["gravity"], friction=friction, fly=flies,
                                                   stiff=segmented).T)
        restitution = c[RESTITUTION]
        bounce = np.stack([restitution, rest_speed(r, c["gravity"])], axis=1)
    dt, t_end = c["integrator.dt"], c["duration"]
    n_steps = np.ones(runs, dtype=np.int64)
    pairs = np.stack([dt, t_end], axis=1)
    combos, inverse = np.unique(pairs, axis=0, return_inverse=True)
    for i, (h, t) in enumerate(combos):
        if h > 0 and t > 0:
            try:
                n_steps[inverse.ravel() == i] = step_count(float(h), float(t))
            except ValueError:  # too many steps: refused by validate, not run
                pass
    outcomes = np.full((runs, kernel.BATCH_OUT), np.nan)   # the batch loop's
    W, _, D = method.kernel_arrays()
    S, SE, SP = METHODS[STIFF_METHOD].kernel_arrays()
    stages = max(len(W), len(S)) if slips else len(W)
    stiff = dict(zs=np.zeros(kernel.SLIDING_MK_SIZE), Ks=np.zeros((kernel.stage_rows(stages), kernel.SLIDING_MK_SIZE)),
                 S=S, SE=SE, SP=SP, s_kind=len(SE) - 1, s_exp=METHODS[STIFF_METHOD].error_exponent,
                 s_tol=stiff_tolerance(scene.contact))
    tape = landscape.tape
    flight = dict(tape=tape, flight=np.empty(10), turned=np.empty((3, 3)), flown=np.empty(kernel.OUT_BOUNCES),
                  flown_rows=np.empty((KEPT_ROWS, kernel.ROW_SIZE)), **bounce_scratch(len(tape)))
    for k, values_k in enumerate(sets):
        these = np.flatnonzero(of_set == k)
        whole = len(these) == runs   # (no copies for a sweep of one set of values)
        part = (lambda a: a) if whole else (lambda a: np.ascontiguousarray(a[these]))
        record = landscape.record(values_k)
        part_status, part_outcomes = part(status), part(outcomes)
        machine_code.call("advance_batch", fn=record.ctypes.data, W=W, P=D, Z0=part(z0), PARAMS=part(p),
                          DT=part(np.ascontiguousarray(dt)), T_END=part(np.ascontiguousarray(t_end)),
                          N_STEPS=part(n_steps), BOUNCE=part(bounce), status=part_status, out=part_outcomes,
                          acc=np.empty(kernel.BATCH_ACCUMULATORS), p=np.empty(kernel.P_SIZE), **flight, **stiff,
                          **kernel.run_arrays(size, stages, kernel.BATCH_ROWS))
        if not whole:
            status[these], outcomes[these] = part_status, part_outcomes
    # the batch loop's runs roll, slip, grip and fly (no rest): the contact's outcomes from its columns
    done = status != INVALID
    flying, sliding = outcomes[:, kernel.O_FLIES] == 1.0, outcomes[:, kernel.O_SLIDES] == 1.0
    contact = np.full((runs, len(OUTCOMES) - len(kernel.OUTCOMES)), np.nan)
    contact[done, O_END_MODE - len(kernel.OUTCOMES)] = np.where(flying[done], FLYING,
                                                                np.where(sliding[done], SLIDING, ROLLING))
    for column, of in ((O_LANDINGS, kernel.O_LANDINGS), (O_FIRST_SLIP, kernel.O_FIRST_SLIP),
                       (O_FIRST_GRIP, kernel.O_FIRST_GRIP)):
        contact[done, column - len(kernel.OUTCOMES)] = outcomes[done, of]
    outcomes = np.column_stack([outcomes[:, :len(kernel.OUTCOMES)], contact])
    # the runs it left to the mode machine
    _run_each(scene, grid, values, np.flatnonzero(status == kernel.REFERRED), status, outcomes)
    messages = {task.lo + i: text for i, text in messages.items()}
    return Result(task.lo, status.astype(np.int8), outcomes, messages)


def _run_each(scene: Scene, grid: Grid, values: np.ndarray, runs, status: np.ndarray, outcomes: np.ndarray) -> None:
    """Run each of ``runs`` (rows of ``values``, valid) through ``Simulation`` (``run_one``)."""
    for i in runs:
        varied = _varied(scene, grid.keys, tuple(float(v) for v in values[i]))  # (valid: checked above)
        status[i], outcomes[i] = run_one(varied)
