"""Compiling ahead of need: every method is warmed, and a compile is announced once."""

import json
import os
import resource
import subprocess
import sys
from importlib import resources

import pytest

from numba import njit

from rollball import METHODS, kernel, machine_code
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
    assert set(machine_code.entries()) == set(kernel.ENTRIES)   # compiled, or loaded from the disk cache


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


def test_making_the_machine_code_is_announced_once_and_only_within_the_block():
    said = []
    with compile_notice(lambda: said.append("compiling")):
        (listener,) = machine_code.listeners
        listener()
        listener()
    assert said == ["compiling"] and machine_code.listeners == []


def test_the_command_line_says_once_when_it_makes_the_machine_code_and_not_again(tmp_path):
    env = {**os.environ, "ROLLBALL_CACHE_DIR": str(tmp_path)}   # (no machine code kept yet)
    command = [sys.executable, "-m", "rollball", "simulate", "hills", "--t-end", "0.1"]
    first = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    again = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    assert first.returncode == 0 and first.stderr.count("compiling the integrator, first run only") == 1
    assert again.returncode == 0 and "compiling" not in again.stderr


def test_an_unknown_run_to_warm_first_is_refused_in_one_line(capsys):
    from rollball.warmup import main

    assert main(["rk5"]) == 2
    err = capsys.readouterr().err.strip()
    assert "unknown run 'rk5'" in err and "\n" not in err




