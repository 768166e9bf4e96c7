"""Making the kernel's shipped code: ``python -m rollball.kernel_build`` compiles the kernel's
entry points with numba (``machine_code.compile_with_numba``), links their LLVM modules into
one and writes it into the package as kernel.bc, with kernel.json saying what it was made
from and how to call it (machine_code.py). A maintainer's step after changing the kernel's
code (comments and docstrings aside), and a CI's on a platform that wants code of its own: the
test suite says when they are out of date."""

from __future__ import annotations

import hashlib
import json
import os
import sys

from .files import atomic_write_bytes, atomic_write_text
from .machine_code import SHIPPED, STAMP, compile_with_numba, raw_digest, stamp


def build(folder) -> dict:
    """Compile the entry points with numba and write their bitcode and its stamp into folder;
    returns the stamp."""
    bitcode, symbols, needed = compile_with_numba()
    facts = {**stamp(), "sources": raw_digest(), "bitcode": hashlib.sha256(bitcode).hexdigest(), "entries": symbols,
             "calls": needed}
    atomic_write_bytes(os.path.join(folder, SHIPPED), bitcode)
    atomic_write_text(os.path.join(folder, STAMP), json.dumps(facts, indent=1) + "\n")
    return facts


def main() -> int:
    """Make kernel.bc and kernel.json anew in the package's folder."""
    folder = os.path.dirname(os.path.abspath(__file__))
    print("rollball: compiling the kernel's entry points with numba (a minute or two) ...", file=sys.stderr)
    facts = build(folder)
    size = os.path.getsize(os.path.join(folder, SHIPPED))
    print(f"rollball: wrote {SHIPPED} ({size / 1e6:.1f} MB) and {STAMP} for the kernel {facts['kernel'][:12]}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
