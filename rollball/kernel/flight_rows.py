"""A flying ball's recorded rows, compiled (docs/design.md §1, "Flight and landing"): what
``flight.Flight.rows`` records at each time from the centre and its velocity there (given: a
parabola's, or the integrated motion through air), the constant ω and the start's orientation."""

from __future__ import annotations

import math

from .interface import (
    ROW_CENTER, ROW_CONTACT, ROW_DISSIPATED, ROW_ENERGY, ROW_OMEGA, ROW_R, ROW_SIZE, ROW_SLIP, ROW_T, ROW_VELOCITY,
    SAMPLE_SLACK,
)
from .lowlevel import EXACT, data_pointer, landscape
from .physics import closest_points, rodrigues


@EXACT
def flight_rows(fn, count, centers, velocities, times, start_time, omega, R, guess, tips, mass, radius, gravity,
                dissipated, rows, refer, feet, normals, distances, turn, iterations, d, feet_after):
    """rows[:count] (``interface.ROW_FIELDS``) at times[:count], where the centre is centers[i]
    and moves at velocities[i]: the contact columns the centre's closest surface point (Newton's
    method from ``guess``, a ``tips`` point put in where it is nearer), R = exp(A(ω) τ) R
    (τ = t − start_time), the energy ½ m|ċ|² + ⅕ m r²|ω|² + m g c_z, normal force 0, the slip
    speed of the ball's point nearest the surface, ``dissipated``; the rest 0. refer[i] = 1 where
    that foot is not found or cannot be the nearest point (farther than the point below the
    centre, or on the far side of the surface): there flight.py searches the foot and sets the
    contact and slip columns. Rows at times before ``feet_after`` are written without their foot
    (contact and slip NaN, refer 0: a sweep's runs read only the last row's, ``sweeps.batch``);
    -inf: every row has its foot (each row's foot is its own Newton's method, so a row has the
    same foot either way). feet, normals, distances: scratch of at least ``count`` rows; turn (3, 3)."""
    n = count
    first = 0   # (the rows from here on have their foot: times increase)
    while first < n and times[first] < feet_after:
        first += 1
    for i in range(n):
        feet[i, 0], feet[i, 1] = guess[0], guess[1]
    closest_points(fn, centers[first:n], feet[first:n], normals[first:n], distances[first:n], iterations, d)
    for i in range(first):
        feet[i, 0] = feet[i, 1] = normals[i, 0] = normals[i, 1] = normals[i, 2] = distances[i] = math.nan
    w1, w2, w3 = omega[0], omega[1], omega[2]
    spin = 0.2 * mass * radius * radius * (w1 * w1 + w2 * w2 + w3 * w3)
    for i in range(n):
        cx, cy, cz = centers[i, 0], centers[i, 1], centers[i, 2]
        for q in range(tips.shape[0] if i >= first else 0):   # (``Surface._nearer_tips``)
            a1, a2, a3 = cx - tips[q, 0], cy - tips[q, 1], cz - tips[q, 2]
            far = math.sqrt(a1 * a1 + a2 * a2 + a3 * a3)
            if not abs(distances[i]) <= far and far > 0.0:
                feet[i, 0], feet[i, 1] = tips[q, 0], tips[q, 1]
                normals[i, 0], normals[i, 1], normals[i, 2] = a1 / far, a2 / far, a3 / far
                distances[i] = far
        refer[i] = 0
        if i >= first:
            landscape(fn, cx, cy, data_pointer(d))
            below, distance = d[0], distances[i]
            plausible = (math.isfinite(distance) and abs(distance) <= abs(cz - below) * (1.0 + SAMPLE_SLACK)
                         and not ((distance > 0.0 and cz < below) or (distance < 0.0 and cz > below)))
            refer[i] = 0 if plausible and not math.isnan(feet[i, 0]) else 1
        for k in range(ROW_SIZE):
            rows[i, k] = 0.0
        vx, vy, vz = velocities[i, 0], velocities[i, 1], velocities[i, 2]
        rows[i, ROW_T] = times[i]
        rows[i, ROW_CONTACT], rows[i, ROW_CONTACT + 1] = feet[i, 0], feet[i, 1]
        rows[i, ROW_CENTER], rows[i, ROW_CENTER + 1], rows[i, ROW_CENTER + 2] = cx, cy, cz
        rows[i, ROW_VELOCITY], rows[i, ROW_VELOCITY + 1], rows[i, ROW_VELOCITY + 2] = vx, vy, vz
        rows[i, ROW_OMEGA], rows[i, ROW_OMEGA + 1], rows[i, ROW_OMEGA + 2] = w1, w2, w3
        tau = times[i] - start_time
        rodrigues(w1 * tau, w2 * tau, w3 * tau, R, turn)
        for a in range(3):
            for b in range(3):
                rows[i, ROW_R + 3 * a + b] = turn[a, b]
        rows[i, ROW_ENERGY] = 0.5 * mass * (vx * vx + vy * vy + vz * vz) + spin + mass * gravity * cz
        # u = ċ − r ω × N, its part along the surface
        n1, n2, n3 = normals[i, 0], normals[i, 1], normals[i, 2]
        u1 = vx - radius * (w2 * n3 - w3 * n2)
        u2 = vy - radius * (w3 * n1 - w1 * n3)
        u3 = vz - radius * (w1 * n2 - w2 * n1)
        un = u1 * n1 + u2 * n2 + u3 * n3
        t1, t2, t3 = u1 - un * n1, u2 - un * n2, u3 - un * n3
        rows[i, ROW_SLIP] = math.sqrt(t1 * t1 + t2 * t2 + t3 * t3)
        rows[i, ROW_DISSIPATED] = dissipated
