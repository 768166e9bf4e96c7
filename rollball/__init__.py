"""RollBall: a solid ball rolling, sliding and flying over a landscape z = f(x, y).

The public names below are imported when first used (PEP 562), not with the package: ``import
rollball.cli`` stays cheap, so ``rollball --help`` and a refused argument answer at once, and
sympy, numba and scipy are loaded only by the commands that run something.
"""

__version__ = "0.2.0"

from .cache import guard_numba_cache  # noqa: E402

guard_numba_cache()   # before numba is imported: its cache folder must be ours alone too

from .lazy import lazy_names  # noqa: E402

# Each public name and the module (below this package) that defines it.
_LAZY = {
    "FormulaError": "formula", "parse_formula": "formula",
    "Landscape": "landscape",
    "Scene": "scene", "SceneError": "scene",
    "Simulation": "simulation", "simulate": "simulation",
    "SweepTable": "sweeps", "sweep": "sweeps",
    "METHODS": "tableaus", "TABLEAUS": "tableaus", "Method": "tableaus", "MethodKind": "tableaus",
    "Tableau": "tableaus", "get_method": "tableaus",
    "COLUMNS": "trajectory", "Failure": "trajectory", "Reason": "trajectory", "Status": "trajectory",
    "Trajectory": "trajectory", "read_csv": "trajectory",
    "Track": "track", "TrackError": "track", "Residuals": "track_check", "residuals": "track_check",
    "Fit": "fitting", "FitError": "fitting", "fit": "fitting",
    "Comparison": "comparison", "compare": "comparison",
    "RunSpec": "run_specs", "parse_runs": "run_specs",
}

__all__ = sorted(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY)
