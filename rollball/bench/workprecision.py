"""Work against precision: every method over a range of steps (or tolerances) on example
scenes, error at the final time against a tight reference, wall time and step count.

As in DiffEqDevTools' ``WorkPrecision``: one untimed run measures the error, then
repeated timed runs measure the cost (their median). scipy's DOP853 on the same equations
(``reference.reference_rhs``) over a range of tolerances is the baseline a Python user
would otherwise write.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..examples import EXAMPLES_DIR
from ..landscape import landscape_for
from ..reference import reference_rhs, reference_solution
from ..scene import Scene
from ..simulation import Simulation, initial_state
from .. import trajectory as row_layout


@dataclass(frozen=True)
class Sweep:
    """One line of the work-precision plot: a method and the settings it is run at."""

    label: str
    method: str           # a name in METHODS, or "scipy-dop853"
    munthe_kaas: bool
    setting: str          # "dt" or "rtol"
    values: tuple[float, ...]


@dataclass(frozen=True)
class Point:
    scene: str
    label: str
    setting: str
    value: float
    steps: int
    seconds: float
    error_alpha: float
    error_R: float


def sweeps(quick: bool) -> list[Sweep]:
    dts = {
        "euler": (1e-3, 3e-4, 1e-4) if quick else (1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5),
        "rk4": (2e-2, 5e-3, 1e-3) if quick else (5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3),
        "lawson5": (2e-2, 5e-3, 1e-3) if quick else (5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3),
    }
    result = [Sweep(f"{name} {'MK' if mk else 'classic'}", name, mk, "dt", values)
              for name, values in dts.items() for mk in (True, False)]
    tolerances = (1e-4, 1e-7, 1e-10) if quick else tuple(10.0 ** -k for k in range(3, 12))
    result.append(Sweep("adaptive (DP5(4) MK)", "dopri5", True, "rtol", tolerances))
    scipy_tolerances = (1e-4, 1e-7) if quick else tuple(10.0 ** -k for k in range(3, 11))
    result.append(Sweep("scipy DOP853", "scipy-dop853", False, "rtol", scipy_tolerances))
    return result


def _ours(scene: Scene, sweep: Sweep, value: float, t_end: float):
    options = dict(method=sweep.method, t_end=t_end)
    if sweep.setting == "dt":
        options.update(munthe_kaas=sweep.munthe_kaas, dt=value, record_every=10**9)
    else:
        options.update(rtol=value, atol=value * 1e-3, record_dt=t_end)
    run = Simulation(scene, **options)
    start = time.perf_counter()
    run.advance()
    seconds = time.perf_counter() - start
    row = run.rows[-1]
    if run.time != t_end:
        raise RuntimeError(f"{sweep.label} at {sweep.setting} {value:g} stopped early: {run.message()}")
    return seconds, run.steps, row[row_layout.CONTACT], row[row_layout.R].reshape(3, 3)


def _scipy(scene: Scene, value: float, t_end: float):
    from scipy.integrate import solve_ivp

    rhs = reference_rhs(scene)
    alpha, v = initial_state(landscape_for(scene.landscape), scene)
    y0 = np.concatenate([alpha, v, np.eye(3).ravel()])
    start = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=value, atol=value * 1e-3)
    seconds = time.perf_counter() - start
    y = sol.y[:, -1]
    return seconds, len(sol.t) - 1, y[:2], y[5:].reshape(3, 3)


def _run(scene: Scene, sweep: Sweep, value: float, t_end: float):
    """(seconds, steps, final contact point, final R) of one run."""
    if sweep.method == "scipy-dop853":
        return _scipy(scene, value, t_end)
    return _ours(scene, sweep, value, t_end)


def measure(scene_names: list[str], t_end: float | None, quick: bool, repeats: int) -> list[Point]:
    """Every sweep on every scene, to t_end (None: the scene's own duration)."""
    points = []
    for name in scene_names:
        scene = Scene.load(EXAMPLES_DIR / f"{name}.json")
        until = scene.duration if t_end is None else t_end
        alpha_ref, _, R_ref = reference_solution(scene, [0.0, until])
        for sweep in sweeps(quick):
            for value in sweep.values:
                _, steps, alpha, R = _run(scene, sweep, value, until)  # untimed: the error (and compiling)
                seconds = float(np.median([_run(scene, sweep, value, until)[0] for _ in range(repeats)]))
                points.append(Point(name, sweep.label, sweep.setting, value, steps, seconds,
                                    float(np.abs(alpha - alpha_ref[-1]).max()),
                                    float(np.abs(R - R_ref[-1]).max())))
    return points
