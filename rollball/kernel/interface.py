"""The kernel's binary interface, declared once as data: what Python and the compiled kernel
must agree on. From here come the entry points' argument slots (``machine_code.Arguments``
packs them, ``entries`` unpacks them), the columns of a recorded row (``trajectory``), the
run's counters, status codes and failure reasons with their sentences, and the arrays a run
hands the kernel (``run_arrays``). Plain Python: nothing here is compiled. kernel.json records
``description()``, and the shipped code is used only where it is this one.
"""

from __future__ import annotations

import math

import numpy as np

VERSION = 4   # of the slot convention and the landscape's record below (kernel.json records it)

# -- the entry points' arguments -------------------------------------------------------------------
#
# Python calls an entry point with one pointer to int64 "slots" (ENTRY_SLOTS of them) holding the
# arguments of the kernel function it runs, in the declared order: a number in one slot (a float as
# its bits), an array in three (its data's address, rows, columns: 1 for a vector); arrays
# C-contiguous, "vector" and "matrix" of float64, "ints" an int64 vector. Calls name every
# argument (``machine_code.Arguments``), and each entry's names are its function's parameters.
ADDRESS, INT, FLOAT = "address", "int", "float"   # one slot each (address: the landscape's record)
VECTOR, MATRIX, INTS = "vector", "matrix", "ints"  # three slots each
NUMBER_KINDS = (ADDRESS, INT, FLOAT)
ENTRY_SLOTS = 192

# The arrays of a run every loop takes (``run_arrays`` makes them).
RUN_ARRAYS = (("z", VECTOR), ("R", MATRIX), ("K", MATRIX), ("probe", VECTOR), ("rows", MATRIX), ("ints", INTS),
              ("info", VECTOR), ("work", VECTOR))

# The scratch of a flight in vacuum (``bounces.bounces``: its landing search's, its rows' and its
# impact's), which the sweeps' batch loop hands it too; ``flight.bounce_scratch`` makes them.
FLIGHT_SCRATCH = (("hints", MATRIX), ("tips", MATRIX), ("landed", MATRIX), ("refer", INTS), ("hit", VECTOR),
                  ("times", VECTOR), ("guess", VECTOR), ("centers", MATRIX), ("feet", MATRIX), ("normals", MATRIX),
                  ("distances", VECTOR), ("below", VECTOR), ("sampled", VECTOR), ("spacings", VECTOR),
                  ("nearest", MATRIX), ("start_centers", MATRIX), ("start_feet", MATRIX), ("start_normals", MATRIX),
                  ("start_distances", VECTOR), ("row_times", VECTOR), ("row_centers", MATRIX),
                  ("row_velocities", MATRIX), ("row_feet", MATRIX), ("row_normals", MATRIX),
                  ("row_distances", VECTOR), ("turn", MATRIX), ("d", VECTOR), ("bounds", MATRIX))

