"""Scene values fitted to a measured track by least squares (docs/design.md §10).

``fit(scene, track, keys)`` varies the scene values named by dotted keys (those a sweep varies:
``start.*``, ``ball.*``, ``contact.friction``, ``contact.restitution``, ``gravity``,
``parameters.NAME``) until the run's positions at the track's times are closest to the track, with
scipy's ``least_squares`` (trust-region reflective, bounds, an optional robust loss, the Jacobian
by finite differences). The estimates' standard errors and correlations come from the Jacobian
at the solution, as lmfit reports them: cov = (JᵀJ)⁻¹ s², s² the residuals' sum of squares over
their degrees of freedom. Each evaluation is one run; the landscape is compiled once (its
parameters' values are an argument of the compiled code, not part of it).
"""

from __future__ import annotations

import dataclasses
import math
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .comparison import Cancelled
from .fit_options import LOSSES, NOT_FITTED
from .scene import Scene, SceneError
from .sweeps.grid import PARAMETER_PREFIX, check_keys, unit, value_of, with_values
from .sweeps.options import KEYS
from .track import Track
from .track_check import Residuals, check_point, model_at, residuals, run_for

# Where a value is valid (as a scene file checks it): the default bounds of a fit.
LIMITS = {"ball.radius": (0.0, math.inf), "ball.mass": (0.0, math.inf), "gravity": (0.0, math.inf),
          "contact.friction": (0.0, math.inf), "contact.restitution": (0.0, 1.0)}
DIFF_STEP = 1e-7   # relative step of the finite differences: above a run's round-off, below its curvature
MAX_RUNS = 2000    # a fit that has not converged by then stops (and says so)
# scipy's ftol, xtol, gtol: a fit stops when a step changes the sum of squares by less than 1e-6 of it,
# which moves an estimate by under 1 % of its standard error for tracks of 100 positions or fewer
TOLERANCE = 1e-6


class FitError(ValueError):
    """A fit that cannot be made as asked (one line)."""


@dataclass(frozen=True)
class Fit:
    """A fit's result: ``values`` (the estimates, in the order of ``keys``), ``errors`` (their
    standard errors; NaN where the track does not determine a value), ``correlation`` (p×p),
    ``scene`` (the scene with the estimates), ``residuals`` (the track against the fitted scene),
    ``runs`` (runs made, the Jacobian's included), ``converged`` and scipy's ``message``."""

    keys: tuple[str, ...]
    initial: tuple[float, ...]
    values: np.ndarray
    errors: np.ndarray
    correlation: np.ndarray
    scene: Scene
    residuals: Residuals
    runs: int
    converged: bool
    message: str
    loss: str
    seconds: float

    def lines(self) -> list[str]:
        """The report as the command line prints it: each estimate ± its standard error, the
        correlations, the residuals against the noise and the verdict."""
        width = max(len(k) for k in self.keys)
        out = [(f"{'converged' if self.converged else 'NOT converged'} after {self.runs} runs "
                f"({self.seconds:.2f} s CPU; {self.message})")]
        for key, value, error, start in zip(self.keys, self.values, self.errors, self.initial):
            u = f" {unit(key)}" if unit(key) else ""
            err = f"{error:.3g}" if math.isfinite(error) else "not determined"
            out.append(f"  {key:<{width}} = {value:.8g} ± {err}{u}  (scene: {start:.8g})")
        if len(self.keys) > 1:
            out.append("correlations:")
            for i in range(len(self.keys)):
                for j in range(i + 1, len(self.keys)):
                    out.append(f"  {self.keys[i]}, {self.keys[j]}: {self.correlation[i, j]:+.3f}")
        return out + self.residuals.lines()

    def to_dict(self) -> dict:
        """The estimates as plain data (strict JSON: NaN as None)."""
        return {"keys": list(self.keys), "values": [float(v) for v in self.values],
                "errors": [_finite_or_none(e) for e in self.errors],
                "correlation": [[_finite_or_none(c) for c in row] for row in self.correlation],
                "runs": self.runs, "converged": self.converged, "loss": self.loss,
                "rms": self.residuals.rms, "noise": self.residuals.noise, "points": len(self.residuals.track)}


def check_fit_keys(scene: Scene, keys) -> tuple[str, ...]:
    """The keys as a tuple, or ``FitError`` for one that cannot be fitted in this scene."""
    keys = tuple(keys)
    if not keys:
        raise FitError("nothing to fit: name one or more keys, e.g. contact.friction,start.vx")
    for key in keys:
        if keys.count(key) > 1:
            raise FitError(f"{key} is named twice")
        if key in NOT_FITTED:
            raise FitError(f"cannot fit {key}: {NOT_FITTED[key]}")
        if key not in KEYS and not key.startswith(PARAMETER_PREFIX):
            raise FitError(f"cannot fit {key!r}; the keys: {', '.join(k for k in KEYS if k not in NOT_FITTED)}, "
                           f"and parameters.NAME for a parameter of the scene")
    try:
        check_keys(scene, keys)
    except ValueError as e:
        raise FitError(str(e).replace("cannot vary", "cannot fit")) from None
    for key in keys:
        if not math.isfinite(value_of(scene, key)):
            raise FitError(f"cannot fit {key}: the scene's value is null (the ball always rolls); "
                           f"give it a number to start from")
    return keys


