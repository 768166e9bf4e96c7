"""``rollball compare`` as the judge: the reference states and checks its own error (and says so
where it is not good to 1e-10, quoting no error below it), orders come from the finest steps whose
slopes agree, and a run whose error stops shrinking with the step is named, not fitted."""

import dataclasses
import json
import math

import pytest
from conftest import make_scene

from rollball import comparison, comparison_report, compare
from rollball.comparison import (REFERENCE_ACCURACY, RunResult, RunSpec, fit_order, fit_range, stall,
                                 tolerance_stalls)
from rollball.examples import EXAMPLES_DIR
from rollball.scene import Scene
from rollball.trajectory import Status


class FakeReference:
    """Only what fit_order reads: a floor per error key."""

    def __init__(self, floor=1e-13):
        self._floor = floor

    def floor(self, key):
        return self._floor


def ladder(spec, dts, errors, rtol=False):
    return [RunResult(spec, None if rtol else dt, dt if rtol else None, None, Status.OK, 10, 0, 40, 1e-3,
                      {"contact": e, "velocity": e, "omega": e, "orientation": e, "energy": e}, False)
            for dt, e in zip(dts, errors)]


HALVING = [0.1 / 2 ** k for k in range(8)]


# -- the fit over synthetic ladders ----------------------------------------------------------------

def test_an_error_that_plateaus_gets_no_order_and_is_named_not_converging():
    # dt^5 down to 1e-8, then flat: the old fit over the coarse pairs read 5 from it
    errors = [1e-2 / 32 ** k for k in range(4)] + [1e-8 * f for f in (1.0, 0.98, 1.01, 0.99)]
    assert stall(HALVING, errors) == 4   # 1e-8 at dt = 0.00625, and no smaller below it
    lo, hi, stalls = fit_range(HALVING, errors)
    assert stalls == 4 and (lo, hi) == (0, 5)
    order = fit_order(RunSpec("rk4"), ladder(RunSpec("rk4"), HALVING, errors), FakeReference())
    assert order.contact is None and order.orientation is None
    text = order.reasons["contact"]
    assert text == order.not_converging["contact"]
    assert f"stops shrinking below dt = {HALVING[4]:.3g}" in text and text.endswith("not converging")
    assert order.to_dict()["not_converging"]["contact"] == text


def test_an_error_that_grows_at_the_finest_steps_is_not_converging():
    errors = [1e-3 / 16 ** k for k in range(5)] + [3e-8, 9e-8]
    lo, hi, stalls = fit_range(HALVING[:7], errors)
    assert stalls == 4
    order = fit_order(RunSpec("rk4"), ladder(RunSpec("rk4"), HALVING[:7], errors), FakeReference())
    assert order.contact is None and "not converging" in order.reasons["contact"]


def test_the_order_comes_from_the_finest_steps_whose_slopes_agree():
    # slope 2 for four coarse pairs (not yet asymptotic), then 4 for the three finest: the
    # longest agreeing run is the coarse one; the order is the fine one's
    errors = [1.0]
    for q in (2, 2, 2, 2, 4, 4, 4):
        errors.append(errors[-1] / 2 ** q)
    lo, hi, stalls = fit_range(HALVING, errors)
    assert (lo, hi, stalls) == (4, 8, None)
    order = fit_order(RunSpec("rk4"), ladder(RunSpec("rk4"), HALVING, errors), FakeReference(1e-30))
    assert order.contact == pytest.approx(4, abs=1e-9) and order.ranges["contact"] == (HALVING[4], HALVING[7])
    assert not order.not_converging and not order.notes


def test_errors_below_the_reference_floor_take_no_part():
    errors = [1e-4 / 16 ** k for k in range(8)]   # dt^4 all the way; the last three under the floor
    order = fit_order(RunSpec("rk4"), ladder(RunSpec("rk4"), HALVING, errors), FakeReference(1e-10))
    assert order.contact == pytest.approx(4, abs=1e-9)
    assert order.ranges["contact"][1] == HALVING[4]   # 1e-4/16^4 = 1.5e-9, the finest above 1e-10


