"""Changing the contact's mode between kernel runs: the ball's state where a run stopped, and the
kernel state a run in the next mode starts from (docs/design.md §1, "A run whose contact changes mode").

A run of the kernel follows one mode: rolling (the 2011 model's state: contact point and angular
momentum about it) or sliding (contact point, centre velocity, angular velocity and the energy
dissipated). It stops at a change of mode (status ``transition``: a lift-off, a slip or a grip)
with the state there in its arrays; ``stopped_state`` reads it as a ``BallState``, which is the
same in every mode, and ``start_arrays`` makes the arrays of a run in any mode from one:

- rolling → sliding (a slip): the same centre velocity c' = r omega x N and omega: the slip
  starts from zero, in the direction in which rolling would need more friction than mu F.N;
- sliding → rolling (a grip): v = (2/5) m r² omega + m r N x c', the angular momentum about the
  contact point (the kernel's v, ``interface``: T omega when the ball rolls, and kept by the
  impulse that stops a slip);
- the orientation R and the energy dissipated D go on as they are (a rolling run carries D in
  its parameters, ``kernel.parameters(..., dissipated=D)``, and records it in every row); so does
  the part of D that rolling resistance, spin friction and air took (``BallState.dissipated_by``:
  a run carries it in its parameters, ``causes``, and its state the energy they take in the run,
  the quadratures of a state ``kernel.state_size(..., resisted=True)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import kernel
from .geometry import cross, unit_normal


@dataclass(frozen=True)
class BallState:
    """The ball at one instant, whatever its mode: contact point, centre velocity, angular
    velocity (world frame), orientation (body to world) and the energy dissipated so far."""

    x: float
    y: float
    velocity: np.ndarray    # centre velocity c' (3, m/s)
    omega: np.ndarray       # angular velocity (3, rad/s)
    R: np.ndarray           # orientation (3, 3)
    dissipated: float = 0.0  # J
    # the part of ``dissipated`` rolling resistance, spin friction and air took (J each)
    dissipated_by: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def slip_velocity(self, normal: np.ndarray, radius: float) -> np.ndarray:
        """The velocity of the ball's material point at the contact, c' + omega x (-r N)."""
        return np.asarray(self.velocity) - radius * cross(self.omega, normal)

    def momentum(self, normal: np.ndarray, radius: float, mass: float) -> np.ndarray:
        """The angular momentum about the contact point, (2/5) m r² omega + m r N x c'."""
        return 0.4 * mass * radius * radius * np.asarray(self.omega) + mass * radius * cross(normal, self.velocity)


def rolling_omega(v: np.ndarray, normal: np.ndarray, radius: float, mass: float) -> np.ndarray:
    """omega = T⁻¹ v of a rolling ball, T⁻¹ = 5 / (7 m r²) (I + 5/2 N Nᵀ)."""
    return 5.0 / (7.0 * mass * radius * radius) * (v + 2.5 * np.dot(normal, v) * normal)


def stopped_state(z: np.ndarray, R: np.ndarray, p: np.ndarray, normal: np.ndarray) -> BallState:
    """The state a kernel run holds (its arrays z and R after it stopped, its parameters p and
    the unit normal at z's contact point, ``probe[PROBE_N:PROBE_N + 3]``), in every layout."""
    r, m = float(p[0]), float(p[1])
    n = len(z)
    resisted = n in _RESISTED
    if resisted:   # (the quadratures: the energy rolling resistance, spin friction and air took in this run)
        n -= kernel.QUADRATURES
    taken = z[n:n + kernel.QUADRATURES] if resisted else np.zeros(kernel.QUADRATURES)
    if n in kernel.SLIDING_SIZES:
        o = z[kernel.S_OMEGA:kernel.S_OMEGA + 3].copy()
        velocity = z[kernel.S_VELOCITY:kernel.S_VELOCITY + 3].copy()
        dissipated = float(z[kernel.S_DISSIPATED])
    else:
        o = rolling_omega(z[2:5], normal, r, m)
        velocity = r * cross(o, normal)
        dissipated = float(p[kernel.P_DISSIPATED])
    if n in (kernel.CLASSIC_SIZE, kernel.SLIDING_CLASSIC_SIZE):   # (the classic scheme holds R in z)
        R = z[n - 9:n].reshape(3, 3)
    by = tuple(float(c) for c in p[kernel.P_CAUSES:kernel.P_CAUSES + kernel.QUADRATURES] + taken)
    return BallState(float(z[0]), float(z[1]), velocity, o, np.array(R, dtype=float),
                     dissipated + float(taken.sum()) if resisted else dissipated, by)


_RESISTED = tuple(kernel.state_size(mk, slides, True) for mk in (True, False) for slides in (True, False))


def start_arrays(state: BallState, d: np.ndarray, *, sliding: bool, munthe_kaas: bool, stages: int, rows: int,
                 radius: float, mass: float, resisted: bool = False) -> dict[str, np.ndarray]:
    """The arrays of a kernel run (``kernel.run_arrays``) starting from ``state`` in the mode
    ``sliding`` (else rolling), for a method whose W has ``stages`` rows and ``rows`` rows to
    record; d: the landscape at the state's contact point (``Landscape.evaluate``); ``resisted``:
    the state carries the dissipation's quadratures (from 0; what came before is
    ``state.dissipated_by``, the run's parameters' ``causes``).

    Rolling from a state that slips takes its angular momentum about the contact point (a grip);
    sliding from a rolling state slips from zero (a slip)."""
    normal = unit_normal(np.asarray(d, dtype=float))
    arrays = kernel.run_arrays(kernel.state_size(munthe_kaas, sliding, resisted), stages, rows)
    z, R = arrays["z"], arrays["R"]
    z[0], z[1] = state.x, state.y
    if sliding:
        z[kernel.S_VELOCITY:kernel.S_VELOCITY + 3] = state.velocity
        z[kernel.S_OMEGA:kernel.S_OMEGA + 3] = state.omega
        z[kernel.S_DISSIPATED] = state.dissipated
        motion = kernel.SLIDING_MOTION_SIZE
    else:
        z[2:5] = state.momentum(normal, radius, mass)
        motion = kernel.MOTION_SIZE
    R[:] = state.R
    if not munthe_kaas:
        z[motion:motion + 9] = R.ravel()
    return arrays
