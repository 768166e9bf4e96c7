"""The landscape's local minima over the view square and the basin of a point (rollball.basins):
minima of landscapes whose minima are known exactly, numbered by height, and the steepest descent
that assigns a point to one."""

import math

import numpy as np
import pytest

from rollball import Scene
from rollball.basins import Basins
from rollball.landscape import landscape_for


def basins(text, lo=-3.0, hi=3.0, parameters=(), values=()):
    return Basins(landscape_for(text, parameters), values, lo, hi)


def test_a_double_well_has_its_two_minima_at_the_exact_places_numbered_by_x_at_equal_heights():
    b = basins("(x**2 - 1)**2 + y**2")
    assert [(m.number, m.x, m.y, m.f) for m in b.minima] == [(1, -1.0, 0.0, 0.0), (2, 1.0, 0.0, 0.0)]


def test_minima_are_numbered_lowest_first():
    # f = (x² − 1)² + y² + a x: the minima are the roots of 4x³ − 4x + a = 0 with 3x² > 1
    a = 0.3
    roots = sorted(r.real for r in np.roots([4.0, 0.0, -4.0, a]) if abs(r.imag) < 1e-12 and 3 * r.real ** 2 > 1)
    b = basins("(x**2 - 1)**2 + y**2 + a*x", parameters=("a",), values=(a,))
    assert [m.number for m in b.minima] == [1, 2]
    assert b.minima[0].x == pytest.approx(roots[0], abs=1e-14) and b.minima[1].x == pytest.approx(roots[1], abs=1e-14)
    assert b.minima[0].f < b.minima[1].f and b.minima[0].y == 0.0


def test_the_minima_of_sines_are_at_odd_multiples_of_half_pi():
    b = basins("0.5*sin(x)*cos(y)", -4.0, 4.0)
    assert [(m.x, m.y, m.f) for m in b.minima] == [
        (-math.pi / 2, 0.0, -0.5), (math.pi / 2, -math.pi, -0.5), (math.pi / 2, math.pi, -0.5)]


@pytest.mark.parametrize("text", ["x", "x**4 + y**4", "-(x**2 + y**2)", "x**2 - y**2", "0*x"])
def test_no_strict_minimum_means_none(text):
    assert basins(text).minima == ()


def test_a_minimum_outside_the_view_square_is_not_listed():
    assert basins("(x - 2)**2 + (y + 5)**2").minima == ()
    assert [(m.x, m.y) for m in basins("(x - 2)**2 + (y + 5)**2", -6.0, 6.0).minima] == [(2.0, -5.0)]


def test_a_scenes_minima_are_of_its_view_square_and_its_parameters():
    scene = Scene.from_dict({"format": "rollball-scene", "version": 3, "landscape": "(x - c)**2 + y**2",
                             "parameters": {"c": 1.5}, "view": {"min": -2.0, "max": 2.0, "step": 0.1}})
    b = Basins.of(scene)
    assert [(m.x, m.y) for m in b.minima] == [(1.5, 0.0)] and (b.lo, b.hi) == (-2.0, 2.0)


def test_a_point_descends_into_the_well_on_its_side():
    b = basins("(x**2 - 1)**2 + y**2")
    x = np.array([-2.9, -1.0, -0.4, -1e-3, 1e-3, 0.7, 2.5])
    assert b.basin(x, np.full_like(x, 0.8)).tolist() == [1, 1, 1, 1, 2, 2, 2]


def test_the_descent_follows_the_slope_not_the_distance():
    """On f = (x² − 1)² + x/2 + 10 (y − x)² a point falls first into the valley y = x: from
    (−0.5, 0.75) it ends in the lower well (x < 0), though the other is nearer, as the steepest
    descent integrated by scipy (to 1e-12) says."""
    from scipy.integrate import solve_ivp

    b = basins("(x**2 - 1)**2 + x/2 + 10*(y - x)**2")
    roots = sorted(r.real for r in np.roots([4.0, 0.0, -4.0, 0.5]) if abs(r.imag) < 1e-12 and 3 * r.real ** 2 > 1)
    np.testing.assert_allclose([(m.x, m.y) for m in b.minima], [(r, r) for r in roots], rtol=0, atol=1e-14)
    start = (-0.5, 0.75)
    flow = solve_ivp(lambda t, p: [-(4 * p[0] * (p[0] ** 2 - 1) + 0.5 - 20 * (p[1] - p[0])), -20 * (p[1] - p[0])],
                     (0.0, 60.0), start, rtol=1e-12, atol=1e-12)
    assert flow.y[0, -1] == pytest.approx(roots[0], abs=1e-6)
    assert min(b.minima, key=lambda m: math.dist(start, (m.x, m.y))).number == 2
    assert b.basin(*start) == 1.0


def test_on_a_ridge_or_outside_or_undefined_there_is_no_basin():
    b = basins("(x**2 - 1)**2 + y**2")
    assert b.basin(0.0, 0.5) == 0.0            # on the ridge x = 0: the descent ends on the saddle
    assert b.basin(3.5, 0.0) == 0.0            # outside the square
    assert math.isnan(b.basin(np.nan, 0.0))    # no resting point: no basin
    slope = basins("x**3 - 3*x + y**2")   # a minimum at (1, 0); left of x = −1 it falls away out of the square
    assert [(m.x, m.y, m.f) for m in slope.minima] == [(1.0, 0.0, -2.0)]
    assert slope.basin(-1.5, 0.5) == 0.0 and slope.basin(0.0, 1.0) == 1.0


def test_basin_keeps_the_shape_of_its_points():
    b = basins("(x**2 - 1)**2 + y**2")
    x, y = np.meshgrid(np.linspace(-2, 2, 4), np.linspace(-1, 1, 3))
    result = b.basin(x, y)
    assert result.shape == (3, 4) and (result[:, :2] == 1).all() and (result[:, 2:] == 2).all()


def test_a_bad_square_is_refused():
    with pytest.raises(ValueError, match="finite lo < hi"):
        Basins(landscape_for("x**2"), (), 1.0, -1.0)
