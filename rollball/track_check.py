"""A measured track against a run of a scene: the residuals, their RMS and maximum (docs/design.md §10).

The run records every step (fixed steps) or every accepted step (adaptive); the model's position
at a track's time is interpolated between the two rows around it:

- the centre by cubic Hermite interpolation from the rows' positions and velocities: its error is
  at most h⁴/384 · max|c⁗| (h the step: below 10⁻¹² m for 1 ms steps and 100 m/s⁴), far below
  any camera's millimetre. A landing changes the velocity at once; its row holds the velocity
  after the impact, so a step that ends at a landing is interpolated as the parabola through the
  two positions with the velocity at its start (its error h³/6 · max|c‴|).
- the contact point linearly (its velocity is not recorded): the error is at most h²/8 · max|α̈|,
  1 µm for 1 ms steps and 8 m/s²; its height is the landscape's at that point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fit_options import POINTS
from .landscape import landscape_of
from .scene import Scene
from .simulation import Simulation
from .track import AXES, Track
from .trajectory import Status, Trajectory

EXPLAINED, ROUGH = 1.5, 3.0             # residual RMS / noise: within the noise, roughly, not explained


def check_point(point: str) -> None:
    """Refuse (ValueError) a point of the ball that is not one of ``POINTS``."""
    if point not in POINTS:
        raise ValueError(f"point must be one of {', '.join(POINTS)}, not {point!r}")


def model_at(trajectory: Trajectory, scene: Scene, track: Track, point: str = "center") -> np.ndarray:
    """The run's positions at the track's times on the track's axes: (len(track), len(axes)).

    Times after the run's last row (a run the physics stopped) hold its last position."""
    check_point(point)
    t, times = trajectory.t, track.t
    if len(t) < 2:
        raise ValueError("the run has fewer than 2 rows: nothing to compare a track with")
    i = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    h = t[i + 1] - t[i]
    s = np.clip((times - t[i]) / h, 0.0, 1.0)[:, None]
    if point == "center":
        p0, p1 = trajectory.center[i], trajectory.center[i + 1]
        v0, v1 = trajectory.velocity[i] * h[:, None], trajectory.velocity[i + 1] * h[:, None]
        hermite = ((2 * s - 3) * s * s + 1) * p0 + ((s - 2) * s + 1) * s * v0 \
            + (3 - 2 * s) * s * s * p1 + (s - 1) * s * s * v1
        landing = np.isin(t[i + 1], [c.time for c in trajectory.transitions if c.kind == "landing"])
        parabola = p0 + s * v0 + s * s * (p1 - p0 - v0)
        position = np.where(landing[:, None], parabola, hermite)
    else:
        xy = trajectory.contact[i] + s * (trajectory.contact[i + 1] - trajectory.contact[i])
        z = landscape_of(scene).evaluate(xy[:, 0], xy[:, 1], scene.parameter_values)[0]
        position = np.column_stack([xy, z])
    return position[:, [AXES.index(axis) for axis in track.axes]]


def run_for(scene: Scene, track: Track) -> Trajectory:
    """A run of the scene to the track's last time (not its own duration), every step a row,
    without the energy and transition checks (the track is the check here)."""
    run = Simulation(scene, t_end=float(track.t[-1]))
    run.judge_energy = False
    run.advance(rows=False)
    return run.trajectory()


@dataclass(frozen=True)
class Residuals:
    """The track minus the model at the track's times, on the track's axes (metres).

    ``noise``: one coordinate's noise (m), given or estimated from the track (``Track.noise``);
    ``t_reached``: where the run ended (before the track's end if the physics stopped it)."""

    track: Track
    point: str
    model: np.ndarray
    noise: float
    noise_estimated: bool
    t_reached: float
    status: Status = Status.OK

    @property
    def values(self) -> np.ndarray:
        return self.track.positions - self.model

    @property
    def rms(self) -> float:
        """Root mean square over every measured coordinate (comparable with ``noise``)."""
        return float(np.sqrt(np.mean(self.values ** 2)))

    @property
    def distances(self) -> np.ndarray:
        """Each position's distance from the model's (m)."""
        return np.sqrt(np.sum(self.values ** 2, axis=1))

    @property
    def max(self) -> float:
        return float(self.distances.max())

    @property
    def max_time(self) -> float:
        return float(self.track.t[int(np.argmax(self.distances))])

    @property
    def per_axis(self) -> dict[str, tuple[float, float]]:
        """Axis -> (RMS, largest absolute residual), metres."""
        v = self.values
        return {axis: (float(np.sqrt(np.mean(v[:, k] ** 2))), float(np.max(np.abs(v[:, k]))))
                for k, axis in enumerate(self.track.axes)}

    @property
    def covered(self) -> bool:
        """Whether the run reached the track's last time."""
        return self.t_reached >= self.track.t[-1] * (1 - 1e-12)

    @property
    def ratio(self) -> float:
        """Residual RMS over the noise (about 1 when the model explains the track)."""
        return self.rms / self.noise if self.noise > 0 else math.inf

    @property
    def explained(self) -> bool:
        return self.covered and self.ratio <= EXPLAINED

    def verdict(self) -> str:
        """One sentence: whether the model explains the track, in words."""
        how = "estimated from the track" if self.noise_estimated else "given"
        noise = f"the track's noise ({_mm(self.noise)}, {how})"
        if not self.covered:
            return (f"the model does not explain the track: the run stopped at t = {self.t_reached:.6g} s "
                    f"({self.status}), before the track's end at {self.track.t[-1]:.6g} s")
        if self.ratio <= EXPLAINED:
            return f"the model explains the track: the residual RMS is {self.ratio:.2f} times {noise}"
        if self.ratio <= ROUGH:
            return (f"the model explains the track only roughly: the residual RMS is {self.ratio:.2f} times "
                    f"{noise}")
        return (f"the model does not explain the track: the residual RMS is {self.ratio:.3g} times {noise}, "
                f"far above it")

    def lines(self) -> list[str]:
        """The figures as the command line prints them."""
        axes = ", ".join(f"{axis} {_mm(rms)}" for axis, (rms, _) in self.per_axis.items())
        largest = ", ".join(f"{axis} {_mm(m)}" for axis, (_, m) in self.per_axis.items())
        return [(f"residual RMS {_mm(self.rms)} ({axes}); largest {_mm(self.max)} at t = {self.max_time:.6g} s "
                 f"(largest per axis: {largest})"),
                self.verdict()]


def residuals(scene: Scene, track: Track, point: str = "center", noise: float | None = None,
              trajectory: Trajectory | None = None) -> Residuals:
    """The track against a run of ``scene`` (made to the track's last time unless ``trajectory``
    is given): ``point`` "center" (the ball's centre) or "contact" (its contact point); ``noise``
    one coordinate's noise in metres, or None to estimate it from the track."""
    check_point(point)
    if noise is not None and not (math.isfinite(noise) and noise > 0):
        raise ValueError(f"the noise must be a finite number of metres above 0, not {noise!r}")
    traj = run_for(scene, track) if trajectory is None else trajectory
    return Residuals(track, point, model_at(traj, scene, track, point),
                     track.noise() if noise is None else float(noise), noise is None,
                     float(traj.t[-1]), traj.status)


def _mm(metres: float) -> str:
    return f"{metres * 1000:.3g} mm"
