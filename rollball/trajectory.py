"""A recorded run: one row per recorded step, the CSV columns of docs/design.md §5, and how it ended."""

from __future__ import annotations

import enum
import io
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .files import atomic_write
from .kernel.interface import REASONS, ROW_ENERGY, ROW_FORCE, ROW_SLICES, ROW_T, STATUSES
# the modes of the contact, one a row (``Trajectory.modes`` holds their positions in MODES)
from .modes import (FLYING, MODES, RESTING, ROLLING, SLIDING, TRANSITION_KINDS, Change,  # noqa: F401 (the row's interface)
                    Mode, interval_modes)

if TYPE_CHECKING:
    from .transition_verdict import TransitionCheck

COLUMNS = ("t", "x", "y", "cx", "cy", "cz", "vx", "vy", "vz", "wx", "wy", "wz",
           "r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33",
           "energy", "normal_force")
# The CSV adds columns per row after the 23 above (docs/design.md §5); readers that take the
# first 23 keep working: the energy error, then, only where the run could change mode, the
# contact's mode, the slip speed (m/s) and the energy dissipated so far (J). ``csv_columns`` says
# which a trajectory's CSV has.
MODE_COLUMNS = ("mode", "slip_speed", "dissipated")
# What took the energy dissipated (``Trajectory.dissipated_by``, J so far each; ``dissipated`` is
# their sum): sliding friction, the landings' impacts, rolling resistance, spin friction and air.
# A scene that dissipates (``Scene.dissipates``) has one CSV column each after ``dissipated``.
DISSIPATION_CAUSES = ("sliding", "impacts", "rolling", "spin", "air")
DISSIPATION_COLUMNS = tuple(f"dissipated_{cause}" for cause in DISSIPATION_CAUSES)
EXTRA_COLUMNS = ("energy_error", *MODE_COLUMNS, *DISSIPATION_COLUMNS)
ROLLING_CSV_COLUMNS = COLUMNS + ("energy_error",)   # numbers only, as before the contact of version 3
CSV_COLUMNS = ROLLING_CSV_COLUMNS + MODE_COLUMNS
UNITS = {"t": "s", "x": "m", "y": "m", "cx": "m", "cy": "m", "cz": "m",
         "vx": "m/s", "vy": "m/s", "vz": "m/s", "wx": "rad/s", "wy": "rad/s", "wz": "rad/s",
         **{f"r{i}{j}": "1" for i in (1, 2, 3) for j in (1, 2, 3)},
         "energy": "J", "normal_force": "N", "energy_error": "1", "mode": "-", "slip_speed": "m/s",
         "dissipated": "J", **{name: "J" for name in DISSIPATION_COLUMNS}}

# Where a row keeps what (the kernel's interface declares it once; use these, never raw column numbers)
T = ROW_T                          # time
CONTACT = ROW_SLICES["contact"]    # contact point (x, y)
CENTER = ROW_SLICES["center"]      # ball centre
VELOCITY = ROW_SLICES["velocity"]  # centre velocity
OMEGA = ROW_SLICES["omega"]        # angular velocity (world frame)
R = ROW_SLICES["R"]                # orientation, row-major 3x3
ENERGY = ROW_ENERGY
NORMAL_FORCE = ROW_FORCE
SLIP_SPEED = ROW_SLICES["slip_speed"].start   # the speed of the ball's point at the contact
DISSIPATED = ROW_SLICES["dissipated"].start   # the energy dissipated so far
# the causes a row carries itself (the kernel's quadratures, J so far each: rolling resistance, spin
# friction, air, in the order of ``sliding.BallState.dissipated_by``); the others ``dissipated_by`` finds
ROW_CAUSES = {cause: ROW_SLICES[f"dissipated_{cause}"].start for cause in DISSIPATION_CAUSES
              if f"dissipated_{cause}" in ROW_SLICES}
