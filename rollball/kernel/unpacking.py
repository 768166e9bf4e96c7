"""Memory Python hands the kernel, seen as the kernel's arguments: an entry point's slots as
the arguments of the function it runs, and the scratch array as its parts. Both are generated
from the interface's declarations (``interface.ENTRIES``, ``interface.SCRATCH``), so that the
unpacking cannot disagree with the packing (``machine_code.Arguments``)."""

from __future__ import annotations

import linecache

from numba import carray, types

from .interface import ENTRIES, ENTRY_MODULE, ENTRY_SLOTS, INTS, MATRIX, SCRATCH, VECTOR, entry_name, layout
from .lowlevel import JIT, as_floats, float_pointer, int_pointer

ENTRY_SIGNATURE = types.void(types.CPointer(types.int64))   # every entry point: a pointer to its slots


@JIT
def _vector(a, i):
    return carray(float_pointer(a[i]), (a[i + 1],))


@JIT
def _matrix(a, i):
    return carray(float_pointer(a[i]), (a[i + 1], a[i + 2]))


@JIT
def _integers(a, i):
    return carray(int_pointer(a[i]), (a[i + 1],))


_READ = {VECTOR: "_vector(a, {slot})", MATRIX: "_matrix(a, {slot})", INTS: "_integers(a, {slot})",
         "float": "x[{slot}]", "int": "a[{slot}]", "address": "a[{slot}]"}


def _compile(source: str, name: str, namespace: dict):
    """Define the function ``name`` from generated source (kept in linecache for tracebacks)."""
    filename = f"<rollball.kernel generated {name}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(keepends=True), filename)
    exec(compile(source, filename, "exec"), namespace)
    function = namespace.pop(name)
    function.__module__ = ENTRY_MODULE
    return function


def entry_source(name: str) -> str:
    """The entry point of the kernel function ``name``: its arguments read from the slots."""
    arguments = [_READ[kind].format(slot=slot) for _, kind, slot in layout(name)]
    return (f"def {entry_name(name)}(slots):\n"
            f"    a, x = carray(slots, ({ENTRY_SLOTS},)), carray(as_floats(slots), ({ENTRY_SLOTS},))\n"
            f"    {name}({', '.join(arguments)})\n")


def make_entry(name: str, function):
    """The entry point (a plain function, compiled by machine_code.py) that runs ``function``,
    whose parameters must be those ENTRIES declares for ``name``, in that order."""
    declared = [parameter for parameter, _ in ENTRIES[name]]
    code = function.py_func.__code__
    parameters = list(code.co_varnames[:code.co_argcount])
    if parameters != declared:
        raise TypeError(f"{name}: interface.ENTRIES declares {declared}, the function takes {parameters}")
    namespace = {"carray": carray, "as_floats": as_floats, "_vector": _vector, "_matrix": _matrix,
                 "_integers": _integers, name: function}
    return _compile(entry_source(name), entry_name(name), namespace)


def scratch_source() -> str:
    """``scratch(work, n)``: the views of the scratch array's parts, in SCRATCH's order."""
    views, constant, ns = [], 0, 0   # a part starts at constant + ns * n

    def offset(constant, ns):
        terms = [str(constant)] if constant or not ns else []
        return " + ".join(terms + ([f"{ns} * n" if ns > 1 else "n"] if ns else []))

    for _, size in SCRATCH:
        start = offset(constant, ns)
        if size == "n":
            ns += 1
        else:
            constant += 9 if size == (3, 3) else size
        view = f"work[{start}:{offset(constant, ns)}]"
        views.append(f"{view}.reshape((3, 3))" if size == (3, 3) else view)
    return "def scratch(work, n):\n    return (" + ",\n            ".join(views) + ")\n"


scratch = JIT(_compile(scratch_source(), "scratch", {}))
scratch.__doc__ = """Views into the caller's scratch array (nothing is allocated inside the kernel), as
    interface.SCRATCH lists them: d, Y, zn, pn, Rn, Ye, Re, pe, sa, sb, sm."""
