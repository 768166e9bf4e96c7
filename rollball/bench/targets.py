"""The speed targets: kernel step against C, real-time factor, new-formula latency,
cold start and memory. Times are medians of repeated runs; the C comparison alternates
the two in one run, so both see the same load on a shared machine."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import random
import subprocess
import sys
import tempfile
import time

import numpy as np

from ..examples import EXAMPLES_DIR
from ..scene import Air, Scene
from ..run_size import MAX_ROWS
from ..simulation import Simulation
from ..tableaus import METHODS
from ..trajectory import CONTACT
from .cstep import CStep

HILLS = EXAMPLES_DIR / "hills.json"


def _ns_per_step(scene: Scene, **options) -> float:
    run = Simulation(scene, **options)
    start = time.perf_counter()
    run.advance(rows=False)
    return (time.perf_counter() - start) / run.steps * 1e9


def c_ratio(repeats: int, steps: int) -> dict:
    """RK4 Munthe-Kaas, h = 1e-3, on the hills, recording every 100th step, against C."""
    scene = Scene.load(HILLS)
    s, b = scene.start, scene.ball
    assert s.vx == s.vy == s.spin == 0, "the C step starts at rest"
    options = dict(method="rk4", munthe_kaas=True, dt=1e-3, record_every=100)
    c = CStep.build()
    _ns_per_step(scene, t_end=0.01, **options)  # compiled
    if c is None:
        ours = [_ns_per_step(scene, t_end=steps * 1e-3, **options) for _ in range(repeats)]
        return {"ns_ours": float(np.median(ours)), "ns_c": None, "ratio": None, "same_step": None}
    # the same step: after 1000 steps both agree to round-off
    short = Simulation(scene, t_end=1.0, **options)
    short.advance(rows=False)
    _, x, y = c.run(b.radius, b.mass, scene.gravity, s.x, s.y, 1e-3, 1000)
    same = float(np.abs(short.rows[-1, CONTACT] - [x, y]).max())
    ours, theirs = [], []
    for _ in range(repeats):
        ours.append(_ns_per_step(scene, t_end=steps * 1e-3, **options))
        theirs.append(c.run(b.radius, b.mass, scene.gravity, s.x, s.y, 1e-3, steps)[0])
    return {"ns_ours": float(np.median(ours)), "ns_c": float(np.median(theirs)),
            "ratio": float(np.median(np.array(ours) / np.array(theirs))), "same_step": same}


def step_costs(repeats: int, steps: int) -> dict:
    """ns per step of every method on the hills: the fixed-step ones at h = 1e-3 (the explicit
    ones both ways), the adaptive ones at rtol 1e-8 (their steps are longer)."""
    scene = Scene.load(HILLS)
    costs = {}
    for name, method in METHODS.items():
        if method.adaptive:
            runs = {f"{name} (rtol 1e-8)": dict(rtol=1e-8, atol=1e-11, t_end=200.0, record_dt=1.0)}
        else:
            runs = {f"{name} {'MK' if mk else 'classic'}": dict(munthe_kaas=mk, dt=1e-3, t_end=steps * 1e-3,
                                                               record_every=100)
                    for mk in ((True, False) if method.classic_allowed else (True,))}
        for label, options in runs.items():
            _ns_per_step(scene, method=name, **{**options, "t_end": 0.01})  # compiled
            costs[label] = float(np.median([_ns_per_step(scene, method=name, **options) for _ in range(repeats)]))
    return costs


def real_time_factor(repeats: int, t_end: float) -> float:
    """Simulated seconds per wall-clock second, RK4 Munthe-Kaas at h = 1e-4 on the hills."""
    scene = Scene.load(HILLS)
    ns = [_ns_per_step(scene, method="rk4", munthe_kaas=True, dt=1e-4, t_end=t_end, record_every=100)
          for _ in range(repeats)]
    return 1e-4 / (float(np.median(ns)) * 1e-9)


LATENCY_GOAL = 0.030   # seconds: a formula never seen before, ready and 100 steps run (issue 25)


def new_formula_latency(count: int) -> tuple[float, float]:
    """Median seconds (wall clock, CPU) from a formula never seen before to a finished run of
    100 steps, in a warm process: parse, differentiate, generate, compile, validate the scene and
    step. The CPU figure is what a busy machine does not inflate."""
    from ..simulation import simulate

    simulate(Scene.load(HILLS), t_end=0.01)  # warm
    rng = random.Random()
    times, cpu = [], []
    for _ in range(count):
        a, b, c = (round(rng.uniform(0.1, 0.9), 6) for _ in range(3))
        formula = f"{a}*sin({b}*x)*cos(y) + {c}*x*y^2"
        start, start_cpu = time.perf_counter(), time.process_time()
        simulate(Scene(landscape=formula), t_end=0.1, dt=1e-3)
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return float(np.median(times)), float(np.median(cpu))


_COLD = """
import time
start = time.perf_counter()
from rollball import Scene, simulate   # the package loads the simulation's modules when they are used
imported = time.perf_counter()
simulate(Scene.load({hills!r}), t_end=0.01)
simulated = time.perf_counter()
simulate(Scene(landscape="0.3*cos(x)*sin(2*y) + 0.01*x^3"), t_end=0.01)
formula = time.perf_counter()
print(imported - start, simulated - imported, formula - simulated)
"""

_WARM_UP = """
import time
start = time.process_time()
from rollball.warmup import warm_up
warm_up()
print(time.process_time() - start)
"""

# (what a child process prints last: its own high-water mark; ru_maxrss would include the parent's, from the fork)
_HIGH_WATER = """
import resource
try:
    status = open("/proc/self/status").read().split("VmHWM:")[1]
    print(int(status.split()[0]) * 1024)
