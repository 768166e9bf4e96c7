"""RollBall: a solid ball rolling without slipping over a landscape z = f(x, y)."""

__version__ = "0.1.0"

from .formula import FormulaError, parse_formula  # noqa: E402
from .landscape import Landscape  # noqa: E402
from .scene import Scene, SceneError  # noqa: E402
from .simulation import Simulation, simulate  # noqa: E402
from .sweeps import SweepTable, sweep  # noqa: E402
from .tableaus import METHODS, TABLEAUS, Tableau, get_tableau  # noqa: E402
from .trajectory import COLUMNS, Status, Trajectory, read_csv  # noqa: E402

__all__ = ["COLUMNS", "FormulaError", "Landscape", "METHODS", "Scene", "SceneError", "Simulation",
           "Status", "SweepTable", "TABLEAUS", "Tableau", "Trajectory", "get_tableau", "parse_formula", "read_csv",
           "simulate", "sweep"]
