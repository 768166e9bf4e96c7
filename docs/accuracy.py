"""The accuracy figures the manual quotes (docs/reference/methods.md), measured against an independent reference.

Run from the repository's root (about seven minutes on 2 shared cores; needs scipy):

    .venv/bin/python docs/accuracy.py            # writes docs/accuracy.md and docs/accuracy.json

Every error here is against scipy's DOP853 on the plain equations of ``rollball/reference.py``
(numpy linear algebra, R as a full matrix; none of RollBall's kernel) at rtol = atol = 1e-13, and
is the largest over the rows of the run (every 0.01 s), not only at its end:

1. how tightly the adaptive pairs hold R: R's error against the contact point's, and against
   rtol, on the hills and the saddle (the ball turns about an axis that swings);
2. evaluations: dop853 against scipy's DOP853 on the same equations, for the same contact error,
   on the hills, the saddle and a crater that is not an example (``CRATER``, the one of
   tests/test_step_control.py; held out from choosing the PI control, while the error scale's
   floors, the ball's own units, were checked on all three). Each runs a ladder of tolerances a quarter
   decade apart; a run's largest contact error does not fall smoothly with its tolerance (the
   hills: 1.7e-8 at rtol 1e-8, 7.9e-9 at 10^-8.25), so each ladder's work-precision front (the
   runs no other run beats in both evaluations and error) is interpolated log-log at contact
   errors from 1e-8 to 1e-10 m (``TARGETS``): what the cheapest setting reaching an error costs;
3. rk4's R error against its contact point's on the hills;
4. energy over 1000 s on the bowl at h = 0.02: gauss4 against rk4;
5. lift-off times against scipy's event location (rtol = atol = 1e-12);
6. the period of the bowl example's 0.3 m oscillation (dop853 at rtol 1e-12).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))   # this checkout's rollball, whatever is installed (hence E402 below)

from rollball import Scene, simulate  # noqa: E402
from rollball.scene import Ball, Integrator, Start  # noqa: E402
from rollball.examples import EXAMPLES_DIR  # noqa: E402
from rollball.files import check_outputs, replace_together  # noqa: E402
from rollball.landscape import landscape_for  # noqa: E402
from rollball.reference import normal_force_zeros, reference_rhs, reference_solution  # noqa: E402
from rollball.simulation import initial_state  # noqa: E402

ROW = 0.01                      # seconds between the rows compared
PAIR_TOLERANCES = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
LADDER = tuple(10.0 ** (-k / 4) for k in range(20, 43))        # dop853's: 1e-5 .. 10^-10.5
SCIPY_TOLERANCES = tuple(10.0 ** (-k / 4) for k in range(8, 45))  # scipy's: 1e-2 .. 1e-11
TARGETS = tuple(10.0 ** (-k / 4) for k in range(32, 41))       # contact errors 1e-8 .. 1e-10 m
ATOL_PER_RTOL = 1e-3            # as rollball compare


# a held-out crater: a bowl with a Gaussian pit off its centre, the ball thrown across it
CRATER = Scene(landscape="0.3*(x^2+y^2) - 0.25*exp(-5*((x+0.1)^2+(y-0.15)^2))", gravity=9.81, ball=Ball(0.1, 1.0),
               start=Start(-0.9, -0.6, 0.4, 0.9, 0.0), integrator=Integrator("dop853", True, 1e-3), duration=5.0)


def example(name: str) -> Scene:
    return CRATER if name == "crater" else Scene.load(EXAMPLES_DIR / f"{name}.json")


def rows(t_end: float) -> np.ndarray:
    return np.linspace(0.0, t_end, round(t_end / ROW) + 1)


def errors(traj, alpha, R) -> tuple[float, float]:
    """Largest contact error (m) and ‖R − R_ref‖_F over the rows."""
    assert np.allclose(traj.t, rows(traj.t[-1]), rtol=0, atol=1e-9)
    contact = float(np.linalg.norm(traj.contact - alpha, axis=1).max())
    orientation = float(np.sqrt(((traj.R - R) ** 2).sum(axis=(1, 2))).max())
    return contact, orientation


def truth(scene: Scene, t_end: float):
    times = rows(t_end)
    alpha, _, R = reference_solution(scene, times, rtol=1e-13, atol=1e-13)
    tighter, _, R2 = reference_solution(scene, times, rtol=1e-14, atol=1e-14)
    own = {"contact": float(np.linalg.norm(alpha - tighter, axis=1).max()),
           "orientation": float(np.sqrt(((R - R2) ** 2).sum(axis=(1, 2))).max())}
    return alpha, R, own


def scipy_run(scene: Scene, rtol: float, t_end: float):
    """scipy's DOP853 on the reference equations: (evaluations, contact rows, R rows)."""
    from scipy.integrate import solve_ivp

    alpha0, v0 = initial_state(landscape_for(scene.landscape), scene)
    sol = solve_ivp(reference_rhs(scene), (0.0, t_end), np.concatenate([alpha0, v0, np.eye(3).ravel()]),
                    method="DOP853", t_eval=rows(t_end), rtol=rtol, atol=rtol * ATOL_PER_RTOL)
    y = sol.y.T
    return int(sol.nfev), y[:, :2], y[:, 5:].reshape(-1, 3, 3)


