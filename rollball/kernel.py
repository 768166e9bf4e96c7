"""The compiled stepping kernel: the reduced equations of motion, one Runge–Kutta stage
loop for every tableau (classic and Munthe-Kaas), fixed or adaptive steps, validity checks
and recording.

Everything here is landscape-independent and compiled once; the landscape arrives as the
address of its compiled code ``f(x, y, out)`` writing f and its first and second derivatives
to out[0:6] (``landscape``). Python calls the kernel only through the entry points at the end
of this file (``ENTRIES``), which machine_code.py compiles: from the LLVM code numba made of
them, shipped with RollBall, where it fits this machine, else with numba (cached on disk).

State vector z: contact point (x, y), angular momentum about the contact point v (3),
then either u (3, the Munthe-Kaas Lie-algebra increment, zero at each step start; the
adaptive pairs carry omega there instead and R follows it, ``turn``) or
R (9, row-major, integrated as a plain matrix by the classic scheme), or nothing: a state
of MOTION_SIZE carries no orientation at all (sweeps, whose outcomes do not need it). Stage derivatives
are the rows of K; the hot loop indexes whole arrays and never slices them.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import carray, njit, types
from numba.extending import intrinsic

LANDSCAPE_SIGNATURE = types.void(types.float64, types.float64, types.CPointer(types.float64))

# numpy's error model: a division by zero gives inf/nan (caught by the checks) instead of
# a branch and an exception on every division. Nothing here allocates, so it runs without
# numba's reference counting (_nrt=False): the counting of arrays handed between the helpers
# would cost as much as a stage.
#
# What is inlined where, and why (numba's cold compile is what a machine without the shipped
# code waits for once, and what kernel_build takes; the step's speed is the ratio to
# hand-written C):
# - JIT, numba's own inlining (the helper's code is copied into every caller before typing):
#   the small per-stage and per-step helpers (dynamics, combine, rodrigues, the finiteness
#   checks, step_events, accept, record, ...). Each copy costs compile time, so JIT helpers
#   are kept small and called from few places.
# - STEP, compiled once as a function of its own and inlined by LLVM (forceinline) into the
#   loops that call it: the explicit step, one per state layout (``_trial_step``), which holds
#   most of the code. Inlined by numba it was copied into every loop; called, a step cost a
#   fifth more.
# - COLD, compiled once and called: what runs once per run, per recorded row or per event
#   (start, the event location, the last valid state), the implicit step, whose stage
#   iteration outweighs a call, the step of the searches inside a step (``search_step``), and
#   the fixed-step loop ``advance``, which the sweeps' batch loop calls once per chunk of steps.
#   (numba still compiles a called function again into each caller's machine code: LLVM's share
#   of a cold compile grows with how many loops reach a function, not with how often it runs.)
# One signature each: a constant bool or int passed to a compiled function makes numba compile
# it anew for that constant, so flags passed to COLD functions are floats (EXPLICIT/IMPLICIT,
# the event kinds) or read from the arrays (shape_of).
JIT = njit(cache=True, nogil=True, error_model="numpy", inline="always", fastmath={"contract"},
           _nrt=False)
COLD = njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
STEP = njit(cache=True, nogil=True, error_model="numpy", forceinline=True, fastmath={"contract"}, _nrt=False)


@intrinsic
def data_pointer(typingctx, array):
    """The data pointer of an array, without the reference counting of ``array.ctypes``
    (which costs more than the landscape call itself). The caller keeps the array alive."""
    def codegen(context, builder, signature, args):
        return context.make_array(signature.args[0])(context, builder, args[0]).data
    return types.CPointer(array.dtype)(array), codegen


@intrinsic
def landscape(typingctx, address, x, y, out):
    """Call the landscape's compiled code (LANDSCAPE_SIGNATURE) at ``address``: f and its
    derivatives at (x, y) into out[0:6]. An address, not a function object, so that the
    kernel's compiled code holds nothing of this process and can be shipped."""
    def codegen(context, builder, signature, args):
        double = ir.DoubleType()
        code = ir.FunctionType(ir.VoidType(), [double, double, double.as_pointer()])
        builder.call(builder.inttoptr(args[0], code.as_pointer()), args[1:])
        return context.get_dummy_value()
    return types.void(types.int64, types.float64, types.float64, types.CPointer(types.float64)), codegen


def _pointer_to(dtype):
    @intrinsic
    def pointer(typingctx, address):
        """The address (an int64) as a pointer to numbers of this dtype."""
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(signature.return_type))
        return types.CPointer(dtype)(types.int64), codegen
    return pointer


float_pointer, int_pointer = _pointer_to(types.float64), _pointer_to(types.int64)


@intrinsic
def as_floats(typingctx, pointer):
    """The same memory as a pointer to float64 (the entry points' float arguments)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(signature.return_type))
    return types.CPointer(types.float64)(pointer), codegen


# What one evaluation learns about a state besides its derivative ("probe").
PROBE_N = 0        # unit normal N (3)
PROBE_OMEGA = 3    # angular velocity omega (3)
PROBE_FORCE = 6    # normal force F.N
PROBE_FIT = 7      # r * largest principal curvature (the ball fits while < 1)
PROBE_HEIGHT = 8   # f(x, y)
PROBE_FIT_LO = 9   # r * smallest principal curvature (< 0 where the surface bends away)
PROBE_SIZE = 10

# Integer run counters (``ints``) and float run facts (``info``).
# I_DENSE: the step whose extra dense-output stages K holds (they are computed on demand).
# I_HELD: 1 once a stopped step's last valid state is already in zn, Rn, pn (``fold_search``).
# I_RETRY: 1 while the adaptive step follows a rejection (kept between calls).
(I_STEPS, I_ROWS, I_LAST_RECORDED, I_STATUS, I_REJECTED, I_NONFINITE, I_EVALS, I_REASON, I_DENSE, I_HELD,
 I_RETRY) = range(11)
# F_LIFTOFF first time F.N < 0 (located on the dense output), at (F_LIFT_X, F_LIFT_Y);
# F_LIFT_KINK 1 where it is a convex kink of the surface rather than F.N crossing 0.
# F_FOLD: when the last step's ends say the contact point reaches the edge of the no-fit region.
F_LIFTOFF, F_LIFT_X, F_LIFT_Y, F_LIFT_KINK, F_FAIL_T, F_FAIL_X, F_FAIL_Y, F_FAIL_VALUE, F_TIME, F_H, F_FOLD = range(11)
INTS_SIZE, INFO_SIZE = 11, 11

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
R_KINK = 8                 # a kink or cusp of a valley (value: the angle the normal turns, rad)
R_HEIGHT_JUMP = 9          # the height jumps (value: the jump, m)
R_NOT_CONVERGED = 10       # an implicit step's stage equations did not converge (value: the step)

ROW_SIZE = 23  # t, x, y, c(3), c'(3), omega(3), R(9), energy, normal force
ROW_CENTER, ROW_VELOCITY, ROW_ENERGY, ROW_FORCE = 3, 6, 21, 22  # where ``record`` writes them

# Step-size control of the embedded pairs: the next step is h * SAFETY * err^exponent,
# bounded to [MIN_FACTOR, MAX_FACTOR] times h, with exponent -1/(q + 1) for an error
# estimate of order q (the method's ``error_exponent``).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 5.0
MIN_STEP = 1e-13  # adaptive steps below this (relative to t, or absolute below t = 1) stop the run
# An adaptive step that turns the state non-finite is retried 5 times smaller; after this
# many such steps in a run the ball is pressing against the end of the landscape, and the
# run stops as a fixed-step run would at the first.
NONFINITE_TRIES = 50

MOTION_SIZE, MK_SIZE, CLASSIC_SIZE = 5, 8, 14


def state_size(munthe_kaas: bool) -> int:
    return MK_SIZE if munthe_kaas else CLASSIC_SIZE


P_TURN = 7  # p[P_TURN] > 0: omega is carried instead of u, R follows it to this tolerance (rad)


def parameters(radius: float, mass: float, gravity: float, turn: float = 0.0) -> np.ndarray:
    """The ball and gravity as the kernel reads them, with the constants it would otherwise
    recompute at every evaluation: r, m, g0, 5/(7 m r^2), m r, m r^2, m g0; then ``turn``:
    0 for the Munthe-Kaas increment u in the state, else the tolerance (rad) for the
    orientation's sub-steps when omega is carried instead (``turn``: the adaptive pairs)."""
    r, m, g0 = radius, mass, gravity
    return np.array([r, m, g0, 5.0 / (7.0 * m * r * r), m * r, m * r * r, m * g0,
                     turn + 0.0 * r])   # (+ 0 r: a column like the others where r is an array, sweeps)


# What ``dynamics`` computes: the stage derivative alone, or also the probe. Floats, like mk
# there (1.0 Munthe-Kaas): numba would compile it anew for every constant bool passed.
STAGE, FULL = 0.0, 1.0