# advance takes, beside its fixed method, the embedded pair (S, SE, SP, s_kind, s_exp: as
# advance_adaptive's W, E, P, err_kind, err_exp) that takes its stiff steps at the tolerance s_tol
# (rtol and atol both): a stretch of them ends at the first step whose direction is EXIT_MARGIN
# times further from stiff (``loops.turn_stiff``). (The sweeps' batches, p[P_STIFF] 0, have none.)
EXIT_MARGIN = 1.5
# A sliding ball's slip whose speed would change by as much as itself within SLIP_TIME sqrt(r/g) is
# stiff for a fixed step, whatever the step (``loops.slip_stiff``).
SLIP_TIME = 0.5
# advance and advance_adaptive take the absolute time ``t_start`` of the run's start and its
# absolute ``t_end``: a run that goes on after a change of contact mode keeps the whole run's clock
# (its steps and rows on the grid a run from t = 0 has, ``grid_steps_before``; advance's n_steps
# counts the whole run's steps, those before t_start included).
ENTRIES = {
    "advance": (("fn", ADDRESS), ("W", MATRIX), ("P", MATRIX), ("p", VECTOR), ("dt", FLOAT), ("t_start", FLOAT),
                ("t_end", FLOAT), ("n_steps", INT), ("every", INT), ("max_steps", INT), *RUN_ARRAYS,
                ("stepping", FLOAT), ("S", MATRIX), ("SE", MATRIX), ("SP", MATRIX), ("s_kind", INT), ("s_exp", FLOAT),
                ("s_tol", FLOAT)),
    "advance_adaptive": (("fn", ADDRESS), ("W", MATRIX), ("E", MATRIX), ("P", MATRIX), ("p", VECTOR),
                         ("err_kind", INT), ("err_exp", FLOAT), ("t_start", FLOAT), ("t_end", FLOAT),
                         ("record_dt", FLOAT), ("rtol", FLOAT), ("atol", FLOAT), ("max_steps", INT), *RUN_ARRAYS),
    "advance_batch": (("fn", ADDRESS), ("W", MATRIX), ("P", MATRIX), ("Z0", MATRIX), ("PARAMS", MATRIX),
                      ("DT", VECTOR), ("T_END", VECTOR), ("N_STEPS", INTS), ("BOUNCE", MATRIX), ("status", INTS),
                      ("out", MATRIX), *RUN_ARRAYS, ("zs", VECTOR), ("Ks", MATRIX), ("S", MATRIX), ("SE", MATRIX),
                      ("SP", MATRIX), ("s_kind", INT), ("s_exp", FLOAT), ("s_tol", FLOAT), ("acc", VECTOR),
                      ("p", VECTOR), ("tape", MATRIX),
                      *(("flight", VECTOR), ("turned", MATRIX), ("flown", VECTOR), ("flown_rows", MATRIX)),
                      *FLIGHT_SCRATCH),
    "evaluate_points": (("fn", ADDRESS), ("xs", VECTOR), ("ys", VECTOR), ("out", MATRIX), ("d", VECTOR)),
    "closest_points": (("fn", ADDRESS), ("centers", MATRIX), ("feet", MATRIX), ("normals", MATRIX),
                       ("distances", VECTOR), ("iterations", INT), ("d", VECTOR)),
    "nearest_feet": (("fn", ADDRESS), ("centers", MATRIX), ("guess", VECTOR), ("hints", MATRIX), ("tips", MATRIX),
                     ("spacing", FLOAT), ("reach_default", FLOAT), ("feet", MATRIX), ("normals", MATRIX),
                     ("distances", VECTOR), ("below", VECTOR), ("sampled", VECTOR), ("spacings", VECTOR),
                     ("nearest", MATRIX), ("start_centers", MATRIX), ("start_feet", MATRIX), ("start_normals", MATRIX),
                     ("start_distances", VECTOR), ("iterations", INT), ("d", VECTOR)),
    "land": (("fn", ADDRESS), ("start", VECTOR), ("gravity", FLOAT), ("radius", FLOAT), ("t_end", FLOAT),
             ("hints", MATRIX), ("tips", MATRIX), ("reach_default", FLOAT), ("iterations", INT),
             ("out", VECTOR), ("times", VECTOR), ("guess", VECTOR), ("centers", MATRIX), ("feet", MATRIX),
             ("normals", MATRIX), ("distances", VECTOR), ("below", VECTOR), ("sampled", VECTOR), ("spacings", VECTOR),
             ("nearest", MATRIX), ("start_centers", MATRIX), ("start_feet", MATRIX), ("start_normals", MATRIX),
             ("start_distances", VECTOR), ("d", VECTOR), ("tape", MATRIX), ("bounds", MATRIX)),
    "bound_boxes": (("fn", ADDRESS), ("tape", MATRIX), ("boxes", MATRIX), ("out", MATRIX), ("work", MATRIX)),
    "impact": (("hit", VECTOR),),
    "bounces": (("fn", ADDRESS), ("state", VECTOR), ("R", MATRIX), ("gravity", FLOAT), ("radius", FLOAT),
                ("mass", FLOAT), ("restitution", FLOAT), ("friction", FLOAT), ("rest", FLOAT), ("t_end", FLOAT),
                ("step", FLOAT), ("every", INT), ("enough", INT), ("dissipated", FLOAT), ("hints", MATRIX),
                ("tips", MATRIX), ("reach_default", FLOAT), ("iterations", INT), ("out", VECTOR),
                ("landed", MATRIX), ("rows", MATRIX), ("refer", INTS), ("hit", VECTOR), ("times", VECTOR),
                ("guess", VECTOR), ("centers", MATRIX), ("feet", MATRIX), ("normals", MATRIX), ("distances", VECTOR),
                ("below", VECTOR), ("sampled", VECTOR), ("spacings", VECTOR), ("nearest", MATRIX),
                ("start_centers", MATRIX), ("start_feet", MATRIX), ("start_normals", MATRIX),
                ("start_distances", VECTOR),
                ("row_times", VECTOR), ("row_centers", MATRIX), ("row_velocities", MATRIX), ("row_feet", MATRIX),
                ("row_normals", MATRIX), ("row_distances", VECTOR), ("turn", MATRIX), ("d", VECTOR), ("tape", MATRIX),
                ("bounds", MATRIX), ("feet_after", FLOAT)),
    "flight_rows": (("fn", ADDRESS), ("count", INT), ("centers", MATRIX), ("velocities", MATRIX), ("times", VECTOR),
                    ("start_time", FLOAT), ("omega", VECTOR), ("R", MATRIX), ("guess", VECTOR), ("tips", MATRIX),
                    ("mass", FLOAT), ("radius", FLOAT), ("gravity", FLOAT), ("dissipated", FLOAT), ("rows", MATRIX),
                    ("refer", INTS), ("feet", MATRIX), ("normals", MATRIX), ("distances", VECTOR), ("turn", MATRIX),
                    ("iterations", INT), ("d", VECTOR), ("feet_after", FLOAT)),
}


# Each entry point is the function ``entry_name(name)`` of the module ENTRY_MODULE (``unpacking``
# makes them); their machine code's symbols begin with both.
ENTRY_MODULE = "rollball.kernel.unpacking"


def entry_name(name: str) -> str:
    """The name of the entry point's function that runs the kernel function ``name``."""
    return f"{name}_entry"


def layout(name: str) -> tuple[tuple[str, str, int], ...]:
    """The arguments of the entry point ``name``: (parameter, kind, first slot) each."""
    slot, out = 0, []
    for parameter, kind in ENTRIES[name]:
        out.append((parameter, kind, slot))
        slot += 1 if kind in NUMBER_KINDS else 3
    if slot > ENTRY_SLOTS:
        raise ValueError(f"{name}: {slot} slots, more than ENTRY_SLOTS")
    return tuple(out)