except (OSError, IndexError):
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
"""
_MEMORY = """
from rollball import Scene, simulate
traj = simulate(Scene.load({hills!r}), method="rk4", dt=1e-3, t_end={steps} * 1e-3, record_every=100)
assert traj.steps == {steps}, traj.message
""" + _HIGH_WATER


# An adaptive run recording every step until the row limit stops it, on a scene whose ball may slip
# (a run whose contact changes mode: its kernel runs write into the mode machine's rows).
_ROW_LIMIT = """
import dataclasses
from rollball import Scene, mode_machine, simulation
from rollball.scene import Contact
for module in (simulation, mode_machine):
    module.MAX_ROWS = {rows}
scene = Scene.load({hills!r})
scene = dataclasses.replace(scene, contact=Contact(friction=1.0), duration=1e6)
run = simulation.Simulation(scene, method="dopri5", rtol=1e-12, atol=1e-12, record_dt=None)
run.advance(rows=False)
traj = run.trajectory()
assert run.segmented and str(traj.status) == "row_limit" and len(traj) > 0.99 * {rows}, traj.message
""" + _HIGH_WATER
ROW_LIMIT_GOAL = 2.5e9   # bytes: an adaptive run recording every step up to MAX_ROWS rows


CHILD_TIMEOUT = 1800.0   # s: the most a measurement's child process may take (numba's cold compile takes 240 s of CPU)


def _python(code: str, env: dict | None = None, timeout: float = CHILD_TIMEOUT) -> tuple[list[float], float]:
    """Run ``code`` in a fresh interpreter: the numbers it prints, and its wall time. A child that
    takes longer than ``timeout`` is killed and RuntimeError says so."""
    start = time.perf_counter()
    try:
        out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                             env={**os.environ, **(env or {})}, timeout=timeout).stdout
    except subprocess.TimeoutExpired:
        raise RuntimeError(f"a measurement's child process took more than {timeout:g} s and was stopped") from None
    return [float(v) for v in out.split()], time.perf_counter() - start


def cold_start(quick: bool = False) -> dict:
    """A fresh process: with empty numba and landscape caches, then again with them filled;
    every method compiled in one process, and (not ``quick``, a minute or more) the same where
    the shipped kernel code does not fit and numba compiles the kernel's sources (rollball/kernel/)."""
    with tempfile.TemporaryDirectory() as numba_cache, tempfile.TemporaryDirectory() as ours:
        env = {"NUMBA_CACHE_DIR": numba_cache, "ROLLBALL_CACHE_DIR": ours}
        code = _COLD.format(hills=str(HILLS))
        (imp, first, formula), wall = _python(code, env)
        (imp2, first2, formula2), wall2 = _python(code, env)
    return {"import": imp, "first_simulate_cold_cache": first, "new_formula_cold_cache": formula,
            "process_cold_cache": wall, "first_simulate_disk_cache": first2,
            "known_formula_disk_cache": formula2, "process_disk_cache": wall2,
            "all_methods_cold_cache": all_methods_cold(),
            "all_methods_numba_cold_cache": None if quick else all_methods_cold("numba")}