def test_a_lone_agreeing_pair_is_fitted_with_a_note():
    errors = [1e-1, 1e-1 / 2 ** 5.2, 1e-1 / 2 ** 5.2 / 2 ** 4.6, 1e-1 / 2 ** 5.2 / 2 ** 4.6 / 2 ** 3.0]
    lo, hi, stalls = fit_range(HALVING[:4], errors)
    assert (lo, hi, stalls) == (2, 4, None)
    order = fit_order(RunSpec("rk4"), ladder(RunSpec("rk4"), HALVING[:4], errors), FakeReference())
    assert order.contact == pytest.approx(3.0) and "one pair of steps only" in order.notes["contact"]


def test_a_tolerance_ladder_whose_error_stops_shrinking_is_named():
    rtols = [1e-3, 1e-6, 1e-9, 1e-12]
    stalls = tolerance_stalls(RunSpec("dop853"), ladder(RunSpec("dop853"), rtols, [1e-3, 1e-6, 1e-6, 1.1e-6],
                                                       rtol=True), FakeReference())
    assert "stops shrinking below rtol = 1e-06" in stalls["contact"]
    assert not tolerance_stalls(RunSpec("dop853"), ladder(RunSpec("dop853"), rtols, [1e-3, 1e-6, 1e-9, 1e-12],
                                                          rtol=True), FakeReference())


# -- the reference's own error ------------------------------------------------------------------

@pytest.mark.parametrize("name", ["billiard", "bump", "liftoff", "cylinder", "ridge_jump"])
def test_the_reference_is_checked_to_1e_10_on_the_hybrid_examples(name):
    """Sliding, flying and landing: the reference's estimate is its difference from dop853 a
    decade looser and from dopri5 at its tolerance, and it is at most 1e-10. It is true: on the
    billiard, whose path is known in closed form, the reference's error is below it."""
    scene = Scene.load(EXAMPLES_DIR / f"{name}.json")
    t_end = scene.duration
    traj, ref = comparison._reference(scene, t_end, comparison.record_step(t_end))
    assert [(c.method, c.rtol) for c in ref.checks] == [("dop853", 1e-12), ("dopri5", 1e-13)]
    assert ref.checked, ref.problems
    assert 0 < ref.error_estimates["contact"] <= REFERENCE_ACCURACY
    assert ref.error_estimates["contact"] == max(c.difference["contact"] for c in ref.checks)
    if name == "billiard":  # skids at mu g, grips at 2 v0 / (7 mu g), then rolls at 5/7 v0
        import numpy as np

        s, mu, g = scene.start, 0.2, scene.gravity
        t_grip = 2 * s.vx / (7 * mu * g)
        t = traj.t
        x = np.where(t < t_grip, s.x + s.vx * t - mu * g * t ** 2 / 2,
                     s.x + s.vx * t_grip - mu * g * t_grip ** 2 / 2 + 5 / 7 * s.vx * (t - t_grip))
        true_error = float(np.hypot(traj.contact[:, 0] - x, traj.contact[:, 1] - s.y).max())
        assert true_error <= ref.error_estimates["contact"]


@pytest.fixture(scope="module")
def poor_reference():
    """A reference that claims more than it has: dop853 at rtol 1e-8 whose checks are set to
    find nothing (as a reference whose checks share its error would): compare cannot see it
    through the estimate, but the runs' errors stop shrinking at the reference's own error."""
    original = comparison._reference

    def claims_too_much(*args, **kwargs):
        rtol = comparison.REFERENCE_RTOL
        comparison.REFERENCE_RTOL = 1e-8
        try:
            traj, ref = original(*args, **kwargs)
        finally:
            comparison.REFERENCE_RTOL = rtol
        tiny = {key: 1e-16 for key in ref.error_estimates}
        checks = tuple(dataclasses.replace(check, difference=tiny) for check in ref.checks)
        return traj, dataclasses.replace(ref, error_estimates=tiny, error_estimate=1e-16, checks=checks)

    comparison._reference = claims_too_much
    try:
        scene = make_scene("0.2*sin(3*x)*sin(2*y)", x=0.1, y=0.2, vx=1.0, vy=0.5, duration=1.5)
        return compare(scene, runs="rk4,lawson5", quick=True)
    finally:
        comparison._reference = original


def test_a_real_ladder_that_stops_converging_is_named(poor_reference, tmp_path):
    cmp = poor_reference
    stalled = {(spec.method, key) for spec, key, _ in cmp.not_converging}
    assert ("lawson5", "contact") in stalled, cmp.not_converging
    lawson5 = next(o for o in cmp.orders if o.spec.method == "lawson5")
    assert lawson5.contact is None and "stops shrinking below dt =" in lawson5.reasons["contact"]
    assert "not converging" in cmp.summary() and "lawson5" in cmp.summary()
    comparison_report.save(cmp, tmp_path)
    doc = json.loads((tmp_path / "compare.json").read_text())
    assert any(e["method"] == "lawson5" and e["error"] == "contact" and "not converging" in e["text"]
               for e in doc["not_converging"])
    assert "not converging" in (tmp_path / "compare.md").read_text()


