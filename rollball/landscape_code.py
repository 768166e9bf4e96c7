"""A landscape's machine code: the generated source of ``landscape(x, y, p, out)`` (landscape.py)
made into a C callback, kept in the cache folder, and loaded into an LLVM engine of its own
that is freed with it (docs/design.md §8).

The source is translated to LLVM IR here (``_ir``: the same numbers as numba's compile of the
same source, bit for bit), optimised in an LLVM context of its own and emitted as object code
for this processor; what the translation does not know, numba lowers (``_compile``, without its
engine). The object code is kept in the cache folder (cache.py: read only when a regular file
of ours of plausible size, checked by its SHA-256) and loaded into a fresh MCJIT engine. Neither
numba's compiler (when the translation suffices) nor its on-disk cache is used for landscapes:
numba keeps 0.3-0.5 MB of every function it compiles for as long as the process lives (measured
with the function dropped and its code never finalised), and its cache index is a pickle.
A ``LandscapeCode`` lives as long as someone holds it (the ``Landscape`` does, and every run
holds its landscape), and its engine with it.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import math
import sys
import types

from . import cache
from .llvm_runtime import initialise, llvm_lock, numba_version, target_machine

SYMBOL = "rollball_landscape"
_MACHINE = None     # the target machine that emits landscapes' object code (under llvm_lock)
LIMIT = 64 << 20    # bytes a landscape's cached machine code may have (a few kB to a few MB)
_CTYPE = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                          ctypes.POINTER(ctypes.c_double))   # kernel/interface.py: LANDSCAPE_ARGUMENTS


class LandscapeCode:
    """The compiled ``landscape(x, y, p, out)``: ``address`` for the kernel, ``ctypes`` to call it
    from Python. Holding this object keeps the code; dropping the last reference frees it (its
    engine disposed of under ``llvm_lock``, in whichever thread drops it)."""

    def __init__(self, engine, address: int, unwritten: str | None = None):
        self._engine = engine
        self.address = address
        self.ctypes = _CTYPE(address)
        self.unwritten = unwritten   # why the code could not be kept in the cache folder, if so

    def __del__(self):
        engine, self._engine = self._engine, None
        if engine is None or sys.is_finalizing():   # (the interpreter shutting down frees it all)
            return
        with llvm_lock():
            engine.close()


def load(text: str, name: str, cached: bool = True) -> LandscapeCode:
    """The machine code of the generated module ``text`` (whose function is ``landscape``): from
    the cache folder when it is there and sound, else made now (and kept there, when ``cached``;
    ``unwritten`` says why that failed, if it did)."""
    import llvmlite.binding as llvm

    global _MACHINE
    with llvm_lock():
        initialise()
        machine = _MACHINE = _MACHINE or target_machine()   # made once (0.7 ms); an engine owns its own
        key = _key(text, machine)
        path = cache.cache_dir() / f"landscape-{key}.o"
        entry = _unpack(cache.read(path, LIMIT, "machine code of a landscape")) if cached else None
        unwritten = None
        if entry is None or not _resolvable(entry[0]):
            try:
                entry = _object_code(text, machine)
            except _Unsupported:
                entry = _compile(text, name, machine)
            if cached:
                data = json.dumps({"calls": entry[0]}).encode() + b"\n" + entry[1]
                unwritten = cache.write(path, hashlib.sha256(data).digest() + data)
        calls, code = entry
        if not _resolvable(calls):
            raise RuntimeError(f"the landscape's code calls symbols not found here: {', '.join(calls)}")
        engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), target_machine())
        engine.add_object_file(llvm.ObjectFileRef.from_data(code))
        engine.finalize_object()
        address = engine.get_function_address(SYMBOL)
    if not address:
        raise RuntimeError("the landscape's machine code has no entry point")
    return LandscapeCode(engine, address, unwritten)


def _key(text: str, machine) -> str:
    """What the machine code depends on: the source, numba and LLVM, the processor."""
    import llvmlite
    import llvmlite.binding as llvm

    facts = [text, numba_version(), llvmlite.__version__, ".".join(map(str, llvm.llvm_version_info)),
             str(machine.triple), llvm.get_host_cpu_name(), llvm.get_host_cpu_features().flatten()]
    return hashlib.sha256("\0".join(facts).encode()).hexdigest()[:40]


def _unpack(data: bytes | None) -> tuple[list[str], bytes] | None:
    """(the symbols it calls, object code) of a cache entry, or None unless it is whole."""
    if data is None or len(data) < 32 or hashlib.sha256(data[32:]).digest() != data[:32]:
        return None
    header, _, code = data[32:].partition(b"\n")
    try:
        calls = json.loads(header)["calls"]
    except (ValueError, KeyError, TypeError):
        return None
    if not code or not isinstance(calls, list) or not all(isinstance(c, str) for c in calls):
        return None
    return calls, code


def _resolvable(calls: list[str]) -> bool:
    """Every symbol the code calls is known here (MCJIT ends the process on one it cannot link)."""
    import llvmlite.binding as llvm

    return all(llvm.address_of_symbol(name) for name in calls)


def _compile(text: str, name: str, machine) -> tuple[list[str], bytes]:
    """numba's lowering of ``landscape`` as a C callback, optimised, as object code for
    ``machine``; the callback renamed to ``SYMBOL``. numba's engine is not involved (its
    library is never finalised), so nothing of it stays in numba's engine."""
    from numba.core import sigutils
    from numba.core.ccallback import CFunc
    from .kernel import LANDSCAPE_SIGNATURE

    module = types.ModuleType(name)
    exec(compile(text, f"<{name}>", "exec"), module.__dict__)  # our generated code, checked, not user text
    callback = CFunc(module.landscape, sigutils.normalize_signature(LANDSCAPE_SIGNATURE), locals={},
                     options={"error_model": "numpy"})
    with llvm_lock():
        result = callback._compile_uncached()
        library = result.library
        for other in library._linking_libraries:
            library._final_module.link_in(other._get_module_for_linking(), preserve=True)
        library._optimize_final_module()
        final = library._final_module
        final.verify()
        final.get_function(result.fndesc.llvm_cfunc_wrapper_name).name = SYMBOL
        calls = sorted(f.name for f in final.functions if f.is_declaration and not f.name.startswith("llvm."))
        return calls, machine.emit_object(final)


