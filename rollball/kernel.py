"""The compiled stepping kernel: the reduced equations of motion, one Runge–Kutta stage
loop for every tableau (classic and Munthe-Kaas), validity checks and recording.

Everything here is landscape-independent and compiled once (cached on disk by numba);
the landscape arrives as a compiled callback ``fn(x, y, out)`` writing f and its first and
second derivatives to out[0:6].

State vector z: contact point (x, y), angular momentum about the contact point v (3),
then either u (3, the Munthe-Kaas Lie-algebra increment, zero at each step start) or
R (9, row-major, integrated as a plain matrix by the classic scheme).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types

LANDSCAPE_SIGNATURE = types.void(types.float64, types.float64, types.CPointer(types.float64))

# What one evaluation learns about a state besides its derivative ("probe").
PROBE_N = 0        # unit normal N (3)
PROBE_OMEGA = 3    # angular velocity omega (3)
PROBE_FORCE = 6    # normal force F.N
PROBE_FIT = 7      # r * largest principal curvature (the ball fits while < 1)
PROBE_HEIGHT = 8   # f(x, y)
PROBE_SIZE = 9

# Integer run counters (``ints``) and float run facts (``info``).
I_STEPS, I_ROWS, I_LAST_RECORDED, I_STATUS = 0, 1, 2, 3
F_LIFTOFF, F_PREV_FORCE, F_FAIL_T, F_FAIL_X, F_FAIL_Y, F_FAIL_VALUE = 0, 1, 2, 3, 4, 5

# Status codes (see simulation.Status).
RUNNING, OK, DOES_NOT_FIT, NONFINITE = 0, 1, 2, 3

ROW_SIZE = 23  # t, x, y, c(3), c'(3), omega(3), R(9), energy, normal force


def state_size(munthe_kaas: bool) -> int:
    return 8 if munthe_kaas else 14


@njit(cache=True, nogil=True)
def dynamics(fn, d, p, z, mk, dz, probe, full):
    """dz = z'(z); with ``full`` also fill ``probe`` (normal, omega, F.N, r*kappa, height)."""
    r, m, g0 = p[0], p[1], p[2]
    fn(z[0], z[1], d.ctypes)
    fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
    W2 = 1.0 + fx * fx + fy * fy
    W = math.sqrt(W2)
    n1, n2, n3 = -fx / W, -fy / W, 1.0 / W
    v1, v2, v3 = z[2], z[3], z[4]
    # omega = T^-1 v, T^-1 = 5/(7 m r^2) (I + 5/2 N N^T)
    k = 5.0 / (7.0 * m * r * r)
    nv = 2.5 * (n1 * v1 + n2 * v2 + n3 * v3)
    o1, o2, o3 = k * (v1 + nv * n1), k * (v2 + nv * n2), k * (v3 + nv * n3)
    # N' columns: dN/dx = (n_x - N (N . n_x)) / W with n = (-f_x, -f_y, 1)
    s = n1 * fxx + n2 * fxy
    Nx1, Nx2, Nx3 = (n1 * s - fxx) / W, (n2 * s - fxy) / W, n3 * s / W
    s = n1 * fxy + n2 * fyy
    Ny1, Ny2, Ny3 = (n1 * s - fxy) / W, (n2 * s - fyy) / W, n3 * s / W
    # C' = phi' + r N', E = C'^T C'
    Cx1, Cx2, Cx3 = 1.0 + r * Nx1, r * Nx2, fx + r * Nx3
    Cy1, Cy2, Cy3 = r * Ny1, 1.0 + r * Ny2, fy + r * Ny3
    E11 = Cx1 * Cx1 + Cx2 * Cx2 + Cx3 * Cx3
    E12 = Cx1 * Cy1 + Cx2 * Cy2 + Cx3 * Cy3
    E22 = Cy1 * Cy1 + Cy2 * Cy2 + Cy3 * Cy3
    det = E11 * E22 - E12 * E12
    # alpha' = r E^-1 C'^T (omega x N)
    w1, w2, w3 = o2 * n3 - o3 * n2, o3 * n1 - o1 * n3, o1 * n2 - o2 * n1
    b1 = r * (Cx1 * w1 + Cx2 * w2 + Cx3 * w3)
    b2 = r * (Cy1 * w1 + Cy2 * w2 + Cy3 * w3)
    a1 = (E22 * b1 - E12 * b2) / det
    a2 = (E11 * b2 - E12 * b1) / det
    # N' alpha', then v' = m r (N x g) - m r^2 (N' alpha') x (N x omega), with N x omega = -w
    d1, d2, d3 = Nx1 * a1 + Ny1 * a2, Nx2 * a1 + Ny2 * a2, Nx3 * a1 + Ny3 * a2
    mr, mr2 = m * r, m * r * r
    dz[0] = a1
    dz[1] = a2
    dz[2] = -mr * g0 * n2 + mr2 * (d2 * w3 - d3 * w2)
    dz[3] = mr * g0 * n1 + mr2 * (d3 * w1 - d1 * w3)
    dz[4] = mr2 * (d1 * w2 - d2 * w1)
    if mk:
        # u' = dexp_u^-1(omega) = omega - 1/2 u x omega + 1/12 u x (u x omega)
        u1, u2, u3 = z[5], z[6], z[7]
        c1, c2, c3 = u2 * o3 - u3 * o2, u3 * o1 - u1 * o3, u1 * o2 - u2 * o1
        dz[5] = o1 - 0.5 * c1 + (u2 * c3 - u3 * c2) / 12.0
        dz[6] = o2 - 0.5 * c2 + (u3 * c1 - u1 * c3) / 12.0
        dz[7] = o3 - 0.5 * c3 + (u1 * c2 - u2 * c1) / 12.0
    else:
        # R' = A(omega) R, column by column
        for j in range(3):
            q1, q2, q3 = z[5 + j], z[8 + j], z[11 + j]
            dz[5 + j] = o2 * q3 - o3 * q2
            dz[8 + j] = o3 * q1 - o1 * q3
            dz[11 + j] = o1 * q2 - o2 * q1
    if full:
        probe[0], probe[1], probe[2] = n1, n2, n3
        probe[3], probe[4], probe[5] = o1, o2, o3
        # F.N = m (c'' - g).N with c''.N = r (omega x N').N
        probe[6] = m * r * ((o2 * d3 - o3 * d2) * n1 + (o3 * d1 - o1 * d3) * n2
                            + (o1 * d2 - o2 * d1) * n3) + m * g0 * n3
        probe[7] = r * largest_curvature(d)
        probe[8] = d[0]