def parse_bounds(text: str) -> tuple[str, tuple[float, float]]:
    """``KEY=LO:HI`` -> (key, (lo, hi)); an empty LO or HI is unbounded on that side."""
    key, sep, spec = (s.strip() for s in text.partition("="))
    lo, colon, hi = spec.partition(":")
    if not sep or not colon:
        raise FitError(f"--bounds {text!r}: expected KEY=LO:HI, e.g. contact.friction=0.05:0.5")
    try:
        pair = (float(lo) if lo.strip() else -math.inf, float(hi) if hi.strip() else math.inf)
    except ValueError:
        raise FitError(f"--bounds {key}: LO and HI must be numbers, not {lo!r}, {hi!r}") from None
    return key, pair


def _bounds(scene: Scene, keys, given: dict) -> tuple[np.ndarray, np.ndarray]:
    unknown = set(given) - set(keys)
    if unknown:
        raise FitError(f"bounds for {', '.join(sorted(unknown))}, which is not fitted")
    lo, hi = [], []
    for key in keys:
        a, b = LIMITS.get(key, (-math.inf, math.inf))
        if key.startswith(PARAMETER_PREFIX):
            p = scene.parameters[scene.parameter_names.index(key[len(PARAMETER_PREFIX):])]
            a, b = (-math.inf if p.min is None else p.min), (math.inf if p.max is None else p.max)
        a, b = given.get(key, (a, b))
        if math.isnan(a) or math.isnan(b) or not a < b:
            raise FitError(f"bounds of {key}: {a:g} to {b:g} is not a range (LO < HI)")
        if not a <= value_of(scene, key) <= b:
            raise FitError(f"the scene's {key} = {value_of(scene, key):g} is outside its bounds {a:g} to {b:g}")
        lo.append(a)
        hi.append(b)
    return np.array(lo), np.array(hi)


def fit(scene: Scene, track: Track, keys, *, bounds: dict | None = None, loss: str = "linear",
        point: str = "center", noise: float | None = None, progress: Callable[[int], None] | None = None,
        cancel: threading.Event | None = None) -> Fit:
    """Fit the scene values named by ``keys`` (dotted, as a sweep varies them) to ``track``.

    The scene's values are the starting point. ``bounds``: key -> (lo, hi) (by default a value's
    valid range: friction ≥ 0, restitution in [0, 1], a parameter's min/max); ``loss``: "linear"
    (least squares) or one of scipy's robust losses, scaled by the noise, which count far-off
    positions (a frame that tracked the wrong thing) less; ``point``: the track follows the ball's
    "center" or its "contact" point; ``noise``: one coordinate's noise (m), else estimated from
    the track. ``progress(runs)`` is called after each run (the runs made so far); ``cancel``, when
    set, stops the fit before its next run with ``Cancelled`` (nothing is returned). Raises
    ``FitError`` (or ``SceneError``) with one line.
    """
    if loss not in LOSSES:
        raise FitError(f"unknown loss {loss!r}; the losses: {', '.join(LOSSES)}")
    check_point(point)
    keys = check_fit_keys(scene, keys)
    lo, hi = _bounds(scene, keys, dict(bounds or {}))
    if noise is not None and not (math.isfinite(noise) and noise > 0):
        raise FitError(f"the noise must be a finite number of metres above 0, not {noise!r}")
    scale = track.noise() if noise is None else float(noise)
    from scipy.optimize import least_squares

    x0 = np.array([value_of(scene, key) for key in keys])
    runs = 0
    clock = time.process_time()

    def difference(x):
        nonlocal runs
        if cancel is not None and cancel.is_set():
            raise Cancelled
        runs += 1
        try:
            trial = with_values(scene, keys, x)
        except SceneError as e:
            raise FitError(f"the fit tried {_values(keys, x)}, which the scene refuses ({e}); "
                           f"bound it with --bounds") from None
        traj = run_for(trial, track)
        if progress is not None:
            progress(runs)
        return (model_at(traj, trial, track, point) - track.positions).ravel()

    result = least_squares(difference, x0, bounds=(lo, hi), method="trf", loss=loss, f_scale=scale,
                           x_scale="jac", diff_step=DIFF_STEP, ftol=TOLERANCE, xtol=TOLERANCE, gtol=TOLERANCE,
                           max_nfev=MAX_RUNS)
    seconds = time.process_time() - clock
    errors, correlation = _uncertainty(result.jac, 2 * result.cost, len(keys))
    estimates = ", ".join(f"{k} = {v:.6g} ± {e:.2g}" for k, v, e in zip(keys, result.x, errors))
    note = (f"Fitted to the track {os.path.basename(track.source)}: {estimates}." if track.source
            else f"Fitted to a track: {estimates}.")
    fitted = dataclasses.replace(with_values(scene, keys, result.x),
                                 description=f"{scene.description} {note}".strip())
    return Fit(keys, tuple(x0), result.x, errors, correlation, fitted, residuals(fitted, track, point, noise),
               runs, bool(result.success), result.message, loss, seconds)


def _uncertainty(jac: np.ndarray, squares: float, p: int) -> tuple[np.ndarray, np.ndarray]:
    """Standard errors and the correlation matrix from the Jacobian at the solution:
    cov = (JᵀJ)⁻¹ s², s² = Σ r² / (N − p) (``squares`` = Σ r²; with a robust loss scipy's
    Jacobian and cost are those of the loss, which this approximates). A value the track does
    not determine (J's column zero or dependent on others) gets NaN."""
    s2 = squares / max(jac.shape[0] - p, 1)
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    if sv.size == 0 or sv[-1] <= sv[0] * 1e-10:
        nan = np.full(p, math.nan)
        return nan, np.full((p, p), math.nan)
    cov = (vt.T / sv ** 2) @ vt * s2
    errors = np.sqrt(np.diag(cov))
    return errors, cov / np.outer(errors, errors)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _values(keys, x) -> str:
    return ", ".join(f"{k} = {v:.6g}" for k, v in zip(keys, x))