CAUSES = slice(min(ROW_CAUSES.values()), max(ROW_CAUSES.values()) + 1)
# the cause of the energy the total gains beyond the row's own causes and the impacts over an interval
# that ends in each mode: a flight's rows carry what the causes took (air in flight in its column),
# so all a flight's first row adds is the slide to a kink it left from (``ModeMachine._to_kink``).
# The row where a moving ball is held (the first of a stay, resting) ends the motion that stopped
# there: its interval is the mode's of the row before (``modes.interval_modes``).
MODE_CAUSES = {SLIDING: "sliding", ROLLING: "rolling", RESTING: "spin", FLYING: "sliding"}

ENERGY_WARNING = 1e-2          # a relative energy error above this gets a warning
ORTHOGONALITY_WARNING = 1e-3   # likewise ||R^T R - I|| at the end of a run


class _Named(str, enum.Enum):
    def __str__(self) -> str:
        return self.value


# How a run ended (the kernel's status codes, and aborted and row_limit set by Python), and why
# the physics stopped a run (``Failure.reason``; ``Failure.value`` says how far): members named
# from the kernel interface's tables (STATUSES, REASONS), which say what each means.
Status = _Named("Status", [(name.upper(), name) for name in STATUSES if name != "running"], module=__name__)
# Why a flight's landing search stopped a run, or what a kernel run's non-finite stop comes from
# (set in Python, not by the kernel): like REASONS, each with the status it gives, what
# ``Failure.value`` holds and its sentence.
FLIGHT_REASONS = {
    "stiff_drag": ("nonfinite", "the drag's rate k|ċ|/m times the step, at the last state",
                   "the air's drag slows the ball faster than the steps can follow after {where}: its rate k|ċ|/m "
                   "times the step is {value:.3g} (a motion this stiff needs steps below 1/(k|ċ|/m)), so the run "
                   "stops; use a smaller step, or less air"),
    "off_domain": ("nonfinite", "nothing",
                   "the flying ball leaves the landscape's domain after {where} (the landscape cannot be evaluated "
                   "below it): there is no surface to land on, so the run stops"),
    "no_foot": ("does_not_fit", "nothing",
                "the flying ball's nearest surface point cannot be found at {where} (Newton's method reaches no "
                "point as near as the surface's own samples there), so the landing search cannot go on and the "
                "run stops rather than risk a wrong landing"),
    "narrow_feature": ("does_not_fit", "the centre's height above the surface there (m)",
                       "the flying ball meets a feature of the surface at {where} narrower than the landing search "
                       "can follow (the centre is {value:.3g} m above the surface there, less than the ball's radius "
                       "r = {radius:g} m): the run stops rather than fly through it"),
    "false_landing": ("does_not_fit", "the centre's distance to the contact point found (m)",
                      "a landing found at {where} is not where the ball touches the surface (the centre is "
                      "{value:.6g} m from that surface point, not r = {radius:g} m): the run stops rather than "
                      "land there"),
    "ridge_slip": ("does_not_fit", "the normal force on the ridge's edge there (N)",
                   "the ball turning over a ridge at {where} would need more friction than μ F·N to roll over "
                   "its edge (F·N = {value:.3g} N): a real ball would slide over it, which the model does not "
                   "follow"),
    "ridge_pivot": ("does_not_fit", "the normal force the ball would need on the ridge's edge there (N)",
                    "the ball reaches a ridge of the surface at {where} sliding, too slowly to leave its edge: a "
                    "real ball would turn over the edge with F·N = {value:.3g} N, rubbing on it, which the model "
                    "does not follow"),
    "edge_landing": ("does_not_fit", "the time the flight would take to come down on the edge (s)",
                     "the ball leaves a ridge's edge at {where} so slowly that it comes down on that edge again "
                     "{value:.3g} s later, before it is past it: a landing on an edge, which the model does not "
                     "follow"),
    "tip_slip": ("does_not_fit", "the normal force on the tip there (N)",
                 "the ball turning over a tip of the surface at {where} (the tip of a cone, or a like point) would "
                 "need more friction than μ F·N to roll over it (F·N = {value:.3g} N): a real ball would slide "
                 "about it, which the model does not follow"),
}
Reason = _Named("Reason", [(name.upper(), name) for name in (*REASONS, *FLIGHT_REASONS)], module=__name__)


