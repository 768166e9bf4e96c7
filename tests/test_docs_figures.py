"""The manual's accuracy figures are what the scripts that make them measured: docs/accuracy.py
(docs/accuracy.json) and ``rollball compare hills`` (docs/compare-hills/compare.json). When a
script is run again and its figures move beyond noise, this fails until the manual says so."""

import json
import math
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# the pages that quote the figures (the reports the scripts write are not among them)
MANUAL = "\n".join(p.read_text(encoding="utf-8") for p in sorted(
    [*(ROOT / "docs" / "guide").glob("*.md"), *(ROOT / "docs" / "reference").glob("*.md"),
     ROOT / "docs" / "performance.md"]))
ACCURACY = json.loads((ROOT / "docs" / "accuracy.json").read_text())


def within(values, lo, hi, slack=0.1):
    """Every measured value inside the manual's range [lo, hi], give or take ``slack`` (relative)."""
    values = list(values)
    return lo * (1 - slack) <= min(values) and max(values) <= hi * (1 + slack)


def runs(scene, method):
    found = next(s for s in ACCURACY["pairs"] if s["scene"] == scene)
    return [r for r in found["runs"] if r["method"] == method]


def same_error(scene):
    """dop853's evaluations over scipy's DOP853's for the same contact error, 1e-8 .. 1e-10 m."""
    return [s["ratio"] for s in next(s for s in ACCURACY["pairs"] if s["scene"] == scene)["same_error"]]


@pytest.mark.parametrize("text, values, lo, hi, slack", [
    ("dopri5's R error is 15–17 times", lambda: [r["R_over_contact"] for r in runs("hills", "dopri5")], 15, 17, 0.1),
    ("(470–580 rtol)", lambda: [r["R_over_rtol"] for r in runs("hills", "dopri5")], 470, 580, 0.1),
    ("dop853's 3.5–11 times", lambda: [r["R_over_contact"] for r in runs("hills", "dop853")], 3.5, 11, 0.1),
    ("(2.4–35 rtol)", lambda: [r["R_over_rtol"] for r in runs("hills", "dop853")], 2.4, 35, 0.1),
    ("on the saddle 3.8–5.8 and", lambda: [r["R_over_contact"] for r in runs("saddle", "dopri5")], 3.8, 5.8, 0.1),
    ("1.5–4.1 times (at most 0.3 rtol)", lambda: [r["R_over_contact"] for r in runs("saddle", "dop853")], 1.5, 4.1,
     0.1),
    ("(at most 0.3 rtol)", lambda: [r["R_over_rtol"] for r in runs("saddle", "dop853")], 0, 0.3, 0.1),
    ("0.62–0.72 times its evaluations on the saddle", lambda: same_error("saddle"), 0.62, 0.72, 0.05),
    ("0.59–0.74 on a crater that is not an example", lambda: same_error("crater"), 0.59, 0.74, 0.05),
    # at most scipy's evaluations at every error measured (the manual's "0.79–0.93" within noise, never above 1)
    ("and 0.79–0.93 on the hills;", lambda: same_error("hills"), 0.79, 0.93, 0.05),
    ("and 0.79–0.93 on the hills;", lambda: same_error("hills") + same_error("saddle") + same_error("crater"), 0,
     1.0, 0),
    ("rk4's R error is 88–110 times", lambda: [r["R_over_contact"] for r in ACCURACY["rk4_orientation"]["runs"]],
     88, 110, 0.1),
    ("dopri5 at rtol 1e-10 within 9e-11 s", lambda: [r["dopri5_rtol_1e-10"] for r in ACCURACY["liftoff"]],
     0, 9e-11, 0.1),
    ("h = 1e-2 within 6e-9 s", lambda: [r["rk4_dt_0.01"] for r in ACCURACY["liftoff"]], 0, 6e-9, 0.1),
    ("2e-10 after 1000 s on the bowl", lambda: [ACCURACY["energy"]["gauss4"]], 1.5e-10, 2.5e-10, 0.1),
    ("RK4's grows to 5e-6", lambda: [ACCURACY["energy"]["rk4"]], 4.5e-6, 5.5e-6, 0.1),
    ("0.3 m amplitude takes 2.306 s (measured", lambda: ACCURACY["bowl_period"]["periods"], 2.3055, 2.3065, 0),
])
def test_the_manuals_figures_are_the_accuracy_scripts(text, values, lo, hi, slack):
    assert " ".join(text.split()) in " ".join(MANUAL.split())
    assert within(values(), lo, hi, slack), (text, values())


