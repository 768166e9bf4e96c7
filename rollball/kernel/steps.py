"""Taking a step (explicit or implicit), the adaptive pairs' error norm and step-size
control constants, and accepting a step's new state."""

from __future__ import annotations

import math

from .collocation import collocation_step
from .explicit import trial_step
from .interface import (F_ERR_OLD, IMPLICIT, MOTION_SIZE, PROBE_OMEGA, PROBE_SIZE, P_TURN, S_DISSIPATED,
                        S_OMEGA)
from .lowlevel import COLD, JIT
from .physics import motion_size

# Step-size control of the embedded pairs: after an accepted step the next one is
# h * SAFETY * err^(exponent + cut * beta) * err_old^beta (PI control, as Hairer's DOPRI5 and
# DOP853: err_old the last accepted step's error, at least ERR_OLD_MIN, which it also is
# before the first), bounded to [MIN_FACTOR, MAX_FACTOR] times h; exponent = -1/(q + 1) for an
# error estimate of order q (the method's ``error_exponent``). beta and cut by the pair's error
# estimate (err_kind): DOPRI5's (0) Hairer's 0.04 and 0.75; DOP853's (1) 0.08 and his 0.2
# (0.08 measured against 0 and 0.04: rejected steps fall from a quarter of the steps to a few,
# and the error follows rtol more evenly). A rejected step is retried at
# h * SAFETY * err^exponent, at least MIN_FACTOR times h.
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 5.0
PI_BETA = (0.04, 0.08)
PI_CUT = (0.75, 0.2)
ERR_OLD_MIN = 1e-4
# An adaptive step that turns the state non-finite is retried 5 times smaller; after this
# many such steps in a run the ball is pressing against the end of the landscape, and the
# run stops as a fixed-step run would at the first.
NONFINITE_TRIES = 50


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


@JIT
def natural_size(p, n, q):
    """The unit of the motion's component q (n = MOTION_SIZE or SLIDING_MOTION_SIZE) in the ball's
    own scales: length r, time sqrt(r / g0), mass m. alpha: r; rolling v (kg m^2/s):
    m r sqrt(g0 r); sliding c' (m/s): sqrt(g0 r), omega (rad/s): sqrt(g0 / r), D (J): m g0 r."""
    r, m, g = p[0], p[1], abs(p[2])
    if q < 2:
        return r
    if n == MOTION_SIZE:
        return m * r * math.sqrt(g * r)
    if q < S_OMEGA:
        return math.sqrt(g * r)
    if q < S_DISSIPATED:
        return math.sqrt(g / r)
    return m * g * r


@JIT
def error_norm(E, kind, K, last, n, z, zn, h, rtol, atol, p):
    """The error of a step in units of the tolerance (the step is accepted when <= 1).

    Each estimate is h (E K)_q per component q < n, weighed by scale_q = atol + rtol
    max(|z_q|, |zn_q|, s_q), s_q the component's unit in the ball's own scales (``natural_size``):
    a component passing through 0 (alpha where the path crosses an axis, v at rest and wherever
    it turns) is held relative to the ball's size rather than to atol alone, which cut the steps
    there for no gain in the contact point. The pairs pass the motion, alpha and v
    (n = MOTION_SIZE; sliding alpha, c', omega and D): omega is a function of it or part of it,
    and R follows omega's dense output held to its own tolerance (``turn``).
    kind 0: one estimate (E row 0), RMS over the components (Hairer's DOPRI5). kind 1: two
    estimates of orders 5 and 3 (rows 0 and 1) combined as err5^2 / sqrt(err5^2 + 0.01 err3^2),
    as Hairer's DOP853 does.
    """
    a5, a3 = 0.0, 0.0
    for q in range(n):
        scale = atol + rtol * max(abs(z[q]), abs(zn[q]), natural_size(p, n, q))
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
def next_step_factor(err, err_kind, err_exp, info):
    """The factor for the step after an accepted one (PI control, above); updates info[F_ERR_OLD]."""
    old = info[F_ERR_OLD]
    if not old >= ERR_OLD_MIN:  # (nan before the first accepted step)
        old = ERR_OLD_MIN
    info[F_ERR_OLD] = max(err, ERR_OLD_MIN)
    if err <= 0.0:
        return MAX_FACTOR
    beta, cut = PI_BETA[err_kind], PI_CUT[err_kind]
    return max(MIN_FACTOR, min(MAX_FACTOR, SAFETY * err ** (err_exp + cut * beta) * old ** beta))


@JIT
def accept(p, mk, n, z, R, K, last, probe, zn, Rn, pn):
    """Make the trial state the current one; K[0] becomes its derivative (the u-part omega;
    carrying omega, z's omega becomes the exact one of the new state)."""
    m = motion_size(n)
    for q in range(n):
        z[q] = zn[q]
        K[0, q] = K[last, q]
    if mk and n > m and p[P_TURN] > 0.0:  # the next step starts from the exact omega
        if m == MOTION_SIZE:  # (sliding, omega is the motion's own)
            for q in range(3):
                z[5 + q] = pn[PROBE_OMEGA + q]
    elif mk and n > m:  # the next step starts from u = 0, where dexp_u^-1(omega) = omega
        for q in range(3):
            z[m + q] = 0.0
            K[0, m + q] = pn[PROBE_OMEGA + q]
    for a in range(3):
        for c in range(3):
            R[a, c] = Rn[a, c]
    for q in range(PROBE_SIZE):
        probe[q] = pn[q]
