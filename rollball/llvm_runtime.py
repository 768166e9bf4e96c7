"""LLVM as the kernel's and the landscapes' machine code need it, without numba's compiler.

Code numba made calls a few of numba's C helpers (``NRT_Free``, ``numba_do_raise``, ...). They
live in numba's extension modules, which load here by their files, without the numba package
(importing it costs about half a second of processor time): a process that runs shipped or
cached machine code never imports numba. Where the compiler is needed (the kernel compiled here,
a landscape the translation does not know) numba is imported and sets LLVM up its own way, as
it always does; both give the same symbols, from the same libraries.
"""

from __future__ import annotations

import contextlib
import importlib.machinery
import importlib.metadata
import importlib.util
import os
import sys
import threading

# numba's extension modules with the C helpers its code calls, and how numba names their symbols
# (numba.core.base._load_global_helpers and numba.core.runtime.nrt.initialize)
_HELPERS = (("numba._helperlib", "numba_"), ("numba._dynfunc", "numba_"), ("numba.core.runtime._nrt_python", "NRT_"))

_LOCK = threading.RLock()
_initialised = False
_engine = None   # an engine kept for the process's life, as numba keeps its own (initialise)


@contextlib.contextmanager
def llvm_lock():
    """The lock every use of LLVM in this process takes: LLVM's global state (the symbol table,
    engines being made or disposed of) is not safe to use from two threads at once (an app that
    checks a formula in one thread while a run makes the kernel's machine code, or frees a
    landscape, in another would otherwise abort). Once numba is imported its compiler lock is
    taken too, after this one: numba's own compiles take it."""
    with _LOCK:
        compiler_lock = sys.modules.get("numba.core.compiler_lock")
        if compiler_lock is None:
            yield
        else:
            with compiler_lock.global_compiler_lock:
                yield


def numba_version() -> str:
    """The installed numba's version (machine code depends on it), without importing numba."""
    return importlib.metadata.version("numba")


def initialise() -> None:
    """LLVM's native target set up, and numba's C helpers known to every engine (under
    ``llvm_lock``; idempotent)."""
    global _initialised, _engine
    if _initialised:
        return
    import llvmlite.binding as llvm

    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    # making an engine makes the process's own symbols (Python's C API, the C library) known to
    # LLVM's symbol search
    _engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), target_machine())
    for name, prefix in _HELPERS:
        for helper, address in _extension(name).c_helpers.items():
            if name == "numba._helperlib" and llvm.address_of_symbol(helper):
                # a C library function (sqrt, exp, ...): bound to the one numba's helpers were
                # linked with, as numba binds it (numba.core.externals)
                llvm.add_symbol(helper, address)
            llvm.add_symbol(helper if helper.startswith("_") else prefix + helper, address)
    _initialised = True


def _extension(name: str):
    """numba's extension module ``name``: numba's own where numba is imported, else loaded from
    its file without the package (kept out of sys.modules, so a later ``import numba`` finds the
    package whole; Python loads such a module's library once per process either way)."""
    if name in sys.modules:
        return sys.modules[name]
    package, _, rest = name.partition(".")
    root = importlib.util.find_spec(package).submodule_search_locations[0]   # (finding it imports nothing)
    folder, _, stem = (root + "/" + rest.replace(".", "/")).rpartition("/")
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        spec = importlib.util.spec_from_file_location(name, f"{folder}/{stem}{suffix}")
        if spec is not None and spec.origin and os.path.isfile(spec.origin):
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            return module
    raise ImportError(f"numba's extension module {name} was not found in {folder}")


def target_machine():
    """LLVM's target for this processor, set up as numba sets up its own."""
    import llvmlite.binding as llvm

    target = llvm.Target.from_default_triple()
    return target.create_target_machine(
        cpu=llvm.get_host_cpu_name(), features=llvm.get_host_cpu_features().flatten(), opt=3,
        reloc="static" if target.name.startswith("x86") else "default", codemodel="jitdefault", jit=True)
