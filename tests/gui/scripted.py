"""A run whose rows are written out from closed forms, handed to the window as a simulation would
hand them: the views of the contact's modes are tested on rows whose modes and transitions are
known exactly, whatever the integrators do.

On the plane z = 0: a ball struck at v₀ = 2 m/s without spin slides (μ = 0.2) until
t₁ = 2v₀/(7μg), then rolls at 5v₀/7; at t₂ it is thrown up at 1 m/s (a flight: a parabola,
normal force 0) and lands at t₃ = t₂ + 2/g, then rolls on. Friction dissipates 2/7 of the
kinetic energy (D = E₀ − E until the grip); the landing takes the throw's ½ m (1 m/s)².
"""

from __future__ import annotations

import numpy as np

from rollball import Scene, Status
from rollball.kernel.interface import ROW_SIZE, ROW_SLICES
from rollball.trajectory import FLYING, ROLLING, SLIDING, Transition

G, MU, V0, R, M = 9.81, 0.2, 2.0, 0.1, 1.0
T1 = 2 * V0 / (7 * MU * G)          # the slip ends
T2, UP = 0.6, 1.0                   # thrown up at 1 m/s
T3 = T2 + 2 * UP / G                # lands
T_END = 1.0
SCENE = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "0",
                         "gravity": G, "ball": {"radius": R, "mass": M},
                         "start": {"x": -1.0, "y": 0.0, "vx": V0, "vy": 0.0, "omega": [0.0, 0.0, 0.0]},
                         "contact": {"friction": MU, "restitution": 0.0, "after_liftoff": "fly"},
                         "integrator": {"method": "rk4", "dt": 0.01}, "duration": T_END,
                         "view": {"min": -1.5, "max": 1.5, "step": 0.1}})


def rows(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows at ``times`` and their modes (positions in ``trajectory.MODES``)."""
    v1 = 5 * V0 / 7
    x1 = -1.0 + V0 * T1 - 0.5 * MU * G * T1 ** 2
    out = np.zeros((len(times), ROW_SIZE))
    modes = np.zeros(len(times), dtype=np.int8)
    for k, t in enumerate(times):
        z, vz, force = R, 0.0, M * G
        if t < T1:
            mode, v, x = SLIDING, V0 - MU * G * t, -1.0 + V0 * t - 0.5 * MU * G * t * t
            w = 5 * MU * G * t / (2 * R)
        else:
            mode, v, w = ROLLING, v1, v1 / R
            x = x1 + v1 * (t - T1)
            if T2 <= t < T3:
                s = t - T2
                mode, z, vz, force = FLYING, R + UP * s - 0.5 * G * s * s, UP - G * s, 0.0
        row = out[k]
        row[ROW_SLICES["t"]] = t
        row[ROW_SLICES["contact"]] = (x, 0.0)
        row[ROW_SLICES["center"]] = (x, 0.0, z)
        row[ROW_SLICES["velocity"]] = (v, 0.0, vz)
        row[ROW_SLICES["omega"]] = (0.0, w, 0.0)
        row[ROW_SLICES["R"]] = np.eye(3).ravel()
        row[ROW_SLICES["energy"]] = 0.5 * M * (v * v + vz * vz) + 0.2 * M * R * R * w * w + M * G * z
        row[ROW_SLICES["normal_force"]] = force
        kinetic = 0.5 * M * v * v + 0.2 * M * R * R * w * w
        row[ROW_SLICES["slip_speed"]] = v - R * w   # the contact point's speed over the plane
        # what friction took (all the kinetic energy lost until the grip), then the landing's too
        row[ROW_SLICES["dissipated"]] = (0.5 * M * V0 * V0 - min(kinetic, 0.5 * M * V0 * V0)
                                         + (0.5 * M * UP * UP if t >= T3 else 0.0))
        modes[k] = mode
    return out, modes


TRANSITIONS = (Transition(T1, "grip", -1.0 + V0 * T1 - 0.5 * MU * G * T1 ** 2, 0.0),
               Transition(T2, "liftoff", float(rows(np.array([T2]))[0][0, 1]), 0.0),
               Transition(T3, "landing", float(rows(np.array([T3]))[0][0, 1]), 0.0, impact_speed=UP,
                          energy_lost=0.5 * M * UP * UP))


class ScriptedSimulation:
    """What the app's run controller and worker ask of a ``Simulation``, for the rows above:
    all of them in the first ``advance``."""

    def __init__(self, scene: Scene = SCENE, dt: float = 0.01):
        self.scene = scene
        self.t_end = T_END
        self._times = np.arange(0.0, T_END + dt / 2, dt)
        self._rows, self._modes = rows(self._times)
        self._count = 0
        self.status = None
        self.liftoff_time = T2
        self.adaptive = False
        self.steps = self.evaluations = 0

    @property
    def modes(self) -> np.ndarray:
        return self._modes[: self._count]

    @property
    def transitions(self) -> list:
        shown = self._times[self._count - 1] if self._count else -1.0
        return [c for c in TRANSITIONS if c.time <= shown]

    @property
    def row_capacity(self) -> int:
        return len(self._rows)

    @property
    def done(self) -> bool:
        return self.status is not None

    @property
    def progress(self) -> float:
        return 1.0 if self.done else 0.0

    def advance(self, max_steps=None) -> np.ndarray:
        self._count, self.status = len(self._rows), Status.OK
        return self._rows.copy()

    def cancel(self) -> None:
        if not self.done:
            self.status = Status.ABORTED

    def message(self, status=None) -> str:
        return "reached the end"


class RollingSimulation(ScriptedSimulation):
    """The same start, rolling all the way (no friction limit, nothing to fly over): no transitions."""

    def __init__(self, dt: float = 0.01):
        super().__init__(dt=dt)
        self._rows[:, ROW_SLICES["normal_force"]] = M * G
        self._modes[:] = ROLLING
        self.liftoff_time = None

    @property
    def transitions(self) -> list:
        return []


def compare_scripted(window, tmp_path):
    """The scripted scene opened in compare mode with two runs: one that slides and flies
    ("flies", ``ScriptedSimulation``) and one that only rolls ("rolls"), set up in the window as
    compare mode sets up its runs; the runs, not started."""
    from rollball_app.controller import Run

    open_scene(window, tmp_path)
    window.compare_action.setChecked(True)
    runs = [Run(ScriptedSimulation(), window.landscape, "flies", "#1f77b4"),
            Run(RollingSimulation(), window.landscape, "rolls", "#2ca02c")]
    window.view.set_runs([run.color for run in runs])
    window.readouts.set_runs([(run.label, run.color) for run in runs])
    return runs


def open_scene(window, tmp_path) -> None:
    """The scripted scene opened in the window (from a file in ``tmp_path``)."""
    SCENE.save(tmp_path / "billiard.json")
    window.files.open_scene(tmp_path / "billiard.json", remember=False)


def ready_to_play(window, tmp_path) -> "ScriptedSimulation":
    """The scripted scene opened, played as fast as computed over its time: its run, not started."""
    from .guitools import FASTEST

    open_scene(window, tmp_path)
    simulation = ScriptedSimulation()
    window.speed.setCurrentIndex(FASTEST)
    window.timeline.set_span(simulation.t_end)
    return simulation
