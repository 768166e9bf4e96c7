"""A ball off the surface: free flight, exact; the landing, located; the impact (docs/design.md §1).

In flight the centre falls freely and the spin is constant, so the motion is closed form:
c(t) = c₀ + ċ₀ τ + ½ g τ², ω constant, R(t) = exp(A(ω) τ) R₀ with τ = t − t₀ (the rotation
vector's exponential, exact at any angle: Rodrigues' formula in the kernel's rows, scipy's in
``state``): no integrator, no step error. The ball lands where the centre's distance to the
surface first comes down to r. That distance is measured to the centre's closest surface point
(its foot), found by Newton's method on (c − φ(α)) ∥ N(α); the first root
in time is never stepped over (each step is certified to hold none, from the distance being
1-Lipschitz in the centre and the empty balls about the ends, ``landing``; provided each look's
distance is the true one) and is then located by a bracketing root finder to round-off. The impact there is an impulse
at the contact point (``impact``): the normal velocity turns into −e times itself, the tangential
impulse is Coulomb's, sticking where μ allows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernel, machine_code
from .geometry import cross, fit_ratio, rotation
from .kernel.interface import (
    BEST_SAMPLES, CLEAR_MARGIN, CLEAR_WITHIN, FIRST_STEP, FOOT_ITERATIONS, GAP_TOLERANCE, GRAZE, GRAZE_LOOKS,
    GRID_SPACING, GROW_BY,
    LANDING_BATCH, LANDING_FLYING, LANDING_LANDED, MAX_LOOKS, OUT_LANDING, PATH_ITERATIONS, ROW_SIZE, ROW_SLICES,
    SAMPLE_SLACK, SHRINK, SHRINK_MOST, TRACK, TRACK_MOST, TRACK_SLACK,
)
from .trajectory import SLIP_SPEED

# A rebound whose apex above the surface would be lower than this share of the radius ends in
# contact: the bounces after it last 2 v/(g (1 − e)) together, v = sqrt(2 g · REST_HEIGHT · r):
# with r = 0.1 m about a millimetre a second and a few milliseconds even at e = 0.9, far below
# what can be seen or matters, and an endless series of ever smaller bounces is cut off.
REST_HEIGHT = 1e-6

# The landing search's numbers (the compiled search, ``kernel.landing``, shares them): kernel/interface.py
ZOOM_SAMPLES = 9         # where no foot found is as near as the nearest sample: finer grids, per side...
ZOOM_ROUNDS = 200        # ...at most this many, each over ± a spacing about the last nearest points...
ZOOM_BEAM = 24           # ...this many of them
POLISH_STEP = 1e-9       # Newton's last step (× (1 + |α|)) below which ``_polish`` takes a foot as found
MAX_HINTS = 8            # surface points the search was shown it missed, before a run stops
REFER = "refer"          # ``Surface.land``: the kernel's search leaves this flight to flight.py's own
KEPT_ROWS = 4096         # a flight's rows made through arrays a surface keeps, at most (``Surface.flight_rows``)


class OffLandscape(Exception):
    """The landing search cannot go on: ``reason`` "off_domain" where the landscape cannot be
    evaluated below the flying ball (outside its domain: there is nothing to land on),
    "no_foot" where its nearest surface point is not found (Newton's method converges to no
    point as near as the nearest sample of the surface), "narrow_feature" where a surface point
    under the centre's path is within r of it although the search, blind to it, certified the
    step clear (``Flight.track``). ``time`` is the last time a closest point was found,
    ``center`` the centre then, ``point`` (x, y) where it happened (the centre's, or the feature's)."""

    def __init__(self, time: float, center: np.ndarray, reason: str = "off_domain", point=None,
                 value: float = math.nan):
        super().__init__(f"no surface below the ball after t = {time:.6g} s" if reason == "off_domain" else
                         f"the landing search stops at t = {time:.6g} s ({reason})")
        self.time, self.center, self.reason, self.value = time, center, reason, value
        self.point = (float(center[0]), float(center[1])) if point is None else (float(point[0]), float(point[1]))


def rest_speed(radius, gravity):
    """The slowest rebound that still flies (m/s): apex REST_HEIGHT · r above the surface (floats
    or arrays of them: a sweep's runs)."""
    return np.sqrt(2.0 * gravity * REST_HEIGHT * radius)


@dataclass(frozen=True)
class FreeState:
    """The ball at time t off (or just touching) the surface: centre, its velocity, ω, R."""

    t: float
    center: np.ndarray     # (3,)
    velocity: np.ndarray   # (3,)
    omega: np.ndarray      # (3,) world frame
    R: np.ndarray          # (3, 3) body to world

    @classmethod
    def from_row(cls, row: np.ndarray) -> "FreeState":
        """The state a recorded row holds (``kernel.interface.ROW_SLICES``)."""
        return cls(float(row[ROW_SLICES["t"]][0]), row[ROW_SLICES["center"]].copy(),
                   row[ROW_SLICES["velocity"]].copy(), row[ROW_SLICES["omega"]].copy(),
                   row[ROW_SLICES["R"]].reshape(3, 3).copy())


@dataclass(frozen=True)
class Foot:
    """The centre's closest surface point: contact coordinates, the surface's unit normal there,
    and the centre's signed distance along it (> 0 above the surface)."""

    x: float
    y: float
    normal: np.ndarray
    distance: float
    lost: bool = False   # NaN because no foot is as near as the nearest surface sample (not off the domain)


@dataclass(frozen=True)
class Bounces:
    """What ``Surface.bounces`` did: how it ended (``kernel.BOUNCES_*``), the rows it recorded,
    the landings it made (t, x, y, the normal speed, the energy lost each), the energy dissipated
    then; ``state``: the ball just after its last impact where it settled (``foot`` (x, y),
    ``sticking``), else the start of the flight it stopped in (whose first row is recorded);
    ``landing``: where its rows did not fit (BOUNCES_ROOM), the landing search's answer for that
    flight (``Flight.landing``'s)."""

    status: float
    rows: np.ndarray
    landings: np.ndarray
    dissipated: float
    state: FreeState
    foot: tuple[float, float]
    sticking: bool
    landing: tuple | None


def bounce_scratch(tape: int, hints: int = 0, tips: int = 0) -> dict[str, np.ndarray]:
    """The scratch of ``kernel.bounces.bounces`` (``kernel.interface.FLIGHT_SCRATCH``) for rows of
    up to KEPT_ROWS flights' rows, a landscape whose tape has ``tape`` rows and so many ``hints`` and
    ``tips`` (their arrays, to be filled)."""
    k, size = 2 + BEST_SAMPLES + hints, KEPT_ROWS
    return dict(
        hints=np.empty((hints, 3)), tips=np.empty((tips, 3)), landed=np.empty((kernel.BOUNCES_CHAIN, 5)),
        refer=np.empty(size, dtype=np.int64), hit=np.empty(kernel.HIT_SIZE), times=np.empty(LANDING_BATCH),
        guess=np.empty(2), centers=np.empty((1, 3)), feet=np.empty((1, 2)), normals=np.empty((1, 3)),
        distances=np.empty(1), below=np.empty(1), sampled=np.empty(1), spacings=np.empty(1),
        nearest=np.empty((1, 2 * BEST_SAMPLES)), start_centers=np.empty((k, 3)), start_feet=np.empty((k, 2)),
        start_normals=np.empty((k, 3)), start_distances=np.empty(k), row_times=np.empty(size),
        row_centers=np.empty((size, 3)), row_velocities=np.empty((size, 3)), row_feet=np.empty((size, 2)),
        row_normals=np.empty((size, 3)), row_distances=np.empty(size), turn=np.empty((3, 3)), d=np.empty(6),
        bounds=np.empty((tape, 2)))


class Surface:
    """The landscape as flight needs it: the closest point to a centre."""

    def __init__(self, landscape, values=(), reach: float = 1.0):
        self.landscape, self.values = landscape, tuple(values)
        self.reach_default = reach   # m: how far to look where the point below is undefined
        # surface points (x, y, f) flights left from, measured directly (a closest point at the tip
        # of a cone is no root of Newton's method; elsewhere the feet Newton finds are as near)
        self.tips: list[np.ndarray] = []
        # surface points (x, y, the spacing they were sampled at) a flight found under its centre's
        # path nearer than the feet it was given (a feature narrower than the grid): every foot
        # search samples them and starts there
        self.hints: list[np.ndarray] = []
        self._record = landscape.record(self.values)   # (held while its address is in use)
        self._rows_call: machine_code.Arguments | None = None   # flight_rows', packed for up to KEPT_ROWS rows

    def evaluate(self, x, y) -> np.ndarray:
        """f, f_x, f_y, f_xx, f_xy, f_yy at the points (x, y) (``Landscape.evaluate``'s)."""
        return self.landscape.evaluate(x, y, self.values)

    def feet(self, centers: np.ndarray, guesses: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For centres (n, 3) from first guesses (n, 2): the feet (n, 2), the unit normals there
        (n, 3) and the signed distances (n,), by Newton's method on the gradient of ½|c − φ(α)|²:
        b = ((c − φ)·φ_x, (c − φ)·φ_y) = 0, with the Hessian G − d_z H (G = φ_αᵀφ_α, H the
        second derivatives of f, d = c − φ). NaN where it does not converge (outside the
        landscape's domain, or beyond a focal point where the nearest point is elsewhere)."""
        c = np.asarray(centers, dtype=float).reshape(-1, 3)
        n = len(c)
        def make(fn):   # (the iteration runs compiled: kernel.physics.closest_points)
            arrays = np.empty((n, 3)), np.empty((n, 2)), np.empty((n, 3)), np.empty(n)
            call = machine_code.Arguments("closest_points", fn=fn, centers=arrays[0], feet=arrays[1],
                                          normals=arrays[2], distances=arrays[3], iterations=FOOT_ITERATIONS,
                                          d=np.empty(6))
            return (call, *arrays)

        packed = self.landscape.packed(self.values, ("closest_points", n), make)
        call, at, alpha, normal, distance = packed
        at[:], alpha[:] = c, np.asarray(guesses, dtype=float).reshape(-1, 2)
        call()
        return alpha.copy(), normal.copy(), distance.copy()

    def foot(self, center: np.ndarray, guess=None, spacing: float = 0.0) -> Foot:
        """The closest surface point to ``center``: the nearest of the feet Newton's method
        finds from ``guess`` (the last foot), from the point below the centre and from the
        nearest points of a grid over the square the closest point must lie in (within the
        distance to the point below, |c_z − f(c_x, c_y)|, of the centre), its samples at most
        ``spacing`` apart and at most SAMPLES per side (``spacing`` 0: SAMPLES per side; a flight
        of a ball of radius r looks with GRID_SPACING × r, ``kernel.feet.grid_side``)."""
        return self.feet_of(np.asarray(center, dtype=float)[None, :], guess, spacing)[0]

    def feet_of(self, centers: np.ndarray, guess=None, spacing: float = 0.0) -> list[Foot]:
        """``foot`` for each of the centres (n, 3), all at once.

        The foot is the nearest (smallest |D|) of the points Newton's method converges to (which
        may be any point where c − φ is along N: a farther foot, on the far side of a fold, has
        a signed distance of either sign). It is accepted only where it is no farther than the
        nearest surface point sampled (the grid, the point below the centre, the ``hints``) and
        on the centre's side of the surface (above it where c_z > f(c_x, c_y)); elsewhere a damped
        Newton's method starts again from the same points (``_polish``), then both from the
        points a beam search of the samples ends at (``_zoom``); where that search converged to a
        point with no root near (a kink), that point is the foot; where none passes even then the
        foot is NaN, and ``lost`` where the centre is over the landscape."""
        c = np.asarray(centers, dtype=float).reshape(-1, 3)
        n = len(c)
        hints = np.array(self.hints).reshape(-1, 3)   # (x, y, the spacing it was found at)
        alpha, normal, distance, below, sampled, spacings, points = self._first_feet(c, guess, hints, spacing)
        ok = self._plausible(c, below, distance, sampled)
        if not ok.all():   # Newton's method at round-off, its step not below the compiled test's?
            starts = [c[:, None, :2]] + ([] if guess is None else [np.broadcast_to(np.asarray(guess, float),
                                                                                   (n, 1, 2))])
            starts.append(points)   # (``_first_feet``'s starts)
            if len(hints):
                starts.append(np.broadcast_to(hints[None, :, :2], (n, len(hints), 2)))
            starts = np.concatenate(starts, axis=1)
            bad = np.flatnonzero(~ok)
            alpha, normal, distance = alpha.copy(), normal.copy(), distance.copy()
            a2, n2, d2 = self._polish(c[bad], starts[bad])
            nearer = np.isnan(distance[bad]) | (np.abs(d2) < np.abs(distance[bad]))
            take = bad[nearer]
            alpha[take], normal[take], distance[take] = a2[nearer], n2[nearer], d2[nearer]
            ok[bad] = self._plausible(c[bad], below[bad], distance[bad], sampled[bad])
        if not ok.all():   # the foot was not found from these starts: a search of the samples for starts
            bad = np.flatnonzero(~ok)
            spacing = np.full((len(bad), BEST_SAMPLES), 1.0) * spacings[bad, None]
            points = points[bad]
            if len(hints):
                shown = np.broadcast_to(hints[None, :, :2], (len(bad), len(hints), 2))
                points = np.concatenate([points, shown], axis=1)
                spacing = np.concatenate([spacing, np.broadcast_to(hints[None, :, 2], (len(bad), len(hints)))], axis=1)
            points, zoomed, finest = self._zoom(c[bad], points, spacing)
            sampled[bad] = np.minimum(sampled[bad], zoomed)
            a2, n2, d2 = self._from_starts(c[bad], points)
            redo = np.isnan(d2)   # (Newton's method at round-off, its step not below the compiled test's)
            if redo.any():
                a3, n3, d3 = self._polish(c[bad][redo], points[redo])
                a2[redo], n2[redo], d2[redo] = a3, n3, d3
            alpha, normal, distance = alpha.copy(), normal.copy(), distance.copy()
            nearer = np.isnan(distance[bad]) | (np.abs(d2) < np.abs(distance[bad]))
            take = bad[nearer]
            alpha[take], normal[take], distance[take] = a2[nearer], n2[nearer], d2[nearer]
            ok[bad] = self._plausible(c[bad], below[bad], distance[bad], sampled[bad])
            # no foot where the nearest sample converged to a point: a kink or a like point, where
            # no Newton's root is (the distance is not smooth there), nearest to round-off: the foot
            # is that point, its distance less the most the spacing it was last sampled at can hide
            # (|φ_α| ≤ √(1 + |∇f|²) per unit of α), its normal the direction from it to the centre
            kinked = ~ok[bad] & (finest <= 1e-12 * (1.0 + np.abs(points[:, 0]).max(axis=1)))
            for i in np.flatnonzero(kinked):
                j, point = bad[i], points[i, 0]
                d = self.evaluate(point[0], point[1])
                arm = c[j] - np.array([point[0], point[1], d[0]])
                far = float(np.linalg.norm(arm))
                if not (far > 0.0 and np.isfinite([far, below[j], *d[:3]]).all()):
                    continue   # (over no landscape, or at the edge of its domain: nothing found)
                side = 1.0 if c[j, 2] >= below[j] else -1.0
                alpha[j], normal[j] = point, side * arm / far
                distance[j] = side * max(far - 2.0 * finest[i] * math.sqrt(1.0 + d[1] ** 2 + d[2] ** 2), 0.0)
                ok[j] = True
        found = []
        for j in range(n):
            if not ok[j]:
                lost = bool(np.isfinite(sampled[j]) and np.isfinite(below[j]))
                found.append(Foot(math.nan, math.nan, np.full(3, math.nan), math.nan, lost))
                continue
            found.append(Foot(float(alpha[j, 0]), float(alpha[j, 1]), normal[j], float(distance[j])))
        return found

    def _first_feet(self, c, guess, hints, spacing):
        """The first search of ``feet_of``, compiled (``kernel.feet.nearest_feet``): for the
        centres c (n, 3) the feet (n, 2), normals (n, 3), signed distances (n,) Newton's method
        finds from the point below, ``guess``, the BEST_SAMPLES nearest of the grid (its samples
        at most ``spacing`` apart, at most SAMPLES per side) and the ``hints``, the nearest of them
        with the ``tips`` put in; the heights below (n,), the nearest sampled distance (n,), the
        grid's spacing (n,) and those samples' (x, y) (n, BEST_SAMPLES, 2)."""
        n, tips = len(c), np.array(self.tips, dtype=float).reshape(-1, 3)
        guess = np.empty(0) if guess is None else np.array(guess, dtype=float).reshape(2)
        k = 1 + len(guess) // 2 + BEST_SAMPLES + len(hints)

        def make(fn):
            out = {"feet": np.empty((n, 2)), "normals": np.empty((n, 3)), "distances": np.empty(n),
                   "below": np.empty(n), "sampled": np.empty(n), "spacings": np.empty(n),
                   "nearest": np.empty((n, 2 * BEST_SAMPLES))}
            call = machine_code.Arguments(
                "nearest_feet", fn=fn, centers=np.empty((n, 3)), guess=guess.copy(),
                hints=np.empty((len(hints), 3)), tips=np.empty((len(tips), 3)), spacing=0.0,
                reach_default=self.reach_default, **out, start_centers=np.empty((n * k, 3)),
                start_feet=np.empty((n * k, 2)), start_normals=np.empty((n * k, 3)), start_distances=np.empty(n * k),
                iterations=FOOT_ITERATIONS, d=np.empty(6))
            return call, out

        packed = self.landscape.packed(self.values, ("nearest_feet", n, len(guess), len(hints), len(tips),
                                                     self.reach_default), make)
        call, out = packed
        kept = call.kept   # (the arguments are written in place: packing costs more than the copies)
        kept["centers"][:], kept["guess"][:], kept["hints"][:], kept["tips"][:] = c, guess, hints, tips
        call.set("spacing", spacing)
        call()
        return (out["feet"].copy(), out["normals"].copy(), out["distances"].copy(), out["below"].copy(),
                out["sampled"].copy(), out["spacings"].copy(), out["nearest"].reshape(n, BEST_SAMPLES, 2).copy())

    def land(self, start: FreeState, *, gravity: float, radius: float, t_end: float):
        """The compiled landing search (``kernel.landing.land``) of a flight in vacuum from ``start``:
        (t, the foot) where it lands, None where it is still flying at t_end, or REFER where that
        search leaves the flight to ``Flight.landing``'s own (see ``kernel.landing``)."""
        hints, tips = np.array(self.hints, dtype=float).reshape(-1, 3), np.array(self.tips, dtype=float).reshape(-1, 3)
        k = 2 + BEST_SAMPLES + len(hints)   # (a look's starts: below, the guess, the samples, the hints)
        call = self.landscape.packed(self.values, ("land", len(hints), len(tips), self.reach_default), lambda fn: (
            machine_code.Arguments(
                "land", fn=fn, start=np.empty(7), gravity=0.0, radius=0.0, t_end=0.0,
                hints=np.empty((len(hints), 3)), tips=np.empty((len(tips), 3)), reach_default=self.reach_default,
                iterations=FOOT_ITERATIONS, out=np.empty(OUT_LANDING), times=np.empty(LANDING_BATCH),
                guess=np.empty(2), centers=np.empty((1, 3)), feet=np.empty((1, 2)), normals=np.empty((1, 3)),
                distances=np.empty(1), below=np.empty(1), sampled=np.empty(1), spacings=np.empty(1),
                nearest=np.empty((1, 2 * BEST_SAMPLES)), start_centers=np.empty((k, 3)), start_feet=np.empty((k, 2)),
                start_normals=np.empty((k, 3)), start_distances=np.empty(k), d=np.empty(6),
                tape=self.landscape.tape, bounds=np.empty((len(self.landscape.tape), 2)))))
        kept = call.kept
        kept["start"][0], kept["start"][1:4], kept["start"][4:7] = start.t, start.center, start.velocity
        kept["hints"][:], kept["tips"][:] = hints, tips
        call.set("gravity", gravity)
        call.set("radius", radius)
        call.set("t_end", t_end)
        call()
        out = kept["out"]
        if out[0] == LANDING_FLYING:
            return None
        if out[0] != LANDING_LANDED:
            return REFER
        return float(out[1]), Foot(float(out[2]), float(out[3]), out[4:7].copy(), float(out[7]))

    def bounces(self, start: FreeState, *, gravity: float, radius: float, mass: float, restitution: float,
                friction: float, rest: float, t_end: float, every: int, step: float, enough: int,
                dissipated: float, feet_after: float = -math.inf) -> "Bounces":
        """The compiled flights of a ball in vacuum from ``start`` (``kernel.bounces.bounces``):
        landing, rows at the recording times (every ``every``-th multiple of ``step``), impact
        (``impact``, a rebound at most ``rest`` settling) and the next flight, until the ball
        settles, flies to t_end, makes ``enough`` landings (-1: no limit), makes BOUNCES_CHAIN of
        them, or leaves a flight to flight.py (see ``Bounces``). Rows whose foot the kernel
        refers are searched here (``refer_rows``); rows at times before ``feet_after`` are written
        without their foot (``kernel.flight_rows``)."""
        hints, tips = np.array(self.hints, dtype=float).reshape(-1, 3), np.array(self.tips, dtype=float).reshape(-1, 3)
        call = self.landscape.packed(self.values, ("bounces", len(hints), len(tips), self.reach_default), lambda fn: (
            machine_code.Arguments(
                "bounces", fn=fn, state=np.empty(10), R=np.empty((3, 3)), gravity=0.0,
                radius=0.0, mass=0.0, restitution=0.0, friction=0.0, rest=0.0, t_end=0.0, step=0.0, every=1,
                enough=-1, dissipated=0.0, reach_default=self.reach_default, iterations=FOOT_ITERATIONS,
                out=np.empty(kernel.OUT_BOUNCES), rows=np.empty((KEPT_ROWS, ROW_SIZE)), tape=self.landscape.tape,
                feet_after=-math.inf, **bounce_scratch(len(self.landscape.tape), len(hints), len(tips)))))
        kept = call.kept
        state = kept["state"]
        state[0], state[1:4], state[4:7], state[7:10] = start.t, start.center, start.velocity, start.omega
        kept["R"][:], kept["hints"][:], kept["tips"][:] = start.R, hints, tips
        for key, value in (("gravity", gravity), ("radius", radius), ("mass", mass), ("restitution", restitution),
                           ("friction", friction), ("rest", rest), ("t_end", t_end), ("step", step), ("every", every),
                           ("enough", enough), ("dissipated", dissipated), ("feet_after", feet_after)):
            call.set(key, value)
        call()
        out = kept["out"]
        count, landings = int(out[1]), int(out[2])
        rows = kept["rows"][:count].copy()
        self.refer_rows(rows, kept["refer"][:count], radius)
        after = FreeState(float(state[0]), state[1:4].copy(), state[4:7].copy(), state[7:10].copy(), kept["R"].copy())
        answer = kept["out"][8:8 + OUT_LANDING]
        landing = (None if answer[0] == LANDING_FLYING else
                   (float(answer[1]), Foot(float(answer[2]), float(answer[3]), answer[4:7].copy(), float(answer[7]))))
        return Bounces(float(out[0]), rows, kept["landed"][:landings].copy(), float(out[3]), after,
                       (float(out[4]), float(out[5])), bool(out[6]), landing)

    def refer_rows(self, rows: np.ndarray, refer: np.ndarray, radius: float) -> None:
        """A flight's rows (``kernel.flight_rows``'), their foot searched in full where ``refer``
        says Newton's method did not give one that can be the nearest: the contact columns and
        the slip speed of the ball's point nearest the surface."""
        for i in np.flatnonzero(refer):
            row = rows[i]
            foot = self.foot(row[ROW_SLICES["center"]].copy(), spacing=GRID_SPACING * radius)
            row[ROW_SLICES["contact"]] = foot.x, foot.y
            row[SLIP_SPEED] = tangential_slip(row[ROW_SLICES["velocity"]], row[ROW_SLICES["omega"]], foot.normal,
                                              radius)[0]

    def flight_rows(self, centers: np.ndarray, velocities: np.ndarray, times: np.ndarray, start: FreeState, guess,
                    *, mass: float, radius: float, gravity: float, dissipated: float) -> tuple[np.ndarray, np.ndarray]:
        """A flight's rows at ``times`` (``kernel.flight_rows``), where the centre is at ``centers``
        (n, 3) and moves at ``velocities`` (n, 3), and which of them need the foot searched in
        full (``Flight.rows``). Up to KEPT_ROWS rows go through arrays packed once per surface (a
        run records a flight's rows a few at a time: every bounce's first row); more, through
        arrays of their own, so that no run keeps a long flight's arrays."""
        n, tips = len(times), np.array(self.tips, dtype=float).reshape(-1, 3)
        call = self._rows_call
        if call is None or len(call.kept["times"]) < n or len(call.kept["tips"]) != len(tips):
            size = max(n, min(2 * len(call.kept["times"]), KEPT_ROWS) if call is not None else 64)
            call = machine_code.Arguments(
                "flight_rows", fn=self._record.ctypes.data, count=0, centers=np.empty((size, 3)),
                velocities=np.empty((size, 3)), times=np.empty(size), start_time=0.0, omega=np.empty(3),
                R=np.empty((3, 3)), guess=np.empty(2), tips=np.empty((len(tips), 3)), mass=0.0, radius=0.0,
                gravity=0.0, dissipated=0.0, rows=np.empty((size, ROW_SIZE)), refer=np.empty(size, dtype=np.int64),
                feet=np.empty((size, 2)), normals=np.empty((size, 3)), distances=np.empty(size), turn=np.empty((3, 3)),
                iterations=FOOT_ITERATIONS, d=np.empty(6), feet_after=-math.inf)
            if size <= KEPT_ROWS:
                self._rows_call = call
        kept = call.kept
        kept["centers"][:n], kept["velocities"][:n], kept["times"][:n] = centers, velocities, times
        kept["omega"][:], kept["R"][:], kept["guess"][:], kept["tips"][:] = start.omega, start.R, guess, tips
        for key, value in (("count", n), ("start_time", start.t), ("mass", mass), ("radius", radius),
                           ("gravity", gravity), ("dissipated", dissipated)):
            call.set(key, value)
        call()
        if call is not self._rows_call and len(kept["times"]) == n:   # (its own arrays: no copies)
            return kept["rows"], kept["refer"]
        return kept["rows"][:n].copy(), kept["refer"][:n].copy()

    def _from_starts(self, c, starts):
        """Newton's feet from starts (n, k, 2) for the centres c (n, 3), the tips put in, and
        each centre's nearest (smallest |D|) first: (alpha (n, 2), normal (n, 3), distance (n,))
        of the nearest, NaN where none converged."""
        n, k = starts.shape[:2]
        alpha, normal, distance = self.feet(np.repeat(c, k, axis=0), np.ascontiguousarray(starts).reshape(-1, 2))
        alpha, normal, distance = self._nearer_tips(np.repeat(c, k, axis=0), alpha, normal, distance)
        alpha, normal, distance = alpha.reshape(n, k, 2), normal.reshape(n, k, 3), distance.reshape(n, k)
        size = np.where(np.isnan(distance), np.inf, np.abs(distance))
        i = np.argmin(size, axis=1)
        rows = np.arange(n)
        return alpha[rows, i], normal[rows, i], distance[rows, i]

    def _polish(self, c, starts):
        """Newton's method (as ``feet``) in numpy from starts (n, k, 2) for centres (n, 3), damped:
        a step that does not bring the surface point nearer is halved (up to 40 times), and where
        the Hessian G − d_z H is not positive definite the step is along the gradient (scaled by
        1/(1 + |∇f|²)), so that each iterate is nearer than the last and the iteration cannot
        cycle (undamped, it does about a fold of a steep landscape). A foot is taken as found
        where the last step is below POLISH_STEP (1 + |α|) and c − φ is along N (on a steep
        landscape the gradient's round-off keeps the step above the compiled test's
        4·10⁻¹⁶ (1 + |α|): at round-off it jumps back and forth). The nearest per centre, as
        ``_from_starts``."""
        n, k = starts.shape[:2]
        centers = np.repeat(c, k, axis=0)
        alpha = np.ascontiguousarray(starts, dtype=float).reshape(-1, 2).copy()
        step = np.full(len(alpha), np.inf)

        def far(points):
            f = self.evaluate(points[:, 0], points[:, 1])
            return f, ((centers[:, 0] - points[:, 0]) ** 2 + (centers[:, 1] - points[:, 1]) ** 2
                       + (centers[:, 2] - f[0]) ** 2)

        with np.errstate(all="ignore"):
            d, now = far(alpha)
            for _ in range(FOOT_ITERATIONS):
                f, fx, fy, fxx, fxy, fyy = d
                dx, dy, dz = centers[:, 0] - alpha[:, 0], centers[:, 1] - alpha[:, 1], centers[:, 2] - f
                b1, b2 = dx + dz * fx, dy + dz * fy
                h11, h12, h22 = 1.0 + fx * fx - dz * fxx, fx * fy - dz * fxy, 1.0 + fy * fy - dz * fyy
                det = h11 * h22 - h12 * h12
                definite = (h11 > 0.0) & (det > 0.0)
                scale = 1.0 + fx * fx + fy * fy
                s1 = np.where(definite, (h22 * b1 - h12 * b2) / det, b1 / scale)
                s2 = np.where(definite, (h11 * b2 - h12 * b1) / det, b2 / scale)
                moving = np.isfinite(s1) & np.isfinite(s2)
                s1, s2 = np.where(moving, s1, 0.0), np.where(moving, s2, 0.0)
                trial = alpha + np.column_stack([s1, s2])
                d_t, after = far(trial)
                for _ in range(40):   # halve the steps that do not come nearer (round-off aside)
                    worse = ~(after <= now * (1.0 + 1e-15) + 1e-300) & moving
                    if not worse.any():
                        break
                    s1, s2 = np.where(worse, 0.5 * s1, s1), np.where(worse, 0.5 * s2, s2)
                    trial = alpha + np.column_stack([s1, s2])
                    d_w, after_w = far(trial)
                    d_t[:, worse], after[worse] = d_w[:, worse], after_w[worse]
                alpha, d, now = trial, d_t, after
                step = np.maximum(np.abs(s1), np.abs(s2)) / (1.0 + np.abs(alpha).max(axis=1))
                if not (step > 4e-16).any():
                    break
            f, fx, fy = self.evaluate(alpha[:, 0], alpha[:, 1])[:3]
            w = np.sqrt(1.0 + fx * fx + fy * fy)
            normal = np.column_stack([-fx / w, -fy / w, 1.0 / w])
            g = centers - np.column_stack([alpha, f])
            distance = np.einsum("ij,ij->i", g, normal)
            off = np.linalg.norm(g - distance[:, None] * normal, axis=1)
            good = (step <= POLISH_STEP) & (off <= 1e-6 * (1.0 + np.abs(distance))) & np.isfinite(distance)
        alpha[~good], distance[~good] = np.nan, np.nan
        alpha, normal, distance = self._nearer_tips(centers, alpha, normal, distance)
        alpha, normal, distance = alpha.reshape(n, k, 2), normal.reshape(n, k, 3), distance.reshape(n, k)
        i = np.argmin(np.where(np.isnan(distance), np.inf, np.abs(distance)), axis=1)
        rows = np.arange(n)
        return alpha[rows, i], normal[rows, i], distance[rows, i]

    @staticmethod
    def _plausible(c, below, distance, sampled):
        """Whether each foot's signed distance can be the nearest surface point's: found, no
        farther than a sampled surface point, and on the centre's side of the surface (a comparison
        with NaN is False, without a warning)."""
        near = np.abs(distance) <= sampled * (1.0 + SAMPLE_SLACK)
        side = ~(((distance > 0.0) & (c[:, 2] < below)) | ((distance < 0.0) & (c[:, 2] > below)))
        return np.isfinite(distance) & near & side

    def _zoom(self, c, points, spacing):
        """A search of the surface's samples for the points nearest each centre, from points
        (n, k, 2) with spacings (n, k): each round samples a ZOOM_SAMPLES × ZOOM_SAMPLES grid over
        ± its spacing about each point and keeps the ZOOM_BEAM nearest samples of them all, a
        sample that is its grid's own point with the spacing shrunk 4 times, one that moved with
        its grid's spacing (so a point follows a flank as far as it leads, and several go on where
        a ridge parts two flanks), until every spacing is at round-off or after ZOOM_ROUNDS
        rounds. The last points (n, ZOOM_BEAM, 2), nearest first, each centre's nearest sampled
        distance (n,) and the spacing its nearest point was last sampled at (n,)."""
        n = points.shape[0]
        unit = np.linspace(-1.0, 1.0, ZOOM_SAMPLES)
        ux, uy = (u.ravel() for u in np.meshgrid(unit, unit, indexing="ij"))
        middle = (ZOOM_SAMPLES * ZOOM_SAMPLES) // 2
        ends = np.full((n, ZOOM_BEAM, 2), np.nan)
        best, finest = np.full(n, np.inf), np.full(n, np.inf)
        for j in range(n):
            p, h = points[j][np.isfinite(points[j]).all(axis=1)], spacing[j][np.isfinite(points[j]).all(axis=1)]
            for _ in range(ZOOM_ROUNDS):
                if not len(p):
                    break
                gx = p[:, 0, None] + h[:, None] * ux
                gy = p[:, 1, None] + h[:, None] * uy
                gx[:, middle], gy[:, middle] = p[:, 0], p[:, 1]
                heights = self.evaluate(gx.ravel(), gy.ravel())[0].reshape(gx.shape)
                far = (gx - c[j, 0]) ** 2 + (gy - c[j, 1]) ** 2 + (heights - c[j, 2]) ** 2
                far = np.where(np.isnan(far), np.inf, far)
                child = np.where(np.arange(gx.shape[1]) == middle, 2.0 / (ZOOM_SAMPLES - 1), 1.0)[None, :] * h[:, None]
                order = np.lexsort((child.ravel(), far.ravel()))   # (the nearest, the finer first among equals)
                xy = np.column_stack([gx.ravel()[order], gy.ravel()[order]])
                size = child.ravel()[order]
                with np.errstate(all="ignore"):   # (points within a spacing of a nearer one are the same)
                    cells = np.column_stack([np.round(xy / (4.0 * size[:, None])), np.log2(size)])
                _, first = np.unique(np.where(np.isfinite(cells), cells, 0.0), axis=0, return_index=True)
                keep = np.sort(first)[:ZOOM_BEAM]
                keep = keep[np.isfinite(far.ravel()[order][keep])]
                best[j] = min(best[j], float(np.sqrt(far.min())))
                p, h = xy[keep], size[keep]
                if not (h > 1e-13 * (1.0 + np.abs(p).max(axis=1))).any():
                    break
            ends[j, : len(p)] = p
            if len(p):
                finest[j] = h[0]
        return ends, best, finest

    def _nearer_tips(self, centers, alpha, normal, distance):
        """The feet (alpha, normal, distance per centre) with a tip put in where it is nearer
        (or no foot was found): its distance |c − T|, its normal the direction from it to c."""
        for tip in self.tips:
            arm = centers - tip
            far = np.linalg.norm(arm, axis=1)
            nearer = ~(np.abs(distance) <= far) & (far > 0)
            if nearer.any():
                alpha, normal, distance = alpha.copy(), normal.copy(), distance.copy()
                alpha[nearer] = tip[:2]
                normal[nearer] = arm[nearer] / far[nearer, None]
                distance[nearer] = far[nearer]
        return alpha, normal, distance


class Flight:
    """A ball in free flight from ``start`` until it lands: its exact state at any time,
    recorded rows, and the landing."""

    compiled = True   # its landing searched by the kernel first (its centre on a parabola: ``kernel.landing``)

    def __init__(self, surface: Surface, start: FreeState, *, radius: float, mass: float, gravity: float):
        self.surface, self.start = surface, start
        self.radius, self.mass, self.gravity = radius, mass, gravity
        self.g = np.array([0.0, 0.0, -gravity])
        self.spacing = GRID_SPACING * radius   # (its looks' grids: ``Surface.foot``)

    def state(self, t: float) -> FreeState:
        s = self.start
        center, velocity = self.center_at(t)
        return FreeState(t, center, velocity, s.omega.copy(), rotation(s.omega * (t - s.t)) @ s.R)

    def center_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The centre and its velocity (3,) at t: ``centers``' numbers, without numpy's setup,
        which costs a flight's one time far more than its arithmetic."""
        s = self.start
        tau = t - s.t
        c, v, g = s.center, s.velocity, self.g
        return (np.array([c[k] + v[k] * tau + 0.5 * g[k] * tau * tau for k in range(3)]),
                np.array([v[k] + g[k] * tau for k in range(3)]))

    def centers(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Centre positions and velocities (n, 3) at ``times`` (computed as (3, n): numpy's loops
        over a last axis of 3 cost about a hundred times as much)."""
        tau = np.asarray(times, dtype=float) - self.start.t
        center, velocity, g = self.start.center[:, None], self.start.velocity[:, None], self.g[:, None]
        return (center + velocity * tau + 0.5 * g * tau * tau).T, (velocity + g * tau).T

    def air_dissipated(self, times: np.ndarray) -> np.ndarray:
        """The energy the air took from the flight's start to each of ``times`` (J): none in vacuum
        (``drag_flight.DragFlight`` has air)."""
        return np.zeros(len(np.asarray(times)))

    def pull(self, speed: float) -> float:
        """A bound on the centre's acceleration |c̈| from a time its speed is ``speed`` on: g."""
        return self.gravity

    def sag(self, t: float, s: float) -> float:
        """The farthest the centre's path between t and s departs from its chord: g (s − t)²/8
        (the most the parabola lies off its chord, the second derivative g bounding it)."""
        delta = s - t
        return self.gravity * delta * delta / 8.0

    def gap(self, t: float, guess=None) -> tuple[float, Foot]:
        """The centre's distance to the surface minus r at time t, and the foot."""
        center = self.centers(np.array([t]))[0][0]
        foot = self.surface.foot(center, guess, self.spacing)
        return foot.distance - self.radius, foot

    def gaps(self, times: np.ndarray, guess=None, motion=None) -> tuple[np.ndarray, list[Foot]]:
        """``gap`` at each of the times, all at once (``motion``: their ``centers``, where the caller has them)."""
        motion = self.centers(np.asarray(times, dtype=float)) if motion is None else motion
        feet = self.surface.feet_of(motion[0], guess, self.spacing)
        return np.array([foot.distance for foot in feet]) - self.radius, feet

    def path_time(self, t: float, length: float, velocity=None) -> float:
        """The time Δ after t over which the centre's path is ``length`` long, ∫|ċ| = length (its
        speed along the parabola is exact: |ċ|² = p² + w², w = ċ·ĝ + g τ along gravity, p the
        rest, so the path's length is [w √(p² + w²) + p² asinh(w/p)] / 2g between the ends'
        w); the computed length at the Δ returned is at most ``length``. ``velocity``: the
        centre's at t, where the caller has it."""
        if not length > 0.0:
            return 0.0
        velocity = self.centers(np.array([t]))[1][0] if velocity is None else velocity
        speed, g = float(np.linalg.norm(velocity)), self.gravity
        if g == 0.0:
            return length / speed if speed > 0 else math.inf
        w0 = -float(velocity[2])            # along gravity (down)
        p = math.hypot(float(velocity[0]), float(velocity[1]))

        def primitive(w):
            return 0.5 * (w * math.hypot(p, w) + (p * p * math.asinh(w / p) if p > 0 else 0.0))

        origin = primitive(w0)

        def path(delta):
            return (primitive(w0 + g * delta) - origin) / g

        # |ċ| ≤ speed + g τ, so the path is no longer than speed Δ + ½ g Δ²: a Δ short of the answer
        delta = 2.0 * length / (speed + math.sqrt(speed * speed + 2.0 * g * length))
        along = path(delta)
        best = delta if along <= length else 0.0
        for _ in range(PATH_ITERATIONS):   # Newton's method on path(Δ) = length, ∂path/∂Δ = |ċ|
            rate = math.hypot(p, w0 + g * delta)
            if not rate > 0.0:
                break
            after = delta + (length - along) / rate
            if after == delta:   # (a fixed point: the iterations left change nothing)
                break
            delta, along = after, path(after)
            if along <= length:
                best = max(best, delta)
        return best

    def clear(self, t: float, s: float, h_t: float, h_s: float, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the ball touches nothing between t and s > t, from the gaps h_t, h_s (> 0)
        at the ends, where the centre is at a = c(t) and b = c(s): the open balls of radius r + h
        about them hold no surface point (h is the distance to the nearest), and so no ball of
        radius r + e about a point of their chord is outside both while L²/4 + (r + e)² < (r + h)²
        (L the chord, h the smaller gap; a point of that ball u along the chord and ρ across it
        from where x of L is behind: min(|·−c(t)|², |·−c(s)|²) ≤ x(L − x) + (r + e)²). The centre's
        path is within e = ``sag`` of the chord at every time, so the ball of radius r is inside
        that ball. CLEAR_MARGIN × r of the gap is kept for round-off."""
        h = min(h_t, h_s) - CLEAR_MARGIN * self.radius
        e = self.sag(t, s)
        if not h > e:
            return False
        chord = float(np.linalg.norm(b - a))
        return 0.25 * chord * chord < (h - e) * (2.0 * self.radius + h + e)   # (r + h)² − (r + e)²

    def landing(self, t_end: float) -> tuple[float, Foot] | None:
        """The first time in (t₀, t_end] the ball touches the surface again, and the contact
        there; None if it is still flying at t_end (``_search``), checked:

        - the surface under the centre's path up to there is sampled every TRACK × r of the path
          (``track``): where a surface point below the centre is nearer than r before the landing
          found, the search was blind to it (a feature narrower than its grid) and runs again with
          that point among every foot search's samples and starts (``Surface.hints``); where it
          is still blind, ``OffLandscape`` "narrow_feature";
        - the centre at the landing is r from the contact's surface point (within 2 GRAZE × r)
          and that point is the nearest a search of its own finds; else ``OffLandscape``
          "false_landing".
        ``OffLandscape`` also where no surface is found below the ball ("off_domain") or its
        nearest point is not found ("no_foot").

        In vacuum (``compiled``) the kernel's search (``Surface.land``), which takes the same
        looks, answers first; it leaves to this one every flight where its first foot search does
        not suffice, where the track finds the surface nearer, or where the landing's check fails."""
        if self.compiled:
            found = self.surface.land(self.start, gravity=self.gravity, radius=self.radius, t_end=t_end)
            if found is not REFER:
                return found
        r = self.radius
        for _ in range(MAX_HINTS + 1):
            found = self._search(t_end)
            end = t_end if found is None else found[0]
            touch = self.track(self.start.t, end)
            if touch is None:
                break
            tau, x, y, height = touch
            spacing = TRACK * r
            if (len(self.surface.hints) >= MAX_HINTS
                    or any(math.hypot(x - hx, y - hy) <= 4.0 * spacing for hx, hy, _ in self.surface.hints)):
                raise OffLandscape(tau, self.centers(np.array([tau]))[0][0], "narrow_feature", (x, y), height)
            self.surface.hints.append(np.array([x, y, spacing]))
        if found is not None:
            self._verify(*found)
        return found

    def track(self, t: float, s: float):
        """The first of the surface samples under the centre's path between t and s (every TRACK
        × r of its length, at most TRACK_MOST × ⌈(s − t)/…⌉ in all) whose height is within r of
        the centre below it, as (time, x, y, c_z − f), or None. Such a surface point is inside the
        ball: the ball touched the surface by then (the vertical distance bounds the distance). The
        speed is largest at an end of the interval: along a parabola it falls to the apex and then
        grows; with air too (the path bends ever further down, and once the speed grows
        d|ċ|/dt = g sin γ − (k/m)|ċ|² stays ≥ 0: where it is 0 its derivative is g cos γ γ̇ ≥ 0)."""
        if not s > t:
            return None
        r = self.radius
        speeds = np.linalg.norm(self.centers(np.array([t, s]))[1], axis=1)
        length = float(speeds.max()) * (s - t)   # (the speed is largest at an end: see ``track``)
        count = int(min(math.ceil(length / (TRACK * r)), 100 * TRACK_MOST)) + 1
        for first in range(1, count + 1, TRACK_MOST):
            k = np.arange(first, min(first + TRACK_MOST, count + 1))
            times = t + (s - t) * (k / count)
            centers = self.centers(times)[0]
            height = centers[:, 2] - self.surface.evaluate(centers[:, 0], centers[:, 1])[0]
            with np.errstate(invalid="ignore"):
                inside = np.flatnonzero(height < r * (1.0 - TRACK_SLACK))
            if len(inside):
                i = int(inside[0])
                return float(times[i]), float(centers[i, 0]), float(centers[i, 1]), float(height[i])
        return None

    def _verify(self, t: float, foot: Foot) -> None:
        """``OffLandscape`` "false_landing" unless the centre at t is r from the foot's surface
        point (within 2 GRAZE × r) and a search of its own (no guess) finds no nearer one."""
        r = self.radius
        center = self.centers(np.array([t]))[0][0]
        point = np.array([foot.x, foot.y, float(self.surface.evaluate(foot.x, foot.y)[0])])
        far = float(np.linalg.norm(center - point))
        own = self.surface.foot(center, spacing=self.spacing)
        if not (abs(far - r) <= 2.0 * GRAZE * r and own.distance >= far - 2.0 * GRAZE * r):
            raise OffLandscape(t, center, "false_landing", (foot.x, foot.y), far)

    def _off(self, t: float, foot: Foot) -> OffLandscape:
        """Why the search cannot go on from t where a look found no foot."""
        center = self.centers(np.array([t]))[0][0]
        return OffLandscape(t, center, "no_foot" if foot.lost else "off_domain")

    def _search(self, t_end: float) -> tuple[float, Foot] | None:
        """The first time in (t₀, t_end] the ball touches the surface again, and the contact
        there; None if it is still flying at t_end. ``OffLandscape`` where no surface is found
        below it.

        The gap h = D − r (D the centre's distance to the surface, ``Surface.foot``) is looked
        at from t₀ on. Each step from a look is certified to hold no root of h before the next
        look is taken as the new start: by (1) D being 1-Lipschitz in the centre, so no root lies
        within the time the centre's path is h long (``path_time``, the exact length along the
        parabola), or (2) the gaps at both ends (``clear``). Steps are proposed long (the local
        model of the gap's fall, while it grows half the time flown, the step (2) would allow
        if the gap fell at its rate, never moving the centre by more than r so that the foot's
        grid sees the surface near), and one that is not certified is tried again SHRINK times
        as long, down to (1). The search ends at a certified look whose gap is at most
        GAP_TOLERANCE × r (the landing; Brent's method then puts it on the root beside), or
        at most GRAZE × r while the gap no longer falls (a graze: contact there). Just after a
        lift-off the gap grows from 0 like τ³, and below GRAZE × r the ball is in contact: the
        first looks double from FIRST_STEP until it is clear, checking the gap's sign only."""
        r = self.radius
        tol, floor = GAP_TOLERANCE * r, GRAZE * r
        t = self.start.t
        h, foot = self.gap(t)
        if math.isnan(h):
            raise self._off(t, foot)
        if h <= floor:   # just lifted off: not yet clear of the surface
            cleared = self._clear_off(t, h, foot, t_end)
            if len(cleared) == 2:
                return cleared
            t, h, foot = cleared
            if t >= t_end:
                return None
        cap = math.inf        # a step not certified: the next one at most this long
        last = before = math.inf   # the last two certified steps (the next is at most GROW_BY times the last)
        grazing = 0           # certified looks within the floor in a row
        sure = proposal = None   # (1): no root before t + sure, the look at t's path time; its step proposed
        here = velocity = None   # the centre and its velocity at t (from the batch that looked there)
        for _ in range(MAX_LOOKS):
            if t >= t_end:
                return None
            guess = np.array([foot.x, foot.y])
            if here is None:
                here, velocity = (v[0] for v in self.centers(np.array([t])))
            speed = float(np.linalg.norm(velocity))
            rate = float(np.dot(velocity, foot.normal))
            if h <= tol or (h <= floor and (rate >= 0.0 or grazing >= GRAZE_LOOKS)):
                return self._touch(t, h, foot, rate, t_end)
            if sure is None:
                sure = self.path_time(t, h - CLEAR_MARGIN * r, velocity)
            if t + sure >= t_end:
                return None
            if proposal is None:   # (the same for each try from the same look)
                proposal = self._proposal(h, foot, speed, rate)
            step = min(proposal, GROW_BY * last)
            step = min(step, r / speed if speed > 0 else step, cap)
            step = max(step, sure)
            # while the gap grows, the steps ahead are looked at together, as the last ones grew
            growth = min(max(last / before, 1.0), GROW_BY) if rate >= 0.0 and last < math.inf else 1.0
            count = LANDING_BATCH if growth > 1.0 and cap == math.inf else 1
            times = t + np.cumsum(step * growth ** np.arange(count))
            if not times[-1] < t_end:   # (increasing: those before t_end, then t_end)
                times = np.append(times[times < t_end], t_end)
            motion = self.centers(times)
            gaps, feet = self.gaps(times, guess, motion)
            for s, h_s, foot_s, there, moving in zip(times, gaps, feet, *motion):
                if math.isnan(h_s):
                    raise self._off(t, foot_s)
                # (the chord test first: a look after the first of a batch needs its path time only where it fails)
                certified = h_s > -tol and h_s > 0.0 and self.clear(t, s, h, h_s, here, there)
                if not certified:
                    if sure is None:
                        sure = self.path_time(t, h - CLEAR_MARGIN * r, velocity)
                    if h_s < -tol and s <= t + sure:   # (only where the foot at t was not the nearest point)
                        return self._locate(t, float(s), guess)
                    certified = h_s > -tol and s <= t + sure
                if not certified:
                    cap = self._retry(t, s, h, h_s, speed)   # not certified: try again shorter
                    break
                grazing = grazing + 1 if h_s <= floor else 0
                t, h, foot, cap, last, before = float(s), float(h_s), foot_s, math.inf, s - t, last
                here, velocity, sure, proposal = there, moving, None, None
                if h <= floor or t >= t_end:
                    break
        raise RuntimeError("the landing search took too many steps")

    def _retry(self, t: float, s: float, h: float, h_s: float, speed: float) -> float:
        """The step to try after the step from t to s was not certified (gaps h, h_s): where the
        gap falling as the secant says leaves what ``clear`` needs, else the chord ``clear``
        allows from the smaller gap; never more than SHRINK_MOST of the step."""
        r, step = self.radius, s - t
        if h_s <= 0.0:   # the surface is reached between: aim short of the secant's root
            return min(self._leaves_clear(h, (h_s - h) / step, 0.0, speed), SHRINK_MOST * step)
        a, b = self.centers(np.array([t, s]))[0]
        chord = float(np.linalg.norm(b - a))
        m = min(h, h_s) - CLEAR_MARGIN * r
        allowed = 2.0 * math.sqrt(max(m, 0.0) * (2.0 * r + m))
        return max(min(0.9 * allowed / chord, SHRINK_MOST), SHRINK) * step

    def _leaves_clear(self, h: float, rate: float, bend: float, speed: float) -> float:
        """The step after which a gap h falling as h + rate Δ − ½ bend Δ² leaves what ``clear``
        needs for a chord speed Δ ((speed Δ)²/4 ≤ 2 r (gap − e), e = A Δ²/8, A = ``pull``), with the quadratic
        terms doubled for safety: close to the surface the gap left is of order h² (the approach
        converges quadratically)."""
        r, g = self.radius, self.pull(speed)
        a = 2.0 * (0.25 * speed * speed + r * bend + 0.25 * r * g)
        b, c = 2.0 * r * rate, 2.0 * r * h
        if not a > 0:
            return h / -rate if rate < 0 else math.inf
        return 2.0 * c / (math.sqrt(b * b + 4.0 * a * c) - b)   # (the positive root, without cancellation)

    def _proposal(self, h: float, foot: Foot, speed: float, rate: float) -> float:
        """A step to try from a look with gap h > 0 falling at ``rate`` (``landing``): the one
        ``clear`` would certify if the gap fell no faster than the local model h + D′Δ − ½ A Δ²,
        A twice the bound of D″ ≥ −(|c̈| + |ċ|² κ/(1 − Dκ)) (|c̈| ≤ ``pull``), κ the largest principal curvature
        towards the ball at the foot; where the gap is not falling, at least the one ``clear``
        certifies if the gap at its end is no smaller than h: 0.9 of the chord 2√(m (2r + m)),
        m = h − CLEAR_MARGIN × r, at the speed here (as ``_retry``'s; the model alone proposes about
        60 % of that chord while the gap creeps up after a lift-off, docs/design.md §1, "Flight and landing")."""
        r, g = self.radius, self.pull(speed)
        kappa = max(float(fit_ratio(self.surface.evaluate(foot.x, foot.y), 1.0)), 0.0)
        room = 1.0 - (h + r) * kappa
        bend = 2.0 * (g + speed * speed * kappa / room) if room > 0 else math.inf
        step = self._leaves_clear(h, rate, bend, speed) if bend < math.inf else 0.0
        if rate >= 0.0 and speed > 0.0:
            m = h - CLEAR_MARGIN * r
            step = max(step, 0.9 * 2.0 * math.sqrt(max(m, 0.0) * (2.0 * r + m)) / speed)
        return step

    def _clear_off(self, t: float, h: float, foot: Foot, t_end: float):
        """Just after a lift-off: looks FIRST_STEP after it, doubling, until the gap exceeds
        GRAZE × r (returns that look's t, h, foot), or the landing (t, foot) where one is below
        the surface, or where the ball is not clear by CLEAR_WITHIN (it never left). The next
        LANDING_BATCH looks are taken at once, each judged as if taken alone."""
        floor, tol = GRAZE * self.radius, GAP_TOLERANCE * self.radius
        step = FIRST_STEP
        while True:
            if t >= t_end:
                return t, h, foot
            times, now, size = [], t, step
            while len(times) < LANDING_BATCH and now < t_end:
                now = min(now + size, t_end)
                times.append(now)
                size *= 2.0
            gaps, feet = self.gaps(np.array(times), np.array([foot.x, foot.y]))
            for s, h_s, foot_s in zip(times, gaps, feet):
                if math.isnan(h_s):
                    raise self._off(t, foot_s)
                if h_s < -tol:
                    return self._locate(t, s, np.array([foot.x, foot.y]))
                if h_s > floor:
                    return s, float(h_s), foot_s
                if s - self.start.t > CLEAR_WITHIN:
                    return s, foot_s   # it never left the surface
                t, h, foot, step = s, float(h_s), foot_s, 2.0 * step

    def _touch(self, t: float, h: float, foot: Foot, rate: float, t_end: float) -> tuple[float, Foot] | None:
        """The landing from a certified look at t whose gap h is within the floor: the root
        beside it (Brent's method between t and a look below the surface, where the gap falling
        at its rate would have reached 0, or twice, four or eight times as far), else contact at
        t (a graze, or the gap at round-off)."""
        tol = GAP_TOLERANCE * self.radius
        guess = np.array([foot.x, foot.y])
        if h > 0.0 and rate < 0.0:   # (the four looks at once)
            ends = [min(t + k * h / -rate, t_end) for k in (1.1, 2.0, 4.0, 8.0)]
            for b, h_b, foot_b in zip(ends, *self.gaps(np.array(ends), guess)):
                if h_b < -tol:
                    return self._locate(t, b, guess)
                if b >= t_end:
                    return None if h_b > tol else (b, foot_b)
        return t, foot

    def _locate(self, a: float, b: float, guess) -> tuple[float, Foot]:
        """The root of the gap in [a, b] (gap(a) ≥ 0 ≥ gap(b)), to round-off."""
        from scipy.optimize import brentq

        looks = {}   # (the root is often the last time looked at)

        def gap(t):
            if t not in looks:
                looks[t] = self.gap(t, guess)
            return looks[t][0]
        if gap(a) <= 0.0:
            t = a
        else:
            t = brentq(gap, a, b, xtol=4 * np.finfo(float).eps * max(abs(b), 1.0), rtol=4 * np.finfo(float).eps,
                       maxiter=200)
        gap(t)
        return t, looks[t][1]

    def rows(self, times: np.ndarray, dissipated: float, guess=None) -> np.ndarray:
        """Recorded rows (``kernel.interface.ROW_FIELDS``) at ``times``: the exact state; as
        contact point the centre's closest surface point; normal force 0; slip speed the
        tangential speed of the ball's point nearest the surface; ``dissipated`` as given
        (compiled: ``Surface.flight_rows``; the full foot search where Newton's method from
        ``guess``, or the start's point below, does not give a foot that can be the nearest)."""
        times = np.asarray(times, dtype=float)
        if len(times) == 0:
            return np.zeros((0, ROW_SIZE))
        centers, velocities = self.centers(times)
        s = self.start
        guess = np.asarray(guess if guess is not None else s.center[:2], dtype=float)
        rows, refer = self.surface.flight_rows(centers, velocities, times, s, guess, mass=self.mass,
                                               radius=self.radius, gravity=self.gravity, dissipated=dissipated)
        self.surface.refer_rows(rows, refer, self.radius)
        return rows


def energy(velocity, omega, height, mass, radius, gravity):
    """½ m |ċ|² + ½ (2/5) m r² |ω|² + m g c_z, elementwise over rows."""
    v2 = np.sum(np.asarray(velocity) ** 2, axis=-1)
    w2 = np.sum(np.asarray(omega) ** 2, axis=-1)
    return 0.5 * mass * v2 + 0.2 * mass * radius * radius * w2 + mass * gravity * np.asarray(height)


def tangential_slip(velocity, omega, normal, radius):
    """|u − (u·N) N| for the velocity u = ċ + ω × (−r N) of the ball's point towards the surface."""
    velocity, omega, normal = np.broadcast_arrays(*(np.atleast_2d(np.asarray(a, float)) for a in (velocity, omega,
                                                                                                  normal)))
    u = velocity - radius * cross(omega, normal)
    u_t = u - np.einsum("ij,ij->i", u, normal)[:, None] * normal
    return np.linalg.norm(u_t, axis=1)


@dataclass(frozen=True)
class Impact:
    """What a landing does: the velocities after it and what it cost."""

    velocity: np.ndarray   # the centre's, after
    omega: np.ndarray      # after
    normal_speed: float    # the speed the ball hit the surface with, along the normal (m/s, ≥ 0)
    rebound: float         # the normal speed it leaves with (e times the above; 0 where it settled)
    sticking: bool         # the contact point's tangential velocity is 0 after (friction sufficed)
    energy_lost: float     # J
    impulse: np.ndarray    # the impulse the surface gave at the contact point (N s)
    settled: bool          # the rebound was too slow to fly: the ball stays on the surface


def impact(velocity, omega, normal, *, mass: float, radius: float, restitution: float, friction: float,
           rest: float = -1.0) -> Impact:
    """The impulse a ball hitting the surface with the centre's ``velocity`` and ``omega`` gets at
    the contact point, the surface's unit ``normal`` there, with restitution e and friction μ (inf:
    a scene's null, always enough to stick); a rebound e|u_n| at most ``rest`` settles (its normal
    velocity taken away too, its energy counted as lost; the default never settles). Computed by
    the kernel (``kernel.bounces.impact``, where the law is written), as a flight's bounces are."""
    hit = np.zeros(kernel.HIT_SIZE)
    hit[kernel.HIT_VELOCITY: kernel.HIT_VELOCITY + 3] = velocity
    hit[kernel.HIT_OMEGA: kernel.HIT_OMEGA + 3] = omega
    hit[kernel.HIT_NORMAL: kernel.HIT_NORMAL + 3] = normal
    hit[[kernel.HIT_MASS, kernel.HIT_RADIUS, kernel.HIT_RESTITUTION, kernel.HIT_FRICTION, kernel.HIT_REST]] = (
        mass, radius, restitution, friction, rest)
    machine_code.call("impact", hit=hit)
    return Impact(hit[kernel.HIT_AFTER: kernel.HIT_AFTER + 3].copy(),
                  hit[kernel.HIT_SPIN_AFTER: kernel.HIT_SPIN_AFTER + 3].copy(), float(hit[kernel.HIT_APPROACH]),
                  float(hit[kernel.HIT_REBOUND]), bool(hit[kernel.HIT_STICKING]), float(hit[kernel.HIT_LOST]),
                  hit[kernel.HIT_IMPULSE: kernel.HIT_IMPULSE + 3].copy(), bool(hit[kernel.HIT_SETTLED]))
