"""Speed against error on one scene: which method, at which step or tolerance, gives which
error, at what cost.

``compare(scene)`` runs every method (or the run specs given) over a ladder of step sizes
(fixed-step methods) or tolerances (adaptive ones) and measures each run against a
reference: the most accurate method in ``METHODS`` at a tight tolerance, whose own error
is estimated against a second, tighter run. As in DiffEqDevTools' ``WorkPrecision``, one
run measures the error and timed repeats of the same run measure its cost.

All runs are compared with the reference at common recorded times: multiples of
``record_dt`` (a fixed step is a whole fraction or a whole multiple of it), and the error of
a run is the maximum over those times, not only at the end.
"""

from __future__ import annotations

import math
import os
import platform
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from . import __version__
from .scene import Scene
from .simulation import CHUNK, Simulation
from .run_specs import RunSpec, default_runs, parse_runs, valid_specs
from .tableaus import METHODS, MethodKind
from .trajectory import Status, Trajectory

ERRORS = ("contact", "velocity", "omega", "orientation", "energy")  # keys of every error dict
FITTED = ("contact", "orientation")   # the errors whose log-log slope against dt is the order
ERROR_UNITS = {"contact": "m", "velocity": "m/s", "omega": "rad/s", "orientation": "‖R − R_ref‖_F",
               "energy": "relative"}

REFERENCE_RTOL = 1e-13     # the reference run
CHECK_METHOD = "dopri5"    # its checks: itself a decade looser, and another method at its tolerance
REFERENCE_ACCURACY = 1e-10   # the reference is checked when its own error (m; ‖ΔR‖_F) is at most this
ATOL_PER_RTOL = 1e-3       # atol = 1e-3 rtol for every adaptive run
FLOOR_FACTOR = 10.0        # errors below 10x the reference's difference from itself a decade looser: not measured
ROUNDOFF = 100 * np.finfo(float).eps   # nor are errors below this times the quantity's size
CEILING = 1e-2             # fixed-step ladders start at about this contact error
SPREAD = 0.4               # orders are fitted where the local slopes agree to within this (asymptotic range)
PLATEAU_SLOPE = 0.5        # a pair of steps whose error shrinks slower than dt^0.5: not converging there
TARGETS = (1e-6, 1e-10)    # the summary names the cheapest run reaching each
ROWS_PER_SECOND = 20       # the common times: at least 50 and at most 1000 of them
MIN_ROWS, MAX_ROWS = 50, 1000
COARSEST = 10              # the first step tried is t_end / 10


@dataclass(frozen=True)
class Effort:
    """How much a comparison may spend: full or quick."""

    budget: float           # seconds of computing per run spec (its ladder stops beyond)
    max_points: int         # ladder points per run spec
    decades: float          # error decades between ladder points (fixed steps)
    tolerances: tuple[float, ...]
    repeats: int            # timed repeats of a short run (at least); their median is its cost
    short: float            # a run shorter than this (s) is repeated, as often as fits in
    spread: float           # this many seconds (very short runs are at the mercy of other work)


FULL = Effort(budget=12.0, max_points=12, decades=1.0,
              tolerances=tuple(10.0 ** -k for k in range(3, 13)), repeats=5, short=0.2, spread=0.05)
QUICK = Effort(budget=2.0, max_points=6, decades=2.0,
               tolerances=(1e-3, 1e-6, 1e-9, 1e-12), repeats=3, short=0.05, spread=0.02)


class Cancelled(Exception):
    """The caller's cancel event was set: the comparison stopped and returned nothing."""


class NothingToCompare(ValueError):
    """The reference run stopped (the physics ended it) before the first common time."""


def _specs(runs) -> list[RunSpec]:
    if runs is None:
        return default_runs()
    if isinstance(runs, str):
        return parse_runs(runs)
    specs = []
    for run in runs:
        if isinstance(run, str):
            new = parse_runs(run)
        elif isinstance(run, RunSpec):
            new = [run]
        else:
            raise ValueError(f"a run is a RunSpec or a string like 'rk4/classic', not {run!r}")
        specs += [spec for spec in new if spec not in specs]
    if not specs:
        raise ValueError(f"no runs given; valid runs: {', '.join(valid_specs())}")
    return specs


# -- errors against the reference -----------------------------------------------------------

