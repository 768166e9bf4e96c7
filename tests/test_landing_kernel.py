"""The compiled landing search (``kernel.landing.land``, through ``Surface.land``) answers every
flight in vacuum as flight.py's own search does, to round-off, and leaves to flight.py the flights
its first foot search cannot answer. The answers themselves are held against independent
computations elsewhere (tests/test_flight.py, test_flight_honest.py, test_flight_parts.py): here
the two searches are held against each other, on the examples' flights, a 3-D throw that bounces
and a ball that flies to the end; and a flight's compiled rows against its exact state and the
full foot search."""

import dataclasses
import json

import numpy as np
import pytest

from rollball import Scene, Simulation
from rollball.examples import EXAMPLES_DIR
from rollball.flight import REFER, Flight
from rollball.mode_machine import SEARCH, ModeMachine

LIFTOFF = json.loads((EXAMPLES_DIR / "liftoff.json").read_text())


def thrown(landscape, duration=1.5, restitution=0.0, **start):
    data = json.loads(json.dumps(LIFTOFF))
    data["landscape"], data["duration"] = landscape, duration
    data["start"].update(start)
    data["contact"]["restitution"] = restitution
    return Scene.from_dict(data)


def watch(scene, monkeypatch, name):
    """Run the scene with ``Flight.<name>`` watched: each call's flight, its arguments, the
    surface's hints and tips before it, and what it returned."""
    seen, method = [], getattr(Flight, name)

    def watched(flight, *args):
        before = list(flight.surface.hints), list(flight.surface.tips)
        out = method(flight, *args)
        seen.append((flight, args, before, out))
        return out

    with monkeypatch.context() as m:
        m.setattr(Flight, name, watched)
        # (a flight at a time: in vacuum the kernel's bounces take a run's flights without these calls)
        m.setattr(ModeMachine, "fly", lambda self: self._fly(SEARCH))
        run = Simulation(scene)
        run.judge_energy = False
        run.advance()
    return seen


def flights_of(scene, monkeypatch):
    """Each flight of the scene's run, as (flight, t_end, the surface's hints and tips then)."""
    return [(flight, t_end, hints, tips) for flight, (t_end,), (hints, tips), _ in watch(scene, monkeypatch, "landing")]


def both(flight, t_end, hints, tips):
    """The kernel's answer and flight.py's own, from the same surface hints and tips."""
    surface = flight.surface
    surface.hints, surface.tips = list(hints), list(tips)
    compiled = surface.land(flight.start, gravity=flight.gravity, radius=flight.radius, t_end=t_end)
    flight.compiled = False
    try:
        own = flight.landing(t_end)
    finally:
        del flight.compiled
    return compiled, own


SCENES = {
    "liftoff": Scene.load(EXAMPLES_DIR / "liftoff.json"),
    "cylinder": Scene.load(EXAMPLES_DIR / "cylinder.json"),
    "ridge_jump": Scene.load(EXAMPLES_DIR / "ridge_jump.json"),
    # off a bump onto a tilted valley, in 3-D, bouncing (e = 0.5) ever lower: 12 landings
    "valley": thrown("0.5*exp(-x^2-y^2) + 0.2*(y-0.3*x)^2 - 0.1*x", x=-2.5, y=0.2, vx=5.0, vy=0.8, duration=1.4,
                     restitution=0.5),
    # off the top of a hill too steep to come back to: it flies to the end
    "away": thrown("-0.5*x^2", x=0.0, y=0.0, vx=4.0, duration=0.6),
}


@pytest.mark.parametrize("name", sorted(SCENES))
def test_the_kernel_lands_each_flight_as_flight_py_does(name, monkeypatch):
    flights, owns = flights_of(SCENES[name], monkeypatch), []
    assert flights
    for flight, t_end, hints, tips in flights:
        compiled, own = both(flight, t_end, hints, tips)
        owns.append(own)
        assert compiled is not REFER   # (these flights need nothing beyond the first foot search)
        if own is None:
            assert compiled is None
            continue
        (t, foot), (t_own, foot_own) = compiled, own
        assert t == pytest.approx(t_own, rel=1e-14, abs=1e-14)
        assert [foot.x, foot.y] == pytest.approx([foot_own.x, foot_own.y], rel=1e-12, abs=1e-12)
        assert foot.distance == pytest.approx(foot_own.distance, rel=1e-12)
        assert foot.normal == pytest.approx(foot_own.normal, rel=1e-12, abs=1e-12)
    assert (owns == [None]) == (name == "away")   # (one flight to the end there; every other flight lands)