@njit(cache=True, nogil=True)
def largest_curvature(d):
    """The largest principal curvature (> 0 bending up) from d = f, f_x, f_y, f_xx, f_xy, f_yy."""
    fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
    # roots of det(II - kappa G) = 0, G first, II second fundamental form
    W2 = 1.0 + fx * fx + fy * fy
    W = math.sqrt(W2)
    G11, G12, G22 = 1.0 + fx * fx, fx * fy, 1.0 + fy * fy
    h11, h12, h22 = fxx / W, fxy / W, fyy / W
    mean = 0.5 * (G11 * h22 + G22 * h11 - 2.0 * G12 * h12) / W2
    gauss = (h11 * h22 - h12 * h12) / W2
    return mean + math.sqrt(max(mean * mean - gauss, 0.0))


@njit(cache=True, nogil=True)
def evaluate_points(fn, xs, ys, out):
    """out[:, i] = f, f_x, f_y, f_xx, f_xy, f_yy at (xs[i], ys[i])."""
    d = np.empty(6)
    for i in range(xs.shape[0]):
        fn(xs[i], ys[i], d.ctypes)
        for k in range(6):
            out[k, i] = d[k]


@njit(cache=True, nogil=True)
def rodrigues(u, R, out):
    """out = exp(A(u)) R, exact at any angle, with a series for small |u|."""
    th2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2]
    th = math.sqrt(th2)
    if th < 1e-4:
        a = 1.0 - th2 / 6.0 * (1.0 - th2 / 20.0)
        b = 0.5 - th2 / 24.0 * (1.0 - th2 / 30.0)
    else:
        a = math.sin(th) / th
        h = math.sin(0.5 * th) / th
        b = 2.0 * h * h
    u1, u2, u3 = u[0], u[1], u[2]
    # Q = I + a A + b A^2, A^2 = u u^T - |u|^2 I
    q11, q22, q33 = 1.0 + b * (u1 * u1 - th2), 1.0 + b * (u2 * u2 - th2), 1.0 + b * (u3 * u3 - th2)
    q12, q21 = -a * u3 + b * u1 * u2, a * u3 + b * u1 * u2
    q13, q31 = a * u2 + b * u1 * u3, -a * u2 + b * u1 * u3
    q23, q32 = -a * u1 + b * u2 * u3, a * u1 + b * u2 * u3
    for j in range(3):
        r1, r2, r3 = R[0, j], R[1, j], R[2, j]
        out[0, j] = q11 * r1 + q12 * r2 + q13 * r3
        out[1, j] = q21 * r1 + q22 * r2 + q23 * r3
        out[2, j] = q31 * r1 + q32 * r2 + q33 * r3


