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

from numba.core import event

from .files import atomic_write_bytes, atomic_write_text, check_outputs
from .machine_code import SHIPPED, STAMP, compile_with_numba, raw_digest, stamp


def build(folder) -> dict:
    """Compile the entry points with numba and write their bitcode and its stamp into folder;
    returns the stamp. The stamp also records numba's compiles of the kernel's functions
    (``"compiled"``, ``Compiles``), which the test suite checks without compiling again."""
    compiles = Compiles()
    with event.install_listener("numba:compile", compiles):
        bitcode, symbols, needed = compile_with_numba()
    facts = {**stamp(), "sources": raw_digest(), "bitcode": hashlib.sha256(bitcode).hexdigest(), "entries": symbols,
             "calls": needed, "compiled": compiles.counts()}
    atomic_write_bytes(os.path.join(folder, SHIPPED), bitcode)
    atomic_write_text(os.path.join(folder, STAMP), json.dumps(facts, indent=1) + "\n")
    return facts


class Compiles(event.Listener):
    """numba's compiles of the kernel's functions while the shipped code is made: each compile
    event of a function of the package, by its dispatcher. A function compiled once per state
    layout by a factory (``kernel.explicit._trial_step``) has a dispatcher per layout; one
    dispatcher compiling twice is one function compiled for two sets of argument types or
    constants (a constant bool or int passed to it compiles it again for that constant)."""

    def __init__(self):
        self._seen: dict[tuple[str, int], int] = {}

    def on_start(self, ev) -> None:
        dispatcher = ev.data["dispatcher"]
        function = dispatcher.py_func
        if function.__module__.startswith("rollball."):
            key = (f"{function.__module__}.{function.__qualname__}", id(dispatcher))
            self._seen[key] = self._seen.get(key, 0) + 1

    def on_end(self, ev) -> None:
        pass

    def counts(self) -> dict[str, list[int]]:
        """For each function compiled (module.qualname), how many times each of its dispatchers
        compiled, in ascending order."""
        counts: dict[str, list[int]] = {}
        for (name, _), times in self._seen.items():
            counts.setdefault(name, []).append(times)
        return {name: sorted(counts[name]) for name in sorted(counts)}


def main(folder: str | None = None) -> int:
    """Make kernel.bc and kernel.json anew in the package's folder (or ``folder``), which is
    checked first: a folder the files cannot be written into is said before the compile, not
    after it."""
    folder = folder or os.path.dirname(os.path.abspath(__file__))
    try:
        check_outputs(folder, (SHIPPED, STAMP))
    except OSError as e:
        print(f"rollball: cannot write the kernel's code into {folder}: {e}", file=sys.stderr)
        return 1
    print("rollball: compiling the kernel's entry points with numba (several minutes) ...", file=sys.stderr)
    facts = build(folder)
    size = os.path.getsize(os.path.join(folder, SHIPPED))
    print(f"rollball: wrote {SHIPPED} ({size / 1e6:.1f} MB) and {STAMP} for the kernel {facts['kernel'][:12]}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