def all_methods_cold(source: str = "shipped") -> float:
    """CPU seconds to compile every method (and the sweeps' batch loop), ``warm_up``, in one fresh
    process with empty numba and landscape caches: what ``scripts/setup`` waits for once. The
    kernel from ``source``: "shipped" (its LLVM code made into machine code) or "numba"
    (compiled from rollball/kernel/, as where the shipped code does not fit: machine_code.py)."""
    with tempfile.TemporaryDirectory() as numba_cache, tempfile.TemporaryDirectory() as ours:
        (seconds,), _ = _python(_WARM_UP, {"NUMBA_CACHE_DIR": numba_cache, "ROLLBALL_CACHE_DIR": ours,
                                           "ROLLBALL_MACHINE_CODE": source})
    return seconds


def peak_memory(steps: int) -> float:
    """Peak resident memory (bytes) of a process running ``steps`` steps, every 100th recorded."""
    (rss,), _ = _python(_MEMORY.format(hills=str(HILLS), steps=steps))
    return rss


def row_limit_memory(rows: int = MAX_ROWS) -> float:
    """Peak resident memory (bytes) of a process whose dopri5 run records every step of a run whose
    contact changes mode (hills, friction 1) until it stops at ``rows`` rows (the row limit)."""
    (rss,), _ = _python(_ROW_LIMIT.format(hills=str(HILLS), rows=rows))
    return rss


XVFB = ["xvfb-run", "-a", "-s", "-screen 0 1400x900x24 +extension GLX +render"]


def app_responsiveness() -> dict:
    """The window's longest event-loop gap while 10⁶ steps are computed and played, and its
    latency from an edit of the landscape to the landscape drawn (``latency``), measured in
    a child process (``python -m rollball_app.responsiveness``; under Xvfb when there is no display), or
    why it could not be measured. The core imports no Qt: the app does this in its own process."""
    import shutil

    command = [sys.executable, "-m", "rollball_app.responsiveness"]
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        if shutil.which("xvfb-run") is None:
            return {"error": "no display and no xvfb-run"}
        command = XVFB + command
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=900)
    except (OSError, subprocess.TimeoutExpired) as error:
        return {"error": str(error)}
    lines = result.stdout.strip().splitlines()
    if result.returncode != 0 or not lines:
        last = (result.stderr.strip().splitlines() or ["no output"])[-1]
        return {"error": f"exit {result.returncode}: {last}"}
    return json.loads(lines[-1])


# Examples whose ball flies (their own contact) and one that slips and grips on a curved surface
HYBRID = ("liftoff", "ridge_jump", "cylinder")
HYBRID_GOAL = 4.0   # a run that changes mode costs at most this many times the glued run
SLIPPING = Scene("1.5*x^2 + 0.9*y^2 + 0.3*x*y", duration=0.9)   # the convergence tests' bowl


def _hybrid_scenes() -> dict[str, Scene]:
    """The examples that fly (their own contact), and a ball thrown across a tilted bowl with
    friction 0.2 (a slip from rolling in 3-D, then a grip; rk4 at dt 1e-3)."""
    scenes = {name: Scene.load(EXAMPLES_DIR / f"{name}.json") for name in HYBRID}
    bowl = dataclasses.replace(SLIPPING, start=dataclasses.replace(SLIPPING.start, x=-0.1, y=0.1, vx=1.2, vy=-0.6))
    scenes["bowl, slip and grip"] = dataclasses.replace(bowl, contact=dataclasses.replace(bowl.contact, friction=0.2))
    return scenes


def _run_cpu(scene: Scene) -> float:
    """CPU time of one run of the scene (its energy and transition checks left out)."""
    run = Simulation(scene)
    run.judge_energy = False
    start = time.process_time()
    run.advance(rows=False)
    return time.process_time() - start


def _glued(scene: Scene) -> Scene:
    """The scene glued to its surface: friction null, after_liftoff "glued" (the 2011 model)."""
    return dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, friction=None, after_liftoff="glued"))


