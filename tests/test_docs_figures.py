"""The README's accuracy figures are what the scripts that make them measured: docs/accuracy.py
(docs/accuracy.json) and ``rollball compare hills`` (docs/compare-hills/compare.json). When a
script is run again and its figures move beyond noise, this fails until the README says so."""

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
ACCURACY = json.loads((ROOT / "docs" / "accuracy.json").read_text())


def within(values, lo, hi, slack=0.1):
    """Every measured value inside the README's range [lo, hi], give or take ``slack`` (relative)."""
    values = list(values)
    return lo * (1 - slack) <= min(values) and max(values) <= hi * (1 + slack)


def runs(scene, method):
    found = next(s for s in ACCURACY["pairs"] if s["scene"] == scene)
    return [r for r in found["runs"] if r["method"] == method]


@pytest.mark.parametrize("text, values, lo, hi, slack", [
    ("dopri5's R error is 15–16 times", lambda: [r["R_over_contact"] for r in runs("hills", "dopri5")], 15, 16, 0.1),
    ("(360–390 rtol)", lambda: [r["R_over_rtol"] for r in runs("hills", "dopri5")], 360, 390, 0.1),
    ("dop853's 2–14 times", lambda: [r["R_over_contact"] for r in runs("hills", "dop853")], 2, 14, 0.1),
    ("(8–46 rtol)", lambda: [r["R_over_rtol"] for r in runs("hills", "dop853")], 8, 46, 0.1),
    ("on the saddle 4–5 and", lambda: [r["R_over_contact"] for r in runs("saddle", "dopri5")], 4, 5, 0.1),
    ("4–7 times (at most 9 rtol)", lambda: [r["R_over_contact"] for r in runs("saddle", "dop853")], 4, 7, 0.1),
    ("0.99–1.2 times its evaluations", lambda: [r["evaluations_over_scipy"] for r in runs("hills", "dop853")
                                               if "evaluations_over_scipy" in r], 0.99, 1.2, 0.1),
    ("0.72–0.83 on the saddle", lambda: [r["evaluations_over_scipy"] for r in runs("saddle", "dop853")
                                         if "evaluations_over_scipy" in r], 0.72, 0.83, 0.1),
    ("rk4's R error is 88–110 times", lambda: [r["R_over_contact"] for r in ACCURACY["rk4_orientation"]["runs"]],
     88, 110, 0.1),
    ("dopri5 at rtol 1e-10 within 9e-11 s", lambda: [r["dopri5_rtol_1e-10"] for r in ACCURACY["liftoff"]], 0, 9e-11, 0.1),
    ("h = 1e-2 within 4e-9 s", lambda: [r["rk4_dt_0.01"] for r in ACCURACY["liftoff"]], 0, 4e-9, 0.1),
    ("2e-10 after 1000 s on the bowl", lambda: [ACCURACY["energy"]["gauss4"]], 1.5e-10, 2.5e-10, 0.1),
    ("RK4's grows to 5e-6", lambda: [ACCURACY["energy"]["rk4"]], 4.5e-6, 5.5e-6, 0.1),
    ("0.3 m amplitude takes 2.306 s (measured", lambda: ACCURACY["bowl_period"]["periods"], 2.3055, 2.3065, 0),
])
def test_readme_figures_are_the_accuracy_scripts(text, values, lo, hi, slack):
    assert " ".join(text.split()) in " ".join(README.split())
    assert within(values(), lo, hi, slack), (text, values())


def test_readme_orders_are_the_hills_comparisons():
    doc = json.loads((ROOT / "docs" / "compare-hills" / "compare.json").read_text())
    orders = {o["method"]: o["orientation"] for o in doc["orders"] if o["munthe_kaas"]}
    quoted = re.search(r"fitted slopes ([\d.]+), ([\d.]+), ([\d.]+), ([\d.]+) and ([\d.]+) are the orders",
                       " ".join(README.split()))
    assert quoted
    for method, text in zip(("euler", "rk4", "lawson5", "gauss4", "gauss6"), quoted.groups()):
        assert f"{orders[method]:.2f}" == text