@njit(cache=True, nogil=True)
def record(rows, i, t, z, R, probe, p):
    """Write one trajectory row (the CSV columns of DESIGN §5)."""
    r, m, g0 = p[0], p[1], p[2]
    n1, n2, n3 = probe[0], probe[1], probe[2]
    o1, o2, o3 = probe[3], probe[4], probe[5]
    row = rows[i]
    row[0] = t
    row[1] = z[0]
    row[2] = z[1]
    row[3] = z[0] + r * n1
    row[4] = z[1] + r * n2
    row[5] = probe[8] + r * n3
    row[6] = r * (o2 * n3 - o3 * n2)
    row[7] = r * (o3 * n1 - o1 * n3)
    row[8] = r * (o1 * n2 - o2 * n1)
    row[9], row[10], row[11] = o1, o2, o3
    for a in range(3):
        for b in range(3):
            row[12 + 3 * a + b] = R[a, b]
    row[21] = 0.5 * (o1 * z[2] + o2 * z[3] + o3 * z[4]) + m * g0 * row[5]
    row[22] = probe[6]


@njit(cache=True, nogil=True)
def _finite(a):
    for x in a.flat:
        if not math.isfinite(x):
            return False
    return True


SEGMENT_SAMPLES = 8  # fit checks between the ends of a step whose contact point raced


@njit(cache=True, nogil=True)
def _fit_along_segment(fn, d, r, z, zn, h, speed0, speed1):
    """r * kappa inside the step, if the contact point moved farther than its end speeds explain.

    Near the no-fit boundary the contact point speeds up without bound, so a fixed step can
    jump across a thin no-fit region with both ends fitting. Such a step moves the contact
    point much farther than h times its speed at either end; then the fit is sampled along
    the straight segment between the two contact points. Returns (largest r*kappa, x, y).
    """
    dx, dy = zn[0] - z[0], zn[1] - z[1]
    if math.sqrt(dx * dx + dy * dy) <= 2.0 * h * max(speed0, speed1):
        return 0.0, 0.0, 0.0
    worst, wx, wy = 0.0, 0.0, 0.0
    for j in range(1, SEGMENT_SAMPLES + 1):
        s = j / (SEGMENT_SAMPLES + 1.0)
        x, y = z[0] + s * dx, z[1] + s * dy
        fn(x, y, d.ctypes)
        fit = r * largest_curvature(d)
        if fit > worst:
            worst, wx, wy = fit, x, y
    return worst, wx, wy