def hybrid_costs(repeats: int) -> dict:
    """CPU time of a run that changes mode against the same scene glued to its surface (friction
    null, after_liftoff "glued": the 2011 model's one kernel run), the two in turn, medians and the
    median of the ratios: the examples that fly, and a ball thrown across a tilted bowl with
    friction 0.2 (a slip from rolling in 3-D, then a grip; rk4 at dt 1e-3)."""
    out = {}
    for name, scene in _hybrid_scenes().items():
        glued = _glued(scene)
        _run_cpu(scene), _run_cpu(glued)   # (compiled, the landscape too)
        pairs = [(_run_cpu(scene), _run_cpu(glued)) for _ in range(repeats)]
        hybrid, plain = (np.array(column) for column in zip(*pairs))
        out[name] = {"hybrid_ms": float(np.median(hybrid)) * 1e3, "glued_ms": float(np.median(plain)) * 1e3,
                     "ratio": float(np.median(hybrid / np.maximum(plain, 1e-9)))}
    return out


def hybrid_sweeps(repeats: int, runs: int = 200) -> dict:
    """CPU time of a sweep of ``runs`` runs of each example that flies and of the slipping bowl
    (``_hybrid_scenes``), over its start speed vx (±5 %: every run lifts off, or slips and grips),
    on one worker, against the same sweep glued (the compiled batch path), the two in turn: medians,
    the median of the ratios and the ratio of the fastest sweeps (``fastest_ratio``, as
    ``dissipation_cost``'s; ``_all`` and ``_dask`` likewise); and the same sweeps' wall time
    on every core (a sweep's default, ``local_workers`` of them: ``workers``, ``hybrid_all_s``,
    ``glued_all_s``, ``ratio_all``), each where the sweep puts it (``processes``: worker processes
    for runs through ``Simulation``, threads where the batch loop runs them);
    ``hybrid_first_s``: the first hybrid sweep on every core, which would start worker processes
    (the others find them started, as sweeps in a row do). Where Dask distributed is
    installed, the same on a Dask cluster of ``local_workers`` processes on this machine
    (``dask_workers``, ``hybrid_dask_s``, ``glued_dask_s``, ``ratio_dask``)."""
    from ..sweeps import processes, sweep   # (sweeps load on demand)
    from ..sweeps.runner import local_workers

    def cpu(scene, vary) -> float:
        started = time.process_time()
        sweep(scene, vary, workers=1)
        return time.process_time() - started

    def wall(scene, vary, **where) -> float:
        started = time.perf_counter()
        sweep(scene, vary, **where)
        return time.perf_counter() - started

    def in_turn(scene, glued, vary, timed, **where) -> tuple[float, float, float, float]:
        pairs = [(timed(scene, vary, **where), timed(glued, vary, **where)) for _ in range(repeats)]
        hybrid, plain = (np.array(column) for column in zip(*pairs))
        return (float(np.median(hybrid)), float(np.median(plain)), float(np.median(hybrid / np.maximum(plain, 1e-9))),
                float(hybrid.min() / max(plain.min(), 1e-9)))

    out, scenes = {}, {}
    for name, scene in _hybrid_scenes().items():
        vary = {"start.vx": np.linspace(0.95 * scene.start.vx, 1.05 * scene.start.vx, runs)}
        glued = _glued(scene)
        scenes[name] = scene, glued, vary
        cpu(scene, vary), cpu(glued, vary)   # (compiled, the landscape too)
        figures = out[name] = {"runs": runs, "workers": local_workers()}
        figures["hybrid_s"], figures["glued_s"], figures["ratio"], figures["fastest_ratio"] = in_turn(
            scene, glued, vary, cpu)
        processes.close()
        started = time.perf_counter()
        figures["processes"] = sweep(scene, vary).processes   # (too small a sweep stays on threads)
        figures["hybrid_first_s"] = time.perf_counter() - started
        wall(glued, vary)
        (figures["hybrid_all_s"], figures["glued_all_s"], figures["ratio_all"],
         figures["fastest_ratio_all"]) = in_turn(scene, glued, vary, wall)
    processes.close()
    with _local_cluster(local_workers()) as cluster:   # (afterwards: an idle cluster takes some CPU time)
        for name, (scene, glued, vary) in scenes.items() if cluster is not None else ():
            where = {"scheduler": cluster.scheduler_address}
            wall(scene, vary, **where), wall(glued, vary, **where)   # (each worker compiles the landscape)
            figures = out[name]
            figures["dask_workers"] = len(cluster.workers)
            (figures["hybrid_dask_s"], figures["glued_dask_s"], figures["ratio_dask"],
             figures["fastest_ratio_dask"]) = in_turn(scene, glued, vary, wall, **where)
    return out


