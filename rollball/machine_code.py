"""The kernel's machine code, and calling it.

numba needs about a minute of processor time to compile kernel.py (typing it and lowering it
to LLVM's intermediate code takes most of it; its compiled code is kept on disk). RollBall
therefore ships that intermediate code: ``kernel.bc``, the LLVM bitcode numba made of the
kernel's entry points (``kernel.ENTRIES``) on x86-64 Linux, optimised, with no particular
processor's instructions in it. Where it fits (this machine's target, the numba it was made
with, the kernel.py it was made from: ``kernel.json``), LLVM turns it into machine code for
this processor in about two seconds, kept on disk too; elsewhere numba compiles the same entry points from
kernel.py as before (a minute or more, cached too). Both give the same runs.

``python -m rollball.kernel_build`` makes kernel.bc and kernel.json anew from kernel.py
(a developer's step after changing the kernel; a test says when they are out of date).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import inspect
import json
import os
import threading
from importlib import resources

import numpy as np

from . import kernel
from . import cache
from .cache import cache_dir

SHIPPED, STAMP = "kernel.bc", "kernel.json"

_ENTRY_TYPE = ctypes.CFUNCTYPE(None, ctypes.c_void_p)   # kernel.ENTRY_SIGNATURE; ctypes drops the GIL
_lock = threading.Lock()
_entries: dict[str, object] | None = None   # name -> ctypes function
_keep: list = []                            # what the entries' code lives in
listeners: list = []                        # called (no arguments) before machine code is generated
source: str | None = None                   # where this process's kernel came from: "shipped" or "numba"


def sources_digest() -> str:
    """The SHA-256 of kernel.py, everything the entry points are compiled from."""
    return hashlib.sha256(resources.files("rollball").joinpath("kernel.py").read_bytes()).hexdigest()


def stamp(entries: dict[str, str] | None = None) -> dict:
    """What shipped code must agree with to be used here (``entries``: their symbols; the
    shipped stamp also lists the symbols the code calls, ``calls``)."""
    import llvmlite.binding as llvm
    import numba

    facts = {"format": "rollball-machine-code", "version": 1, "kernel": sources_digest(),
             "numba": numba.__version__, "triple": llvm.get_process_triple()}
    if entries is not None:
        facts["entries"] = entries
    return facts


class Arguments:
    """The arguments of the kernel function ``name`` (a key of ``kernel.ENTRIES``) packed into
    its entry point's slots: an array as its address and shape, a number as its bits. Calling
    runs the function on them, without the GIL; ``set`` changes one, by its parameter's name.
    Packing costs microseconds an array, so a caller that runs a function again and again
    packs once; the arrays are read and written in place and kept alive here."""

    def __init__(self, name: str, *args):
        self.name = name
        self.kinds, self.offsets, self.positions = _layout(name)
        if len(args) != len(self.kinds):
            raise TypeError(f"{name}: {len(self.kinds)} arguments expected, {len(args)} given")
        self.slots = np.zeros(kernel.ENTRY_SLOTS, dtype=np.int64)
        self.address = self.slots.ctypes.data
        self.kept = list(args)
        for key, value in zip(self.positions, args):
            self.set(key, value)

    def set(self, key: str, value) -> None:
        i, position = self.offsets[key], self.positions[key]
        kind = self.kinds[position]
        if kind == "float":
            self.slots.view(np.float64)[i] = float(value)
        elif kind in _NUMBERS:
            self.slots[i] = int(value)
        else:
            ndim, dtype = (2, np.float64) if kind == "matrix" else (1, np.int64 if kind == "ints" else np.float64)
            if not (isinstance(value, np.ndarray) and value.ndim == ndim and value.dtype == dtype
                    and value.flags.c_contiguous and value.flags.aligned):
                raise TypeError(f"{self.name}: {key} must be a C-contiguous {kind} of {np.dtype(dtype)}")
            self.slots[i: i + 3] = value.ctypes.data, value.shape[0], value.shape[1] if ndim == 2 else 1
        self.kept[position] = value

    def __call__(self) -> None:
        entries()[self.name](self.address)


_NUMBERS = ("float", "int", "address")


@functools.cache
def _layout(name: str) -> tuple[list[str], dict[str, int], dict[str, int]]:
    """The kinds of the kernel function's arguments, and by parameter name each one's first
    slot and its position."""
    kinds = kernel.ENTRIES[name][1].split()
    names = list(inspect.signature(getattr(kernel, name).py_func).parameters)
    if len(kinds) != len(names):
        raise TypeError(f"{name}: kernel.ENTRIES gives {len(kinds)} kinds for {len(names)} parameters")
    offsets = dict(zip(names, np.cumsum([0] + [1 if k in _NUMBERS else 3 for k in kinds]).tolist()))
    return kinds, offsets, {key: i for i, key in enumerate(names)}


def call(name: str, *args) -> None:
    """Run the kernel function ``name`` once on these arguments (``Arguments``)."""
    Arguments(name, *args)()


def entries() -> dict:
    """Every entry point as a ctypes function, compiled or loaded on first use (thread-safe)."""
    global _entries
    if _entries is None:
        with _lock:
            if _entries is None:
                _entries = {name: _ENTRY_TYPE(address) for name, address in _addresses().items()}
    return _entries


def _addresses() -> dict[str, int]:
    global source
    shipped = _shipped()
    if shipped is not None:
        try:
            addresses = _from_bitcode(*shipped)
            source = "shipped"
            return addresses
        except (_Unusable, RuntimeError):   # (RuntimeError: LLVM could not read or compile it)
            pass
    source = "numba"
    return {name: numba_entry(name).address for name in kernel.ENTRIES}


def numba_entry(name: str):
    """The entry point ``name`` compiled by numba (a ``cfunc``; cached on disk)."""
    from numba import cfunc

    compiled = cfunc(kernel.ENTRY_SIGNATURE, cache=True, error_model="numpy")(kernel.ENTRIES[name][0])
    _keep.append(compiled)
    return compiled


class _Unusable(Exception):
    """The shipped code cannot be used on this machine (numba compiles the kernel instead)."""


def _shipped() -> tuple[bytes, dict, list] | None:
    """The shipped bitcode, its entry points' symbols and the symbols it calls, where they fit
    this machine and this kernel.py."""
    if os.environ.get("ROLLBALL_MACHINE_CODE") == "numba":   # (tests of the other way)
        return None
    folder = resources.files("rollball")
    try:
        facts = json.loads(folder.joinpath(STAMP).read_text(encoding="utf-8"))
        bitcode = folder.joinpath(SHIPPED).read_bytes()
    except (OSError, ValueError):
        return None
    entries, calls = facts.pop("entries", None), facts.pop("calls", None)
    if (facts != stamp() or not isinstance(entries, dict) or set(entries) != set(kernel.ENTRIES)
            or not isinstance(calls, list)):
        return None
    return bitcode, entries, calls


def _target_machine():
    """LLVM's target for this processor, set up as numba sets up its own."""
    import llvmlite.binding as llvm

    target = llvm.Target.from_default_triple()
    return target.create_target_machine(
        cpu=llvm.get_host_cpu_name(), features=llvm.get_host_cpu_features().flatten(), opt=3,
        reloc="static" if target.name.startswith("x86") else "default", codemodel="jitdefault", jit=True)