def _matching_rows(t: np.ndarray, t_ref: np.ndarray) -> np.ndarray:
    """For every time in t, the index of the reference row at the same time, or -1."""
    if len(t_ref) == 0:
        return np.full(len(t), -1)
    tolerance = 1e-9 * max(1.0, abs(float(t_ref[-1])))
    j = np.clip(np.searchsorted(t_ref, t), 1, max(1, len(t_ref) - 1))
    left = np.minimum(j - 1, len(t_ref) - 1)
    right = np.minimum(j, len(t_ref) - 1)
    nearest = np.where(np.abs(t_ref[left] - t) <= np.abs(t_ref[right] - t), left, right)
    return np.where(np.abs(t_ref[nearest] - t) <= tolerance, nearest, -1)


def error_series(traj: Trajectory, ref_traj: Trajectory) -> dict[str, np.ndarray]:
    """The errors of ``traj`` against the reference at each of traj's row times: contact (m),
    velocity (m/s), omega (rad/s), orientation (‖R − R_ref‖_F), energy (relative to the
    reference's energy scale). NaN at times the reference did not record (record the
    reference at ``record_dt`` = a multiple of traj's row spacing)."""
    index = _matching_rows(traj.t, ref_traj.t)
    found = index >= 0
    at = np.where(found, index, 0)
    series = {
        "contact": _row_norms(traj.contact - ref_traj.contact[at]),
        "velocity": _row_norms(traj.velocity - ref_traj.velocity[at]),
        "omega": _row_norms(traj.omega - ref_traj.omega[at]),
        "orientation": _row_norms((traj.R - ref_traj.R[at]).reshape(-1, 9)),
        "energy": np.abs(traj.energy - ref_traj.energy[at]) / ref_traj.energy_scale,
    }
    return {key: np.where(found, value, np.nan) for key, value in series.items()}


def _row_norms(values: np.ndarray) -> np.ndarray:
    """Each row's Euclidean norm, by hypot: no square overflows where a run that blew up holds
    entries beyond 10¹⁵⁴ (a classic update's R before it is reported overflowed); a norm beyond
    the largest double is inf, as it is."""
    with np.errstate(over="ignore"):   # (only the norm itself can overflow, to its true inf)
        return np.hypot.reduce(values, axis=1)


def _max_errors(traj: Trajectory, ref_traj: Trajectory) -> dict[str, float]:
    """The maximum of each error over the common times (NaN where there are none)."""
    series = error_series(traj, ref_traj)
    out = {}
    for key in ERRORS:
        values = series[key][~np.isnan(series[key])]
        out[key] = float(values.max()) if len(values) else math.nan
    return out


# -- runs ------------------------------------------------------------------------------------

# Compute time: this thread's processor time where that clock is fine-grained (Linux, macOS),
# so that other programs on a shared machine do not count; else the wall clock.
compute_clock = time.thread_time if time.get_clock_info("thread_time").resolution <= 1e-6 else time.perf_counter


def _advance(run: Simulation, cancel: threading.Event | None) -> float:
    """Run to the end in chunks (checking ``cancel`` between them); the compute seconds it
    took: processor time of this thread, which on an idle machine is the wall time and on a
    shared one leaves out the time other programs held the processor. The run does not judge
    whose its energy error is: a comparison measures the true error, and that check (taking an
    interval again at shorter steps, up to a tenth of a second) would be timed as the method's
    cost and spoil the ladders' estimates of what a finer run costs."""
    run.judge_energy = False
    seconds = 0.0
    while not run.done:
        start = compute_clock()
        run.advance(CHUNK, rows=False)
        seconds += compute_clock() - start
        if cancel is not None and cancel.is_set():
            raise Cancelled()
    return seconds


@dataclass(frozen=True)
class Check:
    """A run the reference is checked against, and the largest difference from it per error key."""

    method: str
    rtol: float
    status: Status
    difference: dict[str, float]

    def to_dict(self) -> dict:
        return {"method": self.method, "rtol": self.rtol, "status": str(self.status),
                "difference": {k: _finite_or_none(v) for k, v in self.difference.items()}}


