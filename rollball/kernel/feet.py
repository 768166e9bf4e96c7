"""A flying ball's closest surface points, compiled: the first search of ``flight.Surface.feet_of``
(the samples about each centre, the starts of Newton's method, the nearest of the feet it finds)."""

from __future__ import annotations

import math

from .interface import SAMPLES, SAMPLES_LEAST
from .lowlevel import EXACT, JIT, data_pointer, landscape
from .physics import closest_points


@JIT
def grid_side(reach, spacing):
    """The samples per side of a look's grid over a square of half-width ``reach``: as many as
    put them at most ``spacing`` apart, at least SAMPLES_LEAST and at most SAMPLES (``spacing`` 0,
    a reach not finite: SAMPLES)."""
    if not spacing > 0.0:
        return SAMPLES
    wanted = 2.0 * reach / spacing
    if not wanted < SAMPLES - 1:   # (NaN and inf too)
        return SAMPLES
    return max(SAMPLES_LEAST, int(math.ceil(wanted)) + 1)


@JIT
def grid_unit(a, side):
    """The a-th of ``side`` points from -1 to 1 evenly spaced, as numpy's linspace gives it."""
    if a == side - 1:
        return 1.0
    return a * (2.0 / (side - 1)) + -1.0


@JIT
def nearer(fn, d, x, y, cx, cy, cz, j, f0, f1, f2, j0, j1, j2):
    """The three nearest samples so far (squared distances f, indices j; inf and -1 for none) with
    the sample j at (x, y) taken in: evaluated only where it could be among them. Among equally
    near samples the smaller index first; a sample whose distance is not finite is never taken."""
    dx, dy = x - cx, y - cy
    if dx * dx + dy * dy > f2:
        return f0, f1, f2, j0, j1, j2
    landscape(fn, x, y, data_pointer(d))
    dz = d[0] - cz
    far = dx * dx + dy * dy + dz * dz
    if not far < math.inf:   # (NaN too)
        return f0, f1, f2, j0, j1, j2
    if far < f0 or far == f0 and j < j0:
        return far, f0, f1, j, j0, j1
    if far < f1 or far == f1 and j < j1:
        return f0, far, f1, j0, j, j1
    if far < f2 or far == f2 and j < j2:
        return f0, f1, far, j0, j1, j
    return f0, f1, f2, j0, j1, j2


@JIT
def ring_beyond(reach, side, lo, hi, f2):
    """Whether every sample of the ring of grid points lo..hi (and so every ring outside it) is
    horizontally farther from the grid's middle than sqrt(f2): its nearest side's offset, taken
    a millionth short for round-off, squared beyond f2."""
    near = reach * min(abs(grid_unit(lo, side)), abs(grid_unit(hi, side))) * (1.0 - 1e-6)
    return near * near > f2


