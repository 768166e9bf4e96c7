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

The modules, from the bottom layer up (each imports only those before it): ``interface``
(data), ``lowlevel`` (compile options, intrinsics), ``physics`` (landscape, dynamics, dexp⁻¹,
curvatures, Rodrigues), ``dense`` (interpolation, omega's polynomial, the turn of R),
``recording`` (rows, the start, failures), ``explicit`` and ``collocation`` (the steps),
``steps`` (choosing a step, error norm, acceptance), ``feet`` (a flying ball's closest surface
points), ``events`` (locating lift-off, breaks, the fold, the changes of contact mode),
``unpacking`` (slots and scratch, generated), ``loops`` (the stepping loops), ``entries`` (the
entry points).
"""

# The names the rest of the core reads the kernel by (it imports rollball.kernel and
# rollball.kernel.interface only: pyproject.toml's import contracts), re-exported here
from .interface import *  # noqa: F401,F403  (the names Python reads the kernel's arrays by)
from .collocation import collocation_step  # noqa: F401
from .dense import TURN_SHARE, omega_polynomial, turn  # noqa: F401
from .entries import ENTRIES, ENTRY_SIGNATURE  # noqa: F401
from .lowlevel import LANDSCAPE_SIGNATURE  # noqa: F401
from .physics import DEXPINV_SERIES, dexpinv, dynamics, rodrigues  # noqa: F401
from .steps import MIN_STEP  # noqa: F401