# -- the generated source as LLVM IR ------------------------------------------------------
#
# The generated ``landscape`` is straight-line arithmetic: assignments of numbers, x, y, the
# parameters' values p[k], earlier names, + - * / **, calls of math functions and abs/min/max, comparisons, and/or/not
# and conditional expressions. It is translated here as numba would compile it (floats throughout;
# an integer constant exponent by repeated squaring, any other power by pow; conditional
# expressions evaluate both sides, which cannot fail), in an LLVM context of its own that is
# freed afterwards. Anything else in the source is ``_Unsupported``, and numba compiles it.

class _Unsupported(Exception):
    pass


# math functions by their libm name (one argument unless said)
_LIBM = {"sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
         "exp", "expm1", "log", "log1p", "log2", "log10", "cbrt", "erf", "erfc"}
_LIBM2 = {"atan2", "hypot", "pow", "fmod"}
_INTRINSICS = {"sqrt": "llvm.sqrt.f64", "fabs": "llvm.fabs.f64", "floor": "llvm.floor.f64",
               "ceil": "llvm.ceil.f64", "trunc": "llvm.trunc.f64"}
_MAX_SQUARING = 0x10000    # numba's cut-off: larger integer exponents go to pow


def _ir(text: str) -> str:
    """LLVM IR of ``landscape(x, y, p, out)`` from the generated module ``text``, as ``SYMBOL``."""
    import ast

    from llvmlite import ir

    tree = ast.parse(text)
    functions = [node for node in tree.body if isinstance(node, ast.FunctionDef)]
    if len(functions) != 1 or [a.arg for a in functions[0].args.args] != ["x", "y", "p", "out"]:
        raise _Unsupported("not one landscape(x, y, p, out)")
    double, boolean = ir.DoubleType(), ir.IntType(1)
    module = ir.Module(name="landscape")
    function = ir.Function(module, ir.FunctionType(ir.VoidType(), [double, double, ir.PointerType(),
                                                                   ir.PointerType()]), SYMBOL)
    builder = ir.IRBuilder(function.append_basic_block("entry"))
    names = {"x": function.args[0], "y": function.args[1]}
    declared = {}

    def callee(name, arity):
        if name not in declared:
            declared[name] = ir.Function(module, ir.FunctionType(double, [double] * arity), name)
        return declared[name]

    def number(value):
        return ir.Constant(double, float(value))

    def as_double(value):
        return builder.uitofp(value, double) if value.type == boolean else value

    def as_bool(value):
        return value if value.type == boolean else builder.fcmp_unordered("!=", value, number(0.0))

    def integer(node):
        """The value of an integer constant (possibly negated), else None."""
        if isinstance(node, ast.Constant) and type(node.value) is int:
            return node.value
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            inner = integer(node.operand)
            return None if inner is None else -inner
        return None

    def power(base, exponent: int):
        if exponent == 0:
            return number(1.0)
        if abs(exponent) > _MAX_SQUARING:
            return builder.call(callee("pow", 2), [base, number(exponent)])
        result, n = number(1.0), abs(exponent)
        while n:
            if n & 1:
                result = builder.fmul(result, base)
            n >>= 1
            if n:
                base = builder.fmul(base, base)
        return builder.fdiv(number(1.0), result) if exponent < 0 else result

    def value(node):
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return number(node.value)
        if isinstance(node, ast.Name):
            if node.id not in names:
                raise _Unsupported(f"name {node.id}")
            return names[node.id]
        if (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id == "p"
                and integer(node.slice) is not None and integer(node.slice) >= 0):   # a parameter's value
            slot = builder.gep(function.args[2], [ir.Constant(ir.IntType(64), integer(node.slice))],
                               source_etype=double)
            return builder.load(slot, typ=double)
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "math":
            constants = {"pi": math.pi, "e": math.e, "tau": math.tau, "inf": math.inf, "nan": math.nan}
            if node.attr not in constants:
                raise _Unsupported(f"math.{node.attr}")
            return number(constants[node.attr])
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                return builder.fneg(as_double(value(node.operand)))
            if isinstance(node.op, ast.UAdd):
                return as_double(value(node.operand))
            if isinstance(node.op, ast.Not):
                return builder.not_(as_bool(value(node.operand)))
        if isinstance(node, ast.BinOp):
            left = as_double(value(node.left))
            if isinstance(node.op, ast.Pow):
                exponent = integer(node.right)
                if exponent is not None:
                    return power(left, exponent)
                return builder.call(callee("pow", 2), [left, as_double(value(node.right))])
            right = as_double(value(node.right))
            operations = {ast.Add: builder.fadd, ast.Sub: builder.fsub, ast.Mult: builder.fmul, ast.Div: builder.fdiv}
            if type(node.op) in operations:
                return operations[type(node.op)](left, right)
        if isinstance(node, ast.Compare) and len(node.ops) == 1:
            symbols = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!="}
            if type(node.ops[0]) in symbols:
                symbol = symbols[type(node.ops[0])]
                left, right = as_double(value(node.left)), as_double(value(node.comparators[0]))
                if symbol == "!=":   # Python: NaN != anything
                    return builder.fcmp_unordered(symbol, left, right)
                return builder.fcmp_ordered(symbol, left, right)
        if isinstance(node, ast.BoolOp):
            parts = [as_bool(value(v)) for v in node.values]
            combine = builder.and_ if isinstance(node.op, ast.And) else builder.or_
            result = parts[0]
            for part in parts[1:]:
                result = combine(result, part)
            return result
        if isinstance(node, ast.IfExp):
            test = as_bool(value(node.test))
            body, orelse = value(node.body), value(node.orelse)
            if body.type != orelse.type:
                body, orelse = as_double(body), as_double(orelse)
            return builder.select(test, body, orelse)
        if isinstance(node, ast.Call) and not node.keywords:
            args = [as_double(value(a)) for a in node.args]
            func = node.func
            if isinstance(func, ast.Name) and func.id in ("min", "max") and len(args) >= 2:
                result = args[0]
                for arg in args[1:]:   # as Python's min and max: the first of equals, NaN as it falls
                    better = builder.fcmp_ordered("<" if func.id == "min" else ">", arg, result)
                    result = builder.select(better, arg, result)
                return result
            if isinstance(func, ast.Name) and func.id == "abs" and len(args) == 1:
                return builder.call(callee("llvm.fabs.f64", 1), args)
            if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) and func.value.id == "math":
                name = func.attr
                if name in _LIBM and len(args) == 1 or name in _LIBM2 and len(args) == 2:
                    return builder.call(callee(name, len(args)), args)
                if name in _INTRINSICS and len(args) == 1:
                    return builder.call(callee(_INTRINSICS[name], 1), args)
                if name == "copysign" and len(args) == 2:
                    return builder.call(callee("llvm.copysign.f64", 2), args)
        raise _Unsupported(ast.dump(node)[:80])

    for statement in functions[0].body:
        if not isinstance(statement, ast.Assign) or len(statement.targets) != 1:
            raise _Unsupported("a statement other than an assignment")
        target = statement.targets[0]
        result = as_double(value(statement.value))
        if isinstance(target, ast.Name):
            names[target.id] = result
        elif (isinstance(target, ast.Subscript) and isinstance(target.value, ast.Name) and target.value.id == "out"
              and integer(target.slice) is not None and 0 <= integer(target.slice) < 6):
            slot = builder.gep(function.args[3], [ir.Constant(ir.IntType(64), integer(target.slice))],
                               source_etype=double)
            builder.store(result, slot)
        else:
            raise _Unsupported("an assignment to something else")
    builder.ret_void()
    return str(module)


def _object_code(text: str, machine) -> tuple[list[str], bytes]:
    """(the symbols it calls, object code) of the generated module, translated by ``_ir`` in an
    LLVM context of its own, freed when done. No IR passes: the code is one straight block that
    LLVM's code generator (at -O3) optimises whole, and a pass builder would keep ~30 kB for good
    each time one is made (and cannot be reused)."""
    import llvmlite.binding as llvm

    context = llvm.create_context()
    module = llvm.parse_assembly(_ir(text), context=context)
    module.triple = machine.triple
    module.data_layout = str(machine.target_data)
    module.verify()
    calls = sorted(f.name for f in module.functions if f.is_declaration and not f.name.startswith("llvm."))
    return calls, machine.emit_object(module)