# -- the landscape ------------------------------------------------------------------------------
#
# The entries take a landscape as ``fn``: the address of its record, float64 words whose first holds
# the address of the landscape's machine code (an int64, its bits) and the rest the values of the
# formula's parameters in their declared order (none for a formula without parameters). The code is
# the C function LANDSCAPE_ARGUMENTS, f(x, y, parameters, out): ``parameters`` points at the record's
# values, and it writes f, f_x, f_y, f_xx, f_xy, f_yy to out[0:LANDSCAPE_OUTPUTS]. New values are a
# new record for the same code: nothing is compiled.
POINTER = "pointer"   # a C pointer to float64 (only in the landscape's arguments)
LANDSCAPE_ARGUMENTS = (("x", FLOAT), ("y", FLOAT), ("parameters", POINTER), ("out", POINTER))
LANDSCAPE_RECORD_CODE, LANDSCAPE_RECORD_VALUES = 0, 1   # word of the code's address, first value
LANDSCAPE_OUTPUTS = 6


def landscape_record(address: int, values=()) -> np.ndarray:
    """A landscape's record (see above): its code's ``address``, then its parameters' ``values``."""
    record = np.empty(LANDSCAPE_RECORD_VALUES + len(values))
    record[LANDSCAPE_RECORD_CODE:LANDSCAPE_RECORD_VALUES].view(np.int64)[0] = address
    record[LANDSCAPE_RECORD_VALUES:] = values
    return record


# -- a flight's landing ---------------------------------------------------------------------------
#
# The landing search's numbers (flight.py's search and the compiled one, ``landing.land``, take
# the same looks: docs/design.md §1, "Flight").
FOOT_ITERATIONS = 50     # Newton's iterations for the closest surface point (converges in a few)
GAP_TOLERANCE = 1e-12    # × r: a gap this small is contact (round-off of the distance)
FIRST_STEP = 1e-6        # s: the first look after a lift-off, then doubling until the ball is clear
CLEAR_WITHIN = 1e-2      # s: a ball not clear of the surface by then never left it
MAX_LOOKS = 1_000_000    # looks of the landing search (far more than it takes: see ``landing``)
SHRINK = 0.1             # a step not certified to hold no root is tried again at least this share...
SHRINK_MOST = 0.8        # ...and at most this share as long
GROW_BY = 2.0            # a step tried is at most this many times the last certified one
LANDING_BATCH = 8        # while the gap grows, the landing search looks this many steps ahead at once
GRAZE = 1e-6             # × r: a gap below this is contact (a graze, or just after a lift-off)
GRAZE_LOOKS = 8          # certified looks within it while the gap still falls, before it is contact
CLEAR_MARGIN = 1e-13     # × r: the share of a gap a certified step keeps for round-off
PATH_ITERATIONS = 8      # Newton's iterations for the time a path length takes
GRID_SPACING = 0.25      # × r: the samples of the grid a closest point is looked for on at most this far apart...
SAMPLES = 21             # ...and at most this many per side (a wider square: a tenth of its half-width apart)...
SAMPLES_LEAST = 3        # ...and at least this many...
BEST_SAMPLES = 3         # ...and how many of its nearest points Newton's method starts from
SAMPLE_SLACK = 1e-9      # a foot may be this share farther than the nearest surface sample (round-off)
TRACK = 1e-3             # × r: the spacing of the surface samples under the centre's path (``Flight.track``)
TRACK_MOST = 100_000     # (the samples taken at once)
TRACK_SLACK = 1e-9       # × r: a sample this much nearer than r is inside the ball (round-off)
# The track certifies stretches of its samples at once where the landscape's bounds over the box
# the stretch's path lies in (``bounds.box_bounds``, from the landscape's tape) put the whole
# surface there more than r below the centre; the rest it samples, TRACK_LEAF at least at once, and
# where the bounds fail in a row, twice as many samples each time before it tries them again (at
# most TRACK_BLIND).
TRACK_LEAF, TRACK_BLIND = 16, 4096
# A landscape's tape (``Landscape.tape``, ``bounds.box_bounds``): f's operations in order, one row
# of TAPE_COLUMNS floats each: the operation, its operands' rows (a, b), an integer k (a power, a
# parameter's index, or how many terms share the sum or product the row is part of) and two numbers
# (a constant's value as its interval, a real power). An operation's interval encloses every value
# the landscape's own code computes there for (x, y) in the box, its round-off included.
TAPE_COLUMNS = 6
(TAPE_CONST, TAPE_X, TAPE_Y, TAPE_PARAMETER, TAPE_ADD, TAPE_MUL, TAPE_POWER, TAPE_REAL_POWER, TAPE_POW,
 TAPE_EXP, TAPE_LOG, TAPE_SQRT, TAPE_SIN, TAPE_COS, TAPE_TANH, TAPE_ATAN, TAPE_SINH, TAPE_ASINH, TAPE_COSH,
 TAPE_ABS, TAPE_MIN, TAPE_MAX, TAPE_ASIN, TAPE_ACOS, TAPE_ATANH, TAPE_ACOSH) = range(26)
# ``landing.land`` writes its answer into OUT_LANDING floats: LANDING_LANDED (then the time, the
# foot's x, y, the normal there (3) and the centre's signed distance), LANDING_FLYING (still in
# the air at t_end), or LANDING_REFER (flight.py searches this flight itself).
LANDING_FLYING, LANDING_LANDED, LANDING_REFER = 0.0, 1.0, 2.0
OUT_LANDING = 8