@dataclass(frozen=True)
class Reference:
    """The run every other one is measured against, and its own error: the larger difference
    from its two checks (``checks``), the same method a decade looser (whose difference is
    about the looser run's own error, larger than the reference's) and another method at the
    same tolerance (another step sequence: an error both runs of the one method share shows
    there). The reference is ``checked`` when that estimate is at most ``REFERENCE_ACCURACY``
    in the contact point (m) and the orientation, and every check ended as it did."""

    method: str
    rtol: float
    atol: float
    error_estimate: float                 # the largest of error_estimates but energy
    error_estimates: dict[str, float]     # key -> the larger difference from the checks
    status: Status
    message: str
    steps: int
    seconds: float
    scales: dict = field(default_factory=dict)   # key -> size of the quantity (round-off is relative to it)
    checks: tuple[Check, ...] = ()

    def floor(self, key: str) -> float:
        """Errors below this may be the reference's, not the run's: not measured. The same
        method a decade looser differs from it by about its own error, of the reference's
        order: FLOOR_FACTOR times that; another method's difference bounds both runs' errors
        together: that as it is; and round-off: ROUNDOFF times the quantity's size."""
        bounds = [(FLOOR_FACTOR if check.method == self.method else 1.0) * check.difference[key]
                  for check in self.checks] or [FLOOR_FACTOR * self.error_estimates[key]]
        bounds = [b if not math.isnan(b) else math.inf for b in bounds]
        return max(*bounds, ROUNDOFF * self.scales.get(key, 0.0))

    @property
    def checked(self) -> bool:
        return not self.problems

    @property
    def problems(self) -> list[str]:
        """Why the reference is not good to REFERENCE_ACCURACY (empty when it is)."""
        out = [f"{check.method} at rtol {check.rtol:.0e} ended {check.status}, the reference {self.status}"
               for check in self.checks if check.status != self.status]
        for key in FITTED:
            estimate = self.error_estimates[key]
            if not estimate <= REFERENCE_ACCURACY:
                out.append(f"its own {key} error is {estimate:.1e} {ERROR_UNITS[key]}, "
                           f"above {REFERENCE_ACCURACY:.0e}")
        return out

    def to_dict(self) -> dict:
        return {"method": self.method, "rtol": self.rtol, "error_estimate": _finite_or_none(self.error_estimate),
                "atol": self.atol,
                "error_estimates": {k: _finite_or_none(v) for k, v in self.error_estimates.items()},
                "floors": {k: _finite_or_none(self.floor(k)) for k in ERRORS if k in self.error_estimates},
                "checks": [c.to_dict() for c in self.checks], "accuracy_required": REFERENCE_ACCURACY,
                "checked": self.checked, "problems": self.problems,
                "status": str(self.status), "message": self.message, "steps": self.steps, "seconds": self.seconds}


def reference_method() -> str:
    """The most accurate adaptive method in ``METHODS`` (highest order)."""
    adaptive = [m for m in METHODS.values() if m.kind is MethodKind.ADAPTIVE]
    return max(adaptive, key=lambda m: m.order).name


def _reference(scene: Scene, t_end: float, record_dt: float, cancel=None) -> tuple[Trajectory, Reference]:
    method = reference_method()
    settings = [(method, REFERENCE_RTOL), (method, REFERENCE_RTOL * 10)]
    if CHECK_METHOD != method:
        settings.append((CHECK_METHOD, REFERENCE_RTOL))
    runs = []
    for name, rtol in settings:
        _advance(Simulation(scene, method=name, t_end=record_dt, record_dt=record_dt), cancel)  # compiled
        run = Simulation(scene, method=name, t_end=t_end, rtol=rtol, atol=rtol * ATOL_PER_RTOL, record_dt=record_dt)
        seconds = _advance(run, cancel)
        runs.append((run.trajectory(), seconds))
    (traj, seconds), others = runs[0], runs[1:]
    checks = tuple(Check(name, rtol, other.status, _max_errors(other, traj))
                   for (name, rtol), (other, _) in zip(settings[1:], others))
    with np.errstate(invalid="ignore"):
        estimates = {key: float(np.nanmax([c.difference[key] for c in checks])) for key in ERRORS}
    estimate = max(v for k, v in estimates.items() if k != "energy")
    with np.errstate(all="ignore"):
        scales = {"contact": float(np.nanmax(np.linalg.norm(traj.contact, axis=1), initial=0.0)),
                  "orientation": 1.0}   # ‖R‖_F = √3 for a rotation; its entries are at most 1
    return traj, Reference(method, REFERENCE_RTOL, REFERENCE_RTOL * ATOL_PER_RTOL, estimate, estimates,
                           traj.status, traj.message, traj.steps, seconds, scales, checks)


def record_step(t_end: float) -> float:
    """The spacing of the common recorded times for a run to t_end."""
    return t_end / min(MAX_ROWS, max(MIN_ROWS, math.ceil(t_end * ROWS_PER_SECOND)))


def reference_run(scene: Scene, t_end: float | None = None, record_dt: float | None = None,
                  cancel: threading.Event | None = None) -> tuple[Trajectory, float]:
    """The reference trajectory (rows at multiples of ``record_dt`` and at t_end) and an
    estimate of its own error (the largest difference, in m, m/s, rad/s or ‖ΔR‖_F, from its
    checks: ``Reference``). Setting ``cancel`` raises ``Cancelled`` within one
    chunk of steps."""
    t_end = scene.duration if t_end is None else t_end
    traj, ref = _reference(scene, t_end, record_step(t_end) if record_dt is None else record_dt, cancel)
    return traj, ref.error_estimate


