"""A ball flying through air: m c̈ = m g − k |ċ| ċ, integrated; its landing found as in vacuum
(docs/design.md §1, "Flight with air").

The drag acts on the centre only (it exerts no torque in this model), so ω stays constant and
R(t) = exp(A(ω) τ) R₀ as in vacuum; the centre has no closed form in 3-D. Its position,
velocity and the energy the air has taken, D_air = ∫ k |ċ|³ dt, are integrated together by
scipy's DOP853 at RTOL (far below any run's tolerance), step by step as far as the landing
search looks, and read between steps from each step's dense output (7th order). The search of
``flight.Flight`` runs unchanged on that motion; the bounds it certifies steps with are the
honest ones with air:

- the speed: d|ċ|/dt = ĉ̇·g − (k/m)|ċ|² ≤ g − (k/m)|ċ|², so |ċ| never exceeds
  U = max(|ċ(t)|, v_t) after t (v_t = √(m g / k), the terminal speed), nor |ċ(t)| + g τ;
- the acceleration: |c̈| ≤ g + (k/m)|ċ|² ≤ g + (k/m) U² (``pull``), so the path lies within
  that times (s − t)²/8 of its chord (``sag``) and is at most ∫ min(|ċ(t)| + g τ, U) dτ long
  (``path_time``).
"""

from __future__ import annotations

import math

import numpy as np

from .flight import Flight, FreeState, Surface
from .trajectory import DISSIPATED, ROW_CAUSES

ROW_AIR = ROW_CAUSES["air"]
RTOL = 1e-13   # DOP853's relative tolerance for the centre's motion (its error measured: tests/test_drag_flight.py)
MAX_STEPS = 50_000   # DOP853's steps a flight may take (a few seconds' CPU): in thick air the motion is stiff,
#                      the steps ≲ 3/√(g k/m) (the drag's rate at v_t), and a flight of T s takes about T √(g k/m)/3
SEEN_AT_ONCE = 64   # a call for at most this many times keeps what they gave (the search's looks)...
SEEN_MOST = 1024    # ...up to this many times in all (then it starts again)


