"""Landscape derivatives: compiled code, numpy evaluation and sympy agree."""

import ctypes

import numpy as np
import pytest
import sympy as sp

from rollball.formula import X, Y
from rollball.landscape import Landscape, landscape_for


def compiled_values(landscape, x, y):
    out = np.zeros(6)
    landscape.compiled.ctypes(x, y, None, out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    return out


@pytest.mark.parametrize("text", [
    "0.5*sin(x)*cos(y)", "exp(-(x^2 + y^2))", "x^3*y - 2*x*y^2 + 7", "atan2(y + 3, x + 5)",
    "log(2 + x^2 + y^2) + sqrt(3 + x) + tanh(x*y) + hypot(x, 1 + y)", "abs(x)*y^2 + max(x, y) + min(x^2, 1)",
    "cosh(x/3)/(1 + y^2)", "pi*e^(x/4)", "0", "3.5", "abs(-acos(x/2)) + abs(log(x + 3))*y",
])
def test_compiled_numpy_and_sympy_agree(text):
    landscape = Landscape(text)
    names = {"RealAbs": abs, "RealSign": lambda u: (u > 0) - (u < 0)}
    exact = [sp.lambdify((X, Y), d, [names, "mpmath"]) for d in landscape.derivatives]
    for x, y in [(0.3, -0.7), (-1.1, 0.45), (0.9, 1.3)]:
        expected = np.array([float(f(x, y)) for f in exact])
        np.testing.assert_allclose(compiled_values(landscape, x, y), expected, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(landscape.evaluate(x, y), expected, rtol=1e-12, atol=1e-13)


def test_derivatives_against_finite_differences():
    landscape = Landscape("0.5*sin(x)*cos(y) + 0.1*x^2*y")
    x, y, h = 0.4, -0.3, 1e-5
    f = landscape.evaluate
    values = f(x, y)
    np.testing.assert_allclose(values[1], (f(x + h, y)[0] - f(x - h, y)[0]) / (2 * h), rtol=1e-8)
    np.testing.assert_allclose(values[2], (f(x, y + h)[0] - f(x, y - h)[0]) / (2 * h), rtol=1e-8)
    np.testing.assert_allclose(values[3], (f(x + h, y)[1] - f(x - h, y)[1]) / (2 * h), rtol=1e-8)
    np.testing.assert_allclose(values[4], (f(x, y + h)[1] - f(x, y - h)[1]) / (2 * h), rtol=1e-8)
    np.testing.assert_allclose(values[5], (f(x, y + h)[2] - f(x, y - h)[2]) / (2 * h), rtol=1e-8)


def test_constant_landscapes_give_arrays_of_the_grid_shape():
    for text in ("0", "2.5", "x - x + 1", "sin(0.3)"):
        X_, Y_ = np.meshgrid(np.linspace(-1, 1, 4), np.linspace(-1, 1, 5), indexing="ij")
        values = Landscape(text).evaluate(X_, Y_)
        assert values.shape == (6, 4, 5)
        assert np.isfinite(values).all()
        assert (values[1:] == 0).all()


def test_outside_the_domain_is_nan_not_an_exception():
    values = Landscape("sqrt(x) + log(y)").evaluate(np.array([-1.0, 1.0]), np.array([1.0, -1.0]))
    assert np.isnan(values[0]).all()
    assert np.isnan(compiled_values(Landscape("sqrt(x)"), -1.0, 0.0)[0])


def test_generated_source_uses_only_known_names():
    source = Landscape("abs(x) + max(x, y^2) + atan2(y, x) + log10(2 + x)").source
    assert source.startswith("def landscape(x, y, p, out):")
    assert "import" not in source and "__" not in source and "p[" not in source
    named = Landscape("import_*x + out + math", ("import_", "out", "math")).source   # names never reach the code
    assert "p_0 = p[0]" in named and "p_2 = p[2]" in named and "import_" not in named


def test_the_same_formula_is_compiled_once():
    assert landscape_for("x*y + 1") is landscape_for("x*y + 1")
    assert Landscape("x*y + 2").compiled is Landscape("x*y + 2").compiled


@pytest.mark.parametrize("text", ["x^-2", "(x*y)^-3", "min(x, y)^-1", "1/x", "(x^2)^-3 + y"])
def test_poles_give_inf_or_nan_never_stale_values(text, capfd):
    values = Landscape(text).evaluate(np.array([0.0, 1.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    assert not np.isfinite(values[0, 0]) and not np.isfinite(values[0, 2])
    assert np.isfinite(values[:, 1]).all()
    assert "Exception" not in capfd.readouterr().err


def test_small_evaluations_reuse_their_packed_call_and_give_what_a_fresh_call_gives():
    """``Landscape.evaluate`` of at most PACKED_POINTS points reuses a packed call (per thread,
    values and size): its numbers are those of an evaluation through a call of its own (more
    points than PACKED_POINTS), each answer is the caller's own array, parameter values are told
    apart, and at most PACKED_CALLS calls are kept."""
    from rollball import landscape as module

    surface = Landscape("a*sin(x) + cos(b*y) + x*y", ("a", "b"))
    rng = np.random.default_rng(7)
    x, y = rng.uniform(-2, 2, module.PACKED_POINTS + 1), rng.uniform(-2, 2, module.PACKED_POINTS + 1)
    for values in ((1.0, 2.0), (0.5, -3.0)):
        whole = surface.evaluate(x, y, values)   # (one call of its own)
        for n in (1, 5, module.PACKED_POINTS):
            first = surface.evaluate(x[:n], y[:n], values)
            again = surface.evaluate(x[:n], y[:n], values)
            assert np.array_equal(first, whole[:, :n]) and np.array_equal(again, whole[:, :n])
            first[:] = np.nan   # (the caller's own: the next answer is untouched)
            assert np.array_equal(surface.evaluate(x[:n], y[:n], values), whole[:, :n])
        assert float(surface.evaluate(x[0], y[0], values)[0]) == whole[0, 0]
    assert not np.array_equal(surface.evaluate(x[:3], y[:3], (1.0, 2.0)), surface.evaluate(x[:3], y[:3], (0.5, -3.0)))
    for n in range(1, 3 * module.PACKED_CALLS):
        surface.evaluate(x[: n % module.PACKED_POINTS + 1], y[: n % module.PACKED_POINTS + 1], (1.0, 2.0))
        assert len(surface._packed.calls) <= module.PACKED_CALLS


def test_threads_evaluating_one_landscape_at_once_each_get_their_own_answers():
    """Each thread has its own packed calls (``Landscape.packed``): threads evaluating the same
    landscape at the same time get the numbers a lone evaluation gives."""
    surface = Landscape("exp(-x^2)*sin(3*y) + 0.1*x")
    points = [(np.full(4, 0.1 * k), np.linspace(-1, 1, 4) + k) for k in range(8)]
    expected = [surface.evaluate(px, py) for px, py in points]
    wrong = []

    def work(k):
        px, py = points[k]
        for _ in range(300):
            if not np.array_equal(surface.evaluate(px, py), expected[k]):
                wrong.append(k)
                return

    assert all_finished(work, 8) and not wrong


def all_finished(work, count: int, timeout: float = 120.0) -> bool:
    """Whether ``work(k)`` for k < count, each in a thread of its own, all at once, finished
    within ``timeout`` seconds each."""
    import threading

    threads = [threading.Thread(target=work, args=(k,)) for k in range(count)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=timeout)
    return not any(thread.is_alive() for thread in threads)


def test_threads_evaluating_one_landscape_with_many_parameter_values_each_keep_their_own_records():
    """Threads that evaluate one landscape at once, each with ever new parameter values, make
    every thread drop its packed calls again and again (past PACKED_CALLS): a thread dropping
    its own never frees the record another thread's call is reading. (When every thread's
    calls were kept together, one thread's drop freed the records of calls other threads were
    running: 4 threads of 500 evaluations crashed the process in each of ten runs.) Each answer
    is checked against the formula."""
    surface, wrong = Landscape("a*x^2 + b*y", ("a", "b")), []

    def work(seed):
        rng = np.random.default_rng(seed)
        for a, b, x, y in rng.uniform(-1, 1, (2000, 4)):
            f, fx, fy = surface.evaluate(x, y, (a, b))[:3]
            if abs(f - (a * x * x + b * y)) > 1e-12 or abs(fx - 2 * a * x) > 1e-12 or fy != b:
                wrong.append((a, b, x, y))

    assert all_finished(work, 4) and not wrong
