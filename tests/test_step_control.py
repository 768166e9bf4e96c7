"""dop853's step-size control (PI control, and an error scale that holds each component relative to
at least the ball's own size, ``kernel.steps.error_norm``): for the same largest contact error it
needs no more right-hand-side evaluations than scipy's DOP853 on the independent equations of
rollball/reference.py, on a crater scene that is not an example and played no part in choosing the PI
control (its first 2.5 s, where the ball crosses the pit: the 5 s of docs/accuracy.py cost a minute
here)."""

import numpy as np
import pytest

from conftest import make_scene
from rollball import simulate
from rollball.landscape import landscape_for
from rollball.reference import reference_rhs, reference_solution
from rollball.simulation import initial_state

ROW = 0.01
# a held-out crater: a bowl with a Gaussian pit off its centre, the ball thrown across it
CRATER = make_scene("0.3*(x^2+y^2) - 0.25*exp(-5*((x+0.1)^2+(y-0.15)^2))", x=-0.9, y=-0.6, vx=0.4, vy=0.9,
                    duration=2.5)


def scipy_ladder(scene, times, alpha):
    """(evaluations, largest contact error) of scipy's DOP853 at rtol 1e-4 .. 1e-10 (atol 1e-3 rtol; looser
    tolerances are off the asymptotic range here: their errors do not fall monotonically)."""
    from scipy.integrate import solve_ivp

    a0, v0 = initial_state(landscape_for(scene.landscape), scene)
    out = []
    for k in range(4, 11):
        rtol = 10.0 ** -k
        sol = solve_ivp(reference_rhs(scene), (0.0, times[-1]), np.concatenate([a0, v0, np.eye(3).ravel()]),
                        method="DOP853", t_eval=times, rtol=rtol, atol=rtol * 1e-3)
        out.append((sol.nfev, float(np.linalg.norm(sol.y.T[:, :2] - alpha, axis=1).max())))
    return out


@pytest.fixture(scope="module")
def crater():
    """The crater's rows' times, the reference's contact points there and scipy's ladder."""
    times = np.linspace(0.0, CRATER.duration, round(CRATER.duration / ROW) + 1)
    alpha, _, _ = reference_solution(CRATER, times, rtol=1e-12, atol=1e-12)  # (within 2e-13 m of rtol 1e-13)
    return times, alpha, scipy_ladder(CRATER, times, alpha)


@pytest.mark.parametrize("rtol", [1e-8, 1e-10])
def test_dop853_needs_no_more_evaluations_than_scipys_for_the_same_contact_error(crater, rtol):
    scene = CRATER
    times, alpha, ladder = crater
    errors = np.log([e for _, e in ladder])[::-1]
    evaluations = np.log([n for n, _ in ladder])[::-1]
    assert np.all(np.diff(errors) > 0)  # (scipy's error falls as its tolerance does)

    traj = simulate(scene, method="dop853", rtol=rtol, atol=rtol * 1e-3, record_dt=ROW)
    error = float(np.linalg.norm(traj.contact - alpha, axis=1).max())
    assert errors[0] <= np.log(error) <= errors[-1]
    theirs = float(np.exp(np.interp(np.log(error), errors, evaluations)))
    assert traj.evaluations <= theirs, (traj.evaluations, theirs, error)