def _from_bitcode(bitcode: bytes, entries: dict[str, str], calls: list[str]) -> dict[str, int]:
    """The entry points' addresses in machine code made from the bitcode (or kept from an
    earlier process), under numba's compiler lock: LLVM's state is shared with numba's."""
    import llvmlite.binding as llvm
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.registry import cpu_target
    from numba.core.runtime import rtsys

    with global_compiler_lock:
        rtsys.initialize(cpu_target.target_context)   # LLVM initialised, numba's symbols known
        missing = [name for name in calls if not llvm.address_of_symbol(name)]
        if missing:   # (MCJIT would end the process on a call it cannot link)
            raise _Unusable(f"symbols not found here: {', '.join(missing)}")
        machine = _target_machine()
        key = hashlib.sha256(b"\0".join([bitcode, str(machine.triple).encode(), llvm.get_host_cpu_name().encode(),
                                         llvm.get_host_cpu_features().flatten().encode(),
                                         ".".join(map(str, llvm.llvm_version_info)).encode()])).hexdigest()[:32]
        path = _object_path(key)
        code = _read(path)
        if code is None:
            for listener in list(listeners):
                listener()
            code = machine.emit_object(llvm.parse_bitcode(bitcode))
            _write(path, code)
        engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), machine)
        engine.add_object_file(llvm.ObjectFileRef.from_data(code))
        engine.finalize_object()
        _keep.append(engine)
        addresses = {name: engine.get_function_address(symbol) for name, symbol in entries.items()}
    if not all(addresses.values()):
        raise _Unusable("an entry point is missing from the shipped code")
    return addresses


def _object_path(key: str):
    return cache_dir() / f"kernel-{key}.o"


# The kernel's machine code is about 250 kB; a cached file larger than this is not ours.
OBJECT_LIMIT = 64 << 20


def _read(path) -> bytes | None:
    """Machine code kept by an earlier process, if it is there whole (its SHA-256 first) and
    sound: a regular file of ours of plausible size (cache.read; else one warning, and it is
    made again)."""
    data = cache.read(path, OBJECT_LIMIT, "machine code of the kernel")
    if data is None:
        return None
    digest, code = data[:32], data[32:]
    return code if code and hashlib.sha256(code).digest() == digest else None


def _write(path, code: bytes) -> None:
    """Keep the machine code for later processes; a cache that cannot be written costs only time."""
    cache.write(path, hashlib.sha256(code).digest() + code)
