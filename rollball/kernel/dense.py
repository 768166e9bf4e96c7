"""Dense output: the state inside a step from its stages (``interpolate``, ``state_at``), and
the orientation carried along omega's polynomial through a step (``turn``: Magnus sub-steps),
for the adaptive pairs that carry omega instead of the Munthe-Kaas increment."""

from __future__ import annotations

import math

from .interface import PROBE_SIZE, P_TURN
from .lowlevel import COLD, JIT
from .physics import _finite, _finite_matrix, evaluate, motion_size, rodrigues, shape_of


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
def state_at(fn, d, p, z, R, h, P, K, theta0, theta, Ye, Re, pe):
    """The dense output's state at t + theta h in Ye, Re, with its probe pe (one evaluation,
    into the spare last row of K); whether it is finite. R is the orientation at t + theta0 h
    (theta0 is 0 but when carrying omega, where R is turned on from there; Re may be R)."""
    n, mk = shape_of(z)
    m = motion_size(n)
    interpolate(z, h, P, K, theta, Ye)
    if n == m:  # no orientation carried
        pass
    elif mk and p[P_TURN] > 0.0:
        turn(p, z, R, h, P, K, theta0, theta, Re)
    elif mk:
        rodrigues(Ye[m], Ye[m + 1], Ye[m + 2], R, Re)
    else:
        for a in range(3):
            for c in range(3):
                Re[a, c] = Ye[m + 3 * a + c]
    evaluate(fn, d, p, Ye, mk, K, K.shape[0] - 1, pe)
    return _finite(Ye, 0, n) and _finite(pe, 0, PROBE_SIZE) and _finite_matrix(Re)