@STEP
def dynamics(fn, d, p, z, mk, K, row, probe, full):
    """K[row] = z'(z); with ``full`` (FULL) also fill ``probe`` (normal, omega, F.N, r*kappa,
    height). Compiled once (numba's inlining copied it into every caller), inlined by LLVM."""
    r, k, mr, mr2, mg = p[0], p[3], p[4], p[5], p[6]
    landscape(fn, z[0], z[1], data_pointer(d))
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
    if K.shape[1] == MOTION_SIZE:  # no orientation carried
        pass
    elif mk != 0.0 and p[P_TURN] > 0.0:
        # omega' = k (v' + nv' N + nv N'), N' = d: omega carried as a quadrature of the motion
        e1, e2, e3 = K[row, 2], K[row, 3], K[row, 4]
        nve = 2.5 * (d1 * v1 + d2 * v2 + d3 * v3 + n1 * e1 + n2 * e2 + n3 * e3)
        K[row, 5] = k * (e1 + nve * n1 + nv * d1)
        K[row, 6] = k * (e2 + nve * n2 + nv * d2)
        K[row, 7] = k * (e3 + nve * n3 + nv * d3)
    elif mk != 0.0:
        K[row, 5], K[row, 6], K[row, 7] = dexpinv(z[5], z[6], z[7], o1, o2, o3)
    else:
        # R' = A(omega) R, column by column
        for j in range(3):
            q1, q2, q3 = z[5 + j], z[8 + j], z[11 + j]
            K[row, 5 + j] = o2 * q3 - o3 * q2
            K[row, 8 + j] = o3 * q1 - o1 * q3
            K[row, 11 + j] = o1 * q2 - o2 * q1
    if full != 0.0:
        probe[0], probe[1], probe[2] = n1, n2, n3
        probe[3], probe[4], probe[5] = o1, o2, o3
        # F.N = m (c'' - g).N with c''.N = r (omega x N').N
        probe[6] = mr * ((o2 * d3 - o3 * d2) * n1 + (o3 * d1 - o1 * d3) * n2
                         + (o1 * d2 - o2 * d1) * n3) + mg * n3
        hi, lo = curvatures(fx, fy, fxx, fxy, fyy, iW)
        probe[7] = r * hi
        probe[8] = d[0]
        probe[9] = r * lo


# Below this |u|^2 the coefficient of dexp^-1 is its series (to round-off for |u| < 0.1).
DEXPINV_SERIES = 1e-2


@JIT
def dexpinv(u1, u2, u3, o1, o2, o3):
    """dexp_u^-1(omega) = omega - 1/2 u x omega + c(theta) u x (u x omega) on so(3), exact:
    c = (1 - (theta/2) cot(theta/2)) / theta^2, theta = |u|, with its series
    1/12 + theta^2/720 + theta^4/30240 + theta^6/1209600 for small theta. (The truncation
    after 1/12 limits Munthe-Kaas to order 5; the exact inverse to none.)"""
    th2 = u1 * u1 + u2 * u2 + u3 * u3
    if th2 < DEXPINV_SERIES:
        c = 1.0 / 12.0 + th2 * (1.0 / 720.0 + th2 * (1.0 / 30240.0 + th2 * (1.0 / 1209600.0)))
    else:
        x = 0.5 * math.sqrt(th2)
        c = (1.0 - x * math.cos(x) / math.sin(x)) / th2
    c1, c2, c3 = u2 * o3 - u3 * o2, u3 * o1 - u1 * o3, u1 * o2 - u2 * o1
    return (o1 - 0.5 * c1 + c * (u2 * c3 - u3 * c2),
            o2 - 0.5 * c2 + c * (u3 * c1 - u1 * c3),
            o3 - 0.5 * c3 + c * (u1 * c2 - u2 * c1))


@JIT
def curvatures(fx, fy, fxx, fxy, fyy, iW):
    """The largest and smallest principal curvature (> 0 bending up towards the ball),
    iW = 1 / sqrt(1 + f_x² + f_y²)."""
    # roots of det(II - kappa G) = 0, G first, II second fundamental form
    G11, G12, G22 = 1.0 + fx * fx, fx * fy, 1.0 + fy * fy
    h11, h12, h22 = fxx * iW, fxy * iW, fyy * iW
    iW2 = iW * iW
    mean = 0.5 * (G11 * h22 + G22 * h11 - 2.0 * G12 * h12) * iW2
    gauss = (h11 * h22 - h12 * h12) * iW2
    root = math.sqrt(max(mean * mean - gauss, 0.0))
    return mean + root, mean - root


@COLD
def evaluate_points(fn, xs, ys, out, d):
    """out[:, i] = f, f_x, f_y, f_xx, f_xy, f_yy at (xs[i], ys[i]); d (6): scratch."""
    for i in range(xs.shape[0]):
        landscape(fn, xs[i], ys[i], data_pointer(d))
        for k in range(6):
            out[k, i] = d[k]


@JIT
def rodrigues(u1, u2, u3, R, out):
    """out = exp(A(u)) R, exact at any angle, with a series for small |u| (out may be R)."""
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


# -- the orientation of the adaptive pairs ----------------------------------------------------
#
# R does not act on the motion: R' = A(omega(t)) R with omega a function of (alpha, v). The
# pairs therefore carry omega itself in z[5:8] (its derivative from the motion's, ``dynamics``),
# set to the exact omega at every step start; the step's dense output then gives omega at any
# time inside it, to the pair's order. ``turn`` carries R through the step in sub-steps, each by
# the 6th-order Magnus integrator on the three Gauss points (Blanes, Casas and Ros 2000), as
# many as keep its error below p[P_TURN] (TURN_SHARE of rtol). Integrated as u by the pair
# itself, the orientation's error per step grows with the angle turned (u' = dexp_u^-1(omega)
# is the stiffest part of the system where the axis turns) and u would set the step; here the
# motion does.

GAUSS_SPREAD = math.sqrt(15.0) / 10.0   # the Gauss points of [0, 1]: 1/2 -+ this, and 1/2
MAX_TURNS = 1e6                         # sub-steps in one span at most (else R is not finite)
MAGNUS_ERROR = 5e-5                     # Magnus 6's error in R over a span: at most this times
                                        # phi^4 |C| (measured 2e-5 - 6e-5; ``turn``)
# The orientation's tolerance per step, as a share of rtol: the pairs' steps, taken on by the
# higher-order solution, are far more accurate than their estimate (rtol) says.
TURN_SHARE = 1e-2


@JIT
def magnus6(a1, a2, a3, b1, b2, b3, c1, c2, c3, h):
    """The commutator terms of the 6th-order Magnus increment over a step h, from omega at its
    three Gauss points a, b (the middle), c: Omega = (the integral of omega) + these, with
    [X, Y] = X x Y on so(3). (The integral by the Gauss points is alpha1 + alpha3 / 12.)"""
    q = h * math.sqrt(15.0) / 3.0
    s = h * 10.0 / 3.0
    x1, x2, x3 = h * b1, h * b2, h * b3                                   # alpha1
    y1, y2, y3 = q * (c1 - a1), q * (c2 - a2), q * (c3 - a3)              # alpha2
    w1, w2, w3 = s * (c1 - 2.0 * b1 + a1), s * (c2 - 2.0 * b2 + a2), s * (c3 - 2.0 * b3 + a3)  # alpha3
    k1, k2, k3 = x2 * y3 - x3 * y2, x3 * y1 - x1 * y3, x1 * y2 - x2 * y1  # C1 = [alpha1, alpha2]
    f1, f2, f3 = 2.0 * w1 + k1, 2.0 * w2 + k2, 2.0 * w3 + k3
    m1 = y1 - (x2 * f3 - x3 * f2) / 60.0                                  # alpha2 + C2
    m2 = y2 - (x3 * f1 - x1 * f3) / 60.0
    m3 = y3 - (x1 * f2 - x2 * f1) / 60.0
    l1, l2, l3 = -20.0 * x1 - w1 + k1, -20.0 * x2 - w2 + k2, -20.0 * x3 - w3 + k3
    return (l2 * m3 - l3 * m2) / 240.0, (l3 * m1 - l1 * m3) / 240.0, (l1 * m2 - l2 * m1) / 240.0


def stage_rows(stages: int) -> int:
    """The rows of K for a method whose W has ``stages`` rows: those, omega's polynomial
    (three rows, ``omega_polynomial``) and a spare last row for evaluations on the dense output."""
    return stages + 4


@JIT
def omega_polynomial(h, P, K):
    """omega's dense output over the step as a polynomial in theta: omega(t + theta h) =
    omega(t) + sum_k c_k theta^(k+1), component q of c_k into K[P.shape[0] + q, k]."""
    base = P.shape[0]
    for q in range(3):
        for k in range(P.shape[1]):
            c = 0.0
            for i in range(P.shape[0]):
                c += P[i, k] * K[i, 5 + q]
            K[base + q, k] = h * c


@JIT
def omega_at(z, P, K, theta):
    """omega at t + theta h (``omega_polynomial``; omega(t) in z[5:8])."""
    base = P.shape[0]
    o1, o2, o3 = 0.0, 0.0, 0.0
    for k in range(P.shape[1] - 1, -1, -1):
        o1 = (o1 + K[base, k]) * theta
        o2 = (o2 + K[base + 1, k]) * theta
        o3 = (o3 + K[base + 2, k]) * theta
    return z[5] + o1, z[6] + o2, z[7] + o3


@JIT
def omega_integral(z, h, P, K, theta):
    """The integral of omega from t to t + theta h (exact: a polynomial, ``omega_polynomial``)."""
    base = P.shape[0]
    o1, o2, o3 = 0.0, 0.0, 0.0
    for k in range(P.shape[1] - 1, -1, -1):
        o1 = (o1 + K[base, k] / (k + 2)) * theta
        o2 = (o2 + K[base + 1, k] / (k + 2)) * theta
        o3 = (o3 + K[base + 2, k] / (k + 2)) * theta
    return h * (z[5] + o1) * theta, h * (z[6] + o2) * theta, h * (z[7] + o3) * theta


