"""The core stays a plain library: no Qt, no app, importable on a machine without a display."""

import subprocess
import sys
from pathlib import Path

import pytest

import rollball


def test_core_imports_no_gui():
    code = ("import sys, rollball, rollball.cli, rollball.reference; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'PyQt5', 'PyQt6', 'pyqtgraph', "
            "'superqt', 'app', 'rollball_app')]; print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr


def test_core_sources_do_not_mention_gui_modules():
    for path in Path(rollball.__file__).parent.glob("*.py"):
        for line in path.read_text(encoding="utf-8").splitlines():
            words = line.split()
            if words[:1] in (["import"], ["from"]):
                assert words[1].split(".")[0] not in ("PySide6", "pyqtgraph", "superqt", "app",
                                                            "rollball_app"), (path, line)


def test_the_app_starts_as_installed_and_from_a_checkout():
    """The app's folder app/ is installed as rollball_app; ``python -m rollball_app`` works from
    any folder and ``python -m app`` from the checkout's root."""
    root = Path(__file__).resolve().parent.parent
    for module, cwd in (("rollball_app", Path(__file__).parent), ("app", root)):
        result = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True, text=True,
                                timeout=120, cwd=cwd)
        assert result.returncode == 0 and "rollball-app" in result.stdout, (module, result.stderr)


def test_the_tests_import_the_app_by_its_installed_name():
    """A local app/ folder is the installed rollball_app only in a checkout: tests, scripts and the
    core import rollball_app, so they test what is installed."""
    root = Path(__file__).resolve().parent.parent
    for path in [*root.joinpath("tests").rglob("*.py"), *root.joinpath("scripts").glob("*.py")]:
        for line in path.read_text(encoding="utf-8").splitlines():
            words = line.split()
            if words[:1] in (["import"], ["from"]) and len(words) > 1:
                assert words[1].split(".")[0] != "app", (path, line)


# The distribution that brings each module a package imports (pyproject.toml's names).
DISTRIBUTIONS = {"numpy": "numpy", "numba": "numba", "llvmlite": "llvmlite", "sympy": "sympy",
                 "matplotlib": "matplotlib", "tqdm": "tqdm", "scipy": "scipy", "PySide6": "PySide6-Essentials",
                 "pyqtgraph": "pyqtgraph", "OpenGL": "PyOpenGL", "imageio": "imageio",
                 "imageio_ffmpeg": "imageio-ffmpeg"}


def _declared(*groups: str) -> set[str]:
    """The distributions pyproject.toml declares: the core's, and the named extras'."""
    import re
    tomllib = pytest.importorskip("tomllib")   # (Python 3.11 and newer)
    project = tomllib.loads((Path(__file__).resolve().parent.parent / "pyproject.toml").read_text())["project"]
    lists = [project["dependencies"]] + [project["optional-dependencies"][group] for group in groups]
    return {re.split(r"[\[<>=!~; ]", item, maxsplit=1)[0] for items in lists for item in items}


def _imported_at_load(folder: Path, leave_out=()) -> dict[str, Path]:
    """Top-level third-party modules the files of ``folder`` import when they are loaded (a
    module imported inside a function, for an optional extra, is not counted)."""
    import ast
    found = {}
    for path in folder.rglob("*.py"):
        if any(part in leave_out for part in path.relative_to(folder).parts):
            continue
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else [])
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top not in ("rollball", "rollball_app", "app"):
                    found.setdefault(top, path)
    return found


def test_what_the_core_and_the_app_import_is_what_they_declare():
    """`scripts/run` installs the core and the app's extra only: a module they import on loading
    that only the test or bench extras bring would fail for a new user (a flight's scipy did)."""
    root = Path(__file__).resolve().parent.parent
    for folder, groups, leave_out in ((root / "rollball", (), ("bench",)), (root / "app", ("app",), ())):
        declared = _declared(*groups)
        missing = {module: str(path) for module, path in _imported_at_load(folder, leave_out).items()
                   if DISTRIBUTIONS.get(module, module) not in declared}
        assert missing == {}, (folder.name, missing)
