"""What compare mode runs: up to six variants of the current scene, each a method, its
orientation scheme and its step (or tolerance), with a colour; the presets; and the recording
that lets every run be measured against the one reference. No Qt here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rollball import METHODS, RunSpec, Scene, Simulation, parse_runs
from rollball.simulation import ADAPTIVE_ROWS, recording

from .compare_limit import MAX_RUNS
COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b")
MAX_REFERENCE_ROWS = 50_000     # the reference records at most about this many rows
COMMENSURATE = 1e-9             # steps whose ratio is this close to a whole number share row times

PRESETS = {
    "Euler vs RK4 vs Munthe-Kaas": "euler/classic,rk4/classic,rk4",
    "Classic against Munthe-Kaas": "euler/classic,euler,rk4/classic,rk4,lawson5/classic,lawson5",
    "Fixed steps against adaptive": "euler,rk4,lawson5,dopri5",
    "Every method": ",".join(list(METHODS)[:MAX_RUNS]),
}


@dataclass(frozen=True)
class CompareRun:
    """A run spec and its setting: the step size (fixed-step methods) or rtol (adaptive)."""

    spec: RunSpec
    setting: float

    @classmethod
    def of(cls, spec: RunSpec | str, scene: Scene) -> "CompareRun":
        """A spec with the scene's own step or tolerance."""
        spec = parse_runs(spec)[0] if isinstance(spec, str) else spec
        return cls(spec, scene.integrator.dt if spec.fixed_step else scene.integrator.rtol)

    @property
    def label(self) -> str:
        what = "h" if self.spec.fixed_step else "rtol"
        return f"{self.spec.label}, {what} = {self.setting:g}"

    def options(self) -> dict:
        """The ``Simulation`` keyword arguments of this run (without the recording)."""
        if self.spec.fixed_step:
            return {"method": self.spec.method, "munthe_kaas": self.spec.munthe_kaas, "dt": self.setting}
        return {"method": self.spec.method, "rtol": self.setting, "atol": self.setting * 1e-3}


def preset(name: str, scene: Scene) -> list[CompareRun]:
    return [CompareRun.of(spec, scene) for spec in parse_runs(PRESETS[name])]


def reference_spacing(runs: list[CompareRun], t_end: float) -> float:
    """The reference's row spacing: the smallest fixed step when every other fixed step is a
    whole multiple of it (so each run's rows meet reference rows often), made coarser if the
    reference would record more than ``MAX_REFERENCE_ROWS`` rows."""
    steps = sorted(run.setting for run in runs if run.spec.fixed_step)
    base = steps[0] if steps else t_end / ADAPTIVE_ROWS
    if any(abs(h / base - round(h / base)) > COMMENSURATE * h / base for h in steps):
        base = t_end / ADAPTIVE_ROWS   # no common grid: the runs meet it where they happen to
    return base * max(1, math.ceil(t_end / base / MAX_REFERENCE_ROWS))


def simulation(scene: Scene, run: CompareRun, spacing: float) -> Simulation:
    """The run's simulation, recorded for display on rows that meet the reference's: an
    adaptive run at a multiple of ``spacing``, a fixed-step one every N-th step as usual."""
    options = run.options()
    if run.spec.fixed_step:
        return Simulation(scene, **options, **recording(scene, method=run.spec.method, dt=run.setting))
    record_dt = spacing * max(1, math.ceil(scene.duration / ADAPTIVE_ROWS / spacing))
    return Simulation(scene, **options, record_dt=record_dt)


def warm_up(scene: Scene, run: CompareRun) -> Simulation:
    """A run of one step (or a millisecond) of the same method, to compile it untimed."""
    return Simulation(scene, **run.options(), t_end=run.setting if run.spec.fixed_step else 1e-3)
