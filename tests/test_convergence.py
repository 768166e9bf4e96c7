"""Measured convergence orders against an independent reference, and R staying in SO(3)."""

import numpy as np
import pytest

from rollball import Status, simulate
from rollball.reference import reference_solution

STEPS = {
    "euler": [0.01, 0.005, 0.0025, 0.00125],
    "rk4": [0.1, 0.05, 0.025, 0.0125],
    "lawson5": [0.1, 0.05, 0.025, 0.0125, 0.00625],
}
ORDER = {"euler": 1, "rk4": 4, "lawson5": 5}
T_END = 1.0


@pytest.fixture(scope="module")
def hills(request):
    from conftest import make_scene

    scene = make_scene("0.5*sin(x)*cos(y)", x=0.3, y=-0.2, vx=1.0, vy=0.5, spin=2.0)
    alpha, _, R = reference_solution(scene, [0.0, T_END])
    return scene, alpha[-1], R[-1]


FLOOR = 1e-11  # below this the reference's own error would show


def slope(hs, errors):
    """Log-log slope over the three smallest steps whose errors stand above the floor."""
    hs, errors = np.array(hs), np.array(errors)
    keep = errors > FLOOR
    assert keep.sum() >= 3, errors
    return np.polyfit(np.log(hs[keep][-3:]), np.log(errors[keep][-3:]), 1)[0]


@pytest.mark.parametrize("munthe_kaas", [True, False], ids=["munthe-kaas", "classic"])
@pytest.mark.parametrize("method", list(STEPS))
def test_measured_order(hills, method, munthe_kaas):
    scene, alpha_ref, R_ref = hills
    e_alpha, e_R = [], []
    for h in STEPS[method]:
        traj = simulate(scene, method=method, munthe_kaas=munthe_kaas, dt=h, t_end=T_END,
                        record_every=10**6)
        assert traj.t[-1] == T_END
        e_alpha.append(np.abs(traj.contact[-1] - alpha_ref).max())
        e_R.append(np.abs(traj.R[-1] - R_ref).max())
    p = ORDER[method]
    assert slope(STEPS[method], e_alpha) == pytest.approx(p, abs=0.2)
    assert slope(STEPS[method], e_R) == pytest.approx(p, abs=0.25)


@pytest.mark.parametrize("method", list(STEPS))
def test_orientation_rides_along(hills, method):
    """The motion (alpha, v) does not depend on how R is advanced: bit for bit the same."""
    scene = hills[0]
    mk = simulate(scene, method=method, munthe_kaas=True, t_end=0.5)
    classic = simulate(scene, method=method, munthe_kaas=False, t_end=0.5)
    assert np.array_equal(mk.contact, classic.contact)
    assert np.array_equal(mk.omega, classic.omega)
    assert not np.array_equal(mk.R, classic.R)


def test_munthe_kaas_stays_in_so3_classic_does_not(hills):
    scene = hills[0]
    n = 100_000
    mk = simulate(scene, method="rk4", munthe_kaas=True, dt=0.05, t_end=n * 0.05, record_every=1000)
    classic = simulate(scene, method="rk4", munthe_kaas=False, dt=0.05, t_end=n * 0.05, record_every=1000)
    assert mk.steps == classic.steps == n
    assert mk.status is classic.status is Status.OK
    assert mk.orthogonality_error().max() < 1e-12
    assert np.allclose(np.linalg.det(mk.R), 1.0, atol=1e-12)
    assert classic.orthogonality_error()[-1] > 1e-2


def test_euler_classic_leaves_so3_fast(hills):
    traj = simulate(hills[0], method="euler", munthe_kaas=False, dt=0.01, t_end=5.0)
    assert traj.orthogonality_error()[-1] > 0.1
    traj = simulate(hills[0], method="euler", munthe_kaas=True, dt=0.01, t_end=5.0)
    assert traj.orthogonality_error().max() < 1e-13
