"""What the landing search computes per look (rollball/flight.py): the path time only where a
look is not certified by the chord test alone, the centre's motion in numbers equal to the
closed form's, the cross products equal to numpy's."""

import numpy as np
import pytest

from rollball.flight import FreeState, Flight, Surface
from rollball.geometry import cross
from rollball.landscape import landscape_for

G, R, M = 9.81, 0.1, 1.3


def test_cross_is_numpys_bit_for_bit():
    rng = np.random.default_rng(7)
    for shape in [(3,), (5, 3), (400, 3)]:
        a = rng.normal(size=shape) * 10.0 ** rng.uniform(-8, 8, size=shape)
        b = rng.normal(size=shape)
        assert np.array_equal(cross(a, b), np.cross(a, b))
        one = np.broadcast_to(rng.normal(size=3), shape)   # (one vector against many, as the rows take it)
        assert np.array_equal(cross(one, a), np.cross(one, a))


def test_the_centres_at_once_are_the_closed_form_at_each_time():
    start = FreeState(0.25, np.array([0.3, -0.7, 1.9]), np.array([1.7, 0.4, 2.3]), np.zeros(3), np.eye(3))
    f = Flight(Surface(landscape_for("0*x")), start, radius=R, mass=M, gravity=G)
    times = 0.25 + np.linspace(0.0, 0.9, 1001)
    centers, velocities = f.centers(times)
    assert centers.shape == velocities.shape == (1001, 3)
    for i in (0, 1, 500, 1000):
        tau = float(times[i]) - 0.25
        exact = [c + v * tau + (0.5 * g) * tau * tau for c, v, g in zip(start.center, start.velocity, (0.0, 0.0, -G))]
        assert centers[i].tolist() == exact
        assert velocities[i].tolist() == [v + g * tau for v, g in zip(start.velocity, (0.0, 0.0, -G))]
        one = f.centers(np.array([times[i]]))
        assert one[0][0].tolist() == exact and one[1][0].tolist() == velocities[i].tolist()


def test_a_look_certified_by_the_chord_needs_no_path_time(monkeypatch):
    """The path time (proof (1) of ``_search``) is computed at a batch's first look, and at a later
    look of the batch only where the chord test (2) fails there (which ends the batch): at most
    twice per batch of looks. The flight of examples/liftoff.json: off the flank of a crest, its gap
    growing for most of the way (the looks batched)."""
    start = FreeState(0.0, np.array([-0.4195396470476961, 0.0, 0.5250160196118248]),
                      np.array([4.141038622526674, 0.0, 1.3818813739841604]), np.zeros(3), np.eye(3))
    f = Flight(Surface(landscape_for("0.5*exp(-x^2)")), start, radius=R, mass=1.0, gravity=G)
    counts = {"path_time": 0, "gaps": 0}
    for name in counts:
        method = getattr(Flight, name)

        def counted(self, *args, _method=method, _name=name, **kwargs):
            counts[_name] += 1
            return _method(self, *args, **kwargs)
        monkeypatch.setattr(Flight, name, counted)
    found = f._search(1.0)
    assert found is not None and found[0] == pytest.approx(0.4454, abs=1e-4) and counts["gaps"] >= 10
    assert counts["path_time"] <= 2 * counts["gaps"]
