"""The core stays a plain library: no Qt, no app, importable on a machine without a display."""

import subprocess
import sys
from pathlib import Path

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