@pytest.fixture(scope="module")
def unchecked():
    """A reference whose checks differ by more than 1e-10 (dop853 at rtol 1e-7): compare says so."""
    rtol = comparison.REFERENCE_RTOL
    comparison.REFERENCE_RTOL = 1e-7
    try:
        scene = make_scene("0.2*sin(3*x)*sin(2*y)", x=0.1, y=0.2, vx=1.0, vy=0.5, duration=1.5)
        return compare(scene, runs="rk4,dopri5", quick=True)
    finally:
        comparison.REFERENCE_RTOL = rtol


def test_an_unchecked_reference_is_said_and_no_error_below_it_is_quoted(unchecked, tmp_path):
    cmp = unchecked
    ref = cmp.reference
    assert not ref.checked and ref.error_estimates["contact"] > REFERENCE_ACCURACY
    floor = ref.floor("contact")
    worst = max(ref.floor("contact"), ref.floor("orientation"))
    assert "not checked to 1e-10" in cmp.summary() and f"below {worst:.1e} are below the reference's accuracy" \
        in cmp.summary()
    assert cmp.best(1e-10) is None   # a target under the floor is never claimed reached
    comparison_report.save(cmp, tmp_path)
    doc = json.loads((tmp_path / "compare.json").read_text())
    assert doc["reference"]["checked"] is False and doc["reference"]["problems"]
    assert doc["reference"]["floors"]["contact"] == pytest.approx(floor)
    below = [run for run in doc["runs"] if "contact" in run["below_reference_accuracy"]]
    assert below, "the finest runs are below the floor"
    for run in doc["runs"]:
        value = run["error"]["contact"]
        assert (value is None) == ("contact" in run["below_reference_accuracy"])
        assert value is None or value >= floor
    text = (tmp_path / "compare.md").read_text()
    assert "The reference is not checked to 1e-10" in text and "below the reference's accuracy" in text
    for run in cmp.runs:   # no number under the floor in the report
        if "contact" in run.below:
            assert f"{run.error['contact']:.2e}" not in text
    assert (tmp_path / "compare.png").stat().st_size > 0


def test_a_checked_reference_says_so(tmp_path):
    scene = make_scene("0.2*sin(3*x)*sin(2*y)", x=0.1, y=0.2, vx=1.0, vy=0.5, duration=0.5)
    cmp = compare(scene, runs="rk4", quick=True)
    assert cmp.reference.checked and "not checked" not in cmp.summary()
    assert "The reference is checked" in comparison_report.markdown(cmp)
    assert math.isfinite(cmp.reference.error_estimate)


def test_a_ball_that_slips_and_grips_again_is_judged_by_what_the_reference_resolves():
    """Sliding on a curved surface, slipping and gripping in turn (the bowl with friction 0.1, a
    start at 3 m/s and spin): today the reference differs from its checks by about 2e-8 m there
    (slip and grip are located alike by both dop853 runs but not by dopri5). Whatever it
    resolves, compare says whether it is checked and quotes no error below its floor."""
    doc = json.loads((EXAMPLES_DIR / "bowl.json").read_text())
    doc.update(version=3, contact={"friction": 0.1, "restitution": 0.0, "after_liftoff": "fly"})
    doc["start"].update(vx=3.0, spin=5.0)
    cmp = compare(Scene.from_dict(doc), runs="rk4,dopri5", t_end=3.0, quick=True)
    ref = cmp.reference
    assert ref.checked == (ref.error_estimates["contact"] <= REFERENCE_ACCURACY
                           and ref.error_estimates["orientation"] <= REFERENCE_ACCURACY)
    assert ("not checked to 1e-10" in cmp.summary()) == (not ref.checked)
    for run in cmp.runs:
        data = run.to_dict()
        for key in ("contact", "orientation"):
            assert data["error"][key] is None or data["error"][key] >= ref.floor(key)
    for target in (1e-6, 1e-10):
        best = cmp.best(target)
        assert best is None or target >= max(ref.floor("contact"), ref.floor("orientation"))
