"""The kernel's machine code, and calling it.

numba needs about a minute of processor time to compile the kernel (typing it and lowering it
to LLVM's intermediate code takes most of it). RollBall therefore ships that intermediate
code: ``kernel.bc``, the LLVM bitcode numba made of the kernel's entry points
(``kernel.ENTRY_POINTS``) on x86-64 Linux, optimised, with no particular processor's instructions
in it. ``kernel.json`` says what it was made from: a digest of the kernel package's code
(comments and docstrings aside), the numba and llvmlite that made it, the target, the
interface (each entry's arguments) and the SHA-256 of kernel.bc itself. Where all of that
agrees with this installation, LLVM turns the bitcode into machine code for this processor
in about two seconds. Elsewhere numba compiles the same entry points here (a minute or more,
without numba's own disk cache) and LLVM makes machine code of that. Either machine code is
kept in the cache folder, keyed by what it was made from, so later processes load it in well
under a second; both give the same runs.

``python -m rollball.kernel_build`` makes kernel.bc and kernel.json anew (a maintainer's step
after changing the kernel; a test says when they are out of date).
"""

from __future__ import annotations

import ast
import ctypes
import functools
import hashlib
import io
import json
import os
import threading
import tokenize
from importlib import resources

import numpy as np

from . import cache
from .cache import cache_dir
from .kernel import interface
from .llvm_runtime import initialise, llvm_lock, numba_version, target_machine
from .text import shown

SHIPPED, STAMP = "kernel.bc", "kernel.json"
FORMAT = "rollball-machine-code"
FORMAT_VERSION = 2

_ENTRY_TYPE = ctypes.CFUNCTYPE(None, ctypes.c_void_p)   # kernel.ENTRY_SIGNATURE; ctypes drops the GIL
_lock = threading.Lock()
_entries: dict[str, object] | None = None   # name -> ctypes function
_keep: list = []                            # what the entries' code lives in
listeners: list = []                        # called (no arguments) before machine code is generated
source: str | None = None                   # where this process's kernel came from: "shipped" or "numba"
refused: str | None = None                  # why the shipped code was not used (None: it was, or not yet asked)


def sources_digest(folder=None) -> str:
    """The SHA-256 of the kernel package's code (``folder``: the package's, by default),
    everything the entry points are compiled from, without its comments and docstrings
    (``_code``): editing those keeps the shipped code."""
    return _digest(_code, folder)


def raw_digest(folder=None) -> str:
    """The SHA-256 of the kernel package's files as they are (quick to compute: where it is the
    one kernel.json records, so is the digest of the code)."""
    return _digest(lambda text: text, folder)


def _digest(normal, folder) -> str:
    folder = resources.files("rollball").joinpath("kernel") if folder is None else folder
    digest = hashlib.sha256()
    for name in sorted(item.name for item in folder.iterdir() if item.name.endswith(".py")):
        digest.update(f"{name}\0{normal(folder.joinpath(name).read_text(encoding='utf-8'))}\0".encode())
    return digest.hexdigest()


def _code(text: str) -> str:
    """The tokens of a module's source that make its code, one a line: no comments, blank lines
    or docstrings (an f-string as one token, as older Pythons give it)."""
    docstrings = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
                    and isinstance(first.value.value, str)):
                docstrings.add((first.lineno, first.col_offset))
    lines = text.splitlines(keepends=True)
    out, skip_newline, fstring = [], False, None   # fstring: (depth, start) of an f-string being read
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        kind = tokenize.tok_name[token.type]
        if kind == "FSTRING_START":
            fstring = (fstring[0] + 1, fstring[1]) if fstring else (1, token.start)
            continue
        if fstring:
            if kind == "FSTRING_END":
                fstring = (fstring[0] - 1, fstring[1])
                if fstring[0] == 0:
                    (r0, c0), (r1, c1) = fstring[1], token.end
                    span = "".join(lines[r0 - 1:r1])
                    out.append("STRING " + span[c0:len(span) - len(lines[r1 - 1]) + c1])
                    fstring = None
            continue
        if kind in ("COMMENT", "NL", "ENCODING"):
            continue
        if kind == "STRING" and token.start in docstrings:
            skip_newline = True
            continue
        if skip_newline and kind == "NEWLINE":
            skip_newline = False
            continue
        skip_newline = False
        out.append(f"{kind} {token.string}")
    return "\n".join(out)


