"""A sweep's batch of fixed-step runs (``advance_batch``), without the GIL: each run stepped by
``advance`` itself, its rows folded into its outcomes chunk by chunk. A run that flies goes on
as the mode machine goes on where the contact only rolls and flies in vacuum (interface, "sweeps"):
from a lift-off in the tangent plane, the flights of ``bounces``, then rolling again from where
the ball settles; anything more the loop leaves to the mode machine (REFERRED). The arithmetic
between the kernel's runs is the mode machine's, operation for operation (EXACT: no fused
multiply-adds), so a run gives the numbers ``Simulation`` gives."""

from __future__ import annotations

import math

import numpy as np

from .bounces import bounces
from .interface import (
    A_CENTER, A_CONTACT, A_FIRST, A_FLYING, A_FORCE, A_HIGH, A_LOW, A_PATH, A_ROWS, A_SPEED, A_T, BATCH_CHUNK,
    F_EVENT_T, O_FIRST_GRIP, O_FIRST_SLIP, O_SLIDES, S_DISSIPATED, S_OMEGA, S_VELOCITY, T_GRIP, T_SLIP,
    BOUNCES_CONTINUE, BOUNCES_REFER, BOUNCES_ROOM, BOUNCES_SETTLED, EXPLICIT, FOOT_ITERATIONS, F_H, F_LIFT_KINK,
    F_LIFTOFF, I_ROWS, I_STATUS, I_TRANSITION, NOT_RUN, OK, O_DRIFT, O_FLIES, O_LANDINGS, O_LIFTOFF, O_MAX_SPEED,
    O_MIN_FORCE, O_PATH, O_T, O_X, O_Y, PROBE_N, P_DISSIPATED, P_FLY, P_MU, REFERRED, ROW_CENTER, ROW_CONTACT,
    ROW_DISSIPATED, ROW_ENERGY, ROW_FORCE, ROW_OMEGA, ROW_R, ROW_SIZE, ROW_T, ROW_VELOCITY, RUNNING, TIP_RING,
    TIP_SUSPECT, TRANSITION, T_LIFTOFF,
)
from .lowlevel import EXACT, INLINE_EXACT, data_pointer, landscape
from .loops import advance

TINY = 2.2250738585072014e-308  # the smallest normal double (``Trajectory.energy_scale``'s least)
P_MG = 6   # p[6]: m g0 (``interface.parameters``)


@INLINE_EXACT
def fold_rows(rows, first, count, acc, flying):
    """Fold rows[first:count] into a run's accumulators (interface's A_*): E + D at its first row,
    its largest and smallest, min F.N, max speed, the path length (from the last row folded
    before), and the last row's time, contact and centre; ``flying``: 1.0 for a flight's rows."""
    for i in range(first, count):
        total = rows[i, ROW_ENERGY] + rows[i, ROW_DISSIPATED]
        v = ROW_VELOCITY
        speed = math.sqrt(rows[i, v] * rows[i, v] + rows[i, v + 1] * rows[i, v + 1] + rows[i, v + 2] * rows[i, v + 2])
        c = ROW_CENTER
        if acc[A_ROWS] == 0.0:
            acc[A_FIRST], acc[A_HIGH], acc[A_LOW] = total, total, total
            acc[A_FORCE], acc[A_SPEED], acc[A_PATH] = rows[i, ROW_FORCE], speed, 0.0
        else:
            acc[A_HIGH], acc[A_LOW] = max(acc[A_HIGH], total), min(acc[A_LOW], total)
            acc[A_FORCE], acc[A_SPEED] = min(acc[A_FORCE], rows[i, ROW_FORCE]), max(acc[A_SPEED], speed)
            dx, dy, dz = (rows[i, c] - acc[A_CENTER], rows[i, c + 1] - acc[A_CENTER + 1],
                          rows[i, c + 2] - acc[A_CENTER + 2])
            acc[A_PATH] += math.sqrt(dx * dx + dy * dy + dz * dz)
        acc[A_T], acc[A_CONTACT], acc[A_CONTACT + 1] = rows[i, ROW_T], rows[i, ROW_CONTACT], rows[i, ROW_CONTACT + 1]
        acc[A_CENTER], acc[A_CENTER + 1], acc[A_CENTER + 2] = rows[i, c], rows[i, c + 1], rows[i, c + 2]
        acc[A_ROWS] += 1.0
    if count > first:
        acc[A_FLYING] = flying


