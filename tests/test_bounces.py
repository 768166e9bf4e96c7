"""A flight in vacuum taken by the kernel flight after flight (kernel/bounces.py, through
``Surface.bounces`` and ``ModeMachine.fly``): the landing times of a ball bouncing on a plane
against their closed form, across more landings than one call makes; and whole runs against the
same runs taken a flight at a time by the mode machine's own ``_fly`` (each flight's landing
searched by the kernel's ``land`` or flight.py, its impact and rows made one by one): settling
into rolling and into sliding, a stop after a number of landings, flights whose rows do not fit
the kernel's buffer, a flight the kernel's search leaves to flight.py, and adaptive runs."""

import json
import math

import numpy as np
import pytest

from rollball import Scene, Simulation
from rollball.examples import EXAMPLES_DIR
from rollball.flight import FreeState, Surface, rest_speed
from rollball.kernel import interface
from rollball.landscape import landscape_for
from rollball.mode_machine import SEARCH, ModeMachine
from rollball.modes import FLYING
from rollball.scene import Contact, Start

G, R, M = 9.81, 0.1, 1.3


def test_a_ball_dropped_on_a_plane_lands_when_the_closed_form_says_across_calls():
    """Dropped from h above contact onto z = 0 with restitution e: landing k (from 1) at
    t_k = t_1 + 2 v_1 (e + ... + e^(k-1)) / g with t_1 = sqrt(2 h / g), v_1 = g t_1; the rebound
    e^k v_1 flies while it exceeds the rest speed, and each landing loses (1 - e^2) ½ m v_k²."""
    e, h = 0.9, 0.5
    surface = Surface(landscape_for("0*x"))
    state = FreeState(0.0, np.array([0.2, -0.1, R + h]), np.zeros(3), np.zeros(3), np.eye(3))
    landings, rows, dissipated, calls = [], [], 0.0, 0
    while True:
        done = surface.bounces(state, gravity=G, radius=R, mass=M, restitution=e, friction=math.inf,
                               rest=rest_speed(R, G), t_end=100.0, every=1, step=1e-2, enough=-1,
                               dissipated=dissipated)
        calls += 1
        landings.extend(done.landings)
        rows.append(done.rows)
        dissipated, state = done.dissipated, done.state
        if done.status != interface.BOUNCES_CONTINUE:
            break
    assert done.status == interface.BOUNCES_SETTLED and done.sticking and calls == 2
    landings, rows = np.array(landings), np.concatenate(rows)
    v1 = math.sqrt(2 * G * h)
    speeds = v1 * e ** np.arange(len(landings))
    count = int(math.floor(math.log(rest_speed(R, G) / v1) / math.log(e))) + 1   # the first rebound too slow
    assert len(landings) == count > interface.BOUNCES_CHAIN
    times = v1 / G + np.concatenate([[0.0], np.cumsum(2 * speeds[1:] / G)])   # (rebound k: speeds[k])
    assert np.abs(landings[:, 0] - times).max() < 1e-12
    assert np.abs(landings[:, 1:3] - [0.2, -0.1]).max() == 0.0
    assert np.abs(landings[:, 3] - speeds).max() < 1e-12
    lost = 0.5 * M * speeds ** 2 * (1 - e * e)
    lost[-1] = 0.5 * M * speeds[-1] ** 2   # (the last rebound settles: its energy is lost too)
    assert np.abs(landings[:, 4] - lost).max() < 1e-12 and dissipated == pytest.approx(lost.sum(), rel=1e-13)
    # rows every 10 ms between the landings and one at each rebound, on the parabolas
    t = rows[:, interface.ROW_T]
    assert np.all(np.diff(t) > 0) and len(rows) == math.floor(times[-1] * 1e2) + count - 1
    k = np.searchsorted(times, t, side="right")   # the landings before each row
    start = np.where(k > 0, times[np.maximum(k - 1, 0)], 0.0)
    up = np.where(k > 0, speeds[np.maximum(k - 1, 0)] * e, 0.0)
    height = np.where(k > 0, R + up * (t - start) - 0.5 * G * (t - start) ** 2, R + h - 0.5 * G * t * t)
    assert np.abs(rows[:, interface.ROW_CENTER + 2] - height).max() < 1e-12
    assert np.all(rows[:, interface.ROW_CONTACT: interface.ROW_CONTACT + 2] == [0.2, -0.1])


LIFTOFF = json.loads((EXAMPLES_DIR / "liftoff.json").read_text())
RIDGE = json.loads((EXAMPLES_DIR / "ridge_jump.json").read_text())


def scene(base, **changes):
    data = json.loads(json.dumps(base))
    for key, value in changes.items():
        part, _, name = key.partition(".")
        if name:
            data[part][name] = value
        else:
            data[part] = value
    return Scene.from_dict(data)


def run(scene, stop_after=None, **options):
    simulation = Simulation(scene, stop_after=stop_after, **options)
    simulation.advance()
    return simulation


def one_flight_at_a_time(monkeypatch):
    monkeypatch.setattr(ModeMachine, "fly", lambda self: self._fly(SEARCH))


# how the kernel's calls end in each case (at least these)
ENDS = {"ridge_jump": {interface.BOUNCES_SETTLED}, "step_down": {interface.BOUNCES_SETTLED},
        "stop_after": {interface.BOUNCES_ENOUGH}, "fine_rows": {interface.BOUNCES_ROOM},
        "spike": {interface.BOUNCES_REFER}, "adaptive": {interface.BOUNCES_SETTLED}}
