"""The compiled stepping kernel: the reduced equations of motion, one Runge–Kutta stage
loop for every tableau (classic and Munthe-Kaas), fixed or adaptive steps, validity checks
and recording.

Everything here is landscape-independent and compiled once (cached on disk by numba);
the landscape arrives as a compiled callback ``fn(x, y, out)`` writing f and its first and
second derivatives to out[0:6].

State vector z: contact point (x, y), angular momentum about the contact point v (3),
then either u (3, the Munthe-Kaas Lie-algebra increment, zero at each step start) or
R (9, row-major, integrated as a plain matrix by the classic scheme). Stage derivatives
are the rows of K; the hot loop indexes whole arrays and never slices them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

LANDSCAPE_SIGNATURE = types.void(types.float64, types.float64, types.CPointer(types.float64))

# numpy's error model: a division by zero gives inf/nan (caught by the checks) instead of
# a branch and an exception on every division. The helpers are inlined into the loops that
# call them (numba's own inlining), which keeps the step as cheap as hand-written C.
# Nothing in it allocates, so it runs without numba's reference counting (_nrt=False): the
# counting of arrays handed between the inlined helpers would cost as much as a stage.
JIT = njit(cache=True, nogil=True, error_model="numpy", inline="always", fastmath={"contract"},
           _nrt=False)


@intrinsic
def data_pointer(typingctx, array):
    """The data pointer of an array, without the reference counting of ``array.ctypes``
    (which costs more than the landscape call itself). The caller keeps the array alive."""
    def codegen(context, builder, signature, args):
        return context.make_array(signature.args[0])(context, builder, args[0]).data
    return types.CPointer(array.dtype)(array), codegen


# What one evaluation learns about a state besides its derivative ("probe").
PROBE_N = 0        # unit normal N (3)
PROBE_OMEGA = 3    # angular velocity omega (3)
PROBE_FORCE = 6    # normal force F.N
PROBE_FIT = 7      # r * largest principal curvature (the ball fits while < 1)
PROBE_HEIGHT = 8   # f(x, y)
PROBE_SIZE = 9

# Integer run counters (``ints``) and float run facts (``info``).
I_STEPS, I_ROWS, I_LAST_RECORDED, I_STATUS, I_REJECTED, I_NONFINITE, I_EVALS, I_REASON = range(8)
F_LIFTOFF, F_PREV_FORCE, F_FAIL_T, F_FAIL_X, F_FAIL_Y, F_FAIL_VALUE, F_TIME, F_H = range(8)
INTS_SIZE, INFO_SIZE = 8, 8

# Status codes (see trajectory.Status).
RUNNING, OK, DOES_NOT_FIT, NONFINITE = 0, 1, 2, 3
# Why a run stopped (ints[I_REASON]; see trajectory.Reason), with F_FAIL_VALUE:
R_NONE = 0
R_NO_FIT = 1               # r * kappa >= 1 at the end of a step (value: r * kappa)
R_SECANT_NO_FIT = 2        # the secant curvature of a step says r * kappa >= 1 (value: that)
R_START_UNDEFINED = 3      # the landscape gives non-finite values at the start point
R_START_OVERFLOW = 4       # the landscape is finite at the start, the initial state overflows
R_UNDEFINED = 5            # the state or the landscape became non-finite during the run
R_ORIENTATION = 6          # only the orientation overflowed (value: 1 classic, 0 Munthe-Kaas)
R_STEP_UNDERFLOW = 7       # the adaptive step size fell below round-off (value: the step)
R_NOT_CONVERGED = 10       # an implicit step's stage equations did not converge (value: the step)

ROW_SIZE = 23  # t, x, y, c(3), c'(3), omega(3), R(9), energy, normal force

# Step-size control of the embedded pairs: the next step is h * SAFETY * err^exponent,
# bounded to [MIN_FACTOR, MAX_FACTOR] times h, with exponent -1/(q + 1) for an error
# estimate of order q (the method's ``error_exponent``).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 5.0
MIN_STEP = 1e-13  # adaptive steps below this (relative to t, or absolute below t = 1) stop the run
# An adaptive step that turns the state non-finite is retried 5 times smaller; after this
# many such steps in a run the ball is pressing against the end of the landscape, and the
# run stops as a fixed-step run would at the first.
NONFINITE_TRIES = 50

MK_SIZE, CLASSIC_SIZE = 8, 14


def state_size(munthe_kaas: bool) -> int:
    return MK_SIZE if munthe_kaas else CLASSIC_SIZE


def parameters(radius: float, mass: float, gravity: float) -> np.ndarray:
    """The ball and gravity as the kernel reads them, with the constants it would otherwise
    recompute at every evaluation: r, m, g0, 5/(7 m r^2), m r, m r^2, m g0."""
    r, m, g0 = radius, mass, gravity
    return np.array([r, m, g0, 5.0 / (7.0 * m * r * r), m * r, m * r * r, m * g0])


@JIT
def dynamics(fn, d, p, z, mk, K, row, probe, full):
    """K[row] = z'(z); with ``full`` also fill ``probe`` (normal, omega, F.N, r*kappa, height)."""
    r, k, mr, mr2, mg = p[0], p[3], p[4], p[5], p[6]
    fn(z[0], z[1], data_pointer(d))
    fx, fy, fxx, fxy, fyy = d[1], d[2], d[3], d[4], d[5]
    W2 = 1.0 + fx * fx + fy * fy
    iW = 1.0 / math.sqrt(W2)  # one division, then products
    n1, n2, n3 = -fx * iW, -fy * iW, iW
    v1, v2, v3 = z[2], z[3], z[4]
    # omega = T^-1 v, T^-1 = 5/(7 m r^2) (I + 5/2 N N^T)
    nv = 2.5 * (n1 * v1 + n2 * v2 + n3 * v3)
    o1, o2, o3 = k * (v1 + nv * n1), k * (v2 + nv * n2), k * (v3 + nv * n3)
    # N' columns: dN/dx = (n_x - N (N . n_x)) / W with n = (-f_x, -f_y, 1)
    s = n1 * fxx + n2 * fxy
    Nx1, Nx2, Nx3 = (n1 * s - fxx) * iW, (n2 * s - fxy) * iW, n3 * s * iW
    s = n1 * fxy + n2 * fyy
    Ny1, Ny2, Ny3 = (n1 * s - fxy) * iW, (n2 * s - fyy) * iW, n3 * s * iW
    # C' = phi' + r N', E = C'^T C'
    Cx1, Cx2, Cx3 = 1.0 + r * Nx1, r * Nx2, fx + r * Nx3
    Cy1, Cy2, Cy3 = r * Ny1, 1.0 + r * Ny2, fy + r * Ny3
    E11 = Cx1 * Cx1 + Cx2 * Cx2 + Cx3 * Cx3
    E12 = Cx1 * Cy1 + Cx2 * Cy2 + Cx3 * Cy3
    E22 = Cy1 * Cy1 + Cy2 * Cy2 + Cy3 * Cy3
    idet = 1.0 / (E11 * E22 - E12 * E12)
    # alpha' = r E^-1 C'^T (omega x N)
    w1, w2, w3 = o2 * n3 - o3 * n2, o3 * n1 - o1 * n3, o1 * n2 - o2 * n1
    b1 = r * (Cx1 * w1 + Cx2 * w2 + Cx3 * w3)
    b2 = r * (Cy1 * w1 + Cy2 * w2 + Cy3 * w3)
    a1 = (E22 * b1 - E12 * b2) * idet
    a2 = (E11 * b2 - E12 * b1) * idet
    # N' alpha', then v' = m r (N x g) - m r^2 (N' alpha') x (N x omega), with N x omega = -w
    d1, d2, d3 = Nx1 * a1 + Ny1 * a2, Nx2 * a1 + Ny2 * a2, Nx3 * a1 + Ny3 * a2
    K[row, 0] = a1
    K[row, 1] = a2
    K[row, 2] = -mg * r * n2 + mr2 * (d2 * w3 - d3 * w2)
    K[row, 3] = mg * r * n1 + mr2 * (d3 * w1 - d1 * w3)
    K[row, 4] = mr2 * (d1 * w2 - d2 * w1)
    if mk:
        K[row, 5], K[row, 6], K[row, 7] = dexpinv(z[5], z[6], z[7], o1, o2, o3)
    else:
        # R' = A(omega) R, column by column
        for j in range(3):
            q1, q2, q3 = z[5 + j], z[8 + j], z[11 + j]
            K[row, 5 + j] = o2 * q3 - o3 * q2
            K[row, 8 + j] = o3 * q1 - o1 * q3
            K[row, 11 + j] = o1 * q2 - o2 * q1
    if full:
        probe[0], probe[1], probe[2] = n1, n2, n3
        probe[3], probe[4], probe[5] = o1, o2, o3
        # F.N = m (c'' - g).N with c''.N = r (omega x N').N
        probe[6] = mr * ((o2 * d3 - o3 * d2) * n1 + (o3 * d1 - o1 * d3) * n2
                         + (o1 * d2 - o2 * d1) * n3) + mg * n3
        probe[7] = r * largest_curvature(fx, fy, fxx, fxy, fyy, iW)
        probe[8] = d[0]


