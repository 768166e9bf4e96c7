"""A flying ball's landing, compiled (docs/design.md §1, "Flight"): the search of
``flight.Flight.landing`` for a ball in vacuum, its centre on the parabola c₀ + ċ₀τ + ½gτ², step
for step as flight.py's search takes it (the same looks, certificates, proposals and retries, the
same Brent's method), each look the compiled first foot search (``feet.nearest_feet``); only the
curvature a step is proposed from is the kernel's own (``physics.curvatures``), whose rounding
differs from numpy's in the last bits.

Where flight.py's search would need more than that first search (a foot not plausible, none
found, a bracket Brent's method refuses), where the track under the path finds the surface nearer
than the search did, or where the landing's own check fails, the search stops with LANDING_REFER:
flight.py then searches the whole flight itself (its robust foot search, its hints, its reasons
to stop), so every answer is flight.py's own; a landing or a flight to t_end this search finds is
what flight.py's would find, to round-off (tests/test_landing_kernel.py)."""

from __future__ import annotations

import math

from .bounds import box_bounds
from .feet import nearest_feet
from .interface import (
    BEST_SAMPLES, CLEAR_MARGIN, CLEAR_WITHIN, FIRST_STEP, GAP_TOLERANCE, GRAZE, GRAZE_LOOKS, GRID_SPACING, GROW_BY,
    LANDING_BATCH,
    LANDING_FLYING, LANDING_LANDED, LANDING_REFER, MAX_LOOKS, OUT_LANDING, PATH_ITERATIONS, SAMPLE_SLACK, SHRINK,
    SHRINK_MOST, TRACK, TRACK_BLIND, TRACK_LEAF, TRACK_MOST, TRACK_SLACK,
)
from .lowlevel import EXACT, JIT, data_pointer, landscape
from .physics import curvatures

EPS = 2.220446049250313e-16   # (the double's machine epsilon, as numpy's finfo gives it)
BRENT_ITERATIONS = 200


@JIT
def motion(start, gravity, t):
    """The centre and its velocity at t (start: t₀, c₀ (3), ċ₀ (3)), as ``Flight.centers``."""
    tau = t - start[0]
    return (start[1] + start[4] * tau, start[2] + start[5] * tau,
            start[3] + start[6] * tau + 0.5 * -gravity * tau * tau, start[4], start[5], start[6] + -gravity * tau)


@JIT
def primitive(p, w):
    """∫ √(p² + w²) dw (``Flight.path_time``)."""
    return 0.5 * (w * math.hypot(p, w) + (p * p * math.asinh(w / p) if p > 0 else 0.0))


@JIT
def path_time(gravity, vx, vy, vz, length):
    """``Flight.path_time``: the time after which the parabola from velocity v is ``length`` long."""
    if not length > 0.0:
        return 0.0
    speed, g = math.sqrt(vx * vx + vy * vy + vz * vz), gravity
    if g == 0.0:
        return length / speed if speed > 0 else math.inf
    w0, p = -vz, math.hypot(vx, vy)
    origin = primitive(p, w0)
    delta = 2.0 * length / (speed + math.sqrt(speed * speed + 2.0 * g * length))
    along = (primitive(p, w0 + g * delta) - origin) / g
    best = delta if along <= length else 0.0
    for _ in range(PATH_ITERATIONS):
        rate = math.hypot(p, w0 + g * delta)
        if not rate > 0.0:
            break
        after = delta + (length - along) / rate
        if after == delta:
            break
        delta, along = after, (primitive(p, w0 + g * after) - origin) / g
        if along <= length:
            best = max(best, delta)
    return best


@JIT
def chord(start, gravity, t, s):
    """|c(s) − c(t)|."""
    ax, ay, az, _, _, _ = motion(start, gravity, t)
    bx, by, bz, _, _, _ = motion(start, gravity, s)
    return math.sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay) + (bz - az) * (bz - az))


@JIT
def clear(start, gravity, r, t, s, h_t, h_s):
    """``Flight.clear``: the ball touches nothing between looks at t and s with gaps h_t, h_s."""
    h = min(h_t, h_s) - CLEAR_MARGIN * r
    delta = s - t
    e = gravity * delta * delta / 8.0
    if not h > e:
        return False
    c = chord(start, gravity, t, s)
    return 0.25 * c * c < (h - e) * (2.0 * r + h + e)


