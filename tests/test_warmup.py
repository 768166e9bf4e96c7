"""Compiling ahead of need: every method is warmed, and a compile is announced once."""

import json
import os
import subprocess
import sys

from numba import njit

from rollball import METHODS, kernel
from rollball.warmup import compile_notice, variants, warm_up


def _fresh_function(module: str):
    def add_one(x):
        return x + 1.0
    add_one.__module__ = module
    return njit(add_one)   # a new dispatcher: calling it compiles


def test_every_method_is_warmed_with_each_orientation_update_it_allows():
    warmed = variants()
    assert {method for method, _ in warmed} == set(METHODS)
    assert ("rk4", False) in warmed and ("rk4", True) in warmed
    assert len(set(warmed)) == len(warmed)


def test_the_warm_up_reports_each_part_and_readies_sweeps_too():
    parts, ready = [], []
    warm_up(lambda done, total, text: parts.append((done, total, text)), [("lawson5", False)],
            lambda method, mk: ready.append((method, mk)))
    total = len(variants()) + 1
    assert parts[0] == (0, total, "lawson5 classic") and ready[0] == ("lawson5", False)
    assert parts[-2:] == [(total - 1, total, "sweeps"), (total, total, "done")]
    assert sorted(ready) == sorted(variants())
    assert kernel.advance_batch.signatures   # compiled, or loaded from the disk cache


def test_a_kernel_compile_is_announced_once_and_a_landscape_compile_not_at_all():
    said = []
    with compile_notice(lambda: said.append("compiling")):
        _fresh_function("rollball_landscape_0123")(1.0)
        assert said == []
        _fresh_function("rollball.kernel")(1.0)
        _fresh_function("rollball.kernel")(2.0)
    assert said == ["compiling"]
    _fresh_function("rollball.kernel")(3.0)   # outside the block: nothing more
    assert said == ["compiling"]


def test_an_unknown_run_to_warm_first_is_refused_in_one_line(capsys):
    from rollball.warmup import main

    assert main(["rk5"]) == 2
    err = capsys.readouterr().err.strip()
    assert "unknown run 'rk5'" in err and "\n" not in err




def test_numbas_first_class_function_notice_is_kept_off_stderr_even_when_highlighted():
    # numba wraps the text in terminal highlighting codes; pytest resets warning filters per test,
    # so the check runs in a process of its own
    code = ("import warnings, rollball.kernel\n"
            "from numba.core.errors import NumbaExperimentalFeatureWarning as N\n"
            "warnings.warn('\\x1b[1m\\x1b[1mFirst-class function type feature is experimental\\x1b[0m', N)\n"
            "warnings.warn('First-class function type feature is experimental', N)\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and "First-class" not in result.stderr


def test_the_warm_up_stops_quietly_when_its_reader_has_gone():
    # the app reads the "ready" lines; closed while the warm-up still runs, the pipe breaks
    process = subprocess.Popen([sys.executable, "-m", "rollball.warmup"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    process.stdout.close()
    _, err = process.communicate(timeout=600)
    assert process.returncode == 1 and "Traceback" not in err and "BrokenPipe" not in err


_COUNT_COMPILES = """
import json, sys
from numba.core import event
compiled = {}
class Count(event.Listener):
    def on_start(self, ev):
        func = ev.data["dispatcher"].py_func
        if func.__module__.startswith("rollball."):
            name = f"{func.__module__}.{func.__qualname__}"
            compiled.setdefault(name, []).append(id(ev.data["dispatcher"]))
    def on_end(self, ev):
        pass
event.register("numba:compile", Count())
from rollball.warmup import warm_up
warm_up()
print(json.dumps(compiled))
"""


def test_a_cold_warm_up_compiles_each_kernel_function_once(tmp_path):
    # The cold compile is the first Start's wait. Each compiled function once: a constant bool
    # or int passed to one would compile it again for that constant, and a helper numba
    # inlines is not compiled on its own at all. The explicit step is one function per state
    # layout. (Empty caches: a process of its own, compiling everything, ~30 s.)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "ROLLBALL_CACHE_DIR": str(tmp_path / "ours")}
    result = subprocess.run([sys.executable, "-c", _COUNT_COMPILES], capture_output=True, text=True, env=env,
                            timeout=900)
    assert result.returncode == 0, result.stderr
    compiled = json.loads(result.stdout.strip().splitlines()[-1])
    assert {name: len(ids) for name, ids in compiled.items() if len(ids) != len(set(ids))} == {}
    steps = compiled.pop("rollball.kernel._trial_step.<locals>.trial_step")
    assert len(steps) == len(set(steps)) == 3  # MK_SIZE, CLASSIC_SIZE, MOTION_SIZE
    assert {"rollball.kernel.advance", "rollball.kernel.advance_adaptive", "rollball.kernel.advance_batch"} <= set(compiled)
    # the right-hand side is compiled once (and inlined by LLVM); the other per-stage helpers are
    # inlined by numba, not compiled alone; few functions in all
    assert "rollball.kernel.dynamics" in compiled and "rollball.kernel.combine" not in compiled
    assert len(compiled) <= 26, sorted(compiled)