def test_the_warm_up_stops_quietly_when_its_reader_has_gone():
    # the app reads the "ready" lines; closed while the warm-up still runs, the pipe breaks
    process = subprocess.Popen([sys.executable, "-m", "rollball.warmup"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    process.stdout.close()
    _, err = process.communicate(timeout=600)
    assert process.returncode == 1 and "Traceback" not in err and "BrokenPipe" not in err


_COUNT_COMPILES = """
import json
from numba.core import event
from rollball.kernel_build import Compiles
compiles = Compiles()
event.register("numba:compile", compiles)
from rollball import machine_code
from rollball.warmup import warm_up
warm_up()
print(json.dumps({"compiled": compiles.counts(), "source": machine_code.source}))
"""


# The cold warm-up is bounded by its CPU time, not the wall's: where the shipped code does not fit,
# numba compiles the whole kernel in it (about 10 min of CPU on a slow machine), and on a machine
# loaded 6-fold that is an hour of wall time. The wall bound is only the last resort against a
# process that hangs without spending CPU.
COLD_CPU_SECONDS = 2400
COLD_WALL_SECONDS = 6 * 3600


def _cpu_bound():
    resource.setrlimit(resource.RLIMIT_CPU, (COLD_CPU_SECONDS, COLD_CPU_SECONDS))


def _cold_warm_up(tmp_path, source: str) -> dict:
    """warm_up in a process of its own with empty numba and landscape caches, the kernel from
    ``source`` (at most COLD_CPU_SECONDS of CPU): the kernel functions numba compiled, and where
    the kernel's machine code came from."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "ROLLBALL_CACHE_DIR": str(tmp_path / "ours"),
           "ROLLBALL_MACHINE_CODE": source}
    result = subprocess.run([sys.executable, "-c", _COUNT_COMPILES], capture_output=True, text=True, env=env,
                            timeout=COLD_WALL_SECONDS, preexec_fn=_cpu_bound)
    assert result.returncode == 0, (result.returncode, result.stderr)
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def shipped_cold(tmp_path_factory):
    return _cold_warm_up(tmp_path_factory.mktemp("shipped"), "shipped")


def _shipped_fits():
    try:
        machine_code._shipped()
    except machine_code._Unusable as error:
        pytest.skip(f"the shipped code does not fit here ({error}); numba's way is used instead (every run "
                    f"compiles the kernel with numba once)")


def test_a_cold_warm_up_from_the_shipped_code_compiles_nothing_with_numba(shipped_cold):
    # The cold compile is the first Start's wait: the shipped code is made into machine code by
    # LLVM alone (~2 s of the ~5 s here); numba compiles no kernel function (a minute and more)
    _shipped_fits()
    assert shipped_cold["source"] == "shipped"
    assert shipped_cold["compiled"] == {}


def _stamp_of_this_kernel() -> dict:
    """The shipped code's stamp (kernel.json), skipping where it was made for another numba,
    llvmlite or target (that installation uses numba's way)."""
    facts = json.loads(resources.files("rollball").joinpath(machine_code.STAMP).read_text())
    here = machine_code.stamp()
    for key in ("numba", "llvmlite", "triple"):
        if facts[key] != here[key]:
            pytest.skip(f"the shipped code was made for {key} {facts[key]}, this is {here[key]}: numba's way is "
                        f"used here (every run compiles the kernel with numba once)")
    return facts


def test_numba_compiled_each_kernel_function_once_when_the_shipped_code_was_made():
    # Where the shipped code does not fit (another platform, another numba), numba compiles the
    # same entry points from the kernel package, as ``python -m rollball.kernel_build`` did to
    # make the shipped code; the build records numba's compiles in kernel.json (``Compiles``), and
    # the test below ties kernel.json to this kernel's code, so the compile is checked here without
    # its ten minutes. Each function compiled once: a constant bool or int passed to one would
    # compile it again for that constant, and a helper numba inlines is not compiled on its own at
    # all. The explicit step is one function per state layout, and one more per mode for the
    # adaptive pairs' tries (which leave R to be carried once the try is accepted).
    compiled = dict(_stamp_of_this_kernel()["compiled"])
    assert {name: times for name, times in compiled.items() if times != [1] * len(times)} == {}
    steps = compiled.pop("rollball.kernel.explicit._trial_step.<locals>.trial_step")
    # rolling: MK_SIZE, CLASSIC_SIZE, MOTION_SIZE and the pairs' MK_SIZE tries; sliding:
    # SLIDING_MK_SIZE, SLIDING_CLASSIC_SIZE and the pairs' SLIDING_MK_SIZE tries; and the six
    # that are not motion only again, with the dissipation's quadratures
    assert len(steps) == 13
    assert all(len(times) == 1 for times in compiled.values())   # (one dispatcher each)
    # (the adaptive loop is inlined into its entry point)
    assert {"rollball.kernel.loops.advance", "rollball.kernel.batch.advance_batch"} <= set(compiled), sorted(compiled)
    # the right-hand side is compiled once (and inlined by LLVM); the other per-stage helpers are
    # inlined by numba, not compiled alone; few functions in all
    assert "rollball.kernel.physics.dynamics" in compiled and "rollball.kernel.explicit.combine" not in compiled
    # (32 with the sliding equations and the mode looks; 37 with a change of mode searched for
    # inside a step and placed by the method's own step, a tip's approach and the closest points;
    # 38 with going on from where a couple's side turned inside a step; 39 with the sub-step kept
    # short of a tip or a ridge's edge, its stages too; 40 with a flight's look at the surface; 42
    # with a flight's landing search and its Brent's method; 43 with a flight's rows; 45 with an
    # impact and a flight's bounces; 47 with the landscape's bounds over a box and its entry point;
    # 48 with a slip's direction on the slow motion to first order)
    assert len(compiled) <= 48, sorted(compiled)


def test_the_shipped_code_is_made_from_this_kernel():
    # the kernel's code changed (comments and docstrings aside) without ``python -m
    # rollball.kernel_build``: the shipped code is stale, and every user would wait for numba.
    # (Another numba, llvmlite or target is no error: that installation uses numba's way.)
    facts = _stamp_of_this_kernel()
    here = machine_code.stamp()
    assert facts["kernel"] == machine_code.sources_digest(), "run: python -m rollball.kernel_build"
    assert facts["interface"] == here["interface"], "run: python -m rollball.kernel_build"
    assert set(facts["entries"]) == set(kernel.ENTRIES)
    assert machine_code._shipped()[1]["bitcode"] == facts["bitcode"]


def test_making_the_shipped_code_checks_its_folder_before_the_long_compile(tmp_path, monkeypatch, capsys):
    # the compile takes minutes: a folder the files cannot be written into is said first
    from rollball import kernel_build

    def compile_not_expected(folder):
        raise AssertionError("compiled before the folder was checked")

    monkeypatch.setattr(kernel_build, "build", compile_not_expected)
    not_a_folder = tmp_path / "kernel.bc"
    not_a_folder.write_text("a file where the folder should be")
    assert kernel_build.main(str(not_a_folder)) == 1
    err = capsys.readouterr().err
    assert err.startswith("rollball: cannot write the kernel's code into") and str(not_a_folder) in err
    assert err.count("\n") == 1
