"""The front door answers at once: ``rollball --help``, a command's help and a refused argument
load none of the numerical modules (sympy, numba, scipy, ...) that a run needs, and neither does
``rollball-app`` refusing its arguments, which also loads no Qt. CPU time is measured (not wall
time, which a busy machine stretches); the bounds are many times what they take."""

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
HEAVY = {"numpy", "sympy", "numba", "llvmlite", "scipy", "matplotlib", "tqdm"}
QT = {"PySide6", "pyqtgraph", "OpenGL"}
CPU_BOUND = 1.0   # seconds; about 0.06 s on a 2020s core (a run's imports take 1 to 4 s)


def _run(args: list[str], **kwargs) -> tuple[subprocess.CompletedProcess, float]:
    """The finished process and the CPU time (user + system) it used."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    result = subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=120, cwd=ROOT,
                            **kwargs)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return result, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _imported(args: list[str]) -> tuple[set[str], list[str]]:
    """The top-level modules ``python -X importtime ARGS`` imports, and the other lines of its stderr."""
    result, _ = _run(["-X", "importtime", *args])
    modules, lines = set(), []
    for line in result.stderr.splitlines():
        if line.startswith("import time:"):
            modules.add(line.rpartition("|")[2].strip().split(".")[0])
        else:
            lines.append(line)
    return modules, lines


def test_the_command_line_module_loads_nothing_numerical():
    modules, _ = _imported(["-c", "import rollball.cli"])
    assert "rollball" in modules and modules & (HEAVY | QT) == set()


@pytest.mark.parametrize("args, code", [
    (["--help"], 0),
    (["examples"], 0),
    (["simulate", "--help"], 0),
    (["sweep", "--help"], 0),
    (["fit", "--help"], 0),
    (["check", "--help"], 0),
    (["fit", "billiard", "billiard_track.csv", "--loss", "square", "--fit", "start.vx"], 2),
    (["simulate", "hills", "--dt", "-1"], 2),
    (["simulate", "hills", "--method", "rk45"], 2),
    (["simulate"], 2),
    (["no-such-command"], 2),
    (["compare", "hills", "--runs", "rk9"], 2),
    (["compare", "hills", "--runs", "dopri5/classic"], 2),
])
def test_help_and_refused_arguments_answer_at_once(args, code):
    result, cpu = _run(["-m", "rollball", *args])
    assert result.returncode == code, result.stderr
    if code:
        assert len(result.stderr.splitlines()) == 1 and "Traceback" not in result.stderr, result.stderr
    assert cpu < CPU_BOUND
    modules, _ = _imported(["-m", "rollball", *args])
    assert modules & (HEAVY | QT) == set()


@pytest.mark.parametrize("args", [
    ["--bad"],
    ["hills", "--run-to", "1"],
    ["--record", "out.avi"],
    ["--record", "out.mp4", "--fps", "500"],
    ["--screenshot", "out.png", "--size", "10x10"],
    ["--fps", "10"],
    ["--compare", "rk9"],
    ["--compare", "rk4/mk"],
    ["--compare", "dopri5/classic"],
    ["--compare", "euler,euler/classic,rk4,rk4/classic,lawson5,lawson5/classic,dopri5"],   # seven runs
])
def test_the_app_refuses_bad_arguments_in_a_line_before_loading_qt_or_the_core(args):
    result, cpu = _run(["-m", "rollball_app", *args])
    assert result.returncode == 2 and result.stdout == ""
    assert len(result.stderr.splitlines()) == 1 and result.stderr.startswith("rollball-app: error: "), result.stderr
    assert cpu < CPU_BOUND
    modules, lines = _imported(["-m", "rollball_app", *args])
    assert modules & (HEAVY | QT) == set() and lines == result.stderr.splitlines()


# A run of an example and of one that flies, lands and bounces; prints where the kernel's machine code
# came from, how the runs ended, and which of numba, its compiled kernel modules and scipy the process imported.
RUN = """
import sys
import rollball
from rollball import machine_code
from rollball.examples import scene_path
run = rollball.simulate(scene_path("hills"), t_end=0.5)
jump = rollball.simulate(scene_path("ridge_jump"))
heavy = {"numba", "scipy", "rollball.kernel.lowlevel", "rollball.kernel.entries"}
print(machine_code.source, run.status, jump.status, jump.landings,
      sorted(name for name in sys.modules if name in heavy))
"""


def test_a_run_on_the_shipped_machine_code_imports_no_compiler(tmp_path):
    """The shipped kernel made into machine code for this processor (first process), then that
    machine code loaded from the cache folder (second), and the landscape's code translated and
    then loaded: neither process imports numba or the kernel's compiled modules (they are for
    compiling only), nor scipy, not even for flights in vacuum and their landings (a flight's state
    turns R by ``geometry.rotation``: scipy's import added 1.3–1.4 s of CPU to the first liftoff run of a process)."""
    env = {key: value for key, value in os.environ.items() if key != "ROLLBALL_MACHINE_CODE"}
    env["ROLLBALL_CACHE_DIR"] = str(tmp_path)
    for _ in range(2):
        result, _ = _run(["-c", RUN], env=env)
        assert result.returncode == 0, result.stderr
        assert result.stdout.split() == ["shipped", "ok", "ok", "9", "[]"], result.stdout


# Runs the app as ``rollball-app ARGS`` where the module PACKAGE cannot be imported.
WITHOUT = """
import runpy, sys

BLOCKED = sys.argv[1]


class Missing:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] == BLOCKED:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)

sys.meta_path.insert(0, Missing())
sys.argv = ["rollball-app", *sys.argv[2:]]
runpy.run_module("rollball_app", run_name="__main__", alter_sys=True)
"""


@pytest.mark.parametrize("package", ["PySide6", "pyqtgraph"])
def test_the_app_without_its_packages_says_what_to_install(package, tmp_path):
    result, _ = _run(["-c", WITHOUT, package, "hills", "--screenshot", str(tmp_path / "out.png")])
    assert result.returncode == 2 and not (tmp_path / "out.png").exists()
    assert result.stderr.splitlines() == [
        f"rollball-app: error: the app needs {package}, which is not installed: pip install 'rollball[app]'"]