@dataclass
class RunResult:
    """One run of the comparison: its setting, how it ended, its cost and its errors."""

    spec: RunSpec
    dt: float | None           # fixed-step methods
    rtol: float | None         # adaptive methods
    atol: float | None
    status: Status
    steps: int
    rejected: int
    evaluations: int
    seconds: float             # compute time of the run alone (median of repeats when short)
    error: dict[str, float]    # maxima over the common times (NaN where none: see status)
    below_reference_floor: bool   # some fitted error (contact, orientation) is below the reference's floor
    message: str = ""
    at_floor: bool = False     # every fitted error is: a finer step or tighter tolerance tells nothing more
    below: tuple[str, ...] = ()   # the error keys below the reference's accuracy: not measured, never quoted

    @property
    def ok(self) -> bool:
        return self.status is Status.OK

    @property
    def worst(self) -> float:
        """The larger of the contact (m) and orientation errors: what the summary ranks by."""
        return max(self.error["contact"], self.error["orientation"])

    def to_dict(self) -> dict:
        return {"method": self.spec.method, "munthe_kaas": self.spec.munthe_kaas, "dt": self.dt,
                "rtol": self.rtol, "atol": self.atol, "status": str(self.status), "steps": self.steps,
                "rejected": self.rejected, "evaluations": self.evaluations, "seconds": self.seconds,
                "error": {k: None if k in self.below else _finite_or_none(v) for k, v in self.error.items()},
                "below_reference_accuracy": list(self.below),
                "below_reference_floor": self.below_reference_floor, "at_reference_floor": self.at_floor,
                "message": self.message}


@dataclass(frozen=True)
class Order:
    """The fitted slope of log error against log dt for one fixed-step run spec; None where it
    cannot be fitted, ``reasons`` saying why; ``ranges`` the (coarsest, finest) dt fitted over."""

    spec: RunSpec
    contact: float | None
    orientation: float | None
    expected: int
    reasons: dict = field(default_factory=dict)   # key -> why that order is None
    ranges: dict = field(default_factory=dict)    # key -> (largest dt, smallest dt) fitted
    not_converging: dict = field(default_factory=dict)   # key -> where the error stops shrinking, in words
    notes: dict = field(default_factory=dict)     # key -> a fitted order's caveat (fitted over one pair only)

    def to_dict(self) -> dict:
        return {"method": self.spec.method, "munthe_kaas": self.spec.munthe_kaas,
                "contact": self.contact, "orientation": self.orientation, "expected": self.expected,
                "reasons": dict(self.reasons), "fitted_dt": {k: list(v) for k, v in self.ranges.items()},
                "not_converging": dict(self.not_converging), "notes": dict(self.notes)}


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


class _Runner:
    """Runs of one comparison: the scene, the reference, the effort, the clock."""

    def __init__(self, scene, t_end, record_dt, ref_traj, reference, effort, cancel):
        self.scene, self.t_end, self.record_dt = scene, t_end, record_dt
        self.ref_traj, self.reference, self.effort, self.cancel = ref_traj, reference, effort, cancel

    def grid_step(self, dt: float) -> tuple[float, int]:
        """The step nearest dt that lands on the common times, and how many steps per row."""
        if dt >= self.record_dt:
            j = max(1, round(dt / self.record_dt))
            return self.record_dt * j, 1
        k = max(1, round(self.record_dt / dt))
        return self.record_dt / k, k

    def finer(self, dt: float, ratio: float) -> float:
        """The step about ratio times smaller than dt that lands on the common times."""
        finer, _ = self.grid_step(dt / ratio)
        if finer < dt:
            return finer
        if dt > self.record_dt:
            return dt - self.record_dt
        return self.record_dt / (round(self.record_dt / dt) + 1)

    def options(self, spec: RunSpec, setting: float) -> dict:
        if spec.fixed_step:
            dt, every = self.grid_step(setting)
            return dict(method=spec.method, munthe_kaas=spec.munthe_kaas, dt=dt, record_every=every)
        return dict(method=spec.method, rtol=setting, atol=setting * ATOL_PER_RTOL, record_dt=self.record_dt)

    def cost(self, seconds: float) -> float:
        """What measuring a run of this many seconds costs: the run, and timed repeats when short."""
        if seconds >= self.effort.short:
            return seconds
        return seconds + max(self.effort.repeats * seconds, min(self.effort.spread, 100 * seconds))

    def warm_up(self, spec: RunSpec) -> None:
        """A short run, so that compiling is not timed."""
        setting = self.record_dt if spec.fixed_step else 1e-3
        _advance(Simulation(self.scene, t_end=self.record_dt, **self.options(spec, setting)), self.cancel)

    def run(self, spec: RunSpec, setting: float) -> RunResult:
        """One untimed-for-error run, then (when short) timed repeats for the cost."""
        options = self.options(spec, setting)
        run = Simulation(self.scene, t_end=self.t_end, **options)
        seconds = _advance(run, self.cancel)
        traj = run.trajectory()
        if seconds < self.effort.short and traj.status is Status.OK:
            times = []
            repeats = max(self.effort.repeats, min(100, math.ceil(self.effort.spread / max(seconds, 1e-6))))
            for _ in range(repeats):
                again = Simulation(self.scene, t_end=self.t_end, **options)
                times.append(_advance(again, self.cancel))
            seconds = float(np.median(times))
        error = _max_errors(traj, self.ref_traj)
        below = tuple(key for key in ERRORS if error[key] < self.reference.floor(key))
        fitted = [key in below for key in FITTED]
        return RunResult(spec, options.get("dt"), options.get("rtol"), options.get("atol"), traj.status,
                         traj.steps, traj.rejected, traj.evaluations, seconds, error, any(fitted),
                         traj.message, all(fitted), below)