@njit(cache=True, nogil=True)
def advance(fn, A, b, mk, p, dt, t_end, n_steps, every, max_steps, z, R, K, probe, rows, ints, info):
    """Run up to ``max_steps`` further steps; all run state lives in the arrays passed in.

    On the first call (no rows yet) the initial state is checked and recorded. The run
    stops early, with ints[I_STATUS] set, where the state turns non-finite or the ball no
    longer fits; the last valid state is then the last row.
    """
    n = z.shape[0]
    s = b.shape[0]
    d = np.empty(6)
    Y = np.empty(n)
    zn = np.empty(n)
    Rn = np.empty((3, 3))
    Kn = np.empty(n)
    pn = np.empty(PROBE_SIZE)

    if ints[I_ROWS] == 0:
        if not _finite(z):
            ints[I_STATUS] = NONFINITE
            info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y] = 0.0, z[0], z[1]
            return
        dynamics(fn, d, p, z, mk, K[0], probe, True)
        if not (_finite(K[0]) and _finite(probe)):
            ints[I_STATUS] = NONFINITE
            info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y] = 0.0, z[0], z[1]
            return
        record(rows, 0, 0.0, z, R, probe, p)
        ints[I_ROWS] = 1
        info[F_PREV_FORCE] = probe[PROBE_FORCE]
        if probe[PROBE_FORCE] <= 0.0:
            info[F_LIFTOFF] = 0.0
        if probe[PROBE_FIT] >= 1.0:
            ints[I_STATUS] = DOES_NOT_FIT
            info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y] = 0.0, z[0], z[1]
            info[F_FAIL_VALUE] = probe[PROBE_FIT]
            return

    k0 = ints[I_STEPS]
    k_stop = min(n_steps, k0 + max_steps)
    for k in range(k0 + 1, k_stop + 1):
        last = k == n_steps
        h = t_end - (k - 1) * dt if last else dt
        t = t_end if last else k * dt
        for i in range(1, s):
            for q in range(n):
                acc = 0.0
                for j in range(i):
                    acc += A[i, j] * K[j, q]
                Y[q] = z[q] + h * acc
            dynamics(fn, d, p, Y, mk, K[i], pn, False)
        for q in range(n):
            acc = 0.0
            for i in range(s):
                acc += b[i] * K[i, q]
            zn[q] = z[q] + h * acc
        if mk:
            rodrigues(zn[5:8], R, Rn)
            zn[5] = zn[6] = zn[7] = 0.0
        else:
            for a in range(3):
                for c in range(3):
                    Rn[a, c] = zn[5 + 3 * a + c]
        motion_ok = _finite(zn[:5])
        rotation_ok = _finite(zn[5:]) and _finite(Rn)
        if motion_ok and rotation_ok:
            dynamics(fn, d, p, zn, mk, Kn, pn, True)
            motion_ok = _finite(Kn[:5]) and _finite(pn)
            rotation_ok = _finite(Kn[5:])
        ok = motion_ok and rotation_ok
        if not ok:
            ints[I_STATUS] = NONFINITE
            info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y] = t, z[0], z[1]
            info[F_FAIL_VALUE] = 1.0 if motion_ok and not rotation_ok else 0.0
        elif pn[PROBE_FIT] >= 1.0:
            ints[I_STATUS] = DOES_NOT_FIT
            info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y] = t, zn[0], zn[1]
            info[F_FAIL_VALUE] = pn[PROBE_FIT]
        else:
            fit, fx, fy = _fit_along_segment(fn, d, p[0], z, zn, h, math.hypot(K[0, 0], K[0, 1]),
                                             math.hypot(Kn[0], Kn[1]))
            if fit >= 1.0:
                ints[I_STATUS] = DOES_NOT_FIT
                info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y] = t, fx, fy
                info[F_FAIL_VALUE] = fit
        if ints[I_STATUS] != RUNNING:
            # keep the last valid state as the last row
            if ints[I_LAST_RECORDED] != k - 1:
                record(rows, ints[I_ROWS], (k - 1) * dt, z, R, probe, p)
                ints[I_ROWS] += 1
                ints[I_LAST_RECORDED] = k - 1
            return
        force = pn[PROBE_FORCE]
        if force <= 0.0 and info[F_PREV_FORCE] > 0.0 and math.isnan(info[F_LIFTOFF]):
            prev = info[F_PREV_FORCE]
            info[F_LIFTOFF] = t - h + h * prev / (prev - force)
        info[F_PREV_FORCE] = force
        z[:] = zn
        R[:, :] = Rn
        K[0, :] = Kn
        probe[:] = pn
        ints[I_STEPS] = k
        if k % every == 0 or last:
            record(rows, ints[I_ROWS], t, z, R, probe, p)
            ints[I_ROWS] += 1
            ints[I_LAST_RECORDED] = k
    if ints[I_STEPS] == n_steps:
        ints[I_STATUS] = OK