@COLD
def turn(p, z, R, h, P, K, theta0, theta1, out):
    """out = R (the orientation at t + theta0 h) carried to t + theta1 h along omega's dense
    output (out may be R), the polynomial ``omega_polynomial`` wrote into K with the step's
    stages. The sub-steps: Magnus 6's error in one of m sub-steps of a span turning by phi rad
    is MAGNUS_ERROR phi^4 |C| / m^7, C = [phi_mid, phi_end - phi_start] the span's commutator
    (how far its axis turns), so m is chosen for a total of p[P_TURN] (the tolerance): a span
    whose axis keeps its direction is one sub-step, however far it turns."""
    x0, x1 = theta0, theta1
    a1, a2, a3 = omega_at(z, P, K, x0)
    b1, b2, b3 = omega_at(z, P, K, 0.5 * (x0 + x1))
    c1, c2, c3 = omega_at(z, P, K, x1)
    span = h * (x1 - x0)
    phi = abs(span) * math.sqrt(max(a1 * a1 + a2 * a2 + a3 * a3, b1 * b1 + b2 * b2 + b3 * b3,
                                    c1 * c1 + c2 * c2 + c3 * c3))
    e1, e2, e3 = c1 - a1, c2 - a2, c3 - a3
    bend = span * span * math.sqrt((b2 * e3 - b3 * e2) ** 2 + (b3 * e1 - b1 * e3) ** 2 + (b1 * e2 - b2 * e1) ** 2)
    turns = math.ceil((MAGNUS_ERROR * phi ** 4 * bend / p[P_TURN]) ** (1.0 / 6.0))
    if not turns <= MAX_TURNS:
        for a in range(3):
            for c in range(3):
                out[a, c] = math.nan
        return
    m = max(turns, 1)
    for a in range(3):
        for c in range(3):
            out[a, c] = R[a, c]
    dx = (x1 - x0) / m
    q1, q2, q3 = omega_integral(z, h, P, K, x0)
    for j in range(m):
        x = x0 + j * dx
        a1, a2, a3 = omega_at(z, P, K, x + (0.5 - GAUSS_SPREAD) * dx)
        b1, b2, b3 = omega_at(z, P, K, x + 0.5 * dx)
        c1, c2, c3 = omega_at(z, P, K, x + (0.5 + GAUSS_SPREAD) * dx)
        u1, u2, u3 = magnus6(a1, a2, a3, b1, b2, b3, c1, c2, c3, h * dx)
        e1, e2, e3 = omega_integral(z, h, P, K, x1 if j == m - 1 else x + dx)
        rodrigues(u1 + e1 - q1, u2 + e2 - q2, u3 + e3 - q3, out, out)
        q1, q2, q3 = e1, e2, e3


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


@COLD
def record_last(rows, ints, t, z, R, probe, p):
    """A run stopped by the physics: its last valid state (the current one) is the last row."""
    if ints[I_LAST_RECORDED] != ints[I_STEPS]:
        record(rows, ints[I_ROWS], t, z, R, probe, p)
        ints[I_ROWS] += 1
        ints[I_LAST_RECORDED] = ints[I_STEPS]


@JIT
def shape_of(z):
    """(n, munthe_kaas) read from the state's length at run time: the functions compiled once
    (COLD) take them so, not as the constants of the loops, which would compile them anew
    for every loop."""
    n = z.shape[0]
    return n, n == MK_SIZE


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


@COLD
def start(fn, d, p, z, R, K, probe, rows, ints, info):
    """Check and record the initial state; K[0] and probe describe it afterwards."""
    n, mk = shape_of(z)
    landscape(fn, z[0], z[1], data_pointer(d))
    if not _finite(d, 0, 6):
        _fail(ints, info, NONFINITE, R_START_UNDEFINED, 0.0, z[0], z[1], math.nan)
        return
    # (np.int64(0): a literal 0 would compile dynamics anew for it)
    dynamics(fn, d, p, z, 1.0 if mk else 0.0, K, np.int64(0), probe, FULL)
    ints[I_EVALS] += 1
    ints[I_DENSE] = -1
    if mk and p[P_TURN] > 0.0:
        for q in range(3):
            z[5 + q] = probe[PROBE_OMEGA + q]
    record(rows, 0, 0.0, z, R, probe, p)
    if not (_finite(z, 0, n) and _finite_row(K, 0, 0, n) and _finite(probe, 0, PROBE_SIZE)
            and _finite_row(rows, 0, 0, ROW_SIZE)):
        _fail(ints, info, NONFINITE, R_START_OVERFLOW, 0.0, z[0], z[1], math.nan)
        return
    ints[I_ROWS] = 1
    if probe[PROBE_FORCE] < 0.0:
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = 0.0, z[0], z[1], 0.0
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


def _trial_step(n: int, mk: bool):
    """The explicit step for one state layout: with n and mk constants of the compiled code,
    its stage loops unroll as in hand-written C."""
    orientation = n > MOTION_SIZE

    @STEP
    def trial_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
        """One Runge–Kutta step of size h from z (K[0] = z'(z)) to zn, Rn.

        W holds the method (see ``Tableau.kernel_arrays``): rows 1 .. last-1 the stage
        coefficients, row ``last`` the weights b. Stages 1 .. last-1 fill K[1 .. last-1];
        zn = z + h sum b_i K_i; then the full evaluation at zn (before u is reset) goes to
        K[last] and pn. Returns whether the new state is finite: 0 = yes, 1 = the motion is
        not, 2 = only the orientation is not. Counts its evaluations in ints[I_EVALS].
        Carrying omega (p[P_TURN] > 0), Rn follows omega's dense output (P) through the step,
        after the evaluation at zn and the dense-output stages (rows of W after ``last``).
        """
        for i in range(1, last):
            combine(n, z, h, W, i, K, i, Y)
            dynamics(fn, d, p, Y, 1.0 if mk else 0.0, K, i, pn, STAGE)
        ints[I_EVALS] += last - 1
        combine(n, z, h, W, last, K, last, zn)
        carry = orientation and mk and p[P_TURN] > 0.0
        if carry:  # (finite until carried, after the evaluation at zn)
            for a in range(3):
                for c in range(3):
                    Rn[a, c] = R[a, c]
        elif orientation and mk:
            rodrigues(zn[5], zn[6], zn[7], R, Rn)
        elif orientation:
            for a in range(3):
                for c in range(3):
                    Rn[a, c] = zn[5 + 3 * a + c]
        code = end_of_step(fn, d, p, mk, n, orientation, zn, Rn, K, last, pn, ints)
        if carry and code == 0:
            code = carry_orientation(fn, d, p, W, P, h, z, R, K, last, Y, Rn, pn, ints)
        return code

    return trial_step


trial_step_mk = _trial_step(MK_SIZE, True)
trial_step_classic = _trial_step(CLASSIC_SIZE, False)
trial_step_motion = _trial_step(MOTION_SIZE, False)