Report = Callable[[str, int], None]   # (what runs next, ladder points so far)


def _fixed_ladder(runner: _Runner, spec: RunSpec, report: Report) -> list[RunResult]:
    """Steps from coarse to fine: first a search down to a contact error of about CEILING,
    then a point every ``effort.decades`` decades of error,
    until every fitted error is at the reference's floor (one exact error, as the contact
    point's on a plane, does not stop it), a run that ends early, the budget or ``max_points``."""
    effort, order = runner.effort, METHODS[spec.method].order
    ratio = min(10.0, max(1.5, 10.0 ** (effort.decades / order)))
    dt, _ = runner.grid_step(runner.t_end / COARSEST)
    spent, points = 0.0, []
    while True:
        report(f"{spec} dt {dt:.3g}", len(points))
        start = time.perf_counter()
        result = runner.run(spec, dt)
        spent += time.perf_counter() - start
        contact = result.error["contact"]
        if not points and not (result.ok and contact <= CEILING):  # still searching
            shrink = 0.25
            if result.ok and contact > 0:
                shrink = min(0.5, max(1e-3, 0.8 * (CEILING / contact) ** (1.0 / order)))
            smaller = runner.finer(dt, 1 / shrink)
            if spent + runner.cost(result.seconds * dt / smaller) > effort.budget or smaller < runner.t_end * 1e-9:
                return [result]  # the ladder never started: show how the last try ended
            dt = smaller
            continue
        points.append(result)
        if not result.ok or result.at_floor or len(points) >= effort.max_points:
            return points
        finer = runner.finer(dt, ratio)
        if spent + runner.cost(result.seconds * dt / finer) > effort.budget:
            return points
        dt = finer


def _tolerance_ladder(runner: _Runner, spec: RunSpec, report: Report) -> list[RunResult]:
    """Tolerances from loose to tight, until the reference's floor, a run that ends early,
    the budget or ``max_points``."""
    spent, points = 0.0, []
    for rtol in runner.effort.tolerances[: runner.effort.max_points]:
        report(f"{spec} rtol {rtol:.0e}", len(points))
        start = time.perf_counter()
        result = runner.run(spec, rtol)
        spent += time.perf_counter() - start
        points.append(result)
        # the next tolerance is 10-1000x tighter: its cost grows by a few times at most
        if not result.ok or result.at_floor or spent + runner.cost(4 * result.seconds) > runner.effort.budget:
            break
    return points


def _slope(dts: list[float], errors: list[float]) -> float:
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])


def _local_slopes(steps: list[float], errors: list[float]) -> list[float]:
    """log error ratio over log step ratio, pair by pair (steps from coarse to fine)."""
    return [math.log(errors[i] / errors[i + 1]) / math.log(steps[i] / steps[i + 1]) for i in range(len(steps) - 1)]


def stall(steps: list[float], errors: list[float]) -> int | None:
    """Where the error stops shrinking as the step (or tolerance) shrinks: the index of the
    point below whose step every finer pair's local slope is under PLATEAU_SLOPE (the error
    flat or growing), or None when the finest pair still shrinks it."""
    local = _local_slopes(steps, errors)
    k = len(steps) - 1
    while k >= 1 and local[k - 1] < PLATEAU_SLOPE:
        k -= 1
    return None if k == len(steps) - 1 else k