@JIT
def leaves_clear(r, gravity, h, rate, bend, speed):
    """``Flight._leaves_clear``."""
    a = 2.0 * (0.25 * speed * speed + r * bend + 0.25 * r * gravity)
    b, c = 2.0 * r * rate, 2.0 * r * h
    if not a > 0:
        return h / -rate if rate < 0 else math.inf
    return 2.0 * c / (math.sqrt(b * b + 4.0 * a * c) - b)


@JIT
def proposal(fn, d, r, gravity, h, x, y, speed, rate):
    """``Flight._proposal``: the step from a look with gap h at the foot (x, y), κ the largest
    principal curvature there (``physics.curvatures``; NaN where f cannot be evaluated); where the
    gap is not falling, at least the chord ``clear`` certifies if the gap does not fall."""
    landscape(fn, x, y, data_pointer(d))
    fx, fy = d[1], d[2]
    kappa, _ = curvatures(fx, fy, d[3], d[4], d[5], 1.0 / math.sqrt(1.0 + fx * fx + fy * fy))
    kappa = 0.0 if 0.0 > kappa else kappa   # (max(κ, 0), NaN kept)
    room = 1.0 - (h + r) * kappa
    bend = 2.0 * (gravity + speed * speed * kappa / room) if room > 0 else math.inf
    step = leaves_clear(r, gravity, h, rate, bend, speed) if bend < math.inf else 0.0
    if rate >= 0.0 and speed > 0.0:
        m = h - CLEAR_MARGIN * r
        step = max(step, 0.9 * 2.0 * math.sqrt(max(m, 0.0) * (2.0 * r + m)) / speed)
    return step


@JIT
def retry(start, gravity, r, t, s, h, h_s, speed):
    """``Flight._retry``: the step to try after the step from t to s was not certified."""
    step = s - t
    if h_s <= 0.0:
        return min(leaves_clear(r, gravity, h, (h_s - h) / step, 0.0, speed), SHRINK_MOST * step)
    m = min(h, h_s) - CLEAR_MARGIN * r
    allowed = 2.0 * math.sqrt(max(m, 0.0) * (2.0 * r + m))
    return max(min(0.9 * allowed / chord(start, gravity, t, s), SHRINK_MOST), SHRINK) * step


@JIT
def gap_at(fn, start, gravity, r, t, guess, hints, tips, spacing, reach_default, iterations, work):
    """One look at t (``Surface.feet_of``'s first search for the centre then): the gap, the foot in
    work's feet, normals and distances (their one row); NaN where the foot is not plausible
    (``Surface._plausible``), where flight.py's search would look further."""
    (centers, feet, normals, distances, below, sampled, spacings, nearest, s_centers, s_feet, s_normals, s_distances,
     d) = work
    cx, cy, cz, _, _, _ = motion(start, gravity, t)
    centers[0, 0], centers[0, 1], centers[0, 2] = cx, cy, cz
    k = 1 + guess.shape[0] // 2 + BEST_SAMPLES + hints.shape[0]
    nearest_feet(fn, centers, guess, hints, tips, spacing, reach_default, feet, normals, distances, below, sampled,
                 spacings, nearest, s_centers[:k], s_feet[:k], s_normals[:k], s_distances[:k], iterations, d)
    distance = distances[0]
    if not (math.isfinite(distance) and abs(distance) <= sampled[0] * (1.0 + SAMPLE_SLACK)):
        return math.nan
    if (distance > 0.0 and cz < below[0]) or (distance < 0.0 and cz > below[0]):
        return math.nan
    return distance - r


@JIT
def foot_out(out, status, t, work):
    """Write the answer: status, t and the last look's foot (x, y, normal (3), distance)."""
    feet, normals, distances = work[1], work[2], work[3]
    out[0], out[1] = status, t
    out[2], out[3] = feet[0, 0], feet[0, 1]
    out[4], out[5], out[6] = normals[0, 0], normals[0, 1], normals[0, 2]
    out[7] = distances[0]
    return status


