"""The compiled stepping kernel: the reduced equations of motion, one Runge–Kutta stage loop
for every tableau (classic and Munthe-Kaas), fixed or adaptive steps, validity checks and
recording.

Everything here is landscape-independent and compiled once; the landscape arrives as the
address of its record: the address of its compiled code ``f(x, y, parameters, out)``, then
its parameters' values (``interface.LANDSCAPE_ARGUMENTS``); the code writes f and its first and
second derivatives to out[0:6] (``lowlevel.landscape`` calls it). Python calls the kernel only through its entry points
(``entries.ENTRIES``), whose arguments, rows, codes and arrays ``interface`` declares;
machine_code.py makes them into machine code: from the LLVM code shipped with RollBall where
it fits this machine, else compiled here by numba (and kept on disk).

State vector z: contact point (x, y), angular momentum about the contact point v (3),
then either u (3, the Munthe-Kaas Lie-algebra increment, zero at each step start; the
adaptive pairs carry omega there instead and R follows it, ``dense.turn``) or
R (9, row-major, integrated as a plain matrix by the classic scheme), or nothing: a state
of MOTION_SIZE carries no orientation at all (sweeps, whose outcomes do not need it). A sliding
ball's state is (x, y), the centre velocity (3), omega (3) and the energy dissipated, then the
same orientation parts (``interface``: its length tells which). Stage derivatives
are the rows of K; the hot loop indexes whole arrays and never slices them.

The modules, from the bottom layer up (each imports only those before it): ``interface`` (data),
``lowlevel`` (compile options, intrinsics), ``physics`` (landscape, dynamics, dexp⁻¹, curvatures,
Rodrigues), ``dense`` (interpolation, omega's polynomial, the turn of R), ``recording`` (rows, the
start, failures), ``explicit`` and ``collocation`` (the steps), ``steps`` (choosing a step, error
norm, acceptance), ``bounds`` (the landscape's bounds over a box, from its tape), ``feet`` (a flying
ball's closest surface points), ``landing``, ``flight_rows`` and ``bounces`` (a flight's landing
search, its rows, its impact and, in vacuum, flight after flight), ``events`` (locating lift-off,
breaks, the fold, the changes of contact mode), ``unpacking`` (slots and scratch, generated),
``loops`` (the stepping loops), ``batch`` (a sweep's batch of runs: rolling, and flying in
vacuum), ``entries`` (the entry points).
"""

# The names the rest of the core reads the kernel by (it imports rollball.kernel and
# rollball.kernel.interface only: pyproject.toml's import contracts), re-exported here. The
# interface's names come with the package; the compiled modules' names (which import numba) only
# when first read: a process that runs the shipped machine code never imports them
# (machine_code.py).
import importlib

from .interface import *  # noqa: F401,F403  (the names Python reads the kernel's arrays by)

# name here: (module, its name there); ENTRY_POINTS are the entry points' functions by the names
# of interface.ENTRIES (ENTRIES here is the interface's declaration)
_COMPILED_NAMES = {"collocation_step": ("collocation", "collocation_step"),
                   "omega_polynomial": ("dense", "omega_polynomial"), "turn": ("dense", "turn"),
                   "ENTRY_POINTS": ("entries", "ENTRIES"), "ENTRY_SIGNATURE": ("entries", "ENTRY_SIGNATURE"),
                   "LANDSCAPE_SIGNATURE": ("lowlevel", "LANDSCAPE_SIGNATURE"),
                   "DEXPINV_SERIES": ("physics", "DEXPINV_SERIES"), "dexpinv": ("physics", "dexpinv"),
                   "dynamics": ("physics", "dynamics"), "rodrigues": ("physics", "rodrigues"),
                   "turning_point": ("physics", "turning_point")}


def __getattr__(name: str):
    if name not in _COMPILED_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, attribute = _COMPILED_NAMES[name]
    value = globals()[name] = getattr(importlib.import_module(f".{module}", __name__), attribute)
    return value
