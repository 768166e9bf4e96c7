"""RollBall: a solid ball rolling without slipping over a landscape z = f(x, y)."""

__version__ = "0.2.0"

from .cache import guard_numba_cache  # noqa: E402

guard_numba_cache()   # before numba is imported: its cache folder must be ours alone too

from .formula import FormulaError, parse_formula  # noqa: E402
from .landscape import Landscape  # noqa: E402
from .scene import Scene, SceneError  # noqa: E402
from .simulation import Simulation, simulate  # noqa: E402
from .sweeps import SweepTable, sweep  # noqa: E402
from .tableaus import METHODS, TABLEAUS, Method, MethodKind, Tableau, get_method  # noqa: E402
from .trajectory import COLUMNS, Failure, Reason, Status, Trajectory, read_csv  # noqa: E402
from .comparison import Comparison, RunSpec, compare, parse_runs  # noqa: E402

__all__ = ["COLUMNS", "Comparison", "Failure", "FormulaError", "Landscape", "METHODS", "Method", "MethodKind",
           "Reason", "RunSpec", "Scene", "SceneError", "Simulation", "Status", "SweepTable", "TABLEAUS", "Tableau",
           "Trajectory", "compare", "get_method", "parse_formula", "parse_runs", "read_csv", "simulate", "sweep"]
