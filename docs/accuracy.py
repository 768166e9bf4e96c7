"""The accuracy figures the README quotes, measured against an independent reference.

Run from the repository's root (about a minute on 2 shared cores; needs scipy):

    .venv/bin/python docs/accuracy.py            # writes docs/accuracy.md and docs/accuracy.json

Every error here is against scipy's DOP853 on the plain equations of ``rollball/reference.py``
(numpy linear algebra, R as a full matrix; none of RollBall's kernel) at rtol = atol = 1e-13, and
is the largest over the rows of the run (every 0.01 s), not only at its end:

1. how tightly the adaptive pairs hold R: R's error against the contact point's, and against
   rtol, on the hills and the saddle (the ball turns about an axis that swings);
2. evaluations: dop853 against scipy's DOP853 on the same equations, for the same contact error
   (scipy's evaluations to reach dop853's error, interpolated log-log between its tolerances; and
   both ladders' evaluations to reach 1e-8 and 1e-10), on the hills, the saddle and a crater that
   played no part in choosing the step-size control (``CRATER``, the one of
   tests/test_step_control.py);
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
sys.path.insert(0, str(ROOT))

from rollball import Scene, simulate  # noqa: E402
from rollball.scene import Ball, Integrator, Start  # noqa: E402
from rollball.examples import EXAMPLES_DIR  # noqa: E402
from rollball.landscape import landscape_for  # noqa: E402
from rollball.reference import reference_rhs, reference_solution  # noqa: E402
from rollball.simulation import initial_state  # noqa: E402

ROW = 0.01                      # seconds between the rows compared
PAIR_TOLERANCES = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
SCIPY_TOLERANCES = tuple(10.0 ** -k for k in range(2, 13))
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
    scipy = []
    for rtol in SCIPY_TOLERANCES:
        evaluations, a, Rs = scipy_run(scene, rtol, t_end)
        scipy.append({"rtol": rtol, "evaluations": evaluations,
                      "contact": float(np.linalg.norm(a - alpha, axis=1).max()),
                      "orientation": float(np.sqrt(((Rs - R) ** 2).sum(axis=(1, 2))).max())})
    out["scipy_dop853"] = scipy
    # scipy's evaluations for dop853's contact error, interpolated log-log (errors above the floor)
    usable = []  # from the tightest tolerance on, while the error grows as the tolerance loosens
    for s in reversed([s for s in scipy if s["contact"] > 10 * own["contact"]]):
        if usable and s["contact"] <= usable[0]["contact"]:
            break
        usable.insert(0, s)
    log_err = np.log([s["contact"] for s in usable])[::-1]
    log_ev = np.log([s["evaluations"] for s in usable])[::-1]
    for run in out["runs"]:
        e = np.log(run["contact"])
        if run["method"] == "dop853" and log_err[0] <= e <= log_err[-1]:
            run["scipy_evaluations_same_error"] = float(np.exp(np.interp(e, log_err, log_ev)))
            run["evaluations_over_scipy"] = run["evaluations"] / run["scipy_evaluations_same_error"]
    mine = [r for r in out["runs"] if r["method"] == "dop853"]
    mine_err = np.log([r["contact"] for r in mine])[::-1]
    mine_ev = np.log([r["evaluations"] for r in mine])[::-1]
    out["to_reach"] = {}
    for target in (1e-8, 1e-10):
        e = np.log(target)
        if log_err[0] <= e <= log_err[-1] and mine_err[0] <= e <= mine_err[-1] and np.all(np.diff(mine_err) > 0):
            out["to_reach"][f"{target:g}"] = {"dop853": float(np.exp(np.interp(e, mine_err, mine_ev))),
                                              "scipy_dop853": float(np.exp(np.interp(e, log_err, log_ev)))}
    return out


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
    """The first time F·N = 0 by scipy's DOP853 (rtol = atol = 1e-12) with its event location
    (as tests/test_dense_output.py)."""
    from scipy.integrate import solve_ivp

    landscape = landscape_for(scene.landscape)
    r, m, g0 = scene.ball.radius, scene.ball.mass, scene.gravity
    rhs = reference_rhs(scene)

    def force(t, y):
        alpha, v = y[:2], y[2:5]
        _, fx, fy, fxx, fxy, fyy = landscape.evaluate(alpha[0], alpha[1])
        n = np.array([-fx, -fy, 1.0])
        N = n / np.linalg.norm(n)
        omega = 5 / (7 * m * r * r) * (v + 2.5 * N * (N @ v))
        dN = (np.eye(3) - np.outer(N, N)) @ np.array([[-fxx, -fxy], [-fxy, -fyy], [0, 0]]) / np.linalg.norm(n)
        return m * r * np.cross(omega, dN @ rhs(t, y)[:2]) @ N + m * g0 * N[2]

    force.terminal, force.direction = True, -1
    alpha, v = initial_state(landscape, scene)
    sol = solve_ivp(rhs, (0.0, t_max), np.concatenate([alpha, v, np.eye(3).ravel()]), method="DOP853",
                    rtol=1e-12, atol=1e-12, events=force)
    return float(sol.t_events[0][0])


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
                  "| method | rtol | evaluations | contact (m) | ‖R − R_ref‖_F | R / contact | R / rtol "
                  "| scipy DOP853's evaluations for that contact error | ratio |",
                  "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
        for r in scene["runs"]:
            same = r.get("scipy_evaluations_same_error")
            lines.append(f"| {r['method']} | {r['rtol']:.0e} | {r['evaluations']} | {r['contact']:.2e} | "
                         f"{r['orientation']:.2e} | {r['R_over_contact']:.3g} | {r['R_over_rtol']:.3g} | "
                         + (f"{same:.0f} | {r['evaluations_over_scipy']:.2f} |" if same else "— | — |"))
        for method in ("dopri5", "dop853"):
            mine = [r for r in scene["runs"] if r["method"] == method]
            lines += ["", f"- {method}: R's error {span(r['R_over_contact'] for r in mine)} × the contact "
                          f"point's, {span(r['R_over_rtol'] for r in mine)} × rtol"]
        ratios = [r["evaluations_over_scipy"] for r in scene["runs"] if "evaluations_over_scipy" in r]
        if ratios:
            lines.append(f"- dop853's evaluations against scipy's DOP853 for the same contact error: "
                         f"{span(ratios)} ×")
        for target, reach in scene.get("to_reach", {}).items():
            lines.append(f"- to reach a contact error of {target} m: dop853 {reach['dop853']:.0f} evaluations, "
                         f"scipy's DOP853 {reach['scipy_dop853']:.0f} "
                         f"({reach['dop853'] / reach['scipy_dop853']:.2f} ×)")
        lines += ["", "scipy's DOP853: " + "; ".join(f"rtol {s['rtol']:.0e}: {s['evaluations']} evaluations, "
                                                     f"contact {s['contact']:.1e}" for s in scene["scipy_dop853"]), ""]
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


def main() -> None:
    start = time.perf_counter()
    results = {"pairs": [pairs("hills", 10.0), pairs("saddle", example("saddle").duration),
                         pairs("crater", CRATER.duration)],
               "rk4_orientation": rk4_orientation("hills", 10.0), "energy": long_energy(),
               "liftoff": liftoffs(), "bowl_period": bowl_period()}
    results["seconds"] = time.perf_counter() - start
    out = ROOT / "docs"
    (out / "accuracy.json").write_text(json.dumps(results, indent=1) + "\n")
    (out / "accuracy.md").write_text(markdown(results), encoding="utf-8")
    print(markdown(results))


if __name__ == "__main__":
    main()
