"""The implicit Gauss–Legendre methods: order, symmetry, bounded energy error, honest failure."""

from decimal import Decimal, localcontext

import numpy as np
import pytest

from rollball import Status, kernel, simulate
from rollball.implicit import GAUSS4, GAUSS6, Collocation
from rollball.landscape import landscape_for
from rollball.reference import reference_solution
from rollball.simulation import Simulation, initial_state
from rollball.trajectory import Reason
from test_convergence import slope

# an anisotropic bowl: the motion fills a two-dimensional region instead of a line
BOWL = dict(landscape="0.5*x^2 + 1.5*y^2", x=0.3, y=0.2, vx=0.2, vy=-0.1, spin=1.0)


def test_the_tableaus_check_themselves():
    assert (GAUSS4.order, GAUSS4.stages, GAUSS6.order, GAUSS6.stages) == (4, 2, 6, 3)
    a, b, c = GAUSS4.a, GAUSS4.b, GAUSS4.c
    with localcontext() as context:
        context.prec = 60
        moved = ((a[0][0] + Decimal("1e-12"), a[0][1] - Decimal("1e-12")), a[1])  # rows still sum to c
    with pytest.raises(ValueError, match="not symmetric"):
        Collocation("bad", "Bad", 4, c, moved, b)
    # symmetric, rows summing to c, but order 2 only: the implicit midpoint rule twice over
    half = Decimal("0.5")
    with pytest.raises(ValueError, match="order condition"):
        Collocation("bad", "Bad", 4, (half, half), ((half / 2, half / 2), (half / 2, half / 2)), (half, half))
    with pytest.raises(ValueError, match="order above 2"):
        Collocation("bad", "Bad", 2, c, a, b)


def _start(scene):
    alpha, v = initial_state(landscape_for(scene.landscape), scene)
    z = np.zeros(kernel.MK_SIZE)
    z[:2], z[2:5] = alpha, v
    return z, np.eye(3)


def _step(tab, scene, h, z, R):
    """One step of size h > 0 from (z, R) as a run takes it (the compiled ``advance``, one step of
    the method): (status, new z, new R, evaluations)."""
    run = Simulation(scene, method=tab.name, dt=h, t_end=h)
    run._z[:], run._R[:] = z, R   # (the arrays the kernel run starts from)
    run.judge_energy = False
    run.advance()
    return run.status, run._z.copy(), run._R.copy(), run.evaluations


@pytest.mark.parametrize("tab", [GAUSS4, GAUSS6], ids=["gauss4", "gauss6"])
def test_a_step_forward_then_back_returns_to_the_start(scene_factory, tab):
    """The rolling ball's motion is reversible (ρ: the momentum negated, the contact point and R
    kept; ρ f(ρ y) = −f(y)) and a symmetric method's step Φ_h is too: Φ_−h = ρ Φ_h ρ, so the step
    back, Φ_−h(Φ_h(y)) = ρ Φ_h(ρ Φ_h(y)), returns to y. Both steps are a run's own (the compiled
    kernel's, which numba does not compile again here)."""
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)
    z, R = _start(scene)
    rho = np.ones(len(z))
    rho[2:] = -1.0   # (the momentum, and u, which is 0 at a step's start)
    for h in (0.05, 0.2):
        status, z1, R1, evaluations = _step(tab, scene, h, z, R)
        assert status is Status.OK and evaluations > 2 * tab.stages
        status, z0, R0, _ = _step(tab, scene, h, rho * z1, R1)
        assert status is Status.OK
        z0 = rho * z0
        # the motion (alpha, v) to round-off; the orientation, carried by Munthe-Kaas from
        # u = 0 in each direction, to within the method's local error
        assert np.abs(z0[:5] - z[:5]).max() < 1e-15 * np.abs(z[:5]).max()  # a few ulps
        assert np.abs(R0 - R).max() < 30 * h**5