@JIT
def dexpinv(u1, u2, u3, o1, o2, o3):
    """u' = dexp_u^-1(omega) = omega - 1/2 u x omega + 1/12 u x (u x omega)."""
    c1, c2, c3 = u2 * o3 - u3 * o2, u3 * o1 - u1 * o3, u1 * o2 - u2 * o1
    return (o1 - 0.5 * c1 + (u2 * c3 - u3 * c2) * (1.0 / 12.0),
            o2 - 0.5 * c2 + (u3 * c1 - u1 * c3) * (1.0 / 12.0),
            o3 - 0.5 * c3 + (u1 * c2 - u2 * c1) * (1.0 / 12.0))


@JIT
def largest_curvature(fx, fy, fxx, fxy, fyy, iW):
    """The largest principal curvature (> 0 bending up), iW = 1 / sqrt(1 + f_x² + f_y²)."""
    # roots of det(II - kappa G) = 0, G first, II second fundamental form
    G11, G12, G22 = 1.0 + fx * fx, fx * fy, 1.0 + fy * fy
    h11, h12, h22 = fxx * iW, fxy * iW, fyy * iW
    iW2 = iW * iW
    mean = 0.5 * (G11 * h22 + G22 * h11 - 2.0 * G12 * h12) * iW2
    gauss = (h11 * h22 - h12 * h12) * iW2
    return mean + math.sqrt(max(mean * mean - gauss, 0.0))