@INLINE_EXACT
def near_tip(fn, d, x, y, normals):
    """Whether the unit normals on a ring about (x, y) differ by more than TIP_SUSPECT, or one is
    not finite: the mode machine may find a tip there (``ModeMachine._at_tip``), which it measures
    the flight's distances from. A smooth surface's differ by about its curvature times TIP_RING.
    normals: scratch of 8 rows at least."""
    ring = TIP_RING * (1.0 + abs(x) + abs(y))
    for i in range(8):
        angle = i * (math.pi / 4.0)
        landscape(fn, x + ring * math.cos(angle), y + ring * math.sin(angle), data_pointer(d))
        w = math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
        normals[i, 0], normals[i, 1], normals[i, 2] = -d[1] / w, -d[2] / w, 1.0 / w
        if not (math.isfinite(normals[i, 0]) and math.isfinite(normals[i, 1]) and math.isfinite(normals[i, 2])):
            return True
    for i in range(8):
        for j in range(i + 1, 8):
            a, b, c = normals[i, 0] - normals[j, 0], normals[i, 1] - normals[j, 1], normals[i, 2] - normals[j, 2]
            if not a * a + b * b + c * c <= TIP_SUSPECT * TIP_SUSPECT:
                return True
    return False


@INLINE_EXACT
def leave(row, probe, flight, turned):
    """The flight from a lift-off's row (``ModeMachine._lift_off``): the row's t, centre and ω, its
    centre's velocity less its part along the unit normal there (probe's); R the row's."""
    n1, n2, n3 = probe[PROBE_N], probe[PROBE_N + 1], probe[PROBE_N + 2]
    v1, v2, v3 = row[ROW_VELOCITY], row[ROW_VELOCITY + 1], row[ROW_VELOCITY + 2]
    along = v1 * n1 + v2 * n2 + v3 * n3
    flight[0] = row[ROW_T]
    for q in range(3):
        flight[1 + q], flight[7 + q] = row[ROW_CENTER + q], row[ROW_OMEGA + q]
        for c in range(3):
            turned[q, c] = row[ROW_R + 3 * q + c]
    flight[4], flight[5], flight[6] = v1 - along * n1, v2 - along * n2, v3 - along * n3


@INLINE_EXACT
def rolling_from(fn, d, p, x, y, v1, v2, v3, o1, o2, o3, z):
    """z for rolling on from (x, y) with centre velocity v and angular velocity omega (a landing, a
    grip): the angular momentum about the contact point, (2/5) m r² omega + m r N × v
    (``sliding.BallState.momentum``, N the unit normal there), u zero."""
    landscape(fn, x, y, data_pointer(d))
    w = math.sqrt(1.0 + d[1] * d[1] + d[2] * d[2])
    n1, n2, n3 = -d[1] / w, -d[2] / w, 1.0 / w
    r, m = p[0], p[1]
    spin, arm = 0.4 * m * r * r, m * r
    for q in range(z.shape[0]):
        z[q] = 0.0
    z[0], z[1] = x, y
    z[2] = spin * o1 + arm * (n2 * v3 - n3 * v2)
    z[3] = spin * o2 + arm * (n3 * v1 - n1 * v3)
    z[4] = spin * o3 + arm * (n1 * v2 - n2 * v1)


@INLINE_EXACT
def sliding_from(x, y, v1, v2, v3, o1, o2, o3, dissipated, zs):
    """zs for sliding on from (x, y) with centre velocity v, angular velocity omega and the energy
    dissipated so far (a slip, a landing whose friction did not stop the contact point), u zero
    (``sliding.start_arrays``)."""
    for q in range(zs.shape[0]):
        zs[q] = 0.0
    zs[0], zs[1] = x, y
    zs[S_VELOCITY], zs[S_VELOCITY + 1], zs[S_VELOCITY + 2] = v1, v2, v3
    zs[S_OMEGA], zs[S_OMEGA + 1], zs[S_OMEGA + 2] = o1, o2, o3
    zs[S_DISSIPATED] = dissipated


@INLINE_EXACT
def slip_from(probe, p, z, zs):
    """zs, the sliding state a slip starts from (``sliding.stopped_state``): the rolling state z's
    contact point, its omega = 5 / (7 m r²) (v + 5/2 (N.v) N) (``rolling_omega``, N the probe's),
    the centre velocity r omega x N and the energy dissipated before."""
    n1, n2, n3 = probe[PROBE_N], probe[PROBE_N + 1], probe[PROBE_N + 2]
    r, m = p[0], p[1]
    v1, v2, v3 = z[2], z[3], z[4]
    k = 5.0 / (7.0 * m * r * r)
    along = 2.5 * (n1 * v1 + n2 * v2 + n3 * v3)
    o1, o2, o3 = k * (v1 + along * n1), k * (v2 + along * n2), k * (v3 + along * n3)
    sliding_from(z[0], z[1], r * (o2 * n3 - o3 * n2), r * (o3 * n1 - o1 * n3), r * (o1 * n2 - o2 * n1), o1, o2, o3,
                 p[P_DISSIPATED], zs)