@EXACT   # (compiled once, called from three places: inlined, the search took three times as long to compile)
def locate(fn, start, gravity, r, a, b, guess, hints, tips, spacing, reach_default, iterations, work, out):
    """``Flight._locate``: the root of the gap in [a, b] by Brent's method (scipy's brentq,
    step for step), then the look there; LANDING_REFER where a gap is not found or the bracket
    holds no sign change."""
    fa = gap_at(fn, start, gravity, r, a, guess, hints, tips, spacing, reach_default, iterations, work)
    if math.isnan(fa):
        return LANDING_REFER
    t = a
    if fa > 0.0:
        xtol, rtol = 4 * EPS * max(abs(b), 1.0), 4 * EPS
        xpre, xcur, fpre = a, b, fa
        fcur = gap_at(fn, start, gravity, r, b, guess, hints, tips, spacing, reach_default, iterations, work)
        if math.isnan(fcur):
            return LANDING_REFER
        xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
        t = math.nan
        if fcur == 0.0:
            t = xcur
        elif (fpre < 0.0) == (fcur < 0.0):
            return LANDING_REFER
        else:
            for _ in range(BRENT_ITERATIONS):
                if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
                    xblk, fblk = xpre, fpre
                    spre = scur = xcur - xpre
                if abs(fblk) < abs(fcur):
                    xpre, xcur, xblk = xcur, xblk, xcur
                    fpre, fcur, fblk = fcur, fblk, fcur
                delta = (xtol + rtol * abs(xcur)) / 2
                sbis = (xblk - xcur) / 2
                if fcur == 0.0 or abs(sbis) < delta:
                    t = xcur
                    break
                if abs(spre) > delta and abs(fcur) < abs(fpre):
                    if xpre == xblk:
                        stry = -fcur * (xcur - xpre) / (fcur - fpre)
                    else:
                        dpre = (fpre - fcur) / (xpre - xcur)
                        dblk = (fblk - fcur) / (xblk - xcur)
                        stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
                    if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                        spre, scur = scur, stry
                    else:
                        spre, scur = sbis, sbis
                else:
                    spre, scur = sbis, sbis
                xpre, fpre = xcur, fcur
                if abs(scur) > delta:
                    xcur += scur
                else:
                    xcur += delta if sbis > 0 else -delta
                fcur = gap_at(fn, start, gravity, r, xcur, guess, hints, tips, spacing, reach_default, iterations,
                              work)
                if math.isnan(fcur):
                    return LANDING_REFER
        if math.isnan(t):
            return LANDING_REFER
    if math.isnan(gap_at(fn, start, gravity, r, t, guess, hints, tips, spacing, reach_default, iterations, work)):
        return LANDING_REFER
    return foot_out(out, LANDING_LANDED, t, work)