@njit(cache=True, nogil=True)
def evaluate_points(fn, xs, ys, out):
    """out[:, i] = f, f_x, f_y, f_xx, f_xy, f_yy at (xs[i], ys[i])."""
    d = np.empty(6)
    for i in range(xs.shape[0]):
        fn(xs[i], ys[i], d.ctypes)
        for k in range(6):
            out[k, i] = d[k]


@JIT
def rodrigues(z, R, out):
    """out = exp(A(u)) R for u = z[5:8], exact at any angle, with a series for small |u|."""
    u1, u2, u3 = z[5], z[6], z[7]
    th2 = u1 * u1 + u2 * u2 + u3 * u3
    th = math.sqrt(th2)
    if th < 1e-4:
        a = 1.0 - th2 / 6.0 * (1.0 - th2 / 20.0)
        b = 0.5 - th2 / 24.0 * (1.0 - th2 / 30.0)
    else:
        a = math.sin(th) / th
        h = math.sin(0.5 * th) / th
        b = 2.0 * h * h
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


@JIT
def record(rows, i, t, z, R, probe, p):
    """Write one trajectory row (the CSV columns of DESIGN §5)."""
    r, m, g0 = p[0], p[1], p[2]
    n1, n2, n3 = probe[0], probe[1], probe[2]
    o1, o2, o3 = probe[3], probe[4], probe[5]
    rows[i, 0] = t
    rows[i, 1] = z[0]
    rows[i, 2] = z[1]
    rows[i, 3] = z[0] + r * n1
    rows[i, 4] = z[1] + r * n2
    cz = probe[8] + r * n3
    rows[i, 5] = cz
    rows[i, 6] = r * (o2 * n3 - o3 * n2)
    rows[i, 7] = r * (o3 * n1 - o1 * n3)
    rows[i, 8] = r * (o1 * n2 - o2 * n1)
    rows[i, 9], rows[i, 10], rows[i, 11] = o1, o2, o3
    for a in range(3):
        for b in range(3):
            rows[i, 12 + 3 * a + b] = R[a, b]
    rows[i, 21] = 0.5 * (o1 * z[2] + o2 * z[3] + o3 * z[4]) + m * g0 * cz
    rows[i, 22] = probe[6]


@JIT
def record_last(rows, ints, t, z, R, probe, p):
    """A run stopped by the physics: its last valid state (the current one) is the last row."""
    if ints[I_LAST_RECORDED] != ints[I_STEPS]:
        record(rows, ints[I_ROWS], t, z, R, probe, p)
        ints[I_ROWS] += 1
        ints[I_LAST_RECORDED] = ints[I_STEPS]


SEGMENT_SAMPLES = 8  # fit checks between the ends of a step whose contact point raced


