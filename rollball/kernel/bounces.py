"""A flying ball's impacts and, in vacuum, its bounces, compiled (docs/design.md §1, "Flight"):
``impact``, the impulse of a landing (the one definition: flight.py's ``impact`` calls it), and
``bounces``, what the mode machine's ``fly`` does for a flight in vacuum, flight after flight: the
landing search (``landing.land``), the rows at the recording times (``flight_rows.flight_rows``),
the impact there and, where the ball rebounds, the next flight; until the ball settles on the
surface, flies to t_end, makes the landings asked for, or leaves a flight to flight.py (the
search referred it, or its rows do not fit the buffer): every answer is the one the mode
machine's own ``fly`` gives, flight for flight (tests/test_bounces.py)."""

from __future__ import annotations

import math

import numpy as np

from .flight_rows import flight_rows
from .interface import (
    BOUNCES_CONTINUE, BOUNCES_DONE, BOUNCES_ENOUGH, BOUNCES_FLYING, BOUNCES_REFER, BOUNCES_ROOM, BOUNCES_SETTLED,
    HIT_AFTER, HIT_APPROACH, HIT_FRICTION, HIT_IMPULSE, HIT_LOST, HIT_MASS, HIT_NORMAL, HIT_OMEGA, HIT_RADIUS,
    HIT_REBOUND, HIT_RESTITUTION, HIT_REST, HIT_SETTLED, HIT_SPIN_AFTER, HIT_STICKING, HIT_VELOCITY, LANDING_FLYING,
    LANDING_REFER, OUT_LANDING,
)
from .landing import land, motion
from .lowlevel import EXACT
from .physics import rodrigues


@EXACT
def impact(hit):
    """The impulse J = J_n N + J_t at the contact point of a ball hitting the surface (hit: the
    centre's velocity, omega, the surface's unit normal there, m, r, e, mu, ``rest``; interface's
    HIT_*), and what it leaves: the velocities after, the normal speed it hit with, the rebound,
    whether the contact point sticks, the energy lost, the impulse, and whether it settled.

    The contact point's velocity u = c' + omega x (-r N) changes by J_n/m along N and by (7/2) J_t/m
    in the tangent plane (a homogeneous ball: dc' = J/m, d omega = (5/(2 m r^2)) (-r N) x J). Normal:
    u_n -> -e u_n, so J_n = (1 + e) m |u_n|. Tangential: sticking needs J_t = -(2/7) m u_t, taken
    when |J_t| <= mu J_n (always for mu = inf, a scene's null friction); else J_t = -mu J_n u_t/|u_t|
    (the slip keeps its direction and shrinks). Angular momentum about the contact point does not
    change (the impulse acts there). A rebound e |u_n| at most ``rest`` settles: the normal velocity
    left is taken away too (its impulse added), and its energy counted as lost."""
    v1, v2, v3 = hit[HIT_VELOCITY], hit[HIT_VELOCITY + 1], hit[HIT_VELOCITY + 2]
    w1, w2, w3 = hit[HIT_OMEGA], hit[HIT_OMEGA + 1], hit[HIT_OMEGA + 2]
    n1, n2, n3 = hit[HIT_NORMAL], hit[HIT_NORMAL + 1], hit[HIT_NORMAL + 2]
    m, r, e, mu = hit[HIT_MASS], hit[HIT_RADIUS], hit[HIT_RESTITUTION], hit[HIT_FRICTION]
    u1, u2, u3 = v1 - r * (w2 * n3 - w3 * n2), v2 - r * (w3 * n1 - w1 * n3), v3 - r * (w1 * n2 - w2 * n1)
    u_n = u1 * n1 + u2 * n2 + u3 * n3
    approach = max(-u_n, 0.0)
    j_n = (1.0 + e) * m * approach
    t1, t2, t3 = u1 - u_n * n1, u2 - u_n * n2, u3 - u_n * n3
    k = -(2.0 / 7.0) * m
    j1, j2, j3 = k * t1, k * t2, k * t3
    slip = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
    sticking = mu == math.inf or math.sqrt(j1 * j1 + j2 * j2 + j3 * j3) <= mu * j_n
    if not sticking:
        k = -mu * j_n / slip if slip > 0 else 0.0
        j1, j2, j3 = k * t1, k * t2, k * t3
    i1, i2, i3 = j_n * n1 + j1, j_n * n2 + j2, j_n * n3 + j3
    a1, a2, a3 = v1 + i1 / m, v2 + i2 / m, v3 + i3 / m
    q = 5.0 / (2.0 * m * r * r)   # d omega = q (-r N) x J
    b1 = w1 + q * (-r * (n2 * i3 - n3 * i2))
    b2 = w2 + q * (-r * (n3 * i1 - n1 * i3))
    b3 = w3 + q * (-r * (n1 * i2 - n2 * i1))
    before = 0.5 * m * (v1 * v1 + v2 * v2 + v3 * v3) + 0.2 * m * r * r * (w1 * w1 + w2 * w2 + w3 * w3)
    after = 0.5 * m * (a1 * a1 + a2 * a2 + a3 * a3) + 0.2 * m * r * r * (b1 * b1 + b2 * b2 + b3 * b3)
    lost, rebound = before - after, e * approach
    settled = not rebound > hit[HIT_REST]
    if settled:
        v_n = a1 * n1 + a2 * n2 + a3 * n3
        a1, a2, a3 = a1 - v_n * n1, a2 - v_n * n2, a3 - v_n * n3
        lost += 0.5 * m * v_n * v_n
        i1, i2, i3 = i1 - m * v_n * n1, i2 - m * v_n * n2, i3 - m * v_n * n3
        rebound = 0.0
    hit[HIT_AFTER], hit[HIT_AFTER + 1], hit[HIT_AFTER + 2] = a1, a2, a3
    hit[HIT_SPIN_AFTER], hit[HIT_SPIN_AFTER + 1], hit[HIT_SPIN_AFTER + 2] = b1, b2, b3
    hit[HIT_APPROACH], hit[HIT_REBOUND], hit[HIT_LOST] = approach, rebound, lost
    hit[HIT_STICKING], hit[HIT_SETTLED] = 1.0 if sticking else 0.0, 1.0 if settled else 0.0
    hit[HIT_IMPULSE], hit[HIT_IMPULSE + 1], hit[HIT_IMPULSE + 2] = i1, i2, i3