@JIT
def search(fn, start, gravity, r, t_end, hints, tips, spacing, reach_default, iterations, times, guess, work, out):
    """``Flight._search`` (with ``_clear_off`` and ``_touch``): LANDING_LANDED (out: t, the foot),
    LANDING_FLYING (still flying at t_end) or LANDING_REFER. flight.py looks at a batch of times
    at once (one vectorised call) and uses them in turn up to the first that ends the batch; here
    each is looked at when its turn comes (``times``: the batch's), so the looks after that one
    are not taken at all: every look used is the same, with the same guess."""
    feet, normals, distances = work[1], work[2], work[3]
    none, one = guess[:0], guess[:2]
    tol, floor = GAP_TOLERANCE * r, GRAZE * r
    t = start[0]
    h = gap_at(fn, start, gravity, r, t, none, hints, tips, spacing, reach_default, iterations, work)
    if math.isnan(h):
        return LANDING_REFER
    fx, fy, dd = feet[0, 0], feet[0, 1], distances[0]
    m1, m2, m3 = normals[0, 0], normals[0, 1], normals[0, 2]
    if h <= floor:   # just lifted off: looks FIRST_STEP after it, doubling, until it is clear
        step = FIRST_STEP
        cleared = False
        while not cleared:
            if t >= t_end:
                break
            n, now, size = 0, t, step
            while n < LANDING_BATCH and now < t_end:
                now = min(now + size, t_end)
                times[n] = now
                n += 1
                size *= 2.0
            guess[0], guess[1] = fx, fy
            for i in range(n):
                s = times[i]
                h_s = gap_at(fn, start, gravity, r, s, one, hints, tips, spacing, reach_default, iterations, work)
                if math.isnan(h_s):
                    return LANDING_REFER
                if h_s < -tol:
                    guess[0], guess[1] = fx, fy
                    return locate(fn, start, gravity, r, t, s, one, hints, tips, spacing, reach_default, iterations,
                                  work, out)
                if h_s > floor or s - start[0] > CLEAR_WITHIN:
                    if h_s <= floor:   # it never left the surface
                        return foot_out(out, LANDING_LANDED, s, work)
                    t, h = s, h_s
                    fx, fy, dd = feet[0, 0], feet[0, 1], distances[0]
                    m1, m2, m3 = normals[0, 0], normals[0, 1], normals[0, 2]
                    cleared = True
                    break
                t, h, step = s, h_s, 2.0 * step
                fx, fy, dd = feet[0, 0], feet[0, 1], distances[0]
                m1, m2, m3 = normals[0, 0], normals[0, 1], normals[0, 2]
        if t >= t_end:
            return LANDING_FLYING
    cap = math.inf
    last = before = math.inf
    grazing = 0
    sure = chosen = math.nan   # (not yet computed for this look)
    for _ in range(MAX_LOOKS):
        if t >= t_end:
            return LANDING_FLYING
        guess[0], guess[1] = fx, fy
        _, _, _, vx, vy, vz = motion(start, gravity, t)
        speed = math.sqrt(vx * vx + vy * vy + vz * vz)
        rate = vx * m1 + vy * m2 + vz * m3
        if h <= tol or (h <= floor and (rate >= 0.0 or grazing >= GRAZE_LOOKS)):   # ``_touch``
            if h > 0.0 and rate < 0.0:
                for k in range(4):
                    times[k] = min(t + (1.1, 2.0, 4.0, 8.0)[k] * h / -rate, t_end)
                for k in range(4):
                    b = times[k]
                    h_b = gap_at(fn, start, gravity, r, b, one, hints, tips, spacing, reach_default, iterations,
                                 work)
                    if math.isnan(h_b):
                        return LANDING_REFER
                    if h_b < -tol:
                        return locate(fn, start, gravity, r, t, b, one, hints, tips, spacing, reach_default, iterations,
                                      work, out)
                    if b >= t_end:
                        return LANDING_FLYING if h_b > tol else foot_out(out, LANDING_LANDED, b, work)
            out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7] = LANDING_LANDED, t, fx, fy, m1, m2, m3, dd
            return LANDING_LANDED
        if math.isnan(sure):
            sure = path_time(gravity, vx, vy, vz, h - CLEAR_MARGIN * r)
        if t + sure >= t_end:
            return LANDING_FLYING
        if math.isnan(chosen):
            chosen = proposal(fn, work[12], r, gravity, h, fx, fy, speed, rate)
        step = min(chosen, GROW_BY * last)
        step = min(step, r / speed if speed > 0 else step, cap)
        step = max(step, sure)
        growth = min(max(last / before, 1.0), GROW_BY) if rate >= 0.0 and last < math.inf else 1.0
        count = LANDING_BATCH if growth > 1.0 and cap == math.inf else 1
        acc = 0.0
        for k in range(count):
            acc += step * math.pow(growth, float(k))
            times[k] = t + acc
        if not times[count - 1] < t_end:
            n = 0
            while times[n] < t_end:
                n += 1
            times[n] = t_end
            count = n + 1
        for i in range(count):
            s = times[i]
            h_s = gap_at(fn, start, gravity, r, s, one, hints, tips, spacing, reach_default, iterations, work)
            if math.isnan(h_s):
                return LANDING_REFER
            certified = h_s > -tol and h_s > 0.0 and clear(start, gravity, r, t, s, h, h_s)
            if not certified:
                if h_s < -tol and s <= t + sure:
                    return locate(fn, start, gravity, r, t, s, one, hints, tips, spacing, reach_default, iterations,
                                  work, out)
                certified = h_s > -tol and s <= t + sure
            if not certified:
                cap = retry(start, gravity, r, t, s, h, h_s, speed)
                break
            grazing = grazing + 1 if h_s <= floor else 0
            t, h, cap, last, before = s, h_s, math.inf, s - t, last
            fx, fy, dd = feet[0, 0], feet[0, 1], distances[0]
            m1, m2, m3 = normals[0, 0], normals[0, 1], normals[0, 2]
            sure = chosen = math.nan
            if h <= floor or t >= t_end:
                break
    return LANDING_REFER