@dataclass(frozen=True)
class Liftoff:
    """Where the real ball would first leave the surface: F·N turns negative, or a convex kink."""

    time: float   # s, located on the method's dense output
    x: float      # contact point (m)
    y: float
    kink: bool    # at a convex kink (a ridge) rather than where F·N crosses 0


@dataclass(frozen=True)
class Transition:
    """Where the contact changes mode: ``kind`` in TRANSITION_KINDS ("slip": rolling turns into
    sliding, "grip": sliding into rolling, "liftoff", "landing", "rest"), at ``time`` and contact point
    (x, y). A landing also says how fast the ball hit the surface along its normal
    (``impact_speed``, m/s) and the kinetic energy the impact took (``energy_lost``, J)."""

    time: float
    kind: str
    x: float
    y: float
    impact_speed: float | None = None
    energy_lost: float | None = None

    def sentence(self) -> str:
        where = f"t = {self.time:.6g} s, (x, y) = ({self.x:.6g}, {self.y:.6g})"
        if self.kind == "landing":
            return (f"landing at {where}: hits at {self.impact_speed:.4g} m/s along the normal, "
                    f"{self.energy_lost:.4g} J lost")
        return {"slip": f"slip at {where}: rolling would need more friction than μ F·N",
                "grip": f"grip at {where}: the slip ends, the ball rolls",
                "liftoff": f"lift-off at {where}: the ball leaves the surface",
                "rest": f"rest at {where}: the ball comes to rest"}[self.kind]


@dataclass(frozen=True)
class Failure:
    """Where and why the physics stopped a run: the facts behind ``Trajectory.message``."""

    reason: Reason
    time: float   # s
    x: float      # contact point (m)
    y: float
    value: float  # what crossed its limit (see Reason); nan where nothing is measured


@dataclass(frozen=True)
class EnergyCheck:
    """Whose a run's energy error is, found by taking again the recorded interval where most of
    it happened (``energy_check.energy_check``): with the run's step and steps 4, 16, 64, 256 times
    shorter (tolerances 10^4 times tighter for the adaptive methods; euler's interval is taken
    again by rk4). A smooth landscape's error shrinks as the method's order predicts
    (``expected``, per step 4 times shorter) once the steps resolve it; one that shrinks no faster
    than across a jump of the curvature is the landscape's."""

    time: float        # s: the start of the interval
    end: float         # s: its end
    x: float           # contact point at its start (m)
    y: float
    jump: float        # the energy's change across it, relative to its scale
    shrink: float      # the change there with the longer of the two steps (``finer``) over that with the shorter
    expected: float    # what a smooth landscape's shrinks by
    landscape: bool    # True: the error does not shrink with the step: the landscape's
    finer: str = "the run's step and one 4 times shorter, the shorter"  # how it was taken again, and which shrinks