@pytest.mark.parametrize("tab, hs", [(GAUSS4, [0.1, 0.05, 0.025, 0.0125]), (GAUSS6, [0.1, 0.07, 0.05, 0.035])],
                         ids=["gauss4", "gauss6"])
def test_measured_order(scene_factory, tab, hs):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)
    alpha_ref, _, R_ref = reference_solution(scene, [0.0, 2.0])
    e_alpha, e_R = [], []
    for h in hs:
        traj = simulate(scene, method=tab.name, dt=h, t_end=2.0, record_every=10**6)
        assert traj.status is Status.OK and traj.t[-1] == 2.0
        e_alpha.append(np.abs(traj.contact[-1] - alpha_ref[-1]).max())
        e_R.append(np.abs(traj.R[-1] - R_ref[-1]).max())
    assert slope(hs, e_alpha) == pytest.approx(tab.order, abs=0.25)
    assert slope(hs, e_R) == pytest.approx(tab.order, abs=0.4)  # (R still a little above its rate)


def test_energy_error_stays_bounded_where_rk4_drifts(scene_factory):
    scene = scene_factory(BOWL["landscape"], **{k: v for k, v in BOWL.items() if k != "landscape"})
    every = 500  # a row every 10 s
    gauss = simulate(scene, method="gauss4", dt=0.02, t_end=1000.0, record_every=every)
    rk4 = simulate(scene, method="rk4", dt=0.02, t_end=1000.0, record_every=every)
    assert gauss.status is rk4.status is Status.OK
    e_gauss = np.abs(gauss.energy / gauss.energy[0] - 1)
    e_rk4 = np.abs(rk4.energy / rk4.energy[0] - 1)
    at = {t: int(t / 10) for t in (10, 100, 1000)}
    # rk4 drifts linearly: 100 times the error after 100 times the time
    assert e_rk4[at[1000]] > 50 * e_rk4[at[10]]
    # gauss4 does not: its error at 1000 s is no larger than its largest error in the first
    # 100 s, and far below rk4's at every time after the start
    assert e_gauss.max() <= 1.5 * e_gauss[: at[100] + 1].max()
    assert e_gauss[at[1000]] < 1e-2 * e_rk4[at[1000]]
    assert gauss.evaluations > 2 * 2 * gauss.steps  # the iterations are counted


def test_a_step_too_large_stops_the_run_honestly(scene_factory):
    scene = scene_factory("0.5*sin(x)*cos(y)", x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)
    traj = simulate(scene, method="gauss4", dt=1.5, t_end=3.0)
    assert traj.status is Status.NONFINITE and traj.failure.reason is Reason.NOT_CONVERGED
    assert len(traj) == 1 and traj.t[-1] == 0.0 and np.isfinite(traj.data).all()
    assert "did not converge" in traj.message and "dt" in traj.message


def test_in_the_registry_scene_files_and_command_line(scene_factory, tmp_path):
    from rollball import METHODS, MethodKind, Scene, SceneError
    from rollball.cli import main

    names = list(METHODS)
    assert names.index("lawson5") < names.index("gauss4") < names.index("gauss6") < names.index("dopri5")
    assert METHODS["gauss4"] is GAUSS4 and GAUSS4.kind is MethodKind.IMPLICIT
    assert GAUSS4.fixed_step and not GAUSS4.classic_allowed and not GAUSS4.adaptive
    with pytest.raises(SceneError, match="munthe_kaas"):
        scene_factory("x*y", method="gauss4", munthe_kaas=False)
    with pytest.raises(ValueError, match="Munthe-Kaas"):
        simulate(scene_factory("x*y", method="gauss4"), munthe_kaas=False)
    path = tmp_path / "scene.json"
    scene_factory("0.5*(x^2 + y^2)", x=0.3, method="gauss6", dt=0.01).save(path)
    assert Scene.load(path).integrator.method == "gauss6"
    assert main(["simulate", str(path), "--method", "gauss4", "--t-end", "1"]) == 0