@JIT
def trial_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """The explicit step (``_trial_step``) for z's layout: MK_SIZE, CLASSIC_SIZE or MOTION_SIZE."""
    n = z.shape[0]
    if n == MK_SIZE:
        return trial_step_mk(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if n == CLASSIC_SIZE:
        return trial_step_classic(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    return trial_step_motion(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)


@JIT
def end_of_step(fn, d, p, mk, n, orientation, zn, Rn, K, last, pn, ints):
    """The new state zn, Rn of a step checked, then evaluated in full into K[last] and pn
    (counted in ints[I_EVALS]). Returns the step's report (below): 0, 1 or 2."""
    if not _finite(zn, 0, 5):
        return 1
    if orientation and not (_finite(zn, 5, n) and _finite_matrix(Rn)):
        return 2
    dynamics(fn, d, p, zn, 1.0 if mk else 0.0, K, last, pn, FULL)
    ints[I_EVALS] += 1
    if not (_finite_row(K, last, 0, 5) and _finite(pn, 0, PROBE_SIZE)):
        return 1
    if not _finite_row(K, last, 5, n):
        return 2
    return 0


@COLD
def carry_orientation(fn, d, p, W, P, h, z, R, K, last, Y, Rn, pn, ints):
    """The end of an explicit step carrying omega, once its new state is evaluated: the
    dense-output stages taken, then R carried through the step into Rn (``turn``); returns
    the step's report (0, or 2 where the orientation is not finite)."""
    ints[I_DENSE] = -1  # (this trial's own)
    dense_stages(fn, d, p, W, h, z, K, last, Y, pn, ints)
    omega_polynomial(h, P, K)  # (with the stages: every later turn inside the step reads it)
    turn(p, z, R, h, P, K, 0.0, 1.0, Rn)
    return 0 if _finite_matrix(Rn) else 2


# What a step reports (trial_step and collocation_step alike): 0 done, 1 the motion is not
# finite, 2 only the orientation is not, 3 an implicit step's stage equations did not converge.
STEP_NOT_CONVERGED = 3

# How a method steps (``take_step``). Floats, like the event kinds below: numba compiles a
# function anew for every constant bool or int passed to it.
EXPLICIT, IMPLICIT = 0.0, 1.0


@JIT
def take_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """One step of the method: collocation_step (``stepping`` IMPLICIT) or trial_step (EXPLICIT)."""
    if stepping == IMPLICIT:
        return collocation_step(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints)
    return trial_step(fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)


@COLD
def search_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """``take_step`` for the searches inside a step (``fold_search``, ``approach``, ``retake``):
    compiled once and called, where inlined each of them held a copy of every layout's step."""
    return take_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)


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


@COLD  # compiled once (not into each loop): a call costs nothing beside its iterations
def collocation_step(fn, d, p, W, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """One Gauss–Legendre step of size h (h < 0 steps backwards) from z to zn, Rn, with the
    arguments and codes of trial_step (the orientation always Munthe-Kaas).

    The stage equations are solved in two parts, since u does not act on (alpha, v): first
    the motion, evaluating the right-hand side with u = 0 (so that its u-part is omega),
    then the increments u at the stages from those omegas, which needs no evaluations.

    W (``Collocation.kernel_arrays``) holds a_ij at W[1+i, 1+j], b_i at W[last, 1+i] and the
    extrapolation of the starting values in rows s+1 .. 2s. K[0] holds z'(z); K[1 .. s] hold
    the stage derivatives (on entry those of the previous step, extrapolated with K[0] after
    the first step; on return this step's); K[s+1 .. 2s] is scratch (on return its u-part
    holds omega at the stages); K[last] = K[2s+1] and pn receive the full evaluation at zn.
    Counts its evaluations in ints[I_EVALS]. Returns 0 (done), 1 (the motion is not finite),
    2 (only the orientation is not) or STEP_NOT_CONVERGED.
    """
    n = MK_SIZE
    s = (last - 1) // 2
    new = s + 1
    # starting values: extrapolated from the previous step's stages and z'(z), or z'(z) throughout
    for i in range(s):
        for q in range(5):
            acc = K[0, q]
            if ints[I_STEPS] > 0:
                acc *= W[new + i, 0]
                for j in range(s):
                    acc += W[new + i, 1 + j] * K[1 + j, q]
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
        c = h * W[last, 1 + i]
        for q in range(n):
            zn[q] += c * K[1 + i, q]
    rodrigues(zn[5], zn[6], zn[7], R, Rn)
    return end_of_step(fn, d, p, True, n, True, zn, Rn, K, last, pn, ints)


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
                c = h * W[1 + i, 1 + j]
                for q in range(5):
                    Y[q] += c * K[1 + j, q]
            dynamics(fn, d, p, Y, 1.0, K, new + i, pn, STAGE)
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
                c = h * W[1 + i, 1 + j]
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


@COLD
def evaluate(fn, d, p, z, mk, K, row, probe):
    dynamics(fn, d, p, z, 1.0 if mk else 0.0, K, row, probe, FULL)


@JIT
def error_norm(E, kind, K, last, n, z, zn, h, rtol, atol):
    """The error of a step in units of the tolerance (the step is accepted when <= 1).

    Each estimate is h (E K)_q per component q < n, weighed by scale_q = atol + rtol
    max(|z_q|, |zn_q|). The pairs pass the motion, alpha and v (n = MOTION_SIZE): omega is a
    function of it, and R follows omega's dense output held to its own tolerance (``turn``).
    kind 0: one estimate (E row 0), RMS over the components (Hairer's DOPRI5). kind 1: two
    estimates of orders 5 and 3 (rows 0 and 1) combined as err5^2 / sqrt(err5^2 + 0.01 err3^2),
    as Hairer's DOP853 does.
    """
    a5, a3 = 0.0, 0.0
    for q in range(n):
        scale = atol + rtol * max(abs(z[q]), abs(zn[q]))
        e = 0.0
        for i in range(last + 1):
            e += E[0, i] * K[i, q]
        a5 += (e / scale) ** 2
        if kind == 1:
            e = 0.0
            for i in range(last + 1):
                e += E[1, i] * K[i, q]
            a3 += (e / scale) ** 2
    if kind == 1:
        if a5 == 0.0 and a3 == 0.0:
            return 0.0
        return abs(h) * a5 / math.sqrt((a5 + 0.01 * a3) * n)
    return abs(h) * math.sqrt(a5 / n)


@JIT
def accept(p, mk, n, z, R, K, last, probe, zn, Rn, pn):
    """Make the trial state the current one; K[0] becomes its derivative (the u-part omega;
    carrying omega, z's omega becomes the exact one of the new state)."""
    for q in range(n):
        z[q] = zn[q]
        K[0, q] = K[last, q]
    if mk and n > MOTION_SIZE and p[P_TURN] > 0.0:  # the next step starts from the exact omega
        for q in range(3):
            z[5 + q] = pn[PROBE_OMEGA + q]
    elif mk and n > MOTION_SIZE:  # the next step starts from u = 0, where dexp_u^-1(omega) = omega
        for q in range(3):
            z[5 + q] = 0.0
            K[0, 5 + q] = pn[PROBE_OMEGA + q]
    for a in range(3):
        for c in range(3):
            R[a, c] = Rn[a, c]
    for q in range(PROBE_SIZE):
        probe[q] = pn[q]


# -- dense output and events -----------------------------------------------------------------
#
# After a step from z at t to t + h, z(t + theta h) = z + h sum_i K_i sum_k P[i, k] theta^(k+1)
# (P: ``Tableau.dense_output``), and R(t + theta h) = exp(A(u(theta))) R for Munthe-Kaas.
# Rows at fixed times and the events of a step are read from it. Methods whose dense output
# needs more stages than the step (DOP853: three) give them as rows of W (and K, P) after
# ``last``; ``dense_stages`` computes them once per step, only when the step is interpolated.

ROOT_ITERATIONS = 100  # at most this many evaluations to locate one event
ROOT_TOL = 1e-13       # events are located to this fraction of a step
BREAK_HALVINGS = 48    # bisections that tell a jump or kink of the surface from a smooth bend
KINK_SLACK = 1e-3      # a step whose secant curvature r*|kappa| exceeds twice its ends' plus
                       # this is looked at closer (kinks have no curvature the model can see)
JUMP_SLACK = 0.1       # likewise a height change off the slopes' by this fraction of the step
BREAK_MIN = 1e-6       # a normal turning by more (rad), or a height jumping by more (relative
                       # to 1 + |f|), across 2^-48 of a step is a kink or a jump...
BREAK_SPAN = 1e-9      # ...if that is a stretch of at most this (m): a state racing off to
                       # 1e50 m samples a smooth landscape too coarsely to tell
# The edge of the no-fit region is a fold of the centre surface: there the contact point's
# speed grows without bound (as 1 / (1 - r*kappa)) and reaches the edge in finite time, so the
# stages of a step across it are garbage and its ends may both fit. A step whose contact point
# raced (moved more than twice what its ends' speeds explain), whose stages raced (a stage's
# contact velocity off the ends' by more than STAGE_RACE times their size) or that nears the
# edge (the trend of 1 - r*kappa at its or the last step's ends reaches 0 within a step) is
# taken again in sub-steps that approach the edge geometrically (``fold_search``).
STAGE_RACE = 3.0
FOLD_TOL = 1e-13       # sub-steps end here; the edge is then located to this fraction of the step
FOLD_NEAR = 1e-3       # ...where 1 - r*kappa is below this (else a jump of the curvature is
JUMP_TOL = 1e-6        # crossed, at once once a sub-step this short fits and does not race)
FOLD_TRIES = 400       # sub-steps tried at most (then the step is taken as it is)
LINE_SAMPLES = 8       # fit checks on the straight line between a sub-step's contact points
# (kinds as floats: numba would compile a function once per integer constant passed to it)
FORCE_EVENT, FIT_EVENT = 0.0, 1.0
KINK, JUMP = 0.0, 1.0
SURFACE_SIZE = 8       # x, y, f, N (3), r * largest and smallest principal curvature


@COLD
def interpolate(z, h, P, K, theta, out):
    """out = the dense output at t + theta h."""
    lo, hi = 0, z.shape[0]
    for c in range(lo, hi):
        out[c] = z[c]
    for i in range(P.shape[0]):
        w = 0.0
        for k in range(P.shape[1] - 1, -1, -1):
            w = (w + P[i, k]) * theta
        w *= h
        if w != 0.0:
            for c in range(lo, hi):
                out[c] += w * K[i, c]


@COLD
def dense_stages(fn, d, p, W, h, z, K, last, Y, pe, ints):
    """The extra dense-output stages of the step being taken (rows last+1 .. of W), once."""
    n, mk = shape_of(z)
    if ints[I_DENSE] == ints[I_STEPS] + 1:
        return
    ints[I_DENSE] = ints[I_STEPS] + 1
    for i in range(last + 1, W.shape[0]):
        combine(n, z, h, W, i, K, i, Y)
        dynamics(fn, d, p, Y, 1.0 if mk else 0.0, K, i, pe, STAGE)
        ints[I_EVALS] += 1


@COLD
def state_at(fn, d, p, z, R, h, P, K, theta0, theta, Ye, Re, pe):
    """The dense output's state at t + theta h in Ye, Re, with its probe pe (one evaluation,
    into the spare last row of K); whether it is finite. R is the orientation at t + theta0 h
    (theta0 is 0 but when carrying omega, where R is turned on from there; Re may be R)."""
    n, mk = shape_of(z)
    interpolate(z, h, P, K, theta, Ye)
    if n == MOTION_SIZE:  # no orientation carried
        pass
    elif mk and p[P_TURN] > 0.0:
        turn(p, z, R, h, P, K, theta0, theta, Re)
    elif mk:
        rodrigues(Ye[5], Ye[6], Ye[7], R, Re)
    else:
        for a in range(3):
            for c in range(3):
                Re[a, c] = Ye[5 + 3 * a + c]
    evaluate(fn, d, p, Ye, mk, K, K.shape[0] - 1, pe)
    return _finite(Ye, 0, n) and _finite(pe, 0, PROBE_SIZE) and _finite_matrix(Re)


@COLD
def surface_at(fn, d, r, z, h, P, K, theta, Ye, s):
    """The landscape under the dense output's contact point at t + theta h, in s (SURFACE_SIZE)."""
    interpolate(z, h, P, K, theta, Ye)
    landscape(fn, Ye[0], Ye[1], data_pointer(d))
    fx, fy = d[1], d[2]
    iW = 1.0 / math.sqrt(1.0 + fx * fx + fy * fy)
    hi, lo = curvatures(fx, fy, d[3], d[4], d[5], iW)
    s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7] = Ye[0], Ye[1], d[0], -fx * iW, -fy * iW, iW, r * hi, r * lo


@COLD
def event_value(kind, fn, d, p, z, R, h, P, K, theta, Ye, Re, pe, s):
    """g(theta) of an event, negative before it: -F.N (lift-off) or r*kappa - 1 (no fit);
    +inf where the state is not finite (past any event)."""
    if kind == FORCE_EVENT:
        ok = state_at(fn, d, p, z, R, h, P, K, 0.0, theta, Ye, Re, pe)
        g = -pe[PROBE_FORCE]
    else:
        surface_at(fn, d, p[0], z, h, P, K, theta, Ye, s)
        ok = True
        g = s[6] - 1.0
    return g if ok and math.isfinite(g) else math.inf


@COLD
def locate(kind, fn, d, p, z, R, h, P, K, Ye, Re, pe, s, a, ga, b, gb, ints):
    """Shrink [a, b], g(a) < 0 <= g(b), around the event to ROOT_TOL (Illinois, every third
    try a bisection, so that it never stalls); returns (a, b)."""
    side = 0
    for it in range(ROOT_ITERATIONS):
        if b - a <= ROOT_TOL:
            break
        m = 0.5 * (a + b)
        if it % 3 != 2:
            secant = (a * gb - b * ga) / (gb - ga)
            if a < secant < b:
                m = secant
        g = event_value(kind, fn, d, p, z, R, h, P, K, m, Ye, Re, pe, s)
        if kind == FORCE_EVENT:
            ints[I_EVALS] += 1
        if g >= 0.0:
            b, gb = m, g
            if side == 1:
                ga *= 0.5
            side = 1
        else:
            a, ga = m, g
            if side == -1:
                gb *= 0.5
            side = -1
    return a, b


@JIT
def break_measure(kind, sa, sb):
    """How much of a break of the surface lies between two surface points: the angle the
    normal turns (KINK), or the height change beyond the slopes' trapezoid (JUMP)."""
    if kind == KINK:
        return math.sqrt((sb[3] - sa[3]) ** 2 + (sb[4] - sa[4]) ** 2 + (sb[5] - sa[5]) ** 2)
    dx, dy = sb[0] - sa[0], sb[1] - sa[1]
    slope = ((sa[3] / sa[5] + sb[3] / sb[5]) * dx + (sa[4] / sa[5] + sb[4] / sb[5]) * dy) * 0.5
    return abs(sb[2] - sa[2] + slope)  # grad f = -(N1, N2) / N3


@COLD
def locate_break(kind, fn, d, r, z, h, P, K, Ye, sa, sb, sm, a, b):
    """Halve [a, b] (fractions of the step) BREAK_HALVINGS times towards the half holding more
    of the break; returns (a, b, the measure over [a, b]), sa and sb the surface at a and b.
    A smooth surface's measure vanishes with the interval; a kink's or jump's does not."""
    surface_at(fn, d, r, z, h, P, K, a, Ye, sa)
    surface_at(fn, d, r, z, h, P, K, b, Ye, sb)
    for _ in range(BREAK_HALVINGS):
        m = 0.5 * (a + b)
        surface_at(fn, d, r, z, h, P, K, m, Ye, sm)
        if break_measure(kind, sa, sm) >= break_measure(kind, sm, sb):
            b = m
            for q in range(SURFACE_SIZE):
                sb[q] = sm[q]
        else:
            a = m
            for q in range(SURFACE_SIZE):
                sa[q] = sm[q]
    if (sb[0] - sa[0]) ** 2 + (sb[1] - sa[1]) ** 2 > BREAK_SPAN * BREAK_SPAN:
        return a, b, 0.0
    return a, b, break_measure(kind, sa, sb)


@JIT
def looks(r, z, probe, zn, pn):
    """The cheap looks at a step from (z, probe) to (zn, pn), from what its ends know: whether
    the ball does not fit at the end; whether the step bends sharper than the curvatures at
    its ends explain (``sharp``: a kink, or a secant curvature with r*kappa >= 1); whether the
    height changed off the slopes' trapezoid (``jumpy``). Returns them with the bend
    -(N1 - N0).(phi1 - phi0) and the squared chord |phi1 - phi0|^2."""
    f0 = probe[PROBE_HEIGHT]
    dx, dy, df = zn[0] - z[0], zn[1] - z[1], pn[PROBE_HEIGHT] - f0
    bend = -((pn[0] - probe[0]) * dx + (pn[1] - probe[1]) * dy + (pn[2] - probe[2]) * df)
    chord2 = dx * dx + dy * dy + df * df
    worst = max(probe[PROBE_FIT], pn[PROBE_FIT], -probe[PROBE_FIT_LO], -pn[PROBE_FIT_LO])
    fit_end = pn[PROBE_FIT] >= 1.0
    sharp = chord2 > 0.0 and (r * bend >= chord2 or r * abs(bend) > chord2 * (2.0 * worst + KINK_SLACK))
    # the height change against the slopes' trapezoid, grad f = -(N1, N2) / N3; 1 / N3 bounds
    # 1 and |grad f| (squares: no root per step)
    w0, w1 = 1.0 / probe[2], 1.0 / pn[2]
    off = df + 0.5 * ((probe[0] * w0 + pn[0] * w1) * dx + (probe[1] * w0 + pn[1] * w1) * dy)
    jumpy = off * off > JUMP_SLACK * JUMP_SLACK * (dx * dx + dy * dy) * (w0 + w1) ** 2 + 1e-24 * (1.0 + f0 * f0)
    return fit_end, sharp, jumpy, bend, chord2


@JIT
def step_events(fn, d, p, W, mk, n, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, segment, Ye,
                Re, pe, sa, sb, sm, stepping):
    """The validity checks and events of a finished step from t to t + h, located on its dense
    output. Returns -1 while the run may go on; otherwise the run stops (status and reason
    set) and the result is theta, the last valid point of the step (0 <= theta < 1).

    Stops: r*kappa reaches 1 (at the step's end, or inside a step that raced or nears the
    edge of the no-fit region, where ``fold_search`` takes it again in sub-steps; ``segment``:
    fixed steps, whose contact point may race); a kink or cusp of a valley; a jump in height. A convex
    kink (a ridge) is a lift-off there, and F.N turning negative is one: the first is kept.
    A step bending more sharply than the curvatures at its ends explain is searched for a
    kink; one whose secant curvature says r*kappa >= 1 stops the run even where smooth.
    """
    fit_end, sharp, jumpy, bend, chord2 = looks(p[0], z, probe, zn, pn)
    raced = segment and contact_raced(h, z, zn, K, 0, last)
    raced |= stages_raced(K, last)
    # nearing: the edge is less than a step ahead of this step's end, or of the last step's
    fold = fold_ahead(t, h, probe, pn)
    raced |= fold < t + 2.0 * h or info[F_FOLD] < t + 2.0 * h  # (nan before the first step)
    info[F_FOLD] = fold
    force_end = pn[PROBE_FORCE] < 0.0 and math.isnan(info[F_LIFTOFF])
    if not (fit_end or sharp or jumpy or raced or force_end):
        return -1.0  # the usual step: nothing to look at closer
    return examine_step(fn, d, p, W, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe,
                        sa, sb, sm, fit_end, sharp, jumpy, raced, force_end, bend, chord2, stepping)


@COLD
def examine_step(fn, d, p, W, t, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe, sa, sb, sm,
                 fit_end, sharp, jumpy, raced, force_end, bend, chord2, stepping):
    """``step_events`` for a step its cheap looks have flagged: locate what happens in it."""
    n, mk = shape_of(z)
    r = p[0]
    dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)

    stop, valid = 2.0, 0.0
    # the ball no longer fits: where along the step r*kappa reached 1. The step is taken again
    # in sub-steps (its own stages may have jumped the edge, its dense output bent around it)
    if raced or fit_end:
        edge = fold_search(fn, d, p, W, P, t, h, z, R, K, last, probe, Y, zn, Rn, pn, ints, info, Ye, Re, pe,
                           stepping)
        if edge >= 0.0:
            stop, valid = edge, edge
        else:  # no edge: the step stands, taken again (the search used its buffers)
            retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
            dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)
    if fit_end and stop > 1.0:  # the sub-steps all fit: locate the edge on the step's dense output
        gb = event_value(FIT_EVENT, fn, d, p, z, R, h, P, K, 1.0, Ye, Re, pe, sa)
        a, b = 0.0, 1.0
        if gb >= 0.0:  # the dense output agrees: locate the edge on it
            a, b = locate(FIT_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, sa, 0.0,
                          probe[PROBE_FIT] - 1.0, 1.0, gb, ints)
        surface_at(fn, d, r, z, h, P, K, b, Ye, sa)
        _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t + b * h, sa[0], sa[1], max(sa[6], 1.0))
        stop, valid = b, a
    # a bend sharper than the step's ends explain: a kink, or a bend tighter than the ball
    if sharp and stop > 1.0:
        a, b, turn = locate_break(KINK, fn, d, r, z, h, P, K, Ye, sa, sb, sm, 0.0, 1.0)
        if turn > BREAK_MIN:
            phi = (sb[0] - sa[0]) * (sb[3] - sa[3]) + (sb[1] - sa[1]) * (sb[4] - sa[4]) + (sb[2] - sa[2]) * (sb[5] - sa[5])
            if phi < 0.0:  # the normal turns towards the motion: a valley, where the ball cannot fit
                _fail(ints, info, DOES_NOT_FIT, R_KINK, t + b * h, sb[0], sb[1], turn)
                stop, valid = b, a
            elif math.isnan(info[F_LIFTOFF]):  # a ridge: the real ball flies off it
                info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + a * h, sa[0], sa[1], 1.0
                approach(KINK, fn, d, p, W, t, h, a, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, Ye, sa, sb,
                         sm, info[F_LIFTOFF:F_LIFT_Y + 1], stepping)
                # the run goes on with the whole step, taken again (the approach used its buffers)
                retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
                dense_stages(fn, d, p, W, h, z, K, last, Ye, pe, ints)
        elif r * bend >= chord2:
            _fail(ints, info, DOES_NOT_FIT, R_SECANT_NO_FIT, t + b * h, sb[0], sb[1], r * bend / chord2)
            stop, valid = b, a
    # a jump in height
    if jumpy and stop > 1.0:
        a, b, jump = locate_break(JUMP, fn, d, r, z, h, P, K, Ye, sa, sb, sm, 0.0, 1.0)
        if jump > BREAK_MIN * (1.0 + abs(sa[2])):
            _fail(ints, info, DOES_NOT_FIT, R_HEIGHT_JUMP, t + b * h, sb[0], sb[1], sb[2] - sa[2])
            stop, valid = b, a
    # lift-off: F.N turns negative (first time only, before any stop)
    if force_end and stop > 1.0 and math.isnan(info[F_LIFTOFF]):
        a, b = locate(FORCE_EVENT, fn, d, p, z, R, h, P, K, Ye, Re, pe, sa, 0.0,
                      -probe[PROBE_FORCE], 1.0, -pn[PROBE_FORCE], ints)
        interpolate(z, h, P, K, b, Ye)
        info[F_LIFTOFF], info[F_LIFT_X], info[F_LIFT_Y], info[F_LIFT_KINK] = t + b * h, Ye[0], Ye[1], 0.0
    return valid if stop <= 1.0 else -1.0