@contextlib.contextmanager
def _local_cluster(workers: int):
    """A Dask cluster of ``workers`` processes of one thread on this machine, or None without
    Dask distributed."""
    try:
        from distributed import LocalCluster
    except ImportError:
        yield None
        return
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=":0", worker_dashboard_address=":0") as cluster:
        yield cluster


DISSIPATION_GOAL = 1.5   # a run with rolling resistance, spin friction and air against the same run without
AIR = {"density": 1.2, "drag_coefficient": 0.47}   # (air at sea level, a smooth sphere)


def dissipation_cost(repeats: int) -> dict:
    """CPU time of the wells example (rk4, dt 2e-3, to 16 s: its 20 turning points, the rest after
    16.39 s left out) with its rolling resistance and spin friction and air, against the same run
    with none of the three, the two in turn: medians and the median of the ratios; and the fastest
    run of each and their ratio (``fastest_ratio``: each run's time least disturbed by the machine,
    which the median of the ratios can flatter where the run without varies more)."""
    scene = dataclasses.replace(Scene.load(EXAMPLES_DIR / "wells.json"), duration=16.0)
    on = dataclasses.replace(scene, air=Air(**AIR))
    off = dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, rolling_resistance=0.0,
                                                                 spin_friction=0.0))
    _run_cpu(on), _run_cpu(off)   # (compiled, the landscape too)
    pairs = [(_run_cpu(on), _run_cpu(off)) for _ in range(repeats)]
    with_, without = (np.array(column) for column in zip(*pairs))
    return {"with_ms": float(np.median(with_)) * 1e3, "without_ms": float(np.median(without)) * 1e3,
            "ratio": float(np.median(with_ / np.maximum(without, 1e-9))),
            "fastest_with_ms": float(with_.min()) * 1e3, "fastest_without_ms": float(without.min()) * 1e3,
            "fastest_ratio": float(with_.min() / max(without.min(), 1e-9))}


SWEEP_GOAL = 1.6   # a sweep on two workers against one: wall time, the same runs


def sweep_speedup(repeats: int, runs: int = 400) -> dict | None:
    """Wall time of a sweep of ``runs`` runs of the hills example (glued: the compiled batch path)
    over its start point, on one worker and on two, the two in turn: medians and the median of the
    ratios (one over two). None on a machine with one core."""
    if (os.cpu_count() or 1) < 2:
        return None
    from ..sweeps import sweep   # (sweeps load on demand)

    scene = Scene.load(HILLS)
    side = int(round(runs ** 0.5))
    vary = {"start.x": np.linspace(-1.0, 1.0, side), "start.y": np.linspace(-1.0, 1.0, runs // side)}

    def wall(workers: int) -> float:
        started = time.perf_counter()
        sweep(scene, vary, workers=workers)
        return time.perf_counter() - started

    wall(2)   # (compiled, the landscape too)
    pairs = [(wall(1), wall(2)) for _ in range(repeats)]
    one, two = (np.array(column) for column in zip(*pairs))
    return {"runs": side * (runs // side), "one_s": float(np.median(one)), "two_s": float(np.median(two)),
            "ratio": float(np.median(one / two))}


def measure(quick: bool) -> dict:
    repeats = 3 if quick else 7
    return {
        "c": c_ratio(repeats, 100_000 if quick else 300_000),
        "costs": step_costs(repeats, 50_000 if quick else 200_000),
        "real_time": real_time_factor(repeats, 5.0 if quick else 20.0),
        **dict(zip(("latency", "latency_cpu"), new_formula_latency(7 if quick else 21))),
        "cold": cold_start(quick),
        "memory": peak_memory(10_000_000),
        "row_limit_memory": None if quick else row_limit_memory(),
        "app": app_responsiveness(),
        "hybrid": hybrid_costs(3 if quick else 21),
        "hybrid_sweeps": hybrid_sweeps(1 if quick else 5, 40 if quick else 200),
        "dissipation": dissipation_cost(5 if quick else 21),
        "sweep": sweep_speedup(3 if quick else 5),
    }