def stamp(shipped: dict | None = None) -> dict:
    """What shipped code must have been made from to be used here: this kernel's code, its
    interface, the numba and llvmlite that compile it, and this machine's target. (The digest
    of the code is taken from ``shipped``, a kernel.json, where its files are byte for byte
    those it was made from.)"""
    import llvmlite
    import llvmlite.binding as llvm

    same = shipped is not None and shipped.get("sources") == raw_digest() and isinstance(shipped.get("kernel"), str)
    return {"format": FORMAT, "version": FORMAT_VERSION, "kernel": shipped["kernel"] if same else sources_digest(),
            "interface": interface.description(), "numba": numba_version(), "llvmlite": llvmlite.__version__,
            "triple": llvm.get_process_triple()}


class Arguments:
    """The arguments of the kernel function ``name`` (a key of ``interface.ENTRIES``), each
    given by its declared name, packed into its entry point's slots: an array as its address
    and shape, a number as its bits. Calling runs the function on them, without the GIL;
    ``set`` changes one. The slots are a ctypes array (its items written in a tenth of the time
    a numpy slice takes), and an array's address is read through ctypes too, so packing an
    argument costs about a microsecond; a caller that runs a function again and again packs
    once. The arrays are read and written in place and kept alive here (``kept``, by name)."""

    def __init__(self, name: str, /, **arguments):
        self.name = name
        self.layout = _layout(name)
        missing = [key for key in self.layout if key not in arguments]
        unknown = [key for key in arguments if key not in self.layout]
        problems = [f"{word} {', '.join(keys)}" for word, keys in (("missing", missing), ("unknown", unknown)) if keys]
        if problems:
            raise TypeError(f"{name}: {'; '.join(problems)}")
        self.slots = _SLOTS()
        self._floats = _FLOATS.from_buffer(self.slots)   # (the same memory, as doubles)
        self.address = ctypes.addressof(self.slots)
        self.kept: dict = {}
        for key, value in arguments.items():
            self.set(key, value)

    def set(self, key: str, value) -> None:
        try:
            kind, i, ndim, dtype = self.layout[key]
        except KeyError:
            raise TypeError(f"{self.name}: no argument {key}") from None
        if kind == interface.FLOAT:
            self._floats[i] = float(value)
        elif ndim == 0:
            self.slots[i] = int(value)
        else:
            flags = value.flags if isinstance(value, np.ndarray) else None
            if not (flags is not None and value.ndim == ndim and value.dtype == dtype and flags.c_contiguous
                    and flags.aligned):
                raise TypeError(f"{self.name}: {key} must be a C-contiguous {kind} of {dtype}")
            slots = self.slots
            slots[i], slots[i + 1], slots[i + 2] = (_address(value, flags.writeable), value.shape[0],
                                                    value.shape[1] if ndim == 2 else 1)
        self.kept[key] = value

    def __call__(self) -> None:
        entries()[self.name](self.address)


_SLOTS, _FLOATS = ctypes.c_int64 * interface.ENTRY_SLOTS, ctypes.c_double * interface.ENTRY_SLOTS


def _address(array: np.ndarray, writeable: bool) -> int:
    """The address of an array's first element: through ctypes' view of a writable buffer (a
    quarter of the time numpy's ``ctypes.data`` takes), else (read-only, empty) numpy's."""
    if writeable and array.size:
        return ctypes.addressof(ctypes.c_char.from_buffer(array))
    return array.ctypes.data


@functools.cache
def _layout(name: str) -> dict[str, tuple[str, int, int, np.dtype | None]]:
    """Each argument's kind, first slot, and for an array its number of dimensions and dtype, by
    its name (a number: 0 and None)."""
    shapes = {interface.VECTOR: (1, np.dtype(np.float64)), interface.MATRIX: (2, np.dtype(np.float64)),
              interface.INTS: (1, np.dtype(np.int64))}
    return {parameter: (kind, slot, *shapes.get(kind, (0, None))) for parameter, kind, slot in interface.layout(name)}


def call(name: str, /, **arguments) -> None:
    """Run the kernel function ``name`` once on these arguments (``Arguments``)."""
    Arguments(name, **arguments)()


