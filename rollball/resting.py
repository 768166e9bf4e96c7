"""A ball that has stopped on the surface (docs/design.md §1, "Rest"): whether the couples and
friction can hold it where it stopped, and, held, its spin in place about the normal while spin
friction runs it down, in closed form. The mode machine decides with these what comes after a
stop; the ball is still (centre, contact point and normal force fixed) in every row made here."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .flight import energy
from .trajectory import CENTER, CONTACT, DISSIPATED, ENERGY, NORMAL_FORCE, OMEGA, SLIP_SPEED, T, VELOCITY, R

# tan θ may exceed a bound by this share of it and still be held: a plane tilted by exactly
# atan(c_rr) has a normal known to round-off only, and the exact ball stays there
HOLD_SLACK = 1e-12


def holds(normal: np.ndarray, *, rolling_resistance: float, friction: float) -> bool:
    """Whether a still ball touching the surface where its unit normal is ``normal`` stays. The
    contact force then balances gravity: its tangential part m g sin θ must be within μ F_n
    (F_n = m g cos θ, θ the tilt of the normal), and gravity's moment about the contact point,
    m g r sin θ, within the rolling couple's bound c_rr r F_n: tan θ ≤ c_rr and tan θ ≤ μ
    (``friction`` inf: always enough)."""
    cos = float(normal[2])
    if not cos > 0.0:
        return False
    tan = math.hypot(float(normal[0]), float(normal[1])) / cos
    bound = min(rolling_resistance, friction)
    return tan <= bound * (1.0 + HOLD_SLACK)


@dataclass(frozen=True)
class Spin:
    """A held ball spinning in place from time ``t0``: about the unit ``normal`` at ``spin`` s₀
    (rad/s, ω = s N), orientation ``R0`` then, its other values those of the row ``row`` (contact
    point, centre, the energy dissipated so far). Spin friction's couple μ_s r F_n against the
    spin, F_n = m g N_z, turns s down at the constant rate (5/2) μ_s F_n / (m r) (I = 2/5 m r²)
    until it is 0, R turning about N by the integral of s."""

    t0: float
    spin: float
    normal: np.ndarray
    R0: np.ndarray
    row: np.ndarray
    mass: float
    radius: float
    gravity: float
    spin_friction: float

    @property
    def normal_force(self) -> float:
        return self.mass * self.gravity * float(self.normal[2])

    @property
    def rate(self) -> float:
        """|ṡ| (rad/s²): (5/2) μ_s F_n / (m r)."""
        return 2.5 * self.spin_friction * self.normal_force / (self.mass * self.radius)

    @property
    def stop_time(self) -> float:
        """When the spin reaches 0: t0 + |s₀| / rate (t0 without spin; inf without spin friction)."""
        if self.spin == 0.0:
            return self.t0
        rate = self.rate
        return self.t0 + abs(self.spin) / rate if rate > 0.0 else math.inf

    def rows(self, times: np.ndarray) -> np.ndarray:
        """Recorded rows at ``times`` (each ≥ t0): the still ball, spinning at s(t) = s₀ − sign(s₀)
        rate (t − t0) until the stop and 0 after it, turned about N by φ(t) = ∫ s dt, its energy
        ½ I s² + m g c_z and what spin friction took, ½ I (s₀² − s²), added to the dissipated."""
        times = np.asarray(times, dtype=float)
        elapsed = np.minimum(times, self.stop_time) - self.t0
        sign = math.copysign(1.0, self.spin)
        spin = self.spin - sign * self.rate * elapsed if self.spin != 0.0 else np.zeros(len(times))
        angle = self.spin * elapsed - sign * 0.5 * self.rate * elapsed * elapsed if self.spin != 0.0 else spin
        n = self.normal
        cross = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
        turns = (np.eye(3) + np.sin(angle)[:, None, None] * cross
                 + (1.0 - np.cos(angle))[:, None, None] * (cross @ cross))   # Rodrigues: exp(φ [N]×)
        rows = np.repeat(self.row[None, :], len(times), axis=0)
        rows[:, T] = times
        rows[:, VELOCITY] = 0.0
        rows[:, OMEGA] = spin[:, None] * n
        rows[:, R] = (turns @ self.R0).reshape(-1, 9)
        inertia = 0.4 * self.mass * self.radius * self.radius
        rows[:, ENERGY] = energy(np.zeros(3), rows[:, OMEGA], rows[:, CENTER][:, 2], self.mass, self.radius,
                                 self.gravity)
        rows[:, NORMAL_FORCE] = self.normal_force
        rows[:, SLIP_SPEED] = 0.0
        rows[:, DISSIPATED] = self.row[DISSIPATED] + 0.5 * inertia * (self.spin * self.spin - spin * spin)
        return rows

    @property
    def contact(self) -> tuple[float, float]:
        x, y = (float(value) for value in self.row[CONTACT])
        return x, y