@JIT
def contact_raced(h, z, zn, K, first, last):
    """The contact point moved from z to zn by more than twice what its speeds at the step's
    ends (K[first], K[last]) explain."""
    dx, dy = zn[0] - z[0], zn[1] - z[1]
    speed = max(K[first, 0] ** 2 + K[first, 1] ** 2, K[last, 0] ** 2 + K[last, 1] ** 2)
    return dx * dx + dy * dy > 4.0 * h * h * speed


@JIT
def fold_ahead(t, h, probe, pn):
    """When the contact point, from t to t + h with probes probe and pn, reaches the edge of the
    no-fit region if 1 - r*kappa goes on falling: the earlier of the straight extrapolations
    of 1 - r*kappa and of its square (the square falls linearly near the edge); inf when it
    does not fall."""
    u0, u1 = 1.0 - probe[PROBE_FIT], 1.0 - pn[PROBE_FIT]
    if not u1 < u0:
        return math.inf
    return t + h + h * min(u1 / (u0 - u1), u1 * u1 / (u0 * u0 - u1 * u1))


@JIT
def stages_raced(K, last):
    """A stage's contact velocity is off the step's start's by more than STAGE_RACE times the
    larger of the ends' (the stages felt a fold of the centre surface the ends do not show)."""
    speed = max(K[0, 0] ** 2 + K[0, 1] ** 2, K[last, 0] ** 2 + K[last, 1] ** 2)
    spread = 0.0
    for i in range(1, last):
        spread = max(spread, (K[i, 0] - K[0, 0]) ** 2 + (K[i, 1] - K[0, 1]) ** 2)
    return spread > STAGE_RACE * STAGE_RACE * speed