@JIT
def _fit_along_segment(fn, d, r, z, zn, h, speed0_sq, speed1_sq):
    """r * kappa inside the step, if the contact point moved farther than its end speeds explain.

    Near the no-fit boundary the contact point speeds up without bound, so a fixed step can
    jump across a thin no-fit region with both ends fitting. Such a step moves the contact
    point much farther than h times its speed at either end; then the fit is sampled along
    the straight segment between the two contact points. speed0_sq, speed1_sq: squared
    contact-point speeds at the two ends. Returns (largest r*kappa, x, y).
    """
    dx, dy = zn[0] - z[0], zn[1] - z[1]
    if dx * dx + dy * dy <= 4.0 * h * h * max(speed0_sq, speed1_sq):  # squares: no root per step
        return 0.0, 0.0, 0.0
    worst, wx, wy = 0.0, 0.0, 0.0
    for j in range(1, SEGMENT_SAMPLES + 1):
        s = j / (SEGMENT_SAMPLES + 1.0)
        x, y = z[0] + s * dx, z[1] + s * dy
        fn(x, y, data_pointer(d))
        iW = 1.0 / math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
        fit = r * largest_curvature(d[1], d[2], d[3], d[4], d[5], iW)
        if fit > worst:
            worst, wx, wy = fit, x, y
    return worst, wx, wy


@JIT
def check_step(fn, d, r, t, h, z, zn, probe, pn, K, last, ints, info, segment):
    """Whether the ball still fits over a finished step; otherwise stop with DOES_NOT_FIT.

    Three looks, cheapest first: r*kappa at the step's end; the secant curvature between the
    two contact points, -(N1 - N0).(phi1 - phi0) / |phi1 - phi0|^2, which is the normal
    curvature along the step for a smooth surface and grows like 1/step across a kink or cusp
    of a valley (abs, min, max, sqrt(abs)), whose second derivative the model cannot see;
    and, with ``segment``, samples along a step whose contact point raced. Returns True
    while the run may go on.
    """
    if pn[PROBE_FIT] >= 1.0:
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t, zn[0], zn[1], pn[PROBE_FIT])
        return False
    dx, dy, df = zn[0] - z[0], zn[1] - z[1], pn[PROBE_HEIGHT] - probe[PROBE_HEIGHT]
    bend = -((pn[0] - probe[0]) * dx + (pn[1] - probe[1]) * dy + (pn[2] - probe[2]) * df)
    chord2 = dx * dx + dy * dy + df * df
    if r * bend >= chord2 and chord2 > 0.0:  # r * (secant curvature) >= 1, without a division
        _fail(ints, info, DOES_NOT_FIT, R_SECANT_NO_FIT, t, z[0] + 0.5 * dx, z[1] + 0.5 * dy,
              r * bend / chord2)
        return False
    if segment:
        fit, fx, fy = _fit_along_segment(fn, d, r, z, zn, h, K[0, 0] ** 2 + K[0, 1] ** 2,
                                         K[last, 0] ** 2 + K[last, 1] ** 2)
        if fit >= 1.0:
            _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t, fx, fy, fit)
            return False
    return True


@JIT
def _finite(a, lo, hi):
    """a[lo:hi] all finite: a chain of cheap ands, no early exit and no floating-point chain."""
    ok = True
    for q in range(lo, hi):
        ok &= math.isfinite(a[q])
    return ok


@JIT
def _finite_row(K, row, lo, hi):
    ok = True
    for q in range(lo, hi):
        ok &= math.isfinite(K[row, q])
    return ok


@JIT
def _finite_matrix(R):
    ok = True
    for a in range(3):
        for c in range(3):
            ok &= math.isfinite(R[a, c])
    return ok


@JIT
def _fail(ints, info, status, reason, t, x, y, value):
    ints[I_STATUS] = status
    ints[I_REASON] = reason
    info[F_FAIL_T], info[F_FAIL_X], info[F_FAIL_Y], info[F_FAIL_VALUE] = t, x, y, value


@JIT
def start(fn, d, p, mk, n, z, R, K, probe, rows, ints, info):
    """Check and record the initial state; K[0] and probe describe it afterwards."""
    fn(z[0], z[1], data_pointer(d))
    if not _finite(d, 0, 6):
        _fail(ints, info, NONFINITE, R_START_UNDEFINED, 0.0, z[0], z[1], math.nan)
        return
    dynamics(fn, d, p, z, mk, K, 0, probe, True)
    ints[I_EVALS] += 1
    record(rows, 0, 0.0, z, R, probe, p)
    if not (_finite(z, 0, n) and _finite_row(K, 0, 0, n) and _finite(probe, 0, PROBE_SIZE)
            and _finite_row(rows, 0, 0, ROW_SIZE)):
        _fail(ints, info, NONFINITE, R_START_OVERFLOW, 0.0, z[0], z[1], math.nan)
        return
    ints[I_ROWS] = 1
    info[F_PREV_FORCE] = probe[PROBE_FORCE]
    if probe[PROBE_FORCE] < 0.0:
        info[F_LIFTOFF] = 0.0
    if probe[PROBE_FIT] >= 1.0:
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, 0.0, z[0], z[1], probe[PROBE_FIT])