@JIT
def track_clear(fn, start, gravity, r, t, s, d, tape, bounds):
    """``Flight.track`` finds nothing: no surface sample under the centre's path between t and s
    (every TRACK × r of its length) within r below the centre. The same answer as taking every
    sample: where the landscape has a tape (``Landscape.tape``; none: every sample is taken), a
    stretch of samples is passed over when the landscape's bounds over the box its path lies in
    (``bounds.box_bounds``, sound for the values the samples would compute) put the surface there
    below every centre of the stretch by more than the samples' threshold. The stretches double
    while they are passed over and halve, down to TRACK_LEAF samples, where they are not; those
    are sampled, and as many again as the bounds failed in a row before (at most TRACK_BLIND), so
    that where they never succeed (the path low over a rough surface, a domain's edge) they cost
    little beside the samples."""
    if not s > t:
        return True
    _, _, _, ax, ay, az = motion(start, gravity, t)
    _, _, _, bx, by, bz = motion(start, gravity, s)
    speed = max(math.sqrt(ax * ax + ay * ay + az * az), math.sqrt(bx * bx + by * by + bz * bz))
    count = int(min(math.ceil(speed * (s - t) / (TRACK * r)), 100.0 * TRACK_MOST)) + 1
    near = r * (1.0 - TRACK_SLACK)
    first, stretch, blind, after = 1, TRACK_LEAF, TRACK_LEAF, 0   # (after: the sample the bounds are tried from)
    while first <= count:
        last = min(first + stretch - 1, count)
        if tape.shape[0] > 0 and first >= after and last - first + 1 >= TRACK_LEAF:
            t0, t1 = t + (s - t) * (first / count), t + (s - t) * (last / count)
            x0, y0, z0, _, _, _ = motion(start, gravity, t0)
            x1, y1, z1, _, _, _ = motion(start, gravity, t1)
            # the samples' centres lie in the box (x and y are monotonic in time, rounded too); z
            # is concave, so lowest at an end, the samples' rounded values within a few ulps of it
            tau = max(abs(t0 - start[0]), abs(t1 - start[0]))
            low = min(z0, z1) - 8.0 * EPS * (abs(start[3]) + abs(start[6]) * tau + gravity * tau * tau) - 1e-300
            _, f_hi = box_bounds(fn, tape, bounds, min(x0, x1), max(x0, x1), min(y0, y1), max(y0, y1))
            if f_hi < low - near - 8.0 * EPS * (abs(low) + abs(f_hi) + r):
                first, stretch, blind = last + 1, 2 * stretch, TRACK_LEAF
                continue
            if stretch > TRACK_LEAF:
                stretch = max(stretch // 2, TRACK_LEAF)
                continue
            after, blind = first + blind, min(2 * blind, TRACK_BLIND)
        for k in range(first, last + 1):
            cx, cy, cz, _, _, _ = motion(start, gravity, t + (s - t) * (k / count))
            landscape(fn, cx, cy, data_pointer(d))
            if cz - d[0] < near:
                return False
        first = last + 1
    return True


@EXACT
def land(fn, start, gravity, radius, t_end, hints, tips, reach_default, iterations, out, times, guess,
         centers, feet, normals, distances, below, sampled, spacings, nearest, start_centers, start_feet, start_normals,
         start_distances, d, tape, bounds):
    """``Flight.landing`` for a ball in vacuum from ``start`` (t₀, c₀ (3), ċ₀ (3)) until t_end, on
    the surface ``fn`` with flight.py's ``Surface`` hints and tips: out[0] LANDING_LANDED (out[1]
    the time, out[2:8] the foot: x, y, normal (3), signed distance), LANDING_FLYING (still flying
    at t_end) or LANDING_REFER (flight.py searches this flight itself: see the module). times:
    LANDING_BATCH; the rest: work arrays for a look (``feet.nearest_feet``'s, with room for its starts);
    tape: the landscape's (``Landscape.tape``), bounds its scratch (``track_clear``)."""
    r = radius
    spacing = GRID_SPACING * r   # (the looks' grids)
    work = (centers, feet, normals, distances, below, sampled, spacings, nearest, start_centers, start_feet,
            start_normals, start_distances, d)
    for k in range(OUT_LANDING):
        out[k] = math.nan
    status = search(fn, start, gravity, r, t_end, hints, tips, spacing, reach_default, iterations, times, guess, work,
                    out)
    if status == LANDING_REFER:
        out[0] = status
        return
    end = t_end if status == LANDING_FLYING else out[1]
    if not track_clear(fn, start, gravity, r, start[0], end, d, tape, bounds):
        out[0] = LANDING_REFER
        return
    if status == LANDING_FLYING:
        out[0] = status
        return
    # the landing's own check (``Flight._verify``): the centre r from the foot's surface point, no nearer one
    t, x, y = out[1], out[2], out[3]
    cx, cy, cz, _, _, _ = motion(start, gravity, t)
    landscape(fn, x, y, data_pointer(d))
    far = math.sqrt((cx - x) * (cx - x) + (cy - y) * (cy - y) + (cz - d[0]) * (cz - d[0]))
    if math.isnan(gap_at(fn, start, gravity, r, t, guess[:0], hints, tips, spacing, reach_default, iterations, work)):
        out[0] = LANDING_REFER
        return
    if not (abs(far - r) <= 2.0 * GRAZE * r and distances[0] >= far - 2.0 * GRAZE * r):
        out[0] = LANDING_REFER