def fit_range(dts: list[float], errors: list[float], spread: float = SPREAD) -> tuple[int, int, int | None]:
    """The points (lo .. hi-1 of dts from coarse to fine) to fit an order over, and ``stall``'s
    index (None when the error shrinks to the finest step). Only the points up to the stall
    count; of those, the finest run of neighbouring pairs, at least two, whose local slopes
    are at least PLATEAU_SLOPE and agree to within ``spread`` (extended coarser while they
    still agree): the asymptotic range, where the error goes as dt^q for one q. Coarse steps
    have not settled yet; a lone pair whose slope agrees with no neighbour (an error falling by
    chance) is no range. Without such a run, the finest pair that shrinks the error (hi - lo
    = 2); without that, hi - lo < 2."""
    stalls = stall(dts, errors)
    last = len(dts) if stalls is None else stalls + 1
    local = _local_slopes(dts[:last], errors[:last])
    good = [q >= PLATEAU_SLOPE for q in local]
    for end in range(len(local) - 1, 0, -1):          # the window's finest pair
        if not (good[end] and good[end - 1] and abs(local[end] - local[end - 1]) <= spread):
            continue
        lo = end - 1
        while lo > 0 and good[lo - 1] and max(local[lo - 1:end + 1]) - min(local[lo - 1:end + 1]) <= spread:
            lo -= 1
        return lo, end + 2, stalls
    for i in range(len(local) - 1, -1, -1):
        if good[i]:
            return i, i + 2, stalls
    return 0, min(1, len(dts)), stalls


def asymptotic_range(dts: list[float], errors: list[float], spread: float = SPREAD) -> tuple[int, int]:
    """``fit_range``'s points alone."""
    lo, hi, _ = fit_range(dts, errors, spread)
    return lo, hi


def stall_text(key: str, steps: list[float], errors: list[float], index: int, name: str = "dt") -> str:
    """In words: the error stops shrinking below steps[index], not converging."""
    unit = " m" if ERROR_UNITS[key] == "m" else ""
    return (f"the {key} error stops shrinking below {name} = {steps[index]:.3g} ({errors[index]:.1e}{unit} there, "
            f"{errors[-1]:.1e} at {name} = {steps[-1]:.3g}): not converging")


def _measured(runs: list[RunResult], key: str, reference: Reference, setting) -> list[RunResult]:
    """The runs that ended ok with this error measured (above the reference's floor), one per
    setting, from the coarsest setting to the finest."""
    used = [r for r in runs if math.isfinite(r.error[key]) and r.error[key] > 0
            and r.error[key] >= reference.floor(key)]
    return [r for i, r in enumerate(used) if i == 0 or setting(r) < setting(used[i - 1])]


def fit_order(spec: RunSpec, runs: list[RunResult], reference: Reference) -> Order:
    """The least-squares slope of log error against log dt, in the contact point and the
    orientation, over this spec's runs that ended ok with errors above the reference's floor,
    and of those over the asymptotic range only (``fit_range``: the finest neighbouring steps
    whose slopes agree, away from the coarse steps, where the error does not yet go as
    dt^order). None, with the reason, where fewer than two such runs are, and where the error
    stops shrinking as the step does (``stall``): then no range is asymptotic, and the
    reason, also under ``not_converging``, names the step."""
    mine = sorted((r for r in runs if r.spec == spec and r.ok and r.dt is not None), key=lambda r: -r.dt)
    slopes, reasons, ranges, stalled, notes = {}, {}, {}, {}, {}
    for key in FITTED:
        used = _measured(mine, key, reference, lambda r: r.dt)
        if len(used) < 2:
            slopes[key] = None
            reasons[key] = (f"{len(used)} run{'s' if len(used) != 1 else ''} ended ok with a {key} error "
                            f"above the reference's floor ({reference.floor(key):.1e}); a slope needs two"
                            + (" (the error is at the floor already at the coarsest step)"
                               if mine and not used else ""))
            continue
        dts, errors = [r.dt for r in used], [r.error[key] for r in used]
        lo, hi, stalls = fit_range(dts, errors)
        if stalls is not None:
            slopes[key] = None
            reasons[key] = stalled[key] = stall_text(key, dts, errors, stalls)
            continue
        if hi - lo < 2:
            slopes[key] = None
            reasons[key] = f"no two neighbouring steps where the {key} error shrinks with the step"
            continue
        slope = _slope(dts[lo:hi], errors[lo:hi])
        if math.isfinite(slope):
            slopes[key] = slope
            ranges[key] = (dts[lo], dts[hi - 1])
            if hi - lo == 2 and len(dts) > 2:
                local = ", ".join(f"{q:.2f}" for q in _local_slopes(dts, errors))
                notes[key] = (f"over one pair of steps only: no three neighbouring steps' slopes agree to within "
                              f"{SPREAD:g} (pairwise slopes from coarse to fine: {local})")
        else:
            slopes[key] = None
            reasons[key] = "the fit of the measured errors is not a finite number"
    return Order(spec, slopes["contact"], slopes["orientation"], METHODS[spec.method].order, reasons, ranges,
                 stalled, notes)


