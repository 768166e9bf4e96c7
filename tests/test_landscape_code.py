"""A landscape's machine code: translated from the generated source to LLVM IR by RollBall
(the same numbers as numba's compile of that source, bit for bit), held by whoever uses it and
freed after, so that a long session of new formulas does not grow without bound."""

import ctypes
import re
import gc
import json
import os
import subprocess
import sys
import weakref

import numpy as np
import pytest

import sympy as sp

from rollball import Scene, Simulation, landscape_code
from rollball.examples import EXAMPLES_DIR
from rollball.formula import X, Y, FormulaError, parse_formula
from rollball.landscape import _COMPILED, Landscape, derivative, landscape_for
from rollball.llvm_runtime import initialise, target_machine
from rollball.scene import Start

FORMULAS = ["0.5*sin(x)*cos(y)", "exp(-(x^2 + y^2))", "x^3*y - 2*x*y^2 + 7", "atan2(y + 3, x + 5)",
            "abs(x) + max(x, y^2) + atan2(y, x) + log10(2 + x)", "sqrt(abs(x))", "(x*y)^-3", "min(x, y)^-1",
            "(x^2)^-3 + y", "log(x)", "asin(x/3) + acos(y/4)", "tanh(x)*cosh(y) + sinh(x*y)",
            "asinh(x) + acosh(2+y^2) + atanh(x/5)", "hypot(x, y)", "x^0.3 + 2^x", "max(x, y, 1) - min(x, 2, y)",
            "-abs(x)", "x/abs(x)", "exp(20*(x-1))", "x^17*y^5 + x^(-7)", "tan(x)", "sqrt(1 - x^2 - y^2)",
            "pi*x + e*y"]
# every example's formula with the names of its parameters (if any)
EXAMPLES = sorted({(data["landscape"], tuple(data.get("parameters", {})))
                   for data in (json.loads(path.read_text()) for path in EXAMPLES_DIR.glob("*.json"))})
EXAMPLE_FORMULAS = [text for text, names in EXAMPLES if not names]