@dataclass
class Trajectory:
    """Recorded rows (shape (n, 23)) and the facts of the run that produced them."""

    data: np.ndarray
    status: Status = Status.OK
    message: str = ""
    liftoff: Liftoff | None = None
    steps: int = 0          # accepted steps
    rejected: int = 0       # steps tried and rejected by the error control
    evaluations: int = 0    # right-hand-side evaluations, rejected tries included
    failure: Failure | None = None  # set when the physics stopped the run
    mass: float = 1.0
    radius: float = 0.1
    gravity: float = 9.81
    provenance: dict = field(default_factory=dict)
    energy_check: EnergyCheck | None = None  # set by the run where one interval's jump dominates
    # the mode of each row (positions in MODES); None: the run could not change mode (the 2011
    # model: friction null, glued after a lift-off) and every row rolls
    modes: np.ndarray | None = None
    transitions: tuple[Transition, ...] = ()   # the changes of mode, in time order
    transition_check: TransitionCheck | None = None   # set by the run: whether they are converged
    dissipates: bool = False   # the scene's couples or air take energy (``Scene.dissipates``): the CSV splits it

    @property
    def mode(self) -> np.ndarray:
        """The contact's mode of each row: "rolling", "sliding" or "flying" (strings)."""
        codes = np.zeros(len(self), dtype=np.int8) if self.modes is None else self.modes[: len(self)]
        return np.array(MODES)[codes]

    @property
    def slip_speed(self) -> np.ndarray:
        """The speed of the ball's material point at the contact (m/s; 0 rolling; in flight the
        tangential speed of its point nearest the surface)."""
        return self.data[:, SLIP_SPEED]

    @property
    def dissipated(self) -> np.ndarray:
        """The energy dissipated so far (J), for every row: the sum of ``dissipated_by``."""
        return self.data[:, DISSIPATED]

    @property
    def dissipated_by(self) -> dict[str, np.ndarray]:
        """The energy dissipated so far by each of DISSIPATION_CAUSES (J, every row; zeros where a
        cause is off): the impacts from the landings' ``energy_lost`` (a row at a landing's time
        is the state after it), the row's own causes (ROW_CAUSES) as recorded, and what the total
        gains beyond those over each recorded interval to the cause of the mode of its motion
        (MODE_CAUSES, by ``modes.interval_modes``: the mode of the row it ends in, but the stopping
        motion's at the row where the ball comes to be held; sliding friction while sliding, spin
        friction spinning in place)."""
        t = self.t
        by = {cause: np.zeros(len(self)) for cause in DISSIPATION_CAUSES}
        for cause, column in ROW_CAUSES.items():
            by[cause] = self.data[:, column].copy()
        landings = [change for change in self.transitions if change.kind == "landing"]
        if landings:
            so_far = np.concatenate([[0.0], np.cumsum([change.energy_lost for change in landings])])
            by["impacts"] = so_far[np.searchsorted([change.time for change in landings], t, side="right")]
        rest = self.dissipated - sum(by.values())
        gained = np.diff(rest, prepend=0.0)
        codes = interval_modes(np.zeros(len(self), dtype=np.int8) if self.modes is None else self.modes[: len(self)])
        for mode, cause in MODE_CAUSES.items():
            by[cause] = by[cause] + np.cumsum(np.where(codes == mode, gained, 0.0))
        return by

    @property
    def landings(self) -> int:
        return sum(1 for change in self.transitions if change.kind == "landing")

    @property
    def liftoff_time(self) -> float | None:
        """The first lift-off's time (s), or None."""
        return None if self.liftoff is None else self.liftoff.time

    def __len__(self) -> int:
        return len(self.data)

    @property
    def t(self) -> np.ndarray:
        return self.data[:, T]

    @property
    def contact(self) -> np.ndarray:
        return self.data[:, CONTACT]

    @property
    def center(self) -> np.ndarray:
        return self.data[:, CENTER]

    @property
    def velocity(self) -> np.ndarray:
        return self.data[:, VELOCITY]

    @property
    def omega(self) -> np.ndarray:
        return self.data[:, OMEGA]

    @property
    def R(self) -> np.ndarray:
        return self.data[:, R].reshape(-1, 3, 3)

    @property
    def energy(self) -> np.ndarray:
        return self.data[:, ENERGY]

    @property
    def normal_force(self) -> np.ndarray:
        return self.data[:, NORMAL_FORCE]

    @property
    def energy_scale(self) -> float:
        """What energy errors are relative to: |E(0)|, or m g r where |E(0)| is smaller."""
        e0 = abs(self.energy[0]) if len(self) else 0.0
        return max(e0, self.mass * self.gravity * self.radius, np.finfo(float).tiny)

    def energy_error(self) -> np.ndarray:
        """(E(t) + D(t) - E(0) - D(0)) / energy_scale for every row, D the energy dissipated (0 in
        the 2011 model): what friction and landings took is accounted for, so this measures the
        integrator alone."""
        if not len(self):
            return self.energy.copy()
        total = self.energy + self.dissipated
        return (total - total[0]) / self.energy_scale

    @property
    def energy_drift(self) -> float:
        """max |E(t) - E(0)| relative to |E(0)|, or to m g r where |E(0)| is smaller: the largest of
        ``energy_error``'s sizes, to the last bit (a difference from E(0) + D(0) rounds monotonically,
        so its largest size is at the largest or the smallest E + D; a NaN anywhere gives NaN)."""
        if not len(self):
            return 0.0
        total = self.energy + self.dissipated
        first = total[0]
        return float(np.max(np.abs(np.array([total.max() - first, total.min() - first]))) / self.energy_scale)

    def orthogonality_error(self) -> np.ndarray:
        """||R^T R - I|| (Frobenius) for every row."""
        R = self.R
        total = np.zeros(len(self))
        for i in range(3):               # (R^T R)_ij = column i . column j, summed as arrays
            for j in range(i, 3):
                g = R[:, 0, i] * R[:, 0, j] + R[:, 1, i] * R[:, 1, j] + R[:, 2, i] * R[:, 2, j]
                if i == j:
                    g -= 1.0
                total += g * g if i == j else 2.0 * g * g
        return np.sqrt(total)

    def warnings(self) -> list[str]:
        """What the run's own numbers say about its method and step: the energy error at its
        largest, ||R^T R - I|| at the end and transitions taken again that did not converge
        (``transition_check``; empty when all is well)."""
        notes = []
        drift = self.energy_drift
        if drift > ENERGY_WARNING:
            notes.append(self._energy_note(drift))
        orth = float(self.orthogonality_error()[-1]) if len(self) else 0.0
        if orth > ORTHOGONALITY_WARNING:
            notes.append(f"‖RᵀR − I‖ = {orth:.2g}: R is no longer a rotation (classic update; "
                         f"Munthe-Kaas keeps it one)")
        transitions = self.transition_check.warning() if self.transition_check is not None else None
        if transitions:
            notes.append(transitions)
        return notes

    def _energy_note(self, drift: float) -> str:
        """Whose the energy error is. Where most of it is one jump between two rows, across the
        kink or cone tip where the run's lift-off was found, the model's ball jumps there (its
        centre moves across at once, however short the step): the landscape's, not the step's.
        Else where the run's ``energy_check`` found that the jump does not shrink with the step:
        the landscape's too. Otherwise it is the step's."""
        error = self.energy_error()
        jumps = np.abs(np.diff(error))
        lift = self.liftoff
        if lift is not None and lift.kink and len(jumps):
            i = int(np.argmax(jumps))
            # (a step across the tip may already move the energy before the one that jumps)
            if jumps[i] >= 0.5 * drift and self.t[max(i - 1, 0)] <= lift.time <= self.t[min(i + 2, len(self) - 1)]:
                return (f"energy changed by {drift:.2g} of its scale, {jumps[i]:.2g} of it at once at "
                        f"t = {lift.time:.6g} s, (x, y) = ({lift.x:.6g}, {lift.y:.6g}), where the ball passes a kink "
                        f"or the tip of a cone and the model's ball jumps over it: this is the landscape's, "
                        f"not the step's (a smaller step does not reduce it)")
        check = self.energy_check
        if check is not None and check.landscape:
            return (f"energy changed by {drift:.2g} of its scale, {check.jump:.2g} of it between t = {check.time:.6g} "
                    f"and {check.end:.6g} s from (x, y) = ({check.x:.6g}, {check.y:.6g}), and that does not shrink "
                    f"as the step does (taken again with {check.finer} changes it by 1/{check.shrink:.3g} as much, "
                    f"where a smooth landscape gives 1/{check.expected:.3g}): the landscape is not smooth there; this "
                    f"is the landscape's, not the step's")
        if check is not None:
            return (f"energy changed by {drift:.2g} of its scale: the step is too large for this method (its largest "
                    f"jump, at t = {check.time:.6g} s, taken again with {check.finer} changes it by "
                    f"1/{check.shrink:.3g} as much)")
        return f"energy changed by {drift:.2g} of its scale: the step is too large for this method"

    def to_csv(self, path: str | os.PathLike, keep=()) -> None:
        """Write the CSV of docs/design.md §5 atomically, numbers at full precision (``keep``: paths
        that must not be overwritten, see ``rollball.files``)."""
        atomic_write(path, self.write_csv, keep=keep)

    def write_csv(self, stream) -> None:
        """Provenance and unit lines (``#``), the header, then the rows: the columns of
        ``csv_columns`` (the 23 columns and the energy error; then, where the run could change
        mode, the mode, the slip speed and the energy dissipated, and by each cause where the
        scene dissipates)."""
        columns = csv_columns(self)
        for key, value in self.provenance.items():
            stream.write(f"# {key}: {value}\n")
        stream.write(f"# units: {','.join(UNITS[name] for name in columns)}\n")
        stream.write(",".join(columns) + "\n")
        if not len(self):
            return
        numbers = np.column_stack([self.data[:, : len(COLUMNS)], self.energy_error()])
        if columns == ROLLING_CSV_COLUMNS:   # numbers only: what numpy.loadtxt reads
            np.savetxt(stream, numbers, fmt="%.17g", delimiter=",")
            return
        before = io.StringIO()
        np.savetxt(before, numbers, fmt="%.17g", delimiter=",")
        after = io.StringIO()
        tail = [self.slip_speed, self.dissipated]
        if self.dissipates:
            tail += list(self.dissipated_by.values())
        np.savetxt(after, np.column_stack(tail), fmt="%.17g", delimiter=",")
        for head, mode, tail in zip(before.getvalue().splitlines(), self.mode, after.getvalue().splitlines()):
            stream.write(f"{head},{mode},{tail}\n")