def pairs(name: str, t_end: float) -> dict:
    scene = example(name)
    alpha, R, own = truth(scene, t_end)
    out = {"scene": name, "t_end": t_end, "reference_error": own, "runs": []}
    for method in ("dopri5", "dop853"):
        for rtol in PAIR_TOLERANCES:
            traj = simulate(scene, method=method, rtol=rtol, atol=rtol * ATOL_PER_RTOL, record_dt=ROW, t_end=t_end)
            contact, orientation = errors(traj, alpha, R)
            out["runs"].append({"method": method, "rtol": rtol, "evaluations": int(traj.evaluations),
                                "contact": contact, "orientation": orientation,
                                "R_over_contact": orientation / contact, "R_over_rtol": orientation / rtol})
    floor = 10 * own["contact"]
    ladder = []
    for rtol in LADDER:
        traj = simulate(scene, method="dop853", rtol=rtol, atol=rtol * ATOL_PER_RTOL, record_dt=ROW, t_end=t_end)
        ladder.append({"rtol": rtol, "evaluations": int(traj.evaluations), "contact": errors(traj, alpha, R)[0]})
    scipy = []
    for rtol in SCIPY_TOLERANCES:
        evaluations, a, Rs = scipy_run(scene, rtol, t_end)
        scipy.append({"rtol": rtol, "evaluations": evaluations,
                      "contact": float(np.linalg.norm(a - alpha, axis=1).max()),
                      "orientation": float(np.sqrt(((Rs - R) ** 2).sum(axis=(1, 2))).max())})
    out["dop853_ladder"], out["scipy_dop853"] = ladder, scipy
    mine, theirs = front(ladder, floor), front(scipy, floor)
    out["same_error"] = []
    for target in TARGETS:
        a, b = on_front(mine, target), on_front(theirs, target)
        if a is not None and b is not None:
            out["same_error"].append({"contact": target, "dop853": a, "scipy_dop853": b, "ratio": a / b})
    return out


def front(runs: list[dict], floor: float) -> list[tuple[float, int]]:
    """(contact error, evaluations) of the runs no other run beats in both (errors below ``floor``,
    the reference's own, left out), errors rising."""
    out = []
    for error, evaluations in sorted((r["contact"], r["evaluations"]) for r in runs if r["contact"] > floor):
        if not out or evaluations < out[-1][1]:
            out.append((error, evaluations))
    return out


