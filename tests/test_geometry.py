"""Normals and fit ratios on grids, against curvatures known in closed form."""

import math

import numpy as np
import pytest

from rollball import Scene, simulate
from rollball.examples import scene_path
from rollball.geometry import fit_ratio, reachable_height, rotation, unit_normal
from rollball.landscape import Landscape

xs, ys = np.meshgrid(np.linspace(-0.5, 0.5, 7), np.linspace(-0.4, 0.6, 5), indexing="ij")


def test_sphere_valley_has_curvature_one_over_its_radius_everywhere():
    # the lower half of a sphere of radius 2 bends up by 1/2 in every direction
    d = Landscape("2 - sqrt(4 - x^2 - y^2)").evaluate(xs, ys)
    # umbilic everywhere: the discriminant's square root keeps half the digits
    assert fit_ratio(d, 0.3) == pytest.approx(np.full(xs.shape, 0.15), rel=1e-7)


def test_parabola_valley_curvature_and_the_ridge_direction():
    k = 3.0
    d = Landscape("1.5*x^2").evaluate(xs, ys)
    expected = 0.1 * k / (1 + (k * xs) ** 2) ** 1.5
    assert fit_ratio(d, 0.1) == pytest.approx(expected, rel=1e-12)
    # upside down: the only bending is away from the ball, the other direction is straight
    assert fit_ratio(Landscape("-1.5*x^2").evaluate(xs, ys), 0.1) == pytest.approx(np.zeros(xs.shape), abs=1e-15)


def test_saddle_fits_by_its_positive_curvature():
    d = Landscape("(x^2 - y^2)/2").evaluate(0.0, 0.0)
    assert fit_ratio(d, 0.5) == pytest.approx(0.5)


def test_unit_normal_is_unit_and_perpendicular_to_the_surface():
    d = Landscape("0.5*sin(x)*cos(y) + x*y").evaluate(xs, ys)
    N = unit_normal(d)
    assert N.shape == (3,) + xs.shape
    assert np.linalg.norm(N, axis=0) == pytest.approx(np.ones(xs.shape), rel=1e-15)
    # tangents (1, 0, f_x) and (0, 1, f_y)
    assert N[0] + N[2] * d[1] == pytest.approx(np.zeros(xs.shape), abs=1e-15)
    assert N[1] + N[2] * d[2] == pytest.approx(np.zeros(xs.shape), abs=1e-15)


def test_outside_the_domain_is_nan():
    d = Landscape("log(x)").evaluate(np.array([-1.0, 1.0]), np.array([0.0, 0.0]))
    ratio = fit_ratio(d, 0.1)
    assert np.isnan(ratio[0]) and np.isfinite(ratio[1])


@pytest.mark.parametrize("name", ["incline", "flat", "liftoff"])
def test_reachable_height_is_the_start_energy_over_m_g(name):
    scene = Scene.load(scene_path(name))   # moving starts, flat one with spin
    landscape = Landscape(scene.landscape)
    d = landscape.evaluate(scene.start.x, scene.start.y)
    energy = simulate(scene, t_end=0.01).energy[0]
    assert reachable_height(d, scene) == pytest.approx(energy / (scene.ball.mass * scene.gravity), rel=1e-12)


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-6, 0.99e-4, 1.01e-4, 0.1, 1.0, 3.0, math.pi, 10.0])
def test_rotation_is_scipys_rotation_by_the_vector(angle):
    """``rotation(u)``, Rodrigues' formula with its series below 10⁻⁴, against scipy's rotation by
    the vector u (through quaternions: an independent computation), about three axes; orthonormal."""
    from scipy.spatial.transform import Rotation

    for axis in ([0.0, 0.0, 1.0], [0.6, -0.8, 0.0], [1.0, 2.0, -2.0]):
        u = angle * np.array(axis) / np.linalg.norm(axis)
        R = rotation(u)
        np.testing.assert_allclose(R, Rotation.from_rotvec(u).as_matrix(), rtol=0, atol=2e-15)
        np.testing.assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=2e-15)