# An impact (``bounces.impact``) reads and writes HIT_SIZE floats: the centre's velocity (3), omega
# (3) and the unit normal (3) at the contact, m, r, e, mu (inf: always enough to stick) and the
# slowest rebound that flies; then what it leaves: the velocity and omega after (3 each), the normal
# speed it hit with, the rebound's, 1 where the contact point sticks, the energy lost, 1 where the
# ball settled (a rebound too slow to fly: its normal velocity taken away too), the impulse (3).
(HIT_VELOCITY, HIT_OMEGA, HIT_NORMAL, HIT_MASS, HIT_RADIUS, HIT_RESTITUTION, HIT_FRICTION, HIT_REST, HIT_AFTER,
 HIT_SPIN_AFTER, HIT_APPROACH, HIT_REBOUND, HIT_STICKING, HIT_LOST, HIT_SETTLED, HIT_IMPULSE,
 HIT_SIZE) = 0, 3, 6, 9, 10, 11, 12, 13, 14, 17, 20, 21, 22, 23, 24, 25, 28
# How ``bounces.bounces`` (a flight in vacuum, flight after flight) ended, in out[0] of its
# OUT_BOUNCES floats; BOUNCES_CHAIN landings at most in one call (then BOUNCES_CONTINUE: a caller
# that advances step by step gets its answer between them).
(BOUNCES_SETTLED, BOUNCES_FLYING, BOUNCES_DONE, BOUNCES_ENOUGH, BOUNCES_CONTINUE, BOUNCES_REFER,
 BOUNCES_ROOM) = 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0
OUT_BOUNCES = 8 + OUT_LANDING
BOUNCES_CHAIN = 64


# -- a run's state -------------------------------------------------------------------------------
#
# Rolling (the 2011 model): the contact point (x, y) and the angular momentum about it v (3).
# Sliding (the contact point slips): (x, y), the centre's velocity (3, world), omega (3, world) and the
# energy dissipated by friction D (J). Either motion is followed by the orientation: u (3, the
# Munthe-Kaas increment; the adaptive pairs carry omega there while rolling and nothing while
# sliding, where omega is part of the motion) or R (9, the classic scheme). A ball that loses energy
# to rolling resistance, spin friction or air (docs/design.md §1, "Dissipation") carries after the
# orientation the energy each of the three has taken in this run (J, QUADRATURES: quadratures of the
# motion, outside the error norm). The state's length tells the kernel which dynamics to use.
MOTION_SIZE, MK_SIZE, CLASSIC_SIZE = 5, 8, 14            # rolling: motion only, + u (3), + R (9)
SLIDING_MOTION_SIZE, SLIDING_MK_SIZE, SLIDING_CLASSIC_SIZE = 9, 12, 18   # sliding: the same
SLIDING_SIZES = (SLIDING_MOTION_SIZE, SLIDING_MK_SIZE, SLIDING_CLASSIC_SIZE)
QUADRATURES = 3   # the energy to rolling resistance, spin friction and air, after the orientation
RESISTED_MK_SIZE, RESISTED_CLASSIC_SIZE = MK_SIZE + QUADRATURES, CLASSIC_SIZE + QUADRATURES   # 11, 17
SLIDING_RESISTED_MK_SIZE = SLIDING_MK_SIZE + QUADRATURES             # 15
SLIDING_RESISTED_CLASSIC_SIZE = SLIDING_CLASSIC_SIZE + QUADRATURES   # 21
# where the sliding state keeps what
S_VELOCITY, S_OMEGA, S_DISSIPATED = 2, 5, 8


def state_size(munthe_kaas: bool, sliding: bool = False, resisted: bool = False) -> int:
    """The state's length: Munthe-Kaas or classic, rolling or sliding, with the quadratures of
    the dissipation (``resisted``) or without."""
    if sliding:
        n = SLIDING_MK_SIZE if munthe_kaas else SLIDING_CLASSIC_SIZE
    else:
        n = MK_SIZE if munthe_kaas else CLASSIC_SIZE
    return n + QUADRATURES if resisted else n


P_TURN = 7  # p[P_TURN] > 0: omega is carried instead of u, R follows it to this tolerance (rad)
P_MU = 8    # the friction coefficient mu; inf: always enough friction to roll (the 2011 model)
P_FLY = 9   # 1: the run stops at a lift-off (the ball flies); 0: it goes on glued to the surface
P_DISSIPATED = 10  # the energy dissipated before this run (J): what rolling rows record
P_STIFF = 11  # 1: a fixed-step run's steps whose slip or rolling omega_t is stiff are the stiff pair's; 0: steps on
P_RESISTANCE = 12  # the rolling resistance c_rr (a couple -c_rr r F_n along omega's tangential part)
P_SPIN = 13        # the spin friction mu_s (a couple -mu_s r F_n along omega's normal part)
P_AIR = 14         # the air's drag factor k (kg/m): a force -k |c'| c' on the centre
P_CAUSES = 15      # the energy rolling resistance, spin friction and air took before this run (3, J)
P_UNIT = 18        # the ball's time unit sqrt(r / |g0|) (s; inf without gravity)
P_SIZE = 19


