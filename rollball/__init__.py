"""RollBall: a solid ball rolling without slipping over a landscape z = f(x, y)."""

__version__ = "0.1.0"

from .formula import FormulaError, parse_formula  # noqa: E402
from .landscape import Landscape  # noqa: E402
from .scene import Scene, SceneError  # noqa: E402
from .simulation import Simulation, simulate  # noqa: E402
from .tableaus import METHODS, TABLEAUS, Tableau, get_tableau  # noqa: E402
from .trajectory import COLUMNS, Status, Trajectory, read_csv  # noqa: E402
from .comparison import Comparison, RunSpec, compare, parse_runs  # noqa: E402

__all__ = ["COLUMNS", "Comparison", "FormulaError", "Landscape", "METHODS", "RunSpec", "Scene", "SceneError",
           "Simulation", "Status", "TABLEAUS", "Tableau", "Trajectory", "compare", "get_tableau", "parse_formula",
           "parse_runs", "read_csv", "simulate"]