def test_the_manuals_orders_are_the_hills_comparisons():
    doc = json.loads((ROOT / "docs" / "compare-hills" / "compare.json").read_text())
    orders = {o["method"]: o["orientation"] for o in doc["orders"] if o["munthe_kaas"]}
    quoted = re.search(r"fitted slopes ([\d.]+), ([\d.]+), ([\d.]+), ([\d.]+) and ([\d.]+) are the orders",
                       " ".join(MANUAL.split()))
    assert quoted
    for method, text in zip(("euler", "rk4", "lawson5", "gauss4", "gauss6"), quoted.groups()):
        assert f"{orders[method]:.2f}" == text


def test_the_evaluations_for_an_error_are_read_off_each_ladders_front():
    import sys
    sys.path.insert(0, str(ROOT / "docs"))
    from accuracy import front, on_front

    runs = [{"contact": e, "evaluations": n} for e, n in
            [(1e-6, 100), (2e-7, 90), (1e-7, 150), (1e-8, 140), (1e-9, 300), (5e-15, 900)]]
    # (1e-6, 100) is beaten by (2e-7, 90) and (1e-7, 150) by (1e-8, 140); 5e-15 is below the floor
    assert front(runs, floor=1e-13) == [(1e-9, 300), (1e-8, 140), (2e-7, 90)]
    points = front(runs, floor=1e-13)
    assert on_front(points, 1e-8) == pytest.approx(140)
    assert on_front(points, math.sqrt(1e-9 * 1e-8)) == pytest.approx(math.sqrt(300 * 140))  # log-log
    assert on_front(points, 1e-10) is None and on_front(points, 1e-6) is None


def test_the_manuals_figures_on_the_error_scale_are_docs_dopri5_scale():
    """The ranges the manual (docs/reference/methods.md) and design.md quote are docs/dopri5_scale.py's, read from
    the figures
    it wrote (docs/dopri5_scale.json: the code before the scale and this one)."""
    import sys
    sys.path.insert(0, str(ROOT / "docs"))
    from dopri5_scale import ROLLING, trade

    doc = json.loads((ROOT / "docs" / "dopri5_scale.json").read_text())
    design = " ".join((ROOT / "docs" / "design.md").read_text().split())
    manual = " ".join(MANUAL.split())

    def span(pair):
        return f"{pair[0]:.2f}–{pair[1]:.2f}"

    def sci(value):
        return f"{value:.1e}".replace("e-0", "e-")

    dopri5 = trade(doc["now"], doc["before"], "dopri5", ROLLING)
    dop853 = trade(doc["now"], doc["before"], "dop853", ROLLING)
    valleys = trade(doc["now"], doc["before"], "dopri5", ("valleys",))
    for text in (f"{span(dopri5['evaluations'])} times the evaluations it took and its error is "
                 f"{span(dopri5['error'])} times what it was", f"its error is {span(dopri5['same_cost'])} times",
                 f"the error is {span(valleys['error'])} times, with {span(valleys['evaluations'])} times",
                 f"is at {span(dop853['error'])} times its error with {span(dop853['evaluations'])} times",
                 f"({span(dop853['same_cost'])} times for as many evaluations)"):
        assert text in manual, text
    for text in (f"dopri5 {span(dopri5['evaluations'])} times the evaluations, {span(dopri5['error'])} times",
                 f"{span(dopri5['same_cost'])} times the error the scale before",
                 f"dop853 {span(dop853['evaluations'])}",
                 f"{span(dop853['error'])} times the error", f"{span(dop853['same_cost'])} times for as many"):
        assert text in design, text
    lift = {(b["scene"], b["rtol"]): (b["error"], n["error"], b["evaluations"], n["evaluations"])
            for b, n in zip(doc["before"]["liftoffs"], doc["now"]["liftoffs"])}
    was, now, evaluations, _ = lift[("liftoff", 1e-8)]
    assert sci(now) == sci(was) and f"within {sci(now)} s" in manual and f"same {evaluations} evaluations" in manual
    was, now, _, _ = lift[("cylinder", 1e-8)]
    assert f"within {sci(now)} s (was {sci(was)}) at rtol 1e-8" in manual
    was, now, _, _ = lift[("cylinder", 1e-10)]
    assert f"{sci(now)} s (was {sci(was)}) at 1e-10" in manual
    worst = dopri5["error"][1]
    assert f"about {worst:.1f} times tighter" in manual
