"""Dense output, events located on it, and the exact dexp⁻¹ on so(3) that Munthe-Kaas needs for
high orders: each against exact arithmetic or an independent computation."""

import math
from fractions import Fraction

import mpmath
import numpy as np
import pytest
from conftest import make_scene, V2_EXAMPLES

from rollball import METHODS, Scene, Status, simulate
from rollball.kernel import DEXPINV_SERIES, dexpinv
from rollball.order_conditions import density, rooted_trees, size
from rollball.reference import normal_force_zeros, reference_solution
from rollball.tableaus import Tableau

# -- dexp^-1 ------------------------------------------------------------------------------------


def dexpinv_exact(u, omega, digits=50):
    """dexp_u^-1(omega) at 50 digits: dexp_u = sum_k A(u)^k / (k+1)!, inverted as a matrix."""
    with mpmath.workdps(digits):
        A = mpmath.matrix([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        term, total = mpmath.eye(3), mpmath.eye(3)
        for k in range(1, 200):
            term = term * A / (k + 1)
            total += term
        x = mpmath.lu_solve(total, mpmath.matrix(omega))
        return np.array([float(x[i]) for i in range(3)])


@pytest.mark.parametrize("theta", [0.0, 1e-8, 1e-3, 0.05, math.sqrt(DEXPINV_SERIES) * (1 - 1e-9),
                                   math.sqrt(DEXPINV_SERIES) * (1 + 1e-9), 0.3, 1.0, 2.0, 3.0, 5.0])
def test_dexpinv_is_exact(theta):
    rng = np.random.default_rng(int(theta * 1000) + 1)
    direction = rng.normal(size=3)
    u = theta * direction / np.linalg.norm(direction)
    omega = rng.normal(size=3)
    got = np.array(dexpinv(*u, *omega))
    want = dexpinv_exact(u, omega)
    assert np.abs(got - want).max() <= 4e-16 * max(1.0, np.abs(want).max()), (got - want)


# -- continuous extensions: exact order conditions ----------------------------------------------


def extended(method: Tableau):
    """The stage matrix over K_0 .. K_last (the derivative at the new state as a stage whose row is b)."""
    s, last = method.stages, method.last
    A = [[Fraction(0)] * (last + 1) for _ in range(last + 1)]
    for i, row in enumerate(method.a, start=1):
        A[i][:i] = row
    A[last][:s] = method.b
    return A


def phi(A, tree):
    g = [Fraction(1)] * len(A)
    for child in tree:
        h = phi(A, child)
        Ah = [sum(A[i][j] * h[j] for j in range(len(A))) for i in range(len(A))]
        g = [g[i] * Ah[i] for i in range(len(A))]
    return g


def continuous_condition(method, tree):
    """sum_i b_i(theta) Phi_i(tree) = theta^|tree| / gamma(tree), coefficient by coefficient."""
    P, A = method.dense_output(), extended(method)
    weights = phi(A, tree)
    q = len(P[0])
    got = [sum(P[i][k] * weights[i] for i in range(len(P))) for k in range(q)]
    want = [Fraction(0)] * q
    if size(tree) <= q:
        want[size(tree) - 1] = Fraction(1, density(tree))
    return got == want


# the explicit tableaus (the implicit ones: test_implicit; DOP853 checks its own when built)
TABLEAUS = {name: m for name, m in METHODS.items() if isinstance(m, Tableau)}


@pytest.mark.parametrize("method", TABLEAUS.values(), ids=list(TABLEAUS))
def test_dense_output_has_its_declared_order(method):
    order = method.interpolation_order
    assert order >= min(method.order, 3)
    for p in range(1, order + 1):
        for tree in rooted_trees(p):
            assert continuous_condition(method, tree), (method.name, tree)
    assert not all(continuous_condition(method, tree) for tree in rooted_trees(order + 1))


def test_dense_output_ends_at_the_step():
    for method in TABLEAUS.values():
        P = method.dense_output()
        b = method.b + (0,) * (len(P) - method.stages)
        assert [sum(row) for row in P] == list(b)


# -- rows from the dense output ----------------------------------------------------------------

HILLS = dict(x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)


def test_rows_cost_no_steps():
    """Rows at record_dt are interpolated: 10 000 rows cost the steps the tolerance needs."""
    scene = make_scene("0.5*sin(x)*cos(y)", method="dopri5", **HILLS)
    few = simulate(scene, rtol=1e-6, atol=1e-9, t_end=2.0, record_dt=0.5)
    many = simulate(scene, rtol=1e-6, atol=1e-9, t_end=2.0, record_dt=2.0 / 10_000)
    assert len(many) == 10_001 and many.steps == few.steps < 200
    assert np.array_equal(many.t[::2500], few.t)
    alpha, _, R = reference_solution(scene, many.t)
    assert np.abs(many.contact - alpha).max() < 2e-5
    assert np.abs(many.R - R).max() < 1e-4


@pytest.mark.parametrize("rtol, bound", [(1e-6, 2e-5), (1e-9, 2e-8)])
def test_interpolated_rows_are_as_accurate_as_the_steps(rtol, bound):
    scene = make_scene("0.5*sin(x)*cos(y)", method="dopri5", **HILLS)
    traj = simulate(scene, rtol=rtol, atol=rtol * 1e-3, t_end=2.0, record_dt=0.01)
    alpha, _, R = reference_solution(scene, traj.t)
    assert np.abs(traj.contact - alpha).max() < bound
    assert np.abs(traj.R - R).max() < 10 * bound
    assert traj.orthogonality_error().max() < 1e-13


# -- lift-off located on the dense output, against scipy's own event location --------------------


def reference_liftoff(scene: Scene, t_max: float) -> float:
    """The first time F·N = 0, by scipy's DOP853 with its event location on the independent
    equations of rollball.reference."""
    return float(normal_force_zeros(scene, t_max, first=True)[0])


LIFTOFF_SCENES = {
    "crest": Scene.load(V2_EXAMPLES / "liftoff.json"),
    "cylinder": Scene.load(V2_EXAMPLES / "cylinder.json"),
    "bump": make_scene("0.4*exp(-(x^2 + 2*y^2))", x=-2.0, y=0.3, vx=5.0, vy=-0.5, spin=3.0, duration=1.5),
}


@pytest.fixture(scope="module")
def liftoff_times():
    return {name: reference_liftoff(scene, scene.duration) for name, scene in LIFTOFF_SCENES.items()}


@pytest.mark.parametrize("name", list(LIFTOFF_SCENES))
def test_liftoff_time_is_located_on_the_dense_output(name, liftoff_times):
    scene, t_ref = LIFTOFF_SCENES[name], liftoff_times[name]
    for method in ("rk4", "gauss4"):  # (a cubic Hermite dense output: error O(h^4))
        fixed = simulate(scene, method=method, dt=1e-2, record_every=10)
        assert abs(fixed.liftoff_time - t_ref) < 2e-6, (method, fixed.liftoff_time, t_ref)
    dopri = simulate(scene, method="dopri5", rtol=1e-10, atol=1e-13, record_dt=0.01)
    assert abs(dopri.liftoff_time - t_ref) < 1e-7, (dopri.liftoff_time, t_ref)
    assert not dopri.liftoff.kink
    # the place is the contact point at that time
    alpha, _, _ = reference_solution(scene, [0.0, t_ref])
    assert math.hypot(dopri.liftoff.x - alpha[-1, 0], dopri.liftoff.y - alpha[-1, 1]) < 1e-6


# -- breaks in the surface ----------------------------------------------------------------------


@pytest.mark.parametrize("method, options", [("rk4", dict(dt=1e-3)), ("lawson5", dict(dt=1e-2)),
                                             ("gauss4", dict(dt=1e-2)), ("dopri5", dict(record_dt=0.01))])
def test_a_jump_in_height_stops_the_run_where_it_is(method, options):
    """atan2's branch cut on the negative x axis: the height jumps by 0.2 pi there. Rolling
    straight down the y direction at x = -1 from y = 0.5, the ball reaches y = 0 at t = 0.5 s
    (f is flat along that line... to first order: the path bends a little, so the time is checked
    against the reference)."""
    scene = make_scene("0.1*atan2(y, x)", x=-1.0, y=0.5, vy=-1.0, method=method, duration=2.0)
    traj = simulate(scene, **options)
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason == "height_jump"
    assert abs(traj.failure.value) == pytest.approx(0.2 * math.pi, rel=1e-6)
    assert abs(traj.failure.y) < 1e-6 and traj.failure.x < 0
    assert traj.energy_drift < 1e-4 and traj.t[-1] <= traj.failure.time
    assert 0 < traj.contact[-1, 1] < 5e-3  # the last row: just before (within a part of a step)


@pytest.mark.parametrize("formula, jump", [("x/abs(x)", 2.0), ("-0.3*abs(x)/x", -0.6)])
def test_steps_in_height_across_a_flat_floor(formula, jump):
    """A flat floor with a step at x = 0 (flat on both sides): the ball rolls at 1 m/s from x = -0.5
    and reaches it at t = 0.5 s exactly."""
    traj = simulate(make_scene(formula, x=-0.5, vx=1.0, duration=1.0))
    assert traj.status is Status.DOES_NOT_FIT and traj.failure.reason == "height_jump"
    assert traj.failure.value == pytest.approx(jump, rel=1e-6)
    assert abs(traj.failure.x) < 1e-9 and traj.failure.time == pytest.approx(0.5, abs=1e-9)
    assert traj.energy_drift < 1e-12 and "jumps in height" in traj.message


@pytest.mark.parametrize("h", [1e-2, 1e-3, 1e-4])
def test_a_roof_is_a_liftoff_at_the_crest(h):
    """The roof min(2y, -y): a ball rolling up its side z = 2y crosses the crest y = 0, where the
    real ball leaves the surface: a lift-off at the kink, at the exact time (located by clean
    shortened steps, as the stops are), and the run goes on."""
    traj = simulate(make_scene("min(2*y, -y)", x=0.0, y=-0.5, vy=2.0, duration=0.6, dt=h))
    assert traj.status is Status.OK
    assert traj.liftoff is not None and traj.liftoff.kink
    assert abs(traj.liftoff.y) < 1e-9 and abs(traj.liftoff.x) < 1e-12
    # up the plane z = 2y the contact point decelerates at (5/7) g sin(a) cos(a) = (2/7) g along y
    a = 2 / 7 * 9.81
    t_crest = (2.0 - math.sqrt(4.0 - a)) / a
    assert traj.liftoff.time == pytest.approx(t_crest, abs=1e-12)


def test_the_crest_of_a_saddle_roof_is_a_liftoff():
    """min(y, x y) (the input that crossed its crest with an energy jump of 66): a lift-off at the
    crest y = 0, and the run goes on."""
    traj = simulate(make_scene("min(y, x*y)", x=2.0, y=-0.5, vy=2.0, duration=0.6))
    assert traj.status is Status.OK and traj.liftoff.kink and abs(traj.liftoff.y) < 1e-9
    i = np.searchsorted(traj.t, traj.liftoff.time)
    assert (traj.contact[:i, 1] < 0).all() and traj.energy_error()[:i].max() < 1e-9