@EXACT
def bounces(fn, state, R, gravity, radius, mass, restitution, friction, rest, t_end, step, every, enough, dissipated,
            hints, tips, reach_default, iterations, out, landed, rows, refer, hit, times, guess, centers, feet,
            normals, distances, below, sampled, spacings, nearest, start_centers, start_feet, start_normals,
            start_distances, row_times, row_centers, row_velocities, row_feet, row_normals, row_distances, turn, d,
            tape, bounds, feet_after):
    """The mode machine's ``fly`` for a ball in vacuum from ``state`` (t0, c0 (3), c0' (3), omega (3))
    with the orientation R (3, 3), flight after flight, its rows at the recording times (the
    multiples k·every·step, ``ModeMachine.record_times``) written to ``rows`` from row 0 (``refer``:
    where flight.py searches a row's foot, ``Flight.rows``; the energy the causes took before is
    the caller's to add) and each landing to ``landed`` (t, x, y, the normal speed, the energy
    lost), the impacts' losses added to ``dissipated``. out[0] says how it ended:

    - BOUNCES_SETTLED: the ball landed and stays on the surface: state and R are its state
      just after the impact (t, the centre, c', omega), out[4:6] the foot's (x, y), out[6] 1
      where it sticks (rolls on), 0 where it slides;
    - BOUNCES_FLYING: still flying at t_end (its rows to t_end written); BOUNCES_DONE: a rebound at
      t_end or later; BOUNCES_ENOUGH: the ``enough``-th landing made (the run's ``stop_after``;
      -1: none);
    - BOUNCES_CONTINUE (``landed`` full), BOUNCES_REFER (the landing search referred the flight to
      flight.py), BOUNCES_ROOM (its rows do not fit: out[8:8 + OUT_LANDING] is the search's
      answer): state and R are the flight's start, whose first row is written; the caller goes on
      from there.

    out[1]: rows written; out[2]: landings made; out[3]: ``dissipated`` then. hit: HIT_* (its m,
    r, e, mu and rest are set here); tape: the landscape's (``Landscape.tape``); feet_after: the
    rows before that time have no foot (``flight_rows``; -inf: all have theirs); the rest: scratch
    (``land``'s and ``flight_rows``' arrays, row_* of the rows' capacity, bounds the tape's)."""
    lout = out[8:8 + OUT_LANDING]
    capacity = rows.shape[0]
    spacing = every * step
    count, k, lost = 0, 0, dissipated
    hit[HIT_MASS], hit[HIT_RADIUS], hit[HIT_RESTITUTION], hit[HIT_FRICTION], hit[HIT_REST] = (
        mass, radius, restitution, friction, rest)
    while True:
        t0 = state[0]
        land(fn, state[:7], gravity, radius, t_end, hints, tips, reach_default, iterations, lout, times, guess,
             centers, feet, normals, distances, below, sampled, spacings, nearest, start_centers, start_feet,
             start_normals, start_distances, d, tape, bounds)
        if lout[0] == LANDING_REFER:
            out[0] = BOUNCES_REFER
            break
        flying = lout[0] == LANDING_FLYING
        t = t_end if flying else lout[1]
        # the recording times strictly between t0 and t (and t_end itself where it flies on)
        k0, k1 = math.floor(t0 / spacing) + 1, math.ceil(t / spacing) - 1
        if k1 - k0 + 3 > min(capacity - count, row_times.shape[0]):   # (with the row of a rebound)
            out[0] = BOUNCES_ROOM
            break
        n = 0
        for j in range(int(k0), int(k1) + 1):
            s = float(j * every) * step
            if t0 < s < t:
                row_times[n] = s
                n += 1
        if flying:
            row_times[n] = t_end
            n += 1
        for i in range(n):
            cx, cy, cz, vx, vy, vz = motion(state, gravity, row_times[i])
            row_centers[i, 0], row_centers[i, 1], row_centers[i, 2] = cx, cy, cz
            row_velocities[i, 0], row_velocities[i, 1], row_velocities[i, 2] = vx, vy, vz
        flight_rows(fn, n, row_centers, row_velocities, row_times, t0, state[7:10], R, state[1:3], tips, mass, radius,
                    gravity, lost, rows[count:], refer[count:], row_feet, row_normals, row_distances, turn,
                    iterations, d, feet_after)
        count += n
        if flying:
            out[0] = BOUNCES_FLYING
            break
        # the impact: the state at t (R turned by Rodrigues' formula, as the rows are)
        cx, cy, cz, vx, vy, vz = motion(state, gravity, t)
        tau = t - t0
        rodrigues(state[7] * tau, state[8] * tau, state[9] * tau, R, turn)
        hit[HIT_VELOCITY], hit[HIT_VELOCITY + 1], hit[HIT_VELOCITY + 2] = vx, vy, vz
        hit[HIT_OMEGA], hit[HIT_OMEGA + 1], hit[HIT_OMEGA + 2] = state[7], state[8], state[9]
        hit[HIT_NORMAL], hit[HIT_NORMAL + 1], hit[HIT_NORMAL + 2] = lout[4], lout[5], lout[6]
        impact(hit)
        lost += hit[HIT_LOST]
        landed[k, 0], landed[k, 1], landed[k, 2] = t, lout[2], lout[3]
        landed[k, 3], landed[k, 4] = hit[HIT_APPROACH], hit[HIT_LOST]
        k += 1
        state[0], state[1], state[2], state[3] = t, cx, cy, cz
        for q in range(3):
            state[4 + q], state[7 + q] = hit[HIT_AFTER + q], hit[HIT_SPIN_AFTER + q]
            for c in range(3):
                R[q, c] = turn[q, c]
        if k == enough:
            out[0] = BOUNCES_ENOUGH
            break
        if hit[HIT_SETTLED] != 0.0:
            out[0] = BOUNCES_SETTLED
            out[4], out[5], out[6] = lout[2], lout[3], hit[HIT_STICKING]
            break
        # off again: the state just after the impact is the new flight's first row (its count an
        # int64: a literal 1 would have numba compile flight_rows once more, for that constant)
        row_times[0] = t
        for q in range(3):
            row_centers[0, q], row_velocities[0, q] = state[1 + q], state[4 + q]
        flight_rows(fn, np.int64(1), row_centers, row_velocities, row_times, t, state[7:10], R, state[1:3], tips,
                    mass, radius, gravity, lost, rows[count:], refer[count:], row_feet, row_normals, row_distances,
                    turn, iterations, d, feet_after)
        count += 1
        if t >= t_end:
            out[0] = BOUNCES_DONE
            break
        if k == landed.shape[0]:
            out[0] = BOUNCES_CONTINUE
            break
    out[1], out[2], out[3] = count, k, lost