def _values(calls_code, points, values=(0.0,)):
    import llvmlite.binding as llvm

    calls, code = calls_code
    assert landscape_code._resolvable(calls)
    engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), target_machine())
    engine.add_object_file(llvm.ObjectFileRef.from_data(code))
    engine.finalize_object()
    function = landscape_code._CTYPE(engine.get_function_address(landscape_code.SYMBOL))
    out = np.zeros((len(points), 6))
    values = np.asarray(values, dtype=float)
    for row, (x, y) in zip(out, points):
        function(x, y, values.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                 row.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    return out


@pytest.mark.parametrize("text, names", [(text, ()) for text in FORMULAS] + EXAMPLES)
def test_the_translation_gives_numbas_numbers_bit_for_bit(text, names):
    points = np.concatenate([np.random.default_rng(7).uniform(-3, 3, (50, 2)),
                             [[0, 0], [1, 1], [0, 1], [1, 0], [-1, 0], [2, 2]]])
    source = "import math\n\n\n" + Landscape(text, names).source
    values = np.linspace(0.7, 1.3, len(names)) if names else (0.0,)
    machine = target_machine()
    initialise()
    ours = _values(landscape_code._object_code(source, machine), points, values)
    numbas = _values(landscape_code._compile(source, "rollball_landscape_test", machine), points, values)
    assert np.array_equal(ours, numbas, equal_nan=True)


def _random_formulas(count, seed=5):
    rng = np.random.default_rng(seed)
    functions = ["sin", "cos", "exp", "tanh", "sqrt", "abs", "atan", "log", "asinh"]

    def formula(depth):
        if depth == 0:
            return str(rng.choice(["x", "y", "pi", str(round(rng.uniform(-3, 3), 3))]))
        kind = rng.integers(6)
        if kind == 0:
            return f"{rng.choice(functions)}({formula(depth - 1)})"
        if kind == 1:
            return f"({formula(depth - 1)})^{rng.choice(['2', '3', '-1', '0.5', 'y', '-2'])}"
        if kind == 2:
            return f"{rng.choice(['max', 'min', 'atan2', 'hypot'])}({formula(depth - 1)}, {formula(depth - 1)})"
        if kind == 3:
            return f"({formula(depth - 1)})*({formula(depth - 1)})"
        return f"({formula(depth - 1)}) {rng.choice(list('+-/'))} ({formula(depth - 1)})"
    return [formula(3) for _ in range(count)]


PARAMETRIC = [("a*sin(k*x)*cos(y)", ("a", "k"), (0.5, 2.0)), ("exp(-(x^2 + y^2)/w^2)", ("w",), (1.3,)),
              ("h*max(x, y) + abs(x - c)^q", ("h", "c", "q"), (0.7, -0.2, 2.5)), ("x^n", ("n",), (3.0,))]


@pytest.mark.parametrize("text, names, values", PARAMETRIC)
def test_parameters_are_arguments_with_numbas_numbers_and_the_constants_numbers(text, names, values):
    points = np.random.default_rng(3).uniform(-2, 2, (40, 2))
    source = "import math\n\n\n" + Landscape(text, names).source
    machine = target_machine()
    initialise()
    ours = _values(landscape_code._object_code(source, machine), points, values)
    numbas = _values(landscape_code._compile(source, "rollball_landscape_test_p", machine), points, values)
    assert np.array_equal(ours, numbas, equal_nan=True)
    # the same as the formula with the values written in it, to round-off
    constant = text
    for name, value in zip(names, values):
        constant = re.sub(rf"\b{name}\b", f"({value!r})", constant)
    assert np.allclose(Landscape(text, names).evaluate(points[:, 0], points[:, 1], values),
                       Landscape(constant).evaluate(points[:, 0], points[:, 1]), rtol=1e-12, atol=1e-12, equal_nan=True)


def test_a_parameter_needs_its_value():
    with pytest.raises(ValueError, match="takes 2 parameter values"):
        Landscape("a*x + b", ("a", "b")).evaluate(0.0, 0.0)


def test_derivatives_are_sympys_node_for_node():
    # the same expressions as sympy's diff, so the same generated source and the same numbers
    for text in FORMULAS + EXAMPLE_FORMULAS + _random_formulas(60) + ["x^y", "exp(x)^y", "log10(x*y)", "2^(x*y)"]:
        try:
            f = parse_formula(text)
        except FormulaError:   # a random one may be a constant that is undefined
            continue
        fx, fy = sp.diff(f, X), sp.diff(f, Y)
        theirs = (fx, fy, sp.diff(fx, X), sp.diff(fx, Y), sp.diff(fy, Y))
        by_x, by_y = {}, {}
        gx, gy = derivative(f, X, by_x), derivative(f, Y, by_y)
        ours = (gx, gy, derivative(gx, X, by_x), derivative(gx, Y, by_y), derivative(gy, Y, by_y))
        assert ours == theirs, text


def test_what_the_translation_does_not_know_numba_compiles():
    source = "import math\n\n\ndef landscape(x, y, p, out):\n    out[0] = math.gamma(x) + y\n"
    with pytest.raises(landscape_code._Unsupported):
        landscape_code._ir(source)
    code = landscape_code.load(source, "rollball_landscape_gamma", cached=False)
    out = np.zeros(6)
    code.ctypes(4.0, 0.5, None, out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    assert out[0] == 6.5


def test_code_nobody_holds_is_freed_and_a_run_holds_its_own():
    code = weakref.ref(Landscape("0.123*x*y + 0.5").compiled)
    gc.collect()
    assert code() is None and "0.123" not in "".join(_COMPILED.keys())
    scene = Scene(landscape="0.0625*(x^2 + y^2)", start=Start(0.5, 0.0, 0.0, 0.0, 0.0), duration=0.2)
    run = Simulation(scene)
    landscape_for.cache_clear()
    gc.collect()
    run.advance(10_000)
    assert run.done and run.trajectory().status == "ok"


MEMORY = """
import gc, json, sys
from rollball.landscape import Landscape
def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096
for i in range(20):   # what every process has once: sympy's and LLVM's first allocations
    Landscape(f"0.25*cos({i + 3}*x)*sin(y) + {i}*x").evaluate(0.1, 0.2)
gc.collect()
before = rss()
for i in range(int(sys.argv[1])):
    Landscape(f"0.5*sin({i + 7}*x)*cos(y) + {i}*x*y").evaluate(0.1, 0.2)
gc.collect()
print(json.dumps({"grown": rss() - before}))
"""


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="measures memory with /proc")
def test_new_formulas_in_one_process_do_not_keep_their_memory(tmp_path):
    # 1000 new formulas in one process grow it by less than 50 MB; 100 here, < 5 MB (it was
    # 0.3-0.7 MB a formula when numba compiled every landscape)
    count = 100
    result = subprocess.run([sys.executable, "-c", MEMORY, str(count)], capture_output=True, text=True,
                            timeout=600, env={**os.environ, "ROLLBALL_CACHE_DIR": str(tmp_path)})
    assert result.returncode == 0, result.stderr
    grown = json.loads(result.stdout.strip().splitlines()[-1])["grown"]
    assert grown < count * 50_000, f"{grown / count / 1e3:.0f} kB a formula"


THREADS = r"""
import gc, sys, threading
from rollball import machine_code, simulate
from rollball.landscape import Landscape
from rollball.scene import Scene

def formulas(k):   # new formulas made and dropped, their engines disposed of as they go
    for i in range(int(sys.argv[1])):
        Landscape(f"0.{k}{i + 1}*sin(x)*cos({i + 2}*y)").compiled
        gc.collect()

scene = Scene.load(sys.argv[2])
threads = [threading.Thread(target=formulas, args=(k,)) for k in (1, 2)]
threads.append(threading.Thread(target=lambda: simulate(scene, t_end=0.5)))  # makes the kernel's code
for thread in threads:
    thread.start()
for thread in threads:
    thread.join()
print(machine_code.source)
"""


def test_formulas_made_and_freed_in_threads_while_a_run_makes_the_kernel_code(tmp_path):
    """Every use of LLVM takes one lock: landscapes compiled and freed in two threads while a
    third makes the kernel's machine code from the shipped code, with an empty cache folder
    (unlocked, LLVM's global state is raced and the process aborts)."""
    from rollball.examples import scene_path

    env = dict(os.environ, ROLLBALL_CACHE_DIR=str(tmp_path / "cache"))
    result = subprocess.run([sys.executable, "-c", THREADS, "15", str(scene_path("hills"))], env=env,
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