@EXACT
def nearest_feet(fn, centers, guess, hints, tips, spacing, reach_default, feet, normals, distances, below, sampled,
                 spacings, nearest, start_centers, start_feet, start_normals, start_distances, iterations, d):
    """For each centre (n, 3): the surface below it (``below``), a square grid of half-width
    reach = |c_z − f(c_x, c_y)| (2 ``reach_default`` where that is not finite) about it, its samples
    at most ``spacing`` apart (``grid_side``; the spacing they are at in ``spacings``), and the
    ``hints`` (m, 3: x, y, spacing) sampled, the distance to the nearest sample
    (``sampled``) and the b nearest samples' (x, y) (``nearest``, (n, 2 b), b ≤ 3: nearest first,
    the earlier first among equals); then Newton's method (``closest_points``) from
    the k starts of each centre (start_* (n k, ·)): the point below it, ``guess`` (none or one
    (x, y) for all), the nearest samples and the hints; a ``tips`` point (t, 3: x, y, f) is put in
    where it is nearer than the foot found (or none was: its distance |c − T|, its normal from it
    to c); of the k, the nearest (smallest |D|, the first among equals) is the centre's foot:
    ``feet``, ``normals``, ``distances`` (NaN where none converged). What flight.Surface.feet_of
    computes in numpy, number for number (EXACT), except which of equally near samples start."""
    n, m, best_samples = centers.shape[0], hints.shape[0], nearest.shape[1] // 2
    guessed = 1 if guess.shape[0] == 2 else 0
    k = 1 + guessed + best_samples + m
    for i in range(n):
        cx, cy, cz = centers[i, 0], centers[i, 1], centers[i, 2]
        landscape(fn, cx, cy, data_pointer(d))
        below[i] = d[0]
        reach = abs(cz - d[0])
        if not math.isfinite(reach):
            reach = 2.0 * reach_default
        side = grid_side(reach, spacing)
        spacings[i] = 2.0 * reach / (side - 1)
        # the grid's samples ring by ring (of grid points) from its middle outwards, each evaluated
        # only where it could be among the b nearest (``nearer``): a sample horizontally farther
        # than the b-th nearest so far (dx² + dy² > f2) is farther in space too (a sum of squares
        # rounds monotonically, so round-off cannot make it nearer), and a ring wholly beyond that
        # (``ring_beyond``) ends the grid. The same b samples as every sample taken in order of
        # their index j (equally near ones kept in that order), for about 1 - π/4 fewer evaluations
        # where the surface below is level, more where it slopes.
        f0 = f1 = f2 = math.inf
        j0 = j1 = j2 = -1
        lo0, hi0 = (side - 1) // 2, side // 2
        for ring in range(lo0 + 1):
            if ring_beyond(reach, side, lo0 - ring, hi0 + ring, f2):
                break
            for a in range(lo0 - ring, hi0 + ring + 1):
                edge = a == lo0 - ring or a == hi0 + ring
                b = lo0 - ring
                while b <= hi0 + ring:
                    x, y = cx + reach * grid_unit(a, side), cy + reach * grid_unit(b, side)
                    f0, f1, f2, j0, j1, j2 = nearer(fn, d, x, y, cx, cy, cz, a * side + b, f0, f1, f2, j0, j1, j2)
                    b += 1 if edge or b == hi0 + ring else hi0 + ring - b
        for q in range(m):
            f0, f1, f2, j0, j1, j2 = nearer(fn, d, hints[q, 0], hints[q, 1], cx, cy, cz, side * side + q,
                                            f0, f1, f2, j0, j1, j2)
        best = f0
        sampled[i] = math.sqrt(best)
        # (fewer finite samples than b: the first others, as a sort would give them)
        for s in range(best_samples):
            j = j0 if s == 0 else j1 if s == 1 else j2
            if j < 0:
                j = 0
                while j == j0 or j == j1 or j == j2:
                    j += 1
                if s == 0:
                    j0 = j
                elif s == 1:
                    j1 = j
                else:
                    j2 = j
            if j < side * side:
                x, y = cx + reach * grid_unit(j // side, side), cy + reach * grid_unit(j % side, side)
            else:
                x, y = hints[j - side * side, 0], hints[j - side * side, 1]
            nearest[i, 2 * s], nearest[i, 2 * s + 1] = x, y
        for s in range(k):
            row = i * k + s
            start_centers[row, 0], start_centers[row, 1], start_centers[row, 2] = cx, cy, cz
            if s == 0:
                x, y = cx, cy
            elif s < 1 + guessed:
                x, y = guess[0], guess[1]
            elif s < 1 + guessed + best_samples:
                q = s - 1 - guessed
                x, y = nearest[i, 2 * q], nearest[i, 2 * q + 1]
            else:
                x, y = hints[s - 1 - guessed - best_samples, 0], hints[s - 1 - guessed - best_samples, 1]
            start_feet[row, 0], start_feet[row, 1] = x, y
    closest_points(fn, start_centers, start_feet, start_normals, start_distances, iterations, d)
    for row in range(n * k):
        for q in range(tips.shape[0]):
            a1 = start_centers[row, 0] - tips[q, 0]
            a2 = start_centers[row, 1] - tips[q, 1]
            a3 = start_centers[row, 2] - tips[q, 2]
            far = math.sqrt(a1 * a1 + a2 * a2 + a3 * a3)
            if not abs(start_distances[row]) <= far and far > 0.0:
                start_feet[row, 0], start_feet[row, 1] = tips[q, 0], tips[q, 1]
                start_normals[row, 0], start_normals[row, 1], start_normals[row, 2] = a1 / far, a2 / far, a3 / far
                start_distances[row] = far
    for i in range(n):
        chosen, size = i * k, math.inf
        for row in range(i * k, i * k + k):
            here = abs(start_distances[row])
            if here < size:
                chosen, size = row, here
        feet[i, 0], feet[i, 1] = start_feet[chosen, 0], start_feet[chosen, 1]
        for a in range(3):
            normals[i, a] = start_normals[chosen, a]
        distances[i] = start_distances[chosen]
