"""The adaptive pairs' orientation: R carried along omega's dense output (kernel.turn), checked
against scipy's DOP853 on R' = A(omega(t)) R at 1e-13."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rollball import kernel
from test_hard_cases import exact_rotation

H = 0.2   # the step (s)
# omega(t + theta H) = omega0 + sum_k C[k] theta^(k+1): a ball spinning at 20-40 rad/s whose axis turns
OMEGA0 = np.array([30.0, -8.0, 12.0])
C = np.array([[-6.0, 25.0, 3.0], [9.0, -4.0, -14.0], [2.0, 3.0, 5.0], [-1.0, 0.5, 1.5],
              [0.3, -0.2, 0.1], [0.05, 0.02, -0.04], [-0.01, 0.01, 0.02]])


def omega(t, omega0=OMEGA0, c=C):
    theta = t / H
    return omega0 + sum(c[k] * theta ** (k + 1) for k in range(len(c)))


def arrays(omega0=OMEGA0, c=C):
    """z, P and K as a pair's step leaves them (with omega's polynomial): P the identity, so
    K[k, 5:8] = C[k] / H."""
    degree = len(c)
    P = np.eye(degree)
    K = np.zeros((kernel.stage_rows(degree), kernel.MK_SIZE))
    K[:degree, 5:8] = c / H
    kernel.omega_polynomial(H, P, K)
    z = np.zeros(kernel.MK_SIZE)
    z[5:8] = omega0
    return z, P, K


def turned(tolerance, theta0=0.0, theta1=1.0, R=None, omega0=OMEGA0, c=C):
    z, P, K = arrays(omega0, c)
    p = kernel.parameters(0.1, 1.0, 9.81, tolerance)
    out = np.empty((3, 3))
    kernel.turn(p, z, np.eye(3) if R is None else R, H, P, K, theta0, theta1, out)
    return out


def exact(t0, t1, R0, omega0=OMEGA0, c=C):
    def rhs(t, y):
        w = omega(t, omega0, c)
        A = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
        return (A @ y.reshape(3, 3)).ravel()
    return solve_ivp(rhs, (t0, t1), R0.ravel(), method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1].reshape(3, 3)


def angle(R, R_ref):
    Q = R_ref.T @ R
    return 0.5 * np.linalg.norm([Q[2, 1] - Q[1, 2], Q[0, 2] - Q[2, 0], Q[1, 0] - Q[0, 1]])


@pytest.mark.parametrize("tolerance", [1e-4, 1e-6, 1e-8, 1e-10, 1e-12])
def test_the_error_follows_the_tolerance(tolerance):
    """The step turns the ball by ~7 rad about an axis that swings by 40 degrees: the sub-steps are
    chosen from Magnus 6's error model, so R's error stays below the tolerance (measured 0.05-0.1 of it)."""
    R_ref = exact(0.0, H, np.eye(3))
    error = angle(turned(tolerance), R_ref)
    assert error < tolerance
    assert error > 1e-3 * tolerance or error < 1e-13  # (not sub-stepped far beyond need)


def test_a_fixed_axis_is_one_sub_step_and_exact():
    """omega = f(t) e: Magnus is the integral of omega, exact for the polynomial, whatever the angle (here
    ~25 rad), however loose the tolerance."""
    e = np.array([0.48, -0.6, 0.64])
    c = np.outer([40.0, -30.0, 12.0, 5.0], e)
    R0 = exact_rotation(np.array([0.3, -1.1, 0.7]))
    turned_by = H * (100.0 + 40.0 / 2 - 30.0 / 3 + 12.0 / 4 + 5.0 / 5)
    R = turned(1.0, R=R0, omega0=100.0 * e, c=c)
    np.testing.assert_allclose(R, exact_rotation(turned_by * e) @ R0, rtol=0, atol=1e-13)


def test_spans_follow_on_from_each_other_and_stay_rotations():
    """Rows inside a step turn R on from the previous row: 0 -> 0.3 -> 1 agrees with 0 -> 1 to the
    tolerance, and R stays orthonormal; turning in place (out is R) is allowed."""
    R = turned(1e-10, 0.0, 0.3)
    np.testing.assert_allclose(R, exact(0.0, 0.3 * H, np.eye(3)), rtol=0, atol=1e-10)
    z, P, K = arrays()
    kernel.turn(kernel.parameters(0.1, 1.0, 9.81, 1e-10), z, R, H, P, K, 0.3, 1.0, R)
    assert angle(R, turned(1e-10)) < 1e-10
    np.testing.assert_allclose(R @ R.T, np.eye(3), rtol=0, atol=1e-14)


def test_an_orientation_racing_off_is_not_finite():
    """A span needing more than MAX_TURNS sub-steps gives nan (the step's orientation is not finite)."""
    assert np.isnan(turned(1e-12, omega0=1e9 * np.array([1.0, 0.0, 0.0]))).all()