def entries() -> dict:
    """Every entry point as a ctypes function, compiled or loaded on first use (thread-safe)."""
    global _entries
    if _entries is None:
        with _lock:
            if _entries is None:
                _entries = {name: _ENTRY_TYPE(address) for name, address in _addresses().items()}
    return _entries


class _Unusable(Exception):
    """The shipped code cannot be used on this machine (numba compiles the kernel instead)."""


def _addresses() -> dict[str, int]:
    global source, refused
    try:
        bitcode, facts = _shipped()
        addresses = _machine_code(f"shipped {facts['bitcode']}", lambda: (bitcode, facts["entries"], facts["calls"]))
        source, refused = "shipped", None
        return addresses
    except (_Unusable, RuntimeError) as error:   # (RuntimeError: LLVM could not read or compile it)
        refused = str(error)
    source = "numba"
    return _machine_code("numba " + json.dumps(stamp(), sort_keys=True), compile_with_numba)


def compile_with_numba() -> tuple[bytes, dict[str, str], list[str]]:
    """The entry points compiled by numba in this process (no disk cache: every kernel function
    is compiled here, so its LLVM code is at hand): their LLVM modules linked into one, as
    bitcode; each entry's symbol; the symbols the code calls (``calls``). (The one place the
    kernel's compiled modules, and numba, are imported for the machine code.)"""
    import llvmlite.binding as llvm
    from numba import cfunc

    from . import kernel

    for listener in list(listeners):   # (said where the code cannot be kept too: numba's minute)
        listener()

    linked, symbols = None, {}
    for name, entry in kernel.ENTRY_POINTS.items():
        compiled = cfunc(kernel.ENTRY_SIGNATURE, cache=False, error_model="numpy")(entry)
        symbols[name] = compiled.native_name
        module = llvm.parse_assembly(compiled.inspect_llvm())
        if linked is None:
            linked = module
        else:
            linked.link_in(module)
    linked.verify()
    return linked.as_bitcode(), symbols, calls(linked)


def calls(module) -> list[str]:
    """The symbols the module calls but does not hold (numba's helpers, the C library), which
    the process that runs it must provide (LLVM's own intrinsics aside)."""
    return sorted(f.name for f in module.functions if f.is_declaration and not f.name.startswith("llvm."))


def symbol_prefix(name: str) -> str:
    """How the symbol of the entry point ``name`` begins: numba's mangling of its function's
    module and name (the lengths make each entry's prefix unlike every other's)."""
    parts = interface.ENTRY_MODULE.split(".") + [interface.entry_name(name)]
    return "cfunc._ZN" + "".join(f"{len(part)}{part}" for part in parts)


def _shipped(folder=None) -> tuple[bytes, dict]:
    """The shipped bitcode and its stamp (``kernel.json``, in ``folder``: the package's by
    default) where they fit this machine, this kernel and its interface, and each other; else
    ``_Unusable``, saying why."""
    if os.environ.get("ROLLBALL_MACHINE_CODE") == "numba":   # (numba's way forced: the bench measures it so)
        raise _Unusable("ROLLBALL_MACHINE_CODE=numba")
    folder = resources.files("rollball") if folder is None else folder
    try:
        facts = json.loads(folder.joinpath(STAMP).read_text(encoding="utf-8"))
        bitcode = folder.joinpath(SHIPPED).read_bytes()
    except (OSError, ValueError) as error:
        raise _Unusable(f"no shipped code: {error}") from None
    if not isinstance(facts, dict):
        raise _Unusable(f"{STAMP} is not a stamp")
    expected = stamp(facts)
    different = [key for key in expected if facts.get(key) != expected[key]]
    if different:
        raise _Unusable(f"made for another {', '.join(different)}")
    if facts.get("bitcode") != hashlib.sha256(bitcode).hexdigest():
        raise _Unusable(f"{SHIPPED} is not the code {STAMP} describes (its SHA-256 differs)")
    symbols, needed = facts.get("entries"), facts.get("calls")
    if not (isinstance(symbols, dict) and set(symbols) == set(interface.ENTRIES)
            and all(isinstance(symbols[name], str) and symbols[name].startswith(symbol_prefix(name))
                    and symbols[name][len(symbol_prefix(name)):][:1] in ("B", "E") for name in symbols)):
        raise _Unusable(f"the entry points in {STAMP} are not this kernel's")
    if not (isinstance(needed, list) and all(isinstance(symbol, str) for symbol in needed)):
        raise _Unusable(f"{STAMP} does not list the symbols the code calls")
    return bitcode, facts


