"""dopri5 on rolling scenes before and after the adaptive pairs' error scale held each component
relative to at least the ball's own size (commit e5e8090): error and evaluations at the same rtol.

Run from the repository's root (a few minutes on 2 shared cores):

    git worktree add /tmp/before e5e8090^      # the code before the change (its kernel compiles afresh)
    .venv/bin/python docs/dopri5_scale.py --before /tmp/before

Without ``--before`` it prints this tree's figures alone; ``--now /tmp/scale`` (``git worktree add
/tmp/scale e5e8090``) sets the change alone against its parent. Each tree is measured in a process of
its own (its own ``rollball``), on the examples hills and saddle, the crater of docs/accuracy.py (not an
example) and ``valleys``: the example ripples at wavenumber k = 2 (its default k = 1 is the hills),
a ball at rest finding its way among many valleys: dopri5 and dop853 at rtol 1e-6, 1e-8, 1e-10 (atol = 1e-3 rtol,
as ``rollball compare``), each against that tree's dop853 at rtol 1e-13 (its own error, against
rtol 1e-14, printed: it is far below every error quoted). The error is the largest contact-point
distance over rows every 0.01 s. Then dopri5's lift-off time over the crest (example ``liftoff``)
and the cylinder at rtol 1e-8 and 1e-10, against scipy's event location on the independent
equations of rollball/reference.py (rtol = atol = 1e-12; computed once, in this tree).

The last column weighs the trade: a run's error against the error the code before would have had
at the same number of evaluations (log-log between its neighbouring tolerances): below 1, the
run is now more accurate for its cost.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ("hills", "saddle", "crater", "valleys")
METHODS = ("dopri5", "dop853")
RTOLS = (1e-6, 1e-8, 1e-10)
LIFTOFF_SCENES = ("liftoff", "cylinder")
LIFTOFF_RTOLS = (1e-8, 1e-10)
ATOL_PER_RTOL = 1e-3
ROW = 0.01
REFERENCE = 1e-13


def code(root: Path) -> str:
    """The checkout's rollball/ as git names it (its tree's hash; "+changes" when its files differ)."""
    tree = subprocess.run(["git", "rev-parse", "--short", "HEAD:rollball"], cwd=root, capture_output=True, text=True)
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "rollball"], cwd=root,
                           capture_output=True, text=True)
    return tree.stdout.strip() + ("+changes" if dirty.stdout.strip() else "")


def measure(root: Path) -> dict:
    """This tree's figures (run in a process whose ``rollball`` is root's)."""
    sys.path.insert(0, str(root))
    import numpy as np

    import rollball
    from rollball import Scene, simulate
    from rollball.examples import EXAMPLES_DIR
    from rollball.scene import Ball, Integrator, Start

    assert Path(rollball.__file__).resolve().is_relative_to(root.resolve()), rollball.__file__
    crater = Scene(landscape="0.3*(x^2+y^2) - 0.25*exp(-5*((x+0.1)^2+(y-0.15)^2))", gravity=9.81,
                   ball=Ball(0.1, 1.0), start=Start(-0.9, -0.6, 0.4, 0.9, 0.0),
                   integrator=Integrator("dop853", True, 1e-3), duration=5.0)

    valleys = replace(Scene.load(EXAMPLES_DIR / "ripples.json"), parameters={"a": 0.5, "k": 2.0})

    def scene_of(name):
        return {"crater": crater, "valleys": valleys}.get(name) or Scene.load(EXAMPLES_DIR / f"{name}.json")

    def run(scene, method, rtol, **options):
        return simulate(scene, method=method, rtol=rtol, atol=rtol * ATOL_PER_RTOL, **options)

    out = {"rollball_tree": code(root), "scenes": [], "liftoffs": []}
    for name in SCENES:
        scene = scene_of(name)
        ref = run(scene, "dop853", REFERENCE, record_dt=ROW)
        tighter = run(scene, "dop853", REFERENCE / 10, record_dt=ROW)
        entry = {"scene": name, "t_end": float(ref.t[-1]),
                 "reference_error": float(np.linalg.norm(ref.contact - tighter.contact, axis=1).max()), "runs": []}
        for method in METHODS:
            for rtol in RTOLS:
                traj = run(scene, method, rtol, record_dt=ROW)
                assert len(traj.t) == len(ref.t), (name, method, rtol)
                entry["runs"].append({"method": method, "rtol": rtol, "evaluations": int(traj.evaluations),
                                      "contact": float(np.linalg.norm(traj.contact - ref.contact, axis=1).max())})
        out["scenes"].append(entry)
    for name in LIFTOFF_SCENES:
        scene = scene_of(name)
        for rtol in LIFTOFF_RTOLS:
            traj = run(scene, "dopri5", rtol, record_dt=ROW)
            out["liftoffs"].append({"scene": name, "rtol": rtol, "time": traj.liftoff_time,
                                    "evaluations": int(traj.evaluations)})
    return out


def liftoff_times() -> dict:
    """scipy's first zero of the normal force on the independent equations, per lift-off scene."""
    sys.path.insert(0, str(ROOT))
    from rollball import Scene
    from rollball.examples import EXAMPLES_DIR
    from rollball.reference import normal_force_zeros

    out = {}
    for name in LIFTOFF_SCENES:
        scene = Scene.load(EXAMPLES_DIR / f"{name}.json")
        out[name] = float(normal_force_zeros(scene, scene.duration, first=True)[0])
    return out