CASES = {
    # 8 bounces, then rolling
    "ridge_jump": (scene(RIDGE), {}),
    # 3-D, sliding impacts and sliding after them (the step-down of the issue: slips, flies, bounces)
    "step_down": (Scene(landscape="-0.2*(1 + tanh(5*x)) + 0.01*y", start=Start(x=-0.6, vx=2.0, vy=0.1, spin=2.0),
                        contact=Contact(friction=0.3, restitution=0.6), duration=2.0), {}),
    # the second landing ends the run
    "stop_after": (scene(RIDGE), {"stop_after": 3}),
    # a flight's rows at 2e-5 s: more than the kernel's buffer holds (flight.py records them)
    "fine_rows": (scene(RIDGE), {"dt": 2e-5}),
    # the spike the kernel's track finds: flight.py's search takes that flight
    "spike": (scene(LIFTOFF, landscape="0.5*exp(-x^2) + 0.4*exp(-((x-1.1)/0.0005)^2)"), {}),
    # an adaptive run: rows at its own steps' times
    "adaptive": (scene(RIDGE, **{"integrator": {"method": "dopri5", "munthe_kaas": True, "dt": 0.001,
                                                "rtol": 1e-9, "atol": 1e-12}}), {"record_dt": 0.01}),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_kernels_flights_are_those_taken_one_at_a_time(name, monkeypatch):
    scene_, options = CASES[name]
    ends, bounces = set(), Surface.bounces

    def recorded(self, *args, **kwargs):
        done = bounces(self, *args, **kwargs)
        ends.add(done.status)
        return done

    monkeypatch.setattr(Surface, "bounces", recorded)
    chained = run(scene_, **options)
    assert ends >= ENDS[name]
    one_flight_at_a_time(monkeypatch)
    alone = run(scene_, **options)
    a, b = chained.trajectory(), alone.trajectory()
    assert a.status == b.status and len(a) == len(b)
    assert len(a.transitions) == len(b.transitions)
    # the same landings to round-off (to the last bit until the kernel build of 2 December, which
    # added the sweeps' flights: since, the adaptive ridge_jump's third landing's x is one unit in
    # the last place apart, and the landings after it move by as little); the rows' R (Rodrigues' formula written twice:
    # the kernel's and geometry.rotation) to round-off (2e-15 measured)
    assert [c.kind for c in a.transitions] == [d.kind for d in b.transitions]
    np.testing.assert_allclose([(c.time, c.x, c.y) for c in a.transitions],
                               [(d.time, d.x, d.y) for d in b.transitions], rtol=1e-12, atol=1e-300)
    # (the adaptive run's step-size control carries that round-off on: 6.4e-12 of 36 measured)
    assert np.abs(a.data - b.data).max() < 1e-12 * max(1.0, np.abs(b.data).max())
    landings = sum(1 for c in a.transitions if c.kind == "landing")
    assert landings >= {"stop_after": 1, "spike": 1}.get(name, 2)


@pytest.mark.parametrize("name", ["liftoff", "ridge_jump", "cylinder"])
def test_a_run_that_flies_writes_its_rows_where_it_made_room_for_them(name, monkeypatch):
    """A run whose contact changes mode makes room for its grid's rows and CHANGE_ROWS more (a
    change's row, a landing's): the examples that fly, and land up to nine times, write every row
    into that buffer without growing it (a copy of every row so far: 0.2 ms of a 4 ms liftoff
    run), and their rows are the grid's times and the changes'."""
    from rollball import simulation

    grown = []
    original = ModeMachine._grow
    monkeypatch.setattr(ModeMachine, "_grow", lambda self, used, need: grown.append(need) or original(self, used, need))
    scene = Scene.load(EXAMPLES_DIR / f"{name}.json")
    run = Simulation(scene)
    run.judge_energy = False
    run.advance()
    traj = run.trajectory()
    assert run.status.value == "ok" and traj.landings >= 1 and not grown
    grid = run.n_steps // run.record_every + 1
    assert grid < len(traj) <= grid + simulation.CHANGE_ROWS
    assert np.all(np.diff(traj.t) > 0)


@pytest.mark.parametrize("scene", [
    Scene.load(EXAMPLES_DIR / "ridge_jump.json"),   # nine landings, then it rolls
    # off the top of a hill too steep to come back to, in 3-D: it flies to the end
    Scene.from_dict({**json.loads((EXAMPLES_DIR / "liftoff.json").read_text()), "landscape": "-0.5*x^2 - 0.1*y",
                     "start": {"x": -0.2, "y": 0.1, "vx": 4.0, "vy": 0.5}, "duration": 0.8}),
], ids=["ridge_jump", "away"])
def test_a_runs_flights_without_their_rows_contacts_are_the_same_run_the_last_row_whole(scene):
    """A sweep's runs (``Simulation.flight_contacts`` False) leave a flight's rows without their
    contact point and slip speed (NaN), but the run's last row: every other number the same."""
    runs = []
    for contacts in (True, False):
        run = Simulation(scene)
        run.judge_energy, run.flight_contacts = False, contacts
        run.advance()
        runs.append(run.trajectory())
    full, lean = runs
    assert full.transitions == lean.transitions and full.status == lean.status
    flying = np.flatnonzero(full.modes == FLYING)
    flying = flying[flying < len(full) - 1]
    assert len(flying) > 100
    blank = [*range(interface.ROW_SLICES["contact"].start, interface.ROW_SLICES["contact"].stop), interface.ROW_SLIP]
    assert np.isnan(lean.data[np.ix_(flying, blank)]).all() and np.isfinite(full.data[np.ix_(flying, blank)]).all()
    kept = np.ones(full.data.shape, dtype=bool)
    kept[np.ix_(flying, blank)] = False
    np.testing.assert_array_equal(lean.data[kept], full.data[kept])
    np.testing.assert_array_equal(lean.data[-1], full.data[-1])