@COLD
def line_fits(fn, d, r, z0, z1):
    """The ball fits at LINE_SAMPLES points evenly inside the straight line between the contact
    points of z0 and z1 (a sub-step may jump a thin no-fit region with both ends fitting)."""
    for j in range(1, LINE_SAMPLES + 1):
        theta = j / (LINE_SAMPLES + 1.0)
        landscape(fn, z0[0] + theta * (z1[0] - z0[0]), z0[1] + theta * (z1[1] - z0[1]), data_pointer(d))
        iW = 1.0 / math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
        if not r * curvatures(d[1], d[2], d[3], d[4], d[5], iW)[0] < 1.0:
            return False
    return True


@COLD
def retake(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints):
    """Take the step from z again (after a search inside it used the step's buffers)."""
    search_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
    if p[P_TURN] == 0.0:  # (carrying omega, the step has taken its dense-output stages again)
        ints[I_DENSE] = -1


@COLD
def fold_time(fn, d, r, Zs, K, ps):
    """How long until the contact point, at Zs with velocity K[0] and probe ps, reaches the edge
    of the no-fit region, if 1 - r*kappa keeps falling as the square root it is near there:
    (1 - r*kappa) / (2 d(r*kappa)/dt), the rate from a difference along the velocity; inf
    when r*kappa is not growing."""
    k1, k2 = K[0, 0], K[0, 1]
    speed = math.sqrt(k1 * k1 + k2 * k2)
    if not speed > 0.0:
        return math.inf
    delta = 1e-7 * (1.0 + max(abs(Zs[0]), abs(Zs[1])))
    landscape(fn, Zs[0] + delta * k1 / speed, Zs[1] + delta * k2 / speed, data_pointer(d))
    iW = 1.0 / math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
    rate = (r * curvatures(d[1], d[2], d[3], d[4], d[5], iW)[0] - ps[PROBE_FIT]) / delta * speed
    return (1.0 - ps[PROBE_FIT]) / (2.0 * rate) if rate > 0.0 else math.inf


@COLD
def fold_search(fn, d, p, W, P, t, h, z, R, K, last, probe, Y, zn, Rn, pn, ints, info, Zs, Rs, ps, stepping):
    """Take the step from t to t + h again in sub-steps that each stay within half the time
    ``fold_time`` gives to the edge of the no-fit region (a fold of the centre surface, which
    the contact point reaches at unbounded speed) and are accepted only where they are
    finite, their contact point does not race and they keep at least half of 1 - r*kappa.
    Towards the edge the sub-steps shrink geometrically; the edge is where they fall below
    FOLD_TOL of the step.

    Returns -1 when the sub-steps reach the step's end (no edge; zn, Rn, pn, K spoilt: take
    the step again). Otherwise the run stops (DOES_NOT_FIT at the edge, ints[I_HELD] set)
    and the result is the fraction of the step of the last valid sub-state, which zn, Rn,
    pn hold. Zs, Rs, ps: scratch for the sub-state.
    """
    n, mk = shape_of(z)
    r = p[0]
    spare = K.shape[0] - 1
    for q in range(n):
        Zs[q] = z[q]
        K[spare, q] = K[0, q]
    for a in range(3):
        for c in range(3):
            Rs[a, c] = R[a, c]
    for q in range(PROBE_SIZE):
        ps[q] = probe[q]
    ts, grow, edge = 0.0, 0.25, -1.0
    for _ in range(FOLD_TRIES):
        reach = fold_time(fn, d, r, Zs, K, ps) / h
        if 0.5 * reach <= FOLD_TOL:  # at the edge
            edge = min(ts + reach, 1.0)
            break
        hs = min(grow, 0.5 * reach, 1.0 - ts)
        bad = search_step(stepping, fn, d, p, W, P, hs * h, Zs, Rs, K, last, Y, zn, Rn, pn, ints)
        u0, u1 = 1.0 - ps[PROBE_FIT], 1.0 - pn[PROBE_FIT]
        steady = bad == 0 and not (contact_raced(hs * h, Zs, zn, K, 0, last) or stages_raced(K, last))
        across = bad == 0 and (u1 <= 0.0 or not line_fits(fn, d, r, Zs, zn))
        if not (steady and u1 >= 0.5 * u0) or across:
            near = u0 < FOLD_NEAR or across
            if hs > (JUMP_TOL if steady and not near else FOLD_TOL):
                grow = 0.1 * hs
                continue
            if near:
                edge = min(ts + hs, 1.0)
                break
            if bad != 0:  # not finite however short, away from the edge: the step stands
                break
            # (else a jump of the curvature, where the ball still fits, is crossed)
        # the sub-step is taken: its end is the new sub-state (u = 0 again for Munthe-Kaas)
        ts += hs
        grow = 2.0 * hs
        accept(p, mk, n, Zs, Rs, K, last, ps, zn, Rn, pn)
        if ts >= 1.0 - FOLD_TOL:
            break
    for q in range(n):
        K[0, q] = K[spare, q]
    ints[I_DENSE] = -1
    if edge < 0.0:
        return -1.0
    for q in range(n):
        zn[q] = Zs[q]
    for a in range(3):
        for c in range(3):
            Rn[a, c] = Rs[a, c]
    for q in range(PROBE_SIZE):
        pn[q] = ps[q]
    ints[I_HELD] = 1
    _fail(ints, info, DOES_NOT_FIT, R_NO_FIT, t + edge * h, Zs[0], Zs[1], max(ps[PROBE_FIT], 1.0))
    return ts


REFINE_STEPS = 6  # shorter steps tried to reach the last valid state before a stop


@COLD
def approach(kind, fn, d, p, W, t, h, theta, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, Ye, sa, sb, sm,
             event, stepping):
    """Reach the last valid state before a break inside a step from t to t + h, first guessed
    at theta (a fraction of the step) from the step's dense output.

    The dense output of a step across a kink, a jump or the edge of the no-fit region (kind
    KINK, JUMP or FIT_EVENT) is spoiled by the stages beyond it, so the state is computed by a
    step of theta h from the step's start instead; while such a step still crosses (its ends'
    looks say so), the break is located again on its own, less spoiled, dense output and the
    step shortened to before it; a clean step's dense output, continued a little past its end,
    times a kink or jump. event = (time, x, y) of the break is updated on the way. Returns the
    theta of the clean step (zn, Rn, pn hold its end), or 0 when none was found.
    """
    n, mk = shape_of(z)
    r = p[0]
    for _ in range(REFINE_STEPS):
        hs = theta * h
        if not hs > 0.0:
            break
        bad = search_step(stepping, fn, d, p, W, P, hs, z, R, K, last, Y, zn, Rn, pn, ints)
        if bad != 0:
            break
        fit_end, sharp, jumpy, bend, chord2 = looks(r, z, probe, zn, pn)
        if not (fit_end or sharp or jumpy):
            if kind != FIT_EVENT and theta < 1.0:
                a, b, size = locate_break(kind, fn, d, r, z, hs, P, K, Ye, sa, sb, sm, 1.0, min(1.0 / theta, 2.0))
                if size > 0.0:
                    event[0], event[1], event[2] = t + b * hs, sb[0], sb[1]
            return theta
        a, b, size = 0.0, 0.0, 0.0
        if kind == FIT_EVENT:
            if fit_end:
                a, b = locate(FIT_EVENT, fn, d, p, z, R, hs, P, K, Ye, Rn, pn, sa, 0.0,
                              probe[PROBE_FIT] - 1.0, 1.0, pn[PROBE_FIT] - 1.0, ints)
                surface_at(fn, d, r, z, hs, P, K, b, Ye, sa)
                event[0], event[1], event[2] = t + b * hs, sa[0], sa[1]
        elif sharp or jumpy:
            a, b, size = locate_break(kind, fn, d, r, z, hs, P, K, Ye, sa, sb, sm, 0.0, 1.0)
            if size > 0.0:
                event[0], event[1], event[2] = t + b * hs, sb[0], sb[1]
        theta *= a if a > 0.0 else 0.5
    return 0.0