class DragFlight(Flight):
    """A flight through air, drag factor ``drag`` = k = ½ ρ C_d π r² (kg/m, > 0): its state at
    any time from the integrated motion, the energy the air took (``air_dissipated``), and the
    landing (``Flight.landing``, searched in Python: the kernel's search follows a parabola)."""

    compiled = False

    def __init__(self, surface: Surface, start: FreeState, *, radius: float, mass: float, gravity: float,
                 drag: float):
        if not (drag > 0.0 and math.isfinite(drag)):
            raise ValueError(f"drag must be a finite number greater than 0 (got {drag!r})")
        super().__init__(surface, start, radius=radius, mass=mass, gravity=gravity)
        from scipy.integrate import DOP853   # (scipy loads with a flight, not with the program)

        self.drag = drag
        self.rate = drag / mass                          # k/m (1/m)
        self.terminal = math.sqrt(gravity / self.rate)   # v_t (m/s): drag balances gravity
        self._start = np.concatenate([start.center, start.velocity, [0.0]])
        with np.errstate(all="ignore"):   # (the scale and its first step's choice: an overflow fails the first step)
            length = max(radius, float(np.abs(start.center).max()))
            fast = max(float(np.linalg.norm(start.velocity)), self.terminal, math.sqrt(gravity * radius))
            scale = np.array([length] * 3 + [fast] * 3 + [mass * (fast * fast + gravity * length)])
            self._solver = DOP853(self._motion, start.t, self._start, t_bound=math.inf, rtol=RTOL, atol=RTOL * scale)
        self._ends = [start.t]   # the steps' ends so far...
        self._pieces = []        # ...and their dense outputs
        self._seen: dict[float, np.ndarray] = {}   # y at the times asked about lately

    def _motion(self, t: float, y: np.ndarray) -> np.ndarray:
        """(ċ, g − (k/m)|ċ| ċ, k |ċ|³) for y = (c, ċ, D_air)."""
        v = y[3:6]
        speed = np.sqrt(v @ v)   # (a numpy float: an overflow is inf, a failed step, not an exception)
        out = np.empty(7)
        out[:3] = v
        out[3:6] = self.g - (self.rate * speed) * v
        out[6] = self.drag * speed ** 3
        return out

    def _states(self, times: np.ndarray) -> np.ndarray:
        """y = (c, ċ, D_air) at ``times`` (≥ the start), (n, 7). The search asks about a few times
        at a time, mostly ones it asked about before (a look's gap, then ``sag``, ``path_time`` and
        ``clear`` there): what a few times gave is kept (up to SEEN_MOST of them)."""
        times = np.asarray(times, dtype=float)
        if len(times) > SEEN_AT_ONCE:
            return self._evaluate(times)
        keys = times.tolist()
        missing = [i for i, key in enumerate(keys) if key not in self._seen]
        if missing:
            if len(self._seen) + len(missing) > SEEN_MOST:
                self._seen.clear()
            for i, y in zip(missing, self._evaluate(times[missing])):
                self._seen[keys[i]] = y
        return np.array([self._seen[key] for key in keys]).reshape(-1, 7)

    def _evaluate(self, times: np.ndarray) -> np.ndarray:
        """y at ``times``: the steps taken on as far as the latest, each time read from the dense
        output of the step it falls in (the start's exactly)."""
        out = np.empty((len(times), 7))
        if not len(times):
            return out
        solver, latest = self._solver, float(times.max())
        while self._ends[-1] < latest:
            if len(self._pieces) >= MAX_STEPS:
                raise FloatingPointError(
                    f"the air's drag (k = {self.drag:.6g} kg/m) is so strong that the flight after "
                    f"t = {solver.t:.6g} s takes more than {MAX_STEPS:,} steps to integrate (the drag makes its "
                    f"motion stiff), so the run stops")
            if not solver.h_abs > 0.0:   # (an overflowing motion leaves no step to try: scipy would try it for ever)
                failed = True
            else:
                with np.errstate(all="ignore"):   # (an overflow is told below)
                    solver.step()
                failed = solver.status == "failed" or not np.isfinite(solver.y).all()
            if failed:
                raise FloatingPointError(
                    f"the air's drag (k = {self.drag:.6g} kg/m) slows the flying ball faster than its flight can "
                    f"be integrated after t = {solver.t:.6g} s, so the run stops")
            self._pieces.append(solver.dense_output())
            self._ends.append(solver.t)
        last = max(len(self._pieces) - 1, 0)
        index = np.clip(np.searchsorted(self._ends, times, side="right") - 1, 0, last)
        for i in np.unique(index):
            at = index == i
            out[at] = self._pieces[i](times[at]).T if self._pieces else self._start
        out[times == self.start.t] = self._start
        return out

    def centers(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        y = self._states(times)
        return y[:, :3], y[:, 3:6]

    def center_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        centers, velocities = self.centers(np.array([t]))
        return centers[0], velocities[0]

    def air_dissipated(self, times: np.ndarray) -> np.ndarray:
        """The energy the air took from the flight's start to each of ``times``: ∫ k |ċ|³ dt (J)."""
        return self._states(times)[:, 6]

    def pull(self, speed: float) -> float:
        """|c̈| ≤ g + (k/m) max(|ċ|, v_t)² from a time the speed is ``speed`` on."""
        top = max(speed, self.terminal)
        return self.gravity + self.rate * top * top

    def sag(self, t: float, s: float) -> float:
        """The farthest the path between t and s departs from its chord: ``pull`` (s − t)²/8 (a
        curve whose second derivative is at most A in size lies within A (s − t)²/8 of its chord)."""
        speed = float(np.linalg.norm(self.centers(np.array([t]))[1][0]))
        delta = s - t
        return self.pull(speed) * delta * delta / 8.0

    def path_time(self, t: float, length: float, velocity=None) -> float:
        """A time Δ after t over which the centre's path is at most ``length`` long: its speed is at
        most min(|ċ(t)| + g τ, U), U = max(|ċ(t)|, v_t), whose integral is ``length`` at Δ
        (``velocity``: the centre's at t, where the caller has it)."""
        if not length > 0.0:
            return 0.0
        velocity = self.centers(np.array([t]))[1][0] if velocity is None else velocity
        speed, g = float(np.linalg.norm(velocity)), self.gravity
        top = max(speed, self.terminal)
        if not top > 0.0:
            return math.inf
        rise = (top - speed) / g if g > 0.0 else 0.0   # the time the bound speed + g τ takes to reach U
        ramp = speed * rise + 0.5 * g * rise * rise     # the path's bound over it
        if length <= ramp:
            return 2.0 * length / (speed + math.sqrt(speed * speed + 2.0 * g * length))
        return rise + (length - ramp) / top

    def rows(self, times: np.ndarray, dissipated: float, guess=None) -> np.ndarray:
        """``Flight.rows``, the energy the air took since the start added to ``dissipated`` and in
        the air's column (what it took before the flight the mode machine adds there)."""
        rows = super().rows(times, dissipated, guess)
        air = self.air_dissipated(times)
        rows[:, DISSIPATED] += air
        rows[:, ROW_AIR] = air
        return rows


def new_flight(surface: Surface, start: FreeState, *, radius: float, mass: float, gravity: float,
               drag: float = 0.0) -> Flight:
    """The flight from ``start``: in vacuum (closed form, ``Flight``) where the drag factor k is 0,
    else through air (``DragFlight``)."""
    if drag == 0.0:
        return Flight(surface, start, radius=radius, mass=mass, gravity=gravity)
    return DragFlight(surface, start, radius=radius, mass=mass, gravity=gravity, drag=drag)