def measured(root: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(root))
    done = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--measure", str(root)], cwd=root,
                          env=env, capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"measuring {root} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def at_evaluations(runs: list[dict], method: str, evaluations: float) -> float:
    """The error ``method``'s ladder in ``runs`` would have at this many evaluations: log-log
    between its two neighbouring tolerances (the nearest pair beyond its ends)."""
    import numpy as np

    points = sorted((r["evaluations"], r["contact"]) for r in runs if r["method"] == method)
    n = np.log([p[0] for p in points])
    e = np.log([p[1] for p in points])
    i = int(np.clip(np.searchsorted(n, np.log(evaluations)), 1, len(n) - 1))
    slope = (e[i] - e[i - 1]) / (n[i] - n[i - 1])
    return float(np.exp(e[i - 1] + slope * (np.log(evaluations) - n[i - 1])))


ROLLING = ("hills", "saddle", "crater")   # the manual's first figures; the many valleys apart


def trade(now: dict, before: dict, method: str, scenes: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    """Over these scenes and the three tolerances, the (smallest, largest) ratio now / before of
    the error at the same rtol ("error"), of the evaluations ("evaluations") and of the error
    against before's at as many evaluations ("same_cost"): what docs/reference/methods.md quotes."""
    out = {"error": [], "evaluations": [], "same_cost": []}
    for entry, old in zip(now["scenes"], before["scenes"]):
        if entry["scene"] not in scenes:
            continue
        for run, was in zip(entry["runs"], old["runs"]):
            if run["method"] != method:
                continue
            out["error"].append(run["contact"] / was["contact"])
            out["evaluations"].append(run["evaluations"] / was["evaluations"])
            out["same_cost"].append(run["contact"] / at_evaluations(old["runs"], method, run["evaluations"]))
    return {key: (min(values), max(values)) for key, values in out.items()}


def trade_lines(now: dict, before: dict) -> list[str]:
    lines = ["", "Now / before, over rtol 1e-6, 1e-8, 1e-10 (smallest-largest)", "",
             "| method | scenes | error at the same rtol | evaluations | error for as many evaluations |",
             "|---|---|---:|---:|---:|"]
    for method in METHODS:
        for scenes in (ROLLING, ("valleys",)):
            t = trade(now, before, method, scenes)
            lines.append(f"| {method} | {', '.join(scenes)} | " + " | ".join(
                f"{t[key][0]:.2f}-{t[key][1]:.2f}" for key in ("error", "evaluations", "same_cost")) + " |")
    return lines


def table(now: dict, before: dict | None) -> list[str]:
    lines = []
    for i, entry in enumerate(now["scenes"]):
        old = before["scenes"][i] if before else None
        lines += ["", f"{entry['scene']} (to t = {entry['t_end']:g} s; reference's own error "
                      f"{entry['reference_error']:.1e} m" + (f", before {old['reference_error']:.1e} m" if old else "")
                  + ")", ""]
        if old:
            lines += ["| method | rtol | error before (m) | error now (m) | now / before | evaluations before "
                      "| evaluations now | now / before | error now / before's at as many evaluations |",
                      "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
        else:
            lines += ["| method | rtol | error (m) | evaluations |", "|---|---|---:|---:|"]
        for j, run in enumerate(entry["runs"]):
            if old:
                was = old["runs"][j]
                lines.append(f"| {run['method']} | {run['rtol']:.0e} | {was['contact']:.2e} | {run['contact']:.2e} | "
                             f"{run['contact'] / was['contact']:.2f} | {was['evaluations']} | {run['evaluations']} | "
                             f"{run['evaluations'] / was['evaluations']:.2f} | "
                             f"{run['contact'] / at_evaluations(old['runs'], run['method'], run['evaluations']):.2f} |")
            else:
                lines.append(f"| {run['method']} | {run['rtol']:.0e} | {run['contact']:.2e} | {run['evaluations']} |")
    lines += ["", "dopri5's lift-off time against scipy's event location", ""]
    if before:
        lines += ["| scene | rtol | error before (s) | error now (s) | evaluations before | evaluations now |",
                  "|---|---|---:|---:|---:|---:|"]
    else:
        lines += ["| scene | rtol | error (s) | evaluations |", "|---|---|---:|---:|"]
    for j, lift in enumerate(now["liftoffs"]):
        if before:
            was = before["liftoffs"][j]
            lines.append(f"| {lift['scene']} | {lift['rtol']:.0e} | {was['error']:.1e} | {lift['error']:.1e} | "
                         f"{was['evaluations']} | {lift['evaluations']} |")
        else:
            lines.append(f"| {lift['scene']} | {lift['rtol']:.0e} | {lift['error']:.1e} | {lift['evaluations']} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", type=Path, help="a checkout of the code before the change (e5e8090^)")
    parser.add_argument("--now", type=Path, default=ROOT,
                        help="the checkout to set against it (default: this one; e5e8090 for the change alone)")
    parser.add_argument("--measure", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    args = parser.parse_args()
    if args.measure:
        print(json.dumps(measure(args.measure)))
        return
    before = measured(args.before.resolve()) if args.before else None
    now = measured(args.now.resolve())
    truth = liftoff_times()
    for doc in (now, before) if before else (now,):
        for lift in doc["liftoffs"]:
            lift["reference"] = truth[lift["scene"]]
            lift["error"] = abs(lift["time"] - lift["reference"])
    print("\n".join(table(now, before) + (trade_lines(now, before) if before else [])).lstrip("\n"))
    if args.json:
        args.json.write_text(json.dumps({"before": before, "now": now}, indent=1) + "\n")


if __name__ == "__main__":
    main()