def tolerance_stalls(spec: RunSpec, runs: list[RunResult], reference: Reference) -> dict[str, str]:
    """For an adaptive spec: key -> in words, where its error stops shrinking as rtol does."""
    mine = sorted((r for r in runs if r.spec == spec and r.ok and r.rtol is not None), key=lambda r: -r.rtol)
    out = {}
    for key in FITTED:
        used = _measured(mine, key, reference, lambda r: r.rtol)
        if len(used) >= 2:
            rtols, errors = [r.rtol for r in used], [r.error[key] for r in used]
            index = stall(rtols, errors)
            if index is not None:
                out[key] = stall_text(key, rtols, errors, index, "rtol")
    return out


# -- the comparison --------------------------------------------------------------------------

@dataclass
class Comparison:
    """What ``compare`` measured; ``to_dict`` is docs/design.md §6's compare.json
    (``comparison_report.save`` writes it with the report, compare.md, and the figure, compare.png)."""

    scene: Scene
    t_end: float
    record_dt: float
    quick: bool
    machine: str
    reference: Reference
    runs: list[RunResult] = field(default_factory=list)
    orders: list[Order] = field(default_factory=list)
    reference_trajectory: Trajectory | None = field(default=None, repr=False)  # rows at the common times
    tolerance_stalls: dict = field(default_factory=dict)   # adaptive spec -> {key: where its error stops shrinking}

    @property
    def not_converging(self) -> list[tuple[RunSpec, str, str]]:
        """(spec, error key, in words) for every spec whose error stops shrinking as its step
        or tolerance does, above the reference's floor."""
        out = [(o.spec, key, text) for o in self.orders for key, text in o.not_converging.items()]
        return out + [(spec, key, text) for spec, stalls in self.tolerance_stalls.items()
                      for key, text in stalls.items()]

    @property
    def specs(self) -> list[RunSpec]:
        return list(dict.fromkeys(r.spec for r in self.runs))

    def best(self, target: float) -> RunResult | None:
        """The fastest run that ended ok with contact and orientation errors at most ``target``;
        None for a target below the reference's accuracy (no error there is measured)."""
        if target < max(self.reference.floor(key) for key in FITTED):
            return None
        good = [r for r in self.runs if r.ok and r.worst <= target]
        return min(good, key=lambda r: r.seconds, default=None)

    def summary(self) -> str:
        """One line: the cheapest run for each target error, and its cost."""
        parts = []
        floor = max(self.reference.floor(key) for key in FITTED)
        for target in TARGETS:
            run = self.best(target)
            if run is None and floor > target:
                parts.append(f"{target:.0e} is below what the reference resolves ({floor:.1e})")
            elif run is None:
                parts.append(f"no run reached {target:.0e}")
            else:
                parts.append(f"for {target:.0e}: {setting_text(run)} "
                             f"({_seconds_text(run.seconds)}, {run.steps} steps)")
        text = "fastest " + "; ".join(parts)
        stalled = list(dict.fromkeys(str(spec) for spec, _, _ in self.not_converging))
        if stalled:
            text += f"; not converging (the error stops shrinking): {', '.join(stalled)}"
        if not self.reference.checked:
            text = f"{self.reference_warning()}; {text}"
        return text

    def reference_warning(self) -> str:
        """One sentence when the reference is not checked to REFERENCE_ACCURACY, else empty."""
        ref = self.reference
        if ref.checked:
            return ""
        floor = max(ref.floor(key) for key in FITTED)
        return (f"the reference ({ref.method} at rtol {ref.rtol:.0e}) is not checked to {REFERENCE_ACCURACY:.0e}: "
                f"{'; '.join(ref.problems)}; errors below {floor:.1e} are below the reference's accuracy, "
                f"not measured")

    def to_dict(self) -> dict:
        ref = self.reference
        best = {}
        for target in TARGETS:
            run = self.best(target)
            best[f"{target:.0e}"] = None if run is None else self.runs.index(run)
        return strict_json({
            "format": "rollball-compare", "version": 1, "program": f"rollball {__version__}",
            "scene": self.scene.to_dict(), "t_end": self.t_end, "machine": self.machine,
            "reference": ref.to_dict(),
            "runs": [r.to_dict() for r in self.runs],
            "orders": [o.to_dict() for o in self.orders],
            "not_converging": [{"method": spec.method, "munthe_kaas": spec.munthe_kaas, "error": key, "text": text}
                               for spec, key, text in self.not_converging],
            "record_dt": self.record_dt, "quick": self.quick,
            "best": best,   # index into runs of the fastest run reaching each error, or null
        })