def _machine_code(what: str, make) -> dict[str, int]:
    """The entry points' addresses in machine code made from ``what`` for this processor: kept
    by an earlier process, else made now from the bitcode ``make()`` returns (with its entries'
    symbols and the symbols it calls) and kept. Under ``llvm_lock``: LLVM's state is shared with
    the landscapes' code and numba's."""
    import llvmlite.binding as llvm

    with llvm_lock():
        initialise()   # LLVM set up, numba's helpers known (without numba)
        machine = target_machine()
        key = hashlib.sha256("\0".join([what, str(machine.triple), llvm.get_host_cpu_name(),
                                        llvm.get_host_cpu_features().flatten(),
                                        ".".join(map(str, llvm.llvm_version_info))]).encode()).hexdigest()[:32]
        path = _object_path(key)
        data = cache.read(path, OBJECT_LIMIT, "machine code of the kernel")
        kept = _unpack(_checked(data))
        if kept is None:
            blocked = cache.unwritable(path)
            if blocked is None:   # made now and kept: the first run only
                for listener in list(listeners):
                    listener()
            elif data is not None:
                cache.warn(f"the cached machine code of the kernel {shown(str(path))} is corrupt and cannot be "
                           f"replaced ({blocked}); it is made again in memory, for this process only")
            else:
                cache.warn(f"the machine code of the kernel cannot be kept as {shown(str(path))} ({blocked}); "
                           f"it is made in memory, for this process only")
            bitcode, symbols, needed = make()
            code = machine.emit_object(llvm.parse_bitcode(bitcode))
            if blocked is None:
                _write(path, _pack(symbols, needed, code))
        else:
            symbols, needed, code = kept
        missing = [name for name in needed if not llvm.address_of_symbol(name)]
        if missing:   # (MCJIT would end the process on a call it cannot link)
            raise _Unusable(f"symbols not found here: {', '.join(missing)}")
        engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), machine)
        engine.add_object_file(llvm.ObjectFileRef.from_data(code))
        engine.finalize_object()
        _keep.append(engine)
        addresses = {name: engine.get_function_address(symbol) for name, symbol in symbols.items()}
    if set(addresses) != set(interface.ENTRIES) or not all(addresses.values()):
        raise _Unusable("an entry point is missing from the machine code")
    return addresses


def _pack(symbols: dict[str, str], needed: list[str], code: bytes) -> bytes:
    """Machine code as kept on disk: a line of JSON (the entries' symbols, the symbols it calls), then the code."""
    return json.dumps({"entries": symbols, "calls": needed}).encode() + b"\n" + code


def _unpack(data: bytes | None) -> tuple[dict, list, bytes] | None:
    if data is None:
        return None
    head, _, code = data.partition(b"\n")
    try:
        facts = json.loads(head)
        symbols, needed = facts["entries"], facts["calls"]
    except (ValueError, KeyError, TypeError):
        return None
    if not (code and isinstance(symbols, dict) and isinstance(needed, list)):
        return None
    return symbols, needed, code


def _object_path(key: str):
    return cache_dir() / f"kernel-{key}.o"


# The kernel's machine code is about 250 kB; a cached file larger than this is not ours.
OBJECT_LIMIT = 64 << 20


def _read(path) -> bytes | None:
    """Machine code kept by an earlier process, if it is there whole (its SHA-256 first) and
    sound: a regular file of ours of plausible size (cache.read; else one warning, and it is
    made again)."""
    return _checked(cache.read(path, OBJECT_LIMIT, "machine code of the kernel"))


def _checked(data: bytes | None) -> bytes | None:
    """The machine code in a cached file's bytes, or None unless it is whole (its SHA-256 first)."""
    if data is None:
        return None
    digest, code = data[:32], data[32:]
    return code if code and hashlib.sha256(code).digest() == digest else None


def _write(path, code: bytes) -> None:
    """Keep the machine code for later processes; a cache that cannot be written costs only time."""
    cache.write(path, hashlib.sha256(code).digest() + code)