def csv_columns(trajectory: Trajectory) -> tuple[str, ...]:
    """The columns of a trajectory's CSV, the one choice every writer follows: the 23 columns and
    the energy error, numbers only, for a run that could not change mode (``modes`` None: the 2011
    model, friction null and glued after a lift-off, which every version 1-2 scene is), as written
    before version 3; else those and the mode columns (mode, slip_speed, dissipated), and for a
    scene that dissipates (``Trajectory.dissipates``) the energy dissipated by each cause."""
    if trajectory.modes is None:
        return ROLLING_CSV_COLUMNS
    return CSV_COLUMNS + DISSIPATION_COLUMNS if trajectory.dissipates else CSV_COLUMNS


def read_csv(path: str | os.PathLike, extra: bool = False):
    """Read a trajectory CSV back as an (n, 23) array of its first 23 columns (``#`` lines are
    skipped; files with only these 23 columns, as written before the energy error, read too).
    With ``extra``: (that array, {name: column} of the columns after them that the file has:
    "energy_error", "mode" (strings), "slip_speed", "dissipated", the DISSIPATION_COLUMNS))."""
    with open(path, encoding="utf-8") as stream:
        lines = [line for line in stream if not line.startswith("#")]
    header = tuple(lines[0].strip().split(",")) if lines else ()
    if header[: len(COLUMNS)] != COLUMNS:
        raise ValueError(f"{path}: not a RollBall trajectory (header must begin {','.join(COLUMNS)})")
    body = "".join(lines[1:])
    names = [name for name in header[len(COLUMNS):] if name in EXTRA_COLUMNS]
    if not body.strip():
        rows = np.empty((0, len(COLUMNS)))
        return (rows, {name: np.empty(0, dtype=str if name == "mode" else float) for name in names}) if extra else rows
    rows = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2, usecols=range(len(COLUMNS)))
    if not extra:
        return rows
    columns = {}
    for name in names:
        position = header.index(name)
        columns[name] = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=1, usecols=position,
                                   dtype=str if name == "mode" else float)
    return rows, columns