def parameters(radius: float, mass: float, gravity: float, turn: float = 0.0, friction: float | None = None,
               fly: bool = False, dissipated: float = 0.0, stiff: bool = False, rolling_resistance: float = 0.0,
               spin_friction: float = 0.0, air: float = 0.0, causes=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The ball and gravity as the kernel reads them, with the constants it would otherwise
    recompute at every evaluation: r, m, g0, 5/(7 m r^2), m r, m r^2, m g0; then ``turn``:
    0 for the Munthe-Kaas increment u in the state, else the tolerance (rad) for the
    orientation's sub-steps when omega is carried instead (``turn``: the adaptive pairs);
    then the contact: ``friction`` mu (None: always enough to roll, the 2011 model: no slip is
    ever looked for), ``fly`` (stop the run at a lift-off instead of going on glued), the
    energy ``dissipated`` before this run (J, carried into its rows) and ``stiff`` (a fixed-step
    run's steps where its slip, or its rolling omega_t against rolling resistance, is stiff are
    taken by the stiff pair, ``advance``'s S; a classic run stops before them, T_STIFF, for the
    caller to take that stretch; without it the run steps on with the direction at the step's
    start); then the dissipation
    (docs/design.md §1, "Dissipation"): ``rolling_resistance`` c_rr, ``spin_friction`` mu_s, ``air``
    the drag factor k (kg/m) and the energy each of the three took before this run (``causes``, J,
    which is part of ``dissipated``). A run whose state carries the quadratures (``state_size``,
    ``resisted``) feels them; any other leaves them unread. Last the ball's time unit sqrt(r / |g0|)
    (inf without gravity), which the stiffness bounds and the couples' zero are measured in."""
    r, m, g0 = radius, mass, gravity
    mu = np.inf if friction is None else friction
    # (one run's are floats: checked and packed without numpy's per-call cost, the same numbers)
    floats = all(isinstance(value, float | int) for value in (r, m, g0, turn, mu, dissipated, rolling_resistance,
                                                                spin_friction, air))
    for name, value in (("rolling_resistance", rolling_resistance), ("spin_friction", spin_friction), ("air", air)):
        if not (value >= 0.0 if floats else np.all(np.asarray(value) >= 0.0)):
            raise ValueError(f"{name} must be a number >= 0, not {value!r}")
    if len(causes) != QUADRATURES:
        raise ValueError(f"causes holds the energy to rolling resistance, spin friction and air (3), not {causes!r}")
    if floats:
        r, m, g0 = float(r), float(m), float(g0)
        unit = math.sqrt(r / abs(g0)) if g0 != 0.0 else math.inf
        return np.array([r, m, g0, 5.0 / (7.0 * m * r * r), m * r, m * r * r, m * g0, turn, mu, 1.0 if fly else 0.0,
                         dissipated, 1.0 if stiff else 0.0, rolling_resistance, spin_friction, air,
                         *(float(c) for c in causes), unit], dtype=float)
    zero = 0.0 * r   # (+ 0 r: a column like the others where r is an array, sweeps)
    with np.errstate(divide="ignore"):
        unit = np.sqrt(np.divide(r, np.abs(g0)))
    return np.array([r, m, g0, 5.0 / (7.0 * m * r * r), m * r, m * r * r, m * g0, turn + zero, mu + zero,
                     (1.0 if fly else 0.0) + zero, dissipated + zero, (1.0 if stiff else 0.0) + zero,
                     rolling_resistance + zero, spin_friction + zero, air + zero,
                     *(float(c) + zero for c in causes), unit + zero])


# How a method steps (``take_step``). Floats: numba compiles a function anew for every
# constant bool or int passed to it.
EXPLICIT, IMPLICIT = 0.0, 1.0

# What one evaluation learns about a state besides its derivative ("probe").
PROBE_N = 0        # unit normal N (3)
PROBE_OMEGA = 3    # angular velocity omega (3)
PROBE_FORCE = 6    # normal force F.N
PROBE_FIT = 7      # r * largest principal curvature (the ball fits while < 1)
PROBE_HEIGHT = 8   # f(x, y)
PROBE_FIT_LO = 9   # r * smallest principal curvature (< 0 where the surface bends away)
PROBE_NEED = 10    # |F_t|: the tangential force rolling needs (with this omega; 0 while mu is inf)
PROBE_SLIP = 11    # the slip velocity of the ball's material point at the contact (3; rolling: 0)
PROBE_SPIN_PULL = 14   # the pull on omega.N, times (2/5) m r² (its rate without spin friction; rolling: v.N's; else 0)
PROBE_SLIP_PULL = 15   # a sliding ball's B, the slip's acceleration with friction off, tangential (3; rolling: 0)
PROBE_SIZE = 18

# Integer run counters (``ints``) and float run facts (``info``).
# I_DENSE: the step whose extra dense-output stages K holds (they are computed on demand).
# I_HELD: 1 once a stopped step's last valid state is already in zn, Rn, pn (``fold_search``).
# I_RETRY: 1 while the adaptive step follows a rejection (kept between calls).
# I_TRANSITION: the kind of a transition the run stopped at (TRANSITIONS: its position + 1; 0 none).
(I_STEPS, I_ROWS, I_LAST_RECORDED, I_STATUS, I_REJECTED, I_NONFINITE, I_EVALS, I_REASON, I_DENSE, I_HELD,
 I_RETRY, I_TRANSITION) = range(12)
# F_LIFTOFF first time F.N < 0 (located on the dense output), at (F_LIFT_X, F_LIFT_Y);
# F_LIFT_KINK 1 where it is a convex kink of the surface rather than F.N crossing 0.
# Where the ball flies, LIFT_TIP there: the contact point reached a convex tip (a point where the normal
# turns through a finite angle, the tip of a cone), and the run stopped at the last state before it.
LIFT_TIP = 2.0
# F_FOLD: when the last step's ends say the contact point reaches the edge of the no-fit region.
# F_ERR_OLD: the adaptive step-size control's error of the last accepted step (PI control).
# F_EVENT_T, F_EVENT_X, F_EVENT_Y: the time and contact point of the transition the run stopped at.
# F_RATE_FORCE, F_RATE_SLIP: how fast the lift-off and slip conditions (-F.N, |F_t| - mu F.N) changed
# over the last step (per s; nan before the first), for seeing a change that begins and ends inside
# a step (``events.dipping``).
(F_LIFTOFF, F_LIFT_X, F_LIFT_Y, F_LIFT_KINK, F_FAIL_T, F_FAIL_X, F_FAIL_Y, F_FAIL_VALUE, F_TIME, F_H, F_FOLD,
 F_ERR_OLD, F_EVENT_T, F_EVENT_X, F_EVENT_Y, F_RATE_FORCE, F_RATE_SLIP) = range(17)
INTS_SIZE, INFO_SIZE = 12, 17

# -- recorded rows: the CSV columns of docs/design.md §5 ------------------------------------------

# (slip_speed: the speed of the ball's material point at the contact, 0 rolling; dissipated: the
# energy lost to friction and impacts so far, J; energy is kinetic + potential, without it)
# dissipated_rolling, _spin, _air: the part of it rolling resistance, spin friction and air took)
ROW_FIELDS = (("t", 1), ("contact", 2), ("center", 3), ("velocity", 3), ("omega", 3), ("R", 9), ("energy", 1),
              ("normal_force", 1), ("slip_speed", 1), ("dissipated", 1), ("dissipated_rolling", 1),
              ("dissipated_spin", 1), ("dissipated_air", 1))
ROW_SLICES = {}   # field -> its slice of a row
for _name, _width in ROW_FIELDS:
    _start = sum(c.stop - c.start for c in ROW_SLICES.values())
    ROW_SLICES[_name] = slice(_start, _start + _width)
del _name, _width, _start
ROW_SIZE = sum(width for _, width in ROW_FIELDS)
(ROW_T, ROW_CONTACT, ROW_CENTER, ROW_VELOCITY, ROW_OMEGA, ROW_R, ROW_ENERGY, ROW_FORCE, ROW_SLIP,
 ROW_DISSIPATED, ROW_ROLLING, ROW_SPIN, ROW_AIR) = (ROW_SLICES[name].start for name, _ in ROW_FIELDS)

# -- how a run ended ------------------------------------------------------------------------------

# Statuses (``trajectory.Status``): the kernel's codes are their positions in KERNEL_STATUSES
# (ints[I_STATUS]); the others are set by Python.
STATUSES = {
    "running": "still running (the kernel's code while a run goes on)",
    "ok": "reached its end time",
    "does_not_fit": "the ball no longer fits a valley: the model breaks down",
    "nonfinite": "the landscape or the state could not be evaluated",
    "transition": "stopped where the contact changes mode (a lift-off, a slip or a grip): the run goes on in the "
                  "new mode from the state there",
    "aborted": "the caller cancelled",
    "row_limit": "recording every step filled the row limit before the end",
}
KERNEL_STATUSES = ("running", "ok", "does_not_fit", "nonfinite", "transition")
RUNNING, OK, DOES_NOT_FIT, NONFINITE, TRANSITION = range(len(KERNEL_STATUSES))

# The changes of contact mode a run stops at (status "transition"): the kind's code in
# ints[I_TRANSITION] is its position here plus 1, its time and contact point are info[F_EVENT_T],
# info[F_EVENT_X], info[F_EVENT_Y], and the run's last row and z, R, probe hold the state there,
# located to the method's own accuracy (``events.refine_transition``). Each with the mode the ball
# goes on in and the sentence made from the event's fields.
TRANSITIONS = {
    "liftoff": ("flying", "the ball leaves the surface at {where}: the normal force F·N reaches 0"),
    "slip": ("sliding", "the ball starts to slip at {where}: rolling would need a friction force beyond μ F·N"),
    "grip": ("rolling", "the slip ends at {where}: the ball rolls on"),
    "rest": ("resting", "the ball comes to rest at {where}"),
}
T_NONE = 0
T_LIFTOFF, T_SLIP, T_GRIP, T_REST = range(1, len(TRANSITIONS) + 1)
# Not a change of mode: a fixed-step run stops before a step that starts where the slip's direction
# is stiff (friction would stop the slip within the step, ``loops.slip_reference``), or a rolling
# ball's omega_t's (rolling resistance would stop it within the step, ``loops.turn_stiff``); the
# run in Python takes that stretch with an adaptive pair (``mode_machine``, docs/design.md §8).
T_STIFF = len(TRANSITIONS) + 1
# Inside the kernel only: a couple's side turns (the spin omega.N reaches 0, or a sliding ball's
# omega_t does): the run holds the state there and goes on from it (``loops.resume``).
T_SIDE = len(TRANSITIONS) + 2


def transition_name(code: int) -> str | None:
    """The transition with this code (ints[I_TRANSITION]), or None."""
    return list(TRANSITIONS)[code - 1] if 1 <= code <= len(TRANSITIONS) else None


def transition_sentence(kind: str, time: float, x: float, y: float) -> str:
    """The sentence for a transition, made from its fields."""
    return TRANSITIONS[kind][1].format(where=f"t = {time:.6g} s, (x, y) = ({x:.6g}, {y:.6g})")


# Why the physics stopped a run (``trajectory.Reason``, ``Failure``): its code in ints[I_REASON]
# is its position here plus 1 (0: none), with the status it gives, what info[F_FAIL_VALUE]
# holds and the sentence made from the failure's fields ({where}: its time and contact point;
# two sentences where the value tells two cases apart: value 1, and any other).
_DOES_NOT_FIT = "the ball (r = {radius:g} m) does not fit the surface at {where}: "
REASONS = {
    "no_fit": ("does_not_fit", "r·κ for a principal curvature κ at the end of a step",
               _DOES_NOT_FIT + "r·κ = {value:.4g} ≥ 1 for a principal curvature κ, so the model cannot go on"),
    "secant_no_fit": ("does_not_fit", "r times the secant curvature of a step",
                      _DOES_NOT_FIT + "the step across it bends like r·κ = {value:.4g} ≥ 1, so the model cannot "
                                      "go on"),
    "start_undefined": ("nonfinite", "nothing",
                        "the landscape cannot be evaluated at the start point (x, y) = ({x:.6g}, {y:.6g})"),
    "start_overflow": ("nonfinite", "nothing",
                       "the initial state overflows double precision (energy, angular momentum or angular velocity "
                       "not finite): the start speed or spin, or the ball's radius or mass, is too large"),
    "undefined": ("nonfinite", "nothing",
                  "the state became non-finite at {where}: the landscape cannot be evaluated there (outside its "
                  "domain or at a pole) or the step is too large"),
    "orientation_overflow": ("nonfinite", "1 for the classic update, 0 for Munthe-Kaas",
                             ("the orientation R overflowed at {where}: the classic matrix update has left SO(3) "
                              "far behind (Munthe-Kaas keeps R a rotation)",
                              "the rotation of one step overflowed at {where}: the ball spins too fast for the step")),
    "step_underflow": ("nonfinite", "the step (s)",
                       "the adaptive step size fell to {value:.3g} s, below round-off, at {where}: the equations "
                       "are (nearly) singular there"),
    "kink": ("does_not_fit", "the angle the normal turns there (rad)",
             _DOES_NOT_FIT + "a kink or cusp of a valley, where the normal turns by {value:.3g} rad at once, so the "
                             "model cannot go on"),
    "height_jump": ("does_not_fit", "the jump (m)",
                    "the landscape jumps in height by {value:.4g} m at {where} (it is not continuous there), so the "
                    "rolling ball cannot go on"),
    "not_converged": ("nonfinite", "the step (s)",
                      "the implicit stage equations did not converge at {where}: the step dt = {value:.3g} s is too "
                      "large for this motion; use a smaller dt"),
    "tip": ("does_not_fit", "the angle the normal turns there (rad)",
            "the ball reaches a point of the surface at {where} where the normal turns by {value:.3g} rad at once "
            "(the tip of a cone, or a like point): a real ball leaves the surface there (the lift-off), and the "
            "model cannot step across it"),
    "pivot": ("does_not_fit", "the normal force the ball would need there (N)",
              "the ball reaches a point of the surface at {where} where the normal turns at once (the tip of a "
              "cone, or a like point) too slowly to leave it, sliding (or where the tip's faces cannot be found): a "
              "real ball would turn about it with F·N = {value:.3g} N, rubbing on it, which the model does not "
              "follow"),
}
R_NONE = 0
(R_NO_FIT, R_SECANT_NO_FIT, R_START_UNDEFINED, R_START_OVERFLOW, R_UNDEFINED, R_ORIENTATION, R_STEP_UNDERFLOW,
 R_KINK, R_HEIGHT_JUMP, R_NOT_CONVERGED, R_TIP, R_PIVOT) = range(1, len(REASONS) + 1)


def reason_name(code: int) -> str | None:
    """The reason with this code (ints[I_REASON]), or None."""
    return list(REASONS)[code - 1] if 1 <= code <= len(REASONS) else None


def sentence(reason: str, value: float, time: float, x: float, y: float, radius: float) -> str:
    """The sentence for a failure, made from its fields."""
    template = REASONS[reason][2]
    if isinstance(template, tuple):
        template = template[0] if value == 1.0 else template[1]
    where = f"t = {time:.6g} s, (x, y) = ({x:.6g}, {y:.6g})"
    return template.format(where=where, value=value, x=x, y=y, radius=radius)


# -- the arrays of a run ----------------------------------------------------------------------------

SURFACE_SIZE = 8   # x, y, f, N (3), r * largest and smallest principal curvature
# The scratch array's parts, in order (``loops.scratch`` views them): landscape values d (then,
# from D_SLIP, the slip velocity at the step's start, which a sliding ball's friction keeps its side
# of through the step, and at D_SLIP + 3 the slip speed below which its direction is stiff,
# ``sliding_dynamics``), stage state Y, trial state zn, probe pn and
# orientation Rn, and for the dense output a state Ye, orientation Re, probe pe and three surface
# points. "n": the state's size; (3, 3) a matrix.
# From D_SIDE: omega's tangential part at the step's start (3), whose side the rolling resistance
# keeps through the step, and the sign of omega.N there, the spin friction's (``couple_reference``;
# zeros where the couple is static at the step's start).
D_SLIP = LANDSCAPE_OUTPUTS
D_SIDE = D_SLIP + 4
SCRATCH = (("d", D_SIDE + 4), ("Y", "n"), ("zn", "n"), ("pn", PROBE_SIZE), ("Rn", (3, 3)), ("Ye", "n"), ("Re", (3, 3)),
           ("pe", PROBE_SIZE), ("sa", SURFACE_SIZE), ("sb", SURFACE_SIZE), ("sm", SURFACE_SIZE))


def work_size(n: int) -> int:
    """Length of the scratch array the stepping loops need for a state of size n."""
    return sum(n if size == "n" else 9 if size == (3, 3) else size for _, size in SCRATCH)


def stage_rows(stages: int) -> int:
    """The rows of K for a method whose W has ``stages`` rows: those, omega's polynomial
    (three rows, ``omega_polynomial``) and a spare last row for evaluations on the dense output."""
    return stages + 4


def run_arrays(n: int, stages: int, rows: int) -> dict[str, np.ndarray]:
    """The arrays of one run (RUN_ARRAYS) for a state of size n, a method whose W has ``stages``
    rows, and ``rows`` rows to record: z zero, R the identity, info not-a-number."""
    info = np.full(INFO_SIZE, np.nan)
    return {"z": np.zeros(n), "R": np.eye(3), "K": np.zeros((stage_rows(stages), n)), "probe": np.zeros(PROBE_SIZE),
            "rows": np.empty((rows, ROW_SIZE)), "ints": np.zeros(INTS_SIZE, dtype=np.int64), "info": info,
            "work": np.empty(work_size(n))}


# -- the run's clock --------------------------------------------------------------------------------

MIN_STEP = 1e-13     # adaptive steps below this (relative to t, or absolute below t = 1) stop the run
# The orientation's tolerance per step (p[P_TURN], ``dense.turn``), as a share of rtol: the pairs'
# steps, taken on by the higher-order solution, are far more accurate than their estimate (rtol) says.
TURN_SHARE = 1e-2
GRID_SLIVER = 1e-9   # a run's first step or row closer than this many dt (or record_dt) to t_start joins the next


def grid_steps_before(t_start: float, spacing: float) -> int:
    """The grid times k·spacing (k = 1, 2, ...) a run starting at t_start has passed: its first step
    ends at (k + 1)·dt, its first row after the start is at (k + 1)·record_dt. A grid time less than
    GRID_SLIVER·spacing after t_start counts as passed: the first step takes that sliver with it.
    0 for t_start = 0. (Plain Python that the kernel compiles too: one definition for both.)"""
    k = math.floor(t_start / spacing)
    if (k + 1) * spacing - t_start < GRID_SLIVER * spacing:
        k += 1
    return k


# -- sweeps: batches of fixed-step runs ----------------------------------------------------------
#
# A run of a sweep needs only the motion (contact point and angular momentum): its state has
# MOTION_SIZE entries. Each run is stepped by ``advance`` itself, so a sweep's runs end exactly
# where ``simulate`` ends the same scene, every step recorded into a buffer of BATCH_CHUNK rows
# that is folded into the run's outcomes and reused: memory does not grow with the steps.

#
# A run that flies (p[P_FLY] 1) whose contact only rolls (mu inf) and flies in vacuum goes on in the
# batch loop as the mode machine goes on (``kernel.batch``): from a lift-off in the tangent plane,
# the flights of ``bounces.bounces`` (BOUNCE[b]: the restitution and the slowest rebound that
# flies), then rolling again from where the ball settles. A run whose mu is finite (in vacuum, no
# couple that can stop it) is a Munthe-Kaas one (MK_SIZE, SLIDING_MK_SIZE while it slides) and
# goes on from a slip sliding and from a grip rolling, its stiff stretches the stiff pair's, and
# from a landing whose friction did not stop the contact point sliding, as the mode machine goes on.
# Where the mode machine would do more than that (a kink's or a tip's lift-off, a flight the search
# refers, changes at one time, a stop, a failure), the loop stops the run with the status REFERRED:
# Python runs it through ``Simulation``.

NOT_RUN = 11                  # a run of a batch not run yet (sweeps also mark refused runs, 10)
REFERRED = 12                 # a run of a batch left to the mode machine (``Simulation``)
BATCH_CHUNK = 256             # steps folded into a run's outcomes at a time
BATCH_ROWS = BATCH_CHUNK + 2  # the buffer: the last row folded, a chunk, a stop's row
# acc, a run's accumulators over its rows (``batch.fold_rows``): the first row's E + D, the largest
# and smallest E + D, min F.N, max speed, path length, the last row's time, contact (2) and centre
# (3), the rows folded, 1 where the last row flies
(A_FIRST, A_HIGH, A_LOW, A_FORCE, A_SPEED, A_PATH, A_T, A_CONTACT, A_CENTER, A_ROWS, A_FLYING,
 BATCH_ACCUMULATORS) = 0, 1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 14
# One row of outcomes per run, in this order.
OUTCOMES = ("t_reached", "liftoff_time", "x_end", "y_end", "energy_drift", "min_normal_force",
            "max_speed", "path_length")
O_T, O_LIFTOFF, O_X, O_Y, O_DRIFT, O_MIN_FORCE, O_MAX_SPEED, O_PATH = range(len(OUTCOMES))
# The batch loop's out has five columns more: the landings, 1 where the run ends in flight, the
# first slip's and the first grip's time (NaN: none) and 1 where the run ends sliding.
O_LANDINGS, O_FLIES, O_FIRST_SLIP, O_FIRST_GRIP, O_SLIDES = range(len(OUTCOMES), len(OUTCOMES) + 5)
BATCH_OUT = len(OUTCOMES) + 5
# The liftoff's contact point is looked at on a ring of this radius (× (1 + |x| + |y|)) as the
# mode machine looks for a tip there; unit normals on it this far apart leave the run to it.
TIP_RING, TIP_SUSPECT = 1e-6, 5e-3


def description() -> dict:
    """The interface as kernel.json records it: the version and each entry's arguments."""
    return {"version": VERSION, "slots": ENTRY_SLOTS,
            "landscape": [f"{parameter} {kind}" for parameter, kind in LANDSCAPE_ARGUMENTS],
            "entries": {name: [f"{parameter} {kind}" for parameter, kind in arguments]
                        for name, arguments in ENTRIES.items()}}


__all__ = [name for name in dir() if not name.startswith("_") and name not in ("annotations", "math", "np")]
