"""Work against precision on example scenes: ``rollball.compare`` on each (every method over
its ladder of steps or tolerances, errors against the checked reference at common times),
and scipy's DOP853 on the same equations (``reference.reference_rhs``) over a range of
tolerances, measured against the same reference at the same times: the baseline a Python
user would otherwise write.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..comparison import ATOL_PER_RTOL, Comparison, compare, compute_clock
from ..examples import EXAMPLES_DIR
from ..landscape import landscape_of
from ..reference import reference_rhs
from ..scene import Scene
from ..simulation import initial_state


@dataclass(frozen=True)
class Baseline:
    """One run of scipy's DOP853: its tolerance, cost and errors (contact in m, orientation
    ‖R − R_ref‖_F, maxima over the common times)."""

    rtol: float
    evaluations: int      # right-hand-side evaluations (scipy does not report its steps with t_eval)
    seconds: float
    contact: float
    orientation: float


@dataclass(frozen=True)
class SceneResult:
    name: str
    comparison: Comparison
    scipy: list[Baseline]


def _scipy_run(scene: Scene, rtol: float, times: np.ndarray):
    from scipy.integrate import solve_ivp

    rhs = reference_rhs(scene)
    alpha, v = initial_state(landscape_of(scene), scene)
    y0 = np.concatenate([alpha, v, np.eye(3).ravel()])
    start = compute_clock()  # as for rollball's own runs
    sol = solve_ivp(rhs, (0.0, times[-1]), y0, method="DOP853", rtol=rtol, atol=rtol * ATOL_PER_RTOL,
                    t_eval=times)
    return compute_clock() - start, sol


def scipy_baseline(cmp: Comparison, tolerances, repeats: int) -> list[Baseline]:
    """scipy's DOP853 at each tolerance: one run for the error, the median of ``repeats`` for
    the cost (one run is enough for the slow ones)."""
    ref = cmp.reference_trajectory
    points = []
    for rtol in tolerances:
        seconds, sol = _scipy_run(cmp.scene, rtol, ref.t)
        if not sol.success or sol.y.shape[1] != len(ref.t):
            continue
        if seconds < 0.5:
            seconds = float(np.median([_scipy_run(cmp.scene, rtol, ref.t)[0] for _ in range(repeats)]))
        y = sol.y.T
        contact = float(np.linalg.norm(y[:, :2] - ref.contact, axis=1).max())
        orientation = float(np.linalg.norm(y[:, 5:] - ref.R.reshape(-1, 9), axis=1).max())
        points.append(Baseline(rtol, int(sol.nfev), seconds, contact, orientation))
    return points


def measure(scene_names: list[str], t_end: float | None, quick: bool, log=print) -> list[SceneResult]:
    """``compare`` and the scipy baseline on every scene, to t_end (None: its own duration)."""
    results = []
    tolerances = (1e-4, 1e-7) if quick else tuple(10.0 ** -k for k in range(3, 11))
    for name in scene_names:
        log(f"  {name} ...")
        scene = Scene.load(EXAMPLES_DIR / f"{name}.json")
        cmp = compare(scene, t_end=t_end, quick=quick)
        results.append(SceneResult(name, cmp, scipy_baseline(cmp, tolerances, 3 if quick else 5)))
    return results