@EXACT   # (its own arithmetic, the helpers' inlined, without fused multiply-adds)
def advance_batch(fn, W, P, Z0, PARAMS, DT, T_END, N_STEPS, BOUNCE, status, out, z, R, K, probe, rows, ints, info,
                  work, zs, Ks, S, SE, SP, s_kind, s_exp, s_tol, acc, p, tape, flight, turned, flown, flown_rows,
                  hints, tips, landed, refer, hit, times, guess, centers, feet, normals, distances, below, sampled,
                  spacings, nearest, start_centers, start_feet, start_normals, start_distances, row_times,
                  row_centers, row_velocities, row_feet, row_normals, row_distances, turn, d, bounds):
    """Run every run of a batch whose status is NOT_RUN, without the GIL; write its status and
    outcomes (O_T ... O_FLIES). Per run b: Z0[b] the initial motion state, PARAMS[b] the parameters
    (``parameters``), DT[b], T_END[b], N_STEPS[b] the fixed steps, BOUNCE[b] the restitution and the
    slowest rebound that flies (read where p[P_FLY] is 1); W, P the explicit method; tape the
    landscape's. A run the mode machine is to take has the status REFERRED. z (MOTION_SIZE), R, K,
    probe, rows (BATCH_ROWS), ints, info, work, acc (BATCH_ACCUMULATORS), p (P_SIZE): scratch; the
    rest, a flight's (``bounces``: flight its state, turned its R, flown its out, flown_rows its rows).

    Where mu is finite (PARAMS' P_MU) z and K are a Munthe-Kaas rolling state's (MK_SIZE) and zs, Ks
    a sliding one's (SLIDING_MK_SIZE), K and Ks with the stage rows of W and of the stiff pair S, SE,
    SP (s_kind, s_exp, s_tol: ``advance``'s) too: a slip goes on sliding from the state there
    (``slip_from``) and a grip rolling (``rolling_from``), as the mode machine goes on
    (``ModeMachine.stopped``), each kernel run's first row the last one's again, left out, and a
    landing whose friction did not stop the contact point sliding (``sliding_from``); out's
    O_FIRST_SLIP, O_FIRST_GRIP and O_SLIDES (1 where the run ends sliding). A change at the time
    of the one before is the mode machine's (REFERRED)."""
    for b in range(Z0.shape[0]):
        if status[b] != NOT_RUN:
            continue
        for q in range(p.shape[0]):
            p[q] = PARAMS[b, q]
        for q in range(z.shape[0]):
            z[q] = Z0[b, q]
        for q in range(3):   # (the motion-only state has none: the rows' and the flights' orientation)
            for c in range(3):
                R[q, c] = 1.0 if q == c else 0.0
        for q in range(out.shape[1]):
            out[b, q] = math.nan
        acc[A_ROWS] = 0.0
        first_liftoff, landings, t_start = math.nan, 0.0, 0.0
        first_slip, first_grip, changed, sliding, skip = math.nan, math.nan, -math.inf, False, 0
        code = RUNNING
        while code == RUNNING:   # a kernel run from t_start, rolling (or sliding)
            for q in range(ints.shape[0]):
                ints[q] = 0
            for q in range(info.shape[0]):
                info[q] = math.nan
            info[F_H] = DT[b]
            first = skip   # (after a slip or a grip, the first row is the last one's again)
            while ints[I_STATUS] == RUNNING:
                # (np.int64: a literal int would compile advance anew for it)
                if sliding:
                    advance(fn, W, P, p, DT[b], t_start, T_END[b], N_STEPS[b], np.int64(1), np.int64(BATCH_CHUNK), zs,
                            R, Ks, probe, rows, ints, info, work, EXPLICIT, S, SE, SP, s_kind, s_exp, s_tol)
                else:
                    advance(fn, W, P, p, DT[b], t_start, T_END[b], N_STEPS[b], np.int64(1), np.int64(BATCH_CHUNK), z,
                            R, K, probe, rows, ints, info, work, EXPLICIT, S, SE, SP, s_kind, s_exp, s_tol)
                count = ints[I_ROWS]
                if count == 0:  # the initial state is not finite: nothing to report
                    break
                fold_rows(rows, first, count, acc, 0.0)
                for c in range(ROW_SIZE):  # the last row, the one before the next chunk's
                    rows[0, c] = rows[count - 1, c]
                ints[I_ROWS], first = 1, 1
            if math.isnan(first_liftoff):
                first_liftoff = info[F_LIFTOFF]
            code = ints[I_STATUS]
            if code == TRANSITION and (ints[I_TRANSITION] == T_SLIP or ints[I_TRANSITION] == T_GRIP):
                t = info[F_EVENT_T]
                if t == changed or ints[I_ROWS] == 0:   # (changes at one time: the mode machine's to judge)
                    code = REFERRED
                    break
                changed, skip = t, 1
                if ints[I_TRANSITION] == T_GRIP:   # (rolling on with the slide's D, as a landing's)
                    rolling_from(fn, d, p, zs[0], zs[1], zs[S_VELOCITY], zs[S_VELOCITY + 1], zs[S_VELOCITY + 2],
                                 zs[S_OMEGA], zs[S_OMEGA + 1], zs[S_OMEGA + 2], z)
                    p[P_DISSIPATED], sliding = zs[S_DISSIPATED], False
                    if math.isnan(first_grip):
                        first_grip = t
                elif sliding:   # (a slip that turned about at its zero slides on as it is)
                    sliding_from(zs[0], zs[1], zs[S_VELOCITY], zs[S_VELOCITY + 1], zs[S_VELOCITY + 2], zs[S_OMEGA],
                                 zs[S_OMEGA + 1], zs[S_OMEGA + 2], zs[S_DISSIPATED], zs)
                else:
                    slip_from(probe, p, z, zs)
                    sliding = True
                    if math.isnan(first_slip):
                        first_slip = t
                t_start, code = t, RUNNING
                if not T_END[b] - t > 1e-12 * T_END[b]:
                    code = OK
                continue
            if p[P_FLY] == 0.0 or code == OK:
                break
            if not (code == TRANSITION and ints[I_TRANSITION] == T_LIFTOFF and info[F_LIFT_KINK] == 0.0
                    and first == 1
                    and not near_tip(fn, d, rows[0, ROW_CONTACT], rows[0, ROW_CONTACT + 1], row_normals)):
                code = REFERRED
                break
            leave(rows[0], probe, flight, turned)
            sliding = False
            lost = rows[0, ROW_DISSIPATED]
            how = BOUNCES_CONTINUE
            while how == BOUNCES_CONTINUE:
                bounces(fn, flight, turned, p[2], p[0], p[1], BOUNCE[b, 0], p[P_MU], BOUNCE[b, 1], T_END[b], DT[b],
                        np.int64(1), np.int64(-1), lost, hints, tips, 1.0, np.int64(FOOT_ITERATIONS), flown, landed,
                        flown_rows, refer, hit, times, guess, centers, feet, normals, distances, below, sampled,
                        spacings, nearest, start_centers, start_feet, start_normals, start_distances, row_times,
                        row_centers, row_velocities, row_feet, row_normals, row_distances, turn, d, tape, bounds,
                        T_END[b])
                how, written = flown[0], int(flown[1])
                for i in range(written):   # (a row whose foot flight.py would search)
                    if refer[i] != 0:
                        how = BOUNCES_REFER
                if how == BOUNCES_REFER or how == BOUNCES_ROOM:
                    break
                fold_rows(flown_rows, np.int64(0), written, acc, 1.0)   # (np.int64: no compile for a literal)
                landings += flown[2]
                lost = flown[3]
            if how == BOUNCES_REFER or how == BOUNCES_ROOM:
                code = REFERRED
            elif how != BOUNCES_SETTLED or not T_END[b] - flight[0] > 1e-12 * T_END[b]:
                code = OK   # flying at the end, or settled at it
            else:   # on from the landing: rolling where the friction stopped the contact point, else sliding
                sliding = flown[6] == 0.0
                if sliding:
                    sliding_from(flown[4], flown[5], flight[4], flight[5], flight[6], flight[7], flight[8], flight[9],
                                 lost, zs)
                else:
                    rolling_from(fn, d, p, flown[4], flown[5], flight[4], flight[5], flight[6], flight[7], flight[8],
                                 flight[9], z)
                p[P_DISSIPATED], t_start, code, skip = lost, flight[0], RUNNING, 0
        status[b] = code
        if code == REFERRED or acc[A_ROWS] == 0.0:
            continue
        o = out[b]
        o[O_T], o[O_X], o[O_Y] = acc[A_T], acc[A_CONTACT], acc[A_CONTACT + 1]
        o[O_LIFTOFF] = first_liftoff
        high, low = abs(acc[A_HIGH] - acc[A_FIRST]), abs(acc[A_LOW] - acc[A_FIRST])
        o[O_DRIFT] = max(high, low) / max(abs(acc[A_FIRST]), p[P_MG] * p[0], TINY)
        o[O_MIN_FORCE], o[O_MAX_SPEED], o[O_PATH] = acc[A_FORCE], acc[A_SPEED], acc[A_PATH]
        o[O_LANDINGS], o[O_FLIES] = landings, acc[A_FLYING]
        o[O_FIRST_SLIP], o[O_FIRST_GRIP], o[O_SLIDES] = first_slip, first_grip, 1.0 if sliding else 0.0
