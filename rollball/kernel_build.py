"""Making the kernel's shipped code: ``python -m rollball.kernel_build`` compiles the entry
points of kernel.py with numba, in a process of its own with an empty numba cache (code
numba loads from its cache has no intermediate code left to ship), links their LLVM modules
into one and writes it beside kernel.py as kernel.bc, with kernel.json saying what it was
made from (machine_code.py). A developer's step after changing kernel.py: the test suite
says when they are out of date."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

from . import kernel
from .files import atomic_write_bytes, atomic_write_text
from .machine_code import SHIPPED, STAMP, numba_entry, stamp


def build(folder) -> dict:
    """Compile the entry points with numba and write their bitcode and its stamp into folder;
    returns the stamp (numba's cache must be empty: ``main``)."""
    import llvmlite.binding as llvm

    linked, symbols = None, {}
    for name in kernel.ENTRIES:
        compiled = numba_entry(name)
        symbols[name] = compiled.native_name
        module = llvm.parse_assembly(compiled.inspect_llvm())
        if linked is None:
            linked = module
        else:
            linked.link_in(module)
    linked.verify()
    bitcode = linked.as_bitcode()
    facts = stamp(symbols)
    facts["calls"] = calls(linked)
    atomic_write_bytes(os.path.join(folder, SHIPPED), bitcode)
    atomic_write_text(os.path.join(folder, STAMP), json.dumps(facts, indent=1) + "\n")
    return facts


def calls(module) -> list[str]:
    """The symbols the module calls but does not hold (numba's helpers, the C library), which
    the process that runs it must provide (LLVM's own intrinsics aside)."""
    return sorted(f.name for f in module.functions if f.is_declaration and not f.name.startswith("llvm."))


def main() -> int:
    """Make kernel.bc and kernel.json anew beside kernel.py."""
    folder = os.path.dirname(os.path.abspath(__file__))
    if os.environ.get("_ROLLBALL_BUILD") != "1":
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache, _ROLLBALL_BUILD="1")
            return subprocess.call([sys.executable, "-m", "rollball.kernel_build"], env=env)
    print("rollball: compiling the kernel's entry points with numba (a minute or two) ...", file=sys.stderr)
    facts = build(folder)
    size = os.path.getsize(os.path.join(folder, SHIPPED))
    print(f"rollball: wrote {SHIPPED} ({size / 1e6:.1f} MB) and {STAMP} for kernel.py {facts['kernel'][:12]}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