@COLD
def record_valid(fn, d, p, W, t, h, theta, z, R, K, last, P, probe, rows, ints, info, Y, zn, Rn, pn,
                 Ye, sa, sb, sm, stepping):
    """A run stopped inside a step: its last valid state, reached by ``approach`` (or else the
    step's start), is the last row; the stop's time and place are refined on the way."""
    if ints[I_HELD] == 1:  # the last valid state is known already (``fold_search``)
        record(rows, ints[I_ROWS], t + theta * h, zn, Rn, pn, p)
        ints[I_ROWS] += 1
        return
    reason = ints[I_REASON]
    kind = JUMP if reason == R_HEIGHT_JUMP else FIT_EVENT if reason == R_NO_FIT else KINK
    event = info[F_FAIL_T:F_FAIL_Y + 1]
    theta = approach(kind, fn, d, p, W, t, h, theta, z, R, K, last, P, probe, ints, Y, zn, Rn, pn, Ye, sa, sb,
                     sm, event, stepping)
    if theta > 0.0:
        record(rows, ints[I_ROWS], t + theta * h, zn, Rn, pn, p)
        ints[I_ROWS] += 1
    else:
        record_last(rows, ints, t, z, R, probe, p)


def work_size(n: int) -> int:
    """Length of the scratch array the stepping loops need for a state of size n."""
    return 6 + 3 * n + 2 * PROBE_SIZE + 18 + 3 * SURFACE_SIZE


@JIT
def scratch(work, n):
    """Views into the caller's scratch array (nothing is allocated inside the kernel):
    landscape values d, stage state Y, trial state zn, probe pn and orientation Rn, and for
    the dense output a state Ye, orientation Re, probe pe and three surface points."""
    i = 6 + 2 * n
    j = i + PROBE_SIZE + 9
    k = j + n + PROBE_SIZE + 9
    return (work[:6], work[6:6 + n], work[6 + n:i], work[i:i + PROBE_SIZE],
            work[i + PROBE_SIZE:j].reshape((3, 3)), work[j:j + n], work[j + n:j + n + 9].reshape((3, 3)),
            work[j + n + 9:k], work[k:k + SURFACE_SIZE], work[k + SURFACE_SIZE:k + 2 * SURFACE_SIZE],
            work[k + 2 * SURFACE_SIZE:k + 3 * SURFACE_SIZE])


@COLD  # called by its entry point (simulate) and by the sweeps' batch loop: compiled once
def advance(fn, W, P, p, dt, t_end, n_steps, every, max_steps, z, R, K, probe, rows, ints, info, work,
            stepping):
    """Run up to ``max_steps`` further fixed steps; all run state lives in the arrays passed in.

    W, P: the method (``Tableau.kernel_arrays``); K has ``stage_rows(W.shape[0])`` rows.
    ``stepping``: IMPLICIT for collocation_step's steps (the
    Gauss methods, Munthe-Kaas only), EXPLICIT for trial_step's. One compiled loop serves every
    fixed-step method and both orientation schemes (read from the state's length). On the first
    call (no rows yet) the initial state is checked and recorded. The run stops early, with
    ints[I_STATUS] set, where the state turns non-finite or a check fails; the last valid state
    is then the last row.
    """
    n, mk = shape_of(z)
    last = W.shape[0] - 1
    d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm = scratch(work, n)

    if ints[I_ROWS] == 0:
        for a in range(3):   # (a state without orientation never writes these: they are checked as R)
            for c in range(3):
                Rn[a, c] = Re[a, c] = R[a, c]
        start(fn, d, p, z, R, K, probe, rows, ints, info)
        if ints[I_STATUS] != RUNNING:
            return

    k0 = ints[I_STEPS]
    k_stop = min(n_steps, k0 + max_steps)
    for k in range(k0 + 1, k_stop + 1):
        final = k == n_steps
        t0 = (k - 1) * dt
        h = t_end - t0 if final else dt
        t = t_end if final else k * dt
        bad = take_step(stepping, fn, d, p, W, P, h, z, R, K, last, Y, zn, Rn, pn, ints)
        if bad and info[F_FOLD] < t0 + 2.0 * h:  # a step failing at the edge of the no-fit region
            valid = fold_search(fn, d, p, W, P, t0, h, z, R, K, last, probe, Y, zn, Rn, pn, ints, info, Ye, Re,
                                pe, stepping)
            if valid >= 0.0:
                record_valid(fn, d, p, W, t0, h, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                             Rn, pn, Ye, sa, sb, sm, stepping)
                return
        if bad:
            if bad == STEP_NOT_CONVERGED:
                _fail(ints, info, NONFINITE, R_NOT_CONVERGED, t, z[0], z[1], h)
            else:
                _fail(ints, info, NONFINITE, R_ORIENTATION if bad == 2 else R_UNDEFINED, t, z[0], z[1],
                      0.0 if mk else 1.0)
            record_last(rows, ints, t0, z, R, probe, p)
            return
        valid = step_events(fn, d, p, W, mk, n, t0, h, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info,
                            True, Ye, Re, pe, sa, sb, sm, stepping)
        if valid >= 0.0:
            record_valid(fn, d, p, W, t0, h, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                         Rn, pn, Ye, sa, sb, sm, stepping)
            return
        accept(p, mk, n, z, R, K, last, probe, zn, Rn, pn)
        ints[I_STEPS] = k
        if k - ints[I_LAST_RECORDED] == every or final:  # (no division in the loop)
            record(rows, ints[I_ROWS], t, z, R, probe, p)
            ints[I_ROWS] += 1
            ints[I_LAST_RECORDED] = k
    if ints[I_STEPS] == n_steps:
        ints[I_STATUS] = OK


@JIT
def advance_adaptive(fn, W, E, P, p, err_kind, err_exp, t_end, record_dt, rtol, atol, max_steps, z, R, K,
                     probe, rows, ints, info, work):
    """Run up to ``max_steps`` further trial steps of an embedded pair with step-size control
    (carrying omega, p[P_TURN] > 0); info[F_TIME] is the time reached and info[F_H] the next
    step to try. The error is controlled on the motion; R follows omega (``turn``).

    The loop is generic over the pair; its plug-in points are data (``Tableau.kernel_arrays``):
    - W, square: rows 1 .. last-1 the stage coefficients, row ``last`` the weights b (the
      evaluation at the new state is K[last]; first same as last or not);
    - E, (estimates x (last + 1)): the error weights; ``last`` is E.shape[1] - 1;
    - err_kind: how ``error_norm`` combines E's rows (0: one estimate; 1: DOP853's estimates
      of orders 5 and 3); err_exp = -1/(q + 1) for an estimate of order q;
    - P, (rows of W x degree): the continuous extension, as scipy's ``P``;
    - extra dense-output stages (DOP853's three): rows of W and P after ``last``, evaluated by
      ``dense_stages`` only for steps that are interpolated (a row or an event inside them).
    K has ``stage_rows(W.shape[0])`` rows.

    Steps are cut only to land on t_end. Rows at the multiples of record_dt are the dense
    output at those times (record_dt 0: every accepted step is a row). Events are located on
    the dense output (``step_events``). Returns early, still running, when ``rows`` has fewer
    than two free rows while recording every step: the caller grows it and calls again.
    """
    n = MK_SIZE
    last = E.shape[1] - 1
    d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm = scratch(work, n)
    if ints[I_ROWS] == 0:
        start(fn, d, p, z, R, K, probe, rows, ints, info)
        info[F_TIME] = 0.0
        if ints[I_STATUS] != RUNNING:
            return
    t, h = info[F_TIME], info[F_H]
    retry = ints[I_RETRY] == 1  # right after a rejection the step may shrink but not grow (Hairer's rule)
    for _ in range(max_steps):
        if record_dt == 0.0 and ints[I_ROWS] >= rows.shape[0] - 2:
            break
        land = t + 1.1 * h >= t_end  # stretch a little rather than leave a sliver
        hs = t_end - t if land else h
        bad = trial_step_mk(fn, d, p, W, P, hs, z, R, K, last, Y, zn, Rn, pn, ints)  # (the pairs: MK_SIZE)
        err = math.inf if bad else error_norm(E, err_kind, K, last, MOTION_SIZE, z, zn, hs, rtol, atol)
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
            record_last(rows, ints, t, z, R, probe, p)
            break
        t_new = t_end if land else t + hs
        valid = step_events(fn, d, p, W, True, n, t, hs, z, R, K, last, P, probe, Y, zn, Rn, pn, ints, info,
                            False, Ye, Re, pe, sa, sb, sm, EXPLICIT)
        t_stop = t + valid * hs if valid >= 0.0 else t_new
        theta = 0.0  # Re: the orientation there (the rows' orientations follow on from each other)
        for a in range(3):
            for c in range(3):
                Re[a, c] = R[a, c]
        while record_dt > 0.0:  # the rows inside the step, from its dense output
            t_row = ints[I_ROWS] * record_dt
            if t_end - t_row < 1e-9 * record_dt:
                t_row = t_end
            if t_row > t_new or (valid >= 0.0 and t_row >= t_stop) or t_row <= rows[ints[I_ROWS] - 1, 0]:
                break
            if t_row == t_new:
                record(rows, ints[I_ROWS], t_new, zn, Rn, pn, p)
                ints[I_LAST_RECORDED] = ints[I_STEPS] + 1
            else:
                dense_stages(fn, d, p, W, hs, z, K, last, Ye, pe, ints)
                state_at(fn, d, p, z, Re, hs, P, K, theta, (t_row - t) / hs, Ye, Re, pe)
                theta = (t_row - t) / hs
                record(rows, ints[I_ROWS], t_row, Ye, Re, pe, p)
            ints[I_ROWS] += 1
        if valid >= 0.0:
            record_valid(fn, d, p, W, t, hs, valid, z, R, K, last, P, probe, rows, ints, info, Y, zn,
                         Rn, pn, Ye, sa, sb, sm, EXPLICIT)
            break
        if record_dt == 0.0:
            record(rows, ints[I_ROWS], t_new, zn, Rn, pn, p)
            ints[I_ROWS] += 1
            ints[I_LAST_RECORDED] = ints[I_STEPS] + 1
        t = t_new
        accept(p, True, n, z, R, K, last, probe, zn, Rn, pn)
        ints[I_STEPS] += 1
        grown = hs * min(1.0 if retry else MAX_FACTOR, SAFETY * err ** err_exp if err > 0.0 else MAX_FACTOR)
        h = max(h, grown) if land else grown
        retry = False
        if h <= MIN_STEP * max(1.0, abs(t)):  # creeping up to a singularity (Zeno)
            _fail(ints, info, NONFINITE, R_STEP_UNDERFLOW, t, z[0], z[1], h)
            record_last(rows, ints, t, z, R, probe, p)
            break
        if t == t_end:
            ints[I_STATUS] = OK
            break
    info[F_TIME], info[F_H] = t, h
    ints[I_RETRY] = 1 if retry else 0