def test_a_flight_over_a_spike_narrower_than_the_grid_is_left_to_flight_py(monkeypatch):
    # the spike 0.5 mm wide in liftoff's path: the track under the path finds it, so the kernel refers
    # the flight, and flight.py's search (with the spike's point as a hint) lands on it
    spike = thrown("0.5*exp(-x^2) + 0.4*exp(-((x-1.1)/0.0005)^2)", duration=1.0)
    flight, t_end, hints, tips = flights_of(spike, monkeypatch)[0]
    surface = flight.surface
    surface.hints, surface.tips = list(hints), list(tips)
    assert surface.land(flight.start, gravity=flight.gravity, radius=flight.radius, t_end=t_end) is REFER
    t, foot = flight.landing(t_end)
    assert abs(foot.x - 1.1) < 0.1 and len(surface.hints) == 1


def test_a_flight_through_air_is_searched_by_flight_py(monkeypatch):
    air = dataclasses.replace(SCENES["liftoff"], air=dataclasses.replace(SCENES["liftoff"].air, density=1.2,
                                                                         drag_coefficient=0.47))
    flights = flights_of(air, monkeypatch)
    assert flights and not any(flight.compiled for flight, *_ in flights)


# -- a flight's rows (``kernel.flight_rows``, through ``Surface.flight_rows``) -----------------------

def check_rows(flight, times, rows):
    """A flight's rows against scipy's rotation vector exponential, the parabola, the energy's
    formula and the full foot search of (some of) the rows' centres (Surface.foot)."""
    from scipy.spatial.transform import Rotation

    from rollball.flight import tangential_slip
    from rollball.kernel.interface import ROW_SLICES

    s, m, r, g = flight.start, flight.mass, flight.radius, flight.gravity
    tau = times - s.t
    center = s.center + np.outer(tau, s.velocity) + np.outer(0.5 * tau * tau, [0.0, 0.0, -g])
    velocity = s.velocity + np.outer(tau, [0.0, 0.0, -g])
    column = {name: rows[:, part] for name, part in ROW_SLICES.items()}
    assert np.array_equal(column["t"][:, 0], times)
    assert np.allclose(column["center"], center, rtol=0, atol=1e-13)
    assert np.allclose(column["velocity"], velocity, rtol=0, atol=1e-13)
    assert np.array_equal(column["omega"], np.broadcast_to(s.omega, (len(times), 3)))
    turned = Rotation.from_rotvec(np.outer(tau, s.omega)).as_matrix() @ s.R
    assert np.allclose(column["R"], turned.reshape(-1, 9), rtol=0, atol=1e-14)
    energy = 0.5 * m * (velocity ** 2).sum(axis=1) + 0.2 * m * r * r * (s.omega ** 2).sum() + m * g * center[:, 2]
    assert np.allclose(column["energy"][:, 0], energy, rtol=1e-13, atol=0)
    assert not column["normal_force"].any()
    for i in range(0, len(times), max(len(times) // 25, 1)):
        foot = flight.surface.foot(rows[i, ROW_SLICES["center"]])
        assert rows[i, ROW_SLICES["contact"]] == pytest.approx([foot.x, foot.y], abs=1e-12)
        slip = tangential_slip(rows[i, ROW_SLICES["velocity"]], s.omega, foot.normal, r)[0]
        assert column["slip_speed"][i, 0] == pytest.approx(slip, rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("name", ["liftoff", "valley", "away"])
def test_a_flights_rows_are_its_exact_state_and_its_nearest_surface_point(name, monkeypatch):
    calls = watch(SCENES[name], monkeypatch, "rows")
    seen = [(flight, np.asarray(args[0], dtype=float), rows) for flight, args, _, rows in calls]
    assert sum(len(times) for _, times, _ in seen) > 100
    for flight, times, rows in seen:
        check_rows(flight, times, rows)


def test_a_long_flights_rows_are_made_in_arrays_of_their_own(monkeypatch):
    """A flight of more than KEPT_ROWS rows (liftoff at dt 1e-4: 4 453) is made through arrays of
    its own, which the surface does not keep; its rows are as exact."""
    from rollball.flight import KEPT_ROWS

    scene = dataclasses.replace(SCENES["liftoff"], integrator=dataclasses.replace(SCENES["liftoff"].integrator,
                                                                                 dt=1e-4))
    calls = watch(scene, monkeypatch, "rows")
    flight, args, _, rows = max(calls, key=lambda call: len(call[3]))
    assert len(rows) > KEPT_ROWS
    check_rows(flight, np.asarray(args[0], dtype=float), rows)
    kept = flight.surface._rows_call   # (None: nothing kept; else a short flight's call)
    assert kept is None or len(kept.kept["times"]) <= KEPT_ROWS