def on_front(points: list[tuple[float, int]], error: float) -> float | None:
    """The evaluations to reach ``error`` on a front, log-log between its points (None outside it)."""
    if not points or not points[0][0] <= error <= points[-1][0]:
        return None
    return float(np.exp(np.interp(np.log(error), np.log([e for e, _ in points]), np.log([n for _, n in points]))))


def rk4_orientation(name: str, t_end: float) -> dict:
    scene = example(name)
    alpha, R, _ = truth(scene, t_end)
    runs = []
    for dt in (0.01, 0.005, 0.0025, 0.00125):
        traj = simulate(scene, method="rk4", dt=dt, record_every=round(ROW / dt), t_end=t_end)
        contact, orientation = errors(traj, alpha, R)
        runs.append({"dt": dt, "contact": contact, "orientation": orientation, "R_over_contact": orientation / contact})
    return {"scene": name, "t_end": t_end, "runs": runs}


def long_energy() -> dict:
    scene = example("bowl")
    out = {"scene": "bowl", "t_end": 1000.0, "dt": 0.02}
    for method in ("gauss4", "rk4"):
        traj = simulate(scene, method=method, dt=0.02, t_end=1000.0, record_every=50)
        out[method] = float(np.abs(traj.energy - traj.energy[0]).max() / traj.energy_scale)
    return out


def reference_liftoff(scene: Scene, t_max: float) -> float:
    """The first time F·N = 0, by scipy's DOP853 (rtol = atol = 1e-12) with its event location
    on the independent equations of rollball.reference."""
    return float(normal_force_zeros(scene, t_max, first=True)[0])


def liftoffs() -> list[dict]:
    out = []
    for name in ("liftoff", "cylinder"):
        scene = example(name)
        t_ref = reference_liftoff(scene, scene.duration)
        rk4 = simulate(scene, method="rk4", dt=1e-2, record_every=10).liftoff_time
        dopri = simulate(scene, method="dopri5", rtol=1e-10, atol=1e-13, record_dt=0.01).liftoff_time
        out.append({"scene": name, "reference": t_ref, "rk4_dt_0.01": abs(rk4 - t_ref),
                    "dopri5_rtol_1e-10": abs(dopri - t_ref)})
    return out


def bowl_period() -> dict:
    """Time between upward crossings of x = 0 (linear between rows 1 ms apart), dop853 at 1e-12."""
    traj = simulate(example("bowl"), method="dop853", rtol=1e-12, atol=1e-15, record_dt=0.001)
    x, t = traj.contact[:, 0], traj.t
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    crossings = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    return {"scene": "bowl", "periods": np.diff(crossings).tolist()}


def span(values) -> str:
    values = list(values)
    lo, hi = min(values), max(values)
    return f"{lo:.2g}–{hi:.2g}" if f"{lo:.2g}" != f"{hi:.2g}" else f"{lo:.2g}"


