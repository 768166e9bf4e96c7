"""Kernel runs in one contact mode from a given state, for the tests of slipping, gripping and
lift-off stops: the arrays ``rollball.sliding.start_arrays`` makes, stepped by the kernel's
entry points as ``Simulation`` steps them, until the run ends or stops at a change of mode."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rollball import kernel, machine_code
from rollball.geometry import unit_normal
from rollball.landscape import landscape_for
from rollball.simulation import initial_momentum
from rollball.sliding import BallState, rolling_omega, start_arrays, stopped_state
from rollball.tableaus import MethodKind, get_method


@dataclass
class Segment:
    rows: np.ndarray
    status: str
    transition: str | None
    event: tuple[float, float, float] | None   # time, x, y of the transition
    state: BallState                           # where the run stopped or ended
    force: float                               # F.N there
    need: float                                # the friction rolling needs there
    slip: np.ndarray                           # the slip velocity there
    steps: int
    turned: float = float("nan")   # a run that did not stop at a transition: its last couple's side turn (time)


def rolling_state(formula, x, y, vx, vy, spin=0.0, radius=0.1, mass=1.0) -> BallState:
    """The rolling start of a scene (``simulation.initial_momentum``) as a BallState."""
    d = landscape_for(formula).evaluate(x, y)
    normal = unit_normal(d)
    v = initial_momentum(d, vx, vy, spin, radius, mass)
    o = rolling_omega(v, normal, radius, mass)
    return BallState(x, y, radius * np.cross(o, normal), o, np.eye(3))


def segment(formula, state, *, sliding, method="rk4", dt=1e-3, t_end=1.0, mu=None, fly=False, radius=0.1,
            mass=1.0, gravity=9.81, munthe_kaas=True, rtol=1e-10, atol=1e-12, record_dt=None, every=1,
            max_rows=200_000, rolling_resistance=0.0, spin_friction=0.0, air=0.0):
    """A kernel run in one mode from ``state`` (``sliding`` or rolling); with ``rolling_resistance``,
    ``spin_friction`` or ``air`` (k, kg/m) its state carries the dissipation's quadratures."""
    resisted = rolling_resistance > 0.0 or spin_friction > 0.0 or air > 0.0
    landscape = landscape_for(formula)
    record = landscape.record(())
    tableau = get_method(method)
    W, E, P = tableau.kernel_arrays()
    p = kernel.parameters(radius, mass, gravity, kernel.TURN_SHARE * rtol if tableau.adaptive else 0.0,
                          friction=mu, fly=fly, dissipated=0.0 if sliding else state.dissipated,
                          rolling_resistance=rolling_resistance, spin_friction=spin_friction, air=air,
                          causes=state.dissipated_by)
    d = landscape.evaluate(state.x, state.y)
    if tableau.adaptive:
        rows = max_rows if record_dt is None else int(t_end / record_dt) + 3
    else:
        n_steps = max(1, math.ceil(t_end / dt - 1e-9))
        rows = 1 + n_steps // every + 1
    arrays = start_arrays(state, d, sliding=sliding, munthe_kaas=munthe_kaas, stages=len(W), rows=rows,
                          radius=radius, mass=mass, resisted=resisted)
    arrays["info"][kernel.F_H] = dt
    if tableau.adaptive:
        run = machine_code.Arguments("advance_adaptive", fn=record.ctypes.data, W=W, E=E, P=P, p=p, t_start=0.0,
                                     err_kind=max(len(E) - 1, 0), err_exp=tableau.error_exponent, t_end=t_end,
                                     record_dt=record_dt or 0.0, rtol=rtol, atol=atol, max_steps=10 ** 9, **arrays)
    else:
        run = machine_code.Arguments("advance", fn=record.ctypes.data, W=W, P=P, p=p, dt=dt, t_start=0.0, t_end=t_end,
                                     n_steps=n_steps, every=every, max_steps=10 ** 9, **arrays,
                                     stepping=kernel.IMPLICIT if tableau.kind is MethodKind.IMPLICIT
                                     else kernel.EXPLICIT, S=W, SE=W, SP=P, s_kind=0, s_exp=0.0, s_tol=0.0)
        # (p[P_STIFF] 0: the run steps on where it is stiff, and the pair S is never taken)
    ints, info = arrays["ints"], arrays["info"]
    while ints[kernel.I_STATUS] == kernel.RUNNING:
        run()
    status = kernel.KERNEL_STATUSES[ints[kernel.I_STATUS]]
    kind = kernel.transition_name(int(ints[kernel.I_TRANSITION]))
    event = None if kind is None else (float(info[kernel.F_EVENT_T]), float(info[kernel.F_EVENT_X]),
                                       float(info[kernel.F_EVENT_Y]))
    probe = arrays["probe"]
    normal = probe[kernel.PROBE_N:kernel.PROBE_N + 3]
    return Segment(arrays["rows"][:ints[kernel.I_ROWS]].copy(), status, kind, event,
                   stopped_state(arrays["z"], arrays["R"], p, normal), float(probe[kernel.PROBE_FORCE]),
                   float(probe[kernel.PROBE_NEED]), probe[kernel.PROBE_SLIP:kernel.PROBE_SLIP + 3].copy(),
                   int(ints[kernel.I_STEPS]), float("nan") if kind is not None else float(info[kernel.F_EVENT_T]))