@JIT
def combine(n, z, h, W, row, K, s, out):
    """out = z + h sum_{i<s} W[row, i] K_i, skipping zero weights (row by row: it vectorises)."""
    for q in range(n):
        out[q] = z[q]
    for i in range(s):
        c = h * W[row, i]
        if c != 0.0:
            for q in range(n):
                out[q] += c * K[i, q]


@JIT
def trial_step(fn, d, p, W, s, mk, n, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """One Runge–Kutta step of size h from z (K[0] = z'(z)) to zn, Rn.

    W holds the tableau: rows 0 .. s-1 the stage coefficients A, row s the weights b.
    Stages 1 .. last-1 fill K[1 .. last-1]; zn = z + h sum b_i K_i; then the full
    evaluation at zn (before u is reset) goes to K[last] and pn. Returns whether the new
    state is finite: 0 = yes, 1 = the motion is not, 2 = only the orientation is not.
    Counts its right-hand-side evaluations in ints[I_EVALS].
    """
    for i in range(1, last):
        combine(n, z, h, W, i, K, i, Y)
        dynamics(fn, d, p, Y, mk, K, i, pn, False)
    ints[I_EVALS] += last - 1
    combine(n, z, h, W, s, K, last, zn)
    if mk:
        rodrigues(zn, R, Rn)
    else:
        for a in range(3):
            for c in range(3):
                Rn[a, c] = zn[5 + 3 * a + c]
    if not _finite(zn, 0, 5):
        return 1
    if not (_finite(zn, 5, n) and _finite_matrix(Rn)):
        return 2
    dynamics(fn, d, p, zn, mk, K, last, pn, True)
    ints[I_EVALS] += 1
    if not (_finite_row(K, last, 0, 5) and _finite(pn, 0, PROBE_SIZE)):
        return 1
    if not _finite_row(K, last, 5, n):
        return 2
    return 0


@JIT
def accept(mk, n, t, h, z, R, K, last, probe, zn, Rn, pn, info):
    """Make the trial state the current one; K[0] becomes its derivative (u-part = omega)."""
    force = pn[PROBE_FORCE]
    if force < 0.0 and info[F_PREV_FORCE] >= 0.0 and math.isnan(info[F_LIFTOFF]):
        prev = info[F_PREV_FORCE]
        info[F_LIFTOFF] = t - h + h * prev / (prev - force)
    info[F_PREV_FORCE] = force
    for q in range(n):
        z[q] = zn[q]
        K[0, q] = K[last, q]
    if mk:  # the next step starts from u = 0, where dexp_u^-1(omega) = omega
        for q in range(3):
            z[5 + q] = 0.0
            K[0, 5 + q] = pn[PROBE_OMEGA + q]
    for a in range(3):
        for c in range(3):
            R[a, c] = Rn[a, c]
    for q in range(PROBE_SIZE):
        probe[q] = pn[q]


def work_size(n: int) -> int:
    """Length of the scratch array the stepping loops need for a state of size n."""
    return 6 + 2 * n + PROBE_SIZE + 9


@JIT
def scratch(work, n):
    """Views into the caller's scratch array: landscape values, stage state, trial state,
    trial probe and trial orientation (nothing is allocated inside the kernel)."""
    i = 6 + 2 * n
    return (work[:6], work[6:6 + n], work[6 + n:i], work[i:i + PROBE_SIZE],
            work[i + PROBE_SIZE:i + PROBE_SIZE + 9].reshape((3, 3)))


# What a step reports (trial_step and the implicit steps alike): 0 done, 1 the motion is not
# finite, 2 only the orientation is not, 3 an implicit step's stage equations did not converge.
STEP_NOT_CONVERGED = 3


# -- implicit Gauss-Legendre steps (the tableaus: implicit.py) ------------------------------------
#
# An s-stage Gauss method solves K_i = z'(z + h sum_j a_ij K_j) at every step. The iteration
# lives here, beside the explicit stage loop, so that numba's disk cache (which watches only
# the file a function is defined in) recompiles it whenever what it inlines changes.

# The stage iteration is converged once the scaled change of the stage values is at
# round-off (or the error it predicts at the rate seen is below EPSILON), or once it has
# stopped shrinking (no new smallest change in STALL iterations) below NOISE (round-off
# fluctuations); it fails when it stops shrinking above NOISE (it diverges) or has not
# converged after MAX_ITERATIONS.
EPSILON = 2.0 ** -52
ROUND_OFF = 4.0 * EPSILON
NOISE = 1e-13
STALL = 3
MAX_ITERATIONS = 60


@JIT
def collocation_step(fn, d, p, W, s, mk, n, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """One Gauss–Legendre step of size h (h < 0 steps backwards) from z to zn, Rn, with the
    arguments and codes of trial_step (the orientation always Munthe-Kaas: mk is True).

    The stage equations are solved in two parts, since u does not act on (alpha, v): first
    the motion, evaluating the right-hand side with u = 0 (so that its u-part is omega),
    then the increments u at the stages from those omegas, which needs no evaluations.

    K[0] holds z'(z); K[1 .. s] hold the stage derivatives (on entry those of the previous
    step, extrapolated with K[0] after the first step; on return this step's); K[s+1 .. 2s] is scratch
    (on return its u-part holds omega at the stages); K[last] = K[2s+1] and pn receive the
    full evaluation at zn. Counts its evaluations in ints[I_EVALS]. Returns 0 (done), 1 (the
    motion is not finite), 2 (only the orientation is not) or STEP_NOT_CONVERGED.
    """
    new = s + 1
    # starting values: extrapolated from the previous step's stages and z'(z), or z'(z) throughout
    for i in range(s):
        for q in range(5):
            acc = K[0, q]
            if ints[I_STEPS] > 0:
                acc *= W[2 * s + 1, i]
                for j in range(s):
                    acc += W[s + 1 + i, j] * K[1 + j, q]
            K[new + i, q] = acc
    for i in range(s):
        for q in range(5):
            K[1 + i, q] = K[new + i, q]
    for q in range(5, n):
        Y[q] = 0.0
    code = _iterate(s, h, z, K, W, ints, fn, d, p, Y, pn)
    if code == 0:
        code = _increments(s, h, K, W)
    if code != 0:
        return code
    for q in range(n):
        zn[q] = z[q]
    for i in range(s):
        c = h * W[s, i]
        for q in range(n):
            zn[q] += c * K[1 + i, q]
    rodrigues(zn, R, Rn)
    if not _finite(zn, 0, 5):
        return 1
    if not (_finite(zn, 5, n) and _finite_matrix(Rn)):
        return 2
    dynamics(fn, d, p, zn, True, K, last, pn, True)
    ints[I_EVALS] += 1
    if not (_finite_row(K, last, 0, 5) and _finite(pn, 0, PROBE_SIZE)):
        return 1
    if not _finite_row(K, last, 5, n):
        return 2
    return 0


@JIT
def _iterate(s, h, z, K, W, ints, fn, d, p, Y, pn):
    """Fixed-point iteration for the (alpha, v) parts of the stage derivatives K[1 .. s]."""
    new = s + 1
    best, stalled, previous = np.inf, 0, np.inf
    for _ in range(MAX_ITERATIONS):
        for i in range(s):
            for q in range(5):
                Y[q] = z[q]
            for j in range(s):
                c = h * W[i, j]
                for q in range(5):
                    Y[q] += c * K[1 + j, q]
            dynamics(fn, d, p, Y, True, K, new + i, pn, False)
        ints[I_EVALS] += s
        change = max(_scaled_change(s, h, z, K, 0, 2), _scaled_change(s, h, z, K, 2, 5))
        for i in range(s):
            for q in range(5):
                K[1 + i, q] = K[new + i, q]
        if change != change:  # the stages left the landscape's domain
            return 1
        # done when the change, or the error it predicts at the rate seen (Hairer, Lubich and
        # Wanner VIII.6: change * rate / (1 - rate)), is at round-off
        rate = change / previous  # (0 at the first iteration, which predicts nothing)
        if change <= ROUND_OFF or (0.0 < rate < 1.0 and change * rate <= EPSILON * (1.0 - rate)):
            return 0
        previous = change
        # a change passes from alpha to v and back, so it need not shrink at every
        # iteration: only STALL iterations without a new smallest change end the iteration
        if change < best:
            best, stalled = change, 0
        else:
            stalled += 1
            if stalled == STALL:  # at round-off, or not contracting
                return 0 if change <= NOISE else STEP_NOT_CONVERGED
    return STEP_NOT_CONVERGED


@JIT
def _increments(s, h, K, W):
    """The u-parts of K[1 .. s]: U_i = h sum_j a_ij dexp^-1_(U_j)(omega_j), iterated from U = 0
    (omega_j in the u-part of K[s+1+j]); no right-hand-side evaluations."""
    new = s + 1
    for i in range(s):
        for q in range(5, 8):
            K[1 + i, q] = K[new + i, q]  # dexp^-1 at U = 0
    best, stalled = np.inf, 0
    for _ in range(MAX_ITERATIONS):
        change, size = 0.0, 0.0
        for i in range(s):
            u1, u2, u3 = 0.0, 0.0, 0.0
            for j in range(s):
                c = h * W[i, j]
                u1 += c * K[1 + j, 5]
                u2 += c * K[1 + j, 6]
                u3 += c * K[1 + j, 7]
            k1, k2, k3 = dexpinv(u1, u2, u3, K[new + i, 5], K[new + i, 6], K[new + i, 7])
            change = max(change, abs(k1 - K[1 + i, 5]), abs(k2 - K[1 + i, 6]), abs(k3 - K[1 + i, 7]))
            size = max(size, abs(k1), abs(k2), abs(k3))
            # (Gauss-Seidel: later stages see this one's new value at once)
            K[1 + i, 5], K[1 + i, 6], K[1 + i, 7] = k1, k2, k3
        if not change <= size * 1e300:
            return 2
        if change <= ROUND_OFF * size:
            return 0
        if change < best:
            best, stalled = change, 0
        else:
            stalled += 1
            if stalled == STALL:
                return 0 if change <= NOISE * size else STEP_NOT_CONVERGED
    return STEP_NOT_CONVERGED


@JIT
def _scaled_change(s, h, z, K, lo, hi):
    """The largest change h |K_new - K_old| of a stage value in z[lo:hi] (alpha or v), relative
    to the size of that part of the state plus how far the stages move it; nan if an
    iterate is not finite."""
    scale = 0.0
    for q in range(lo, hi):
        scale = max(scale, abs(z[q]))
        for i in range(s):
            scale = max(scale, abs(h * K[s + 1 + i, q]))
    worst = 0.0
    for q in range(lo, hi):
        for i in range(s):
            delta = abs(h * (K[s + 1 + i, q] - K[1 + i, q]))
            if not delta < np.inf:
                return np.nan
            if delta > 0.0:  # (a part at rest whose stages still move: a large change)
                worst = max(worst, delta / scale if scale > 0.0 else 1.0)
    return worst




def fixed_steps(mk: bool, implicit: bool):
    """The fixed-step loop for one orientation scheme and one kind of step: with mk, the
    state size n and the step (trial_step for the explicit tableaus, collocation_step for
    the implicit ones) constants of the compiled code, the stage loops unroll as in
    hand-written C.
    """
    n = state_size(mk)

    @JIT
    def advance(fn, W, p, dt, t_end, n_steps, every, max_steps, z, R, K, probe, rows, ints, info, work):
        """Run up to ``max_steps`` further fixed steps; all run state lives in the arrays passed in.

        K's last row receives the evaluation at the new state (for an explicit tableau it has one
        row more than the tableau has stages). On the
        first call (no rows yet) the initial state is checked and recorded. The run stops early,
        with ints[I_STATUS] set, where the state turns non-finite or the ball no longer fits;
        the last valid state is then the last row.
        """
        s, last_row = W.shape[1], K.shape[0] - 1
        d, Y, zn, pn, Rn = scratch(work, n)

        if ints[I_ROWS] == 0:
            start(fn, d, p, mk, n, z, R, K, probe, rows, ints, info)
            if ints[I_STATUS] != RUNNING:
                return

        k0 = ints[I_STEPS]
        k_stop = min(n_steps, k0 + max_steps)
        for k in range(k0 + 1, k_stop + 1):
            last = k == n_steps
            h = t_end - (k - 1) * dt if last else dt
            t = t_end if last else k * dt
            if implicit:
                bad = collocation_step(fn, d, p, W, s, mk, n, h, z, R, K, last_row, Y, zn, Rn, pn, ints)
            else:
                bad = trial_step(fn, d, p, W, s, mk, n, h, z, R, K, last_row, Y, zn, Rn, pn, ints)
            if bad == STEP_NOT_CONVERGED:
                _fail(ints, info, NONFINITE, R_NOT_CONVERGED, t, z[0], z[1], h)
            elif bad:
                _fail(ints, info, NONFINITE, R_ORIENTATION if bad == 2 else R_UNDEFINED, t, z[0], z[1],
                      0.0 if mk else 1.0)
            else:
                check_step(fn, d, p[0], t, h, z, zn, probe, pn, K, last_row, ints, info, True)
            if ints[I_STATUS] != RUNNING:
                record_last(rows, ints, (k - 1) * dt, z, R, probe, p)
                return
            accept(mk, n, t, h, z, R, K, last_row, probe, zn, Rn, pn, info)
            ints[I_STEPS] = k
            if k - ints[I_LAST_RECORDED] == every or last:  # (no division in the loop)
                record(rows, ints[I_ROWS], t, z, R, probe, p)
                ints[I_ROWS] += 1
                ints[I_LAST_RECORDED] = k
        if ints[I_STEPS] == n_steps:
            ints[I_STATUS] = OK

    return advance


# advance(fn, W, p, ...) of the explicit tableaus by scheme: ADVANCE[munthe_kaas]; of the
# implicit ones (always Munthe-Kaas): ADVANCE_IMPLICIT
ADVANCE = {mk: fixed_steps(mk, False) for mk in (True, False)}
ADVANCE_IMPLICIT = fixed_steps(True, True)


@JIT
def advance_adaptive(fn, W, p, err_exp, t_end, record_dt, rtol, atol, max_steps, z, R, K, probe, rows,
                     ints, info, work):
    """Run up to ``max_steps`` further trial steps of an embedded pair with step-size control
    (Munthe-Kaas only); info[F_TIME] is the time reached and info[F_H] the next step to try.

    W holds the pair: rows 0 .. s-1 the stage coefficients, row s the weights b (last one
    zero: the last stage is the evaluation at the new state, "first same as last") and
    row s+1 the error weights b - b_hat. The error of a step is measured in alpha and v
    relative to rtol |value| + atol, and in u against rtol + atol (R's entries are of size 1).
    Rows land exactly on the multiples of record_dt and on t_end (steps are shortened to
    reach them), or on every accepted step when record_dt is 0. Returns early, still
    running, when ``rows`` is full: the caller grows it and calls again.
    """
    n = MK_SIZE
    s = W.shape[1]
    d, Y, zn, pn, Rn = scratch(work, n)
    if ints[I_ROWS] == 0:
        start(fn, d, p, True, n, z, R, K, probe, rows, ints, info)
        info[F_TIME] = 0.0
        if ints[I_STATUS] != RUNNING:
            return
    t, h = info[F_TIME], info[F_H]
    retry = False  # right after a rejection the step may shrink but not grow (Hairer's rule)
    for _ in range(max_steps):
        if ints[I_ROWS] >= rows.shape[0] - 1:  # keep one row for the last valid state
            break
        t_out = t_end
        if record_dt > 0.0:
            t_out = min(ints[I_ROWS] * record_dt, t_end)
            if t_end - t_out < 1e-9 * record_dt:
                t_out = t_end
        land = t + 1.1 * h >= t_out  # stretch a little rather than leave a sliver
        hs = t_out - t if land else h
        bad = trial_step(fn, d, p, W, s, True, n, hs, z, R, K, s - 1, Y, zn, Rn, pn, ints)
        err = math.inf
        if not bad:
            acc = 0.0
            for q in range(n):
                e = 0.0
                for i in range(s):
                    e += W[s + 1, i] * K[i, q]
                scale = atol + rtol * (max(abs(z[q]), abs(zn[q])) if q < 5 else 1.0)
                acc += (hs * e / scale) ** 2
            err = math.sqrt(acc / n)
        if not err <= 1.0:  # rejected (or not finite): try again with a smaller step
            ints[I_REJECTED] += 1
            retry = True
            h = hs * max(MIN_FACTOR, SAFETY * err ** err_exp) if err < math.inf else MIN_FACTOR * hs
            ints[I_NONFINITE] += 1 if bad else 0
            if ints[I_NONFINITE] >= NONFINITE_TRIES:
                _fail(ints, info, NONFINITE, R_ORIENTATION if bad == 2 else R_UNDEFINED, t, z[0], z[1], 0.0)
            elif h <= MIN_STEP * max(1.0, abs(t)):
                _fail(ints, info, NONFINITE, R_STEP_UNDERFLOW, t, z[0], z[1], h)
            else:
                continue
        else:  # error control keeps adaptive steps short where the contact point races
            check_step(fn, d, p[0], t + hs, hs, z, zn, probe, pn, K, s - 1, ints, info, False)
        if ints[I_STATUS] != RUNNING:
            record_last(rows, ints, t, z, R, probe, p)
            break
        t = t_out if land else t + hs
        accept(True, n, t, hs, z, R, K, s - 1, probe, zn, Rn, pn, info)
        ints[I_STEPS] += 1
        grown = hs * min(1.0 if retry else MAX_FACTOR, SAFETY * err ** err_exp if err > 0.0 else MAX_FACTOR)
        h = max(h, grown) if land else grown
        retry = False
        if h <= MIN_STEP * max(1.0, abs(t)):  # creeping up to a singularity (Zeno)
            _fail(ints, info, NONFINITE, R_STEP_UNDERFLOW, t, z[0], z[1], h)
        if land or record_dt == 0.0:
            record(rows, ints[I_ROWS], t, z, R, probe, p)
            ints[I_ROWS] += 1
            ints[I_LAST_RECORDED] = ints[I_STEPS]
        if ints[I_STATUS] != RUNNING:
            record_last(rows, ints, t, z, R, probe, p)
            break
        if t == t_end:
            ints[I_STATUS] = OK
            break
    info[F_TIME], info[F_H] = t, h