def strict_json(doc: dict) -> dict:
    """``doc`` with every number JSON cannot hold (NaN, ±inf) replaced by null, each listed
    under "not_computed" with where it was and why ({"path": "runs[3].seconds", "reason": ...});
    what already is null for a stated reason (an order's "reasons") stays as it is."""
    missing = []

    def clean(value, path):
        if isinstance(value, dict):
            return {k: clean(v, f"{path}.{k}" if path else str(k)) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [clean(v, f"{path}[{i}]") for i, v in enumerate(value)]
        if isinstance(value, float) and not math.isfinite(value):
            missing.append({"path": path, "reason": f"not a finite number ({value!r}): it could not be computed"})
            return None
        return value

    out = clean(doc, "")
    out["not_computed"] = missing
    return out


def machine() -> str:
    """The processor (from /proc/cpuinfo where there is one), core count, system and Python."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, {platform.system()}, Python {platform.python_version()}"


def setting_text(run: RunResult) -> str:
    return f"{run.spec} dt {run.dt:.3g}" if run.dt is not None else f"{run.spec} rtol {run.rtol:.0e}"


def _seconds_text(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms" if seconds < 1 else f"{seconds:.3g} s"


def compare(scene: Scene, runs: Iterable[RunSpec | str] | str | None = None, t_end: float | None = None,
            quick: bool = False, progress: Callable[[int, int, str], None] | None = None,
            cancel: threading.Event | None = None) -> Comparison:
    """Run each spec (default: every method, the fixed-step ones Munthe-Kaas and classic) over
    its ladder on ``scene`` up to ``t_end`` (default: the scene's duration) and measure it
    against the reference. ``progress(done, total, text)`` is called before each run;
    setting ``cancel`` raises ``Cancelled`` within one chunk of steps.

    If the reference itself stops early (the ball does not fit, the landscape cannot be
    evaluated), everything is compared up to the last common time before that.
    """
    specs = _specs(runs)
    t_end = scene.duration if t_end is None else t_end
    if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not (0 < t_end < math.inf):
        raise ValueError(f"t_end must be a finite number greater than 0, not {t_end!r}")
    effort = QUICK if quick else FULL
    total = 2 + len(specs) * effort.max_points
    report = (lambda done, text: progress(done, total, text)) if progress else (lambda done, text: None)

    report(0, "reference")
    record_dt = record_step(float(t_end))
    ref_traj, reference = _reference(scene, float(t_end), record_dt, cancel)
    if reference.status is not Status.OK:  # compare up to the last common time it reached
        steps = ref_traj.t / record_dt
        on_grid = np.abs(steps - np.round(steps)) < 1e-6   # (the rows at transitions are not)
        if np.count_nonzero(on_grid) < 2:
            raise NothingToCompare(f"nothing to compare: the reference run stopped at once ({reference.message})")
        reached = int(np.flatnonzero(on_grid)[-1]) + 1
        ref_traj = replace(ref_traj, data=ref_traj.data[:reached])
        t_end = float(ref_traj.t[-1])
    runner = _Runner(scene, float(t_end), record_dt, ref_traj, reference, effort, cancel)
    results: list[RunResult] = []
    for i, spec in enumerate(specs):
        first = 2 + i * effort.max_points
        report(first, f"{spec}: compiling")
        runner.warm_up(spec)
        ladder = _fixed_ladder if spec.fixed_step else _tolerance_ladder
        results += ladder(runner, spec, lambda text, n: report(first + min(n, effort.max_points - 1), text))
    report(total, "done")
    orders = [fit_order(spec, results, reference) for spec in specs if spec.fixed_step]
    stalls = {spec: tolerance_stalls(spec, results, reference) for spec in specs if not spec.fixed_step}
    return Comparison(scene, float(t_end), record_dt, bool(quick), machine(), reference, results, orders, ref_traj,
                      {spec: found for spec, found in stalls.items() if found})