def markdown(results: dict) -> str:
    lines = ["# Accuracy figures", "",
             "Made by `docs/accuracy.py` (see its docstring); every error against scipy's DOP853 on the "
             "independent equations of `rollball/reference.py` at rtol = 1e-13, largest over rows every "
             f"{ROW:g} s. {results['seconds']:.0f} s to make.", ""]
    lines += ["## 1–2. The adaptive pairs: R against the contact point, evaluations against scipy", ""]
    for scene in results["pairs"]:
        own = scene["reference_error"]
        lines += [f"### {scene['scene']} (to t = {scene['t_end']:g} s; the reference's own error, against "
                  f"rtol 1e-14: contact {own['contact']:.1e} m, R {own['orientation']:.1e})", "",
                  "| method | rtol | evaluations | contact (m) | ‖R − R_ref‖_F | R / contact | R / rtol |",
                  "|---|---|---:|---:|---:|---:|---:|"]
        for r in scene["runs"]:
            lines.append(f"| {r['method']} | {r['rtol']:.0e} | {r['evaluations']} | {r['contact']:.2e} | "
                         f"{r['orientation']:.2e} | {r['R_over_contact']:.3g} | {r['R_over_rtol']:.3g} |")
        for method in ("dopri5", "dop853"):
            mine = [r for r in scene["runs"] if r["method"] == method]
            lines += ["", f"- {method}: R's error {span(r['R_over_contact'] for r in mine)} × the contact "
                          f"point's, {span(r['R_over_rtol'] for r in mine)} × rtol"]
        same = scene["same_error"]
        lines += ["", "Evaluations for the same contact error (each ladder's front, log-log): dop853 against scipy's "
                      "DOP853:", "", "| contact (m) | dop853 | scipy's DOP853 | ratio |", "|---:|---:|---:|---:|"]
        lines += [f"| {s['contact']:.2g} | {s['dop853']:.0f} | {s['scipy_dop853']:.0f} | {s['ratio']:.2f} |"
                  for s in same]
        ratios = [s["ratio"] for s in same]
        lines += ["", f"- dop853's evaluations against scipy's DOP853 for the same contact error, "
                      f"{same[0]['contact']:.2g} to {same[-1]['contact']:.2g} m: {min(ratios):.2f}–{max(ratios):.2f} ×"]
        for name, ladder in (("dop853", scene["dop853_ladder"]), ("scipy's DOP853", scene["scipy_dop853"])):
            lines += ["", f"{name}: " + "; ".join(f"rtol {s['rtol']:.2g}: {s['evaluations']}, {s['contact']:.1e}"
                                                  for s in ladder)]
        lines.append("")
    rk4 = results["rk4_orientation"]
    lines += [f"## 3. rk4's R against its contact point ({rk4['scene']}, to t = {rk4['t_end']:g} s)", "",
              "| dt | contact (m) | ‖R − R_ref‖_F | R / contact |", "|---|---:|---:|---:|"]
    lines += [f"| {r['dt']:g} | {r['contact']:.2e} | {r['orientation']:.2e} | {r['R_over_contact']:.3g} |"
              for r in rk4["runs"]]
    lines += ["", f"R / contact: {span(r['R_over_contact'] for r in rk4['runs'])}", ""]
    e = results["energy"]
    lines += [f"## 4. Energy over {e['t_end']:g} s on the bowl at h = {e['dt']:g}", "",
              f"Largest relative energy error: gauss4 {e['gauss4']:.1e}, rk4 {e['rk4']:.1e}.", ""]
    lines += ["## 5. Lift-off time against scipy's event location", "",
              "| scene | reference (s) | rk4, h = 1e-2 | dopri5, rtol 1e-10 |", "|---|---:|---:|---:|"]
    lines += [f"| {r['scene']} | {r['reference']:.9f} | {r['rk4_dt_0.01']:.1e} s | {r['dopri5_rtol_1e-10']:.1e} s |"
              for r in results["liftoff"]]
    lines += ["", "## 6. The bowl example's period (from 0.3 m)", "",
              "Between upward crossings of x = 0: " + ", ".join(f"{p:.6f} s" for p in results["bowl_period"]["periods"])
              + "."]
    return "\n".join(lines) + "\n"


OUTPUTS = ("accuracy.json", "accuracy.md")


def main() -> None:
    out = ROOT / "docs"
    check_outputs(out, OUTPUTS)   # (before seven minutes of runs: each file can be written)
    start = time.perf_counter()
    results = {"pairs": [pairs("hills", 10.0), pairs("saddle", example("saddle").duration),
                         pairs("crater", CRATER.duration)],
               "rk4_orientation": rk4_orientation("hills", 10.0), "energy": long_energy(),
               "liftoff": liftoffs(), "bowl_period": bowl_period()}
    results["seconds"] = time.perf_counter() - start
    replace_together(out, {"accuracy.json": json.dumps(results, indent=1) + "\n", "accuracy.md": markdown(results)},
                     kept_name="accuracy-unsaved")
    print(markdown(results))


if __name__ == "__main__":
    main()