# -- sweeps: batches of fixed-step runs ---------------------------------------------------------
#
# A run of a sweep needs only the motion (contact point and angular momentum): its state has
# MOTION_SIZE entries. Each run is stepped by ``advance`` itself, so a sweep's runs end exactly
# where ``simulate`` ends the same scene, every step recorded into a buffer of BATCH_CHUNK rows
# that is folded into the run's outcomes and reused: memory does not grow with the steps.

NOT_RUN = 11                  # a run of a batch not run yet (sweeps also mark refused runs, 10)
BATCH_CHUNK = 256             # steps folded into a run's outcomes at a time
BATCH_ROWS = BATCH_CHUNK + 2  # the buffer: the last row folded, a chunk, a stop's row
# One row of outcomes per run, in this order.
OUTCOMES = ("t_reached", "liftoff_time", "x_end", "y_end", "energy_drift", "min_normal_force",
            "max_speed", "path_length")
O_T, O_LIFTOFF, O_X, O_Y, O_DRIFT, O_MIN_FORCE, O_MAX_SPEED, O_PATH = range(len(OUTCOMES))
TINY = 2.2250738585072014e-308  # the smallest normal double


@JIT
def fold_rows(rows, first, count, acc):
    """Fold rows[first:count] into a run's accumulators acc = E0, max |E - E0|, min F.N, max
    speed, path length; rows[first - 1] is the row before them (first 0 starts them)."""
    if first == 0:
        acc[0], acc[1], acc[2], acc[3], acc[4] = rows[0, ROW_ENERGY], 0.0, math.inf, 0.0, 0.0
    for i in range(first, count):
        acc[1] = max(acc[1], abs(rows[i, ROW_ENERGY] - acc[0]))
        acc[2] = min(acc[2], rows[i, ROW_FORCE])
        v = ROW_VELOCITY
        acc[3] = max(acc[3], math.sqrt(rows[i, v] ** 2 + rows[i, v + 1] ** 2 + rows[i, v + 2] ** 2))
        if i > 0:
            c = ROW_CENTER
            acc[4] += math.sqrt((rows[i, c] - rows[i - 1, c]) ** 2 + (rows[i, c + 1] - rows[i - 1, c + 1]) ** 2
                                + (rows[i, c + 2] - rows[i - 1, c + 2]) ** 2)


@COLD
def advance_batch(fn, W, P, Z0, PARAMS, DT, T_END, N_STEPS, status, out, z, R, K, probe, rows, ints, info,
                  work, acc):
    """Run every run of a batch whose status is NOT_RUN, without the GIL; write its status and
    outcomes (O_T ...). Per run b: Z0[b] the initial motion state, PARAMS[b] the parameters
    (``parameters``), DT[b], T_END[b], N_STEPS[b] the fixed steps; W, P the explicit method.
    z (MOTION_SIZE), R, K, probe, rows (BATCH_ROWS), ints, info, work, acc (5): scratch."""
    n = MOTION_SIZE
    for b in range(Z0.shape[0]):
        if status[b] != NOT_RUN:
            continue
        p = PARAMS[b]
        for q in range(n):
            z[q] = Z0[b, q]
        for q in range(ints.shape[0]):
            ints[q] = 0
        for q in range(info.shape[0]):
            info[q] = math.nan
        for q in range(out.shape[1]):
            out[b, q] = math.nan
        first = 0
        while ints[I_STATUS] == RUNNING:
            # (np.int64: a literal int would compile advance anew for it)
            advance(fn, W, P, p, DT[b], T_END[b], N_STEPS[b], np.int64(1), np.int64(BATCH_CHUNK), z, R, K, probe,
                    rows, ints, info, work, EXPLICIT)
            count = ints[I_ROWS]
            if count == 0:  # the initial state is not finite: nothing to report
                break
            fold_rows(rows, first, count, acc)
            for c in range(ROW_SIZE):  # the last row, the one before the next chunk's
                rows[0, c] = rows[count - 1, c]
            ints[I_ROWS], first = 1, 1
        status[b] = ints[I_STATUS]
        if first == 0:
            continue
        o = out[b]
        o[O_T], o[O_X], o[O_Y] = rows[0, 0], rows[0, 1], rows[0, 2]
        o[O_LIFTOFF] = info[F_LIFTOFF]
        o[O_DRIFT] = acc[1] / max(abs(acc[0]), p[0] * p[1] * p[2], TINY)
        o[O_MIN_FORCE], o[O_MAX_SPEED], o[O_PATH] = acc[2], acc[3], acc[4]


# -- entry points -----------------------------------------------------------------------------------
#
# What Python calls, each by its address with one C signature (ENTRY_SIGNATURE): a pointer to
# int64 "slots" that hold the arguments of the function it calls, in their order: an array
# as three slots (its data's address, rows, columns: 1 for a vector), an int as one, a float
# as one (its bits). ``machine_code.Arguments`` packs them. These are plain functions here:
# machine_code.py compiles them (numba's ``cfunc``), so importing the kernel compiles nothing.

ENTRY_SIGNATURE = types.void(types.CPointer(types.int64))
ENTRY_SLOTS = 64


@JIT
def _vector(a, i):
    return carray(float_pointer(a[i]), (a[i + 1],)), i + 3


@JIT
def _matrix(a, i):
    return carray(float_pointer(a[i]), (a[i + 1], a[i + 2])), i + 3


@JIT
def _integers(a, i):
    return carray(int_pointer(a[i]), (a[i + 1],)), i + 3


@JIT
def _run_arrays(a, i):
    """The arrays of a run every loop takes, in this order, from slot i (and the next slot)."""
    z, i = _vector(a, i)
    R, i = _matrix(a, i)
    K, i = _matrix(a, i)
    probe, i = _vector(a, i)
    rows, i = _matrix(a, i)
    ints, i = _integers(a, i)
    info, i = _vector(a, i)
    work, i = _vector(a, i)
    return z, R, K, probe, rows, ints, info, work, i


def advance_entry(slots):
    a, x = carray(slots, (ENTRY_SLOTS,)), carray(as_floats(slots), (ENTRY_SLOTS,))
    W, i = _matrix(a, 1)
    P, i = _matrix(a, i)
    p, i = _vector(a, i)
    dt, t_end, n_steps, every, max_steps = x[i], x[i + 1], a[i + 2], a[i + 3], a[i + 4]
    z, R, K, probe, rows, ints, info, work, i = _run_arrays(a, i + 5)
    advance(a[0], W, P, p, dt, t_end, n_steps, every, max_steps, z, R, K, probe, rows, ints, info, work, x[i])


def advance_adaptive_entry(slots):
    a, x = carray(slots, (ENTRY_SLOTS,)), carray(as_floats(slots), (ENTRY_SLOTS,))
    W, i = _matrix(a, 1)
    E, i = _matrix(a, i)
    P, i = _matrix(a, i)
    p, i = _vector(a, i)
    err_kind, err_exp, t_end, record_dt, rtol, atol, max_steps = (a[i], x[i + 1], x[i + 2], x[i + 3], x[i + 4],
                                                                  x[i + 5], a[i + 6])
    z, R, K, probe, rows, ints, info, work, i = _run_arrays(a, i + 7)
    advance_adaptive(a[0], W, E, P, p, err_kind, err_exp, t_end, record_dt, rtol, atol, max_steps, z, R, K, probe,
                     rows, ints, info, work)


def advance_batch_entry(slots):
    a = carray(slots, (ENTRY_SLOTS,))
    W, i = _matrix(a, 1)
    P, i = _matrix(a, i)
    Z0, i = _matrix(a, i)
    PARAMS, i = _matrix(a, i)
    DT, i = _vector(a, i)
    T_END, i = _vector(a, i)
    N_STEPS, i = _integers(a, i)
    status, i = _integers(a, i)
    out, i = _matrix(a, i)
    z, R, K, probe, rows, ints, info, work, i = _run_arrays(a, i)
    acc, i = _vector(a, i)
    advance_batch(a[0], W, P, Z0, PARAMS, DT, T_END, N_STEPS, status, out, z, R, K, probe, rows, ints, info, work,
                  acc)


def evaluate_points_entry(slots):
    a = carray(slots, (ENTRY_SLOTS,))
    xs, i = _vector(a, 1)
    ys, i = _vector(a, i)
    out, i = _matrix(a, i)
    d, i = _vector(a, i)
    evaluate_points(a[0], xs, ys, out, d)


# Each entry point by the name of the function it calls, with that function's arguments as
# ``machine_code.Arguments`` packs them: "address" (the landscape's), "int", "float", "vector" and
# "matrix" (float64 arrays), "ints" (an int64 vector); arrays C-contiguous.
ENTRIES = {
    "advance": (advance_entry, "address matrix matrix vector float float int int int vector matrix matrix vector "
                               "matrix ints vector vector float"),
    "advance_adaptive": (advance_adaptive_entry, "address matrix matrix matrix vector int float float float float "
                                                 "float int vector matrix matrix vector matrix ints vector vector"),
    "advance_batch": (advance_batch_entry, "address matrix matrix matrix matrix vector vector ints ints matrix "
                                           "vector matrix matrix vector matrix ints vector vector vector"),
    "evaluate_points": (evaluate_points_entry, "address vector vector matrix vector"),
}
