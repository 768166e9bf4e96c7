"""A landscape's machine code: the generated source of ``landscape(x, y, out)`` (landscape.py)
made into a C callback, kept in the cache folder, and loaded into an LLVM engine of its own
that is freed with it.

numba types and lowers the source (a ``cfunc``, as the kernel expects) and optimises it; LLVM
then emits object code for this processor, which is kept in the cache folder (cache.py: read
only when a regular file of ours of plausible size, checked by its SHA-256) and loaded into
a fresh MCJIT engine. numba's own engine and its on-disk cache are never used for landscapes:
numba's engine keeps every function it ever finalised, and its cache index is a pickle.
A ``LandscapeCode`` lives as long as someone holds it (the ``Landscape`` does, and every run
holds its landscape), and its engine with it.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import threading
import types

from . import cache

SYMBOL = "rollball_landscape"
LIMIT = 64 << 20    # bytes a landscape's cached machine code may have (a few kB to a few MB)
_CTYPE = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double, ctypes.POINTER(ctypes.c_double))
_lock = threading.Lock()


class LandscapeCode:
    """The compiled ``landscape(x, y, out)``: ``address`` for the kernel, ``ctypes`` to call it
    from Python. Holding this object keeps the code; dropping the last reference frees it."""

    def __init__(self, engine, address: int, unwritten: str | None = None):
        self._engine = engine
        self.address = address
        self.ctypes = _CTYPE(address)
        self.unwritten = unwritten   # why the code could not be kept in the cache folder, if so


def load(text: str, name: str, cached: bool = True) -> LandscapeCode:
    """The machine code of the generated module ``text`` (whose function is ``landscape``): from
    the cache folder when it is there and sound, else made now (and kept there, when ``cached``;
    ``unwritten`` says why that failed, if it did)."""
    import llvmlite.binding as llvm

    from .machine_code import _target_machine

    with _lock:
        _initialise()
        machine = _target_machine()
        key = _key(text, machine)
        path = cache.cache_dir() / f"landscape-{key}.o"
        entry = _unpack(cache.read(path, LIMIT, "machine code of a landscape")) if cached else None
        unwritten = None
        if entry is None or not _resolvable(entry[0]):
            entry = _compile(text, name, machine)
            if cached:
                data = json.dumps({"calls": entry[0]}).encode() + b"\n" + entry[1]
                unwritten = cache.write(path, hashlib.sha256(data).digest() + data)
        calls, code = entry
        if not _resolvable(calls):
            raise RuntimeError(f"the landscape's code calls symbols not found here: {', '.join(calls)}")
        engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), _target_machine())
        engine.add_object_file(llvm.ObjectFileRef.from_data(code))
        engine.finalize_object()
        address = engine.get_function_address(SYMBOL)
    if not address:
        raise RuntimeError("the landscape's machine code has no entry point")
    return LandscapeCode(engine, address, unwritten)


def _initialise() -> None:
    """LLVM set up as numba sets it up, and numba's helper symbols known to every engine."""
    from numba.core.registry import cpu_target
    from numba.core.runtime import rtsys

    rtsys.initialize(cpu_target.target_context)


def _key(text: str, machine) -> str:
    """What the machine code depends on: the source, numba and LLVM, the processor."""
    import llvmlite
    import llvmlite.binding as llvm
    import numba

    facts = [text, numba.__version__, llvmlite.__version__, ".".join(map(str, llvm.llvm_version_info)),
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
    from numba.core.compiler_lock import global_compiler_lock

    from .kernel import LANDSCAPE_SIGNATURE

    module = types.ModuleType(name)
    exec(compile(text, f"<{name}>", "exec"), module.__dict__)  # our generated code, checked, not user text
    callback = CFunc(module.landscape, sigutils.normalize_signature(LANDSCAPE_SIGNATURE), locals={},
                     options={"error_model": "numpy"})
    with global_compiler_lock:
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
